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
    use statrs::distribution::{ContinuousCDF, StudentsT};
    let n = values.len();
    assert!(n > 1, "a confidence interval needs two values or more");
    let (mean, std) = mean_std(values.iter().copied());
    let t = StudentsT::new(0.0, 1.0, (n - 1) as f64)
        .expect("n − 1 ≥ 1 degrees of freedom")
        .inverse_cdf(0.975);
    (mean, t * std / (n as f64).sqrt())
}

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
    fn sample_standard_deviation() {
        let (mean, std) = mean_std([1.0, 2.0, 3.0, 4.0].into_iter());
        assert_eq!(mean, 2.5);
        assert!((std - 1.2909944).abs() < 1e-6);
        assert_eq!(mean_std([5.0].into_iter()), (5.0, 0.0));
    }
}
