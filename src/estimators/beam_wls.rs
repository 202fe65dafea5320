//! Beam-model weighted least squares: the DVL's own error model fitted directly. A scale
//! `s` and a bias `b` shared by the four beams make the velocity error
//! `v_dvl − v = s·v + β·e_z + P·n` with `β = b / cos α` (docs/paper.md, "Measurement model"), so the residual
//! `v_dvl − v_gnss` is regressed on `[v_gnss, e_z]` over every axis at once, each axis
//! weighted by the inverse of its residual variance (beam noise through `(HᵀH)⁻¹`,
//! plus the GNSS-RTK noise). The GNSS-RTK noise in the regressor would pull `s` toward
//! zero by `σ_g² / mean(v²)`; its known variance is taken out of the normal equations
//! (the method-of-moments correction for errors in variables). Two terms shared by the
//! axes stay separable at constant velocity, where a line per axis (least squares EM5)
//! is not: the scale is seen in the large along-track velocity, the bias on z, where
//! the velocity is near zero.

use super::Estimator;
use crate::Vec3;
use crate::noise::BeamGeometry;
use crate::vocab::{Correction, SensorErrors};

pub struct BeamWls {
    /// Weight per axis: the smallest residual variance (DVL velocity noise plus
    /// GNSS-RTK noise) over the axis's own; an axis without noise weighs 1.
    weights: Vec3,
    gnss_variance: f64,
}

impl BeamWls {
    /// For a DVL with the beam noise of `errors` on `geometry`, against GNSS-RTK noise
    /// of `gnss_noise_m_s` per axis.
    pub fn new(errors: &SensorErrors, geometry: &BeamGeometry, gnss_noise_m_s: f64) -> Self {
        let gnss_variance = gnss_noise_m_s.powi(2);
        let residual = geometry
            .velocity_noise_variances(errors.noise_m_s)
            .map(|d| d + gnss_variance);
        let smallest = residual.iter().copied().fold(f64::INFINITY, f64::min);
        Self {
            weights: residual.map(|v| if v > 0.0 { smallest / v } else { 1.0 }),
            gnss_variance,
        }
    }
}

impl Estimator for BeamWls {
    fn estimate(&self, dvl: &[Vec3], gnss: &[Vec3]) -> Correction {
        // Normal equations of (s, β), [[a, c], [c, d]]·θ = [e, f].
        let (mut a, mut c, mut d, mut e, mut f) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (measured, reference) in dvl.iter().zip(gnss) {
            for axis in 0..3 {
                let weight = self.weights[axis];
                let (g, r) = (reference[axis], measured[axis] - reference[axis]);
                a += weight * (g * g - self.gnss_variance);
                e += weight * (g * r + self.gnss_variance);
                if axis == 2 {
                    c += weight * g;
                    d += weight;
                    f += weight * r;
                }
            }
        }
        let determinant = a * d - c * c;
        let (scale, bias) = if determinant > 0.0 {
            ((e * d - c * f) / determinant, (a * f - c * e) / determinant)
        } else if d > 0.0 {
            // No speed to see a scale in: a bias alone.
            (0.0, f / d)
        } else {
            (0.0, 0.0)
        };
        Correction {
            scale: [scale; 3],
            bias_m_s: [0.0, 0.0, bias],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::measure_trajectory;
    use crate::rng::task_rng;

    /// A window of `n` samples at 1 Hz: a slow surge around 1.5 m/s with some sway and
    /// heave.
    fn truth(n: usize) -> Vec<Vec3> {
        (0..n)
            .map(|t| t as f64)
            .map(|t| {
                [
                    1.5 + 0.3 * (t / 40.0).sin(),
                    0.2 * (t / 25.0).cos(),
                    0.05 * (t / 9.0).sin(),
                ]
            })
            .collect()
    }

    #[test]
    fn recovers_noise_free_terms_exactly() {
        let geometry = BeamGeometry::janus_x(20.0);
        let errors = SensorErrors::from_spec_units(1.0, 0.7, 0.0);
        let truth = truth(50);
        let mut rng = task_rng(1, &[]);
        let measured = measure_trajectory(&geometry, &truth, &errors, 0.0, &mut rng);
        let estimator = BeamWls::new(&errors, &geometry, 0.0);
        let correction = estimator.estimate(&measured.dvl, &measured.gnss);
        let beta = 0.007 / 20f64.to_radians().cos();
        assert!(correction.scale.iter().all(|k| (k - 0.01).abs() < 1e-12));
        assert!((correction.bias_m_s[2] - beta).abs() < 1e-12);
    }

    /// Over 2000 noisy windows of both DVLs, the estimates centre on the true terms and
    /// scatter as the Cramér–Rao bound says (`bound::term_covariance`): unbiased and
    /// efficient.
    #[test]
    fn recovers_known_terms_within_their_bound() {
        let geometry = BeamGeometry::janus_x(20.0);
        let gnss_noise = 0.005;
        let truth = truth(40);
        let beta = 0.007 / 20f64.to_radians().cos();
        for noise_cm_s in [2.0, 0.02] {
            let errors = SensorErrors::from_spec_units(1.0, 0.7, noise_cm_s);
            let estimator = BeamWls::new(&errors, &geometry, gnss_noise);
            let bound = crate::bound::term_covariance(&truth, &errors, &geometry, gnss_noise);
            let runs = 2000;
            let mut rng = task_rng(2, &[&noise_cm_s.to_string()]);
            let estimates: Vec<(f64, f64)> = (0..runs)
                .map(|_| {
                    let m = measure_trajectory(&geometry, &truth, &errors, gnss_noise, &mut rng);
                    let c = estimator.estimate(&m.dvl, &m.gnss);
                    (c.scale[0], c.bias_m_s[2])
                })
                .collect();
            for (term, truth, variance) in [(0, 0.01, bound[0][0]), (1, beta, bound[1][1])] {
                let values: Vec<f64> = estimates
                    .iter()
                    .map(|e| if term == 0 { e.0 } else { e.1 })
                    .collect();
                let mean = values.iter().sum::<f64>() / runs as f64;
                let var =
                    values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (runs - 1) as f64;
                let standard_error = (variance / runs as f64).sqrt();
                assert!(
                    (mean - truth).abs() < 4.0 * standard_error,
                    "DVL noise {noise_cm_s} cm/s, term {term}: mean {mean}, true {truth}"
                );
                // The sample variance of 2000 draws is within ±8 % of the true one
                // (2.5 standard errors of sqrt(2/1999)).
                assert!(
                    (var / variance - 1.0).abs() < 0.08,
                    "DVL noise {noise_cm_s} cm/s, term {term}: variance {var} vs bound {variance}"
                );
            }
        }
    }
}
