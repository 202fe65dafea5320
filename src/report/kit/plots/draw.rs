//! Drawing pieces the figures share: the look of each estimator and error model, the
//! panels beside the legend column and the legend's entries, category axes, values cut
//! at a panel's edge with their number, bars and box plots.
//! In: a plotters drawing area or chart and what to draw on it. Out: the drawing, or
//! a [`DrawError`].

use super::render::FAMILY;
use super::scale::Scale;
use crate::report::kit::numbers::three_digits;
use crate::vocab::{ErrorModel, EstimatorKind};
use plotters::chart::MeshStyle;
use plotters::coord::Shift;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::element::{DashedPathElement, Polygon};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

pub type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
/// What drawing on an [`Area`] fails with: plotters' error, over the SVG backend's.
pub type DrawError = DrawingAreaErrorKind<std::io::Error>;
/// What a drawing step returns.
pub type PlotResult<T = ()> = Result<T, DrawError>;
/// A chart drawn on an [`Area`], `X` and `Y` its axes.
pub type Chart<'a, 'b, X, Y> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<X, Y>>;
/// One series of a figure: an estimator, with its error model where it has one.
pub type Series = (EstimatorKind, Option<ErrorModel>);

pub const TITLE_SIZE: u32 = 22;
pub const PANEL_TITLE_SIZE: u32 = 18;
pub const LABEL_SIZE: u32 = 15;
pub const LEGEND_WIDTH: u32 = 240;

pub fn font(size: u32) -> TextStyle<'static> {
    (FAMILY, size).into_font().color(&BLACK)
}

pub fn anchored(size: u32, h: HPos, v: VPos) -> TextStyle<'static> {
    font(size).pos(Pos::new(h, v))
}

/// A chart on `area` with the figures' margin and label areas, `y_label_width` wide
/// enough for its y tick labels, captioned `title` unless it is empty.
pub fn chart_on<'a, 'b>(
    area: &'a Area<'b>,
    title: &str,
    y_label_width: u32,
) -> ChartBuilder<'a, 'b, SVGBackend<'b>> {
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(y_label_width);
    if !title.is_empty() {
        builder.caption(title, font(PANEL_TITLE_SIZE));
    }
    builder
}

/// `root` titled `caption`, its `width` split into `count` panels side by side and the
/// legend column on the right; returns the panels and the legend's area.
pub fn panels_and_legend<'a>(
    root: &Area<'a>,
    caption: &str,
    width: u32,
    count: usize,
) -> PlotResult<(Vec<Area<'a>>, Area<'a>)> {
    let root = root.titled(caption, font(TITLE_SIZE))?;
    let (panels, legend_area) = root.split_horizontally(width - LEGEND_WIDTH);
    Ok((panels.split_evenly((1, count)), legend_area))
}

/// The mesh of `chart` in the figures' style: labels in the figure font, white minor
/// grid lines.
pub fn mesh<'a, 'b, X, Y, XT, YT>(
    chart: &'b mut ChartContext<'a, SVGBackend<'a>, Cartesian2d<X, Y>>,
) -> MeshStyle<'a, 'b, X, Y, SVGBackend<'a>>
where
    X: Ranged<ValueType = XT> + ValueFormatter<XT>,
    Y: Ranged<ValueType = YT> + ValueFormatter<YT>,
{
    let mut mesh = chart.configure_mesh();
    mesh.label_style(font(LABEL_SIZE))
        .axis_desc_style(font(LABEL_SIZE))
        .light_line_style(WHITE);
    mesh
}

/// How a line is stroked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Stroke {
    Solid,
    Dashed,
    Dotted,
}

/// The look of one series: colour, stroke, and its name in legends.
#[derive(Debug, Clone)]
pub struct Look {
    pub label: String,
    pub color: RGBColor,
    pub stroke: Stroke,
}

pub const GREY: RGBColor = RGBColor(120, 120, 120);
const MODEL_COLORS: [RGBColor; 5] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
];

/// Colour by error model, stroke by estimator: DCNet solid, least squares dashed, the
/// Kalman filter dotted; the baseline black, the beam-model WLS brown and dashed, its
/// Kalman filter olive and dotted, the floor grey and dotted, the
/// bound black and dotted.
pub fn series_look(estimator: EstimatorKind, error_model: Option<ErrorModel>) -> Look {
    let label = estimator.label_with(error_model);
    let (color, stroke) = match (estimator, error_model) {
        (EstimatorKind::Floor, _) => (GREY, Stroke::Dotted),
        (EstimatorKind::Bound, _) => (BLACK, Stroke::Dotted),
        (EstimatorKind::BeamWls, _) => (estimator_color(estimator), Stroke::Dashed),
        (EstimatorKind::KalmanBeam, _) => (estimator_color(estimator), Stroke::Dotted),
        (_, None) => (BLACK, Stroke::Solid),
        (estimator, Some(model)) => (
            MODEL_COLORS[model as usize % MODEL_COLORS.len()],
            match estimator {
                EstimatorKind::LeastSquares => Stroke::Dashed,
                EstimatorKind::Kalman | EstimatorKind::DcnetEnsemble => Stroke::Dotted,
                _ => Stroke::Solid,
            },
        ),
    };
    Look {
        label,
        color,
        stroke,
    }
}

/// The legend entries of `series`, each with its line as drawn.
pub fn series_entries(series: &[Series]) -> Vec<(Swatch, String)> {
    series
        .iter()
        .map(|&(estimator, model)| {
            let look = series_look(estimator, model);
            (Swatch::Line(look.color, look.stroke), look.label)
        })
        .collect()
}

/// Colour by estimator, for the bar figures whose x axis holds the error models.
pub fn estimator_color(estimator: EstimatorKind) -> RGBColor {
    match estimator {
        EstimatorKind::Baseline => RGBColor(90, 90, 90),
        EstimatorKind::LeastSquares => RGBColor(31, 119, 180),
        EstimatorKind::BeamWls => RGBColor(140, 86, 75),
        EstimatorKind::Kalman => RGBColor(23, 190, 207),
        EstimatorKind::KalmanBeam => RGBColor(188, 189, 34),
        EstimatorKind::Dcnet => RGBColor(214, 39, 40),
        EstimatorKind::DcnetEnsemble => RGBColor(148, 103, 189),
        EstimatorKind::Floor => GREY,
        EstimatorKind::Bound => BLACK,
    }
}

/// A line through `points` in chart coordinates, stroked as `look` says.
pub fn line<X: Ranged<ValueType = f64>, Y: Ranged<ValueType = f64>>(
    chart: &mut ChartContext<SVGBackend, Cartesian2d<X, Y>>,
    points: Vec<(f64, f64)>,
    color: RGBColor,
    stroke: Stroke,
) -> PlotResult {
    let style = color.stroke_width(2);
    match stroke {
        Stroke::Solid => {
            chart.draw_series(LineSeries::new(points, style))?;
        }
        Stroke::Dashed => {
            chart.draw_series(DashedLineSeries::new(points, 8, 5, style))?;
        }
        Stroke::Dotted => {
            chart.draw_series(DashedLineSeries::new(points, 2, 4, style))?;
        }
    }
    Ok(())
}

/// What a legend entry shows beside its text.
#[derive(Debug, Clone)]
pub enum Swatch {
    Line(RGBColor, Stroke),
    /// A line with its marker in the middle.
    Marked(RGBColor, Stroke, Marker),
    /// A marker alone.
    Mark(RGBColor, Marker),
    Bar(RGBColor),
    Ring,
    Dot(RGBColor),
    /// A value cut at the panel's edge.
    Cut,
}

/// The mark drawn at each point of a line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    Circle,
    Ring,
    Square,
    Diamond,
    Cross,
    /// A filled triangle, point down (point up is the mark of a value cut at the edge).
    Triangle,
    /// A small filled circle.
    Dot,
}

impl Marker {
    /// The mark at each of `points` of `chart`, in `color`.
    pub fn draw<X: Ranged<ValueType = f64>, Y: Ranged<ValueType = f64>>(
        self,
        chart: &mut ChartContext<SVGBackend, Cartesian2d<X, Y>>,
        points: &[(f64, f64)],
        color: RGBColor,
    ) -> PlotResult {
        let at = |point: &(f64, f64)| EmptyElement::at(*point);
        match self {
            Marker::Circle => chart.draw_series(
                points
                    .iter()
                    .map(|p| at(p) + Circle::new((0, 0), 4, color.filled())),
            )?,
            Marker::Ring => chart.draw_series(
                points
                    .iter()
                    .map(|p| at(p) + Circle::new((0, 0), 4, color.stroke_width(2))),
            )?,
            Marker::Square => chart.draw_series(
                points
                    .iter()
                    .map(|p| at(p) + Rectangle::new([(-4, -4), (4, 4)], color.filled())),
            )?,
            Marker::Diamond => chart.draw_series(
                points
                    .iter()
                    .map(|p| at(p) + Polygon::new(DIAMOND.to_vec(), color.filled())),
            )?,
            Marker::Cross => chart.draw_series(
                points
                    .iter()
                    .map(|p| at(p) + Cross::new((0, 0), 4, color.stroke_width(2))),
            )?,
            Marker::Triangle => chart.draw_series(
                points
                    .iter()
                    .map(|p| at(p) + Polygon::new(TRIANGLE.to_vec(), color.filled())),
            )?,
            Marker::Dot => chart.draw_series(
                points
                    .iter()
                    .map(|p| at(p) + Circle::new((0, 0), 2, color.filled())),
            )?,
        };
        Ok(())
    }

    /// The mark centred on `at` of `area`, in `color`.
    fn draw_on(self, area: &Area, at: (i32, i32), color: RGBColor) -> PlotResult {
        let origin = EmptyElement::at(at);
        match self {
            Marker::Circle => area.draw(&(origin + Circle::new((0, 0), 4, color.filled()))),
            Marker::Ring => area.draw(&(origin + Circle::new((0, 0), 4, color.stroke_width(2)))),
            Marker::Square => {
                area.draw(&(origin + Rectangle::new([(-4, -4), (4, 4)], color.filled())))
            }
            Marker::Diamond => {
                area.draw(&(origin + Polygon::new(DIAMOND.to_vec(), color.filled())))
            }
            Marker::Cross => area.draw(&(origin + Cross::new((0, 0), 4, color.stroke_width(2)))),
            Marker::Triangle => {
                area.draw(&(origin + Polygon::new(TRIANGLE.to_vec(), color.filled())))
            }
            Marker::Dot => area.draw(&(origin + Circle::new((0, 0), 2, color.filled()))),
        }
    }
}

/// The corners of [`Marker::Diamond`] around its centre, in pixels.
const DIAMOND: [(i32, i32); 4] = [(0, -5), (5, 0), (0, 5), (-5, 0)];
/// The corners of [`Marker::Triangle`] around its centre, in pixels.
const TRIANGLE: [(i32, i32); 3] = [(0, 5), (5, -4), (-5, -4)];

/// A column of legend entries, top to bottom.
pub fn legend(area: &Area, title: &str, entries: &[(Swatch, String)]) -> PlotResult {
    legend_from(area, 60, title, entries).map(|_| ())
}

/// Legends one below the other in a column, each a title and its entries.
pub fn legends(area: &Area, sections: &[(&str, Vec<(Swatch, String)>)]) -> PlotResult {
    let mut y = 60;
    for (title, entries) in sections {
        // Room for the next title above its first entry.
        y = legend_from(area, y, title, entries)? + 40;
    }
    Ok(())
}

/// A legend whose first entry is at height `y`, its title above; returns the height
/// below its last entry.
fn legend_from(
    area: &Area,
    mut y: i32,
    title: &str,
    entries: &[(Swatch, String)],
) -> PlotResult<i32> {
    let row = 24;
    area.draw(&Text::new(
        title.to_string(),
        (12, y - 28),
        anchored(LABEL_SIZE, HPos::Left, VPos::Center),
    ))?;
    for (swatch, text) in entries {
        let (x0, x1) = (12, 44);
        match swatch {
            Swatch::Line(color, stroke) => legend_line(area, (x0, x1, y), *color, *stroke)?,
            Swatch::Marked(color, stroke, marker) => {
                legend_line(area, (x0, x1, y), *color, *stroke)?;
                marker.draw_on(area, (28, y), *color)?;
            }
            Swatch::Mark(color, marker) => marker.draw_on(area, (28, y), *color)?,
            Swatch::Bar(color) => area.draw(&Rectangle::new(
                [(x0 + 6, y - 7), (x1 - 6, y + 7)],
                color.filled(),
            ))?,
            Swatch::Ring => area.draw(&Circle::new((28, y), 7, BLACK.stroke_width(2)))?,
            Swatch::Dot(color) => area.draw(&Circle::new((28, y), 4, color.filled()))?,
            Swatch::Cut => area.draw(&TriangleMarker::new((28, y), 7, BLACK.filled()))?,
        }
        area.draw(&Text::new(
            text.clone(),
            (x1 + 10, y),
            anchored(LABEL_SIZE, HPos::Left, VPos::Center),
        ))?;
        y += row;
    }
    Ok(y)
}

/// The line of a legend entry, from `x0` to `x1` at height `y`.
fn legend_line(
    area: &Area,
    (x0, x1, y): (i32, i32, i32),
    color: RGBColor,
    stroke: Stroke,
) -> PlotResult {
    let style = color.stroke_width(2);
    let points = vec![(x0, y), (x1, y)];
    match stroke {
        Stroke::Solid => area.draw(&PathElement::new(points, style)),
        Stroke::Dashed => area.draw(&DashedPathElement::new(points, 8, 5, style)),
        Stroke::Dotted => area.draw(&DashedPathElement::new(points, 2, 4, style)),
    }
}

/// The edge of a panel at which a value beyond the axis is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Edge {
    /// The top of a value axis that runs up: the value is written below the mark.
    Top,
    /// The bottom of a value axis that runs up: the value is written above the mark.
    Bottom,
    /// The right end of a value axis that runs right: written left of and above it.
    Right,
    /// The left end of a value axis that runs right: written right of and above it.
    Left,
}

impl Edge {
    /// The edge of a vertical axis `scale` at which the cut `value` is drawn.
    pub fn of_vertical(scale: &Scale, value: f64) -> Edge {
        if scale.is_below(value) {
            Edge::Bottom
        } else {
            Edge::Top
        }
    }

    /// The edge of a horizontal axis `scale` at which the cut `value` is drawn.
    pub fn of_horizontal(scale: &Scale, value: f64) -> Edge {
        if scale.is_below(value) {
            Edge::Left
        } else {
            Edge::Right
        }
    }
}

/// Marks a value drawn at the `edge` of a panel because it lies beyond: a triangle at
/// `at` and the value written beside it, inside the panel.
pub fn cut_mark<X: Ranged<ValueType = f64>, Y: Ranged<ValueType = f64>>(
    chart: &mut ChartContext<SVGBackend, Cartesian2d<X, Y>>,
    at: (f64, f64),
    value: f64,
    color: RGBColor,
    edge: Edge,
) -> PlotResult {
    let (offset, anchor) = match edge {
        Edge::Top => ((8, 4), Pos::new(HPos::Left, VPos::Top)),
        Edge::Bottom => ((8, -4), Pos::new(HPos::Left, VPos::Bottom)),
        Edge::Right => ((-6, -8), Pos::new(HPos::Right, VPos::Bottom)),
        Edge::Left => ((6, -8), Pos::new(HPos::Left, VPos::Bottom)),
    };
    chart.draw_series(std::iter::once(
        EmptyElement::at(at)
            + TriangleMarker::new((0, 0), 7, color.filled())
            + Text::new(
                three_digits(value),
                offset,
                font(LABEL_SIZE - 1).pos(anchor),
            ),
    ))?;
    Ok(())
}

/// The label of category `value` on an axis of categories at 0, 1, 2, …
pub fn category(names: &[String], value: f64) -> String {
    let index = value.round();
    if (value - index).abs() > 1e-6 || index < 0.0 {
        return String::new();
    }
    names.get(index as usize).cloned().unwrap_or_default()
}

/// Lower whisker, first quartile, median, third quartile, upper whisker: quartiles by
/// linear interpolation, whiskers at the furthest values within 1.5 IQR of the box.
pub fn box_stats(values: &[f64]) -> [f64; 5] {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let quantile = |q: f64| {
        let position = q * (sorted.len() - 1) as f64;
        let (low, high) = (position.floor() as usize, position.ceil() as usize);
        sorted[low] + (sorted[high] - sorted[low]) * (position - low as f64)
    };
    let (q1, median, q3) = (quantile(0.25), quantile(0.5), quantile(0.75));
    let reach = 1.5 * (q3 - q1);
    let low = sorted
        .iter()
        .copied()
        .find(|v| *v >= q1 - reach)
        .unwrap_or(q1);
    let high = sorted
        .iter()
        .rev()
        .copied()
        .find(|v| *v <= q3 + reach)
        .unwrap_or(q3);
    [low, q1, median, q3, high]
}

/// Every `k`-th of `points` and its last, so that at most about `most` are left.
pub fn strided<T: Copy>(points: &[T], most: usize) -> Vec<T> {
    let stride = points.len().div_ceil(most.max(1)).max(1);
    let last = points.len().saturating_sub(1);
    (points.iter().enumerate())
        .filter(|(k, _)| k % stride == 0 || *k == last)
        .map(|(_, p)| *p)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_statistics_of_known_samples() {
        let values: Vec<f64> = (1..=9).map(f64::from).collect();
        assert_eq!(box_stats(&values), [1.0, 3.0, 5.0, 7.0, 9.0]);
        // 100 lies beyond q3 + 1.5 IQR, so the whisker stops at the largest value within.
        let values = [1.0, 2.0, 3.0, 4.0, 100.0];
        assert_eq!(box_stats(&values), [1.0, 2.0, 3.0, 4.0, 4.0]);
        assert_eq!(box_stats(&[2.5]), [2.5; 5]);
    }

    #[test]
    fn written_values_and_category_labels_are_short() {
        assert_eq!(three_digits(26.41), "26.4");
        assert_eq!(three_digits(0.5234), "0.523");
        assert_eq!(three_digits(1234.0), "1234");
        assert_eq!(category(&["a".into(), "b".into()], 1.0), "b");
        assert_eq!(category(&["a".into(), "b".into()], 0.5), "");
    }

    #[test]
    fn a_long_line_is_strided_to_about_the_most_points_its_ends_kept() {
        let points: Vec<usize> = (0..10_001).collect();
        let drawn = strided(&points, 3000);
        assert!(drawn.len() <= 3001, "{}", drawn.len());
        assert_eq!((drawn[0], drawn[drawn.len() - 1]), (0, 10_000));
        assert_eq!(strided(&points[..5], 3000), vec![0, 1, 2, 3, 4]);
    }
}
