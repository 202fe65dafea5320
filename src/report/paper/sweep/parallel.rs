//! The parallel-coordinates figure of a sweep over two or more keys: one vertical axis
//! per swept key and one for the metric, one line per point through its values, the
//! line coloured by the metric on a labelled colour bar (a point far above the others
//! ends at the top of the metric axis, its value written there). A point's metric on a
//! DVL is the mean over its DCNet rows (the error models) of `sweep.parquet` on that
//! DVL, one panel per DVL. Numeric keys get a numeric axis ([`Scale`]); any other key
//! (a TOML array or string) gets its values as evenly spaced categories.
//! In: a stored sweep and a metric. Out: the figure.

use super::metric::Metric;
use crate::first_seen;
use crate::report::kit::numbers::three_digits;
use crate::report::kit::plots::canvas::{Drawn, Outcome, draw_svg};
use crate::report::kit::plots::draw::*;
use crate::report::kit::plots::scale::Scale;
use crate::results::sweep::{StoredSweep, Swept};
use crate::vocab::EstimatorKind;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

/// One vertical axis: a numeric one, or categories at evenly spaced heights.
#[derive(Debug, Clone, PartialEq)]
enum Axis {
    Numbers(Scale),
    Categories(Vec<Swept>),
}

impl Axis {
    /// The axis of swept `values`: numeric when they all are.
    fn of(values: &[Swept]) -> Axis {
        let numbers: Option<Vec<f64>> = values.iter().map(Swept::number).collect();
        match numbers {
            Some(numbers) => {
                let low = numbers.iter().copied().fold(f64::INFINITY, f64::min);
                let high = numbers.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                Axis::Numbers(Scale::fit(low, high))
            }
            None => Axis::Categories(first_seen(values.iter().cloned())),
        }
    }

    /// Where `value` lies along the axis, 0 at the bottom and 1 at the top; category
    /// `i` of `n` at (i + 0.5) / n.
    fn position(&self, value: &Swept) -> f64 {
        match self {
            Axis::Numbers(scale) => scale.fraction(value.number().unwrap_or(f64::NAN)),
            Axis::Categories(values) => {
                let index = values.iter().position(|v| v == value).unwrap_or(0);
                (index as f64 + 0.5) / values.len() as f64
            }
        }
    }

    /// The labelled ticks: each label and its position.
    fn labels(&self) -> Vec<(String, f64)> {
        match self {
            Axis::Numbers(scale) => scale
                .ticks()
                .map(|t| (scale.label(t), scale.fraction(t)))
                .collect(),
            Axis::Categories(values) => values
                .iter()
                .map(|v| (v.to_string(), self.position(v)))
                .collect(),
        }
    }
}

/// The colour scale, viridis from dark (0, the lowest metric) to light green (1),
/// stopping before viridis's pale yellow so every line shows on white.
const COLORS: [RGBColor; 5] = [
    RGBColor(68, 1, 84),
    RGBColor(59, 82, 139),
    RGBColor(33, 145, 140),
    RGBColor(94, 201, 98),
    RGBColor(189, 223, 38),
];

/// The colour at `fraction` of the colour scale (clamped to 0..=1), interpolated
/// linearly between the stops.
fn color_at(fraction: f64) -> RGBColor {
    let position = fraction.clamp(0.0, 1.0) * (COLORS.len() - 1) as f64;
    let index = (position.floor() as usize).min(COLORS.len() - 2);
    let (a, b, t) = (COLORS[index], COLORS[index + 1], position - index as f64);
    let mix = |x: u8, y: u8| (f64::from(x) + (f64::from(y) - f64::from(x)) * t).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// One point's line on a panel: its swept values and its metric.
struct Line {
    values: Vec<Swept>,
    metric: f64,
}

/// The lines of `dvl`: each point's metric averaged over its DCNet rows on that DVL,
/// in the order of the points.
fn lines(sweep: &StoredSweep, metric: Metric, dvl: &str) -> Vec<Line> {
    sweep
        .index
        .points
        .iter()
        .filter_map(|point| {
            let rows: Vec<_> = sweep
                .rows
                .iter()
                .filter(|r| &r.point == point && r.dvl == dvl)
                .filter(|r| r.estimator == EstimatorKind::Dcnet)
                .filter_map(|r| metric.of(r).filter(|v| v.is_finite()).map(|v| (r, v)))
                .collect();
            let (first, _) = rows.first()?;
            Some(Line {
                values: first.values.clone(),
                metric: rows.iter().map(|(_, v)| v).sum::<f64>() / rows.len() as f64,
            })
        })
        .collect()
}

const PANEL_HEIGHT: u32 = 420;
const AXIS_GAP: u32 = 240;
const LEFT: i32 = 130;
const COLOR_BAR_WIDTH: u32 = 200;
/// The narrowest figure: its title fits in it whatever the metric.
const MIN_WIDTH: u32 = 1000;

/// The figure, or why the sweep has none.
pub fn parallel(sweep: &StoredSweep, metric: Metric) -> PlotResult<Outcome> {
    let keys = &sweep.index.swept;
    let dvls = first_seen(sweep.rows.iter().map(|r| r.dvl.clone()));
    let panels: Vec<(String, Vec<Line>)> = dvls
        .into_iter()
        .map(|dvl| {
            let lines = lines(sweep, metric, &dvl);
            (dvl, lines)
        })
        .filter(|(_, lines)| !lines.is_empty())
        .collect();
    if panels.is_empty() {
        return Ok(Outcome::NotApplicable(format!(
            "sweep.parquet has no DCNet row with a {}",
            metric.axis()
        )));
    }
    let axes: Vec<Axis> = (0..keys.len())
        .map(|k| {
            let values: Vec<Swept> = sweep.rows.iter().map(|r| r.values[k].clone()).collect();
            Axis::of(&values)
        })
        .collect();
    let caption = format!(
        "{}, a line per point: mean over DCNet error models",
        metric.axis()
    );
    // Wide enough for the axes, and for the longest caption on two axes.
    let width = (LEFT as u32 + AXIS_GAP * keys.len() as u32 + 60 + COLOR_BAR_WIDTH).max(MIN_WIDTH);
    let height = 60 + PANEL_HEIGHT * panels.len() as u32;
    let svg = draw_svg((width, height), |root| {
        let root = root.titled(&caption, font(TITLE_SIZE))?;
        let names: Vec<&str> = keys
            .iter()
            .map(String::as_str)
            .chain([metric.axis()])
            .collect();
        for (area, (dvl, lines)) in root.split_evenly((panels.len(), 1)).iter().zip(&panels) {
            let metrics: Vec<f64> = lines.iter().map(|l| l.metric).collect();
            let metric_scale = Scale::fit_values(&metrics, 1);
            panel(area, dvl, &axes, &metric_scale, &names, lines)?;
        }
        Ok(())
    })?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}

/// One DVL's panel: an axis per swept key and the metric's (`names` names them all),
/// the lines (the lowest metric drawn last, on top; one far above the others ends at
/// the axis top with its value written), the tick labels and the colour bar.
fn panel(
    area: &Area,
    title: &str,
    key_axes: &[Axis],
    metric_scale: &Scale,
    names: &[&str],
    lines: &[Line],
) -> PlotResult {
    let (top, bottom) = (40, PANEL_HEIGHT as i32 - 60);
    let x_of = |axis: usize| LEFT + AXIS_GAP as i32 * axis as i32;
    let y_of = |position: f64| bottom - (position * f64::from(bottom - top)).round() as i32;
    area.draw(&Text::new(
        title.to_string(),
        (LEFT, 12),
        anchored(PANEL_TITLE_SIZE, HPos::Left, VPos::Top),
    ))?;
    let mut order: Vec<&Line> = lines.iter().collect();
    order.sort_by(|a, b| b.metric.total_cmp(&a.metric));
    for line in order {
        let mut points: Vec<(i32, i32)> = line
            .values
            .iter()
            .zip(key_axes)
            .enumerate()
            .map(|(i, (value, axis))| (x_of(i), y_of(axis.position(value))))
            .collect();
        let metric_position = metric_scale.fraction(metric_scale.shown(line.metric));
        let end = (x_of(key_axes.len()), y_of(metric_position));
        points.push(end);
        let color = color_at(metric_position);
        area.draw(&PathElement::new(points, color.stroke_width(2)))?;
        if metric_scale.is_cut(line.metric) {
            area.draw(
                &(EmptyElement::at(end)
                    + TriangleMarker::new((0, 0), 7, color.filled())
                    + Text::new(
                        three_digits(line.metric),
                        (10, 0),
                        anchored(LABEL_SIZE - 1, HPos::Left, VPos::Center),
                    )),
            )?;
        }
    }
    let metric_axis = Axis::Numbers(metric_scale.clone());
    let axes = key_axes.iter().chain([&metric_axis]);
    for (i, (axis, name)) in axes.zip(names).enumerate() {
        let x = x_of(i);
        area.draw(&PathElement::new(
            vec![(x, top), (x, bottom)],
            BLACK.stroke_width(1),
        ))?;
        for (label, position) in axis.labels() {
            let y = y_of(position);
            area.draw(&PathElement::new(
                vec![(x - 5, y), (x, y)],
                BLACK.stroke_width(1),
            ))?;
            area.draw(&Text::new(
                label,
                (x - 8, y),
                anchored(LABEL_SIZE, HPos::Right, VPos::Center),
            ))?;
        }
        area.draw(&Text::new(
            name.to_string(),
            (x, bottom + 14),
            anchored(LABEL_SIZE, HPos::Center, VPos::Top),
        ))?;
    }
    let metric_name = names.last().copied().unwrap_or_default();
    color_bar(area, metric_scale, metric_name, (top, bottom))
}

/// The colour bar at the panel's right: the scale's colours bottom to top, labelled at
/// its ticks.
fn color_bar(area: &Area, scale: &Scale, name: &str, (top, bottom): (i32, i32)) -> PlotResult {
    let x = area.dim_in_pixel().0 as i32 - COLOR_BAR_WIDTH as i32 + 60;
    let steps = 100;
    for step in 0..steps {
        let y0 = bottom - (bottom - top) * step / steps;
        let y1 = bottom - (bottom - top) * (step + 1) / steps;
        let fraction = (f64::from(step) + 0.5) / f64::from(steps);
        area.draw(&Rectangle::new(
            [(x, y1), (x + 20, y0)],
            color_at(fraction).filled(),
        ))?;
    }
    area.draw(&Rectangle::new(
        [(x, top), (x + 20, bottom)],
        BLACK.stroke_width(1),
    ))?;
    for tick in scale.ticks() {
        let y = bottom - (scale.fraction(tick) * f64::from(bottom - top)).round() as i32;
        area.draw(&PathElement::new(
            vec![(x + 20, y), (x + 25, y)],
            BLACK.stroke_width(1),
        ))?;
        area.draw(&Text::new(
            scale.label(tick),
            (x + 28, y),
            anchored(LABEL_SIZE, HPos::Left, VPos::Center),
        ))?;
    }
    area.draw(&Text::new(
        "colour:".to_string(),
        (x - 30, top - 26),
        anchored(LABEL_SIZE, HPos::Left, VPos::Center),
    ))?;
    area.draw(&Text::new(
        name.to_string(),
        (x - 30, top - 8),
        anchored(LABEL_SIZE - 2, HPos::Left, VPos::Center),
    ))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_map_to_heights_on_their_axis() {
        let channels = Axis::of(&[Swept::Integer(8), Swept::Integer(16)]);
        let Axis::Numbers(scale) = &channels else {
            panic!("{channels:?}")
        };
        assert_eq!(
            scale.ticks().collect::<Vec<_>>(),
            [8.0, 10.0, 12.0, 14.0, 16.0]
        );
        // 8 and 16 sit the same distance inside the ends.
        let (low, high) = (
            channels.position(&Swept::Integer(8)),
            channels.position(&Swept::Integer(16)),
        );
        assert!((low - (1.0 - high)).abs() < 1e-12 && low > 0.0 && low < 0.1);
        assert!((channels.position(&Swept::Integer(12)) - 0.5).abs() < 1e-12);

        let windows = Axis::of(&[
            Swept::Text("[20, 40]".into()),
            Swept::Text("[20, 60]".into()),
            Swept::Text("[20, 40]".into()),
            Swept::Text("[10]".into()),
        ]);
        assert_eq!(windows.position(&Swept::Text("[20, 40]".into())), 1.0 / 6.0);
        assert_eq!(windows.position(&Swept::Text("[10]".into())), 5.0 / 6.0);
        assert_eq!(
            windows.labels(),
            [
                ("[20, 40]".to_string(), 1.0 / 6.0),
                ("[20, 60]".to_string(), 0.5),
                ("[10]".to_string(), 5.0 / 6.0)
            ]
        );
    }

    #[test]
    fn the_metric_maps_to_the_colour_scale() {
        assert_eq!(color_at(0.0), RGBColor(68, 1, 84));
        assert_eq!(color_at(1.0), RGBColor(189, 223, 38));
        assert_eq!(color_at(0.5), RGBColor(33, 145, 140));
        // Halfway between the first two stops.
        assert_eq!(color_at(0.125), RGBColor(64, 42, 112));
        assert_eq!(color_at(-3.0), color_at(0.0));
        assert_eq!(color_at(7.0), color_at(1.0));
    }
}
