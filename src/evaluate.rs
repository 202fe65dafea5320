//! The paper's protocol. For each DVL under test, each Monte Carlo run measures the
//! calibration trajectory with fresh noise, every estimator estimates its terms from the
//! first w seconds for every window size w, and the RMSE of the corrected remainder is
//! taken. T_conv is the window with the lowest mean RMSE over runs. Each run's T_conv
//! terms then correct freshly measured test trajectories. In: the spec, the
//! trajectories. Out: per-run rows and the calibration and evaluation tables.
//!
//! Runs go in parallel; every measurement draws from a generator seeded by (seed, DVL,
//! run, trajectory) and every mean is summed in run order, so the numbers do not
//! depend on the thread count.

use crate::Vec3;
use crate::data::Trajectory;
use crate::estimators::{Correction, Entry, ErrorModel, EstimatorKind, lineup};
use crate::noise::{BeamGeometry, Measurements, measure_trajectory};
use crate::rng::task_rng;
use crate::spec::{Dvl, Spec};
use crate::train::Trained;
use indicatif::ProgressBar;
use rayon::prelude::*;

/// Which phase a Monte Carlo row belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    Calibration,
    Evaluation,
}

impl Phase {
    pub fn as_str(self) -> &'static str {
        match self {
            Phase::Calibration => "calibration",
            Phase::Evaluation => "evaluation",
        }
    }
}

impl std::str::FromStr for Phase {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        [Phase::Calibration, Phase::Evaluation]
            .into_iter()
            .find(|p| p.as_str() == s)
            .ok_or_else(|| format!("unknown phase {s:?}: expected calibration or evaluation"))
    }
}

/// One estimator's result in one run, on one window (calibration) or trajectory
/// (evaluation at T_conv).
#[derive(Debug, Clone, PartialEq)]
pub struct RunRow {
    pub run: usize,
    pub dvl: String,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    pub phase: Phase,
    pub window_s: f64,
    pub trajectory: String,
    pub rmse_cm_s: f64,
    pub correction: Correction,
}

#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationRow {
    pub dvl: String,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    pub window_s: f64,
    pub rmse_cm_s: f64,
    pub rmse_std_cm_s: f64,
    pub is_t_conv: bool,
}

#[derive(Debug, Clone, PartialEq)]
pub struct EvaluationRow {
    pub dvl: String,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    pub trajectory: String,
    pub t_conv_s: f64,
    pub rmse_cm_s: f64,
    pub rmse_std_cm_s: f64,
    /// `(baseline − this) / baseline · 100`; absent when the spec runs no baseline.
    pub improvement_pct: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Default)]
pub struct ProtocolResult {
    pub runs: Vec<RunRow>,
    pub calibration: Vec<CalibrationRow>,
    pub evaluation: Vec<EvaluationRow>,
}

/// Runs the protocol for every DVL; `progress` advances once per run and phase.
pub fn run_protocol(
    spec: &Spec,
    trajectories: &[Trajectory],
    dcnets: &[Trained],
    progress: &ProgressBar,
) -> ProtocolResult {
    let mut result = ProtocolResult::default();
    for dvl in &spec.dvls {
        run_dvl(spec, trajectories, dvl, dcnets, progress, &mut result);
    }
    add_improvements(&mut result.evaluation);
    result
}

fn run_dvl(
    spec: &Spec,
    trajectories: &[Trajectory],
    dvl: &Dvl,
    dcnets: &[Trained],
    progress: &ProgressBar,
    result: &mut ProtocolResult,
) {
    let geometry = BeamGeometry::janus_x(spec.beam_pitch_deg);
    let entries = lineup(spec, dvl, dcnets);
    let runs = spec.calibration.monte_carlo_runs;
    let calibration = &trajectories[spec.calibration.trajectory];
    let windows = &spec.calibration.window_sizes;
    let seconds = |samples: usize| samples as f64 / spec.sample_rate_hz;
    let measure = |run: usize, trajectory: &Trajectory| {
        let mut rng = task_rng(
            spec.seed,
            &[&"monte_carlo", &dvl.name, &run, &trajectory.name],
        );
        measure_trajectory(
            &geometry,
            &trajectory.ground_truth,
            &dvl.errors,
            spec.gnss_noise_m_s,
            &mut rng,
        )
    };

    // Calibration: [run][entry][window] → (rmse, terms).
    let calibrated: Vec<Vec<Vec<(f64, Correction)>>> = (0..runs)
        .into_par_iter()
        .map(|run| {
            let measured = measure(run, calibration);
            let per_entry = entries
                .iter()
                .map(|entry| {
                    windows
                        .iter()
                        .map(|&w| calibrate(entry, &measured, &calibration.ground_truth, w))
                        .collect()
                })
                .collect();
            progress.inc(1);
            per_entry
        })
        .collect();

    let mut t_conv = Vec::with_capacity(entries.len());
    for (e, entry) in entries.iter().enumerate() {
        let stats: Vec<(f64, f64)> = (0..windows.len())
            .map(|w| mean_std(calibrated.iter().map(|run| run[e][w].0)))
            .collect();
        let best = (0..windows.len()).fold(
            0,
            |best, w| if stats[w].0 < stats[best].0 { w } else { best },
        );
        t_conv.push(best);
        for (w, &(mean, std)) in stats.iter().enumerate() {
            result.calibration.push(CalibrationRow {
                dvl: dvl.name.clone(),
                estimator: entry.kind,
                error_model: entry.error_model,
                window_s: seconds(windows[w]),
                rmse_cm_s: mean,
                rmse_std_cm_s: std,
                is_t_conv: w == best,
            });
        }
    }
    for (run, per_entry) in calibrated.iter().enumerate() {
        for (entry, per_window) in entries.iter().zip(per_entry) {
            for (&w, &(rmse_cm_s, correction)) in windows.iter().zip(per_window) {
                result.runs.push(row(
                    run,
                    dvl,
                    entry,
                    Phase::Calibration,
                    seconds(w),
                    &calibration.name,
                    rmse_cm_s,
                    correction,
                ));
            }
        }
    }

    // Evaluation with each run's T_conv terms: [run][trajectory][entry] → rmse.
    let evaluated: Vec<Vec<Vec<f64>>> = (0..runs)
        .into_par_iter()
        .map(|run| {
            let per_trajectory = spec
                .evaluation
                .iter()
                .map(|&t| {
                    let trajectory = &trajectories[t];
                    let measured = measure(run, trajectory);
                    (0..entries.len())
                        .map(|e| {
                            rmse_cm_s(
                                &calibrated[run][e][t_conv[e]].1,
                                &measured.dvl,
                                &trajectory.ground_truth,
                            )
                        })
                        .collect()
                })
                .collect();
            progress.inc(1);
            per_trajectory
        })
        .collect();
    for (e, entry) in entries.iter().enumerate() {
        for (i, &t) in spec.evaluation.iter().enumerate() {
            let (mean, std) = mean_std(evaluated.iter().map(|run| run[i][e]));
            result.evaluation.push(EvaluationRow {
                dvl: dvl.name.clone(),
                estimator: entry.kind,
                error_model: entry.error_model,
                trajectory: trajectories[t].name.clone(),
                t_conv_s: seconds(windows[t_conv[e]]),
                rmse_cm_s: mean,
                rmse_std_cm_s: std,
                improvement_pct: None,
            });
        }
    }
    for (run, per_trajectory) in evaluated.iter().enumerate() {
        for (i, &t) in spec.evaluation.iter().enumerate() {
            for (e, entry) in entries.iter().enumerate() {
                let terms = calibrated[run][e][t_conv[e]].1;
                let window_s = seconds(windows[t_conv[e]]);
                result.runs.push(row(
                    run,
                    dvl,
                    entry,
                    Phase::Evaluation,
                    window_s,
                    &trajectories[t].name,
                    per_trajectory[i][e],
                    terms,
                ));
            }
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn row(
    run: usize,
    dvl: &Dvl,
    entry: &Entry,
    phase: Phase,
    window_s: f64,
    trajectory: &str,
    rmse_cm_s: f64,
    correction: Correction,
) -> RunRow {
    RunRow {
        run,
        dvl: dvl.name.clone(),
        estimator: entry.kind,
        error_model: entry.error_model,
        phase,
        window_s,
        trajectory: trajectory.to_string(),
        rmse_cm_s,
        correction,
    }
}

/// Estimates from the first `window` samples and scores the correction on the rest.
fn calibrate(
    entry: &Entry,
    measured: &Measurements,
    truth: &[Vec3],
    window: usize,
) -> (f64, Correction) {
    let correction = entry
        .estimator
        .estimate(&measured.dvl[..window], &measured.gnss[..window]);
    (
        rmse_cm_s(&correction, &measured.dvl[window..], &truth[window..]),
        correction,
    )
}

/// `sqrt(mean_t Σ_xyz (truth − corrected)²)`, in cm/s.
pub fn rmse_cm_s(correction: &Correction, dvl: &[Vec3], truth: &[Vec3]) -> f64 {
    let sum: f64 = dvl
        .iter()
        .zip(truth)
        .map(|(d, t)| {
            let c = correction.apply(*d);
            (0..3).map(|a| (c[a] - t[a]).powi(2)).sum::<f64>()
        })
        .sum();
    100.0 * (sum / dvl.len() as f64).sqrt()
}

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

fn add_improvements(rows: &mut [EvaluationRow]) {
    let baselines: Vec<(String, String, f64)> = rows
        .iter()
        .filter(|r| r.estimator == EstimatorKind::Baseline)
        .map(|r| (r.dvl.clone(), r.trajectory.clone(), r.rmse_cm_s))
        .collect();
    for row in rows {
        row.improvement_pct = baselines
            .iter()
            .find(|(dvl, trajectory, _)| *dvl == row.dvl && *trajectory == row.trajectory)
            .map(|(_, _, base)| 100.0 * (base - row.rmse_cm_s) / base);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rmse_sums_axes_and_averages_samples() {
        let truth = vec![[0.0; 3]; 2];
        let dvl = vec![[0.03, 0.04, 0.0], [0.0, 0.0, 0.0]];
        // sqrt((0.0009 + 0.0016 + 0) / 2) m/s = 0.035355 m/s.
        assert!((rmse_cm_s(&Correction::NONE, &dvl, &truth) - 3.5355339).abs() < 1e-6);
    }

    #[test]
    fn sample_standard_deviation() {
        let (mean, std) = mean_std([1.0, 2.0, 3.0, 4.0].into_iter());
        assert_eq!(mean, 2.5);
        assert!((std - 1.2909944).abs() < 1e-6);
        assert_eq!(mean_std([5.0].into_iter()), (5.0, 0.0));
    }
}
