//! The training-loss figure: DCNet's training and validation loss per epoch, one
//! colour per error model (replicates in their model's colour), the best validation
//! epoch dotted. In: a [`StoredRun`]'s training table. Out: the figure, or why the run
//! trained no DCNet.

use crate::report::kit::plots::canvas::{Drawn, Outcome, draw_svg};
use crate::report::kit::plots::draw::*;
use crate::report::kit::plots::scale::Scale;
use crate::results::read::StoredRun;
use crate::vocab::EstimatorKind;
use plotters::prelude::*;

/// Training and validation loss per epoch of each error model (and replicate, each in
/// its model's colour), log scale.
pub fn training_loss(run: &StoredRun) -> PlotResult<Outcome> {
    if run.training.is_empty() {
        return Ok(Outcome::NotApplicable(
            "the run trained no DCNet (training.parquet is empty)".into(),
        ));
    }
    let models = run.trained_models();
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
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}
