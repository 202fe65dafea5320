//! The operator's score of every method: the dead-reckoning drift each leaves on the
//! trajectories it corrects, beside its velocity RMSE. In: the held-out rows at the
//! largest window. Out: a [`Section`], or none where no scored trajectory records
//! positions.

use super::heldout::window_text;
use crate::installation::study::rows::{StudyResults, TransferRow};
use crate::report::kit::table::{Entry, Section, Table};

/// The drift section of `methods` at `window_s`: per method, the mean over its held-out
/// pairs of the RMS and the end-point drift, % of the distance travelled, and of the
/// velocity RMSE, cm/s.
pub(super) fn drift_section(
    study: &StudyResults,
    methods: &[&str],
    window_s: f64,
) -> Option<Section> {
    let mean = |rows: &[&TransferRow], value: fn(&TransferRow) -> f64| {
        rows.iter().map(|r| value(r)).sum::<f64>() / rows.len() as f64
    };
    let table_rows: Vec<Vec<Entry>> = methods
        .iter()
        .filter_map(|&method| {
            let rows: Vec<&TransferRow> = (study.heldout.iter())
                .filter(|r| r.method == method && r.window_s == window_s)
                .filter(|r| r.drift_rms_pct.is_finite())
                .collect();
            (!rows.is_empty()).then(|| {
                vec![
                    Entry::Text(method.to_string()),
                    Entry::Text(format!("{:.3}", mean(&rows, |r| r.drift_rms_pct))),
                    Entry::Text(format!("{:.3}", mean(&rows, |r| r.drift_end_pct))),
                    Entry::Text(format!("{:.2}", mean(&rows, |r| r.total_cm_s))),
                    Entry::Text(rows.len().to_string()),
                ]
            })
        })
        .collect();
    if table_rows.is_empty() {
        return None;
    }
    Some(Section {
        title: format!("Dead-reckoning drift, window {}", window_text(window_s)),
        caption: format!(
            "The operator's measure of a calibration: each method's terms (from the first {} of a calibration trajectory) correct the DVL of every other trajectory, dead-reckoned with the reference's attitude from the reference's position at the start of each piece; the horizontal error against the reference's positions, as % of the distance travelled, RMS over the trajectory's samples and at its end; the mean over the held-out pairs, beside the mean velocity RMSE of the same pairs. `drift_rms_pct` and `drift_end_pct` in heldout.parquet.",
            window_text(window_s)
        ),
        table: Table::new(
            vec![
                "method".into(),
                "RMS drift (% of distance)".into(),
                "end-point drift (% of distance)".into(),
                "velocity RMSE (cm/s)".into(),
                "held-out pairs".into(),
            ],
            table_rows,
            Vec::new(),
        ),
        paragraph: None,
    })
}
