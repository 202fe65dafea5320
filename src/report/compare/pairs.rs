//! The rows of two folders' tables, paired by their key. In: A's rows and B's. Out: each
//! row of A with B's row of the same key, then the rows only B has.

/// The rows of A and B paired by `key`: A's rows in order, each with B's row of the
/// same key if there is one, then B's rows that A lacks.
pub fn pair<'r, R, K: PartialEq>(
    a: &'r [R],
    b: &'r [R],
    key: impl Fn(&R) -> K,
) -> Vec<(Option<&'r R>, Option<&'r R>)> {
    let mut pairs: Vec<_> = a
        .iter()
        .map(|row| (Some(row), b.iter().find(|other| key(other) == key(row))))
        .collect();
    pairs.extend(
        b.iter()
            .filter(|row| !a.iter().any(|other| key(other) == key(row)))
            .map(|row| (None, Some(row))),
    );
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_pair_by_key_in_a_order_then_b_only() {
        let a = [("x", 1), ("y", 2), ("z", 3)];
        let b = [("w", 9), ("z", 30), ("x", 10)];
        let pairs: Vec<_> = pair(&a, &b, |r| r.0)
            .into_iter()
            .map(|(a, b)| (a.map(|r| r.1), b.map(|r| r.1)))
            .collect();
        assert_eq!(
            pairs,
            [
                (Some(1), Some(10)),
                (Some(2), None),
                (Some(3), Some(30)),
                (None, Some(9))
            ]
        );
    }
}
