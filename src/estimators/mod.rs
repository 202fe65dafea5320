//! Calibration methods behind one trait. An [`Estimator`] takes a calibration window of
//! DVL and GNSS-RTK velocity and returns a [`Correction`] in the form of the measurement
//! model `v_dvl = (1 + k)·v + b`; every error model (EM1–EM5, docs/paper.md) is that form
//! with some terms fixed or tied. In: the spec, one DVL and the trained DCNets. Out: the
//! [`DvlEstimator`]s that [`set_up`] builds, one per (method, error model, replicate)
//! the spec [`requested`], which the protocol runs.

mod baseline;
mod beam_wls;
mod dcnet;
mod ensemble;
mod floor;
mod kalman;
mod least_squares;

pub use baseline::Baseline;
pub use beam_wls::BeamWls;
pub use dcnet::DcnetEstimator;
pub use ensemble::Ensemble;
pub use floor::Floor;
pub use kalman::KalmanFilter;
pub use least_squares::LeastSquares;

use crate::Vec3;
use crate::kalman::ScaleBiasModel;
use crate::model::Settings;
use crate::noise::BeamGeometry;
use crate::spec::{Dvl, Spec};
use crate::train::Trained;
use crate::vocab::{Correction, ErrorModel, EstimatorKind};

pub trait Estimator: Send + Sync {
    /// Estimates the terms from matching DVL and GNSS-RTK samples of one window.
    fn estimate(&self, dvl: &[Vec3], gnss: &[Vec3]) -> Correction;

    /// The terms estimated from the first n samples, for each n of `lengths`. A
    /// recursive method gives them all in one pass.
    fn estimate_prefixes(&self, dvl: &[Vec3], gnss: &[Vec3], lengths: &[usize]) -> Vec<Correction> {
        lengths
            .iter()
            .map(|&n| self.estimate(&dvl[..n], &gnss[..n]))
            .collect()
    }
}

/// A method as the protocol runs it on one DVL.
pub struct DvlEstimator {
    pub kind: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    /// Which DCNet replicate it runs, when `training.replicates` is above 1.
    pub replicate: Option<usize>,
    pub estimator: Box<dyn Estimator>,
}

/// A method the spec asks for: its kind, error model and DCNet replicate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Requested {
    pub kind: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    /// Which DCNet replicate, when `training.replicates` is above 1.
    pub replicate: Option<usize>,
}

/// Every method the spec asks for, in table order: the kinds as listed, each with every
/// error model when it takes one. With `training.replicates` above 1, DCNet runs once
/// per replicate and the ensemble of the replicates after them.
pub fn requested(spec: &Spec) -> Vec<Requested> {
    let replicates = spec.training.replicates;
    let mut requested = Vec::new();
    for &kind in &spec.kinds {
        if !kind.takes_error_model() {
            requested.push(Requested {
                kind,
                error_model: None,
                replicate: None,
            });
            continue;
        }
        for &model in &spec.error_models {
            let one = |kind, replicate| Requested {
                kind,
                error_model: Some(model),
                replicate,
            };
            if kind == EstimatorKind::Dcnet && replicates > 1 {
                requested.extend((0..replicates).map(|r| one(kind, Some(r))));
                requested.push(one(EstimatorKind::DcnetEnsemble, None));
            } else {
                requested.push(one(kind, None));
            }
        }
    }
    requested
}

/// Every method of [`requested`], set up for `dvl`. DCNet runs the models in `dcnets`,
/// those that trained; the ensemble needs every replicate of its error model.
pub fn set_up(spec: &Spec, dvl: &Dvl, dcnets: &[Trained]) -> Vec<DvlEstimator> {
    let geometry = BeamGeometry::janus_x(spec.beam_pitch_deg);
    let dcnet = |trained: &Trained| DcnetEstimator {
        model: trained.model.clone(),
        error_model: trained.error_model,
        window: spec.dataset.window_samples,
        settings: Settings::from(&spec.model),
        device: spec.training.backend.device(),
    };
    let kalman = |model| KalmanFilter::new(model, spec, dvl, &geometry);
    let mut entries = Vec::new();
    for Requested {
        kind,
        error_model,
        replicate,
    } in requested(spec)
    {
        let estimator: Box<dyn Estimator> = match (kind, error_model) {
            (EstimatorKind::Baseline, _) => Box::new(Baseline),
            (EstimatorKind::LeastSquares, Some(model)) => Box::new(LeastSquares(model)),
            (EstimatorKind::Dcnet, Some(model)) => {
                let Some(trained) = dcnets
                    .iter()
                    .find(|t| t.error_model == model && t.replicate == replicate.unwrap_or(0))
                else {
                    continue;
                };
                Box::new(dcnet(trained))
            }
            (EstimatorKind::DcnetEnsemble, Some(model)) => {
                let members: Vec<Box<dyn Estimator>> = dcnets
                    .iter()
                    .filter(|t| t.error_model == model)
                    .map(|t| Box::new(dcnet(t)) as Box<dyn Estimator>)
                    .collect();
                if members.len() < spec.training.replicates {
                    continue;
                }
                Box::new(Ensemble { members })
            }
            (
                EstimatorKind::LeastSquares
                | EstimatorKind::Kalman
                | EstimatorKind::Dcnet
                | EstimatorKind::DcnetEnsemble,
                None,
            ) => {
                unreachable!("{kind} always has an error model")
            }
            (EstimatorKind::Kalman, Some(model)) => Box::new(kalman(ScaleBiasModel::Paper(model))),
            (EstimatorKind::KalmanBeam, _) => Box::new(kalman(ScaleBiasModel::Beam)),
            (EstimatorKind::BeamWls, _) => {
                Box::new(BeamWls::new(&dvl.errors, &geometry, spec.gnss_noise_m_s))
            }
            (EstimatorKind::Floor, _) => Box::new(Floor::new(&dvl.errors, &geometry)),
            (EstimatorKind::Bound, _) => unreachable!("the bound is computed, not run"),
        };
        entries.push(DvlEstimator {
            kind,
            error_model,
            replicate,
            estimator,
        });
    }
    entries
}
