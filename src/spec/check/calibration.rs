//! Checks `[calibration]`. In: the calibration trajectory by name, the window sizes in
//! seconds, the Monte Carlo runs, and the trajectories and rate `[data]` gave (and,
//! with DCNet among the estimators, DCNet's window from `[dataset]`). Out: the
//! [`CalibrationSpec`], window sizes in samples, each leaving samples to evaluate on.
//!
//! [`CalibrationSpec`]: crate::spec::CalibrationSpec

use super::dataset::Window;
use super::{Faults, lookup, positive_samples};
use crate::spec::{CalibrationSpec, TrajectorySource, file, ranges};

/// Checks `[calibration]`: its trajectory, window sizes that each leave samples to
/// evaluate on, and at least one Monte Carlo run.
pub(in crate::spec) fn check_calibration(
    calibration: file::CalibrationFile,
    sources: &[TrajectorySource],
    rate: f64,
    faults: &mut Faults,
) -> CalibrationSpec {
    let file::CalibrationFile {
        trajectory,
        window_sizes_s,
        monte_carlo_runs,
    } = calibration;
    let index = lookup(sources, "calibration.trajectory", &trajectory, faults);
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
    if monte_carlo_runs == 0 {
        faults.add("calibration.monte_carlo_runs", "0 must be at least 1");
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
        assert_eq!(
            quick_faults(&[set]),
            format!(
                "--set {set}: calibration.window_sizes_s[0]: 5 s is shorter than one DCNet window (dataset.window_s = 10 s)"
            )
        );
        let without = quick_spec(&[set, "estimators.kinds=[\"baseline\"]"]);
        assert_eq!(without.calibration.window_sizes, [5]);
    }
}
