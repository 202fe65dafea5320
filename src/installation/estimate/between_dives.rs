//! How far a vehicle's terms move from one dive to the next. A joint calibration shares
//! the vehicle's terms over K dives, but a dive's own terms differ from the vehicle's by
//! more than its noise: the lever arm absorbs what the model leaves out of that dive, a
//! DVL's bias moves between dives. Each term is read as a random-effects model over the
//! dives' own estimates y_k with their standard deviations s_k: y_k = μ + u_k + e_k,
//! u_k ~ N(0, τ²) the dive's own departure, e_k ~ N(0, s_k²) its noise.
//!
//! - τ² by Paule and Mandel's method of moments: the τ² at which the weighted spread
//!   Q(τ²) = Σ w_k (y_k − μ̂)², w_k = 1 / (s_k² + τ²), is K − 1 (zero where Q(0) is
//!   below it already). With few dives it is the estimator recommended over
//!   DerSimonian–Laird's (Veroniki et al., *Research Synthesis Methods* 7, 2016).
//! - The vehicle's term μ̂ = Σ w_k y_k / Σ w_k, its standard error Hartung and Knapp's,
//!   √(q / Σ w_k) with q = Q(τ̂²) / (K − 1), and its 95 % interval ±t₀.₉₇₅(K − 1) of it.
//! - The next dive's own estimate, a dive like these: μ̂ ± t₀.₉₇₅(K − 1) ·
//!   √(q (1 / Σ w_k + τ̂² + s̄²)), s̄² the mean of the s_k²: its own departure, its own
//!   noise and the mean's error. With equal s_k this is the exact prediction interval of a normal
//!   sample, ȳ ± t S √(1 + 1/K).
//!
//! Both intervals are checked by coverage tests on synthetic dives with a known truth
//! (`tests/installation/between_dives.rs`). In: each dive's own estimate of one term.
//! Out: a [`BetweenDives`], or nothing where fewer than [`MIN_DIVES`] dives show it.

use crate::evaluate::statistics::student_t_975;

/// The fewest dives whose spread is estimated: two dives give one degree of freedom
/// for the mean and the spread together.
pub const MIN_DIVES: usize = 3;

/// One vehicle term over the dives of a joint calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BetweenDives {
    /// The dives whose own estimate of the term has a finite standard deviation.
    pub dives: usize,
    /// τ̂, the standard deviation of the term from one dive to the next, beyond the
    /// dives' noise, in the term's unit.
    pub std: f64,
    /// μ̂ and its standard error under the random-effects model.
    pub mean: f64,
    pub mean_std: f64,
    /// t₀.₉₇₅(K − 1).
    pub quantile: f64,
    /// The half-width of the 95 % interval of a next dive's own estimate, about μ̂.
    pub next_dive_half_width: f64,
}

impl BetweenDives {
    /// The 95 % interval of the vehicle's term (the mean over dives).
    pub fn vehicle_95(&self) -> (f64, f64) {
        let half = self.quantile * self.mean_std;
        (self.mean - half, self.mean + half)
    }

    /// The 95 % interval a next dive's own estimate of the term falls in.
    pub fn next_dive_95(&self) -> (f64, f64) {
        (
            self.mean - self.next_dive_half_width,
            self.mean + self.next_dive_half_width,
        )
    }
}

/// The spread of one term over dives whose own estimates are `own`, (value, standard
/// deviation) each; dives with a standard deviation that is not finite and positive (a
/// dive that cannot show the term, or a noise-free one that weighs without bound) are
/// left out. `None` where fewer than [`MIN_DIVES`] remain.
pub fn between_dives(own: &[(f64, f64)]) -> Option<BetweenDives> {
    let shown: Vec<(f64, f64)> = own
        .iter()
        .filter(|(value, std)| value.is_finite() && std.is_finite() && *std > 0.0)
        .map(|&(value, std)| (value, std * std))
        .collect();
    let k = shown.len();
    if k < MIN_DIVES {
        return None;
    }
    let freedom = (k - 1) as f64;
    let tau2 = paule_mandel(&shown, freedom);
    let (mean, weight, spread) = weighted(&shown, tau2);
    let q = spread / freedom;
    let mean_variance = q / weight;
    let own_variance = shown.iter().map(|(_, v)| v).sum::<f64>() / k as f64;
    let quantile = student_t_975(freedom);
    Some(BetweenDives {
        dives: k,
        std: tau2.sqrt(),
        mean,
        mean_std: mean_variance.sqrt(),
        quantile,
        next_dive_half_width: quantile * (q * (1.0 / weight + tau2 + own_variance)).sqrt(),
    })
}

/// At between-dive variance `tau2`, over (value, variance) pairs: the weighted mean,
/// the sum of the weights, and the weighted spread Q.
fn weighted(shown: &[(f64, f64)], tau2: f64) -> (f64, f64, f64) {
    let weights: Vec<f64> = shown.iter().map(|(_, v)| 1.0 / (v + tau2)).collect();
    let total: f64 = weights.iter().sum();
    let mean = shown
        .iter()
        .zip(&weights)
        .map(|((y, _), w)| w * y)
        .sum::<f64>()
        / total;
    let spread = (shown.iter().zip(&weights))
        .map(|((y, _), w)| w * (y - mean).powi(2))
        .sum();
    (mean, total, spread)
}

/// The τ² ≥ 0 at which the weighted spread Q(τ²) is `freedom` (Q falls as τ² grows),
/// by bisection to a relative 1e-12; zero where Q(0) is not above it.
fn paule_mandel(shown: &[(f64, f64)], freedom: f64) -> f64 {
    let spread_at = |tau2: f64| weighted(shown, tau2).2;
    if spread_at(0.0) <= freedom {
        return 0.0;
    }
    // Q(τ²) < K·(largest squared departure)/τ², so this bracket holds the root.
    let (lowest, highest) = shown
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), (y, _)| {
            (l.min(*y), h.max(*y))
        });
    let (mut low, mut high) = (0.0, (highest - lowest).powi(2) * shown.len() as f64);
    while high - low > 1e-12 * high {
        let middle = 0.5 * (low + high);
        if spread_at(middle) > freedom {
            low = middle;
        } else {
            high = middle;
        }
    }
    0.5 * (low + high)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dives_that_agree_within_their_noise_show_no_spread() {
        // Three dives a tenth of their deviation apart: Q(0) is far below 2.
        let found = between_dives(&[(1.0, 1.0), (1.1, 1.0), (0.9, 1.0)]).unwrap();
        assert_eq!(found.std, 0.0);
        assert!((found.mean - 1.0).abs() < 1e-12);
        // q = Q(0) / 2 = 0.02 / 2 scales the mean's variance 1/3.
        assert!((found.mean_std - (0.01f64 / 3.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn equal_deviations_give_the_normal_samples_prediction_interval() {
        // With equal s_k and a spread above them, the next dive's interval is
        // ȳ ± t(K − 1) S √(1 + 1/K), S the sample standard deviation of the y_k.
        let values = [0.0, 3.0, 1.0, 6.0, 2.0];
        let own: Vec<(f64, f64)> = values.iter().map(|&y| (y, 0.5)).collect();
        let found = between_dives(&own).unwrap();
        let k = values.len() as f64;
        let mean = values.iter().sum::<f64>() / k;
        let sample = (values.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / (k - 1.0)).sqrt();
        assert!((found.mean - mean).abs() < 1e-9);
        assert!((found.std - (sample * sample - 0.25).sqrt()).abs() < 1e-6);
        let t4 = 2.776_445_105_197_793;
        assert!((found.quantile - t4).abs() < 1e-9);
        let expected = t4 * sample * (1.0 + 1.0 / k).sqrt();
        assert!(
            (found.next_dive_half_width - expected).abs() < 1e-6,
            "{found:?}"
        );
        assert!((found.mean_std - sample / k.sqrt()).abs() < 1e-6);
    }

    #[test]
    fn a_dive_that_cannot_show_the_term_is_left_out_and_two_are_too_few() {
        let own = [(1.0, 0.1), (1.2, f64::INFINITY), (0.8, 0.1)];
        assert_eq!(between_dives(&own), None);
        let more = [(1.0, 0.1), (1.2, f64::INFINITY), (0.8, 0.1), (1.1, 0.1)];
        assert_eq!(between_dives(&more).unwrap().dives, 3);
    }
}
