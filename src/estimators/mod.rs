//! Calibration methods behind one trait. An [`Estimator`] takes a calibration window of
//! DVL and GNSS-RTK velocity and returns a [`Correction`] in the form of the measurement
//! model `v_dvl = (1 + k)·v + b`; every error model (EM1–EM5, PAPER-NOTES) is that form
//! with some terms fixed or tied. In: the spec, one DVL and the trained DCNets. Out: the
//! [`DvlEstimator`]s that [`set_up`] builds, one per (method, error model) the spec
//! [`requested`], which the protocol runs.

mod baseline;
mod beam_wls;
mod dcnet;
mod floor;
mod least_squares;

pub use baseline::Baseline;
pub use beam_wls::BeamWls;
pub use dcnet::DcnetEstimator;
pub use floor::Floor;
pub use least_squares::LeastSquares;

use crate::Vec3;
use crate::model::Settings;
use crate::noise::BeamGeometry;
use crate::spec::{Dvl, Spec};
use crate::train::Trained;
use crate::vocab::{Correction, ErrorModel, EstimatorKind};

pub trait Estimator: Send + Sync {
    /// Estimates the terms from matching DVL and GNSS-RTK samples of one window.
    fn estimate(&self, dvl: &[Vec3], gnss: &[Vec3]) -> Correction;
}

/// A method as the protocol runs it on one DVL.
pub struct DvlEstimator {
    pub kind: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    pub estimator: Box<dyn Estimator>,
}

/// Every (estimator kind, error model) the spec asks for, in table order: the kinds as
/// listed, each with every error model when it takes one.
pub fn requested(spec: &Spec) -> Vec<(EstimatorKind, Option<ErrorModel>)> {
    let mut requested = Vec::new();
    for &kind in &spec.kinds {
        if kind.takes_error_model() {
            requested.extend(spec.error_models.iter().map(|&m| (kind, Some(m))));
        } else {
            requested.push((kind, None));
        }
    }
    requested
}

/// Every (estimator kind, error model) of [`requested`], set up for `dvl`. DCNet runs for
/// the error models in `dcnets`, the models that trained.
pub fn set_up(spec: &Spec, dvl: &Dvl, dcnets: &[Trained]) -> Vec<DvlEstimator> {
    let geometry = BeamGeometry::janus_x(spec.beam_pitch_deg);
    let mut entries = Vec::new();
    for (kind, error_model) in requested(spec) {
        let estimator: Box<dyn Estimator> = match (kind, error_model) {
            (EstimatorKind::Baseline, _) => Box::new(Baseline),
            (EstimatorKind::LeastSquares, Some(model)) => Box::new(LeastSquares(model)),
            (EstimatorKind::Dcnet, Some(model)) => {
                let Some(trained) = dcnets.iter().find(|t| t.error_model == model) else {
                    continue;
                };
                Box::new(DcnetEstimator {
                    model: trained.model.clone(),
                    error_model: model,
                    window: spec.dataset.window_samples,
                    settings: Settings::from(&spec.model),
                    device: spec.training.backend.device(),
                })
            }
            (EstimatorKind::LeastSquares | EstimatorKind::Dcnet, None) => {
                unreachable!("{kind} always has an error model")
            }
            (EstimatorKind::BeamWls, _) => {
                Box::new(BeamWls::new(&dvl.errors, &geometry, spec.gnss_noise_m_s))
            }
            (EstimatorKind::Floor, _) => Box::new(Floor::new(&dvl.errors, &geometry)),
            (EstimatorKind::Bound, _) => unreachable!("the bound is computed, not run"),
        };
        entries.push(DvlEstimator {
            kind,
            error_model,
            estimator,
        });
    }
    entries
}
