//! The figure of a sweep of installation studies: each method's mean held-out RMSE at
//! each point's largest calibration window, its 95 % interval over calibration
//! trajectories as bars, one line per method across the points in grid order. In: a
//! stored sweep of studies. Out: the figure, or why there is none (one point).

use super::windows::{TICK_CHAR_PX, TICKS_WIDTH_PX, XAxis, rmse_figure};
use crate::installation::study::rows::SummaryRow;
use crate::report::kit::plots::canvas::Outcome;
use crate::report::kit::plots::draw::PlotResult;
use crate::results::study_sweep::StoredStudySweep;

pub fn sweep(stored: &StoredStudySweep) -> PlotResult<Outcome> {
    let points = &stored.index.points;
    if points.len() < 2 {
        return Ok(Outcome::NotApplicable(format!(
            "the sweep has {} point",
            points.len()
        )));
    }
    let mut rows: Vec<(f64, &SummaryRow)> = Vec::new();
    for (p, point) in points.iter().enumerate() {
        let mine: Vec<&SummaryRow> = stored
            .rows
            .iter()
            .filter(|r| &r.point == point)
            .map(|r| &r.summary)
            .collect();
        let largest = mine.iter().map(|r| r.window_s).fold(f64::NAN, f64::max);
        rows.extend(
            mine.into_iter()
                .filter(|r| r.window_s == largest)
                .map(|r| (p as f64, r)),
        );
    }
    // A point is named `key=value,key=value`; its tick shows the values, the axis the keys.
    let ticks: Vec<String> = points
        .iter()
        .map(|point| {
            point
                .split(',')
                .map(|part| part.split_once('=').map_or(part, |(_, value)| value))
                .collect::<Vec<_>>()
                .join(", ")
        })
        .collect();
    // Names too long to stand side by side are numbered, and the axis says what each
    // number is while that fits on it.
    let longest = ticks.iter().map(|t| t.chars().count()).max().unwrap_or(0);
    let keys = stored.index.swept.join(", ");
    let (ticks, label) = if longest * TICK_CHAR_PX <= TICKS_WIDTH_PX / ticks.len() {
        (ticks, keys)
    } else {
        let listed: Vec<String> = ticks
            .iter()
            .enumerate()
            .map(|(i, t)| format!("{} = {t}", i + 1))
            .collect();
        let label = match format!("{keys}: {}", listed.join("; ")) {
            label if label.chars().count() * TICK_CHAR_PX <= TICKS_WIDTH_PX + 200 => label,
            _ => format!("{keys}: point n is the n-th of sweep.json's points"),
        };
        ((1..=ticks.len()).map(|n| n.to_string()).collect(), label)
    };
    rmse_figure(
        &rows,
        XAxis {
            label: &label,
            ticks: Some(&ticks),
            lines: stored.index.swept.len() == 1,
        },
        "Held-out RMSE at each point's largest window: mean over calibration trajectories, bars its 95 % interval".into(),
    )
}
