//! Linear interpolation between a recording's samples, the one way every reader of a
//! recording at a time between its stamps does it (an attitude, a reference, a track,
//! positions, a simulated fix, a bag's IMU rate).
//! In: increasing stamps, a time, the longest gap to read across. Out: the two samples
//! around the time and the weight of the later ([`Between`]), which blends any values
//! recorded on those stamps.

/// A stamp: seconds as `f64`, or a bag's nanoseconds as `i64`.
pub trait Stamp: Copy + PartialOrd {
    /// `self − earlier`, in the stamps' unit, as `f64`.
    fn since(self, earlier: Self) -> f64;
}

impl Stamp for f64 {
    fn since(self, earlier: f64) -> f64 {
        self - earlier
    }
}

impl Stamp for i64 {
    fn since(self, earlier: i64) -> f64 {
        (self - earlier) as f64
    }
}

/// Where a time falls among the stamps: the sample at or before it, the sample at or
/// after it, and the later one's weight (0 at a sample, where the two are one).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Between {
    pub before: usize,
    pub after: usize,
    pub weight: f64,
}

impl Between {
    /// Where `time` falls among the increasing `stamps`: `None` outside their span or
    /// between two samples further apart than `max_gap` (in the stamps' unit; infinite
    /// to read across any gap).
    pub fn locate<T: Stamp>(stamps: &[T], time: T, max_gap: f64) -> Option<Between> {
        let (&first, &last) = (stamps.first()?, stamps.last()?);
        if !(first <= time && time <= last) {
            return None;
        }
        let after = stamps.partition_point(|&t| t < time);
        if stamps[after] == time {
            return Some(Between {
                before: after,
                after,
                weight: 0.0,
            });
        }
        let before = after - 1;
        let span = stamps[after].since(stamps[before]);
        (span <= max_gap).then(|| Between {
            before,
            after,
            weight: time.since(stamps[before]) / span,
        })
    }

    /// The values recorded on the stamps, blended at this time.
    pub fn of<const N: usize>(&self, values: &[[f64; N]]) -> [f64; N] {
        let (a, b) = (values[self.before], values[self.after]);
        std::array::from_fn(|k| a[k] + self.weight * (b[k] - a[k]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_at_a_sample_linear_between_none_outside_or_across_a_long_gap() {
        let stamps = [0.0, 1.0, 3.0];
        let values = [[0.0, 10.0], [2.0, 20.0], [6.0, 0.0]];
        let at = |t: f64, gap: f64| Between::locate(&stamps, t, gap).map(|b| b.of(&values));
        assert_eq!(at(1.0, 1.5), Some([2.0, 20.0]));
        assert_eq!(at(0.25, 1.5), Some([0.5, 12.5]));
        assert_eq!(at(2.0, f64::INFINITY), Some([4.0, 10.0]));
        assert_eq!(at(2.0, 1.5), None, "a gap of 2 read across at most 1.5");
        assert_eq!(at(3.0, 1.5), Some([6.0, 0.0]), "a sample ends a gap");
        assert_eq!(at(-0.1, f64::INFINITY), None);
        assert_eq!(at(3.1, f64::INFINITY), None);
        assert_eq!(Between::locate::<f64>(&[], 0.0, 1.0), None);
        let nanoseconds = [0_i64, 4, 8];
        let between = Between::locate(&nanoseconds, 5, f64::INFINITY).unwrap();
        assert_eq!(
            (between.before, between.after, between.weight),
            (1, 2, 0.25)
        );
    }
}
