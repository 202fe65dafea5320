//! The calibration figure: mean RMSE against the calibration window, one panel per
//! DVL, one line per estimator and error model, each T_conv ringed. A line's colour is
//! its error model (or its estimator's own, for one without), its stroke and marker
//! its kind of estimator, so the legend lists the kinds and the error models apart. A
//! panel's value axis says when it is logarithmic, and one whose lines crowd in a band
//! while another group lies far above is broken between them ([`BrokenAxis`]). In: a
//! [`StoredRun`]'s calibration table. Out: the figure, or why the table is empty.

use super::{calibration_name, series_of};
use crate::evaluate::CalibrationRow;
use crate::report::kit::plots::broken_axis::BrokenAxis;
use crate::report::kit::plots::canvas::{Drawn, Outcome, draw_svg};
use crate::report::kit::plots::draw::*;
use crate::report::kit::plots::scale::Scale;
use crate::results::read::StoredRun;
use crate::vocab::{ErrorModel, EstimatorKind};
use plotters::prelude::*;
use std::ops::Range;

/// Mean RMSE against calibration window size, one panel per DVL, T_conv ringed.
pub fn calibration(run: &StoredRun) -> PlotResult<Outcome> {
    if run.calibration.is_empty() {
        return Ok(Outcome::NotApplicable(
            "calibration.parquet is empty".into(),
        ));
    }
    let dvls = run.dvls();
    let series = series_of(&run.calibration);
    let mut caption = format!(
        "Calibration on {}: mean RMSE over {} runs against window size (T_conv ringed)",
        calibration_name(run),
        run.spec.calibration.monte_carlo_runs
    );
    let replicates = run.spec.training.replicates;
    if replicates > 1 {
        caption += &format!("; DCNet: mean of {replicates} replicates, bars their 95 % CI");
    }
    let width = 560 * dvls.len() as u32 + LEGEND_WIDTH;
    let svg = draw_svg((width, 620), |root| {
        let (panels, legend_area) = panels_and_legend(root, &caption, width, dvls.len())?;
        let windows = WindowAxis::of(&run.calibration);
        let mut marks = PanelMarks::default();
        for (area, dvl) in panels.iter().zip(&dvls) {
            marks = marks.or(calibration_panel(area, dvl, run, &series, &windows)?);
        }
        legends(&legend_area, &legend_sections(&series, marks))
    })?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}

/// The window axis of the calibration figure: its padded range, and how many windows
/// it holds.
struct WindowAxis {
    range: Range<f64>,
    count: usize,
}

impl WindowAxis {
    /// The axis over every window of `rows`.
    fn of(rows: &[CalibrationRow]) -> WindowAxis {
        let windows: Vec<f64> = rows.iter().map(|r| r.window_s).collect();
        // A far series may be cut: as many values as there are windows.
        let count = crate::first_seen(windows.iter()).len();
        let (first, last) = windows.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), w| {
            (lo.min(*w), hi.max(*w))
        });
        let pad = 0.05 * (last - first).max(10.0);
        WindowAxis {
            range: (first - pad)..(last + pad),
            count,
        }
    }
}

/// What a panel drew that the legend explains.
#[derive(Debug, Clone, Copy, Default)]
struct PanelMarks {
    /// A value beyond the axis, drawn at its edge.
    cut: bool,
    /// A break in the value axis.
    broken: bool,
}

impl PanelMarks {
    fn or(self, other: PanelMarks) -> PanelMarks {
        PanelMarks {
            cut: self.cut || other.cut,
            broken: self.broken || other.broken,
        }
    }
}

/// The shade of the band where a value axis is broken.
const BREAK_SHADE: RGBColor = RGBColor(225, 225, 225);
/// The colour of a kind of estimator in the legend, when its lines take their error
/// model's colour.
const KIND_GREY: RGBColor = RGBColor(80, 80, 80);

/// The marker of a kind of estimator on its lines; its stroke is [`series_look`]'s.
fn marker_of(estimator: EstimatorKind) -> Marker {
    match estimator {
        EstimatorKind::Baseline => Marker::Square,
        EstimatorKind::LeastSquares => Marker::Cross,
        EstimatorKind::BeamWls => Marker::Diamond,
        EstimatorKind::Kalman | EstimatorKind::KalmanBeam => Marker::Triangle,
        EstimatorKind::Dcnet => Marker::Circle,
        EstimatorKind::DcnetEnsemble => Marker::Ring,
        EstimatorKind::Floor | EstimatorKind::Bound => Marker::Dot,
    }
}

/// The legend's sections: the kinds of estimator (stroke and marker), the error models
/// (colour), and the marks on the lines.
fn legend_sections(
    series: &[Series],
    marks: PanelMarks,
) -> Vec<(&'static str, Vec<(Swatch, String)>)> {
    let kinds = crate::first_seen(series.iter().map(|(estimator, _)| *estimator));
    let kinds = kinds
        .into_iter()
        .map(|estimator| {
            // Drawn with any error model, for its stroke.
            let model = estimator.takes_error_model().then_some(ErrorModel::Em1);
            let look = series_look(estimator, model);
            let color = if model.is_some() {
                KIND_GREY
            } else {
                look.color
            };
            let swatch = Swatch::Marked(color, look.stroke, marker_of(estimator));
            (swatch, estimator.label().to_string())
        })
        .collect();
    let models: Vec<ErrorModel> = crate::first_seen(series.iter().filter_map(|(_, model)| *model));
    let models = models
        .into_iter()
        .map(|model| {
            let color = series_look(EstimatorKind::Dcnet, Some(model)).color;
            (Swatch::Bar(color), model.to_string())
        })
        .collect::<Vec<_>>();
    let mut on_lines = vec![(Swatch::Ring, "T_conv".to_string())];
    if marks.cut {
        on_lines.push((Swatch::Cut, "beyond the axis".into()));
    }
    if marks.broken {
        on_lines.push((Swatch::Bar(BREAK_SHADE), "axis broken".into()));
    }
    let mut sections = vec![("estimator: line, marker", kinds)];
    if !models.is_empty() {
        sections.push(("error model: colour", models));
    }
    sections.push(("marks", on_lines));
    sections
}

/// The label of a panel's value axis, saying when it is logarithmic or broken.
fn value_label(axis: &BrokenAxis) -> &'static str {
    if axis.is_log() {
        "mean RMSE [cm/s], log scale"
    } else if axis.gap().is_some() {
        "mean RMSE [cm/s], axis broken"
    } else {
        "mean RMSE [cm/s]"
    }
}

/// One DVL's panel of the calibration figure: a line per series; says what it drew
/// that the legend explains.
fn calibration_panel(
    area: &Area,
    dvl: &str,
    run: &StoredRun,
    series: &[Series],
    windows: &WindowAxis,
) -> PlotResult<PanelMarks> {
    let rows: Vec<&CalibrationRow> = run.calibration.iter().filter(|r| r.dvl == dvl).collect();
    let values: Vec<f64> = rows.iter().map(|r| r.rmse_cm_s).collect();
    let y = BrokenAxis::fit(&values, windows.count);
    let x = Scale::linear(windows.range.clone());
    let mut chart = chart_on(area, dvl, 70).build_cartesian_2d(x, y.clone())?;
    mesh(&mut chart)
        .x_desc("calibration window [s]")
        .y_desc(value_label(&y))
        .draw()?;
    if let Some(gap) = y.gap() {
        let Range { start, end } = windows.range.clone();
        chart.draw_series(std::iter::once(Rectangle::new(
            [(start, gap.start), (end, gap.end)],
            BREAK_SHADE.filled(),
        )))?;
    }
    for &(estimator, model) in series {
        let look = series_look(estimator, model);
        let points: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.estimator == estimator && r.error_model == model)
            .map(|r| (r.window_s, y.shown(r.rmse_cm_s)))
            .collect();
        line(&mut chart, points.clone(), look.color, look.stroke)?;
        let marker = marker_of(estimator);
        marker.draw(&mut chart, &points, look.color)?;
        // The confidence interval across DCNet replicates, as error bars.
        let bars = rows.iter().filter_map(|r| {
            let ci = r
                .rmse_ci_cm_s
                .filter(|_| r.estimator == estimator && r.error_model == model)?;
            let ends = [r.rmse_cm_s - ci, r.rmse_cm_s + ci].map(|v| (r.window_s, y.shown(v)));
            Some(PathElement::new(ends.to_vec(), look.color.stroke_width(2)))
        });
        chart.draw_series(bars)?;
    }
    let cut = calibration_marks(&mut chart, &rows, &y)?;
    Ok(PanelMarks {
        cut,
        broken: y.gap().is_some(),
    })
}

/// Rings each T_conv of `rows` and marks each value beyond the axis `y`; says whether
/// one was.
fn calibration_marks(
    chart: &mut Chart<'_, '_, Scale, BrokenAxis>,
    rows: &[&CalibrationRow],
    y: &BrokenAxis,
) -> PlotResult<bool> {
    let mut cut = false;
    for row in rows {
        let at = (row.window_s, y.shown(row.rmse_cm_s));
        if row.is_t_conv {
            chart.draw_series(std::iter::once(Circle::new(at, 8, BLACK.stroke_width(2))))?;
        }
        if y.is_cut(row.rmse_cm_s) {
            let color = series_look(row.estimator, row.error_model).color;
            let edge = if y.is_below(row.rmse_cm_s) {
                Edge::Bottom
            } else {
                Edge::Top
            };
            cut_mark(chart, at, row.rmse_cm_s, color, edge)?;
            cut = true;
        }
    }
    Ok(cut)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quick spec's fourteen series.
    fn quick_series() -> Vec<Series> {
        let mut series = vec![(EstimatorKind::Baseline, None)];
        for estimator in [EstimatorKind::LeastSquares, EstimatorKind::Dcnet] {
            series.extend(ErrorModel::ALL.map(|model| (estimator, Some(model))));
        }
        series.insert(6, (EstimatorKind::BeamWls, None));
        series.extend([(EstimatorKind::Floor, None), (EstimatorKind::Bound, None)]);
        series
    }

    fn texts(entries: &[(Swatch, String)]) -> Vec<&str> {
        entries.iter().map(|(_, text)| text.as_str()).collect()
    }

    #[test]
    fn the_legend_lists_kinds_and_error_models_apart() {
        let series = quick_series();
        assert_eq!(series.len(), 14);
        let sections = legend_sections(&series, PanelMarks::default());
        let titles: Vec<&str> = sections.iter().map(|(title, _)| *title).collect();
        assert_eq!(
            titles,
            ["estimator: line, marker", "error model: colour", "marks"]
        );
        assert_eq!(
            texts(&sections[0].1),
            [
                "baseline",
                "least squares",
                "beam-model WLS",
                "DCNet",
                "floor (true terms)",
                "information bound"
            ]
        );
        assert_eq!(texts(&sections[1].1), ["EM1", "EM2", "EM3", "EM4", "EM5"]);
        assert_eq!(texts(&sections[2].1), ["T_conv"]);
        // A kind drawn in its error model's colour is grey in the legend.
        assert!(matches!(
            sections[0].1[1].0,
            Swatch::Marked(color, Stroke::Dashed, Marker::Cross) if color == KIND_GREY
        ));
        // Every kind has its own stroke and marker, or its own colour.
        let looks: Vec<String> = sections[0]
            .1
            .iter()
            .map(|(s, _)| format!("{s:?}"))
            .collect();
        assert_eq!(crate::first_seen(looks.iter()).len(), looks.len());

        let marks = PanelMarks {
            cut: true,
            broken: true,
        };
        let sections = legend_sections(&series[..1], marks);
        assert_eq!(sections.len(), 2, "no error model, no section for them");
        assert_eq!(
            texts(&sections[1].1),
            ["T_conv", "beyond the axis", "axis broken"]
        );
    }

    #[test]
    fn the_value_axis_says_when_it_is_logarithmic_or_broken() {
        let decades = BrokenAxis::fit(&[0.058, 0.06, 0.09, 0.1, 0.5, 0.7, 2.1], 5);
        assert_eq!(value_label(&decades), "mean RMSE [cm/s], log scale");
        let mut crowded: Vec<f64> = (0..40).map(|i| 5.9 + 0.005 * f64::from(i)).collect();
        crowded.extend([6.4, 6.42, 6.45, 6.43, 6.41]);
        let broken = BrokenAxis::fit(&crowded, 5);
        assert_eq!(value_label(&broken), "mean RMSE [cm/s], axis broken");
        let even: Vec<f64> = (0..30).map(|i| 5.8 + 0.03 * f64::from(i)).collect();
        assert_eq!(value_label(&BrokenAxis::fit(&even, 5)), "mean RMSE [cm/s]");
    }
}
