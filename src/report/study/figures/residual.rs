//! The installation study's residual figure: one held-out trajectory's DVL minus the
//! reference in the body frame against time, before the correction (grey) and after
//! it (in colour), one panel per axis, and the yaw rate in a panel under them, so that
//! a residual that follows the turns shows as such. A sample whose residual after has a
//! component beyond Tukey's [`TUKEY_C`] scales of the rest (the fit's outliers' test) is
//! marked with a cross and counted in the caption; the lines break where the trace's
//! samples are further apart than the default gap limit (a lost bottom lock), never
//! drawn across the gap. In: a [`StudyResults`]'s trace. Out: the figure, or why the
//! study holds no trace.

use crate::data::paired::{default_gap_limit_s, pieces};
use crate::installation::estimate::robust::{TUKEY_C, outliers_among};
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
/// The colour of an outlier's cross.
const OUTLIER: RGBColor = RGBColor(0, 0, 0);

/// Whether each of `points`' residuals after the correction is an outlier.
fn outliers(points: &[&TracePoint]) -> Vec<bool> {
    outliers_among(&points.iter().map(|p| p.after_cm_s).collect::<Vec<_>>())
}

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
    let outlying = outliers(&points);
    let count = outlying.iter().filter(|&&o| o).count();
    let caption = caption(&points, count);
    let times: Vec<f64> = points.iter().map(|p| p.time_s).collect();
    let trace = Trace {
        pieces: pieces(&times, default_gap_limit_s(&times)),
        points,
        outlying,
    };
    let start = times[0];
    let time = Scale::linear(start..times[times.len() - 1].max(start + 1.0));
    let width = 1100 + LEGEND_WIDTH;
    let svg = draw_svg((width, 900), |root| {
        let (panels, legend_area) = panels_and_legend(root, &caption, width, 1)?;
        let rows = panels[0].split_evenly((4, 1));
        for (axis, name) in ["x", "y", "z"].iter().enumerate() {
            trace.axis_panel(&rows[axis], &time, axis, name)?;
        }
        trace.yaw_rate_panel(&rows[3], &time)?;
        let mut entries = vec![
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
        ];
        if count > 0 {
            entries.push((
                Swatch::Mark(OUTLIER, Marker::Cross),
                format!("outlier after (beyond {TUKEY_C} scales)"),
            ));
        }
        legend(&legend_area, "residual", &entries)
    })?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}

/// The figure's caption: the trajectory, the method and its calibration, the RMSE
/// before and after over `points`, and the `outliers` marked.
fn caption(points: &[&TracePoint], outliers: usize) -> String {
    let rms = |f: &dyn Fn(&TracePoint) -> f64| {
        (points.iter().map(|p| f(p).powi(2)).sum::<f64>() / points.len() as f64).sqrt()
    };
    let total = |v: [f64; 3]| v.iter().map(|c| c * c).sum::<f64>();
    let before = rms(&|p| total(p.before_cm_s).sqrt());
    let after = rms(&|p| total(p.after_cm_s).sqrt());
    let first = points[0];
    format!(
        "{}: DVL − reference in the body frame, before and after {} calibrated on {} (RMSE {before:.1} → {after:.1} cm/s{})",
        first.trajectory,
        first.method,
        first.calibration,
        match outliers {
            0 => String::new(),
            1 => "; 1 outlier, ×".into(),
            n => format!("; {n} outliers, ×"),
        }
    )
}

/// The trajectory's samples as drawn: cut into pieces at its gaps, each marked where
/// its residual after is an outlier.
struct Trace<'a> {
    points: Vec<&'a TracePoint>,
    pieces: Vec<std::ops::Range<usize>>,
    outlying: Vec<bool>,
}

impl Trace<'_> {
    /// Axis `axis`'s residual before and after, a line per piece, the outliers crossed.
    fn axis_panel(&self, area: &Area, time: &Scale, axis: usize, name: &str) -> PlotResult {
        let points = &self.points;
        let y = padded((points.iter()).flat_map(|p| [p.before_cm_s[axis], p.after_cm_s[axis]]));
        let mut chart = chart_on(area, "", 70).build_cartesian_2d(time.clone(), y)?;
        mesh(&mut chart).y_desc(format!("{name} [cm/s]")).draw()?;
        for piece in &self.pieces {
            let series = |f: &dyn Fn(&TracePoint) -> f64| -> Vec<(f64, f64)> {
                points[piece.clone()]
                    .iter()
                    .map(|p| (p.time_s, f(p)))
                    .collect()
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
        let crosses: Vec<(f64, f64)> = (points.iter().zip(&self.outlying))
            .filter(|&(_, &o)| o)
            .map(|(p, _)| (p.time_s, p.after_cm_s[axis]))
            .collect();
        Marker::Cross.draw(&mut chart, &crosses, OUTLIER)
    }

    /// The yaw rate, a line per piece.
    fn yaw_rate_panel(&self, area: &Area, time: &Scale) -> PlotResult {
        let y = padded(self.points.iter().map(|p| p.yaw_rate_deg_s));
        let mut chart = chart_on(area, "", 70).build_cartesian_2d(time.clone(), y)?;
        mesh(&mut chart)
            .x_desc("time [s]")
            .y_desc("yaw rate [deg/s]")
            .draw()?;
        for piece in &self.pieces {
            chart.draw_series(LineSeries::new(
                (self.points[piece.clone()].iter()).map(|p| (p.time_s, p.yaw_rate_deg_s)),
                YAW_RATE.stroke_width(2),
            ))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spikes_after_are_marked_and_counted() {
        // 1 Hz with 30 s lost from 100 s, a 1 cm/s wobble after, and two spikes of 60
        // cm/s (one on y, one on z): they alone are marked.
        let trace: Vec<TracePoint> = (0..300u32)
            .filter(|i| !(100..130).contains(i))
            .map(|i| {
                let wobble = (f64::from(i) * 0.7).sin();
                let mut after_cm_s = [wobble, -wobble, 0.5 * wobble];
                match i {
                    50 => after_cm_s[1] += 60.0,
                    200 => after_cm_s[2] -= 60.0,
                    _ => {}
                }
                TracePoint {
                    trajectory: "T1".into(),
                    method: "installation".into(),
                    calibration: "T2".into(),
                    time_s: f64::from(i),
                    before_cm_s: [5.0, 2.0, 1.0],
                    after_cm_s,
                    yaw_rate_deg_s: 0.0,
                }
            })
            .collect();
        let points: Vec<&TracePoint> = trace.iter().collect();
        let marked: Vec<f64> = (points.iter().zip(outliers(&points)))
            .filter(|(_, o)| *o)
            .map(|(p, _)| p.time_s)
            .collect();
        assert_eq!(marked, [50.0, 200.0]);
        let study = StudyResults {
            trace,
            ..StudyResults::default()
        };
        crate::report::kit::plots::render::register_font();
        let Outcome::Drawn(drawn) = residual(&study).unwrap() else {
            panic!("drawn");
        };
        assert!(
            drawn.caption.ends_with("; 2 outliers, ×)"),
            "{}",
            drawn.caption
        );
    }
}
