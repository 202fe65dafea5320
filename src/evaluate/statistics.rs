//! The statistics of the tables: a mean with its sample standard deviation, and a
//! mean with the half-width of its 95 % confidence interval. In: values. Out: numbers.

/// Mean and sample standard deviation (n − 1; 0 for a single value).
pub fn mean_std(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let values: Vec<f64> = values.collect();
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let std = if values.len() > 1 {
        (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    (mean, std)
}

/// The mean of `values` and the half-width of its 95 % confidence interval,
/// `t_{0.975, n−1} · sd / √n` (Student t, sd the sample standard deviation); needs two
/// values or more.
pub fn mean_ci95(values: &[f64]) -> (f64, f64) {
    let n = values.len();
    assert!(n > 1, "a confidence interval needs two values or more");
    let (mean, std) = mean_std(values.iter().copied());
    (
        mean,
        student_t_975(n as f64 - 1.0) * std / (n as f64).sqrt(),
    )
}

/// Student's t₀.₉₇₅ on `freedom` degrees of freedom (at least one): the half-width, in
/// standard deviations, of a 95 % interval whose standard deviation was itself
/// estimated. 12.71 on one, 1.96 on many. Beyond [`NORMAL_FREEDOM`] the normal's
/// quantile, within 10⁻⁵ of Student's there: statrs's Student quantile drifts beyond a
/// million degrees of freedom (1.83 on 10⁷), which a long recording's samples reach.
pub fn student_t_975(freedom: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal, StudentsT};
    if freedom > NORMAL_FREEDOM {
        return Normal::standard().inverse_cdf(0.975);
    }
    StudentsT::new(0.0, 1.0, freedom.max(1.0))
        .expect("positive degrees of freedom")
        .inverse_cdf(0.975)
}

/// The degrees of freedom beyond which [`student_t_975`] takes the normal's quantile.
pub const NORMAL_FREEDOM: f64 = 1e5;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn confidence_interval_of_three_values() {
        // t_{0.975, 2} = 4.3027; sd of [1, 2, 3] = 1; 4.3027 / √3 = 2.4841.
        let (mean, ci) = mean_ci95(&[1.0, 2.0, 3.0]);
        assert_eq!(mean, 2.0);
        assert!((ci - 2.4841).abs() < 1e-4, "{ci}");
    }

    #[test]
    fn students_quantile_from_tables_and_at_least_one_degree_of_freedom() {
        // Tabled t₀.₉₇₅: 12.706 on 1, 2.228 on 10, 1.960 on very many.
        let many = [1e5, 1e6, 1e7].map(|freedom| (freedom, 1.960));
        for (freedom, tabled) in [(1.0, 12.706), (10.0, 2.228)].into_iter().chain(many) {
            let t = student_t_975(freedom);
            assert!((t - tabled).abs() < 1e-3, "{freedom}: {t}");
        }
        assert_eq!(student_t_975(0.2), student_t_975(1.0));
    }

    #[test]
    fn sample_standard_deviation() {
        let (mean, std) = mean_std([1.0, 2.0, 3.0, 4.0].into_iter());
        assert_eq!(mean, 2.5);
        assert!((std - 1.2909944).abs() < 1e-6);
        assert_eq!(mean_std([5.0].into_iter()), (5.0, 0.0));
    }
}
