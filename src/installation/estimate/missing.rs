//! Whether the residuals of a fit still follow a term it left out: for each kind of
//! term the fitted set leaves out (scale, misalignment, lever arm, time offset, bias),
//! the score (Lagrange multiplier) test of adding it, under the noise the residuals
//! show. A term the data ask for and the model lacks is absorbed by the terms it has
//! (a bias takes up a scale × speed it cannot tell from it on a window of near constant
//! speed), which their intervals cannot show. In: a fit, its record and reference, the
//! residuals' noise. Out: the kinds the data ask for, with their statistic.
//!
//! With J the fit's Jacobian, r its residuals and J_a the left-out term's columns at the
//! estimate, the score is s = J_aᵀ r (Jᵀ r = 0 at the solution) and its covariance under
//! the noise Σ is J̃_aᵀ Σ J̃_a, J̃_a = J_a − J (JᵀJ)⁺ Jᵀ J_a the part of J_a the fitted
//! terms cannot move; sᵀ (J̃_aᵀ Σ J̃_a)⁺ s is χ² with as many degrees of freedom as
//! columns (Breusch and Pagan, 1980; Engle, 1984).

use crate::Vec3;
use crate::installation::estimate::fit::{Fit, jacobian_at};
use crate::installation::estimate::residual_noise::ResidualNoise;
use crate::installation::frames::Reference;
use crate::installation::terms::{PerAxis, TermSet};
use nalgebra::DMatrix;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// The p-value below which a left-out term is asked for.
pub const ASKED_P_VALUE: f64 = 1e-3;

/// A kind of term the residuals of a fit follow though the fit left it out.
#[derive(Debug, Clone, PartialEq)]
pub struct Asked {
    /// As a spec names it: `scale`, `misalignment`, `lever_arm`, `time_offset`, `bias`.
    pub term: &'static str,
    /// The score test's χ².
    pub statistic: f64,
    pub freedom: usize,
    pub p_value: f64,
}

/// The kinds of term `fit` left out whose score test rejects their absence at
/// [`ASKED_P_VALUE`], in the order scale, misalignment, lever arm, time offset, bias.
pub fn asked_for(
    fit: &Fit,
    (time_s, dvl_m_s): (&[f64], &[Vec3]),
    reference: &Reference,
    noise: &ResidualNoise,
) -> Vec<Asked> {
    let fitted_names = fit.terms.parameter_names();
    let normal = fit.information();
    let size = normal.nrows();
    let inverse = normal
        .clone()
        .pseudo_inverse(1e-12 * normal.norm())
        .unwrap_or_else(|_| DMatrix::zeros(size, size));
    left_out(fit.terms)
        .into_iter()
        .filter_map(|(term, extended)| {
            let centre_s = fit.mask_centre_s.unwrap_or(0.0);
            let full = jacobian_at(
                (time_s, dvl_m_s),
                reference,
                extended,
                fit.installation,
                centre_s,
            );
            let added: Vec<usize> = extended
                .parameter_names()
                .iter()
                .enumerate()
                .filter(|(_, name)| !fitted_names.contains(name))
                .map(|(k, _)| k)
                .collect();
            let columns = DMatrix::from_fn(full.nrows(), added.len(), |r, c| full[(r, added[c])]);
            let (statistic, p_value) = score_test(fit, &columns, &inverse, noise)?;
            (p_value < ASKED_P_VALUE).then_some(Asked {
                term,
                statistic,
                freedom: added.len(),
                p_value,
            })
        })
        .collect()
}

/// Each kind of term `terms` leaves out, named as a spec names it, with `terms` and it.
fn left_out(terms: TermSet) -> Vec<(&'static str, TermSet)> {
    let mut kinds = Vec::new();
    if terms.scale == PerAxis::Off {
        kinds.push((
            "scale",
            TermSet {
                scale: PerAxis::Scalar,
                ..terms
            },
        ));
    }
    if !terms.misalignment {
        kinds.push((
            "misalignment",
            TermSet {
                misalignment: true,
                ..terms
            },
        ));
    }
    if !terms.lever_arm {
        kinds.push((
            "lever_arm",
            TermSet {
                lever_arm: true,
                ..terms
            },
        ));
    }
    if !terms.time_offset {
        kinds.push((
            "time_offset",
            TermSet {
                time_offset: true,
                ..terms
            },
        ));
    }
    if terms.bias == PerAxis::Off {
        kinds.push((
            "bias",
            TermSet {
                bias: PerAxis::PerAxis,
                ..terms
            },
        ));
    }
    kinds
}

/// The score test of adding `columns` to `fit` (whose (JᵀDJ)⁺ is `inverse`, D its
/// robust loss's curvature) under `noise`: its χ² and p-value; `None` where their
/// covariance cannot be inverted. The columns are taken apart from the fitted ones by
/// the D-weighted projection, the score from the fit's (pseudo-)residuals.
fn score_test(
    fit: &Fit,
    columns: &DMatrix<f64>,
    inverse: &DMatrix<f64>,
    noise: &ResidualNoise,
) -> Option<(f64, f64)> {
    let apart = if fit.jacobian.ncols() == 0 {
        columns.clone()
    } else {
        columns - &fit.jacobian * (inverse * (fit.jacobian.transpose() * fit.curved(columns)))
    };
    let score = columns.transpose() * &fit.residuals;
    let covariance = noise.weighted_information(&apart, &fit.follows);
    let tolerance = 1e-12 * covariance.norm().max(f64::MIN_POSITIVE);
    let spread = covariance.pseudo_inverse(tolerance).ok()?;
    let statistic = (score.transpose() * spread * &score)[(0, 0)];
    let p_value = ChiSquared::new(columns.ncols() as f64)
        .map(|chi| 1.0 - chi.cdf(statistic))
        .unwrap_or(f64::NAN);
    Some((statistic, p_value))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::installation::estimate::filter::tests::weaving_segment;
    use crate::installation::estimate::fit::fit;
    use crate::installation::terms::Installation;

    /// A DVL with a 2 % scale fitted without one: its bias takes up what it can, and the
    /// score test asks for the scale; fitted with it, nothing is asked for.
    #[test]
    fn a_scale_left_out_is_asked_for_and_none_once_fitted() {
        let truth = Installation {
            scale: [0.02; 3],
            lever_arm_m: [-1.9, 0.05, 0.4],
            time_offset_s: 0.6,
            bias_m_s: [0.01, -0.005, 0.003],
            ..Installation::default()
        };
        let (time_s, dvl, reference) = weaving_segment(&truth, 0.01, 3);
        let without = TermSet {
            lever_arm: true,
            time_offset: true,
            bias: PerAxis::PerAxis,
            ..TermSet::NONE
        };
        let fitted = fit(&time_s, &dvl, &reference, without).unwrap();
        let noise = fitted.residual_noise();
        let asked = asked_for(&fitted, (&time_s, &dvl), &reference, &noise);
        assert_eq!(
            asked.iter().map(|a| a.term).collect::<Vec<_>>(),
            ["scale"],
            "{asked:?}"
        );
        let with = TermSet {
            scale: PerAxis::Scalar,
            ..without
        };
        let fitted = fit(&time_s, &dvl, &reference, with).unwrap();
        let noise = fitted.residual_noise();
        let asked = asked_for(&fitted, (&time_s, &dvl), &reference, &noise);
        assert!(asked.is_empty(), "{asked:?}");
    }
}
