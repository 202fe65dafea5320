//! The installation study's residual figure: one held-out trajectory's DVL minus the
//! reference in the body frame against time, before the correction (grey) and after
//! it (in colour), one panel per axis, and the yaw rate in a panel under them, so that
//! a residual that follows the turns shows as such. In: a [`StudyResults`]'s trace. Out: the
//! figure, or why the study holds no trace.

use crate::installation::study::rows::{StudyResults, TracePoint};
use crate::report::kit::plots::canvas::{Drawn, Outcome, draw_svg};
use crate::report::kit::plots::draw::*;
use crate::report::kit::plots::scale::Scale;
use plotters::prelude::*;

/// The colour of the residual after the correction.
const AFTER: RGBColor = RGBColor(31, 119, 180);
/// The colour of the residual before it.
const BEFORE: RGBColor = RGBColor(170, 170, 170);
/// The colour of the yaw rate.
const YAW_RATE: RGBColor = RGBColor(214, 39, 40);

/// A linear axis over `values`, padded; one of 1 around a single value.
fn padded(values: impl Iterator<Item = f64>) -> Scale {
    let (low, high) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !(low.is_finite() && high.is_finite()) {
        return Scale::linear(-1.0..1.0);
    }
    let pad = if high > low { 0.06 * (high - low) } else { 1.0 };
    Scale::linear((low - pad)..(high + pad))
}

/// One trajectory's residual before and after, per axis, with the yaw rate under it.
pub fn residual(study: &StudyResults) -> PlotResult<Outcome> {
    let Some(first) = study.trace.first() else {
        return Ok(Outcome::NotApplicable(
            "the study holds no residual trace".into(),
        ));
    };
    let points: Vec<&TracePoint> = study
        .trace
        .iter()
        .filter(|p| p.trajectory == first.trajectory)
        .collect();
    let rms = |f: &dyn Fn(&TracePoint) -> f64| {
        (points.iter().map(|p| f(p).powi(2)).sum::<f64>() / points.len() as f64).sqrt()
    };
    let total = |v: [f64; 3]| v.iter().map(|c| c * c).sum::<f64>();
    let before = rms(&|p| total(p.before_cm_s).sqrt());
    let after = rms(&|p| total(p.after_cm_s).sqrt());
    let caption = format!(
        "{}: DVL − reference in the body frame, before and after {} calibrated on {} (RMSE {before:.1} → {after:.1} cm/s)",
        first.trajectory, first.method, first.calibration
    );
    let start = points[0].time_s;
    let end = points[points.len() - 1].time_s.max(start + 1.0);
    let time = Scale::linear(start..end);
    let width = 1100 + LEGEND_WIDTH;
    let svg = draw_svg((width, 900), |root| {
        let (panels, legend_area) = panels_and_legend(root, &caption, width, 1)?;
        let rows = panels[0].split_evenly((4, 1));
        for (axis, name) in ["x", "y", "z"].iter().enumerate() {
            let area = &rows[axis];
            let y = padded(
                points
                    .iter()
                    .flat_map(|p| [p.before_cm_s[axis], p.after_cm_s[axis]]),
            );
            let mut chart = chart_on(area, "", 70).build_cartesian_2d(time.clone(), y)?;
            mesh(&mut chart).y_desc(format!("{name} [cm/s]")).draw()?;
            let series = |f: &dyn Fn(&TracePoint) -> f64| -> Vec<(f64, f64)> {
                points.iter().map(|p| (p.time_s, f(p))).collect()
            };
            chart.draw_series(LineSeries::new(
                series(&|p| p.before_cm_s[axis]),
                BEFORE.stroke_width(1),
            ))?;
            chart.draw_series(LineSeries::new(
                series(&|p| p.after_cm_s[axis]),
                AFTER.stroke_width(1),
            ))?;
        }
        let y = padded(points.iter().map(|p| p.yaw_rate_deg_s));
        let mut chart = chart_on(&rows[3], "", 70).build_cartesian_2d(time.clone(), y)?;
        mesh(&mut chart)
            .x_desc("time [s]")
            .y_desc("yaw rate [deg/s]")
            .draw()?;
        chart.draw_series(LineSeries::new(
            points.iter().map(|p| (p.time_s, p.yaw_rate_deg_s)),
            YAW_RATE.stroke_width(2),
        ))?;
        legend(
            &legend_area,
            "residual",
            &[
                (
                    Swatch::Line(BEFORE, Stroke::Solid),
                    "before (no calibration)".to_string(),
                ),
                (
                    Swatch::Line(AFTER, Stroke::Solid),
                    "after the correction".to_string(),
                ),
                (
                    Swatch::Line(YAW_RATE, Stroke::Solid),
                    "yaw rate".to_string(),
                ),
            ],
        )
    })?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}
