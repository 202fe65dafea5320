//! The residual figure every room draws a recording's fit with: the DVL minus the
//! reference in the body frame against time, before the correction (grey) and after
//! it (in colour), one panel per axis, and the yaw rate in a panel under them, so that
//! a residual that follows the turns shows as such. Outliers are crossed; the lines
//! break between pieces (a lost bottom lock), never drawn across a gap; the samples
//! left out of the recording are marked ▼ at each axis's foot at their times. A piece
//! of more than twice as many samples as the panel is wide in pixels is thinned
//! ([`thinned`]): cut into as many runs as the panel has pixel columns, each drawn
//! through its lowest and highest value, which keeps the envelope. In: a
//! [`ResidualTrace`] and its caption. Out: the SVG.

use super::canvas::draw_svg;
use super::draw::*;
use super::scale::Scale;
use crate::Vec3;
use plotters::prelude::*;
use std::ops::Range;

/// The colour of the residual after the correction.
const AFTER: RGBColor = RGBColor(31, 119, 180);
/// The colour of the residual before it.
const BEFORE: RGBColor = RGBColor(170, 170, 170);
/// The colour of the yaw rate.
const YAW_RATE: RGBColor = RGBColor(214, 39, 40);
/// The colour of an outlier's cross and of a left-out sample's tick.
const MARK: RGBColor = RGBColor(0, 0, 0);
/// The figure's panels' width, px: a piece of more samples than twice this is thinned.
const WIDTH: u32 = 1400;

/// One sample as drawn: its time, residual before and after (cm/s, body x, y, z; none
/// where the reference does not cover it), the yaw rate there, and whether it is an
/// outlier.
#[derive(Debug, Clone, PartialEq)]
pub struct ResidualSample {
    pub time_s: f64,
    pub before_cm_s: Option<Vec3>,
    pub after_cm_s: Option<Vec3>,
    pub yaw_rate_deg_s: f64,
    pub outlier: bool,
}

/// A recording's residual as drawn: its samples, the pieces they run in (a line each),
/// the times of the samples left out, and what an outlier is (for the legend).
pub struct ResidualTrace {
    pub samples: Vec<ResidualSample>,
    pub pieces: Vec<Range<usize>>,
    pub left_out_s: Vec<f64>,
    pub outlier_is: String,
}

/// The residual figure of `trace` under `caption`.
pub fn draw_residual(caption: &str, trace: &ResidualTrace) -> PlotResult<String> {
    let times = || trace.samples.iter().map(|s| s.time_s);
    let start = times().fold(f64::INFINITY, f64::min);
    let end = times().fold(f64::NEG_INFINITY, f64::max);
    let (start, end) = match start.is_finite() {
        true => (start, end.max(start + 1.0)),
        false => (0.0, 1.0),
    };
    let time = Scale::linear(start..end);
    let width = WIDTH + LEGEND_WIDTH;
    draw_svg((width, 900), |root| {
        let (panels, legend_area) = panels_and_legend(root, caption, width, 1)?;
        let rows = panels[0].split_evenly((4, 1));
        for (axis, name) in ["x", "y", "z"].iter().enumerate() {
            axis_panel(trace, (&rows[axis], &time), axis, name)?;
        }
        yaw_rate_panel(trace, &rows[3], &time)?;
        legend(&legend_area, "residual", &entries(trace))
    })
}

/// The legend's entries: the lines, and the marks the trace has.
fn entries(trace: &ResidualTrace) -> Vec<(Swatch, String)> {
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
    if trace.samples.iter().any(|s| s.outlier) {
        entries.push((Swatch::Mark(MARK, Marker::Cross), trace.outlier_is.clone()));
    }
    if !trace.left_out_s.is_empty() {
        entries.push((
            Swatch::Mark(MARK, Marker::Triangle),
            "sample left out".to_string(),
        ));
    }
    entries
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

/// The points (time, value) `value` gives of `samples` (those it gives one), thinned
/// where there are more than twice `WIDTH`: cut into `WIDTH` runs of samples, each
/// drawn through its lowest and highest value in time order.
pub fn thinned(
    samples: &[ResidualSample],
    value: impl Fn(&ResidualSample) -> Option<f64>,
) -> Vec<(f64, f64)> {
    let given: Vec<(f64, f64)> = (samples.iter())
        .filter_map(|s| Some((s.time_s, value(s)?)))
        .collect();
    let columns = WIDTH as usize;
    if given.len() <= 2 * columns {
        return given;
    }
    let mut points = Vec::with_capacity(2 * columns);
    for run in given.chunks(given.len().div_ceil(columns)) {
        let by_value = |a: &&(f64, f64), b: &&(f64, f64)| a.1.total_cmp(&b.1);
        let low = *run.iter().min_by(by_value).expect("a run is never empty");
        let high = *run.iter().max_by(by_value).expect("a run is never empty");
        points.extend(match low.0 <= high.0 {
            true => [low, high],
            false => [high, low],
        });
    }
    points
}

/// Axis `axis`'s residual before and after, a line per piece, the outliers crossed and
/// the samples left out ticked at the panel's foot.
fn axis_panel(
    trace: &ResidualTrace,
    (area, time): (&Area, &Scale),
    axis: usize,
    name: &str,
) -> PlotResult {
    let samples = &trace.samples;
    let values = (samples.iter()).flat_map(|s| [s.before_cm_s, s.after_cm_s]);
    let y = padded(values.flatten().map(|v| v[axis]));
    let mut chart = chart_on(area, "", 70).build_cartesian_2d(time.clone(), y)?;
    mesh(&mut chart).y_desc(format!("{name} [cm/s]")).draw()?;
    for piece in &trace.pieces {
        let piece = &samples[piece.clone()];
        chart.draw_series(LineSeries::new(
            thinned(piece, |s| s.before_cm_s.map(|v| v[axis])),
            BEFORE.stroke_width(1),
        ))?;
        chart.draw_series(LineSeries::new(
            thinned(piece, |s| s.after_cm_s.map(|v| v[axis])),
            AFTER.stroke_width(1),
        ))?;
    }
    let crosses: Vec<(f64, f64)> = (samples.iter())
        .filter(|s| s.outlier)
        .filter_map(|s| Some((s.time_s, s.after_cm_s?[axis])))
        .collect();
    Marker::Cross.draw(&mut chart, &crosses, MARK)?;
    let foot = chart.y_range().start;
    let ticks: Vec<(f64, f64)> = trace.left_out_s.iter().map(|&t| (t, foot)).collect();
    Marker::Triangle.draw(&mut chart, &ticks, MARK)
}

/// The yaw rate, a line per piece.
fn yaw_rate_panel(trace: &ResidualTrace, area: &Area, time: &Scale) -> PlotResult {
    let y = padded(trace.samples.iter().map(|s| s.yaw_rate_deg_s));
    let mut chart = chart_on(area, "", 70).build_cartesian_2d(time.clone(), y)?;
    mesh(&mut chart)
        .x_desc("time [s]")
        .y_desc("yaw rate [deg/s]")
        .draw()?;
    for piece in &trace.pieces {
        chart.draw_series(LineSeries::new(
            thinned(&trace.samples[piece.clone()], |s| Some(s.yaw_rate_deg_s)),
            YAW_RATE.stroke_width(2),
        ))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A long piece is thinned to each run's extremes, which keep its envelope: the
    /// highest and lowest values drawn are the trace's, in time order; a short one is
    /// drawn whole.
    #[test]
    fn a_long_trace_is_thinned_to_its_envelope() {
        let samples: Vec<ResidualSample> = (0..100_000)
            .map(|i| ResidualSample {
                time_s: 0.1 * f64::from(i),
                before_cm_s: None,
                after_cm_s: Some([
                    (f64::from(i) * 0.37).sin() + if i == 54_321 { 9.0 } else { 0.0 },
                    0.0,
                    0.0,
                ]),
                yaw_rate_deg_s: 0.0,
                outlier: false,
            })
            .collect();
        let after = |s: &ResidualSample| s.after_cm_s.map(|v| v[0]);
        let points = thinned(&samples, after);
        assert!(points.len() <= 2 * WIDTH as usize, "{}", points.len());
        let high = points.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
        let low = points.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        let all = samples.iter().filter_map(after);
        assert_eq!(high, all.clone().fold(f64::NEG_INFINITY, f64::max));
        assert_eq!(low, all.fold(f64::INFINITY, f64::min));
        assert!(points.windows(2).all(|w| w[0].0 <= w[1].0));
        let few = &samples[..100];
        assert_eq!(thinned(few, after).len(), 100);
        // A sample with no value is left out of the line.
        assert!(thinned(few, |s| s.before_cm_s.map(|v| v[0])).is_empty());
    }
}
