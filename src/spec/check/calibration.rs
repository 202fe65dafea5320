//! Checks `[calibration]`. In: the calibration trajectory by name, the window sizes in
//! seconds, the Monte Carlo runs, and the trajectories and rate `[data]` gave (and,
//! with DCNet among the estimators, DCNet's window from `[dataset]`). Out: the
//! [`CalibrationSpec`], window sizes in samples, each leaving samples to evaluate on.
//!
//! [`CalibrationSpec`]: crate::spec::CalibrationSpec

use super::dataset::Window;
use super::{Defined, Faults, positive_samples};
use crate::spec::{CalibrationSpec, file, ranges};
use crate::vocab::ErrorModel;

/// Checks `[calibration]`: its trajectory, window sizes that each leave samples to
/// evaluate on, and at least one Monte Carlo run.
pub(in crate::spec) fn check_calibration(
    calibration: file::CalibrationFile,
    sources: &Defined,
    rate: f64,
    faults: &mut Faults,
) -> CalibrationSpec {
    let file::CalibrationFile {
        trajectory,
        window_sizes_s,
        monte_carlo_runs,
        time_tolerance_pct,
    } = calibration;
    if !(time_tolerance_pct.is_finite() && time_tolerance_pct > 0.0) {
        faults.add(
            "calibration.time_tolerance_pct",
            format!("{time_tolerance_pct} must be a finite number above zero"),
        );
    }
    let index = sources.lookup("calibration.trajectory", &trajectory, faults);
    let segment = index.and_then(|i| sources[i].known_len());
    if window_sizes_s.is_empty() {
        faults.add(
            "calibration.window_sizes_s",
            "is empty: give at least one window size",
        );
    }
    let mut window_sizes = Vec::new();
    // Each size in samples and the index it was first listed at.
    let mut first_of_size = std::collections::HashMap::new();
    for (i, &size_s) in window_sizes_s.iter().enumerate() {
        let key = format!("calibration.window_sizes_s[{i}]");
        if let Some(size) = positive_samples(&key, size_s, rate, faults) {
            if let Some(&first) = first_of_size.get(&size) {
                faults.add(
                    key,
                    format!("{size_s} s is calibration.window_sizes_s[{first}] again: each window size is calibrated once"),
                );
                continue;
            }
            first_of_size.insert(size, i);
            match segment {
                Some(len) if size >= len => faults.add(
                    key,
                    format!("{size_s} s is not shorter than {trajectory} ({} s): no samples would be left to evaluate on", len as f64 / rate),
                ),
                _ => window_sizes.push(size),
            }
        }
    }
    if monte_carlo_runs < 2 {
        faults.add(
            "calibration.monte_carlo_runs",
            format!("{monte_carlo_runs} must be at least 2: the spread of the RMSE over runs (rmse_std_cm_s) needs two runs"),
        );
    }
    ranges::MONTE_CARLO_RUNS.check(
        "calibration.monte_carlo_runs",
        monte_carlo_runs as f64,
        faults,
    );
    CalibrationSpec {
        trajectory: index.unwrap_or_default(),
        window_sizes,
        monte_carlo_runs,
        time_tolerance: time_tolerance_pct / 100.0,
    }
}

/// With DCNet among the estimators: every calibration window holds one DCNet window.
pub(in crate::spec) fn check_dcnet_windows(
    window: Window,
    window_sizes: &[usize],
    rate: f64,
    faults: &mut Faults,
) {
    let Some(samples) = window.samples else {
        return;
    };
    for (i, &size) in window_sizes.iter().enumerate() {
        if size < samples {
            faults.add(
                format!("calibration.window_sizes_s[{i}]"),
                format!(
                    "{} s is shorter than one DCNet window (dataset.window_s = {} s)",
                    size as f64 / rate,
                    window.seconds
                ),
            );
        }
    }
}

/// Samples a calibration window holds per term that least squares fits: with fewer,
/// the fit follows the noise (EM5, six terms, from 2 s at 1 Hz: 92.8 cm/s RMSE).
pub(in crate::spec) const SAMPLES_PER_TERM: usize = 2;

/// With least squares or beam WLS among the estimators: every calibration window holds
/// [`SAMPLES_PER_TERM`] samples per term of the largest error model calibrated.
pub(in crate::spec) fn check_fitted_windows(
    error_models: &[ErrorModel],
    window_sizes: &[usize],
    rate: f64,
    faults: &mut Faults,
) {
    let Some(model) = error_models.iter().max_by_key(|m| m.term_count()) else {
        return;
    };
    let least = SAMPLES_PER_TERM * model.term_count();
    for (i, &size) in window_sizes.iter().enumerate() {
        if size < least {
            faults.add(
                format!("calibration.window_sizes_s[{i}]"),
                format!(
                    "{} s holds {size} samples at {rate} Hz: least squares needs at least {least} ({SAMPLES_PER_TERM} per term of {model}'s {}) to fit anything but noise",
                    size as f64 / rate,
                    model.term_count()
                ),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::spec::fixture::{quick_faults, quick_spec};

    #[test]
    fn window_sizes_are_samples_shorter_than_the_trajectory() {
        let spec = quick_spec(&["data.sample_rate_hz=2"]);
        assert_eq!(spec.calibration.window_sizes, [40, 80, 120, 160, 200]);
        let set = "calibration.window_sizes_s=[200]";
        assert_eq!(
            quick_faults(&[set]),
            format!(
                "--set {set}: calibration.window_sizes_s[0]: 200 s is not shorter than SCal (200 s): no samples would be left to evaluate on"
            )
        );
    }

    #[test]
    fn a_window_shorter_than_dcnets_is_refused_only_with_dcnet() {
        let set = "calibration.window_sizes_s=[5]";
        // The second fault is least squares' (see below).
        assert_eq!(
            quick_faults(&[set]).lines().next().unwrap(),
            format!(
                "--set {set}: calibration.window_sizes_s[0]: 5 s is shorter than one DCNet window (dataset.window_s = 10 s)"
            )
        );
        let without = quick_spec(&[set, "estimators.kinds=[\"baseline\"]"]);
        assert_eq!(without.calibration.window_sizes, [5]);
    }

    #[test]
    fn a_window_too_short_for_least_squares_and_a_single_run_are_refused() {
        let set = "calibration.window_sizes_s=[11, 20]";
        let kinds = "estimators.kinds=[\"least_squares\"]";
        assert_eq!(
            quick_faults(&[set, kinds]),
            format!(
                "--set {set}: calibration.window_sizes_s[0]: 11 s holds 11 samples at 1 Hz: least squares needs at least 12 (2 per term of EM5's 6) to fit anything but noise"
            )
        );
        let fewer = quick_spec(&[set, kinds, "estimators.error_models=[\"EM2\"]"]);
        assert_eq!(fewer.calibration.window_sizes, [11, 20]);
        let set = "calibration.monte_carlo_runs=1";
        assert_eq!(
            quick_faults(&[set]),
            format!(
                "--set {set}: calibration.monte_carlo_runs: 1 must be at least 2: the spread of the RMSE over runs (rmse_std_cm_s) needs two runs"
            )
        );
    }
}
