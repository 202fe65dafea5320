//! The Kalman filter as a calibration method: the filter of `kalman` run over the
//! calibration window sample by sample, its last estimate the terms. Of an error
//! model's terms (`kalman`, one per error model) or of the beam model's scale and bias
//! (`kalman_beam`); each axis weighted by its noise, the DVL's through the beam
//! geometry plus the GNSS-RTK's, as the spec states them. One pass gives the terms
//! after every prefix of the window, which is how the calibration time is measured.

use super::Estimator;
use crate::Vec3;
use crate::kalman::Prior;
use crate::kalman::scale_bias::{ScaleBiasModel, axis_noise, run};
use crate::noise::BeamGeometry;
use crate::spec::{Dvl, Spec};
use crate::vocab::Correction;

pub struct KalmanFilter {
    pub model: ScaleBiasModel,
    prior: Prior,
    /// The variance per axis of `d − g`, m²/s².
    noise: Vec3,
    sample_period_s: f64,
}

impl KalmanFilter {
    /// The filter of `model` for `dvl`, with the spec's prior, random walk, GNSS-RTK
    /// noise and sample rate.
    pub fn new(model: ScaleBiasModel, spec: &Spec, dvl: &Dvl, geometry: &BeamGeometry) -> Self {
        KalmanFilter {
            model,
            prior: model.prior(spec.kalman.prior, spec.kalman.random_walk),
            noise: axis_noise(&dvl.errors, geometry, spec.gnss_noise_m_s),
            sample_period_s: 1.0 / spec.sample_rate_hz,
        }
    }

    /// The noise variance per axis of `d − g` the filter weighs the axes by, m²/s².
    pub fn noise(&self) -> Vec3 {
        self.noise
    }

    /// The estimate and the standard deviations of the terms after every sample.
    pub fn history(&self, dvl: &[Vec3], gnss: &[Vec3]) -> Vec<(Vec<f64>, Vec<f64>)> {
        run(
            self.model,
            &self.prior,
            self.noise,
            self.sample_period_s,
            dvl,
            gnss,
        )
    }
}

impl Estimator for KalmanFilter {
    fn estimate(&self, dvl: &[Vec3], gnss: &[Vec3]) -> Correction {
        match self.history(dvl, gnss).last() {
            Some((estimate, _)) => self.model.correction(estimate),
            None => Correction::NONE,
        }
    }

    fn estimate_prefixes(&self, dvl: &[Vec3], gnss: &[Vec3], lengths: &[usize]) -> Vec<Correction> {
        let longest = lengths.iter().copied().max().unwrap_or(0);
        let history = self.history(&dvl[..longest], &gnss[..longest]);
        lengths
            .iter()
            .map(|&n| match n {
                0 => Correction::NONE,
                n => self.model.correction(&history[n - 1].0),
            })
            .collect()
    }
}
