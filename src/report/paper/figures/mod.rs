//! The seven figures of a paper run, each drawn from a [`StoredRun`] into SVG text
//! with the kit's drawing pieces, one file per figure or family of figures:
//! [`velocity`], [`calibration`], the bar figures ([`bars`]: RMSE at the first window,
//! improvement with EM5), the Monte Carlo [`spread`], the [`training_loss`] and the
//! Kalman filter's terms against time ([`kalman_terms`], on the kit's term panels,
//! which the installation study draws too). A figure whose data the run does not hold
//! (no DCNet, no baseline, no EM5) is [`Outcome::NotApplicable`], with why; `run` calls
//! [`write_all`] at its end and `plot` calls it on a stored folder. To add a figure,
//! write its file here and list it in [`all`]. In: a [`StoredRun`]. Out: the figure
//! files, and each figure's caption or why it is absent.

pub mod bars;
pub mod calibration;
pub mod kalman_terms;
pub mod spread;
pub mod training_loss;
pub mod velocity;

use crate::evaluate::CalibrationRow;
use crate::report::kit::plots::canvas::Outcome;
use crate::report::kit::plots::draw::{PlotResult, Series};
use crate::report::kit::plots::{Format, PlotError, Written, render, write_figures};
use crate::results::read::StoredRun;
use std::path::Path;

/// Draws every figure of `run` into `folder`, each file written atomically.
pub fn write_all(
    run: &StoredRun,
    folder: &Path,
    format: Format,
) -> Result<Vec<Written>, PlotError> {
    render::register_font();
    let drawn = all(run).map_err(|source| PlotError::Draw {
        what: "run's",
        source,
    })?;
    write_figures(drawn, folder, format)
}

/// Every figure of a run, in the order the report shows them.
pub fn all(run: &StoredRun) -> PlotResult<Vec<(String, Outcome)>> {
    let figures: [(&str, Outcome); 7] = [
        ("velocity", velocity::velocity(run)?),
        ("calibration", calibration::calibration(run)?),
        ("rmse_first_window", bars::rmse_first_window(run)?),
        ("improvement_em5", bars::improvement_em5(run)?),
        ("monte_carlo_spread", spread::monte_carlo_spread(run)?),
        ("training_loss", training_loss::training_loss(run)?),
        ("kalman_terms", kalman_terms::kalman_terms(run)?),
    ];
    Ok(figures
        .into_iter()
        .map(|(stem, outcome)| (stem.to_string(), outcome))
        .collect())
}

/// The name of the run's calibration trajectory.
fn calibration_name(run: &StoredRun) -> &str {
    &run.spec.calibration.trajectory
}

/// The estimator × error-model series of the calibration table, in a stable order.
fn series_of(rows: &[CalibrationRow]) -> Vec<Series> {
    let mut series = crate::first_seen(rows.iter().map(|r| (r.estimator, r.error_model)));
    series.sort_by_key(|(estimator, model)| (*estimator as usize, model.map(|m| m as usize)));
    series
}
