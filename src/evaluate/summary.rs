//! The tables of the protocol, summed from its per-run rows: for each series (DVL,
//! estimator, error model, replicate) the mean and standard deviation over runs at
//! every window and on every test trajectory, and T_conv; the series of DCNet
//! replicates combined into one, with a confidence interval; each DVL's information
//! bound after its estimators, every estimator's efficiency against it, and the
//! improvement over the baseline. In: per-run rows and the bounds. Out: a
//! [`ProtocolResult`].

use super::calibration_time::{calibration_times, held_out_curves};
use super::rows::{CalibrationRow, EvaluationRow, ProtocolResult, RunRow};
use super::statistics::{mean_ci95, mean_std};
use crate::bound::BoundRow;
use crate::first_seen;
use crate::vocab::{EstimatorKind, Phase};

/// The index of T_conv among the windows: the lowest mean RMSE, the first of equals.
pub(super) fn t_conv_index(mean_rmse: &[f64]) -> usize {
    (0..mean_rmse.len()).fold(0, |best, w| {
        if mean_rmse[w] < mean_rmse[best] {
            w
        } else {
            best
        }
    })
}

/// The calibration and evaluation rows of one series (DVL, estimator, error model,
/// replicate).
#[derive(Debug, Clone, PartialEq)]
struct SeriesSummary {
    calibration: Vec<CalibrationRow>,
    evaluation: Vec<EvaluationRow>,
}

impl ProtocolResult {
    /// The calibration and evaluation tables of the per-run rows of `run_on_dvl`: means
    /// and standard deviations over runs, summed in run order, and T_conv. The rows of
    /// DCNet replicates become one series: see `combine_replicates`. Each DVL's
    /// `bounds` follow its estimators, and every estimator gets its efficiency.
    pub fn from_runs(
        runs: Vec<RunRow>,
        bounds: &[BoundRow],
        time_tolerance: f64,
    ) -> ProtocolResult {
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
            let series = &runs[start..end];
            let replicates = first_seen(series.iter().map(|r| r.replicate));
            let summary = if replicates == [None] {
                with_efficiency(summarize(series), bounds)
            } else {
                let per_replicate: Vec<SeriesSummary> = replicates
                    .iter()
                    .map(|&replicate| {
                        let rows: Vec<RunRow> = series
                            .iter()
                            .filter(|r| r.replicate == replicate)
                            .cloned()
                            .collect();
                        with_efficiency(summarize(&rows), bounds)
                    })
                    .collect();
                combine_replicates(series, &per_replicate)
            };
            result.calibration.extend(summary.calibration);
            result.evaluation.extend(summary.evaluation);
            start = end;
        }
        add_bounds(&mut result, bounds);
        add_improvements(&mut result.evaluation);
        result.held_out = held_out_curves(&runs, bounds);
        result.calibration_time =
            calibration_times(&result.held_out, &result.calibration, time_tolerance);
        result.runs = runs;
        result
    }
}

/// The tables of one series with every row's efficiency: the bound over its RMSE, at
/// its window (calibration) or T_conv (evaluation); none for the floor.
fn with_efficiency(mut summary: SeriesSummary, bounds: &[BoundRow]) -> SeriesSummary {
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
    for row in &mut summary.calibration {
        let at = bound(&row.dvl, row.window_s, None);
        row.efficiency = efficiency(row.estimator, at, row.rmse_cm_s);
    }
    for row in &mut summary.evaluation {
        let at = bound(&row.dvl, row.t_conv_s, Some(&row.trajectory));
        row.efficiency = efficiency(row.estimator, at, row.rmse_cm_s);
    }
    summary
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

/// The tables of the runs of one series (DVL, estimator, error model, replicate).
fn summarize(series: &[RunRow]) -> SeriesSummary {
    let first = &series[0];
    let in_phase = |phase: Phase| series.iter().filter(move |r| r.phase == phase);
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
    SeriesSummary {
        calibration,
        evaluation,
    }
}

/// One series from the tables of its replicates: each RMSE the mean of the replicates'
/// means with its 95 % confidence interval, each standard deviation that of every run
/// of every replicate (`series`); the calibration's T_conv the argmin of the mean curve,
/// the evaluation's the mean of the replicates' T_conv; each efficiency the mean of the
/// replicates' bounds (each at its own T_conv) over the mean RMSE.
fn combine_replicates(series: &[RunRow], per_replicate: &[SeriesSummary]) -> SeriesSummary {
    let SeriesSummary {
        mut calibration,
        mut evaluation,
    } = per_replicate[0].clone();
    let pooled_std = |phase: Phase, keep: &dyn Fn(&RunRow) -> bool| {
        mean_std(
            series
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
        let means: Vec<f64> = per_replicate
            .iter()
            .map(|t| t.calibration[w].rmse_cm_s)
            .collect();
        let (mean, ci) = mean_ci95(&means);
        let bounds = per_replicate.iter().map(|t| {
            t.calibration[w]
                .efficiency
                .map(|e| e * t.calibration[w].rmse_cm_s)
        });
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
        let means: Vec<f64> = per_replicate
            .iter()
            .map(|t| t.evaluation[j].rmse_cm_s)
            .collect();
        let (mean, ci) = mean_ci95(&means);
        let bounds = per_replicate.iter().map(|t| {
            t.evaluation[j]
                .efficiency
                .map(|e| e * t.evaluation[j].rmse_cm_s)
        });
        row.efficiency = efficiency(bounds.collect(), mean);
        row.rmse_cm_s = mean;
        row.rmse_ci_cm_s = Some(ci);
        row.rmse_std_cm_s = pooled_std(Phase::Evaluation, &|r| r.trajectory == row.trajectory);
        row.t_conv_s = mean_std(per_replicate.iter().map(|t| t.evaluation[j].t_conv_s)).0;
    }
    SeriesSummary {
        calibration,
        evaluation,
    }
}

/// Each evaluation row's improvement over the baseline of its DVL and trajectory.
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
    use crate::vocab::{Correction, ErrorModel};

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
        let result = ProtocolResult::from_runs(runs, &bounds, 0.1);
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
        let result = ProtocolResult::from_runs(rows, &[], 0.1);
        assert_eq!(result.calibration[0].rmse_ci_cm_s, None);
    }
}
