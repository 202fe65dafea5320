//! The study's table of how long each method needs to calibrate: per method (row) and
//! calibration trajectory (column), its calibration time with its T_conv in brackets,
//! and the median over calibration trajectories that have one. In: the study's calibration-time
//! rows. Out: a [`Section`], or none when the study has one window only.

use crate::installation::study::rows::{StudyResults, StudyTimeRow};
use crate::report::kit::table::{Entry, Section, Table};

/// The median of `values`; `None` when there are none.
fn median(mut values: Vec<f64>) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    Some(if n % 2 == 1 {
        values[n / 2]
    } else {
        (values[n / 2 - 1] + values[n / 2]) / 2.0
    })
}

/// The section, methods in the order given.
pub(super) fn timing_section(
    study: &StudyResults,
    methods: &[&str],
    windows: &[f64],
) -> Option<Section> {
    let rows = &study.calibration_time;
    let first = rows.first()?;
    if windows.len() < 2 {
        return None;
    }
    let calibrations = crate::first_seen(rows.iter().map(|r| r.calibration.as_str()));
    let find = |method: &str, calibration: &str| -> Option<&StudyTimeRow> {
        rows.iter()
            .find(|r| r.method == method && r.calibration == calibration)
    };
    let table_rows = methods
        .iter()
        .filter(|m| rows.iter().any(|r| r.method == **m))
        .map(|method| {
            let mut cells = vec![Entry::Text(method.to_string())];
            let mut times = Vec::new();
            for calibration in &calibrations {
                cells.push(match find(method, calibration) {
                    Some(r) => {
                        if let Some(time) = r.calibration_time_s {
                            times.push(time);
                        }
                        let time = r
                            .calibration_time_s
                            .map_or("never".to_string(), |t| format!("{t:.0}"));
                        Entry::Text(format!("{time} ({:.0})", r.t_conv_s))
                    }
                    None => Entry::Missing,
                });
            }
            cells.push(median(times).map_or(Entry::Text("never".into()), |m| {
                Entry::Text(format!("{m:.0}"))
            }));
            cells
        })
        .collect();
    let header = std::iter::once("method".to_string())
        .chain(calibrations.iter().map(|c| c.to_string()))
        .chain(std::iter::once("median".to_string()))
        .collect();
    Some(Section {
        title: "How long to calibrate".into(),
        caption: format!(
            "Each method's calibration time on each calibration trajectory, s: the shortest window after which its held-out RMSE (the mean over the trajectories it corrects) stays within {} % of what calibration can change there (from no calibration's RMSE down to the specified noise's, {:.2} cm/s in total) of its value at the longest window ({:.0} s), above or below it; \"never\" for a method no better than no calibration by that much. In brackets its T_conv, the window of lowest held-out RMSE. The windows are those of the study, so a time is one of them; the median is over the calibrations that have one.",
            first.tolerance_pct,
            first.noise_floor_cm_s,
            windows.last().copied().unwrap_or(0.0)
        ),
        table: Table::new(header, table_rows, Vec::new()),
        paragraph: None,
    })
}
