//! The calibration figure: mean RMSE against the calibration window, one panel per
//! DVL, one line per estimator and error model, each T_conv ringed. In: a
//! [`StoredRun`]'s calibration table. Out: the figure, or why the table is empty.

use super::{calibration_name, series_of};
use crate::evaluate::CalibrationRow;
use crate::report::plots::canvas::{Drawn, Outcome, draw_svg};
use crate::report::plots::draw::*;
use crate::report::plots::scale::Scale;
use crate::results::read::StoredRun;
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
