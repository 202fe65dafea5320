//! The noise of a fit to position fixes, and its whitening in time linear in the fixes.
//! In: the fixes' times in one block (one piece of the DVL record, one axis), their
//! weights, a [`FixNoiseModel`]. Out: a [`Whitener`] that turns any column of that block
//! (residuals, a Jacobian's column) into one of independent unit-variance rows, the
//! log-determinant of the block's covariance, and each fix's standardised residual.
//!
//! A fix's residual on one axis (the dead reckoning less the fix, the piece's start
//! position aside) is the sum of three errors:
//! - the dead reckoning's: the DVL's noise summed over its samples, a random walk from
//!   the piece's start of variance q per second (q = σ_v² Δt for white DVL noise of
//!   σ_v per sample every Δt; a noise correlated in time walks further);
//! - the fix's own white error, σ_f² (over its weight under a robust loss);
//! - the fix's slowly wandering error (a USBL's sound-speed layers and multipath, a
//!   GNSS's): a first-order Gauss–Markov process of variance σ_w² and correlation time
//!   T, e^(−Δt/T) from one fix to the next.
//!
//! Each is a state of a Kalman filter over the block's fixes (the walk and the
//! wandering error; the white error is the observation's); its innovations divided by
//! their standard deviations are the residuals whitened by the inverse Cholesky factor
//! of their covariance, in O(n) time and memory for n fixes (where the covariance itself
//! is n × n), and the log-determinant is the sum of the innovations' log-variances. A
//! fix of weight zero (an outlier left out) is not observed: its whitened row is zero.

use std::ops::Range;

/// The noise of a fit to fixes on one axis: the fix's white variance σ_f², m²; the dead
/// reckoning's walk q, m²/s; the fixes' wandering error's variance σ_w², m², and its
/// correlation time T, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixNoiseModel {
    pub fix_m2: f64,
    pub walk_m2_s: f64,
    pub wander_m2: f64,
    pub wander_time_s: f64,
}

/// The noise the residuals of a fit to fixes showed: the shape they chose, the variance
/// factor of their whitened sum of squares, and its degrees of freedom n − p.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixResidualNoise {
    pub shape: NoiseShape,
    pub variance_factor: f64,
    pub freedom: usize,
}

/// Its degrees of freedom are n − p: the fixes' rows less the terms and starts fitted.
impl crate::installation::estimate::bound::ReadNoise for FixResidualNoise {
    fn freedom(&self) -> f64 {
        self.freedom as f64
    }
}

/// The shape of the noise of a fit to fixes, relative to the noises given: the dead
/// reckoning's walk in the white DVL noise's, and the fixes' wandering error's variance
/// in their white error's, with its correlation time. The residuals choose it among
/// [`NoiseShape::walks`], then [`NoiseShape::wanders`] (the variance factor scales the
/// whole).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseShape {
    pub walk_scale: f64,
    pub wander_ratio: f64,
    pub wander_time_s: f64,
}

/// The dead reckoning's walks considered, in the white DVL noise's: a DVL noise of
/// AR(1) correlation ρ from one sample to the next walks (1 + ρ)/(1 − ρ) times as far in
/// variance (9 at ρ = 0.8, 19 at 0.9, 39 at 0.95). None below the noise given, its
/// least: over a dive of minutes the residuals of fixes of decimetres read a walk
/// poorly, and a walk read at a sixteenth of the truth's once narrowed the scale's
/// interval to half its error's spread.
const WALK_SCALES: [f64; 8] = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0];

/// The fixes' wandering errors considered: variances in the white error's, and
/// correlation times, s (a USBL's sound-speed error changes over minutes, its multipath
/// over tens of seconds).
const WANDER_RATIOS: [f64; 3] = [0.5, 2.0, 8.0];
const WANDER_TIMES_S: [f64; 3] = [15.0, 60.0, 240.0];

impl NoiseShape {
    /// The noise as given: a white DVL noise's walk and white fixes.
    pub const GIVEN: NoiseShape = NoiseShape {
        walk_scale: 1.0,
        wander_ratio: 0.0,
        wander_time_s: 1.0,
    };

    /// The walks the residuals choose among, with white fixes.
    pub fn walks() -> Vec<NoiseShape> {
        (WALK_SCALES.iter())
            .map(|&walk_scale| NoiseShape {
                walk_scale,
                ..NoiseShape::GIVEN
            })
            .collect()
    }

    /// The wandering errors the residuals choose among, beside this shape's walk.
    pub fn wanders(&self) -> Vec<NoiseShape> {
        let mut shapes = Vec::new();
        for wander_ratio in WANDER_RATIOS {
            for wander_time_s in WANDER_TIMES_S {
                shapes.push(NoiseShape {
                    wander_ratio,
                    wander_time_s,
                    ..*self
                });
            }
        }
        shapes
    }

    /// How many of the noise's parameters this shape reads beyond the noise as given:
    /// the walk's level where not the given one, the wandering error's variance and
    /// time where there is one.
    pub fn parameters(&self) -> usize {
        2 * usize::from(self.wander_ratio > 0.0)
    }

    /// The noise of an axis whose fixes' white variance is `fix_m2`, m², the white DVL
    /// noise walking `walk_m2_s`, m²/s.
    pub fn model(&self, fix_m2: f64, walk_m2_s: f64) -> FixNoiseModel {
        FixNoiseModel {
            fix_m2,
            walk_m2_s: self.walk_scale * walk_m2_s,
            wander_m2: self.wander_ratio * fix_m2,
            wander_time_s: self.wander_time_s,
        }
    }
}

/// One fix's step of the filter: the wandering error's decay since the fix before, the
/// gain of its update, and its innovation's standard deviation (that of the whitening);
/// and the standard deviation of its residual alone at unit weight (the walk since the
/// piece's start, the wandering error and its own), that of its standardised residual.
/// An unobserved fix has no gain.
#[derive(Debug, Clone, Copy)]
struct Step {
    decay: f64,
    gain: Option<[f64; 2]>,
    innovation_std: f64,
    marginal_std: f64,
}

/// The whitening of one block of fixes.
#[derive(Debug, Clone)]
pub struct Whitener {
    steps: Vec<Step>,
    log_det: f64,
}

impl Whitener {
    /// Of the fixes at `time_s` in a piece that starts at `start_s`, each of its own
    /// `relative` white variance (in the model's: σ_f² r) and weighed by its `weights`
    /// (σ_f² r / w; zero: not observed), under `model`.
    pub fn new(
        model: &FixNoiseModel,
        start_s: f64,
        time_s: &[f64],
        (weights, relative): (&[f64], &[f64]),
    ) -> Whitener {
        // The state's covariance, [walk, wander]: the walk from the piece's start, the
        // wandering error at its stationary variance.
        let mut p = [[0.0; 2]; 2];
        p[1][1] = model.wander_m2;
        let (mut steps, mut log_det, mut before_s) =
            (Vec::with_capacity(time_s.len()), 0.0, start_s);
        for ((&t, &weight), &relative) in time_s.iter().zip(weights).zip(relative) {
            let fix_m2 = model.fix_m2 * relative;
            let dt = t - before_s;
            before_s = t;
            let decay = if model.wander_m2 > 0.0 {
                (-dt / model.wander_time_s).exp()
            } else {
                0.0
            };
            p[0][0] += model.walk_m2_s * dt;
            p[1][1] = decay * decay * p[1][1] + model.wander_m2 * (1.0 - decay * decay);
            p[0][1] *= decay;
            p[1][0] = p[0][1];
            let predicted = p[0][0] + 2.0 * p[0][1] + p[1][1];
            let marginal_m2 = model.walk_m2_s * (t - start_s) + model.wander_m2 + fix_m2;
            let marginal_std = marginal_m2.sqrt();
            if weight <= 0.0 {
                steps.push(Step {
                    decay,
                    gain: None,
                    innovation_std: f64::INFINITY,
                    marginal_std,
                });
                continue;
            }
            let variance = predicted + fix_m2 / weight;
            let gain = [
                (p[0][0] + p[0][1]) / variance,
                (p[1][0] + p[1][1]) / variance,
            ];
            for a in 0..2 {
                for b in 0..2 {
                    p[a][b] -= gain[a] * gain[b] * variance;
                }
            }
            log_det += variance.ln();
            steps.push(Step {
                decay,
                gain: Some(gain),
                innovation_std: variance.sqrt(),
                marginal_std,
            });
        }
        Whitener { steps, log_det }
    }

    /// The log-determinant of the block's covariance over the fixes observed.
    pub fn log_det(&self) -> f64 {
        self.log_det
    }

    /// `column` (one value per fix of the block) whitened: the innovations over their
    /// standard deviations; zero for a fix not observed.
    pub fn whiten(&self, column: &[f64]) -> Vec<f64> {
        self.filtered(column, |step, innovation| match step.gain {
            Some(_) => innovation / step.innovation_std,
            None => 0.0,
        })
    }

    /// Each fix's residual in `column` over its standard deviation at unit weight (the
    /// walk since the piece's start, the wandering error and its own): how far, in its
    /// own standard deviations, a fix lies from the dead reckoning.
    pub fn standardised(&self, column: &[f64]) -> Vec<f64> {
        (self.steps.iter().zip(column))
            .map(|(step, value)| value / step.marginal_std)
            .collect()
    }

    /// The filter run over `column`, each fix's innovation turned by `out`.
    fn filtered(&self, column: &[f64], out: impl Fn(&Step, f64) -> f64) -> Vec<f64> {
        let mut state = [0.0; 2];
        (self.steps.iter().zip(column))
            .map(|(step, &value)| {
                state[1] *= step.decay;
                let innovation = value - state[0] - state[1];
                if let Some(gain) = step.gain {
                    state[0] += gain[0] * innovation;
                    state[1] += gain[1] * innovation;
                }
                out(step, innovation)
            })
            .collect()
    }
}

/// The whitening of every block of a fit's residuals (a block: one piece, one axis, its
/// rows contiguous), each block's start position profiled out: a column whitened is
/// projected off its block's whitened column of ones, so that the terms are fitted with
/// each start at its best, the starts never estimated as parameters.
#[derive(Debug, Clone)]
pub struct Whitening {
    blocks: Vec<Block>,
    unit: f64,
}

/// One block: its rows, its whitener, and its whitened column of ones with its square.
#[derive(Debug, Clone)]
struct Block {
    rows: Range<usize>,
    whitener: Whitener,
    ones: Vec<f64>,
    ones_squared: f64,
}

impl Whitening {
    /// Of the blocks, each its rows and whitener, in order, whose variances are in
    /// `unit`² (a column is divided by it as it is whitened).
    pub fn new(blocks: impl IntoIterator<Item = (Range<usize>, Whitener)>, unit: f64) -> Whitening {
        let blocks = (blocks.into_iter())
            .map(|(rows, whitener)| {
                let ones = whitener.whiten(&vec![1.0; rows.len()]);
                let ones_squared = ones.iter().map(|o| o * o).sum();
                Block {
                    rows,
                    whitener,
                    ones,
                    ones_squared,
                }
            })
            .collect();
        Whitening { blocks, unit }
    }

    /// How many blocks have a row observed (a start position each).
    pub fn starts_fitted(&self) -> usize {
        self.blocks.iter().filter(|b| b.ones_squared > 0.0).count()
    }

    /// Each block's start that fits `column` (residuals before their starts) best:
    /// the one added to every row of it.
    pub fn starts(&self, column: &[f64]) -> Vec<f64> {
        (self.blocks.iter())
            .map(|block| {
                let whitened = block.whitener.whiten(&column[block.rows.clone()]);
                match block.ones_squared > 0.0 {
                    true => -dot(&block.ones, &whitened) / block.ones_squared,
                    false => 0.0,
                }
            })
            .collect()
    }

    /// `column` whitened, each block's start profiled out.
    pub fn whiten(&self, column: &[f64]) -> Vec<f64> {
        let mut out = Vec::with_capacity(column.len());
        for block in &self.blocks {
            let mut whitened = block.whitener.whiten(&column[block.rows.clone()]);
            for w in &mut whitened {
                *w /= self.unit;
            }
            if block.ones_squared > 0.0 {
                let along = dot(&block.ones, &whitened) / block.ones_squared;
                for (w, one) in whitened.iter_mut().zip(&block.ones) {
                    *w -= along * one;
                }
            }
            out.extend(whitened);
        }
        out
    }

    /// Each row's standardised residual ([`Whitener::standardised`]) of `column`
    /// (residuals with their starts).
    pub fn standardised(&self, column: &[f64]) -> Vec<f64> {
        (self.blocks.iter())
            .flat_map(|block| block.whitener.standardised(&column[block.rows.clone()]))
            .map(|u| u / self.unit)
            .collect()
    }

    /// The restricted log-likelihood of a fit whose whitened residuals' sum of squares
    /// is `squares` on `freedom` degrees of freedom (the rows observed less the starts
    /// and the terms fitted), `terms_log_det` the log-determinant of its terms' whitened
    /// information: the variance factor profiled out, and the starts and the terms
    /// restricted (what is left of the data once they are fitted, Patterson and
    /// Thompson's REML): −½ ((n − p) ln(r̃ᵀr̃ / (n − p)) + ln |Σ| + Σ ln 1ᵀΣ⁻¹1 + ln
    /// |J̃ᵀJ̃|). Restricted, the walk that the terms and the starts absorb weighs
    /// nothing: by likelihood alone, a scale takes up the walk along a transect, the
    /// residuals read a walk too small, and under a DVL noise of AR(1) 0.9 with fixes of
    /// 2 m the scale's interval covered 86.6 % (the walk read at the white noise's on 78
    /// dives of 284, where the truth's is 19 times it).
    pub fn restricted_log_likelihood(
        &self,
        squares: f64,
        freedom: usize,
        terms_log_det: f64,
    ) -> f64 {
        let n = freedom.max(1) as f64;
        let log_det: f64 = (self.blocks.iter())
            .map(|b| {
                b.whitener.log_det()
                    + if b.ones_squared > 0.0 {
                        b.ones_squared.ln()
                    } else {
                        0.0
                    }
            })
            .sum();
        -0.5 * (n * (squares / n).ln() + log_det + terms_log_det)
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// The covariance the filter whitens, written out: σ_f²/w on the diagonal, q · (the
    /// earlier time − start) and σ_w² e^(−|Δt|/T) everywhere.
    fn dense(model: &FixNoiseModel, start_s: f64, time_s: &[f64], weights: &[f64]) -> DMatrix<f64> {
        let n = time_s.len();
        DMatrix::from_fn(n, n, |a, b| {
            let own = if a == b {
                model.fix_m2 / weights[a]
            } else {
                0.0
            };
            let walk = model.walk_m2_s * (time_s[a].min(time_s[b]) - start_s);
            let wander =
                model.wander_m2 * (-(time_s[a] - time_s[b]).abs() / model.wander_time_s).exp();
            own + walk + wander
        })
    }

    #[test]
    fn the_filter_whitens_as_the_inverse_cholesky_factor_does() {
        let model = FixNoiseModel {
            fix_m2: 0.25,
            walk_m2_s: 0.004,
            wander_m2: 0.6,
            wander_time_s: 40.0,
        };
        let time_s: Vec<f64> = (0..40)
            .map(|i| 3.0 + 5.0 * i as f64 + (i % 3) as f64)
            .collect();
        let weights: Vec<f64> = (0..40)
            .map(|i| if i % 7 == 3 { 0.4 } else { 1.0 })
            .collect();
        let covariance = dense(&model, 0.0, &time_s, &weights);
        let cholesky = covariance.clone().cholesky().unwrap();
        let column: Vec<f64> = (0..40).map(|i| (i as f64 * 0.7).sin() * 3.0).collect();
        let expected = cholesky
            .l()
            .solve_lower_triangular(&DVector::from_vec(column.clone()))
            .unwrap();
        let whitener = Whitener::new(&model, 0.0, &time_s, (&weights, &vec![1.0; time_s.len()]));
        for (got, want) in whitener.whiten(&column).iter().zip(expected.iter()) {
            assert!((got - want).abs() < 1e-10, "{got} against {want}");
        }
        let log_det = 2.0 * cholesky.l().diagonal().iter().map(|d| d.ln()).sum::<f64>();
        assert!((whitener.log_det() - log_det).abs() < 1e-9);
    }

    #[test]
    fn a_fix_of_no_weight_is_left_out_as_if_it_were_not_there() {
        let model = FixNoiseModel {
            fix_m2: 1.0,
            walk_m2_s: 0.01,
            wander_m2: 0.0,
            wander_time_s: 1.0,
        };
        let time_s = [5.0, 10.0, 15.0, 20.0];
        let column = [1.0, 50.0, -0.5, 2.0];
        let with = Whitener::new(&model, 0.0, &time_s, (&[1.0, 0.0, 1.0, 1.0], &[1.0; 4]));
        let without = Whitener::new(&model, 0.0, &[5.0, 15.0, 20.0], (&[1.0; 3], &[1.0; 3]));
        let (a, b) = (with.whiten(&column), without.whiten(&[1.0, -0.5, 2.0]));
        assert_eq!(a[1], 0.0);
        for (x, y) in [a[0], a[2], a[3]].iter().zip(&b) {
            assert!((x - y).abs() < 1e-12);
        }
        assert!((with.log_det() - without.log_det()).abs() < 1e-12);
        // The outlier over its standard deviation: the walk's over 10 s and its own.
        let u = with.standardised(&column)[1];
        assert!(
            (u - 50.0 / (0.01f64 * 10.0 + 1.0).sqrt()).abs() < 1e-12,
            "{u}"
        );
    }

    /// A fix of its own variance (a covariance four times the noise's) whitens as a fix
    /// of a quarter the weight, and stands four times the variance from the track when
    /// standardised, whatever its weight: an outlier left out is judged by its own noise.
    #[test]
    fn a_fix_of_its_own_noise_is_weighed_and_standardised_by_it() {
        let model = FixNoiseModel {
            fix_m2: 0.25,
            walk_m2_s: 0.004,
            wander_m2: 0.3,
            wander_time_s: 30.0,
        };
        let time_s = [5.0, 10.0, 15.0, 20.0];
        let column = [1.0, 4.0, -0.5, 2.0];
        let own = Whitener::new(&model, 0.0, &time_s, (&[1.0; 4], &[1.0, 4.0, 1.0, 1.0]));
        let weighed = Whitener::new(&model, 0.0, &time_s, (&[1.0, 0.25, 1.0, 1.0], &[1.0; 4]));
        for (x, y) in own.whiten(&column).iter().zip(weighed.whiten(&column)) {
            assert!((x - y).abs() < 1e-12, "{x} against {y}");
        }
        assert!((own.log_det() - weighed.log_det()).abs() < 1e-12);
        let left_out = Whitener::new(
            &model,
            0.0,
            &time_s,
            (&[1.0, 0.0, 1.0, 1.0], &[1.0, 4.0, 1.0, 1.0]),
        );
        let marginal = (0.004f64 * 10.0 + 0.3 + 4.0 * 0.25).sqrt();
        for whitener in [&own, &left_out] {
            let u = whitener.standardised(&column)[1];
            assert!((u - 4.0 / marginal).abs() < 1e-12, "{u}");
        }
    }
}
