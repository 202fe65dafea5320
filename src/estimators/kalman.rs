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
use crate::spec::KalmanSpec;
use crate::vocab::{Correction, SensorErrors};

pub struct KalmanFilter {
    pub model: ScaleBiasModel,
    prior: Prior,
    /// The variance per axis of `d − g`, m²/s².
    noise: Vec3,
    sample_period_s: f64,
}

impl KalmanFilter {
    pub fn new(
        model: ScaleBiasModel,
        settings: &KalmanSpec,
        errors: &SensorErrors,
        geometry: &BeamGeometry,
        gnss_noise_m_s: f64,
        sample_rate_hz: f64,
    ) -> Self {
        KalmanFilter {
            model,
            prior: model.prior(settings.prior, settings.random_walk),
            noise: axis_noise(errors, geometry, gnss_noise_m_s),
            sample_period_s: 1.0 / sample_rate_hz,
        }
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
