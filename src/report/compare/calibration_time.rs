//! The calibration times of two folders side by side: each method's T_conv, calibration
//! time and time to the bound in A and in B ([`calibration_time`]
//! (crate::evaluate::calibration_time) defines them). They are read off mean curves, so
//! no standard error goes with them and no cell is marked. In: the two folders'
//! calibration-time tables. Out: the section as Markdown.

use super::pairs::pair;
use crate::evaluate::CalibrationTimeRow;
use crate::results::read::StoredRun;
use comfy_table::{Table, presets::ASCII_MARKDOWN};
use std::fmt::Write;

/// A length in seconds, "never" where none, "—" where the folder lacks the row.
fn seconds(row: Option<&CalibrationTimeRow>, of: fn(&CalibrationTimeRow) -> Option<f64>) -> String {
    match row {
        Some(row) => of(row).map_or("never".into(), |s| format!("{s:.0}")),
        None => "—".into(),
    }
}

/// The section, or nothing when neither folder has calibration times.
pub(super) fn calibration_time_section(a: &StoredRun, b: &StoredRun, out: &mut String) {
    if a.calibration_time.is_empty() && b.calibration_time.is_empty() {
        return;
    }
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    table.set_header([
        "DVL",
        "estimator",
        "EM",
        "T_conv A",
        "T_conv B",
        "time A",
        "time B",
        "to the bound A",
        "to the bound B",
    ]);
    let key = |r: &CalibrationTimeRow| (r.dvl.clone(), r.estimator, r.error_model);
    for (row_a, row_b) in pair(&a.calibration_time, &b.calibration_time, key) {
        let row = row_a.or(row_b).expect("a pair holds a row");
        table.add_row(vec![
            row.dvl.clone(),
            row.estimator.label().to_string(),
            row.error_model.map_or("-".into(), |m| m.to_string()),
            seconds(row_a, |r| Some(r.t_conv_s)),
            seconds(row_b, |r| Some(r.t_conv_s)),
            seconds(row_a, |r| r.calibration_time_s),
            seconds(row_b, |r| r.calibration_time_s),
            seconds(row_a, |r| r.time_to_bound_s),
            seconds(row_b, |r| r.time_to_bound_s),
        ]);
    }
    let tolerance = |run: &StoredRun| {
        run.calibration_time
            .first()
            .map_or("—".into(), |r| format!("{} %", r.tolerance_pct))
    };
    let _ = writeln!(
        out,
        "## Calibration time\n\nSeconds of calibration after which each method's held-out RMSE stays within the tolerance (A: {}, B: {}) of its own value at the longest window (time), or of the bound's (to the bound), beside its T_conv.\n\n{table}\n",
        tolerance(a),
        tolerance(b)
    );
}
