//! Whether two means differ: B's mean RMSE against A's, over their Monte Carlo runs.
//! In: each side's mean, standard deviation and number of runs. Out: B − A, its
//! combined standard error and whether it exceeds [`STANDARD_ERRORS`] of them (a z
//! test), with the rule for deterministic estimators whose standard error is 0.

use crate::results::read::StoredRun;

/// How many combined standard errors a difference must exceed to be marked.
pub const STANDARD_ERRORS: f64 = 2.0;
/// Share of the larger mean below which a difference between two means of standard
/// error 0 (deterministic estimators) is rounding, not a change.
pub const FLOAT_NOISE: f64 = 1e-9;

/// A mean RMSE over Monte Carlo runs with the standard deviation over those runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mean {
    pub rmse_cm_s: f64,
    pub std_cm_s: f64,
    pub runs: usize,
}

impl Mean {
    /// A mean RMSE of `run`'s tables, over its Monte Carlo runs.
    pub(super) fn of(run: &StoredRun, rmse_cm_s: f64, std_cm_s: f64) -> Mean {
        Mean {
            rmse_cm_s,
            std_cm_s,
            runs: run.spec.calibration.monte_carlo_runs,
        }
    }

    /// The standard error of the mean, std / √n; none for a single run, whose stored
    /// standard deviation of 0 says nothing about the spread.
    pub fn standard_error(&self) -> Option<f64> {
        (self.runs >= 2).then(|| self.std_cm_s / (self.runs as f64).sqrt())
    }
}

/// How B's mean stands against A's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Difference {
    /// B − A in cm/s.
    pub cm_s: f64,
    /// √(se_A² + se_B²); none when a side has a single run.
    pub standard_error: Option<f64>,
    /// What |B − A| must exceed to be marked: [`STANDARD_ERRORS`] combined standard
    /// errors, and never less than [`FLOAT_NOISE`] of the larger mean.
    pub threshold_cm_s: Option<f64>,
}

impl Difference {
    pub fn between(a: Mean, b: Mean) -> Self {
        let standard_error = a
            .standard_error()
            .zip(b.standard_error())
            .map(|(a, b)| a.hypot(b));
        let noise = FLOAT_NOISE * a.rmse_cm_s.abs().max(b.rmse_cm_s.abs());
        Difference {
            cm_s: b.rmse_cm_s - a.rmse_cm_s,
            standard_error,
            threshold_cm_s: standard_error.map(|se| (STANDARD_ERRORS * se).max(noise)),
        }
    }

    /// Whether |B − A| exceeds the threshold; none when it cannot be tested.
    pub fn is_beyond(&self) -> Option<bool> {
        self.threshold_cm_s.map(|t| self.cm_s.abs() > t)
    }

    /// (B − A) in combined standard errors, as printed: `±∞` for a change between two
    /// means of standard error 0, `—` for none, `n/a` when it cannot be tested.
    pub fn z_text(&self) -> String {
        match (self.standard_error, self.is_beyond()) {
            (None, _) => "n/a".into(),
            (Some(se), _) if se > 0.0 => format!("{:+.1}", self.cm_s / se),
            (Some(_), Some(true)) if self.cm_s > 0.0 => "+∞".into(),
            (Some(_), Some(true)) => "-∞".into(),
            (Some(_), _) => "—".into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mean(rmse_cm_s: f64, std_cm_s: f64, runs: usize) -> Mean {
        Mean {
            rmse_cm_s,
            std_cm_s,
            runs,
        }
    }

    #[test]
    fn the_standard_error_is_the_std_over_the_root_of_the_runs() {
        assert_eq!(mean(1.0, 0.4, 16).standard_error(), Some(0.1));
        assert!((mean(1.0, 0.3, 9).standard_error().unwrap() - 0.1).abs() < 1e-15);
        assert_eq!(mean(1.0, 0.0, 1).standard_error(), None);
    }

    #[test]
    fn a_difference_is_marked_beyond_two_combined_standard_errors() {
        // se_A = 0.3/√9 = 0.1, se_B = 0.4/√16 = 0.1: combined 0.1414, threshold 0.2828.
        let a = mean(1.0, 0.3, 9);
        let within = Difference::between(a, mean(1.25, 0.4, 16));
        assert!((within.standard_error.unwrap() - 0.141_421_356).abs() < 1e-9);
        assert!((within.threshold_cm_s.unwrap() - 0.282_842_712).abs() < 1e-9);
        assert_eq!(within.is_beyond(), Some(false));
        assert_eq!(within.z_text(), "+1.8");
        let beyond = Difference::between(a, mean(0.7, 0.4, 16));
        assert_eq!(beyond.is_beyond(), Some(true));
        assert_eq!(beyond.z_text(), "-2.1");
    }

    #[test]
    fn deterministic_means_differ_beyond_rounding_only() {
        let a = mean(0.74, 0.0, 20);
        let same = Difference::between(a, a);
        assert_eq!(
            (same.is_beyond(), same.z_text().as_str()),
            (Some(false), "—")
        );
        // A mean summed in another order: 1e-15 off, far below 1e-9 of 0.74.
        let rounded = Difference::between(a, mean(0.74 + 1e-15, 0.0, 20));
        assert_eq!(rounded.is_beyond(), Some(false));
        let changed = Difference::between(a, mean(0.74 - 1e-6, 0.0, 20));
        assert_eq!(
            (changed.is_beyond(), changed.z_text().as_str()),
            (Some(true), "-∞")
        );
    }

    #[test]
    fn a_single_run_leaves_a_cell_untested() {
        let untested = Difference::between(mean(1.0, 0.0, 1), mean(5.0, 0.2, 20));
        assert_eq!(untested.is_beyond(), None);
        assert_eq!(untested.z_text(), "n/a");
    }
}
