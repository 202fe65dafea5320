//! The noise a fit's residuals show, and what it costs the terms: per DVL axis, the
//! residuals' standard deviation and their correlation from one sample to the next,
//! read as a first-order autoregression (AR(1)), and the middle of the least squares'
//! sandwich under that noise, JᵀΣJ, where Σ is each axis's AR(1) covariance over the
//! samples (the axes independent). In: a fit's Jacobian and residuals. Out: a
//! [`ResidualNoise`] and JᵀΣJ.
//!
//! With the terms' covariance (JᵀJ)⁻¹ JᵀΣJ (JᵀJ)⁻¹, white residuals give σ̂²(JᵀJ)⁻¹,
//! the Fisher bound at the noise the segment showed; residuals correlated in time
//! (what the model leaves out follows the manoeuvres) widen it by as much as they
//! cost. This is the covariance of ordinary least squares under AR(1) errors (Greene,
//! *Econometric Analysis*, 8th ed., §20.5), the errors' parameters estimated from the
//! residuals; `tests/installation/coverage.rs` checks that its intervals cover the truth.

use crate::Vec3;
use nalgebra::{DMatrix, DVector};

/// The largest lag-one correlation the noise model takes: a nearer unit root (a
/// residual that drifts for the whole window) reads as this, an effective sample count
/// of about one in two hundred.
pub const MAX_LAG_ONE: f64 = 0.99;

/// Per DVL axis, a fit's residuals' sum of squares and sum of products of neighbours.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResidualSums {
    /// Σ rᵢ², m²/s².
    pub power: Vec3,
    /// Σ rᵢ rᵢ₋₁ over the neighbours of one piece, m²/s².
    pub lagged: Vec3,
    /// How many samples.
    pub samples: usize,
    /// How many pairs of neighbours `lagged` sums over: one fewer than the samples in
    /// one piece, one fewer per piece in several.
    pub pairs: usize,
}

/// The noise of a fit's residuals, per DVL axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResidualNoise {
    /// The residuals' standard deviation, m/s, counting the fitted parameters' degrees
    /// of freedom.
    pub std_m_s: Vec3,
    /// Their correlation from one sample to the next, within ±[`MAX_LAG_ONE`].
    pub lag_one: Vec3,
    /// How many samples they were read from.
    pub samples: usize,
    /// Per axis, the samples' worth of noise the fit left in the residuals, n − f_k
    /// ([`Self::counting_the_absorbed`]; n less a third of the parameters until then).
    pub kept: Vec3,
}

impl ResidualNoise {
    /// Of `residuals` (x, y, z of each sample, in order) after fitting `parameters`;
    /// `follows` says of each sample whether it follows the one before it within a
    /// piece (the products of neighbours are summed within pieces only).
    pub fn of(residuals: &DVector<f64>, parameters: usize, follows: &[bool]) -> ResidualNoise {
        let samples = residuals.len() / 3;
        let mut sums = ResidualSums {
            power: [0.0; 3],
            lagged: [0.0; 3],
            samples,
            pairs: (1..samples).filter(|&i| follows[i]).count(),
        };
        for k in 0..3 {
            let r = |i: usize| residuals[3 * i + k];
            sums.power[k] = (0..samples).map(|i| r(i) * r(i)).sum();
            sums.lagged[k] = (1..samples)
                .filter(|&i| follows[i])
                .map(|i| r(i) * r(i - 1))
                .sum();
        }
        ResidualNoise::of_sums(&sums, parameters)
    }

    /// Of the residuals' sums, after fitting `parameters`.
    pub fn of_sums(sums: &ResidualSums, parameters: usize) -> ResidualNoise {
        let samples = sums.samples;
        let freedom = (3 * samples).saturating_sub(parameters).max(1) as f64;
        let inflation = (3 * samples) as f64 / freedom;
        let mut noise = ResidualNoise {
            std_m_s: [0.0; 3],
            lag_one: [0.0; 3],
            samples,
            kept: [(samples as f64 - parameters as f64 / 3.0).max(1.0); 3],
        };
        for k in 0..3 {
            let (power, lagged) = (sums.power[k], sums.lagged[k]);
            noise.std_m_s[k] = (power / samples.max(1) as f64 * inflation).sqrt();
            // The lag-one estimate's bias taken back: −(1 + 3ρ)/n for a series whose mean
            // is estimated (Marriott and Pope, 1954), and about −(1 + ρ)/n more for each
            // other parameter fitted on the axis (its share of them), which the residuals
            // of a fit lose; `tests/installation/coverage.rs` checks the sum.
            // The mean product of neighbours over the mean square: with every sample
            // in one piece, Σ rᵢ rᵢ₋₁ / Σ rᵢ² as ever; no pairs, no correlation read.
            noise.lag_one[k] = if power > 0.0 && sums.pairs > 0 {
                let read = lagged / power * (samples - 1) as f64 / sums.pairs as f64;
                let per_axis = parameters as f64 / 3.0;
                let bias = (1.0 + 3.0 * read + per_axis * (1.0 + read)) / samples as f64;
                (read + bias).clamp(-MAX_LAG_ONE, MAX_LAG_ONE)
            } else {
                0.0
            };
        }
        noise
    }

    /// This noise with each axis's level read again for what the fit absorbed of it.
    /// The residuals r = (I − H) e of a fit keep E‖r_k‖² = σ_k² (n − f_k) of axis k's
    /// noise, f_k = tr((JᵀJ)⁻¹ J_kᵀ R_k J_k) with R_k the axis's AR(1) correlation over
    /// the samples; [`Self::of_sums`] took f_k as a third of the parameters, which holds
    /// for white noise only: a correlated noise's slow part looks like the terms (a bias
    /// absorbs (1 + ρ)/(1 − ρ) samples' worth of it), and the level read short would
    /// narrow every interval. `absorbed` gives f_k of one axis's JᵀR_kJ, the bread's
    /// inverse applied; `jacobian` is the rows as the bread weighs them (a robust loss's
    /// D J, an outlier's row zero). Per axis this is the sum's share, exact where each
    /// parameter moves one axis, an approximation where one moves several.
    pub fn counting_the_absorbed(
        &self,
        (jacobian, follows): (&DMatrix<f64>, &[bool]),
        absorbed: impl Fn(&DMatrix<f64>) -> f64,
    ) -> ResidualNoise {
        let n = self.samples as f64;
        let mut noise = *self;
        for k in 0..3 {
            let mut unit = ResidualNoise {
                std_m_s: [0.0; 3],
                ..*self
            };
            unit.std_m_s[k] = 1.0;
            let share = absorbed(&unit.weighted_information(jacobian, follows)).clamp(0.0, n - 1.0);
            noise.kept[k] = n - share;
            noise.std_m_s[k] = self.std_m_s[k] * (self.kept[k] / noise.kept[k]).sqrt();
        }
        noise
    }

    /// The degrees of freedom of the noise's level as read from these residuals: on
    /// each axis Bartlett's m (1 − ρ²) / (1 + ρ²), m the samples' worth the fit left
    /// ([`Self::kept`]), what an AR(1) series of correlation ρ is worth for its variance,
    /// and their mean over the three axes. 400 white samples are worth about 400; 60 at
    /// ρ = 0.9, about 6.
    pub fn freedom(&self) -> f64 {
        let per_axis = [0, 1, 2].map(|k| {
            let r2 = self.lag_one[k] * self.lag_one[k];
            self.kept[k] * (1.0 - r2) / (1.0 + r2)
        });
        (per_axis.iter().sum::<f64>() / 3.0).max(1.0)
    }

    /// JᵀΣJ for a Jacobian whose rows are x, y, z of each sample in order: per axis, Σ's
    /// entry for samples i and j of one piece is σ² ρ^|i−j|, for samples of two pieces
    /// zero (`follows` as [`Self::of`]'s). With the running sum fᵢ = Jᵢ + ρ fᵢ₋₁ (fᵢ =
    /// Jᵢ where a piece starts) and A = Σ Jᵢ fᵢᵀ (the pairs j ≤ i), it is σ² (A + Aᵀ −
    /// Σ JᵢJᵢᵀ): one pass over the rows.
    pub fn weighted_information(&self, jacobian: &DMatrix<f64>, follows: &[bool]) -> DMatrix<f64> {
        let (rows, n) = jacobian.shape();
        let samples = rows / 3;
        let mut information = DMatrix::zeros(n, n);
        for k in (0..3).filter(|&k| self.std_m_s[k] != 0.0) {
            let (variance, rho) = (self.std_m_s[k].powi(2), self.lag_one[k]);
            let mut running = DVector::<f64>::zeros(n);
            let mut pairs = DMatrix::<f64>::zeros(n, n);
            let mut diagonal = DMatrix::<f64>::zeros(n, n);
            for (i, &follows) in follows.iter().enumerate().take(samples) {
                let row = jacobian.row(3 * i + k).transpose();
                running *= if follows { rho } else { 0.0 };
                running += &row;
                pairs += &row * running.transpose();
                diagonal += &row * row.transpose();
            }
            information += variance * (&pairs + pairs.transpose() - diagonal);
        }
        information
    }
}

/// The scores' long-run covariance, Σᵢⱼ E[sᵢ sⱼᵀ] with sᵢ = Jᵢᵀ rᵢ the sample's
/// score (its three rows of the Jacobian times its residuals), by overlapping batch
/// means over windows of b = ⌈√n⌉ samples (Meketon and Schmeiser, 1984; Bartlett's
/// kernel in effect): whatever the correlation in time, up to b samples long, with no
/// model of it. In time linear in the samples, whatever b.
pub fn batch_means_information(jacobian: &DMatrix<f64>, residuals: &DVector<f64>) -> DMatrix<f64> {
    let (rows, n) = jacobian.shape();
    let samples = rows / 3;
    let score = |i: usize| {
        (0..3).fold(DVector::<f64>::zeros(n), |sum, k| {
            sum + jacobian.row(3 * i + k).transpose() * residuals[3 * i + k]
        })
    };
    let b = (samples as f64).sqrt().ceil() as usize;
    if samples <= b + 1 {
        return DMatrix::from_fn(n, n, |_, _| f64::INFINITY);
    }
    let mut window = DVector::<f64>::zeros(n);
    let mut sum = DMatrix::<f64>::zeros(n, n);
    for i in 0..samples {
        window += score(i);
        if i >= b {
            window -= score(i - b);
        }
        if i + 1 >= b {
            sum += &window * window.transpose();
        }
    }
    let (n_s, b_f) = (samples as f64, b as f64);
    let freedom = (3 * samples).saturating_sub(n).max(1) as f64;
    sum * (n_s * n_s / ((n_s - b_f) * (n_s - b_f + 1.0) * b_f)) * (3.0 * n_s / freedom)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_residuals_read_as_their_rms_and_no_correlation() {
        // ±1 alternating on x: lag-one correlation −1 (clamped), 2 on y constant: +1.
        let samples = 200;
        let residuals = DVector::from_fn(3 * samples, |r, _| match r % 3 {
            0 => {
                if (r / 3) % 2 == 0 {
                    1.0
                } else {
                    -1.0
                }
            }
            1 => 2.0,
            _ => 0.0,
        });
        let follows: Vec<bool> = (0..samples).map(|i| i > 0).collect();
        let noise = ResidualNoise::of(&residuals, 0, &follows);
        assert_eq!(noise.std_m_s, [1.0, 2.0, 0.0]);
        assert_eq!(noise.lag_one, [-MAX_LAG_ONE, MAX_LAG_ONE, 0.0]);
        // With 6 parameters fitted, the variance counts 3 · 200 − 6 degrees of freedom.
        let fitted = ResidualNoise::of(&residuals, 6, &follows);
        assert!((fitted.std_m_s[1] - 2.0 * (600.0f64 / 594.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn neighbours_are_not_read_across_a_gap() {
        // Pieces of two samples each, +1, +1, then −1, −1, and so on: within a piece
        // neighbours agree (each of the 100 pairs' products is 1, as each square),
        // across a gap they would disagree (99 more products of −1).
        let samples = 200;
        let residuals = DVector::from_fn(
            3 * samples,
            |r, _| if (r / 6) % 2 == 0 { 1.0 } else { -1.0 },
        );
        let in_pairs: Vec<bool> = (0..samples).map(|i| i % 2 == 1).collect();
        let bridged: Vec<bool> = (0..samples).map(|i| i > 0).collect();
        // Read 100/200 · 199/100 (the mean product over the mean square), clamped,
        // and 1/200, with its bias (1 + 3ρ)/n taken back.
        let expected = [MAX_LAG_ONE, 0.005 + 1.015 / 200.0];
        for (follows, expected) in [in_pairs, bridged].iter().zip(expected) {
            let noise = ResidualNoise::of(&residuals, 0, follows);
            assert!((noise.lag_one[0] - expected).abs() < 1e-12, "{noise:?}");
        }
    }

    #[test]
    fn the_weighted_information_is_the_dense_sum() {
        // A random-looking Jacobian of 3 columns over 40 samples, against the O(N²) sum,
        // with a gap before sample 25: no correlation across it.
        let samples = 40;
        let gap_before = 25;
        let follows: Vec<bool> = (0..samples).map(|i| i > 0 && i != gap_before).collect();
        let jacobian = DMatrix::from_fn(3 * samples, 3, |r, c| ((r * 7 + c * 13) as f64).sin());
        let noise = ResidualNoise {
            std_m_s: [0.5, 1.0, 2.0],
            lag_one: [0.8, 0.0, -0.3],
            samples,
            kept: [samples as f64; 3],
        };
        let fast = noise.weighted_information(&jacobian, &follows);
        let mut dense = DMatrix::<f64>::zeros(3, 3);
        for k in 0..3 {
            for i in 0..samples {
                for j in 0..samples {
                    if (i < gap_before) != (j < gap_before) {
                        continue;
                    }
                    let weight = noise.std_m_s[k].powi(2)
                        * noise.lag_one[k].powi((i as i32 - j as i32).abs());
                    dense += weight * jacobian.row(3 * i + k).transpose() * jacobian.row(3 * j + k);
                }
            }
        }
        assert!((fast - dense).abs().max() < 1e-9);
    }
}
