//! The standard deviations of a fit's terms, their correlation matrix, and the terms a
//! calibration window cannot show (a standard deviation beyond its tolerance, a pair
//! correlated beyond [`CORRELATION_LIMIT`], or a direction the residuals do not feel at
//! all).
//! In: a [`Fit`] (its Jacobian and residuals at the solution). Out: a [`TermBound`].
//!
//! Two standard deviations per term. The Fisher bound: white noise of standard
//! deviation σ on every component, σ² = σ_dvl² + σ_reference² (the specified noises),
//! gives the covariance σ²(JᵀJ)⁻¹, the best the window could do. The honest one: the
//! noise the residuals show ([`ResidualNoise`]: level and correlation in time, per axis)
//! gives the sandwich (JᵀJ)⁻¹ JᵀΣJ (JᵀJ)⁻¹, what this window did; the flags and the
//! correlations come from it. The inverse is taken on the information scaled to a
//! unit diagonal, by its eigenvalues: a direction whose eigenvalue is below
//! [`FLAT_EIGENVALUE`] times the largest is flat, and every term with a weight in it has
//! an infinite standard deviation and is flagged, naming the others that share it.

use crate::evaluate::statistics::student_t_975;
use crate::installation::estimate::fit::Fit;
use crate::installation::estimate::residual_noise::ResidualNoise;
use crate::installation::terms::PerKind;
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use std::fmt;

/// |correlation| beyond which two terms cannot be told apart.
pub const CORRELATION_LIMIT: f64 = 0.95;

/// An eigenvalue of the unit-diagonal information below this fraction of the largest
/// is a flat direction (the condition number of JᵀJ on A-KIT's straight segments is
/// about 1e6; this is far below anything real data gives).
pub const FLAT_EIGENVALUE: f64 = 1e-12;

/// A term's weight (in a unit eigenvector) above which a flat direction involves it.
const FLAT_WEIGHT: f64 = 0.01;

/// The white noise on each velocity component, m/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// The DVL's (A-KIT's is specified at 0.02 m/s).
    pub dvl_m_s: f64,
    /// The reference's body velocity.
    pub reference_m_s: f64,
}

impl Noise {
    /// The variance of the difference of the two on each component, (m/s)²: the DVL's
    /// and the reference's added.
    pub fn variance_m2_s2(&self) -> f64 {
        self.dvl_m_s.powi(2) + self.reference_m_s.powi(2)
    }

    /// The standard deviation of the difference of the two on each component, m/s:
    /// √(dvl² + reference²).
    pub fn per_axis_m_s(&self) -> f64 {
        self.variance_m2_s2().sqrt()
    }
}

/// The standard deviation beyond which a term means nothing, per kind of term.
pub type Tolerances = PerKind;

/// The tolerances by default. Each one is the uncertainty that makes about 1 cm/s of
/// velocity error (half A-KIT's specified DVL noise) on a vehicle at 2 m/s: a scale of
/// 0.5 % and a misalignment of 0.5° (0.0087 × 2 m/s = 1.7 cm/s) at 2 m/s; a lever arm
/// of 0.1 m at 6°/s of turn; a time offset of 0.05 s at 0.2 m/s² of acceleration (a
/// 15°/s turn at 2 m/s is 0.5 m/s²); a bias of 1 cm/s.
pub const DEFAULT_TOLERANCES: Tolerances = PerKind {
    scale: 0.005,
    // 0.5°, as `to_radians` computes it.
    misalignment_rad: 0.5 * (std::f64::consts::PI / 180.0),
    lever_arm_m: 0.1,
    time_offset_s: 0.05,
    bias_m_s: 0.01,
};

/// Why a term cannot be seen on a window.
#[derive(Debug, Clone, PartialEq)]
pub enum Why {
    /// Its standard deviation exceeds its tolerance.
    Uncertain { std: f64, tolerance: f64 },
    /// It is correlated beyond [`CORRELATION_LIMIT`] with another term.
    Correlated {
        with: &'static str,
        correlation: f64,
    },
    /// Moving it (with the others named, in some proportion) leaves the residuals
    /// unchanged.
    Flat { with: Vec<&'static str> },
    /// A term only turns show (the lever arm, the clock) fitted to position fixes over
    /// headings that span only `span_rad`.
    OneHeading { span_rad: f64 },
    /// The yaw fitted to position fixes over headings that span only `span_rad`: the
    /// DVL's yaw and the attitude's heading error at those headings, together.
    FewHeadings { span_rad: f64 },
    /// A time term (the clock, the fixes' latency) fitted to fixes ran to the edge of its
    /// search, ±`edge_s`, which lies within its 95 % interval of zero (its standard
    /// deviation `std_s` there): the fixes do not place it within the search.
    BeyondSearch { edge_s: f64, std_s: f64 },
}

impl Why {
    /// Whether the residuals do not depend on the term at all, alone: its value is
    /// noise, not the installation's.
    pub fn is_flat_alone(&self) -> bool {
        matches!(self, Why::Flat { with } if with.is_empty())
    }
}

impl fmt::Display for Why {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Why::Uncertain { std, tolerance } => {
                write!(
                    f,
                    "standard deviation {std:.3e} above its tolerance {tolerance:.3e}"
                )
            }
            Why::Correlated { with, correlation } => {
                write!(f, "correlated {correlation:+.3} with {with}")
            }
            Why::Flat { with } if with.is_empty() => {
                f.write_str("the residuals do not depend on it")
            }
            Why::Flat { with } => {
                write!(f, "flat together with {}", with.join(", "))
            }
            Why::OneHeading { span_rad } => write!(
                f,
                "the vehicle's heading spans {:.0}° only: the lever arm and the clock show only as it turns (at one heading they are a shift of the start)",
                span_rad.to_degrees()
            ),
            Why::FewHeadings { span_rad } => write!(
                f,
                "the vehicle's heading spans {:.0}° only: the yaw found is the DVL's and the attitude's heading error at these headings together, and holds at other headings only as far as that error is the same there",
                span_rad.to_degrees()
            ),
            Why::BeyondSearch { edge_s, std_s } => write!(
                f,
                "it ran to the edge of its search, ±{edge_s:.2} s, and its standard deviation there, {std_s:.2} s, puts that edge within its 95 % interval of zero: the fixes do not place it; held at zero, its uncertainty carried into the other terms' intervals"
            ),
        }
    }
}

/// A term a window cannot show, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Unseen {
    pub term: &'static str,
    pub why: Why,
}

/// The noise a fit's residuals showed, from which its standard deviations were read:
/// the quantile a 95 % interval takes in them.
pub trait ReadNoise {
    /// The degrees of freedom the noise's level was read with.
    fn freedom(&self) -> f64;

    /// The half-width of a 95 % interval in standard deviations, though the noise's
    /// level is itself estimated: Student's t₀.₉₇₅ on [`Self::freedom`].
    fn quantile_95(&self) -> f64 {
        student_t_975(self.freedom())
    }
}

impl ReadNoise for ResidualNoise {
    fn freedom(&self) -> f64 {
        ResidualNoise::freedom(self)
    }
}

/// The terms a fit found, in the order of its parameters, whichever reference it was
/// fitted to: each one's value, standard deviations and correlations, whether it is
/// applied, and why any is not seen; `N` the noise its standard deviations were read
/// from (the velocity residuals' [`ResidualNoise`] by default).
#[derive(Debug, Clone, PartialEq)]
pub struct TermBound<N = ResidualNoise> {
    pub names: Vec<&'static str>,
    pub value: Vec<f64>,
    /// Standard deviations under the noise the fit's residuals show, in each term's
    /// unit; infinite on a flat direction.
    pub std: Vec<f64>,
    /// The Fisher bound's: under the specified white noise.
    pub bound_std: Vec<f64>,
    /// Correlation coefficients of the estimates, `[term][term]`; NaN with a term of
    /// infinite std, or one not applied.
    pub correlation: Vec<Vec<f64>>,
    /// Every reason each term cannot be seen (a term may appear more than once), from
    /// `std` and `correlation`.
    pub unseen: Vec<Unseen>,
    /// Whether each term is applied: a term the residuals do not depend on at all (its
    /// value noise, not the installation's) is held at zero; one known loosely or tied
    /// to another is applied at its value, said to be seen poorly.
    pub applied: Vec<bool>,
    /// The noise the residuals show.
    pub residual_noise: N,
}

impl<N: ReadNoise> TermBound<N> {
    /// The half-width of the 95 % interval of term `k`: its standard deviation times
    /// Student's t on the degrees of freedom of the noise it was read from
    /// ([`ReadNoise::quantile_95`]), which a short window of correlated noise widens.
    pub fn half_width_95(&self, k: usize) -> f64 {
        self.residual_noise.quantile_95() * self.std[k]
    }

    /// Whether the window cannot show the term named `name`.
    pub fn is_unseen(&self, name: &str) -> bool {
        self.unseen.iter().any(|unseen| unseen.term == name)
    }

    /// The first `count` terms alone (a fit to fixes places the fixes' latency after
    /// the installation's terms).
    pub fn first(&self, count: usize) -> TermBound<N>
    where
        N: Clone,
    {
        let correlation = (self.correlation.iter().take(count))
            .map(|row| row[..count].to_vec())
            .collect();
        TermBound {
            names: self.names[..count].to_vec(),
            value: self.value[..count].to_vec(),
            std: self.std[..count].to_vec(),
            bound_std: self.bound_std[..count].to_vec(),
            correlation,
            unseen: (self.unseen.iter())
                .filter(|u| self.names[..count].contains(&u.term))
                .cloned()
                .collect(),
            applied: self.applied[..count].to_vec(),
            residual_noise: self.residual_noise.clone(),
        }
    }

    /// Whether the term named `name` is one of these and applied.
    pub fn is_applied(&self, name: &str) -> bool {
        let k = self.names.iter().position(|n| *n == name);
        k.is_some_and(|k| self.applied[k])
    }
}

/// The standard deviations of `fit`'s terms under the noise its residuals show and
/// under the specified `noise`, with the terms beyond `tolerances`.
pub fn bound(fit: &Fit, noise: Noise, tolerances: &Tolerances) -> TermBound {
    let names = fit.terms.parameter_names();
    let kinds = fit.terms.parameter_kinds();
    let sigma_m_s = noise.per_axis_m_s();
    let information = UnitInformation::of(fit, names.len());
    let (inverse, flat_with) = information.pseudo_inverse(&names);
    let residual_noise = fit
        .residual_noise()
        .counting_the_absorbed((&fit.curved(&fit.jacobian), &fit.follows), |weighted| {
            information.absorbed(&inverse, weighted)
        });
    let modelled = information.sandwich(
        &inverse,
        &residual_noise.weighted_information(&fit.jacobian, &fit.follows),
    );
    let unmodelled = information.sandwich(
        &inverse,
        &crate::installation::estimate::residual_noise::batch_means_information(
            &fit.jacobian,
            &fit.residuals,
        ),
    );
    let std: Vec<f64> = information
        .standard_deviations(&modelled, &flat_with)
        .into_iter()
        .zip(information.standard_deviations(&unmodelled, &flat_with))
        .map(|(modelled, unmodelled)| modelled.max(unmodelled))
        .collect();
    let bound_std = information.standard_deviations(&(sigma_m_s.powi(2) * &inverse), &flat_with);
    // Residuals of zero (a noise-free recording) leave the shape of the bound's.
    let shape = if residual_noise.std_m_s == [0.0; 3] {
        &inverse
    } else {
        &modelled
    };
    let correlation = information.correlations(shape, &std);
    let unseen = unseen(&names, &flat_with, &std, &correlation, |k| {
        tolerances.of(kinds[k])
    });
    let applied = names
        .iter()
        .map(|name| {
            !unseen
                .iter()
                .any(|u| u.term == *name && u.why.is_flat_alone())
        })
        .collect();
    TermBound {
        names,
        value: fit.parameters.clone(),
        std,
        bound_std,
        correlation,
        unseen,
        applied,
        residual_noise,
    }
}

/// −(JᵀDJ)⁺ Jᵀr of `fit` (its Jacobian, weights and residuals, pseudo-residuals under a
/// robust loss): the Gauss–Newton step, the inverse the bound's own, taken on the
/// information scaled to a unit diagonal over its directions above [`FLAT_EIGENVALUE`]
/// of the largest; no step along a flat direction, nor in a term the residuals ignore.
pub fn gauss_newton_step(fit: &Fit) -> DVector<f64> {
    let names = fit.terms.parameter_names();
    let gradient = fit.jacobian.transpose() * &fit.residuals;
    normal_step(&fit.information(), &gradient, &names)
}

/// −`normal`⁺ `gradient`: the Gauss–Newton step of parameters `names` whose information
/// is `normal` (JᵀJ, or JᵀDJ) and whose cost's half gradient is `gradient` (Jᵀr), the
/// inverse the bound's own ([`gauss_newton_step`]).
pub fn normal_step(
    normal: &DMatrix<f64>,
    gradient: &DVector<f64>,
    names: &[&'static str],
) -> DVector<f64> {
    let information = UnitInformation::of_normal(normal, names.len());
    let (inverse, _) = information.pseudo_inverse(names);
    let felt = &information.felt;
    let scale = &information.scale;
    let scaled = DVector::from_fn(felt.len(), |a, _| gradient[felt[a]] / scale[felt[a]]);
    let unit_step = -(inverse * scaled);
    let mut step = DVector::zeros(names.len());
    for (a, &k) in felt.iter().enumerate() {
        step[k] = unit_step[a] / scale[k];
    }
    step
}

/// Of estimates whose information is `normal` (JᵀΣ⁻¹J, the residuals whitened by their
/// noise Σ) and whose noise is `variance_factor` times Σ, the parameters named `names`:
/// each one's standard deviation (infinite on a flat direction), their correlations,
/// and every reason each cannot be seen, parameter k beyond `tolerance(k)`.
pub fn whitened_bound(
    normal: &DMatrix<f64>,
    names: &[&'static str],
    variance_factor: f64,
    tolerance: impl Fn(usize) -> f64,
) -> (Vec<f64>, Vec<Vec<f64>>, Vec<Unseen>) {
    let information = UnitInformation::of_normal(normal, names.len());
    let (inverse, flat_with) = information.pseudo_inverse(names);
    let covariance = variance_factor * &inverse;
    let std = information.standard_deviations(&covariance, &flat_with);
    let correlation = information.correlations(&inverse, &std);
    let unseen = unseen(names, &flat_with, &std, &correlation, tolerance);
    (std, correlation, unseen)
}

/// For each term, `Some(the others)` when it lies on a flat direction (a term the
/// residuals ignore is flat alone), `None` otherwise.
type FlatWith = Vec<Option<Vec<&'static str>>>;

/// The information JᵀJ scaled to a unit diagonal, D⁻¹ JᵀJ D⁻¹ with D = √diag(JᵀJ), over
/// the terms the residuals feel.
struct UnitInformation {
    /// √diag(JᵀJ), one per term.
    scale: Vec<f64>,
    /// The terms whose diagonal is not zero, in order.
    felt: Vec<usize>,
    /// `[felt, felt]`.
    unit: DMatrix<f64>,
}

impl UnitInformation {
    /// Of `fit`'s `n` terms.
    fn of(fit: &Fit, n: usize) -> UnitInformation {
        Self::of_normal(&fit.information(), n)
    }

    /// Of the information `normal` of `n` terms.
    fn of_normal(normal: &DMatrix<f64>, n: usize) -> UnitInformation {
        let scale: Vec<f64> = (0..n).map(|k| normal[(k, k)].sqrt()).collect();
        let felt: Vec<usize> = (0..n).filter(|&k| scale[k] > 0.0).collect();
        let unit = DMatrix::from_fn(felt.len(), felt.len(), |a, b| {
            normal[(felt[a], felt[b])] / (scale[felt[a]] * scale[felt[b]])
        });
        UnitInformation { scale, felt, unit }
    }

    /// Where term `k` is among the felt ones.
    fn position(&self, k: usize) -> Option<usize> {
        self.felt.iter().position(|&f| f == k)
    }

    /// The pseudo-inverse of the unit-diagonal matrix over its non-flat directions, and
    /// the terms on each flat one (`names` names the terms).
    fn pseudo_inverse(&self, names: &[&'static str]) -> (DMatrix<f64>, FlatWith) {
        let felt = &self.felt;
        let mut flat_with: FlatWith = (0..self.scale.len())
            .map(|k| (!felt.contains(&k)).then(Vec::new))
            .collect();
        let mut inverse = DMatrix::<f64>::zeros(felt.len(), felt.len());
        if felt.is_empty() {
            return (inverse, flat_with);
        }
        let eigen = SymmetricEigen::new(self.unit.clone());
        let largest = eigen.eigenvalues.max();
        for (index, &eigenvalue) in eigen.eigenvalues.iter().enumerate() {
            let vector = eigen.eigenvectors.column(index);
            if eigenvalue > FLAT_EIGENVALUE * largest {
                inverse += vector * vector.transpose() / eigenvalue;
                continue;
            }
            let involved: Vec<usize> = (0..felt.len())
                .filter(|&a| vector[a].abs() > FLAT_WEIGHT)
                .collect();
            for &a in &involved {
                let others = flat_with[felt[a]].get_or_insert_with(Vec::new);
                for &b in &involved {
                    if b != a && !others.contains(&names[felt[b]]) {
                        others.push(names[felt[b]]);
                    }
                }
            }
        }
        (inverse, flat_with)
    }

    /// The covariance, in the unit-diagonal scaling, of estimates whose information is
    /// `self` and whose noise weights it to `weighted` (JᵀΣJ over every term):
    /// `inverse` · D⁻¹ JᵀΣJ D⁻¹ · `inverse`.
    fn sandwich(&self, inverse: &DMatrix<f64>, weighted: &DMatrix<f64>) -> DMatrix<f64> {
        inverse * self.scaled(weighted) * inverse
    }

    /// tr((JᵀJ)⁻¹ M) over the felt terms, for an `M` over every term (JᵀRJ of a noise
    /// R): how much of that noise the fit absorbs, in samples.
    fn absorbed(&self, inverse: &DMatrix<f64>, weighted: &DMatrix<f64>) -> f64 {
        (inverse * self.scaled(weighted)).trace()
    }

    /// D⁻¹ M D⁻¹ over the felt terms, for an `M` over every term.
    fn scaled(&self, weighted: &DMatrix<f64>) -> DMatrix<f64> {
        let felt = &self.felt;
        DMatrix::from_fn(felt.len(), felt.len(), |a, b| {
            weighted[(felt[a], felt[b])] / (self.scale[felt[a]] * self.scale[felt[b]])
        })
    }

    /// Each term's standard deviation from `covariance` (in the unit-diagonal scaling):
    /// infinite on a flat direction.
    fn standard_deviations(&self, covariance: &DMatrix<f64>, flat_with: &FlatWith) -> Vec<f64> {
        (0..self.scale.len())
            .map(|k| match (self.position(k), &flat_with[k]) {
                (Some(a), None) => covariance[(a, a)].max(0.0).sqrt() / self.scale[k],
                _ => f64::INFINITY,
            })
            .collect()
    }

    /// The correlation of every pair of terms from `covariance` (in the unit-diagonal
    /// scaling): 1 on the diagonal, NaN with a term of infinite standard deviation.
    fn correlations(&self, covariance: &DMatrix<f64>, std: &[f64]) -> Vec<Vec<f64>> {
        let n = std.len();
        (0..n)
            .map(|j| {
                (0..n)
                    .map(|k| {
                        if j == k {
                            1.0
                        } else if !std[j].is_finite() || !std[k].is_finite() {
                            f64::NAN
                        } else {
                            let (a, b) = (self.position(j).unwrap(), self.position(k).unwrap());
                            covariance[(a, b)] / (covariance[(a, a)] * covariance[(b, b)]).sqrt()
                        }
                    })
                    .collect()
            })
            .collect()
    }
}

/// Every reason each term cannot be seen, term by term: on a flat direction; or a
/// standard deviation beyond its `tolerance`, and each term it is correlated with
/// beyond [`CORRELATION_LIMIT`].
fn unseen(
    names: &[&'static str],
    flat_with: &FlatWith,
    std: &[f64],
    correlation: &[Vec<f64>],
    tolerance: impl Fn(usize) -> f64,
) -> Vec<Unseen> {
    let n = names.len();
    let mut unseen = Vec::new();
    for k in 0..n {
        if let Some(with) = &flat_with[k] {
            unseen.push(Unseen {
                term: names[k],
                why: Why::Flat { with: with.clone() },
            });
            continue;
        }
        let tolerance = tolerance(k);
        if std[k] > tolerance {
            unseen.push(Unseen {
                term: names[k],
                why: Why::Uncertain {
                    std: std[k],
                    tolerance,
                },
            });
        }
        for j in 0..n {
            if j != k && correlation[k][j].abs() > CORRELATION_LIMIT {
                unseen.push(Unseen {
                    term: names[k],
                    why: Why::Correlated {
                        with: names[j],
                        correlation: correlation[k][j],
                    },
                });
            }
        }
    }
    unseen
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::installation::terms::{Installation, PerAxis, TermSet};

    /// A fit whose Jacobian is `columns` (each a column of residual derivatives), with
    /// residuals of zero.
    fn fit_with(terms: TermSet, columns: &[Vec<f64>]) -> Fit {
        fit_leaving(terms, columns, vec![0.0; columns[0].len()])
    }

    /// [`fit_with`], leaving `residuals`.
    fn fit_leaving(terms: TermSet, columns: &[Vec<f64>], residuals: Vec<f64>) -> Fit {
        let rows = columns[0].len();
        Fit {
            terms,
            installation: Installation::default(),
            parameters: vec![0.0; columns.len()],
            jacobian: DMatrix::from_fn(rows, columns.len(), |r, c| columns[c][r]),
            residuals: nalgebra::DVector::from_vec(residuals),
            robust: None,
            residual_rms_m_s: [0.0; 3],
            sample_count: rows / 3,
            mask_centre_s: Some(0.0),
            follows: (0..rows / 3).map(|i| i > 0).collect(),
            termination: "test".into(),
        }
    }

    const NOISE: Noise = Noise {
        dvl_m_s: 0.02,
        reference_m_s: 0.0,
    };

    #[test]
    fn a_bias_alone_has_the_noise_over_root_n() {
        // 300 samples, a bias on each axis: std = σ / √300.
        let terms = TermSet::of_error_model(crate::vocab::ErrorModel::Em4);
        let columns: Vec<Vec<f64>> = (0..3)
            .map(|axis| {
                (0..900)
                    .map(|row| if row % 3 == axis { -1.0 } else { 0.0 })
                    .collect()
            })
            .collect();
        let bound = bound(&fit_with(terms, &columns), NOISE, &DEFAULT_TOLERANCES);
        for std in &bound.bound_std {
            assert!((std - 0.02 / 300f64.sqrt()).abs() < 1e-15);
        }
        assert!(bound.unseen.is_empty());
        assert_eq!(bound.correlation[0][1], 0.0);
        // Both noises add in quadrature: 3 and 4 cm/s make 5.
        let both = Noise {
            dvl_m_s: 0.03,
            reference_m_s: 0.04,
        };
        let wider = super::bound(&fit_with(terms, &columns), both, &DEFAULT_TOLERANCES);
        assert!((wider.bound_std[0] - 0.05 / 300f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn a_scale_at_constant_speed_is_a_bias_and_both_are_flagged_as_one_flat_direction() {
        // x only: the scale's column is the speed (2 m/s everywhere), the bias's is 1.
        let terms = TermSet {
            scale: PerAxis::Scalar,
            bias: PerAxis::Scalar,
            ..TermSet::NONE
        };
        let columns = vec![vec![-2.0; 30], vec![-1.0; 30]];
        let bound = bound(&fit_with(terms, &columns), NOISE, &DEFAULT_TOLERANCES);
        assert!(bound.std.iter().all(|s| s.is_infinite()));
        assert_eq!(
            bound.unseen,
            vec![
                Unseen {
                    term: "scale",
                    why: Why::Flat {
                        with: vec!["bias_m_s"]
                    }
                },
                Unseen {
                    term: "bias_m_s",
                    why: Why::Flat {
                        with: vec!["scale"]
                    }
                },
            ]
        );
        assert!(bound.correlation[0][1].is_nan());
    }

    #[test]
    fn a_term_the_residuals_ignore_is_flat_and_a_near_copy_is_correlated() {
        let terms = TermSet {
            lever_arm: true,
            ..TermSet::NONE
        };
        // l_x moves nothing; l_y and l_z move nearly the same residuals.
        let ramp: Vec<f64> = (0..60).map(|i| (i as f64 * 0.37).sin()).collect();
        let near: Vec<f64> = ramp
            .iter()
            .enumerate()
            .map(|(i, v)| v + 0.05 * (i as f64).cos())
            .collect();
        let bound = bound(
            &fit_with(terms, &[vec![0.0; 60], ramp, near]),
            NOISE,
            &DEFAULT_TOLERANCES,
        );
        assert!(bound.std[0].is_infinite());
        assert_eq!(
            bound.unseen[0],
            Unseen {
                term: "lever_arm_x_m",
                why: Why::Flat { with: vec![] }
            }
        );
        // Columns alike make estimates that move against each other.
        assert!(bound.correlation[1][2] < -CORRELATION_LIMIT);
        assert!(bound.unseen.iter().any(|u| u.term == "lever_arm_y_m"
            && matches!(
                u.why,
                Why::Correlated {
                    with: "lever_arm_z_m",
                    ..
                }
            )));
        assert!(bound.is_unseen("lever_arm_z_m"));
    }

    /// Residuals that read as white: 1, 1, −1, −1, … times `level` on every axis (their
    /// lag-one correlation is about 1/n).
    fn white(samples: usize, level: f64) -> Vec<f64> {
        (0..3 * samples)
            .map(|r| level * if (r / 3) % 4 < 2 { 1.0 } else { -1.0 })
            .collect()
    }

    #[test]
    fn a_term_beyond_its_tolerance_is_flagged_with_its_honest_std() {
        // One time offset column, tiny, over 40 samples (120 rows), with residuals of
        // 2 cm/s: std ≈ 0.02 / (0.01 · √120) ≈ 0.18 s, the Fisher bound's at the
        // residuals' level.
        let terms = TermSet {
            time_offset: true,
            ..TermSet::NONE
        };
        let fit = fit_leaving(terms, &[vec![0.01; 120]], white(40, 0.02));
        let bound = bound(&fit, NOISE, &DEFAULT_TOLERANCES);
        let expected = 0.02 / (0.01 * 120f64.sqrt());
        assert!((bound.bound_std[0] - expected).abs() < 1e-12);
        assert!(
            (1.0..1.5).contains(&(bound.std[0] / expected)),
            "{}",
            bound.std[0]
        );
        assert_eq!(
            bound.unseen,
            vec![Unseen {
                term: "time_offset_s",
                why: Why::Uncertain {
                    std: bound.std[0],
                    tolerance: 0.05
                }
            }]
        );
        // The same column with no residual left: the honest std is zero, and seen.
        let exact = super::bound(
            &fit_with(terms, &[vec![0.01; 120]]),
            NOISE,
            &DEFAULT_TOLERANCES,
        );
        assert_eq!(exact.std, [0.0]);
        assert!(exact.unseen.is_empty());
    }

    /// Residuals correlated in time widen a bias's standard deviation by the AR(1)
    /// factor, √(Σᵢⱼ ρ^|i−j| / n), where the Fisher bound does not move; residuals at a
    /// tenth of the specified noise shrink it tenfold.
    #[test]
    fn correlated_residuals_widen_the_honest_std_and_the_bound_stays() {
        let terms = TermSet::of_error_model(crate::vocab::ErrorModel::Em4);
        let samples = 400;
        let columns: Vec<Vec<f64>> = (0..3)
            .map(|axis| {
                (0..3 * samples)
                    .map(|row| if row % 3 == axis { -1.0 } else { 0.0 })
                    .collect()
            })
            .collect();
        // An AR(1) path of correlation 0.8, the same on each axis.
        let mut path = vec![0.0; samples];
        for i in 0..samples {
            let shock = ((i * 7919) % 1000) as f64 / 1000.0 - 0.5;
            path[i] = shock + if i > 0 { 0.8 * path[i - 1] } else { 0.0 };
        }
        let residuals: Vec<f64> = (0..3 * samples).map(|r| path[r / 3]).collect();
        let fit = fit_leaving(terms, &columns, residuals.clone());
        let bound = bound(&fit, NOISE, &DEFAULT_TOLERANCES);
        let noise = fit.residual_noise();
        let rho = noise.lag_one[0];
        assert!((rho - 0.8).abs() < 0.1, "{rho}");
        let n = samples as f64;
        let sum: f64 = n + 2.0
            * (1..samples)
                .map(|l| (n - l as f64) * rho.powi(l as i32))
                .sum::<f64>();
        let expected = noise.std_m_s[0] * sum.sqrt() / n;
        // The AR(1) sandwich, or the batch means' where they read wider.
        for k in 0..3 {
            let ratio = bound.std[k] / expected;
            assert!(
                (1.0 - 1e-9..1.3).contains(&ratio),
                "{} against {expected}",
                bound.std[k]
            );
            assert!((bound.bound_std[k] - 0.02 / n.sqrt()).abs() < 1e-15);
        }
        assert!(
            bound.std[0] > 2.5 * noise.std_m_s[0] / n.sqrt(),
            "about 3 times wider"
        );

        let quiet = fit_leaving(terms, &columns, white(samples, 0.002));
        let quiet = super::bound(&quiet, NOISE, &DEFAULT_TOLERANCES);
        assert!(
            (quiet.std[0] / (quiet.bound_std[0] / 10.0) - 1.0).abs() < 0.05,
            "{}",
            quiet.std[0]
        );
    }
}
