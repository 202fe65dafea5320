//! The DCNet ensemble: the `training.replicates` DCNets of one error model, each
//! estimating the terms of the calibration window as [`DcnetEstimator`] does, and the
//! mean of their terms (scale and bias, term by term) as the estimate.

use super::{DcnetEstimator, Estimator};
use crate::Vec3;
use crate::vocab::Correction;

pub struct Ensemble {
    pub members: Vec<DcnetEstimator>,
}

impl Estimator for Ensemble {
    fn estimate(&self, dvl: &[Vec3], gnss: &[Vec3]) -> Correction {
        let corrections: Vec<Correction> = self
            .members
            .iter()
            .map(|member| member.estimate(dvl, gnss))
            .collect();
        Correction::mean(&corrections)
    }
}
