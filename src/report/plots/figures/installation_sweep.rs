//! The figure of a sweep of installation studies: each method's mean held-out RMSE at
//! each point's largest calibration window, its 95 % interval over calibration
//! trajectories as bars, one line per method across the points in grid order. In: a
//! stored sweep of studies. Out: the figure, or why there is none (one point).

use super::installation_windows::{XAxis, rmse_figure};
use crate::installation::rows::SummaryRow;
use crate::report::plots::canvas::Outcome;
use crate::report::plots::draw::PlotResult;
use crate::results::study_sweep::StoredStudySweep;

pub fn installation_sweep(stored: &StoredStudySweep) -> PlotResult<Outcome> {
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
    rmse_figure(
        &rows,
        XAxis {
            label: &stored.index.swept.join(", "),
            ticks: Some(&ticks),
        },
        "Held-out RMSE at each point's largest window: mean over calibration trajectories, bars its 95 % interval".into(),
    )
}
