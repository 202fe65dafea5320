//! The Monte Carlo runs of the protocol: each run measures the calibration trajectory
//! of one DVL with fresh noise, every estimator estimates its terms from the first w
//! seconds for every window size w, and the RMSE of the corrected remainder is taken;
//! each estimator's T_conv terms then correct freshly measured test trajectories, and
//! its terms from every calibration length of its held-out curve
//! ([`calibration_time`](super::calibration_time)) correct the same measurements,
//! pooled. In: the spec, the trajectories, the DVL and its estimators. Out: per-run
//! rows, one list per estimator.

use super::calibration_time::{HeldOutScore, curve_lengths};
use super::rows::{ProtocolResult, RunRow};
use super::statistics::mean_std;
use super::summary::t_conv_index;
use super::terms_in_time::terms_in_time;
use crate::Vec3;
use crate::bound::bounds;
use crate::data::Trajectory;
use crate::estimators::{DvlEstimator, set_up};
use crate::noise::{BeamGeometry, Measurements, measure_trajectory};
use crate::progress::Progress;
use crate::rng::task_rng;
use crate::spec::{Dvl, Spec};
use crate::train::Trained;
use crate::vocab::{Correction, HELD_OUT, Phase};
use rayon::prelude::*;

/// Runs the protocol for every DVL and estimator; `progress` advances once per run and
/// phase of each DVL.
pub fn run_protocol(
    spec: &Spec,
    trajectories: &[Trajectory],
    dcnets: &[Trained],
    progress: &Progress,
) -> ProtocolResult {
    let runs: Vec<RunRow> = spec
        .dvls
        .iter()
        .flat_map(|dvl| {
            let entries = set_up(spec, dvl, dcnets);
            run_on_dvl(spec, trajectories, dvl, &entries, progress)
        })
        .flatten()
        .collect();
    ProtocolResult {
        terms_in_time: terms_in_time(spec, trajectories),
        ..ProtocolResult::from_runs(
            runs,
            &bounds(spec, trajectories),
            spec.calibration.time_tolerance,
        )
    }
}

/// The protocol of `entries` on one DVL, every Monte Carlo run: one list of rows per
/// entry, calibration rows (run, window) then evaluation rows (run, trajectory). Each
/// entry's rows depend on nothing but that entry, so entries can be computed apart and
/// put together; computing them together only shares the measurements.
pub fn run_on_dvl(
    spec: &Spec,
    trajectories: &[Trajectory],
    dvl: &Dvl,
    entries: &[DvlEstimator],
    progress: &Progress,
) -> Vec<Vec<RunRow>> {
    let inputs = ProtocolInputs {
        spec,
        trajectories,
        dvl,
        entries,
        geometry: BeamGeometry::janus_x(spec.beam_pitch_deg),
        progress,
    };
    progress.set_message(format!(
        "calibration on {}",
        trajectories[spec.calibration.trajectory].name
    ));
    let calibrated = inputs.calibrate_runs();
    let t_conv = inputs.t_conv(&calibrated);
    progress.set_message("evaluation at T_conv".to_string());
    let evaluated = inputs.evaluate_runs(&calibrated, &t_conv);
    (0..entries.len())
        .map(|e| inputs.entry_rows(e, &calibrated, &evaluated, t_conv[e]))
        .collect()
}

/// Calibration results: [run][entry][window] → (rmse, terms).
type Calibrated = Vec<Vec<Vec<(f64, Correction)>>>;

/// One run's evaluation: the RMSE of each entry's T_conv terms, [trajectory][entry],
/// and each entry's held-out curve, [entry] → (length in samples, RMSE, terms).
struct RunEvaluation {
    trajectories: Vec<Vec<f64>>,
    curves: Vec<Vec<(usize, f64, Correction)>>,
}

/// Every run's evaluation.
type Evaluated = Vec<RunEvaluation>;

/// What every stage of [`run_on_dvl`] reads: the spec, the DVL and its estimators.
struct ProtocolInputs<'a> {
    spec: &'a Spec,
    trajectories: &'a [Trajectory],
    dvl: &'a Dvl,
    entries: &'a [DvlEstimator],
    geometry: BeamGeometry,
    progress: &'a Progress,
}

impl ProtocolInputs<'_> {
    /// The calibration trajectory.
    fn calibration(&self) -> &Trajectory {
        &self.trajectories[self.spec.calibration.trajectory]
    }

    /// `samples` at the spec's sample rate, in seconds.
    fn seconds(&self, samples: usize) -> f64 {
        samples as f64 / self.spec.sample_rate_hz
    }

    /// The DVL's and GNSS's measurements of `trajectory` in Monte Carlo run `run`.
    fn measure(&self, run: usize, trajectory: &Trajectory) -> Measurements {
        let mut rng = task_rng(
            self.spec.seed,
            &[&"monte_carlo", &self.dvl.name, &run, &trajectory.name],
        );
        measure_trajectory(
            &self.geometry,
            &trajectory.ground_truth,
            &self.dvl.errors,
            self.spec.gnss_noise_m_s,
            &mut rng,
        )
    }

    /// Every entry calibrated on every window, in every run; `progress` advances once
    /// a run.
    fn calibrate_runs(&self) -> Calibrated {
        let calibration = self.calibration();
        let windows = &self.spec.calibration.window_sizes;
        (0..self.spec.calibration.monte_carlo_runs)
            .into_par_iter()
            .map(|run| {
                let measured = self.measure(run, calibration);
                let per_entry = self
                    .entries
                    .iter()
                    .map(|entry| {
                        windows
                            .iter()
                            .map(|&w| calibrate(entry, &measured, &calibration.ground_truth, w))
                            .collect()
                    })
                    .collect();
                self.progress.inc(1);
                per_entry
            })
            .collect()
    }

    /// Each entry's T_conv: the index of the window with the lowest mean RMSE over runs.
    fn t_conv(&self, calibrated: &Calibrated) -> Vec<usize> {
        let windows = self.spec.calibration.window_sizes.len();
        (0..self.entries.len())
            .map(|e| {
                let means: Vec<f64> = (0..windows)
                    .map(|w| mean_std(calibrated.iter().map(|run| run[e][w].0)).0)
                    .collect();
                t_conv_index(&means)
            })
            .collect()
    }

    /// Every entry's T_conv terms of each run scored on that run's measurements of every
    /// evaluation trajectory, and its held-out curve on them pooled; `progress`
    /// advances once a run.
    fn evaluate_runs(&self, calibrated: &Calibrated, t_conv: &[usize]) -> Evaluated {
        (0..self.spec.calibration.monte_carlo_runs)
            .into_par_iter()
            .map(|run| {
                let mut pooled = HeldOutScore::default();
                let trajectories = self
                    .spec
                    .evaluation
                    .iter()
                    .map(|&t| {
                        let trajectory = &self.trajectories[t];
                        let measured = self.measure(run, trajectory);
                        // The calibration trajectory, when a spec tests on it too, is
                        // not held out.
                        if t != self.spec.calibration.trajectory {
                            pooled.add(&measured.dvl, &trajectory.ground_truth);
                        }
                        (0..self.entries.len())
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
                let curves = self.held_out_curves(run, &calibrated[run], &pooled);
                self.progress.inc(1);
                RunEvaluation {
                    trajectories,
                    curves,
                }
            })
            .collect()
    }

    /// Each entry's terms of run `run` from every length of its held-out curve, scored
    /// on `pooled`: DCNet's are those of its calibration windows, the others' are
    /// estimated again from each first n samples of the run's calibration measurement.
    fn held_out_curves(
        &self,
        run: usize,
        calibrated: &[Vec<(f64, Correction)>],
        pooled: &HeldOutScore,
    ) -> Vec<Vec<(usize, f64, Correction)>> {
        let windows = &self.spec.calibration.window_sizes;
        let measured = self.measure(run, self.calibration());
        self.entries
            .iter()
            .zip(calibrated)
            .map(|(entry, per_window)| {
                let lengths = curve_lengths(entry.kind, windows);
                let corrections: Vec<Correction> = if lengths == *windows {
                    per_window.iter().map(|(_, c)| *c).collect()
                } else {
                    entry
                        .estimator
                        .estimate_prefixes(&measured.dvl, &measured.gnss, &lengths)
                };
                lengths
                    .into_iter()
                    .zip(corrections)
                    .map(|(n, c)| (n, pooled.rmse_cm_s(&c), c))
                    .collect()
            })
            .collect()
    }

    /// Entry `e`'s rows, calibration (run, window), evaluation (run, trajectory) at its
    /// T_conv window `t_conv`, then held out (run, length).
    fn entry_rows(
        &self,
        e: usize,
        calibrated: &Calibrated,
        evaluated: &Evaluated,
        t_conv: usize,
    ) -> Vec<RunRow> {
        let entry = &self.entries[e];
        let windows = &self.spec.calibration.window_sizes;
        let mut rows = Vec::new();
        for (run, per_entry) in calibrated.iter().enumerate() {
            for (&w, &(rmse_cm_s, correction)) in windows.iter().zip(&per_entry[e]) {
                rows.push(row(
                    run,
                    self.dvl,
                    entry,
                    Phase::Calibration,
                    self.seconds(w),
                    &self.calibration().name,
                    rmse_cm_s,
                    correction,
                ));
            }
        }
        for (run, evaluation) in evaluated.iter().enumerate() {
            for (i, &t) in self.spec.evaluation.iter().enumerate() {
                rows.push(row(
                    run,
                    self.dvl,
                    entry,
                    Phase::Evaluation,
                    self.seconds(windows[t_conv]),
                    &self.trajectories[t].name,
                    evaluation.trajectories[i][e],
                    calibrated[run][e][t_conv].1,
                ));
            }
        }
        for (run, evaluation) in evaluated.iter().enumerate() {
            for &(length, rmse_cm_s, correction) in &evaluation.curves[e] {
                rows.push(row(
                    run,
                    self.dvl,
                    entry,
                    Phase::HeldOut,
                    self.seconds(length),
                    HELD_OUT,
                    rmse_cm_s,
                    correction,
                ));
            }
        }
        rows
    }
}

#[allow(clippy::too_many_arguments)]
fn row(
    run: usize,
    dvl: &Dvl,
    entry: &DvlEstimator,
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
        replicate: entry.replicate,
        phase,
        window_s,
        trajectory: trajectory.to_string(),
        rmse_cm_s,
        correction,
    }
}

/// Estimates from the first `window` samples and scores the correction on the rest.
fn calibrate(
    entry: &DvlEstimator,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vocab::EstimatorKind;

    #[test]
    fn rmse_sums_axes_and_averages_samples() {
        let truth = vec![[0.0; 3]; 2];
        let dvl = vec![[0.03, 0.04, 0.0], [0.0, 0.0, 0.0]];
        // sqrt((0.0009 + 0.0016 + 0) / 2) m/s = 0.035355 m/s.
        assert!((rmse_cm_s(&Correction::NONE, &dvl, &truth) - 3.5355339).abs() < 1e-6);
    }

    /// 1000 Monte Carlo runs of every estimator but DCNet on the quick spec's synthetic
    /// trajectories, both DVLs: the beam-model WLS, an efficient estimator, has the
    /// bound's mean RMSE within 3 % at every window and on every test trajectory, and
    /// no estimator's mean RMSE is below the bound by more than its standard error.
    #[test]
    fn the_bound_is_the_efficient_estimators_mean_and_no_estimator_beats_it() {
        let runs = 1000;
        let spec = crate::spec::quick_spec(&[
            "estimators.kinds=[\"baseline\", \"least_squares\", \"beam_wls\", \"floor\"]",
            &format!("calibration.monte_carlo_runs={runs}"),
        ]);
        let trajectories = crate::data::load_trajectories(&spec).unwrap();
        let result = run_protocol(&spec, &trajectories, &[], &Progress::hidden());
        let bound_rows = result
            .calibration
            .iter()
            .filter(|r| r.estimator == EstimatorKind::Bound);
        assert_eq!(bound_rows.count(), 2 * spec.calibration.window_sizes.len());
        let cells = result
            .calibration
            .iter()
            .map(|r| {
                (
                    r.estimator,
                    r.error_model,
                    r.efficiency,
                    r.rmse_cm_s,
                    r.rmse_std_cm_s,
                )
            })
            .chain(result.evaluation.iter().map(|r| {
                (
                    r.estimator,
                    r.error_model,
                    r.efficiency,
                    r.rmse_cm_s,
                    r.rmse_std_cm_s,
                )
            }));
        let mut efficient = 0;
        for (estimator, model, efficiency, rmse, std) in cells {
            if matches!(estimator, EstimatorKind::Floor | EstimatorKind::Bound) {
                assert_eq!(efficiency, None);
                continue;
            }
            let efficiency = efficiency.expect("every estimator has an efficiency");
            let bound = efficiency * rmse;
            let standard_error = std / (runs as f64).sqrt();
            assert!(
                rmse >= bound - standard_error,
                "{estimator} {model:?}: {rmse} cm/s is below the bound {bound} by more than {standard_error}"
            );
            if estimator == EstimatorKind::BeamWls {
                assert!(
                    (efficiency - 1.0).abs() < 0.03,
                    "beam-model WLS at {rmse} cm/s against the bound {bound}"
                );
                efficient += 1;
            }
        }
        assert_eq!(efficient, 2 * (5 + 2));
    }
}
