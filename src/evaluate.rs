//! The paper's protocol. For each DVL under test, each Monte Carlo run measures the
//! calibration trajectory with fresh noise, every estimator estimates its terms from the
//! first w seconds for every window size w, and the RMSE of the corrected remainder is
//! taken. T_conv is the window with the lowest mean RMSE over runs. Each run's T_conv
//! terms then correct freshly measured test trajectories. The tables set each DVL's
//! information bound after its estimators and give every estimator its efficiency
//! against it. In: the spec, the trajectories. Out: per-run rows and the calibration
//! and evaluation tables.
//!
//! With `training.replicates` above 1, each DCNet replicate runs the protocol as its
//! own method (its own T_conv); the tables then hold one row per window or trajectory
//! for DCNet: the mean over replicates with a 95 % Student t confidence interval
//! across them, T_conv the argmin of the replicate-mean curve in calibration and the
//! mean of the replicates' T_conv in evaluation.
//!
//! Runs go in parallel; every measurement draws from a generator seeded by (seed, DVL,
//! run, trajectory) and every mean is summed in run order, so the numbers do not
//! depend on the thread count.

use crate::bound::{BoundRow, bounds};
use crate::data::Trajectory;
use crate::estimators::{DvlEstimator, set_up};
use crate::noise::{BeamGeometry, Measurements, measure_trajectory};
use crate::progress::Progress;
use crate::rng::task_rng;
use crate::spec::{Dvl, Spec};
use crate::train::Trained;
use crate::vocab::{Correction, ErrorModel, EstimatorKind, Phase};
use crate::{Vec3, first_seen};
use rayon::prelude::*;

/// One estimator's result in one run, on one window (calibration) or trajectory
/// (evaluation at T_conv).
#[derive(Debug, Clone, PartialEq)]
pub struct RunRow {
    pub run: usize,
    pub dvl: String,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    /// The DCNet replicate, when `training.replicates` is above 1.
    pub replicate: Option<usize>,
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
    /// Half-width of the 95 % confidence interval of the mean over DCNet replicates,
    /// when there are several.
    pub rmse_ci_cm_s: Option<f64>,
    pub is_t_conv: bool,
    /// The bound at this window over this RMSE; absent for the floor and the bound.
    pub efficiency: Option<f64>,
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
    /// Half-width of the 95 % confidence interval of the mean over DCNet replicates,
    /// when there are several.
    pub rmse_ci_cm_s: Option<f64>,
    /// `(baseline − this) / baseline · 100`; absent when the spec runs no baseline.
    pub improvement_pct: Option<f64>,
    /// The bound at this T_conv on this trajectory over this RMSE; absent for the floor
    /// and the bound.
    pub efficiency: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Default)]
pub struct ProtocolResult {
    pub runs: Vec<RunRow>,
    pub calibration: Vec<CalibrationRow>,
    pub evaluation: Vec<EvaluationRow>,
}

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
            run_block(spec, trajectories, dvl, &entries, progress)
        })
        .flatten()
        .collect();
    ProtocolResult::from_runs(runs, &bounds(spec, trajectories))
}

/// The protocol of `entries` on one DVL, every Monte Carlo run: one list of rows per
/// entry, calibration rows (run, window) then evaluation rows (run, trajectory). Each
/// entry's rows depend on nothing but that entry, so entries can be computed apart and
/// put together; computing them together only shares the measurements.
pub fn run_block(
    spec: &Spec,
    trajectories: &[Trajectory],
    dvl: &Dvl,
    entries: &[DvlEstimator],
    progress: &Progress,
) -> Vec<Vec<RunRow>> {
    let block = Block {
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
    let calibrated = block.calibrate_runs();
    let t_conv = block.t_conv(&calibrated);
    progress.set_message("evaluation at T_conv".to_string());
    let evaluated = block.evaluate_runs(&calibrated, &t_conv);
    (0..entries.len())
        .map(|e| block.entry_rows(e, &calibrated, &evaluated, t_conv[e]))
        .collect()
}

/// Calibration results: [run][entry][window] → (rmse, terms).
type Calibrated = Vec<Vec<Vec<(f64, Correction)>>>;

/// Evaluation results with each run's T_conv terms: [run][trajectory][entry] → rmse.
type Evaluated = Vec<Vec<Vec<f64>>>;

/// What every stage of [`run_block`] reads: the spec, the DVL and its estimators.
struct Block<'a> {
    spec: &'a Spec,
    trajectories: &'a [Trajectory],
    dvl: &'a Dvl,
    entries: &'a [DvlEstimator],
    geometry: BeamGeometry,
    progress: &'a Progress,
}

impl Block<'_> {
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
    /// evaluation trajectory; `progress` advances once a run.
    fn evaluate_runs(&self, calibrated: &Calibrated, t_conv: &[usize]) -> Evaluated {
        (0..self.spec.calibration.monte_carlo_runs)
            .into_par_iter()
            .map(|run| {
                let per_trajectory = self
                    .spec
                    .evaluation
                    .iter()
                    .map(|&t| {
                        let trajectory = &self.trajectories[t];
                        let measured = self.measure(run, trajectory);
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
                self.progress.inc(1);
                per_trajectory
            })
            .collect()
    }

    /// Entry `e`'s rows, calibration (run, window) then evaluation (run, trajectory) at
    /// its T_conv window `t_conv`.
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
        for (run, per_trajectory) in evaluated.iter().enumerate() {
            for (i, &t) in self.spec.evaluation.iter().enumerate() {
                rows.push(row(
                    run,
                    self.dvl,
                    entry,
                    Phase::Evaluation,
                    self.seconds(windows[t_conv]),
                    &self.trajectories[t].name,
                    per_trajectory[i][e],
                    calibrated[run][e][t_conv].1,
                ));
            }
        }
        rows
    }
}

/// The index of T_conv among the windows: the lowest mean RMSE, the first of equals.
fn t_conv_index(mean_rmse: &[f64]) -> usize {
    (0..mean_rmse.len()).fold(0, |best, w| {
        if mean_rmse[w] < mean_rmse[best] {
            w
        } else {
            best
        }
    })
}

impl ProtocolResult {
    /// The calibration and evaluation tables of the per-run rows of [`run_block`]: means
    /// and standard deviations over runs, summed in run order, and T_conv. The rows of
    /// DCNet replicates become one series: see [`combine_replicates`]. Each DVL's
    /// `bounds` follow its estimators, and every estimator gets its efficiency.
    pub fn from_runs(runs: Vec<RunRow>, bounds: &[BoundRow]) -> ProtocolResult {
        let mut result = ProtocolResult::default();
        let same = |a: &RunRow, b: &RunRow| {
            a.dvl == b.dvl && a.estimator == b.estimator && a.error_model == b.error_model
        };
        let mut start = 0;
        while start < runs.len() {
            let end = start
                + runs[start..]
                    .iter()
                    .take_while(|r| same(r, &runs[start]))
                    .count();
            let block = &runs[start..end];
            let replicates = first_seen(block.iter().map(|r| r.replicate));
            let (calibration, evaluation) = if replicates == [None] {
                with_efficiency(summarize(block), bounds)
            } else {
                let per_replicate: Vec<Tables> = replicates
                    .iter()
                    .map(|&replicate| {
                        let rows: Vec<RunRow> = block
                            .iter()
                            .filter(|r| r.replicate == replicate)
                            .cloned()
                            .collect();
                        with_efficiency(summarize(&rows), bounds)
                    })
                    .collect();
                combine_replicates(block, &per_replicate)
            };
            result.calibration.extend(calibration);
            result.evaluation.extend(evaluation);
            start = end;
        }
        add_bounds(&mut result, bounds);
        add_improvements(&mut result.evaluation);
        result.runs = runs;
        result
    }
}

/// The tables of one series with every row's efficiency: the bound over its RMSE, at
/// its window (calibration) or T_conv (evaluation); none for the floor.
fn with_efficiency((mut calibration, mut evaluation): Tables, bounds: &[BoundRow]) -> Tables {
    // The calibration bound of a window is scored on the rest of the one calibration
    // trajectory; an evaluation bound on the trajectory named.
    let bound = |dvl: &str, window_s: f64, trajectory: Option<&str>| {
        bounds.iter().find(|b| {
            b.dvl == dvl
                && b.window_s == window_s
                && match trajectory {
                    None => b.phase == Phase::Calibration,
                    Some(t) => b.phase == Phase::Evaluation && b.trajectory == t,
                }
        })
    };
    let efficiency = |kind: EstimatorKind, bound: Option<&BoundRow>, rmse_cm_s: f64| {
        bound
            .filter(|_| kind != EstimatorKind::Floor)
            .map(|b| b.rmse_cm_s / rmse_cm_s)
    };
    for row in &mut calibration {
        let at = bound(&row.dvl, row.window_s, None);
        row.efficiency = efficiency(row.estimator, at, row.rmse_cm_s);
    }
    for row in &mut evaluation {
        let at = bound(&row.dvl, row.t_conv_s, Some(&row.trajectory));
        row.efficiency = efficiency(row.estimator, at, row.rmse_cm_s);
    }
    (calibration, evaluation)
}

/// Puts each DVL's bound after its estimators' rows: calibration rows for every window
/// and evaluation rows at the bound's own T_conv.
fn add_bounds(result: &mut ProtocolResult, bounds: &[BoundRow]) {
    for dvl in first_seen(bounds.iter().map(|b| b.dvl.as_str())) {
        let curve: Vec<&BoundRow> = bounds
            .iter()
            .filter(|b| b.dvl == dvl && b.phase == Phase::Calibration)
            .collect();
        let best = t_conv_index(&curve.iter().map(|b| b.rmse_cm_s).collect::<Vec<_>>());
        let calibration = curve.iter().enumerate().map(|(w, b)| CalibrationRow {
            dvl: dvl.to_string(),
            estimator: EstimatorKind::Bound,
            error_model: None,
            window_s: b.window_s,
            rmse_cm_s: b.rmse_cm_s,
            rmse_std_cm_s: b.rmse_std_cm_s,
            rmse_ci_cm_s: None,
            is_t_conv: w == best,
            efficiency: None,
        });
        let t_conv_s = curve[best].window_s;
        let evaluation = bounds
            .iter()
            .filter(|b| b.dvl == dvl && b.phase == Phase::Evaluation && b.window_s == t_conv_s)
            .map(|b| EvaluationRow {
                dvl: dvl.to_string(),
                estimator: EstimatorKind::Bound,
                error_model: None,
                trajectory: b.trajectory.clone(),
                t_conv_s,
                rmse_cm_s: b.rmse_cm_s,
                rmse_std_cm_s: b.rmse_std_cm_s,
                rmse_ci_cm_s: None,
                improvement_pct: None,
                efficiency: None,
            });
        insert_after_dvl(&mut result.calibration, |r| r.dvl == dvl, calibration);
        insert_after_dvl(&mut result.evaluation, |r| r.dvl == dvl, evaluation);
    }
}

/// Inserts `new` after the last row that `of_dvl` holds, or at the end.
fn insert_after_dvl<T>(
    rows: &mut Vec<T>,
    of_dvl: impl Fn(&T) -> bool,
    new: impl Iterator<Item = T>,
) {
    let at = rows.iter().rposition(of_dvl).map_or(rows.len(), |i| i + 1);
    rows.splice(at..at, new);
}
/// The calibration and evaluation rows of one series.
type Tables = (Vec<CalibrationRow>, Vec<EvaluationRow>);

/// The tables of the runs of one series (DVL, estimator, error model, replicate).
fn summarize(block: &[RunRow]) -> Tables {
    let first = &block[0];
    let in_phase = |phase: Phase| block.iter().filter(move |r| r.phase == phase);
    let windows = first_seen(in_phase(Phase::Calibration).map(|r| r.window_s));
    let stats: Vec<(f64, f64, f64)> = windows
        .iter()
        .map(|&w| {
            let (mean, std) = mean_std(
                in_phase(Phase::Calibration)
                    .filter(|r| r.window_s == w)
                    .map(|r| r.rmse_cm_s),
            );
            (w, mean, std)
        })
        .collect();
    let means: Vec<f64> = stats.iter().map(|s| s.1).collect();
    let best = t_conv_index(&means);
    let calibration = stats
        .iter()
        .enumerate()
        .map(|(w, &(window_s, mean, std))| CalibrationRow {
            dvl: first.dvl.clone(),
            estimator: first.estimator,
            error_model: first.error_model,
            window_s,
            rmse_cm_s: mean,
            rmse_std_cm_s: std,
            rmse_ci_cm_s: None,
            is_t_conv: w == best,
            efficiency: None,
        })
        .collect();
    let evaluation = first_seen(in_phase(Phase::Evaluation).map(|r| r.trajectory.clone()))
        .into_iter()
        .map(|trajectory| {
            let rows: Vec<&RunRow> = in_phase(Phase::Evaluation)
                .filter(|r| r.trajectory == trajectory)
                .collect();
            let (mean, std) = mean_std(rows.iter().map(|r| r.rmse_cm_s));
            EvaluationRow {
                dvl: first.dvl.clone(),
                estimator: first.estimator,
                error_model: first.error_model,
                trajectory,
                t_conv_s: rows[0].window_s,
                rmse_cm_s: mean,
                rmse_std_cm_s: std,
                rmse_ci_cm_s: None,
                improvement_pct: None,
                efficiency: None,
            }
        })
        .collect();
    (calibration, evaluation)
}

/// One series from the tables of its replicates: each RMSE the mean of the replicates'
/// means with its 95 % confidence interval, each standard deviation that of every run
/// of every replicate (`block`); the calibration's T_conv the argmin of the mean curve,
/// the evaluation's the mean of the replicates' T_conv; each efficiency the mean of the
/// replicates' bounds (each at its own T_conv) over the mean RMSE.
fn combine_replicates(block: &[RunRow], per_replicate: &[Tables]) -> Tables {
    let (mut calibration, mut evaluation) = per_replicate[0].clone();
    let pooled_std = |phase: Phase, keep: &dyn Fn(&RunRow) -> bool| {
        mean_std(
            block
                .iter()
                .filter(|r| r.phase == phase && keep(r))
                .map(|r| r.rmse_cm_s),
        )
        .1
    };
    // The mean of the replicates' bounds (efficiency × RMSE) over `mean`.
    let efficiency = |bounds: Option<Vec<f64>>, mean: f64| {
        bounds.map(|b| b.iter().sum::<f64>() / b.len() as f64 / mean)
    };
    for (w, row) in calibration.iter_mut().enumerate() {
        let means: Vec<f64> = per_replicate.iter().map(|t| t.0[w].rmse_cm_s).collect();
        let (mean, ci) = mean_ci95(&means);
        let bounds = per_replicate
            .iter()
            .map(|t| t.0[w].efficiency.map(|e| e * t.0[w].rmse_cm_s));
        row.efficiency = efficiency(bounds.collect(), mean);
        row.rmse_cm_s = mean;
        row.rmse_ci_cm_s = Some(ci);
        row.rmse_std_cm_s = pooled_std(Phase::Calibration, &|r| r.window_s == row.window_s);
    }
    let means: Vec<f64> = calibration.iter().map(|r| r.rmse_cm_s).collect();
    let best = t_conv_index(&means);
    for (w, row) in calibration.iter_mut().enumerate() {
        row.is_t_conv = w == best;
    }
    for (j, row) in evaluation.iter_mut().enumerate() {
        let means: Vec<f64> = per_replicate.iter().map(|t| t.1[j].rmse_cm_s).collect();
        let (mean, ci) = mean_ci95(&means);
        let bounds = per_replicate
            .iter()
            .map(|t| t.1[j].efficiency.map(|e| e * t.1[j].rmse_cm_s));
        row.efficiency = efficiency(bounds.collect(), mean);
        row.rmse_cm_s = mean;
        row.rmse_ci_cm_s = Some(ci);
        row.rmse_std_cm_s = pooled_std(Phase::Evaluation, &|r| r.trajectory == row.trajectory);
        row.t_conv_s = mean_std(per_replicate.iter().map(|t| t.1[j].t_conv_s)).0;
    }
    (calibration, evaluation)
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

    #[test]
    fn confidence_interval_of_three_values() {
        // t_{0.975, 2} = 4.3027; sd of [1, 2, 3] = 1; 4.3027 / √3 = 2.4841.
        let (mean, ci) = mean_ci95(&[1.0, 2.0, 3.0]);
        assert_eq!(mean, 2.0);
        assert!((ci - 2.4841).abs() < 1e-4, "{ci}");
    }

    /// A DCNet run row of `replicate`: calibration on window `window_s`, or evaluation
    /// on "T" at T_conv `window_s`.
    fn dcnet_row(replicate: usize, run: usize, phase: Phase, window_s: f64, rmse: f64) -> RunRow {
        RunRow {
            run,
            dvl: "DVL1".into(),
            estimator: EstimatorKind::Dcnet,
            error_model: Some(ErrorModel::Em5),
            replicate: Some(replicate),
            phase,
            window_s,
            trajectory: "T".into(),
            rmse_cm_s: rmse,
            correction: Correction::NONE,
        }
    }

    #[test]
    fn replicates_become_one_series_with_a_confidence_interval() {
        // Two runs each; replicate means: window 20 → 1, 2, 3; window 40 → 2, 2, 2.
        // Each replicate's own T_conv: 20, 20, 40; the mean curve's: 40.
        let mut runs = Vec::new();
        for (replicate, (at_20, at_40, t_conv, test)) in [
            (1.0, 2.0, 20.0, 1.0),
            (2.0, 2.0, 20.0, 2.0),
            (3.0, 2.0, 40.0, 3.0),
        ]
        .into_iter()
        .enumerate()
        {
            for run in 0..2 {
                let spread = if run == 0 { -0.5 } else { 0.5 };
                runs.push(dcnet_row(
                    replicate,
                    run,
                    Phase::Calibration,
                    20.0,
                    at_20 + spread,
                ));
                runs.push(dcnet_row(replicate, run, Phase::Calibration, 40.0, at_40));
            }
            for run in 0..2 {
                runs.push(dcnet_row(replicate, run, Phase::Evaluation, t_conv, test));
            }
        }
        // The bound on T: 0.5 cm/s from 20 s of calibration, 1.4 from 40 s; on the
        // calibration trajectory 1.0 at both.
        let bound = |window_s: f64, phase: Phase, rmse_cm_s: f64| BoundRow {
            dvl: "DVL1".into(),
            window_s,
            phase,
            trajectory: "T".into(),
            rmse_cm_s,
            rmse_std_cm_s: 0.0,
        };
        let bounds = [
            bound(20.0, Phase::Calibration, 1.0),
            bound(20.0, Phase::Evaluation, 0.5),
            bound(40.0, Phase::Calibration, 1.0),
            bound(40.0, Phase::Evaluation, 1.4),
        ];
        let result = ProtocolResult::from_runs(runs, &bounds);
        let estimator = |r: &&CalibrationRow| r.estimator == EstimatorKind::Dcnet;
        let calibration: Vec<&CalibrationRow> =
            result.calibration.iter().filter(estimator).collect();
        assert_eq!(calibration.len(), 2);
        let [at_20, at_40] = [calibration[0], calibration[1]];
        assert_eq!(at_20.efficiency, Some(1.0 / 2.0));
        assert_eq!(at_20.rmse_cm_s, 2.0);
        assert!((at_20.rmse_ci_cm_s.unwrap() - 2.4841).abs() < 1e-4);
        assert_eq!((at_40.rmse_cm_s, at_40.rmse_ci_cm_s), (2.0, Some(0.0)));
        // Equal means: the first of equals, as for one model.
        assert!(at_20.is_t_conv && !at_40.is_t_conv);
        assert_eq!(result.evaluation.len(), 2, "DCNet's row and the bound's");
        let test = &result.evaluation[0];
        assert_eq!(test.rmse_cm_s, 2.0);
        // Each replicate's bound at its own T_conv, 0.5, 0.5 and 1.4, over the mean RMSE.
        assert!((test.efficiency.unwrap() - 0.8 / 2.0).abs() < 1e-12);
        assert!((test.rmse_ci_cm_s.unwrap() - 2.4841).abs() < 1e-4);
        assert!((test.t_conv_s - 80.0 / 3.0).abs() < 1e-12);
        // The spread over all six runs at window 20: 0.5 around 1, 2, 3.
        let all = [0.5, 1.5, 1.5, 2.5, 2.5, 3.5];
        assert!((at_20.rmse_std_cm_s - mean_std(all.into_iter()).1).abs() < 1e-12);
    }

    #[test]
    fn a_single_model_has_no_confidence_interval() {
        let mut rows = vec![dcnet_row(0, 0, Phase::Calibration, 20.0, 1.0)];
        rows[0].replicate = None;
        let result = ProtocolResult::from_runs(rows, &[]);
        assert_eq!(result.calibration[0].rmse_ci_cm_s, None);
    }

    #[test]
    fn sample_standard_deviation() {
        let (mean, std) = mean_std([1.0, 2.0, 3.0, 4.0].into_iter());
        assert_eq!(mean, 2.5);
        assert!((std - 1.2909944).abs() < 1e-6);
        assert_eq!(mean_std([5.0].into_iter()), (5.0, 0.0));
    }
}
