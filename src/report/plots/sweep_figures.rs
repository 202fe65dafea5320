//! The figures of a sweep: for each swept key, the chosen metric against the key's
//! values, one panel per DVL and one series per estimator and error model. The values
//! sit evenly spaced and labelled exactly (numbers in ascending order), as a sweep's few
//! values read best. Every point of the sweep is a dot; the line joins, at each value,
//! the mean over the points that share it (over the other swept keys' values). A sweep
//! over two or more keys adds [`super::sweep_parallel`]'s figure.

use super::draw::*;
use super::figures::{Drawn, MaybeDrawn, draw_svg};
use super::scale::Scale;
use crate::first_seen;
use crate::results::sweep::{StoredSweep, SweepRow, Swept};
use plotters::prelude::*;

/// What a sweep figure plots against the swept values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Metric {
    /// Mean RMSE over the test trajectories
    EvaluationRmse,
    /// Mean RMSE at T_conv on the calibration trajectory
    CalibrationRmse,
    /// The convergence window
    TConv,
    /// DCNet training wall time
    TrainingTime,
}

impl Metric {
    pub const ALL: [Metric; 4] = [
        Metric::EvaluationRmse,
        Metric::CalibrationRmse,
        Metric::TConv,
        Metric::TrainingTime,
    ];

    /// How the command line spells it.
    pub fn name(self) -> &'static str {
        match self {
            Metric::EvaluationRmse => "evaluation-rmse",
            Metric::CalibrationRmse => "calibration-rmse",
            Metric::TConv => "t-conv",
            Metric::TrainingTime => "training-time",
        }
    }

    /// What it is, in a sentence's words.
    pub fn description(self) -> &'static str {
        match self {
            Metric::EvaluationRmse => "Mean RMSE over the test trajectories",
            Metric::CalibrationRmse => "Mean RMSE at T_conv on the calibration trajectory",
            Metric::TConv => "The convergence window",
            Metric::TrainingTime => "DCNet training wall time",
        }
    }

    pub(super) fn of(self, row: &SweepRow) -> Option<f64> {
        match self {
            Metric::EvaluationRmse => Some(row.evaluation_rmse_cm_s),
            Metric::CalibrationRmse => Some(row.calibration_rmse_cm_s),
            Metric::TConv => Some(row.t_conv_s),
            Metric::TrainingTime => row.training_s,
        }
    }

    pub(super) fn axis(self) -> &'static str {
        match self {
            Metric::EvaluationRmse => "evaluation RMSE [cm/s]",
            Metric::CalibrationRmse => "calibration RMSE at T_conv [cm/s]",
            Metric::TConv => "T_conv [s]",
            Metric::TrainingTime => "training time [s]",
        }
    }
}

/// One figure per swept key, stem `sweep_<key>` with the key's dots as underscores,
/// and, over two or more keys, `sweep_parallel` ([`super::sweep_parallel`]).
pub fn all(sweep: &StoredSweep, metric: Metric) -> PlotResult<Vec<(String, MaybeDrawn)>> {
    let mut figures = sweep
        .index
        .swept
        .iter()
        .enumerate()
        .map(|(k, key)| {
            let stem = format!("sweep_{}", key.replace('.', "_"));
            Ok((stem, against(sweep, metric, k)?))
        })
        .collect::<PlotResult<Vec<_>>>()?;
    if sweep.index.swept.len() >= 2 {
        figures.push((
            "sweep_parallel".to_string(),
            super::sweep_parallel::parallel(sweep, metric)?,
        ));
    }
    Ok(figures)
}

/// The distinct values of swept key `k`, numbers in ascending order, texts in the
/// order they first appear, each with its label.
fn categories(rows: &[(&SweepRow, f64)], k: usize) -> Vec<(Swept, String)> {
    let mut values = first_seen(rows.iter().map(|(row, _)| row.values[k].clone()));
    if values.iter().all(|v| v.number().is_some()) {
        values.sort_by(|a, b| {
            a.number()
                .unwrap_or(0.0)
                .total_cmp(&b.number().unwrap_or(0.0))
        });
    }
    values
        .into_iter()
        .map(|value| {
            let label = value.to_string();
            (value, label)
        })
        .collect()
}

fn against(sweep: &StoredSweep, metric: Metric, k: usize) -> PlotResult<MaybeDrawn> {
    let key = &sweep.index.swept[k];
    let rows: Vec<(&SweepRow, f64)> = sweep
        .rows
        .iter()
        .filter_map(|r| metric.of(r).filter(|v| v.is_finite()).map(|v| (r, v)))
        .collect();
    if rows.is_empty() {
        return Ok(Err(format!(
            "sweep.parquet has no {} to plot",
            metric.axis()
        )));
    }
    let categories = categories(&rows, k);
    let labels: Vec<String> = categories.iter().map(|(_, label)| label.clone()).collect();
    let x_of = |row: &SweepRow| {
        categories
            .iter()
            .position(|(value, _)| *value == row.values[k])
            .unwrap_or(0) as f64
    };
    let dvls = first_seen(rows.iter().map(|(row, _)| row.dvl.as_str()));
    let series = first_seen(rows.iter().map(|(row, _)| (row.estimator, row.error_model)));
    let caption = if sweep.index.swept.len() == 1 {
        format!("{} against {key}", metric.axis())
    } else {
        format!(
            "{} against {key} (line: mean over the other swept values; dots: each point)",
            metric.axis()
        )
    };
    let width = 560 * dvls.len() as u32 + LEGEND_WIDTH;
    let svg = draw_svg((width, 620), |root| {
        let root = root.titled(&caption, font(TITLE_SIZE))?;
        let (panels, legend_area) = root.split_horizontally(width - LEGEND_WIDTH);
        for (area, dvl) in panels.split_evenly((1, dvls.len())).iter().zip(&dvls) {
            let on_panel: Vec<(&SweepRow, f64)> = rows
                .iter()
                .copied()
                .filter(|(r, _)| r.dvl == *dvl)
                .collect();
            // A far series may be cut: as many dots as there are points.
            let values: Vec<f64> = on_panel.iter().map(|(_, v)| *v).collect();
            let y = Scale::fit_values(&values, sweep.index.points.len());
            let mut chart = chart_on(area, dvl, 70)
                .build_cartesian_2d(-0.5..(labels.len() as f64 - 0.5), y.clone())?;
            mesh(&mut chart)
                .disable_x_mesh()
                .x_labels(labels.len() + 1)
                .x_desc(key.as_str())
                .y_desc(metric.axis())
                .x_label_formatter(&|v| category(&labels, *v))
                .draw()?;
            for &(estimator, model) in &series {
                let look = series_look(estimator, model);
                let dots: Vec<(f64, f64)> = on_panel
                    .iter()
                    .filter(|(r, _)| r.estimator == estimator && r.error_model == model)
                    .map(|(r, v)| (x_of(r), *v))
                    .collect();
                let means: Vec<(f64, f64)> = (0..labels.len())
                    .filter_map(|x| {
                        let at: Vec<f64> = dots
                            .iter()
                            .filter(|d| d.0 == x as f64)
                            .map(|d| d.1)
                            .collect();
                        (!at.is_empty())
                            .then(|| (x as f64, at.iter().sum::<f64>() / at.len() as f64))
                    })
                    .collect();
                let shown = |(x, v): (f64, f64)| (x, y.shown(v));
                line(
                    &mut chart,
                    means.into_iter().map(shown).collect(),
                    look.color,
                    look.stroke,
                )?;
                chart.draw_series(
                    dots.iter()
                        .map(|&point| Circle::new(shown(point), 4, look.color.filled())),
                )?;
                for &(x, value) in dots.iter().filter(|(_, v)| y.is_cut(*v)) {
                    let edge = Edge::of_vertical(&y, value);
                    cut_mark(&mut chart, shown((x, value)), value, look.color, edge)?;
                }
            }
        }
        let entries: Vec<(Swatch, String)> = series
            .iter()
            .map(|&(estimator, model)| {
                let look = series_look(estimator, model);
                (Swatch::Line(look.color, look.stroke), look.label)
            })
            .collect();
        legend(&legend_area, "estimator", &entries)
    })?;
    Ok(Ok(Drawn { caption, svg }))
}
