//! The Monte Carlo spread figure: the distribution over runs of each estimator's RMSE
//! at its T_conv as a box plot, one panel per DVL, the floor's mean drawn across. In: a
//! [`StoredRun`]'s calibration table and its per-run rows. Out: the figure, or why the
//! calibration table is empty.

use super::{calibration_name, series_of};
use crate::report::kit::plots::canvas::{Drawn, Outcome, draw_svg};
use crate::report::kit::plots::draw::*;
use crate::report::kit::plots::scale::Scale;
use crate::results::read::StoredRun;
use crate::vocab::{EstimatorKind, Phase};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

/// The distribution over runs of each estimator's RMSE at its T_conv, one panel per
/// DVL, the floor's mean drawn across.
pub fn monte_carlo_spread(run: &StoredRun) -> PlotResult<Outcome> {
    // The bound is computed, not run: it has no runs to spread.
    let mut series = series_of(&run.calibration);
    series.retain(|(estimator, _)| *estimator != EstimatorKind::Bound);
    if series.is_empty() {
        return Ok(Outcome::NotApplicable(
            "calibration.parquet is empty".into(),
        ));
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
    Ok(Outcome::Drawn(Drawn { caption, svg }))
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
    let mut chart = chart_on(area, dvl, 175)
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
