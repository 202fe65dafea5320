//! The information bound: how well any unbiased calibration can do from w seconds of
//! data. A Janus DVL with scale `s` and bias `b` shared by the beams measures
//! `v_dvl = (1+s)·v + β·e_z + P·n` (`β = b / cos α`, `P = (HᵀH)⁻¹Hᵀ`, beam noise σ_n),
//! and GNSS-RTK measures `v_gnss = v + e` (σ_g per axis). With the true velocity a
//! nuisance, each axis of each sample carries the Fisher information
//! `g·gᵀ / (σ_d,a² + (1+s)²σ_g²)` about θ = (s, β), with `g = (v_a, [a = z])` and σ_d,a²
//! the DVL's velocity noise on axis a; the Cramér–Rao bound is the inverse of their sum
//! over the calibration window. Corrected with terms that err by δθ, the velocity
//! errs by `(δs·v + δβ·e_z + P·n) / (1+s)`, so a run's RMSE over a scored trajectory is
//! `sqrt(floor² + δθᵀ M δθ)`. Its mean over δθ ~ N(0, bound) is the mean RMSE of an
//! efficient estimator, and that is the `bound` row set beside every estimator: the
//! floor is the limit with perfect terms, the bound the limit with w seconds of data.
//! In: the spec's sensors and DVLs, the trajectories' ground truth. Out: one row per
//! DVL, calibration window and scored trajectory, and the held-out curve: one row per
//! calibration length up to the longest window, scored on the test trajectories
//! pooled.

use crate::Vec3;
use crate::data::Trajectory;
use crate::noise::BeamGeometry;
use crate::spec::Spec;
use crate::vocab::{HELD_OUT, Phase, SensorErrors};

/// A 2×2 matrix over θ = (s, β).
pub type Matrix2 = [[f64; 2]; 2];

/// The bound for one DVL and calibration window on one scored trajectory: the rest of
/// the calibration trajectory, or a test trajectory.
#[derive(Debug, Clone, PartialEq)]
pub struct BoundRow {
    pub dvl: String,
    pub window_s: f64,
    pub phase: Phase,
    pub trajectory: String,
    /// Mean and standard deviation over runs of an efficient estimator's RMSE, cm/s.
    pub rmse_cm_s: f64,
    pub rmse_std_cm_s: f64,
}

/// The bound of every DVL of `spec` for every calibration window, on the rest of the
/// calibration trajectory and on every test trajectory.
pub fn bounds(spec: &Spec, trajectories: &[Trajectory]) -> Vec<BoundRow> {
    let geometry = BeamGeometry::janus_x(spec.beam_pitch_deg);
    let calibration = &trajectories[spec.calibration.trajectory];
    let mut rows = Vec::new();
    for dvl in &spec.dvls {
        for &window in &spec.calibration.window_sizes {
            let truth = &calibration.ground_truth;
            let covariance = term_covariance(
                &truth[..window],
                &dvl.errors,
                &geometry,
                spec.gnss_noise_m_s,
            );
            let scored = std::iter::once((Phase::Calibration, calibration, &truth[window..]))
                .chain(spec.evaluation.iter().map(|&t| {
                    let test = &trajectories[t];
                    (Phase::Evaluation, test, &test.ground_truth[..])
                }));
            for (phase, trajectory, scored) in scored {
                let (rmse_cm_s, rmse_std_cm_s) =
                    expected_rmse(&covariance, scored, &dvl.errors, &geometry);
                rows.push(BoundRow {
                    dvl: dvl.name.clone(),
                    window_s: window as f64 / spec.sample_rate_hz,
                    phase,
                    trajectory: trajectory.name.clone(),
                    rmse_cm_s,
                    rmse_std_cm_s,
                });
            }
        }
        let pooled: Vec<Vec3> = spec
            .evaluation
            .iter()
            .filter(|&&t| t != spec.calibration.trajectory)
            .flat_map(|&t| trajectories[t].ground_truth.iter().copied())
            .collect();
        let longest = spec
            .calibration
            .window_sizes
            .iter()
            .copied()
            .max()
            .unwrap_or(0);
        for length in 1..=longest {
            let truth = &calibration.ground_truth[..length];
            let covariance = term_covariance(truth, &dvl.errors, &geometry, spec.gnss_noise_m_s);
            let (rmse_cm_s, rmse_std_cm_s) =
                expected_rmse(&covariance, &pooled, &dvl.errors, &geometry);
            rows.push(BoundRow {
                dvl: dvl.name.clone(),
                window_s: length as f64 / spec.sample_rate_hz,
                phase: Phase::HeldOut,
                trajectory: HELD_OUT.to_string(),
                rmse_cm_s,
                rmse_std_cm_s,
            });
        }
    }
    rows
}

/// The Cramér–Rao bound of θ = (s, β) from calibration samples of true velocity
/// `truth`: the inverse of their Fisher information. Infinite where the window cannot
/// tell the terms apart (no velocity at all, say).
pub fn term_covariance(
    truth: &[Vec3],
    errors: &SensorErrors,
    geometry: &BeamGeometry,
    gnss_noise_m_s: f64,
) -> Matrix2 {
    let dvl = geometry.velocity_noise_variances(errors.noise_m_s);
    let gnss = (1.0 + errors.scale).powi(2) * gnss_noise_m_s.powi(2);
    let mut information = [[0.0; 2]; 2];
    for v in truth {
        for axis in 0..3 {
            let g = [v[axis], if axis == 2 { 1.0 } else { 0.0 }];
            let weight = 1.0 / (dvl[axis] + gnss);
            for (r, row) in information.iter_mut().enumerate() {
                for (c, entry) in row.iter_mut().enumerate() {
                    *entry += weight * g[r] * g[c];
                }
            }
        }
    }
    let [[a, b], [_, d]] = information;
    let determinant = a * d - b * b;
    if determinant > 0.0 && determinant.is_finite() {
        [
            [d / determinant, -b / determinant],
            [-b / determinant, a / determinant],
        ]
    } else {
        [[f64::INFINITY, 0.0], [0.0, f64::INFINITY]]
    }
}

/// The mean and standard deviation (cm/s) over runs of the RMSE over `scored` of a
/// correction whose terms err as N(0, `covariance`), measured by a DVL with `errors`.
pub fn expected_rmse(
    covariance: &Matrix2,
    scored: &[Vec3],
    errors: &SensorErrors,
    geometry: &BeamGeometry,
) -> (f64, f64) {
    if covariance.iter().flatten().any(|c| !c.is_finite()) || scored.is_empty() {
        return (f64::INFINITY, f64::INFINITY);
    }
    let gain = (1.0 + errors.scale).powi(-2);
    let noise = geometry.velocity_noise_variances(errors.noise_m_s);
    let floor_squared = gain * noise.iter().sum::<f64>();
    // M = mean over the scored samples of gᵀg/(1+s)², g = [v, e_z] (3×2).
    let n = scored.len() as f64;
    let mut m = [[0.0; 2]; 2];
    for v in scored {
        m[0][0] += gain * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) / n;
        m[0][1] += gain * v[2] / n;
        m[1][1] += gain / n;
    }
    m[1][0] = m[0][1];
    // δθᵀMδθ = λ₁z₁² + λ₂z₂², z standard normal, λ the eigenvalues of M·covariance.
    let product = multiply(&m, covariance);
    let trace = product[0][0] + product[1][1];
    let determinant = product[0][0] * product[1][1] - product[0][1] * product[1][0];
    let spread = (trace * trace / 4.0 - determinant).max(0.0).sqrt();
    let (high, low) = (trace / 2.0 + spread, (trace / 2.0 - spread).max(0.0));
    let mean = mean_root(floor_squared, high, low);
    let mean_square = floor_squared + trace;
    // The noise part of a run's mean square varies too: each sample's |P·n|² has
    // variance 2·Σσ_d,a⁴ (independent axes), and its mean over the scored samples
    // moves the RMSE by half its relative change.
    let noise_variance = 2.0 * gain * gain * noise.iter().map(|d| d * d).sum::<f64>() / n;
    let variance = (mean_square - mean * mean).max(0.0) + noise_variance / (4.0 * mean_square);
    (100.0 * mean, 100.0 * variance.sqrt())
}

fn multiply(a: &Matrix2, b: &Matrix2) -> Matrix2 {
    std::array::from_fn(|r| std::array::from_fn(|c| a[r][0] * b[0][c] + a[r][1] * b[1][c]))
}

/// `E[sqrt(f² + λ₁z₁² + λ₂z₂²)]` for independent standard normal z₁, z₂. From
/// `√x = ∫₀^∞ (1 − e^(−tx)) t^(−3/2) dt / (2√π)` and the Gaussian's closed form
/// `E[e^(−tX)] = e^(−tf²) / √((1+2tλ₁)(1+2tλ₂))`, one integral of a smooth function,
/// taken by the trapezoid rule in u = ln(t·E[X]), where it converges geometrically.
fn mean_root(floor_squared: f64, high: f64, low: f64) -> f64 {
    let mean_square = floor_squared + high + low;
    if mean_square == 0.0 {
        return 0.0;
    }
    const STEP: f64 = 0.05;
    // Beyond u = ±80 the integrand is below e^(−40) of √E[X] (it falls as e^(−|u|/2)).
    let integral: f64 = (0..=3200)
        .map(|i| {
            let t = (-80.0 + STEP * i as f64).exp() / mean_square;
            let exponent =
                -t * floor_squared - 0.5 * (2.0 * t * high).ln_1p() - 0.5 * (2.0 * t * low).ln_1p();
            -exponent.exp_m1() / t.sqrt()
        })
        .sum::<f64>()
        * STEP;
    integral / (2.0 * std::f64::consts::PI.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_root_has_the_chi_distributions_means() {
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        // E|z| = sqrt(2/π); E sqrt(z₁² + z₂²) = sqrt(π/2); no spread leaves the floor.
        assert!(close(
            mean_root(0.0, 1.0, 0.0),
            (2.0 / std::f64::consts::PI).sqrt()
        ));
        assert!(close(
            mean_root(0.0, 1.0, 1.0),
            (std::f64::consts::PI / 2.0).sqrt()
        ));
        assert!(close(mean_root(0.09, 0.0, 0.0), 0.3));
        // Scaling: E sqrt(4f² + 4q) = 2 E sqrt(f² + q).
        assert!(close(
            mean_root(4.0 * 0.3, 4.0 * 2.0, 4.0 * 0.5),
            2.0 * mean_root(0.3, 2.0, 0.5)
        ));
    }

    /// At constant velocity the information grows as the window, so the terms' spread,
    /// and the RMSE it adds above the floor, shrink as 1/√w.
    #[test]
    fn the_bound_shrinks_as_one_over_root_w_at_constant_velocity() {
        let geometry = BeamGeometry::janus_x(20.0);
        let errors = SensorErrors::from_spec_units(1.0, 0.7, 0.02);
        // Enough scored samples that the noise part's own spread is negligible.
        let scored = vec![[1.5, 0.1, 0.0]; 1_000_000];
        let floor_squared: f64 = geometry
            .velocity_noise_variances(errors.noise_m_s)
            .iter()
            .sum::<f64>()
            / 1.01f64.powi(2);
        let added = |w: usize| {
            let covariance = term_covariance(&vec![[1.5, 0.1, 0.0]; w], &errors, &geometry, 0.005);
            let (mean, std) = expected_rmse(&covariance, &scored, &errors, &geometry);
            // E[RMSE²] = mean² + std², less the noise part's own spread.
            let mean_square = (mean * mean + std * std) / 1e4;
            (mean_square - floor_squared).sqrt()
        };
        for w in [20, 50, 100] {
            let ratio = added(w) / added(4 * w);
            assert!((ratio - 2.0).abs() < 1e-6, "w = {w}: ratio {ratio}");
        }
    }

    #[test]
    fn no_velocity_leaves_the_scale_unknowable() {
        let geometry = BeamGeometry::janus_x(20.0);
        let errors = SensorErrors::from_spec_units(1.0, 0.7, 0.02);
        let covariance = term_covariance(&[[0.0; 3]; 50], &errors, &geometry, 0.005);
        assert!(covariance[0][0].is_infinite());
        let (mean, _) = expected_rmse(&covariance, &[[1.0, 0.0, 0.0]], &errors, &geometry);
        assert!(mean.is_infinite());
    }
}
