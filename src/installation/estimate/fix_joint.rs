//! Several dives of one vehicle fitted to fixes, as one vehicle: each dive's own fit
//! ([`super::fixes`], its clock, its pieces' start positions, the noise its residuals
//! show and the fixes' latency its own) gives the vehicle's terms with their
//! covariance, the dive's clock profiled out (the covariance's block of the vehicle's
//! terms). The vehicle's terms are the dives' estimates weighed by their information,
//! θ̂ = (Σ Pₖ⁻¹)⁻¹ Σ Pₖ⁻¹ θₖ with covariance (Σ Pₖ⁻¹)⁻¹: the joint least-squares
//! solution of the dives' fits wherever each is linear about its own estimate, a dive
//! weighing in only on the terms it applied. Beside it, as for a joint velocity
//! calibration, each term's spread between dives ([`super::between_dives`]).
//! In: each dive's [`FixFit`] and the dive's own terms. Out: a [`FixVehicle`].

use crate::installation::estimate::between_dives::{BetweenDives, between_dives};
use crate::installation::estimate::fixes::{FIX_LATENCY, FixFit};
use crate::installation::terms::{Installation, TermSet};
use nalgebra::{DMatrix, DVector};

/// The vehicle's terms over several dives fitted to fixes.
#[derive(Debug, Clone, PartialEq)]
pub struct FixVehicle {
    /// The vehicle's terms: each parameter the dives estimated, but the dive's own
    /// (its clock) and the fixes' latency.
    pub names: Vec<&'static str>,
    /// Whether any dive applied each term; one none applied is zero, its standard
    /// deviation infinite.
    pub applied: Vec<bool>,
    pub value: Vec<f64>,
    pub std: Vec<f64>,
    /// `[term][term]`; NaN with a term not applied.
    pub correlation: Vec<Vec<f64>>,
    /// Each dive's own estimate of each term and its standard deviation, `[dive][term]`,
    /// where the dive applied it.
    pub own: Vec<Vec<Option<(f64, f64)>>>,
    /// Each term's spread between the dives; `None` where fewer than three show it.
    pub between: Vec<Option<BetweenDives>>,
}

impl FixVehicle {
    /// The installation of `terms` at the vehicle's terms (each no dive applied at
    /// zero) with the clock `clock_s`.
    pub fn installation(&self, terms: &TermSet, clock_s: f64) -> Installation {
        let parameters: Vec<f64> = (terms.parameter_names().iter())
            .map(|name| match self.names.iter().position(|n| n == name) {
                Some(i) => self.value[i],
                None if *name == "time_offset_s" => clock_s,
                None => 0.0,
            })
            .collect();
        Installation::from_parameters(terms, &parameters)
    }
}

/// The vehicle's terms of `fits` (one per dive, each of the same terms), `dive` the
/// parameters that are each dive's own.
pub fn fix_vehicle(fits: &[FixFit], dive: &[&str]) -> FixVehicle {
    let first = &fits[0];
    let columns: Vec<usize> = (0..first.names.len())
        .filter(|&k| first.estimated[k])
        .filter(|&k| first.names[k] != FIX_LATENCY && !dive.contains(&first.names[k]))
        .collect();
    let own: Vec<Vec<Option<(f64, f64)>>> = fits
        .iter()
        .map(|fit| {
            (columns.iter())
                .map(|&k| {
                    let shown = fit.applied[k] && fit.std[k].is_finite();
                    shown.then_some((fit.value[k], fit.std[k]))
                })
                .collect()
        })
        .collect();
    let m = columns.len();
    let mut information: DMatrix<f64> = DMatrix::zeros(m, m);
    let mut weighed: DVector<f64> = DVector::zeros(m);
    for (fit, own) in fits.iter().zip(&own) {
        let shown: Vec<usize> = (0..m).filter(|&i| own[i].is_some()).collect();
        let Some(inverse) = covariance(fit, &columns, &shown).try_inverse() else {
            continue;
        };
        for (a, &i) in shown.iter().enumerate() {
            for (b, &j) in shown.iter().enumerate() {
                information[(i, j)] += inverse[(a, b)];
                weighed[i] += inverse[(a, b)] * fit.value[columns[j]];
            }
        }
    }
    let applied: Vec<bool> = (0..m).map(|i| information[(i, i)] > 0.0).collect();
    let kept: Vec<usize> = (0..m).filter(|&i| applied[i]).collect();
    let inverse = (information
        .select_rows(&kept)
        .select_columns(&kept)
        .try_inverse())
    .expect("a sum of the dives' information matrices, each positive definite");
    // Symmetric to the last digit, as a covariance is.
    let joint = (&inverse + inverse.transpose()) / 2.0;
    let (mut value, mut std) = (vec![0.0; m], vec![f64::INFINITY; m]);
    let mut correlation = vec![vec![f64::NAN; m]; m];
    for (a, &i) in kept.iter().enumerate() {
        value[i] = (0..kept.len())
            .map(|b| joint[(a, b)] * weighed[kept[b]])
            .sum();
        std[i] = joint[(a, a)].sqrt();
        for (b, &j) in kept.iter().enumerate() {
            correlation[i][j] = joint[(a, b)] / (joint[(a, a)] * joint[(b, b)]).sqrt();
        }
    }
    let between = (0..m)
        .map(|i| {
            let shown: Vec<(f64, f64)> = own.iter().filter_map(|dive| dive[i]).collect();
            between_dives(&shown)
        })
        .collect();
    FixVehicle {
        names: columns.iter().map(|&k| first.names[k]).collect(),
        applied,
        value,
        std,
        correlation,
        own,
        between,
    }
}

/// The covariance of `fit`'s parameters `columns[shown]`, from their standard
/// deviations and correlations.
fn covariance(fit: &FixFit, columns: &[usize], shown: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(shown.len(), shown.len(), |a, b| {
        let (i, j) = (columns[shown[a]], columns[shown[b]]);
        let correlation = if i == j { 1.0 } else { fit.correlation[i][j] };
        fit.std[i] * fit.std[j] * correlation
    })
}
