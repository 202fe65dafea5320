//! The seven figures of a run, each drawn from a [`StoredRun`] into SVG text, one file
//! per figure or family of figures: [`velocity`], [`calibration`], the bar figures
//! ([`bars`]: RMSE at the first window, improvement with EM5), the Monte Carlo
//! [`spread`], the [`training_loss`] and the Kalman filter's terms against time
//! ([`terms_in_time`], whose panels the installation study draws too). A figure whose data the run does not hold (no
//! DCNet, no baseline, no EM5) is [`Outcome::NotApplicable`], with why. To add a
//! figure, write its file here and list it in [`all`].

pub mod bars;
pub mod calibration;
pub mod installation_matrix;
pub mod installation_residual;
pub mod installation_sweep;
pub mod installation_windows;
pub mod spread;
pub mod terms_in_time;
pub mod training_loss;
pub mod velocity;

use super::canvas::Outcome;
use super::draw::{PlotResult, Series};
use crate::evaluate::CalibrationRow;
use crate::results::read::StoredRun;

/// Every figure of a run, in the order the report shows them.
pub fn all(run: &StoredRun) -> PlotResult<Vec<(String, Outcome)>> {
    let figures: [(&str, Outcome); 7] = [
        ("velocity", velocity::velocity(run)?),
        ("calibration", calibration::calibration(run)?),
        ("rmse_first_window", bars::rmse_first_window(run)?),
        ("improvement_em5", bars::improvement_em5(run)?),
        ("monte_carlo_spread", spread::monte_carlo_spread(run)?),
        ("training_loss", training_loss::training_loss(run)?),
        ("kalman_terms", terms_in_time::kalman_terms(run)?),
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
