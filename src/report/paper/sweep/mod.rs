//! The figures of a sweep of paper runs, drawn from its `sweep.parquet`: for each swept
//! key, the chosen [`Metric`] against the key's values, one panel per DVL and one
//! series per estimator and error model. The values sit evenly spaced and labelled
//! exactly (numbers in ascending order), as a sweep's few values read best. Every point
//! of the sweep is a dot; the line joins, at each value, the mean over the points that
//! share it (over the other swept keys' values). A sweep over two or more keys adds
//! [`parallel`]'s figure. In: a stored sweep and a metric. Out: the figure files
//! ([`write_sweep`]), each with its caption or why it is absent.

pub mod metric;
pub mod parallel;

pub use metric::Metric;

use crate::first_seen;
use crate::report::kit::plots::canvas::{Drawn, Outcome, draw_svg};
use crate::report::kit::plots::draw::*;
use crate::report::kit::plots::scale::Scale;
use crate::report::kit::plots::{Format, PlotError, Written, render, write_figures};
use crate::results::sweep::{StoredSweep, SweepRow, Swept};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::path::Path;

/// Draws a sweep's figures, `metric` against each swept key, into `folder`.
pub fn write_sweep(
    sweep: &StoredSweep,
    metric: Metric,
    folder: &Path,
    format: Format,
) -> Result<Vec<Written>, PlotError> {
    render::register_font();
    let drawn = all(sweep, metric).map_err(|source| PlotError::Draw {
        what: "sweep's",
        source,
    })?;
    write_figures(drawn, folder, format)
}

/// One figure per swept key, stem `sweep_<key>` with the key's dots as underscores,
/// and, over two or more keys, `sweep_parallel` ([`parallel`]).
pub fn all(sweep: &StoredSweep, metric: Metric) -> PlotResult<Vec<(String, Outcome)>> {
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
            parallel::parallel(sweep, metric)?,
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

/// The metric against swept key `k`, one panel per DVL and one series per estimator
/// and error model.
fn against(sweep: &StoredSweep, metric: Metric, k: usize) -> PlotResult<Outcome> {
    let key = &sweep.index.swept[k];
    let rows: Vec<(&SweepRow, f64)> = sweep
        .rows
        .iter()
        .filter_map(|r| metric.of(r).filter(|v| v.is_finite()).map(|v| (r, v)))
        .collect();
    if rows.is_empty() {
        return Ok(Outcome::NotApplicable(format!(
            "sweep.parquet has no {} to plot",
            metric.axis()
        )));
    }
    let categories = categories(&rows, k);
    let dvls = first_seen(rows.iter().map(|(row, _)| row.dvl.as_str()));
    let figure = MetricAgainstKey {
        key,
        metric,
        key_index: k,
        labels: categories.iter().map(|(_, label)| label.clone()).collect(),
        categories,
        series: first_seen(rows.iter().map(|(row, _)| (row.estimator, row.error_model))),
        points: sweep.index.points.len(),
        rows,
    };
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
        let (panels, legend_area) = panels_and_legend(root, &caption, width, dvls.len())?;
        for (area, dvl) in panels.iter().zip(&dvls) {
            figure.panel(area, dvl)?;
        }
        legend(&legend_area, "estimator", &series_entries(&figure.series))
    })?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}

/// What the figure of the metric against one swept key draws from.
struct MetricAgainstKey<'a> {
    /// The swept key.
    key: &'a str,
    metric: Metric,
    /// The key's index among the swept keys.
    key_index: usize,
    /// The rows with a finite metric, each with its value.
    rows: Vec<(&'a SweepRow, f64)>,
    /// The key's values on the x axis, each with its label.
    categories: Vec<(Swept, String)>,
    labels: Vec<String>,
    series: Vec<Series>,
    /// How many points the sweep has.
    points: usize,
}

impl MetricAgainstKey<'_> {
    /// Where `row`'s value of the key lies on the x axis.
    fn x_of(&self, row: &SweepRow) -> f64 {
        self.categories
            .iter()
            .position(|(value, _)| *value == row.values[self.key_index])
            .unwrap_or(0) as f64
    }

    /// The panel of `dvl`: each series' dots and the line through their means.
    fn panel(&self, area: &Area, dvl: &str) -> PlotResult {
        let on_panel: Vec<(&SweepRow, f64)> = self
            .rows
            .iter()
            .copied()
            .filter(|(r, _)| r.dvl == *dvl)
            .collect();
        // A far series may be cut: as many dots as there are points.
        let values: Vec<f64> = on_panel.iter().map(|(_, v)| *v).collect();
        let y = Scale::fit_values(&values, self.points);
        let labels = &self.labels;
        let mut chart = chart_on(area, dvl, 70)
            .build_cartesian_2d(-0.5..(labels.len() as f64 - 0.5), y.clone())?;
        mesh(&mut chart)
            .disable_x_mesh()
            .x_labels(labels.len() + 1)
            .x_desc(self.key)
            .y_desc(self.metric.axis())
            .x_label_formatter(&|v| category(labels, *v))
            .draw()?;
        for &(estimator, model) in &self.series {
            let dots: Vec<(f64, f64)> = on_panel
                .iter()
                .filter(|(r, _)| r.estimator == estimator && r.error_model == model)
                .map(|(r, v)| (self.x_of(r), *v))
                .collect();
            let means = means_at(&dots, labels.len());
            series_dots(&mut chart, &y, &dots, means, series_look(estimator, model))?;
        }
        Ok(())
    }
}

/// At each of the `count` x positions that has dots, the mean of their values.
fn means_at(dots: &[(f64, f64)], count: usize) -> Vec<(f64, f64)> {
    (0..count)
        .filter_map(|x| {
            let at: Vec<f64> = dots
                .iter()
                .filter(|d| d.0 == x as f64)
                .map(|d| d.1)
                .collect();
            (!at.is_empty()).then(|| (x as f64, at.iter().sum::<f64>() / at.len() as f64))
        })
        .collect()
}

/// One series on a panel with the value axis `y`: the line through `means`, the
/// `dots`, and a mark for each dot beyond the axis.
fn series_dots(
    chart: &mut Chart<'_, '_, RangedCoordf64, Scale>,
    y: &Scale,
    dots: &[(f64, f64)],
    means: Vec<(f64, f64)>,
    look: Look,
) -> PlotResult {
    let shown = |(x, v): (f64, f64)| (x, y.shown(v));
    line(
        chart,
        means.into_iter().map(shown).collect(),
        look.color,
        look.stroke,
    )?;
    chart.draw_series(
        dots.iter()
            .map(|&point| Circle::new(shown(point), 4, look.color.filled())),
    )?;
    for &(x, value) in dots.iter().filter(|(_, v)| y.is_cut(*v)) {
        let edge = Edge::of_vertical(y, value);
        cut_mark(chart, shown((x, value)), value, look.color, edge)?;
    }
    Ok(())
}
