//! The robust loss of a fit, so that a DVL's outliers (acoustic multipath spikes, a
//! bottom lock half lost) do not pull the terms: each residual component u = r / σ,
//! with σ its axis's scale from the median absolute deviation, costs ρ(u) instead of
//! u² / 2. A fit first solves least squares, then Huber's loss from there (convex, so
//! it finds the basin), then Tukey's bisquare from Huber's solution (redescending: a
//! residual beyond [`TUKEY_C`] scales no longer pulls at all). Levenberg–Marquardt
//! minimises Σ ρ through the residual `σ · sign(u) · √(2ρ(u))`, whose squares sum to
//! it, and its Jacobian row `ψ(u) / (sign(u) · √(2ρ(u)))` times the row of r.
//! The standard deviations are the M-estimator's sandwich: the bread JᵀDJ with D =
//! ψ′(u), the meat from the pseudo-residuals σ · ψ(u) (the fit's
//! `curvature` and `residuals`).
//! Beside them, for a fit to positions, the positions grossly off, found by their jumps
//! from one to the next ([`gross_jumps`]), which no fit's parameters can hide.
//! In: a fit's residuals, x, y, z of each sample in order. Out: the scales, the
//! transformed residuals and Jacobian rows, the pseudo-residuals and the curvature; the
//! positions to keep.

use crate::Vec3;
use nalgebra::DVector;

/// Huber's tuning constant, in scales: 95 % efficient on Gaussian noise.
pub const HUBER_C: f64 = 1.345;

/// Tukey's bisquare tuning constant, in scales: a residual beyond it is an outlier,
/// with no weight in the fit. Not the textbook 4.685 (95 % efficient on Gaussian
/// noise): a DVL's residuals beside a real reference are heavy-tailed around their
/// median absolute deviation (on A-KIT T1 their RMS is two to four times the scale it
/// gives, the turns' residuals the widest), and 4.685 rejects the turns that show the
/// lever arm, moving T1's lever arm x by 2.4 of its standard deviations; at 20 the
/// terms of a clean recording stay within about one and a half of least squares' (T1's
/// time offset 1.454 s against 1.428 ± 0.017 s), while an acoustic spike of 50 cm/s
/// (70 scales on A-KIT, 25 at 2 cm/s of white noise) is still rejected.
pub const TUKEY_C: f64 = 20.0;

/// Tukey's bisquare tuning constant for residuals standardised by a noise the fit
/// models (a position fix's innovation over its own standard deviation, not a scale
/// read from the residuals' spread): the textbook 4.685, 95 % efficient on Gaussian
/// noise.
pub const TUKEY_C_MODELLED: f64 = 4.685;

/// The factor from a median absolute deviation to a Gaussian standard deviation.
const MAD_TO_STD: f64 = 1.482_602_218_505_602;

/// A robust loss ρ(u) of a residual in scales: Huber's, or Tukey's bisquare with its
/// constant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Loss {
    Huber,
    Tukey(f64),
}

impl Loss {
    /// Tukey's bisquare for residuals in scales read from their spread ([`TUKEY_C`]).
    pub const TUKEY: Loss = Loss::Tukey(TUKEY_C);
    /// Tukey's bisquare for residuals standardised by a modelled noise
    /// ([`TUKEY_C_MODELLED`]).
    pub const TUKEY_MODELLED: Loss = Loss::Tukey(TUKEY_C_MODELLED);

    /// ρ(u).
    fn rho(self, u: f64) -> f64 {
        match self {
            Loss::Huber if u.abs() <= HUBER_C => 0.5 * u * u,
            Loss::Huber => HUBER_C * (u.abs() - 0.5 * HUBER_C),
            Loss::Tukey(c) => {
                let inside = (1.0 - (u * u / (c * c)).min(1.0)).powi(3);
                c * c / 6.0 * (1.0 - inside)
            }
        }
    }

    /// ψ(u) = ρ′(u).
    pub fn psi(self, u: f64) -> f64 {
        match self {
            Loss::Huber => u.clamp(-HUBER_C, HUBER_C),
            Loss::Tukey(c) if u.abs() < c => u * (1.0 - (u / c).powi(2)).powi(2),
            Loss::Tukey(_) => 0.0,
        }
    }

    /// The weight ψ(u)/u (1 at u = 0): iteratively reweighted least squares'.
    pub fn weight(self, u: f64) -> f64 {
        match u == 0.0 {
            true => 1.0,
            false => self.psi(u) / u,
        }
    }

    /// ψ′(u).
    pub fn psi_prime(self, u: f64) -> f64 {
        match self {
            Loss::Huber => f64::from(u8::from(u.abs() <= HUBER_C)),
            Loss::Tukey(c) if u.abs() < c => {
                let v = (u / c).powi(2);
                (1.0 - v) * (1.0 - 5.0 * v)
            }
            Loss::Tukey(_) => 0.0,
        }
    }

    /// The residual whose square is 2ρ(u), in the residual's unit: σ · sign(u) · √(2ρ).
    pub fn residual(self, u: f64, scale: f64) -> f64 {
        scale * u.signum() * (2.0 * self.rho(u)).sqrt()
    }

    /// d(√(2ρ(u)) · sign(u)) / du: what a row of the Jacobian of r is multiplied by.
    pub fn slope(self, u: f64) -> f64 {
        let root = (2.0 * self.rho(u)).sqrt();
        if root < 1e-12 {
            // ρ ≈ u² / 2 near zero for both losses.
            return 1.0;
        }
        self.psi(u) / (u.signum() * root)
    }
}

/// What a fit under a robust loss keeps of it: the loss with its scales, ψ′ of each
/// residual (the weights D of the information JᵀDJ, x, y, z of each sample), and how
/// many samples are outliers.
#[derive(Debug, Clone)]
pub struct RobustFit {
    pub loss: Robust,
    pub curvature: DVector<f64>,
    pub outliers: usize,
}

/// A robust loss with each axis's scale, m/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Robust {
    pub loss: Loss,
    pub scale_m_s: Vec3,
}

impl Robust {
    /// Whether `residual` (x, y, z, m/s) has a component beyond [`TUKEY_C`] scales: an
    /// outlier.
    pub fn is_outlier(&self, residual: Vec3) -> bool {
        (0..3).any(|k| self.scaled(residual[k], k).abs() >= TUKEY_C)
    }

    /// The residual `r` of axis `axis` in scales.
    pub fn scaled(&self, r: f64, axis: usize) -> f64 {
        r / self.scale_m_s[axis]
    }

    /// What this loss makes of a fit's `residuals` (x, y, z of each sample): their
    /// curvature and outliers.
    pub fn fitted(&self, residuals: &DVector<f64>) -> RobustFit {
        RobustFit {
            loss: *self,
            curvature: self.curvature(residuals),
            outliers: self.outliers(residuals),
        }
    }

    /// The pseudo-residuals σ · ψ(u) of `residuals` (x, y, z of each sample).
    pub fn pseudo_residuals(&self, residuals: &DVector<f64>) -> DVector<f64> {
        DVector::from_fn(residuals.len(), |i, _| {
            let axis = i % 3;
            self.scale_m_s[axis] * self.loss.psi(self.scaled(residuals[i], axis))
        })
    }

    /// ψ′(u) of each of `residuals`: the bread's weights.
    fn curvature(&self, residuals: &DVector<f64>) -> DVector<f64> {
        DVector::from_fn(residuals.len(), |i, _| {
            self.loss.psi_prime(self.scaled(residuals[i], i % 3))
        })
    }

    /// How many samples have a residual component beyond [`TUKEY_C`] scales: the
    /// outliers, which pull nothing under Tukey's loss.
    fn outliers(&self, residuals: &DVector<f64>) -> usize {
        (0..residuals.len() / 3)
            .filter(|&s| self.is_outlier([0, 1, 2].map(|k| residuals[3 * s + k])))
            .count()
    }
}

/// Each axis's scale of `residuals` (x, y, z of each sample), m/s: the median absolute
/// deviation from the median, as a Gaussian standard deviation. `None` where an axis
/// has none (a noise-free record: least squares is exact there).
pub fn scales(residuals: &DVector<f64>) -> Option<Vec3> {
    let median = |values: &mut Vec<f64>| {
        values.sort_by(f64::total_cmp);
        let n = values.len();
        if n % 2 == 1 {
            values[n / 2]
        } else {
            0.5 * (values[n / 2 - 1] + values[n / 2])
        }
    };
    let mut scale = [0.0; 3];
    for (axis, value) in scale.iter_mut().enumerate() {
        let mut axis_values: Vec<f64> = residuals.iter().skip(axis).step_by(3).copied().collect();
        if axis_values.is_empty() {
            return None;
        }
        let centre = median(&mut axis_values);
        let mut deviations: Vec<f64> = axis_values.iter().map(|r| (r - centre).abs()).collect();
        *value = MAD_TO_STD * median(&mut deviations);
    }
    scale
        .iter()
        .all(|s| *s > 0.0 && s.is_finite())
        .then_some(scale)
}

/// Whether each of `residuals` (x, y, z per sample, in any unit) is an outlier by the
/// fits' test, a component beyond [`TUKEY_C`] scales of the rest (each axis's MAD): for
/// residuals no fit weighed (a calibration applied to another dive, a figure's). None
/// is where an axis has no scale.
pub fn outliers_among(residuals: &[Vec3]) -> Vec<bool> {
    let flat = DVector::from_iterator(3 * residuals.len(), residuals.iter().flatten().copied());
    match scales(&flat) {
        Some(scale_m_s) => {
            let tukey = Robust {
                loss: Loss::TUKEY,
                scale_m_s,
            };
            residuals.iter().map(|r| tukey.is_outlier(*r)).collect()
        }
        None => vec![false; residuals.len()],
    }
}

/// Which of a fit's positions to keep: all but those that jump away from their
/// neighbours and back. `residuals` hold blocks of one piece and one axis (`blocks`: the
/// positions in each piece, every axis of a piece in turn, `axes` of them); a jump is
/// the change of the residual, over the axes, from one position of a piece to the next.
/// A position is gross where its jumps to both neighbours exceed `times` the median
/// jump and `floor` (at a piece's end: its one jump, where its neighbour's other jump
/// does not); in a piece of fewer than three, none is. Each jump is read in the
/// positions' own `noise` (one relative standard deviation per position, pieces in
/// turn: the root mean square of the two a jump joins). A jump does not depend on a
/// fit's parameters, so a position that pulls least squares towards it cannot hide.
pub fn gross_jumps(
    residuals: &[f64],
    (blocks, axes, noise): (&[usize], usize, &[f64]),
    (times, floor): (f64, f64),
) -> Vec<bool> {
    let mut jumps: Vec<Vec<f64>> = Vec::with_capacity(blocks.len());
    let (mut row, mut offset) = (0, 0);
    for &n in blocks {
        let jump = |j: usize| {
            let own = (0.5 * (noise[offset + j].powi(2) + noise[offset + j + 1].powi(2))).sqrt();
            (0..axes)
                .map(|axis| residuals[row + axis * n + j + 1] - residuals[row + axis * n + j])
                .map(|d| d * d)
                .sum::<f64>()
                .sqrt()
                / own
        };
        jumps.push((0..n.saturating_sub(1)).map(jump).collect());
        row += n * axes;
        offset += n;
    }
    let mut sorted: Vec<f64> = jumps.iter().flatten().copied().collect();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
    let gross = (times * median).max(floor);
    let big = |jumps: &[f64], j: usize| jumps.get(j).is_some_and(|&jump| jump > gross);
    (jumps.iter().zip(blocks))
        .flat_map(|(jumps, &n)| {
            (0..n).map(move |j| match j {
                _ if n < 3 => true,
                0 => !(big(jumps, 0) && !big(jumps, 1)),
                j if j == n - 1 => !(big(jumps, j - 1) && !big(jumps, j - 2)),
                j => !(big(jumps, j - 1) && big(jumps, j)),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_loss_is_its_derivatives_integral_and_its_residuals_square_is_twice_it() {
        for loss in [Loss::Huber, Loss::TUKEY, Loss::TUKEY_MODELLED] {
            for u in [-7.0, -3.0, -1.0, -0.2, 0.0, 0.3, 1.2, 2.0, 4.0, 6.0] {
                let step = 1e-6;
                let numeric = (loss.rho(u + step) - loss.rho(u - step)) / (2.0 * step);
                assert!((numeric - loss.psi(u)).abs() < 1e-6, "{loss:?} ψ({u})");
                let numeric = (loss.psi(u + step) - loss.psi(u - step)) / (2.0 * step);
                assert!(
                    (numeric - loss.psi_prime(u)).abs() < 1e-5,
                    "{loss:?} ψ′({u})"
                );
                let r = loss.residual(u, 1.0);
                assert!((r * r - 2.0 * loss.rho(u)).abs() < 1e-12);
                let numeric =
                    (loss.residual(u + step, 1.0) - loss.residual(u - step, 1.0)) / (2.0 * step);
                if u != 0.0 {
                    assert!(
                        (numeric - loss.slope(u)).abs() < 1e-5,
                        "{loss:?} slope({u})"
                    );
                }
            }
        }
        assert_eq!(Loss::TUKEY.psi(TUKEY_C + 1.0), 0.0);
        assert_eq!(Loss::TUKEY_MODELLED.weight(TUKEY_C_MODELLED + 0.1), 0.0);
        assert_eq!(Loss::Huber.weight(2.0 * HUBER_C), 0.5);
        assert_eq!(Loss::Huber.psi(5.0), HUBER_C);
    }

    #[test]
    fn the_scale_is_the_noises_and_ignores_a_few_gross_outliers() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let noise = Normal::new(0.0, 0.02).unwrap();
        let mut values: Vec<f64> = (0..30_000).map(|_| noise.sample(&mut rng)).collect();
        for i in (0..values.len()).step_by(34) {
            values[i] += 0.5;
        }
        let scale = scales(&DVector::from_vec(values)).unwrap();
        for s in scale {
            assert!((s - 0.02).abs() < 0.001, "{scale:?}");
        }
        assert_eq!(scales(&DVector::zeros(9)), None);
    }

    /// One position 300 m off in the middle of a piece and one at its start are gross;
    /// a step that stays (its jumps at its two ends only), a smooth drift, and a piece
    /// of two are not; the second axis's block is read as the same positions'.
    #[test]
    fn a_position_that_jumps_away_and_back_is_gross_and_a_step_is_not() {
        let smooth: Vec<f64> = (0..12).map(|j| 0.1 * f64::from(j)).collect();
        let mut north = smooth.clone();
        north[0] += 300.0;
        north[5] += 300.0;
        for value in &mut north[8..] {
            *value += 50.0;
        }
        let residuals = [north, vec![0.0; 12]].concat();
        let kept = gross_jumps(&residuals, (&[12], 2, &[1.0; 12]), (10.0, 5.0));
        let gross: Vec<usize> = (0..12).filter(|&j| !kept[j]).collect();
        assert_eq!(gross, vec![0, 5]);
        let kept = gross_jumps(&[0.0, 500.0, 0.0, 0.0], (&[2], 2, &[1.0; 2]), (10.0, 5.0));
        assert_eq!(kept, vec![true, true]);
    }
}
