//! The bar figures, grouped bars with their values written on them: the RMSE at the
//! first (shortest) calibration window per error model against the baseline, and the
//! improvement over the baseline with EM5 per test trajectory; one panel per DVL, one
//! colour per estimator. In: a [`StoredRun`]'s calibration and evaluation tables. Out:
//! each figure, or why the run lacks what it compares.

use super::calibration_name;
use crate::report::kit::plots::canvas::{Drawn, Outcome, draw_svg};
use crate::report::kit::plots::draw::*;
use crate::report::kit::plots::scale::{self, Scale};
use crate::results::read::StoredRun;
use crate::vocab::{ErrorModel, EstimatorKind};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};
use std::ops::Range;

/// One bar of a grouped bar chart.
struct Bar {
    group: usize,
    estimator: EstimatorKind,
    value: f64,
    spread: Option<f64>,
}

/// Grouped bars with their values written on them. Bars below `floor` are cut at it,
/// and with `cut_far`, when one bar (with its spread) reaches far above the others
/// ([`scale::cut_above`]), the axis ends above the others and that bar is cut at the
/// top; a cut bar keeps its value as white text inside its end. Says whether a bar was
/// cut at the top.
fn bar_panel(
    area: &Area,
    title: &str,
    groups: &[String],
    bars: &[Bar],
    y_desc: &str,
    floor: Option<f64>,
    cut_far: bool,
) -> PlotResult<bool> {
    let y_range = bar_range(bars, floor, cut_far);
    let mut chart = chart_on(area, title, 70).build_cartesian_2d(
        -0.5..(groups.len() as f64 - 0.5),
        Scale::linear(y_range.clone()),
    )?;
    mesh(&mut chart)
        .disable_x_mesh()
        .x_labels(groups.len() + 1)
        .x_label_formatter(&|x| category(groups, *x))
        .y_desc(y_desc)
        .draw()?;
    if y_range.start < 0.0 {
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(-0.5, 0.0), (groups.len() as f64 - 0.5, 0.0)],
            BLACK.stroke_width(1),
        )))?;
    }
    let percent = y_desc.contains('%');
    let mut cut_at_top = false;
    for (group, _) in groups.iter().enumerate() {
        let members: Vec<&Bar> = bars.iter().filter(|b| b.group == group).collect();
        let width = 0.8 / members.len().max(1) as f64;
        for (j, bar) in members.iter().enumerate() {
            let x0 = group as f64 - 0.4 + j as f64 * width;
            cut_at_top |= draw_bar(&mut chart, bar, x0, width, &y_range, percent)?;
        }
    }
    Ok(cut_at_top)
}

/// The value axis of a bar panel: from 0, or below it to the lowest bar (no lower than
/// `floor`), up to the highest top, with a margin; with `cut_far`, a top far above the
/// others does not count.
fn bar_range(bars: &[Bar], floor: Option<f64>, cut_far: bool) -> Range<f64> {
    let tops: Vec<f64> = bars
        .iter()
        .map(|b| b.value + b.spread.unwrap_or(0.0))
        .chain([0.0])
        .collect();
    let ceiling = scale::cut_above(&tops, 1)
        .filter(|_| cut_far)
        .unwrap_or(f64::INFINITY);
    let top = tops
        .iter()
        .copied()
        .filter(|t| *t <= ceiling)
        .fold(0.0f64, f64::max);
    let bottom = bars.iter().map(|b| b.value).fold(0.0f64, f64::min);
    let bottom = floor.map_or(bottom, |f| bottom.max(f));
    let span = (top - bottom).max(1e-9);
    (bottom - 0.08 * span * f64::from(bottom < 0.0))..(top + 0.15 * span)
}

/// One bar from `x0`, a `width` wide slot, with its spread as a whisker and its value
/// (a percentage when `percent`); says whether it was cut at the top of `y_range`.
fn draw_bar(
    chart: &mut Chart<'_, '_, RangedCoordf64, Scale>,
    bar: &Bar,
    x0: f64,
    width: f64,
    y_range: &Range<f64>,
    percent: bool,
) -> PlotResult<bool> {
    let (x1, middle) = (x0 + 0.92 * width, x0 + 0.46 * width);
    let shown = bar.value.clamp(y_range.start, y_range.end);
    chart.draw_series(std::iter::once(Rectangle::new(
        [(x0, 0.0), (x1, shown)],
        estimator_color(bar.estimator).filled(),
    )))?;
    let spread = bar.spread.filter(|s| *s > 0.0).unwrap_or(0.0);
    if spread > 0.0 {
        let (low, high) = (bar.value - spread, bar.value + spread);
        chart.draw_series(std::iter::once(PathElement::new(
            vec![
                (middle, low.max(y_range.start)),
                (middle, high.min(y_range.end)),
            ],
            BLACK.stroke_width(1),
        )))?;
    }
    // A cut bar: its value goes inside the bar's end.
    let inside = if bar.value < y_range.start {
        Some(VPos::Bottom)
    } else if bar.value > y_range.end {
        Some(VPos::Top)
    } else {
        None
    };
    let cut_at_top = matches!(inside, Some(VPos::Top));
    let (y, style) = match inside {
        Some(v) => (
            shown,
            anchored(LABEL_SIZE - 3, HPos::Center, v).color(&WHITE),
        ),
        None if shown >= 0.0 => (
            (shown + spread).min(y_range.end),
            anchored(LABEL_SIZE - 2, HPos::Center, VPos::Bottom),
        ),
        None => (shown, anchored(LABEL_SIZE - 2, HPos::Center, VPos::Top)),
    };
    let text = if percent {
        format!("{:+.0}", bar.value)
    } else {
        format!("{:.2}", bar.value)
    };
    chart.draw_series(std::iter::once(Text::new(text, (middle, y), style)))?;
    Ok(cut_at_top)
}

/// The legend of the bar figures: the estimators of the `drawn` bars (every panel's),
/// each once in the order first drawn, then `whisker` as a line when it is not empty,
/// then each line of `notes`.
fn bar_legend(area: &Area, drawn: &[Bar], whisker: &str, notes: &[&str]) -> PlotResult {
    let estimators = crate::first_seen(drawn.iter().map(|bar| bar.estimator));
    let mut entries: Vec<(Swatch, String)> = estimators
        .iter()
        .map(|e| (Swatch::Bar(estimator_color(*e)), e.label().to_string()))
        .collect();
    if !whisker.is_empty() {
        entries.push((Swatch::Line(BLACK, Stroke::Solid), whisker.to_string()));
    }
    legend(area, "estimator", &entries)?;
    let below = 60 + 24 * entries.len() as i32 + 8;
    for (i, note) in notes.iter().enumerate() {
        area.draw(&Text::new(
            note.to_string(),
            (12, below + 18 * i as i32),
            anchored(LABEL_SIZE - 2, HPos::Left, VPos::Center),
        ))?;
    }
    Ok(())
}

/// RMSE at the first (shortest) calibration window for EM2, EM4 and EM5 against the
/// baseline: the paper's bar figure, one panel per DVL.
pub fn rmse_first_window(run: &StoredRun) -> PlotResult<Outcome> {
    let Some(window) = run
        .calibration
        .iter()
        .map(|r| r.window_s)
        .min_by(f64::total_cmp)
    else {
        return Ok(Outcome::NotApplicable(
            "calibration.parquet is empty".into(),
        ));
    };
    let models: Vec<ErrorModel> = [ErrorModel::Em2, ErrorModel::Em4, ErrorModel::Em5]
        .into_iter()
        .filter(|m| run.calibration.iter().any(|r| r.error_model == Some(*m)))
        .collect();
    let has_baseline = run
        .calibration
        .iter()
        .any(|r| r.estimator == EstimatorKind::Baseline);
    if models.is_empty() || !has_baseline {
        return Ok(Outcome::NotApplicable(
            "the run holds no baseline or none of EM2, EM4, EM5".into(),
        ));
    }
    let estimators: Vec<EstimatorKind> = [EstimatorKind::LeastSquares, EstimatorKind::Dcnet]
        .into_iter()
        .filter(|e| run.calibration.iter().any(|r| r.estimator == *e))
        .collect();
    let mut groups = vec!["baseline".to_string()];
    groups.extend(models.iter().map(ToString::to_string));
    let dvls = run.dvls();
    let caption = format!(
        "RMSE with the terms of the first {window} s of {}: mean ± std over {} runs",
        calibration_name(run),
        run.spec.calibration.monte_carlo_runs
    );
    let width = 520 * dvls.len() as u32 + LEGEND_WIDTH;
    let svg = draw_svg((width, 560), |root| {
        let (panels, legend_area) = panels_and_legend(root, &caption, width, dvls.len())?;
        let (mut cut, mut drawn) = (false, Vec::new());
        for (area, dvl) in panels.iter().zip(&dvls) {
            let bars = first_window_bars(run, dvl, window, &models, &estimators);
            cut |= bar_panel(area, dvl, &groups, &bars, "RMSE [cm/s]", None, true)?;
            drawn.extend(bars);
        }
        let notes: &[&str] = if cut {
            &[
                "bars above the axis are cut;",
                "their value is written in white",
            ]
        } else {
            &[]
        };
        bar_legend(&legend_area, &drawn, "± std over runs", notes)
    })?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}

/// The bars of one DVL's panel of the first-window figure: the baseline, then each of
/// `models` with each of `estimators`, mean ± std at `window`.
fn first_window_bars(
    run: &StoredRun,
    dvl: &str,
    window: f64,
    models: &[ErrorModel],
    estimators: &[EstimatorKind],
) -> Vec<Bar> {
    let bar = |group: usize, estimator: EstimatorKind, model: Option<ErrorModel>| {
        run.calibration
            .iter()
            .find(|r| {
                r.dvl == dvl
                    && r.window_s == window
                    && r.estimator == estimator
                    && r.error_model == model
            })
            .map(|r| Bar {
                group,
                estimator,
                value: r.rmse_cm_s,
                spread: Some(r.rmse_std_cm_s),
            })
    };
    let mut bars: Vec<Bar> = bar(0, EstimatorKind::Baseline, None).into_iter().collect();
    for (i, model) in models.iter().enumerate() {
        for &estimator in estimators {
            bars.extend(bar(i + 1, estimator, Some(*model)));
        }
    }
    bars
}

/// Improvement over the baseline per test trajectory of each estimator with EM5.
pub fn improvement_em5(run: &StoredRun) -> PlotResult<Outcome> {
    let rows: Vec<_> = run
        .evaluation
        .iter()
        .filter(|r| r.error_model == Some(ErrorModel::Em5) && r.improvement_pct.is_some())
        .collect();
    if rows.is_empty() {
        return Ok(Outcome::NotApplicable(
            "the run holds no EM5 estimator with a baseline to compare".into(),
        ));
    }
    let trajectories = crate::first_seen(run.evaluation.iter().map(|r| r.trajectory.clone()));
    let dvls = run.dvls();
    let caption = "Improvement in RMSE over the baseline with EM5, per test trajectory".to_string();
    let width = 520 * dvls.len() as u32 + LEGEND_WIDTH;
    let svg = draw_svg((width, 560), |root| {
        let (panels, legend_area) = panels_and_legend(root, &caption, width, dvls.len())?;
        let mut drawn = Vec::new();
        for (area, dvl) in panels.iter().zip(&dvls) {
            let bars: Vec<Bar> = rows
                .iter()
                .filter(|r| &r.dvl == dvl)
                .filter_map(|r| {
                    Some(Bar {
                        group: trajectories.iter().position(|t| *t == r.trajectory)?,
                        estimator: r.estimator,
                        value: r.improvement_pct?,
                        spread: None,
                    })
                })
                .collect();
            bar_panel(
                area,
                dvl,
                &trajectories,
                &bars,
                "improvement over the baseline [%]",
                Some(-100.0),
                false,
            )?;
            drawn.extend(bars);
        }
        bar_legend(
            &legend_area,
            &drawn,
            "",
            &[
                "bars below -100 % are cut;",
                "their value is written in white",
            ],
        )
    })?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::paper::source::tests::{evaluation, run};
    use EstimatorKind::{Baseline, Dcnet, Kalman, LeastSquares};

    /// The estimators a figure's legend names: its SVG's text that is an estimator's
    /// label.
    fn named(svg: &str) -> Vec<EstimatorKind> {
        let every = [Baseline, LeastSquares, Kalman, Dcnet];
        (every.into_iter())
            .filter(|e| svg.contains(&format!(">\n{}\n</text>", e.label())))
            .collect()
    }

    /// Every bar figure's legend names exactly the estimators it draws bars of: EM5's
    /// improvement drew the Kalman filter's bars and named only least squares and DCNet.
    #[test]
    fn each_bar_figures_legend_names_what_it_draws() {
        crate::report::kit::plots::render::register_font();
        let mut run = run();
        run.evaluation.extend([
            evaluation(Kalman, Some(ErrorModel::Em5), 4.2, Some(31.0)),
            evaluation(LeastSquares, Some(ErrorModel::Em5), 4.8, Some(21.0)),
        ]);
        let Outcome::Drawn(drawn) = improvement_em5(&run).unwrap() else {
            panic!("EM5 improvement not drawn")
        };
        assert_eq!(named(&drawn.svg), [LeastSquares, Kalman, Dcnet]);
        let Outcome::Drawn(drawn) = rmse_first_window(&run).unwrap() else {
            panic!("first window not drawn")
        };
        // The calibration table holds the baseline and DCNet EM5 at its first window.
        assert_eq!(named(&drawn.svg), [Baseline, Dcnet]);
    }
}
