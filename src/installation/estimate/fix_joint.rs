//! Several dives of one vehicle fitted to fixes, as one vehicle: each dive's own fit
//! ([`super::fixes`], its clock, its pieces' start positions, the noise its residuals
//! show and the fixes' latency its own) gives each vehicle term with its standard
//! deviation sₖ, the dive's clock profiled out. Each vehicle term is the dives'
//! estimates weighed by their information in it, θ̂ = Σ wₖ θₖ with wₖ = sₖ⁻² / Σ sⱼ⁻²,
//! its standard deviation (Σ sₖ⁻²)^(−1/2), over the dives that applied it; two terms'
//! covariance is Σ wₖ w′ₖ cov(θₖ, θ′ₖ). Term by term, not with each dive's whole
//! covariance: weighed by whole covariances, dives that disagree in one term pull
//! another through its correlations within a dive, beyond every dive's own value (on
//! A-KIT, the lever arm x of T3, T6 and T13 (−1.689, −1.691, −1.672 m) once combined to
//! −1.756 m, T13's terms tied at 0.99), and a straight dive that applied the scale
//! alone moved the lever arm; term by term, each lies within the dives' own estimates
//! and a dive moves only the terms it applied. A dive that saw few headings
//! ([`Why::FewHeadings`]) applies a yaw that is the DVL's and the attitude's heading
//! error there together, often tighter than a turning dive's (A-KIT's straight T12:
//! ±0.12° against ±0.25–0.32°): where any dive turned, that yaw is set aside, shown but
//! not weighed, as it would carry its headings' error to every other. Beside it, as for
//! a joint velocity calibration, each term's spread between dives
//! ([`super::between_dives`]).
//! In: each dive's [`FixFit`] and the dive's own terms. Out: a [`FixVehicle`].

use crate::installation::estimate::between_dives::{BetweenDives, between_dives};
use crate::installation::estimate::bound::Why;
use crate::installation::estimate::fixes::{FIX_LATENCY, FixFit};
use crate::installation::terms::{Installation, TermSet};

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
    /// Whether each dive's own estimate of each term is left out of the vehicle's,
    /// `[dive][term]`: a yaw seen over few headings where another dive turned.
    pub set_aside: Vec<Vec<bool>>,
    /// Each term's spread between the dives weighed; `None` where fewer than three show it.
    pub between: Vec<Option<BetweenDives>>,
}

impl FixVehicle {
    /// Dive `k`'s own estimate of term `i` where it is weighed in the vehicle's.
    pub fn weighed(&self, k: usize, i: usize) -> Option<(f64, f64)> {
        self.own[k][i].filter(|_| !self.set_aside[k][i])
    }

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
    let columns: Vec<usize> = (0..first.bound.names.len())
        .filter(|&k| first.estimated[k])
        .filter(|&k| first.bound.names[k] != FIX_LATENCY && !dive.contains(&first.bound.names[k]))
        .collect();
    let own: Vec<Vec<Option<(f64, f64)>>> = fits
        .iter()
        .map(|fit| {
            (columns.iter())
                .map(|&k| {
                    let shown = fit.bound.applied[k]
                        && fit.bound.std[k].is_finite()
                        && fit.bound.std[k] > 0.0;
                    shown.then_some((fit.bound.value[k], fit.bound.std[k]))
                })
                .collect()
        })
        .collect();
    let set_aside = set_aside(fits, &columns, &own);
    let weighed: Vec<Vec<Option<(f64, f64)>>> = (own.iter().zip(&set_aside))
        .map(|(dive, aside)| {
            (dive.iter().zip(aside))
                .map(|(estimate, &aside)| estimate.filter(|_| !aside))
                .collect()
        })
        .collect();
    let m = columns.len();
    // Each dive's weight in each term: its information in the term over the dives'.
    let information: Vec<f64> = (0..m)
        .map(|i| {
            weighed
                .iter()
                .filter_map(|d| d[i])
                .map(|(_, s)| 1.0 / (s * s))
                .sum()
        })
        .collect();
    let weight =
        |k: usize, i: usize| weighed[k][i].map_or(0.0, |(_, s)| 1.0 / (s * s) / information[i]);
    let applied: Vec<bool> = information.iter().map(|&i| i > 0.0).collect();
    let value: Vec<f64> = (0..m)
        .map(|i| {
            (0..fits.len())
                .filter_map(|k| weighed[k][i].map(|(y, _)| weight(k, i) * y))
                .sum()
        })
        .collect();
    let std: Vec<f64> = (information.iter())
        .map(|&i| {
            if i > 0.0 {
                1.0 / i.sqrt()
            } else {
                f64::INFINITY
            }
        })
        .collect();
    let correlation = correlation(fits, (&columns, &weighed), (&weight, &std));
    let between = (0..m)
        .map(|i| {
            let shown: Vec<(f64, f64)> = weighed.iter().filter_map(|dive| dive[i]).collect();
            between_dives(&shown)
        })
        .collect();
    FixVehicle {
        names: columns.iter().map(|&k| first.bound.names[k]).collect(),
        applied,
        value,
        std,
        correlation,
        own,
        set_aside,
        between,
    }
}

/// Which of the dives' `own` estimates of the parameters `columns` of `fits` are left
/// out of the vehicle's: a yaw seen over few headings, where some dive's yaw is seen
/// over a turn. Where no dive turned, every dive's yaw is weighed.
fn set_aside(
    fits: &[FixFit],
    columns: &[usize],
    own: &[Vec<Option<(f64, f64)>>],
) -> Vec<Vec<bool>> {
    let few_headings = |fit: &FixFit, k: usize| {
        let name = fit.bound.names[k];
        (fit.bound.unseen.iter())
            .any(|u| u.term == name && matches!(u.why, Why::FewHeadings { .. }))
    };
    let aside: Vec<Vec<bool>> = (fits.iter().zip(own))
        .map(|(fit, dive)| {
            (columns.iter().zip(dive))
                .map(|(&k, estimate)| estimate.is_some() && few_headings(fit, k))
                .collect()
        })
        .collect();
    let any_turned = |i: usize| (own.iter().zip(&aside)).any(|(d, a)| d[i].is_some() && !a[i]);
    (0..aside.len())
        .map(|k| {
            (0..columns.len())
                .map(|i| aside[k][i] && any_turned(i))
                .collect()
        })
        .collect()
}

/// The correlations of the vehicle's terms, each the weighed sum `weight(k, i)` over the
/// dives k of `fits` of their own `own` estimates of the parameters `columns`, whose
/// standard deviations are `std`: each dive's covariance of two terms, where it applied
/// both, times its two weights. NaN with a term no dive applied.
fn correlation(
    fits: &[FixFit],
    (columns, own): (&[usize], &[Vec<Option<(f64, f64)>>]),
    (weight, std): (&dyn Fn(usize, usize) -> f64, &[f64]),
) -> Vec<Vec<f64>> {
    let m = columns.len();
    let covariance = |i: usize, j: usize| -> f64 {
        (fits.iter().enumerate())
            .filter_map(|(k, fit)| {
                let ((_, si), (_, sj)) = (own[k][i]?, own[k][j]?);
                let c = match i == j {
                    true => 1.0,
                    false => fit.bound.correlation[columns[i]][columns[j]],
                };
                Some(weight(k, i) * weight(k, j) * si * sj * c)
            })
            .sum()
    };
    (0..m)
        .map(|i| {
            (0..m)
                .map(|j| match std[i].is_finite() && std[j].is_finite() {
                    true => covariance(i, j) / (std[i] * std[j]),
                    false => f64::NAN,
                })
                .collect()
        })
        .collect()
}
