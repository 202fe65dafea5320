//! The report's section on how long to calibrate: per DVL, every method's calibration
//! time (the shortest calibration window after which its held-out RMSE stays within
//! the spec's tolerance, of its excess over the bound, of its value at the longest
//! window) beside the paper's T_conv, the
//! held-out RMSE there and at the longest window, the bound's among them; then the
//! paper's claim of a calibration 80 % shorter than the baseline's, checked for every
//! error model against the baseline and against the Kalman filter of the same model.
//! In: a [`StoredRun`]'s calibration-time and held-out tables. Out: [`Section`]s, set
//! as Markdown and LaTeX by the kit, as every room's sections are.

use crate::evaluate::rows::{CalibrationTimeRow, HeldOutRow};
use crate::report::kit::table::{Entry, Section, Table};
use crate::results::read::StoredRun;
use crate::vocab::{ErrorModel, EstimatorKind};

/// The section's tables: one per DVL, then the claim's; none when the run has no
/// held-out curves.
pub(crate) fn sections(run: &StoredRun) -> Vec<Section> {
    let rows = &run.calibration_time;
    let Some(first) = rows.first() else {
        return Vec::new();
    };
    let tolerance = first.tolerance_pct;
    let mut sections: Vec<Section> = run
        .dvls()
        .iter()
        .filter(|dvl| rows.iter().any(|r| &r.dvl == *dvl))
        .map(|dvl| dvl_section(dvl, rows, tolerance))
        .collect();
    if let Some(claim) = claim_section(run) {
        sections.push(claim);
    }
    sections
}

/// A length in seconds, or "—" where there is none.
/// A row's calibration time: its seconds, or "never" where it has none.
fn time_or_never(row: Option<&CalibrationTimeRow>) -> Entry {
    match row {
        Some(r) => match r.calibration_time_s {
            Some(s) => Entry::Text(format!("{s:.0}")),
            None => Entry::Text("never".into()),
        },
        None => Entry::Missing,
    }
}

fn seconds(value: Option<f64>) -> Entry {
    match value {
        Some(s) => Entry::Text(format!("{s:.0}")),
        None => Entry::Missing,
    }
}

fn rmse(value: f64) -> Entry {
    if value.is_finite() {
        Entry::Text(format!("{value:.2}"))
    } else {
        Entry::Missing
    }
}

fn dvl_section(dvl: &str, rows: &[CalibrationTimeRow], tolerance: f64) -> Section {
    let of_dvl: Vec<&CalibrationTimeRow> = rows.iter().filter(|r| r.dvl == dvl).collect();
    let long_s = of_dvl.first().map_or(0.0, |r| r.long_window_s);
    let table = Table::new(
        [
            "method",
            "T_conv (s)",
            "calibration time (s)",
            "RMSE there",
            &format!("RMSE at {long_s:.0} s"),
            "time to the bound (s)",
        ]
        .map(String::from)
        .to_vec(),
        of_dvl
            .iter()
            .map(|r| {
                vec![
                    Entry::Text(r.estimator.label_with(r.error_model)),
                    seconds(Some(r.t_conv_s)),
                    time_or_never(Some(r)),
                    rmse(r.rmse_at_time_cm_s),
                    rmse(r.long_window_rmse_cm_s),
                    match r.time_to_bound_s {
                        Some(s) => Entry::Text(format!("{s:.0}")),
                        None => Entry::Text("never".into()),
                    },
                ]
            })
            .collect(),
        vec![
            "DCNet's terms are estimated at the calibration windows only; the calibration time of every method is read there, so that all are compared at the same lengths (the curves of the others, scored after every sample, are in held_out.parquet).".into(),
        ],
    );
    Section {
        title: format!("How long to calibrate {dvl}"),
        caption: format!(
            "Held-out RMSE (cm/s) on the test trajectories pooled, mean over runs. A method's calibration time is the shortest calibration window after which its RMSE stays within {tolerance} % of what calibration changes over the windows (from its RMSE at the shortest down to the bound's at the longest window, {long_s:.0} s) of its own value there, above or below it, for a method that ends at most {tolerance} % of the bound's own drop over the windows above the bound (\"never\" otherwise: it settles on a value worse than the data allow); both are read at the calibration windows, where every method, DCNet too, has its curve. T_conv is the paper's: the window of lowest RMSE on the rest of the calibration trajectory. The time to the bound is the shortest calibration after which the RMSE stays below the bound's at the longest window plus {tolerance} %, a target common to every method (\"never\": not by {long_s:.0} s). The bound's row is an efficient estimator's."
        ),
        table,
        paragraph: None,
    }
}

/// The held-out RMSE of a method after `length_s` of calibration, when its curve holds
/// that length.
fn held_out_at(
    curves: &[HeldOutRow],
    dvl: &str,
    estimator: EstimatorKind,
    error_model: Option<ErrorModel>,
    length_s: f64,
) -> Option<f64> {
    curves
        .iter()
        .find(|r| {
            r.dvl == dvl
                && r.estimator == estimator
                && r.error_model == error_model
                && r.length_s == length_s
        })
        .map(|r| r.rmse_cm_s)
}

/// `1 − shorter / longer` in %, as the paper counts an improvement in calibration time.
fn shorter_by(ours: Option<f64>, theirs: Option<f64>) -> Entry {
    match (ours, theirs) {
        (Some(ours), Some(theirs)) if theirs > 0.0 => {
            Entry::Text(format!("{:.0} %", 100.0 * (1.0 - ours / theirs)))
        }
        _ => Entry::Missing,
    }
}

/// The paper's claim, "80 % shorter calibration than the baseline", for DCNet of every
/// error model: by T_conv and by calibration time against the baseline, and by
/// calibration time against the Kalman filter of the same model, with the filter's
/// held-out RMSE after DCNet's calibration time beside DCNet's own.
fn claim_section(run: &StoredRun) -> Option<Section> {
    let rows = &run.calibration_time;
    let find = |dvl: &str, estimator, error_model| {
        rows.iter()
            .find(|r| r.dvl == dvl && r.estimator == estimator && r.error_model == error_model)
    };
    let mut table_rows = Vec::new();
    for r in rows.iter().filter(|r| r.estimator == EstimatorKind::Dcnet) {
        let baseline = find(&r.dvl, EstimatorKind::Baseline, None);
        let kalman = find(&r.dvl, EstimatorKind::Kalman, r.error_model);
        let kalman_there = r.calibration_time_s.and_then(|length| {
            held_out_at(
                &run.held_out,
                &r.dvl,
                EstimatorKind::Kalman,
                r.error_model,
                length,
            )
        });
        table_rows.push(vec![
            Entry::Text(r.dvl.clone()),
            Entry::Text(r.error_model.map_or(String::new(), |m| m.to_string())),
            seconds(Some(r.t_conv_s)),
            seconds(baseline.map(|b| b.t_conv_s)),
            shorter_by(Some(r.t_conv_s), baseline.map(|b| b.t_conv_s)),
            time_or_never(Some(r)),
            time_or_never(baseline),
            shorter_by(
                r.calibration_time_s,
                baseline.and_then(|b| b.calibration_time_s),
            ),
            time_or_never(kalman),
            shorter_by(
                r.calibration_time_s,
                kalman.and_then(|k| k.calibration_time_s),
            ),
            rmse(r.rmse_at_time_cm_s),
            kalman_there.map_or(Entry::Missing, rmse),
        ]);
    }
    if table_rows.is_empty() {
        return None;
    }
    let notes = claim_notes(run);
    let header = [
        "DVL",
        "model",
        "DCNet T_conv",
        "baseline T_conv",
        "shorter",
        "DCNet time",
        "baseline time",
        "shorter",
        "Kalman time",
        "shorter",
        "DCNet RMSE",
        "Kalman RMSE",
    ];
    Some(Section {
        title: "The paper's claim: an 80 % shorter calibration".into(),
        caption: "DCNet's calibration against the baseline's (the paper's comparison) and against the Kalman filter of the same error model, by T_conv and by calibration time (s); \"shorter\" is 1 − DCNet's / the other's. The last two columns give the held-out RMSE (cm/s) of DCNet and of the Kalman filter after DCNet's calibration time.".into(),
        table: Table::new(
            header.map(String::from).to_vec(),
            table_rows,
            notes,
        ),
        paragraph: None,
    })
}

/// Under the claim's table, per DVL: the DVL's own model and the bound, beside the
/// error models' filters.
fn claim_notes(run: &StoredRun) -> Vec<String> {
    let rows = &run.calibration_time;
    let find = |dvl: &str, estimator, error_model| {
        rows.iter()
            .find(|r| r.dvl == dvl && r.estimator == estimator && r.error_model == error_model)
    };
    run
        .dvls()
        .iter()
        .filter_map(|dvl| {
            let time = |estimator, model, of: fn(&CalibrationTimeRow) -> Option<f64>| {
                find(dvl, estimator, model)
                    .map(|r| of(r).map_or("never".to_string(), |s| format!("{s:.0} s")))
            };
            let own = |r: &CalibrationTimeRow| r.calibration_time_s;
            let beam = time(EstimatorKind::KalmanBeam, None, own)?;
            let within = |estimator, model| match find(dvl, estimator, model) {
                Some(r) => match r.time_to_bound_s {
                    Some(s) => format!("comes within it in {s:.0} s"),
                    None => "never comes within it".into(),
                },
                None => "is not in the run".into(),
            };
            Some(format!(
                "{dvl}: the beam-model Kalman filter (the DVL's own model) settles in {beam}, the bound in {}; of the bound's RMSE at the longest window plus the tolerance, the filter {}, DCNet EM5 {}.",
                time(EstimatorKind::Bound, None, own).unwrap_or_else(|| "—".into()),
                within(EstimatorKind::KalmanBeam, None),
                within(EstimatorKind::Dcnet, Some(ErrorModel::Em5)),
            ))
        })
        .collect()
}
