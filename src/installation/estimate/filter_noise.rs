//! The noise the installation filter's samples show, read as the filter goes, and what
//! it costs the terms: per DVL axis, the level and the lag-one correlation (an AR(1),
//! as the batch fit's [`ResidualNoise`]) of the residuals of every sample so far at the
//! filter's current estimate, and JᵀΣJ under that noise, the middle of the filter's
//! sandwich covariance. Each sample enters, linearised about the estimate after its
//! update, as a pseudo-measurement y = H θ + noise (y the innovation plus H θ̂); the
//! sums of yᵀy, Hᵀy and HᵀH, and of their products with the previous sample's, give
//! the residuals' power and lag-one products at any θ without the samples themselves,
//! and running sums per correlation of a fixed grid give JᵀΣJ at any ρ. So the noise
//! read after n samples is the one a batch fit of them would read, in time independent
//! of n. The noise's own estimate is uncertain on a short record: the correlation is
//! averaged over its standard error and the level taken at its posterior mean. In: each
//! sample's rows and innovation at the updated estimate. Out: a [`ResidualNoise`] and
//! JᵀΣJ.

use crate::installation::estimate::residual_noise::{ResidualNoise, ResidualSums};
use nalgebra::{DMatrix, DVector};

/// How many samples of each axis the specified noise level counts as: a start before
/// the residuals have any, and nothing once they have a few.
pub const SPECIFIED_WEIGHT: f64 = 0.05;

/// The lag-one correlations at which JᵀΣJ is kept exactly; between two, it is
/// interpolated linearly in the AR(1)'s variance factor (1 + ρ) / (1 − ρ), a convex
/// combination of two covariances' middles and so one itself. Up to
/// [`MAX_LAG_ONE`](crate::installation::estimate::residual_noise::MAX_LAG_ONE), as the batch fit's.
const GRID: [f64; 14] = [
    -0.5, 0.0, 0.2, 0.4, 0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.93, 0.95, 0.97, 0.99,
];

/// One axis's sums over the pseudo-measurements so far.
#[derive(Debug, Clone)]
struct AxisSums {
    /// Per ρ of [`GRID`], the running sum fᵢ = Hᵢ + ρ fᵢ₋₁ (reset at a gap) and
    /// Σᵢ Hᵢ fᵢᵀ: Σᵢⱼ ρ^|i−j| Hᵢ Hⱼᵀ is that sum plus its transpose less Σᵢ Hᵢ Hᵢᵀ.
    running: Vec<(DVector<f64>, DMatrix<f64>)>,
    /// Σ HᵢᵀHᵢ, Σ Hᵢᵀ yᵢ and Σ yᵢ².
    squares: (DMatrix<f64>, DVector<f64>, f64),
    /// Σ HᵢᵀHᵢ₋₁, Σ (Hᵢᵀ yᵢ₋₁ + Hᵢ₋₁ᵀ yᵢ) and Σ yᵢ yᵢ₋₁ over neighbouring samples.
    products: (DMatrix<f64>, DVector<f64>, f64),
    /// The previous sample's row and y, while the next one is its neighbour.
    previous: Option<(DVector<f64>, f64)>,
}

/// The filter's running noise estimate.
#[derive(Debug, Clone)]
pub struct OnlineNoise {
    parameters: usize,
    specified_variance: f64,
    axes: [AxisSums; 3],
    samples: usize,
    /// How many samples followed a neighbour.
    pairs: usize,
}

impl OnlineNoise {
    /// No samples yet, `parameters` to be fitted, the noise specified as this variance
    /// per axis, m²/s².
    pub fn new(parameters: usize, specified_variance: f64) -> OnlineNoise {
        let empty = AxisSums {
            running: vec![
                (
                    DVector::zeros(parameters),
                    DMatrix::zeros(parameters, parameters)
                );
                GRID.len()
            ],
            squares: (
                DMatrix::zeros(parameters, parameters),
                DVector::zeros(parameters),
                0.0,
            ),
            products: (
                DMatrix::zeros(parameters, parameters),
                DVector::zeros(parameters),
                0.0,
            ),
            previous: None,
        };
        OnlineNoise {
            parameters,
            specified_variance,
            axes: [empty.clone(), empty.clone(), empty],
            samples: 0,
            pairs: 0,
        }
    }

    /// Adds a sample: its three rows and innovations linearised about `estimate`;
    /// `neighbour` is whether it follows the previous one within a piece (no gap).
    pub fn add(
        &mut self,
        rows: &[Vec<f64>],
        innovation: &[f64],
        estimate: &DVector<f64>,
        neighbour: bool,
    ) {
        if neighbour && self.samples > 0 {
            self.pairs += 1;
        }
        self.samples += 1;
        for (k, axis) in self.axes.iter_mut().enumerate() {
            let h = DVector::from_column_slice(&rows[k]);
            let y = innovation[k] + h.dot(estimate);
            axis.squares.0 += &h * h.transpose();
            axis.squares.1 += &h * y;
            axis.squares.2 += y * y;
            if let (true, Some((before, y_before))) = (neighbour, &axis.previous) {
                axis.products.0 += &h * before.transpose();
                axis.products.1 += &h * *y_before + before * y;
                axis.products.2 += y * y_before;
            }
            for ((running, pairs), rho) in axis.running.iter_mut().zip(GRID) {
                *running *= if neighbour { rho } else { 0.0 };
                *running += &h;
                *pairs += &h * running.transpose();
            }
            axis.previous = Some((h, y));
        }
    }

    /// Σ HᵀH over the samples so far and the three axes: the Fisher information of
    /// white noise of unit variance.
    pub fn gram(&self) -> DMatrix<f64> {
        self.axes.iter().map(|axis| &axis.squares.0).sum()
    }

    /// The noise of the residuals at `estimate`, and JᵀΣJ under it (Σ the AR(1) of each
    /// axis), for a filter whose covariance is `covariance` when its samples weigh
    /// 1 / `variance` each. The level counts what the terms took of the noise: a
    /// residual's expected power is σ² (n − tr(P JᵀΣ̃J) / r), Σ̃ the noise's correlation,
    /// so a correlated noise, which the terms follow more than a white one, is not read
    /// low; the specified level counts as [`SPECIFIED_WEIGHT`] samples of each axis.
    pub fn at(
        &self,
        estimate: &DVector<f64>,
        covariance: &DMatrix<f64>,
        variance: f64,
    ) -> (ResidualNoise, DMatrix<f64>) {
        let theta = estimate;
        let mut sums = ResidualSums {
            power: [0.0; 3],
            lagged: [0.0; 3],
            samples: self.samples,
            pairs: self.pairs,
        };
        for (k, axis) in self.axes.iter().enumerate() {
            let (a, b, c) = &axis.squares;
            sums.power[k] = (c - 2.0 * theta.dot(b) + theta.dot(&(a * theta))).max(0.0);
            let (a, b, c) = &axis.products;
            sums.lagged[k] = c - theta.dot(b) + theta.dot(&(a * theta));
        }
        let per_axis = self.parameters as f64 / 3.0;
        let mut noise = if self.samples as f64 >= per_axis + 3.0 {
            ResidualNoise::of_sums(&sums, self.parameters)
        } else {
            ResidualNoise {
                std_m_s: [0.0; 3],
                lag_one: [0.0; 3],
                samples: self.samples,
                kept: [1.0; 3],
            }
        };
        let n = self.parameters;
        let mut information = DMatrix::zeros(n, n);
        for (k, axis) in self.axes.iter().enumerate() {
            let rho = noise.lag_one[k];
            // The correlation's own uncertainty averaged over: JᵀΣ̃J at ρ̂ ± its standard
            // error, √((1 − ρ̂²) / n), by three-point Gauss–Hermite quadrature.
            let spread = ((1.0 - rho * rho) / (self.samples as f64 - per_axis).max(1.0)).sqrt();
            let correlated = [(-1.0, 1.0 / 6.0), (0.0, 2.0 / 3.0), (1.0, 1.0 / 6.0)]
                .iter()
                .map(|&(node, weight)| {
                    axis.correlated_information(rho + node * 3f64.sqrt() * spread) * weight
                })
                .fold(DMatrix::zeros(n, n), |sum, m| sum + m);
            let taken = (covariance * &correlated).trace() / variance;
            let freedom = (self.samples as f64 - taken).max(0.0);
            let level = (sums.power[k] + SPECIFIED_WEIGHT * self.specified_variance)
                / (freedom + SPECIFIED_WEIGHT);
            // The level's own uncertainty: its mean under the scaled inverse χ² of the
            // residuals' effective degrees of freedom.
            let effective = (freedom * (1.0 - rho * rho) / (1.0 + rho * rho)).max(3.0);
            let level = level * effective / (effective - 2.0);
            noise.std_m_s[k] = level.sqrt();
            information += correlated * level;
        }
        (noise, information)
    }
}

impl AxisSums {
    /// Σᵢⱼ ρ^|i−j| Hᵢ Hⱼᵀ, interpolated between the two nearest ρ of [`GRID`].
    fn correlated_information(&self, rho: f64) -> DMatrix<f64> {
        let factor = |rho: f64| (1.0 + rho) / (1.0 - rho);
        let rho = rho.clamp(GRID[0], GRID[GRID.len() - 1]);
        let upper = GRID.partition_point(|&g| g < rho).clamp(1, GRID.len() - 1);
        let (low, high) = (GRID[upper - 1], GRID[upper]);
        let share = (factor(rho) - factor(low)) / (factor(high) - factor(low));
        let middle = |g: usize| {
            let pairs = &self.running[g].1;
            pairs + pairs.transpose() - &self.squares.0
        };
        middle(upper - 1) * (1.0 - share) + middle(upper) * share
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The known answer: the residuals' power and lag-one products read from the sums
    /// at any θ are those of the samples themselves, and JᵀΣ̃J at a correlation of the
    /// grid is the dense double sum; a gap breaks the products.
    #[test]
    fn the_sums_give_the_residuals_and_the_correlated_information_of_the_samples() {
        let parameters = 2;
        let rows_of = |i: usize| -> Vec<Vec<f64>> {
            (0..3)
                .map(|k| vec![1.0, ((i * 3 + k) as f64 * 0.37).sin()])
                .collect()
        };
        let y_of = |i: usize, k: usize| ((i * 5 + k * 11) as f64 * 0.21).cos();
        let linearised_at = DVector::from_vec(vec![0.3, -0.2]);
        let mut online = OnlineNoise::new(parameters, 1e-4);
        let samples = 40;
        let gap_before = 25;
        for i in 0..samples {
            let rows = rows_of(i);
            // The innovation about `linearised_at` whose pseudo-measurement is y.
            let innovation: Vec<f64> = (0..3)
                .map(|k| y_of(i, k) - rows[k][0] * 0.3 + rows[k][1] * 0.2)
                .collect();
            online.add(&rows, &innovation, &linearised_at, i > 0 && i != gap_before);
        }
        let theta = DVector::from_vec(vec![0.1, 0.4]);
        let residual = |i: usize, k: usize| {
            let row = &rows_of(i)[k];
            y_of(i, k) - row[0] * theta[0] - row[1] * theta[1]
        };
        for (k, axis) in online.axes.iter().enumerate() {
            let (a, b, c) = &axis.squares;
            let power = c - 2.0 * theta.dot(b) + theta.dot(&(a * &theta));
            let direct: f64 = (0..samples).map(|i| residual(i, k).powi(2)).sum();
            assert!(
                (power - direct).abs() < 1e-10,
                "axis {k}: {power} vs {direct}"
            );
            let (a, b, c) = &axis.products;
            let lagged = c - theta.dot(b) + theta.dot(&(a * &theta));
            let direct: f64 = (1..samples)
                .filter(|&i| i != gap_before)
                .map(|i| residual(i, k) * residual(i - 1, k))
                .sum();
            assert!(
                (lagged - direct).abs() < 1e-10,
                "axis {k}: {lagged} vs {direct}"
            );
            let rho = 0.8;
            let fast = axis.correlated_information(rho);
            let mut dense = DMatrix::<f64>::zeros(parameters, parameters);
            for i in 0..samples {
                for j in 0..samples {
                    // No correlation across the gap.
                    if (i < gap_before) != (j < gap_before) {
                        continue;
                    }
                    let weight = rho.powi((i as i32 - j as i32).abs());
                    let (hi, hj) = (&rows_of(i)[k], &rows_of(j)[k]);
                    for a in 0..parameters {
                        for b in 0..parameters {
                            dense[(a, b)] += weight * hi[a] * hj[b];
                        }
                    }
                }
            }
            assert!((fast - dense).abs().max() < 1e-9, "axis {k}");
        }
    }
}
