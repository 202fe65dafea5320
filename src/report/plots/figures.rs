//! The six figures, each drawn from a [`StoredRun`] into SVG text. A figure whose data
//! the run does not hold (no DCNet, no baseline, no EM5) says why instead.

use super::draw::*;
use super::scale::{self, Scale};
use crate::evaluate::CalibrationRow;
use crate::results::read::{StoredRun, StoredTrajectory};
use crate::vocab::{ErrorModel, EstimatorKind, Phase};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};
use std::ops::Range;

/// A figure: its caption and the SVG plotters drew.
pub struct Drawn {
    pub caption: String,
    pub svg: String,
}

/// Either a figure, or why the run cannot have it.
pub type MaybeDrawn = Result<Drawn, String>;

/// Every figure of a run, in the order the report shows them.
pub fn all(run: &StoredRun) -> PlotResult<Vec<(String, MaybeDrawn)>> {
    let figures: [(&str, MaybeDrawn); 6] = [
        ("velocity", velocity(run)?),
        ("calibration", calibration(run)?),
        ("rmse_first_window", rmse_first_window(run)?),
        ("improvement_em5", improvement_em5(run)?),
        ("monte_carlo_spread", monte_carlo_spread(run)?),
        ("training_loss", training_loss(run)?),
    ];
    Ok(figures
        .into_iter()
        .map(|(stem, outcome)| (stem.to_string(), outcome))
        .collect())
}

pub(super) fn draw_svg(
    size: (u32, u32),
    draw: impl FnOnce(&Area) -> PlotResult,
) -> PlotResult<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE)?;
        draw(&root)?;
        root.present()?;
    }
    Ok(svg)
}

fn calibration_name(run: &StoredRun) -> &str {
    &run.spec.calibration.trajectory
}

/// Velocity of a training and a test trajectory over time, body frame.
fn velocity(run: &StoredRun) -> PlotResult<MaybeDrawn> {
    let chosen = &run.spec.report.velocity_trajectories;
    let find = |name: &str| run.trajectories.iter().find(|t| t.name == name);
    let with_role = |role: &str| {
        run.trajectories
            .iter()
            .find(|t| t.roles.iter().any(|r| r == role))
    };
    let pair: Option<[&StoredTrajectory; 2]> = match chosen.as_slice() {
        [a, b] => find(a).zip(find(b)).map(|(a, b)| [a, b]),
        _ => with_role("train")
            .zip(with_role("test"))
            .map(|(a, b)| [a, b]),
    };
    let Some(pair) = pair else {
        return Ok(Err(
            "trajectories.parquet holds no training and test trajectory".into(),
        ));
    };
    let caption = format!(
        "GT velocity of {} and {} over time, body frame",
        pair[0].name, pair[1].name
    );
    let svg = draw_svg((1100, 760), |root| {
        let root = root.titled(&caption, font(TITLE_SIZE))?;
        let (panels, legend_area) = root.split_horizontally(1100 - LEGEND_WIDTH);
        let axes = [("vx", 0), ("vy", 1), ("vz", 2)];
        let colors = [
            RGBColor(31, 119, 180),
            RGBColor(255, 127, 14),
            RGBColor(44, 160, 44),
        ];
        for (area, trajectory) in panels.split_evenly((2, 1)).iter().zip(pair) {
            let end = trajectory.time_s.last().copied().unwrap_or(1.0).max(1.0);
            let (low, high) = trajectory
                .velocity_m_s
                .iter()
                .flatten()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(*v), hi.max(*v))
                });
            let pad = 0.05 * (high - low).max(0.1);
            let title = format!("{} ({})", trajectory.name, trajectory.roles.join(", "));
            let mut chart = chart_on(area, &title, 70).build_cartesian_2d(
                Scale::linear(0.0..end),
                Scale::linear((low - pad)..(high + pad)),
            )?;
            mesh(&mut chart)
                .x_desc("time [s]")
                .y_desc("velocity [m/s]")
                .draw()?;
            for ((_, axis), color) in axes.iter().zip(colors) {
                let points: Vec<(f64, f64)> = trajectory
                    .time_s
                    .iter()
                    .zip(&trajectory.velocity_m_s)
                    .map(|(t, v)| (*t, v[*axis]))
                    .collect();
                chart.draw_series(LineSeries::new(points, color.stroke_width(1)))?;
            }
        }
        let entries: Vec<(Swatch, String)> = axes
            .iter()
            .zip(colors)
            .map(|((name, _), color)| (Swatch::Line(color, Stroke::Solid), name.to_string()))
            .collect();
        legend(&legend_area, "GT velocity", &entries)
    })?;
    Ok(Ok(Drawn { caption, svg }))
}

/// The estimator × error-model series of the calibration table, in a stable order.
fn series_of(rows: &[CalibrationRow]) -> Vec<Series> {
    let mut series = crate::first_seen(rows.iter().map(|r| (r.estimator, r.error_model)));
    series.sort_by_key(|(estimator, model)| (*estimator as usize, model.map(|m| m as usize)));
    series
}

/// Mean RMSE against calibration window size, one panel per DVL, T_conv ringed.
fn calibration(run: &StoredRun) -> PlotResult<MaybeDrawn> {
    if run.calibration.is_empty() {
        return Ok(Err("calibration.parquet is empty".into()));
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
        let mut cut = false;
        for (area, dvl) in panels.iter().zip(&dvls) {
            cut |= calibration_panel(area, dvl, run, &series, &windows)?;
        }
        let mut entries = series_entries(&series);
        entries.push((Swatch::Ring, "T_conv".into()));
        if cut {
            entries.push((Swatch::Cut, "beyond the axis".into()));
        }
        legend(&legend_area, "estimator", &entries)
    })?;
    Ok(Ok(Drawn { caption, svg }))
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

/// One DVL's panel of the calibration figure: a line per series; says whether a value
/// was cut at the axis.
fn calibration_panel(
    area: &Area,
    dvl: &str,
    run: &StoredRun,
    series: &[Series],
    windows: &WindowAxis,
) -> PlotResult<bool> {
    let rows: Vec<&CalibrationRow> = run.calibration.iter().filter(|r| r.dvl == dvl).collect();
    let values: Vec<f64> = rows.iter().map(|r| r.rmse_cm_s).collect();
    let y = Scale::fit_values(&values, windows.count);
    let mut chart = chart_on(area, dvl, 70)
        .build_cartesian_2d(Scale::linear(windows.range.clone()), y.clone())?;
    mesh(&mut chart)
        .x_desc("calibration window [s]")
        .y_desc("mean RMSE [cm/s]")
        .draw()?;
    for &(estimator, model) in series {
        let look = series_look(estimator, model);
        let points: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.estimator == estimator && r.error_model == model)
            .map(|r| (r.window_s, y.shown(r.rmse_cm_s)))
            .collect();
        line(&mut chart, points.clone(), look.color, look.stroke)?;
        chart.draw_series(
            points
                .iter()
                .map(|&point| Circle::new(point, 3, look.color.filled())),
        )?;
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
    calibration_marks(&mut chart, &rows, &y)
}

/// Rings each T_conv of `rows` and marks each value beyond the axis `y`; says whether
/// one was.
fn calibration_marks(
    chart: &mut Chart<'_, '_, Scale, Scale>,
    rows: &[&CalibrationRow],
    y: &Scale,
) -> PlotResult<bool> {
    let mut cut = false;
    for row in rows {
        let at = (row.window_s, y.shown(row.rmse_cm_s));
        if row.is_t_conv {
            chart.draw_series(std::iter::once(Circle::new(at, 8, BLACK.stroke_width(2))))?;
        }
        if y.is_cut(row.rmse_cm_s) {
            let color = series_look(row.estimator, row.error_model).color;
            let edge = Edge::of_vertical(y, row.rmse_cm_s);
            cut_mark(chart, at, row.rmse_cm_s, color, edge)?;
            cut = true;
        }
    }
    Ok(cut)
}

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

/// The legend of the bar figures: the estimators, then `whisker` as a line when it is
/// not empty, then each line of `notes`.
fn bar_legend(
    area: &Area,
    estimators: &[EstimatorKind],
    whisker: &str,
    notes: &[&str],
) -> PlotResult {
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
fn rmse_first_window(run: &StoredRun) -> PlotResult<MaybeDrawn> {
    let Some(window) = run
        .calibration
        .iter()
        .map(|r| r.window_s)
        .min_by(f64::total_cmp)
    else {
        return Ok(Err("calibration.parquet is empty".into()));
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
        return Ok(Err(
            "the run holds no baseline or none of EM2, EM4, EM5".into()
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
        let mut cut = false;
        for (area, dvl) in panels.iter().zip(&dvls) {
            let bars = first_window_bars(run, dvl, window, &models, &estimators);
            cut |= bar_panel(area, dvl, &groups, &bars, "RMSE [cm/s]", None, true)?;
        }
        let mut shown = vec![EstimatorKind::Baseline];
        shown.extend(&estimators);
        let notes: &[&str] = if cut {
            &[
                "bars above the axis are cut;",
                "their value is written in white",
            ]
        } else {
            &[]
        };
        bar_legend(&legend_area, &shown, "± std over runs", notes)
    })?;
    Ok(Ok(Drawn { caption, svg }))
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
fn improvement_em5(run: &StoredRun) -> PlotResult<MaybeDrawn> {
    let rows: Vec<_> = run
        .evaluation
        .iter()
        .filter(|r| r.error_model == Some(ErrorModel::Em5) && r.improvement_pct.is_some())
        .collect();
    if rows.is_empty() {
        return Ok(Err(
            "the run holds no EM5 estimator with a baseline to compare".into(),
        ));
    }
    let trajectories = crate::first_seen(run.evaluation.iter().map(|r| r.trajectory.clone()));
    let estimators: Vec<EstimatorKind> = [EstimatorKind::LeastSquares, EstimatorKind::Dcnet]
        .into_iter()
        .filter(|e| rows.iter().any(|r| r.estimator == *e))
        .collect();
    let dvls = run.dvls();
    let caption = "Improvement in RMSE over the baseline with EM5, per test trajectory".to_string();
    let width = 520 * dvls.len() as u32 + LEGEND_WIDTH;
    let svg = draw_svg((width, 560), |root| {
        let (panels, legend_area) = panels_and_legend(root, &caption, width, dvls.len())?;
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
        }
        bar_legend(
            &legend_area,
            &estimators,
            "",
            &[
                "bars below -100 % are cut;",
                "their value is written in white",
            ],
        )
    })?;
    Ok(Ok(Drawn { caption, svg }))
}

/// The distribution over runs of each estimator's RMSE at its T_conv, one panel per
/// DVL, the floor's mean drawn across.
fn monte_carlo_spread(run: &StoredRun) -> PlotResult<MaybeDrawn> {
    // The bound is computed, not run: it has no runs to spread.
    let mut series = series_of(&run.calibration);
    series.retain(|(estimator, _)| *estimator != EstimatorKind::Bound);
    if series.is_empty() {
        return Ok(Err("calibration.parquet is empty".into()));
    }
    let dvls = run.dvls();
    // The first series on top.
    let names: Vec<String> = series
        .iter()
        .rev()
        .map(|&(e, m)| series_look(e, m).label)
        .collect();
    let caption = format!(
        "RMSE on {} at T_conv over {} Monte Carlo runs (box: quartiles, whiskers: 1.5 IQR)",
        calibration_name(run),
        run.spec.calibration.monte_carlo_runs
    );
    let width = 560 * dvls.len() as u32;
    let height = 140 + 34 * series.len() as u32;
    let svg = draw_svg((width, height), |root| {
        let root = root.titled(&caption, font(TITLE_SIZE))?;
        for (area, dvl) in root.split_evenly((1, dvls.len())).iter().zip(&dvls) {
            let samples = t_conv_samples(run, dvl, &series);
            spread_panel(area, dvl, &series, &names, &samples)?;
        }
        Ok(())
    })?;
    Ok(Ok(Drawn { caption, svg }))
}

/// Each series' RMSE on `dvl` at its T_conv, one value per Monte Carlo run.
fn t_conv_samples(run: &StoredRun, dvl: &str, series: &[Series]) -> Vec<Vec<f64>> {
    series
        .iter()
        .map(|&(estimator, model)| {
            let t_conv = run.calibration.iter().find(|r| {
                r.dvl == dvl && r.estimator == estimator && r.error_model == model && r.is_t_conv
            });
            run.runs
                .iter()
                .filter(|r| {
                    r.phase == Phase::Calibration
                        && r.dvl == dvl
                        && r.estimator == estimator
                        && r.error_model == model
                        && Some(r.window_s) == t_conv.map(|t| t.window_s)
                })
                .map(|r| r.rmse_cm_s)
                .collect()
        })
        .collect()
}

/// One DVL's panel of the spread figure: a box per series of `samples`, the first on
/// top, named `names` from the bottom, and the floor's mean drawn across.
fn spread_panel(
    area: &Area,
    dvl: &str,
    series: &[Series],
    names: &[String],
    samples: &[Vec<f64>],
) -> PlotResult {
    let values: Vec<f64> = samples.iter().flatten().copied().collect();
    let x = Scale::fit_values(&values, 1);
    let mut chart = chart_on(area, dvl, 150)
        .build_cartesian_2d(x.clone(), -0.5..(series.len() as f64 - 0.5))?;
    mesh(&mut chart)
        .disable_y_mesh()
        .y_labels(series.len() + 1)
        .y_label_formatter(&|y| category(names, *y))
        .x_desc("RMSE at T_conv [cm/s]")
        .draw()?;
    for (i, (values, &(estimator, model))) in samples.iter().zip(series).enumerate() {
        if values.is_empty() {
            continue;
        }
        let color = series_look(estimator, model).color;
        let y = (series.len() - 1 - i) as f64;
        spread_box(&mut chart, &x, values, y, color)?;
        if estimator == EstimatorKind::Floor {
            let mean = values.iter().sum::<f64>() / values.len() as f64;
            line(
                &mut chart,
                vec![(mean, -0.5), (mean, series.len() as f64 - 0.5)],
                GREY,
                Stroke::Dotted,
            )?;
        }
    }
    Ok(())
}

/// The box plot of `values` at height `y`: box, median, whiskers, the values beyond
/// them as dots, and one mark at each end of the axis `x` for the values beyond it.
fn spread_box(
    chart: &mut Chart<'_, '_, Scale, RangedCoordf64>,
    x: &Scale,
    values: &[f64],
    y: f64,
    color: RGBColor,
) -> PlotResult {
    let [low, q1, median, q3, high] = box_stats(values).map(|v| x.shown(v));
    chart.draw_series([
        Rectangle::new([(q1, y - 0.3), (q3, y + 0.3)], color.mix(0.25).filled()),
        Rectangle::new([(q1, y - 0.3), (q3, y + 0.3)], color.stroke_width(1)),
    ])?;
    chart.draw_series([
        PathElement::new(
            vec![(median, y - 0.3), (median, y + 0.3)],
            color.stroke_width(3),
        ),
        PathElement::new(vec![(low, y), (q1, y)], color.stroke_width(1)),
        PathElement::new(vec![(q3, y), (high, y)], color.stroke_width(1)),
    ])?;
    chart.draw_series(
        values
            .iter()
            .filter(|v| (**v < low || **v > high) && !x.is_cut(**v))
            .map(|v| Circle::new((*v, y), 2, color.filled())),
    )?;
    // One mark an end: the value furthest beyond it.
    let below = values
        .iter()
        .copied()
        .filter(|v| x.is_below(*v))
        .reduce(f64::min);
    let above = values
        .iter()
        .copied()
        .filter(|v| x.is_cut(*v) && !x.is_below(*v));
    for value in below.into_iter().chain(above.reduce(f64::max)) {
        let at = (x.shown(value), y);
        cut_mark(chart, at, value, color, Edge::of_horizontal(x, value))?;
    }
    Ok(())
}

/// Training and validation loss per epoch of each error model (and replicate, each in
/// its model's colour), log scale.
fn training_loss(run: &StoredRun) -> PlotResult<MaybeDrawn> {
    if run.training.is_empty() {
        return Ok(Err(
            "the run trained no DCNet (training.parquet is empty)".into()
        ));
    }
    let mut models: Vec<(ErrorModel, Option<usize>)> = run
        .training
        .iter()
        .map(|e| (e.error_model, e.replicate))
        .collect();
    models.dedup();
    let epochs = run
        .training
        .iter()
        .map(|e| e.record.epoch)
        .max()
        .unwrap_or(1) as f64;
    let caption = "DCNet closed-loop loss per epoch: training solid, validation dashed".to_string();
    let width = 1000;
    let svg = draw_svg((width, 620), |root| {
        let root = root.titled(&caption, font(TITLE_SIZE))?;
        let (area, legend_area) = root.split_horizontally(width - LEGEND_WIDTH);
        let losses = run
            .training
            .iter()
            .flat_map(|e| [e.record.train_loss, e.record.validation_loss])
            .filter(|v| v.is_finite());
        let (low, high) = losses.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
        let mut chart = chart_on(&area, "", 80)
            .build_cartesian_2d(Scale::linear(0.0..(epochs + 1.0)), Scale::fit(low, high))?;
        mesh(&mut chart)
            .x_desc("epoch")
            .y_desc("loss [(cm/s)²]")
            .draw()?;
        let mut entries = Vec::new();
        for &(model, replicate) in &models {
            let look = series_look(EstimatorKind::Dcnet, Some(model));
            let epochs: Vec<_> = run
                .training
                .iter()
                .filter(|e| e.error_model == model && e.replicate == replicate)
                .collect();
            let train = epochs
                .iter()
                .map(|e| (e.record.epoch as f64, e.record.train_loss))
                .collect();
            let validation = epochs
                .iter()
                .map(|e| (e.record.epoch as f64, e.record.validation_loss))
                .collect();
            line(&mut chart, train, look.color, Stroke::Solid)?;
            line(&mut chart, validation, look.color, Stroke::Dashed)?;
            chart.draw_series(epochs.iter().filter(|e| e.is_best).map(|e| {
                Circle::new(
                    (e.record.epoch as f64, e.record.validation_loss),
                    5,
                    look.color.filled(),
                )
            }))?;
            if replicate.is_some_and(|r| r > 0) {
                continue;
            }
            entries.push((
                Swatch::Line(look.color, Stroke::Solid),
                format!("{model} training"),
            ));
            entries.push((
                Swatch::Line(look.color, Stroke::Dashed),
                format!("{model} validation"),
            ));
        }
        entries.push((Swatch::Dot(BLACK), "best validation epoch".into()));
        legend(&legend_area, "error model", &entries)
    })?;
    Ok(Ok(Drawn { caption, svg }))
}
