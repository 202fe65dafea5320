//! The measurement model of the paper (docs/paper.md). A DVL measures four beam velocities
//! `y = (H v)(1 + s) + b + n`, with one scale `s` and bias `b` shared by the beams and
//! white noise `n` per beam, and reports `v_dvl = (HᵀH)⁻¹Hᵀ y`; a GNSS-RTK receiver
//! reports `v + N(0, σ²)` per axis. In: ground-truth velocity in m/s. Out: noisy DVL and
//! GNSS-RTK velocity in m/s, from a caller-seeded generator.

use crate::Vec3;
use crate::vocab::SensorErrors;
use rand::Rng;
use rand_distr::{Distribution, StandardNormal};

/// The four beam directions of a Janus "x" DVL and the least-squares map back to
/// a velocity.
#[derive(Debug, Clone)]
pub struct BeamGeometry {
    /// Row i is the unit vector of beam i: `[cos ψ sin α, sin ψ sin α, cos α]`.
    pub directions: [Vec3; 4],
    /// `(HᵀH)⁻¹Hᵀ`, 3×4.
    pub pseudo_inverse: [[f64; 4]; 3],
}

impl BeamGeometry {
    /// Beams at yaw 45°, 135°, 225° and 315°, each pitched `pitch_deg` from vertical.
    pub fn janus_x(pitch_deg: f64) -> Self {
        let pitch = pitch_deg.to_radians();
        let directions: [Vec3; 4] = std::array::from_fn(|i| {
            let yaw = (i as f64 * 90.0 + 45.0).to_radians();
            [
                yaw.cos() * pitch.sin(),
                yaw.sin() * pitch.sin(),
                pitch.cos(),
            ]
        });
        let mut normal = [[0.0; 3]; 3];
        for d in &directions {
            for r in 0..3 {
                for c in 0..3 {
                    normal[r][c] += d[r] * d[c];
                }
            }
        }
        let inverse = invert_3x3(&normal);
        let pseudo_inverse = std::array::from_fn(|r| {
            std::array::from_fn(|beam| (0..3).map(|c| inverse[r][c] * directions[beam][c]).sum())
        });
        Self {
            directions,
            pseudo_inverse,
        }
    }

    /// The velocity error that a bias `b` shared by all beams becomes: `b·(HᵀH)⁻¹Hᵀ1`.
    pub fn shared_bias_velocity(&self, bias_m_s: f64) -> Vec3 {
        std::array::from_fn(|axis| bias_m_s * self.pseudo_inverse[axis].iter().sum::<f64>())
    }

    /// The variance per axis (m²/s²) of the velocity noise that beam noise of standard
    /// deviation `noise_m_s` becomes: the diagonal of `σ²(HᵀH)⁻¹`, which is diagonal
    /// for a Janus DVL.
    pub fn velocity_noise_variances(&self, noise_m_s: f64) -> Vec3 {
        std::array::from_fn(|axis| {
            noise_m_s.powi(2) * self.pseudo_inverse[axis].iter().map(|p| p * p).sum::<f64>()
        })
    }

    /// One DVL measurement of the true velocity `v`, with beam noise drawn from `rng`.
    pub fn measure(&self, v: Vec3, errors: &SensorErrors, rng: &mut impl Rng) -> Vec3 {
        let beams: [f64; 4] = std::array::from_fn(|beam| {
            let d = self.directions[beam];
            let along = d[0] * v[0] + d[1] * v[1] + d[2] * v[2];
            let noise: f64 = StandardNormal.sample(rng);
            along * (1.0 + errors.scale) + errors.bias_m_s + errors.noise_m_s * noise
        });
        std::array::from_fn(|axis| {
            (0..4)
                .map(|beam| self.pseudo_inverse[axis][beam] * beams[beam])
                .sum()
        })
    }
}

fn invert_3x3(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let cofactor = |r: usize, c: usize| {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
        m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1]
    };
    let det: f64 = (0..3).map(|c| m[0][c] * cofactor(0, c)).sum();
    std::array::from_fn(|r| std::array::from_fn(|c| cofactor(c, r) / det))
}

/// DVL and GNSS-RTK measurements of one ground-truth trajectory.
#[derive(Debug, Clone)]
pub struct Measurements {
    pub dvl: Vec<Vec3>,
    pub gnss: Vec<Vec3>,
}

/// Measures every sample of `ground_truth`: first all DVL samples, then all GNSS ones,
/// from the one generator.
pub fn measure_trajectory(
    geometry: &BeamGeometry,
    ground_truth: &[Vec3],
    errors: &SensorErrors,
    gnss_noise_m_s: f64,
    rng: &mut impl Rng,
) -> Measurements {
    let dvl = ground_truth
        .iter()
        .map(|&v| geometry.measure(v, errors, rng))
        .collect();
    let gnss = ground_truth
        .iter()
        .map(|v| {
            std::array::from_fn(|axis| {
                let noise: f64 = StandardNormal.sample(rng);
                v[axis] + gnss_noise_m_s * noise
            })
        })
        .collect();
    Measurements { dvl, gnss }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::task_rng;

    #[test]
    fn a_bias_shared_by_all_beams_becomes_a_z_bias_of_b_over_cos_pitch() {
        let geometry = BeamGeometry::janus_x(20.0);
        let errors = SensorErrors::from_spec_units(0.0, 0.7, 0.0);
        let v = [1.3, -0.4, 0.1];
        let measured = geometry.measure(v, &errors, &mut task_rng(0, &[]));
        let expected_z_bias = 0.007 / 20f64.to_radians().cos();
        assert!((measured[0] - v[0]).abs() < 1e-12);
        assert!((measured[1] - v[1]).abs() < 1e-12);
        assert!(
            (measured[2] - v[2] - expected_z_bias).abs() < 1e-12,
            "z bias {}",
            measured[2] - v[2]
        );
        assert!((geometry.shared_bias_velocity(0.007)[2] - expected_z_bias).abs() < 1e-12);
    }

    #[test]
    fn a_beam_scale_scales_the_velocity() {
        let geometry = BeamGeometry::janus_x(20.0);
        let measured = geometry.measure(
            [1.0, 2.0, -0.5],
            &SensorErrors::from_spec_units(1.0, 0.0, 0.0),
            &mut task_rng(0, &[]),
        );
        for (m, v) in measured.iter().zip([1.0, 2.0, -0.5]) {
            assert!((m - 1.01 * v).abs() < 1e-12);
        }
    }

    #[test]
    fn beam_noise_sigma_gives_a_velocity_rmse_of_2_97_sigma() {
        // sqrt(trace((HᵀH)⁻¹)) = sqrt(1/sin²α + 1/(4cos²α)) = 2.9718 at α = 20°.
        let geometry = BeamGeometry::janus_x(20.0);
        let sigma = 0.02;
        let errors = SensorErrors {
            scale: 0.0,
            bias_m_s: 0.0,
            noise_m_s: sigma,
        };
        let mut rng = task_rng(7, &[&"noise"]);
        let n = 200_000;
        let sum_sq: f64 = (0..n)
            .map(|_| geometry.measure([1.5, 0.0, 0.0], &errors, &mut rng))
            .map(|m| (m[0] - 1.5).powi(2) + m[1].powi(2) + m[2].powi(2))
            .sum();
        let ratio = (sum_sq / n as f64).sqrt() / sigma;
        assert!(
            (ratio - 2.9718).abs() < 0.01,
            "velocity RMSE / beam sigma = {ratio}"
        );
    }

    #[test]
    fn gnss_noise_has_the_requested_deviation_per_axis() {
        let geometry = BeamGeometry::janus_x(20.0);
        let truth = vec![[1.0, 0.5, 0.0]; 100_000];
        let m = measure_trajectory(
            &geometry,
            &truth,
            &SensorErrors::from_spec_units(0.0, 0.0, 0.0),
            0.005,
            &mut task_rng(3, &[]),
        );
        let var_x = m.gnss.iter().map(|g| (g[0] - 1.0).powi(2)).sum::<f64>() / truth.len() as f64;
        assert!(
            (var_x.sqrt() - 0.005).abs() < 0.0001,
            "σ_x = {}",
            var_x.sqrt()
        );
        assert!(m.dvl.iter().all(|d| (d[0] - 1.0).abs() < 1e-12));
    }
}
