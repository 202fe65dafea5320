//! The Kalman filters' terms against time: on the calibration trajectory as the first
//! Monte Carlo run of the protocol measures it, each filter's estimate of each term and
//! its standard deviation after every sample, beside the true value (where the model
//! can hold the simulated DVL's terms) and the bound's standard deviation for a batch
//! of that many samples. In: the spec and the trajectories. Out: one row per DVL,
//! filter, sample and term.

use crate::data::Trajectory;
use crate::estimators::KalmanFilter;
use crate::kalman::scale_bias::{ScaleBiasModel, bound_history};
use crate::noise::{BeamGeometry, measure_trajectory};
use crate::rng::task_rng;
use crate::spec::Spec;
use crate::vocab::{ErrorModel, EstimatorKind};

/// One term of one filter after one sample.
#[derive(Debug, Clone, PartialEq)]
pub struct TermInTimeRow {
    pub dvl: String,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    /// The time of the sample from the start of the calibration trajectory, s.
    pub time_s: f64,
    /// As `ScaleBiasModel::term_names` names it: a scale (a fraction) or a bias (m/s).
    pub term: String,
    pub estimate: f64,
    pub std: f64,
    /// The simulated DVL's term, where the model holds it.
    pub true_value: Option<f64>,
    /// The bound's standard deviation from a batch of the samples so far.
    pub bound_std: f64,
}

/// The filters the spec runs, as (kind, error model, model).
fn filters(spec: &Spec) -> Vec<(EstimatorKind, Option<ErrorModel>, ScaleBiasModel)> {
    let mut filters = Vec::new();
    for &kind in &spec.kinds {
        match kind {
            EstimatorKind::Kalman => filters.extend(
                spec.error_models
                    .iter()
                    .map(|&m| (kind, Some(m), ScaleBiasModel::Paper(m))),
            ),
            EstimatorKind::KalmanBeam => filters.push((kind, None, ScaleBiasModel::Beam)),
            _ => {}
        }
    }
    filters
}

/// Every filter's terms against time on every DVL.
pub fn terms_in_time(spec: &Spec, trajectories: &[Trajectory]) -> Vec<TermInTimeRow> {
    let geometry = BeamGeometry::janus_x(spec.beam_pitch_deg);
    let calibration = &trajectories[spec.calibration.trajectory];
    let mut rows = Vec::new();
    for dvl in &spec.dvls {
        // The measurements of the protocol's first run.
        let mut rng = task_rng(
            spec.seed,
            &[&"monte_carlo", &dvl.name, &0usize, &calibration.name],
        );
        let measured = measure_trajectory(
            &geometry,
            &calibration.ground_truth,
            &dvl.errors,
            spec.gnss_noise_m_s,
            &mut rng,
        );
        for (kind, error_model, model) in filters(spec) {
            let filter = KalmanFilter::new(model, spec, dvl, &geometry);
            let history = filter.history(&measured.dvl, &measured.gnss);
            let bound = bound_history(model, &calibration.ground_truth, filter.noise());
            let truth = model.true_terms(&dvl.errors, &geometry);
            let names = model.term_names();
            for (i, ((estimate, std), bound)) in history.iter().zip(&bound).enumerate() {
                for (t, name) in names.iter().enumerate() {
                    rows.push(TermInTimeRow {
                        dvl: dvl.name.clone(),
                        estimator: kind,
                        error_model,
                        time_s: (i + 1) as f64 / spec.sample_rate_hz,
                        term: name.to_string(),
                        estimate: estimate[t],
                        std: std[t],
                        true_value: truth.as_ref().map(|terms| terms[t]),
                        bound_std: bound[t],
                    });
                }
            }
        }
    }
    rows
}
