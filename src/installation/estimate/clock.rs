//! A dive's clock found again. The geometry of an installation (scale, misalignment,
//! lever arm, and the bias where it is carried) belongs to the vehicle; its time offset,
//! and the bias where the spec says so, belong to the dive: the DVL's and the
//! reference's clocks are set again between dives. On a dive, the carried terms are
//! held and the dive's terms are estimated from its first w seconds:
//! 1. τ from a search over ± a search range (30 s by default), on a grid finer than
//!    half a sample: the carried installation's prediction from the reference at t + τ
//!    against the DVL ([`search_offset`]). The speed alone, which needs no geometry,
//!    does not do: most A-KIT segments hold their speed within 1–4 cm/s, and their
//!    clock shows only in the turns, through the lever arm;
//! 2. the least squares of the dive's terms with the carried ones held
//!    ([`fit_about`]), from its scan of τ ± 3 s about the search's; a window whose DVL
//!    moves no more than the noise of the fit's residuals is refused (no clock to show);
//! 3. their standard deviations from the bound, given the carried terms, plus what the
//!    carried terms' own uncertainty passes on to them ([`Carried`]); and a flag where
//!    the window cannot show τ (constant speed, no turn).
//!
//! In: the dive's first w seconds, its reference, the carried installation. Out: a
//! [`Clock`], or why the window cannot show it ([`ClockError`]).

use crate::Vec3;
use crate::data::paired::sample_interval;
use crate::installation::estimate::bound::{Noise, ReadNoise, TermBound, Tolerances, bound};
use crate::installation::estimate::fit::{
    Fit, FitError, TIME_OFFSET_MARGIN_S, TIME_OFFSET_SCAN_STEP_S, fit_about, linearised, mask_about,
};
use crate::installation::frames::Reference;
use crate::installation::terms::{Installation, PerAxis, TermSet};
use nalgebra::DMatrix;

/// How far the search looks for τ by default, s: a dive whose clocks are 5 or 20 s
/// apart is found.
pub const DEFAULT_SEARCH_S: f64 = 30.0;

/// The widest search `correct` takes, s: an hour.
pub const MAX_SEARCH_S: f64 = 3_600.0;

/// The smallest share of the window's samples whose t + τ must lie inside the reference
/// for a step of the search to count.
const SEARCH_COVERAGE: f64 = 0.5;

/// What a dive's clock is re-found from: which terms belong to the dive (τ always,
/// a bias where the spec says so), and how far the search looks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClockSearch {
    pub dive_terms: TermSet,
    pub search_s: f64,
}

/// The terms a dive carries: their values, and where they were estimated their
/// covariance (over the parameters of `terms`, in its order), which the dive's terms
/// found again inherit through the samples that find them.
#[derive(Debug, Clone, PartialEq)]
pub struct Carried {
    pub installation: Installation,
    pub uncertainty: Option<(TermSet, DMatrix<f64>)>,
}

impl Carried {
    /// Terms known exactly, or whose uncertainty is not known.
    pub fn exact(installation: Installation) -> Carried {
        Carried {
            installation,
            uncertainty: None,
        }
    }

    /// Terms with the standard deviations and correlations of `names` (those of
    /// `terms`, in order); a standard deviation that is not finite (a term its
    /// calibration could not see at all, left out of the correction) counts as zero.
    pub fn with(
        installation: Installation,
        terms: TermSet,
        std: &[f64],
        correlation: &[Vec<f64>],
    ) -> Carried {
        Carried {
            installation,
            uncertainty: Some((terms, covariance(std, correlation))),
        }
    }
}

/// The covariance of standard deviations `std` and correlations `correlation`; a
/// standard deviation or correlation that is not finite (a term its calibration could
/// not see at all) counts as zero.
pub fn covariance(std: &[f64], correlation: &[Vec<f64>]) -> DMatrix<f64> {
    let n = std.len();
    let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
    DMatrix::from_fn(n, n, |i, j| {
        let rho = if i == j {
            1.0
        } else {
            finite(correlation[i][j])
        };
        rho * finite(std[i]) * finite(std[j])
    })
}

/// A dive's terms found again, with the carried ones.
#[derive(Debug, Clone)]
pub struct Clock {
    /// The carried terms with the dive's replaced.
    pub installation: Installation,
    /// The search that started it: its best τ, s, and the RMS of the DVL against the
    /// carried prediction there, m/s (all three axes), and every offset it tried.
    pub search: Search,
    /// The least squares of the dive's terms, and their bound given the carried terms.
    pub fit: Fit,
    pub bound: TermBound,
    /// The dive's terms' standard deviations, the carried terms' uncertainty included,
    /// in the order of the bound's names.
    pub std: Vec<f64>,
}

impl Clock {
    /// The time offset's standard deviation (from the noise the residuals show, the
    /// carried terms' uncertainty included), s.
    pub fn time_offset_std_s(&self) -> f64 {
        let index = self.bound.names.iter().position(|n| *n == "time_offset_s");
        index.map_or(f64::NAN, |i| self.std[i])
    }

    /// The half-width of the time offset's 95 % interval, s: its standard deviation
    /// times Student's t on the degrees of freedom of the window's noise
    /// ([`crate::installation::estimate::bound::ReadNoise::quantile_95`]).
    pub fn time_offset_half_width_95_s(&self) -> f64 {
        self.bound.residual_noise.quantile_95() * self.time_offset_std_s()
    }

    /// Whether the window cannot show the time offset (its standard deviation beyond the
    /// tolerance, or one with another term).
    pub fn time_offset_unseen(&self) -> bool {
        self.bound.is_unseen("time_offset_s")
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ClockError {
    #[error(
        "the DVL's velocity over the first {window_s} s varies by {std_cm_s:.2} cm/s \
         (standard deviation, three axes), no more than the {noise_cm_s:.2} cm/s of noise \
         its fit's residuals show (three axes): a dive at constant velocity shows no clock; \
         a window with a turn or a change of speed does"
    )]
    FlatMotion {
        window_s: f64,
        std_cm_s: f64,
        noise_cm_s: f64,
    },
    #[error(
        "no step of the ±{search_s} s search finds half the window's DVL samples inside the reference: \
         the clock may lie beyond the search (a wider --search-s may find it), or the two recordings do not overlap in time"
    )]
    NoOverlap { search_s: f64 },
    #[error(
        "the best time offset, {found_s:.2} s, lies at the edge of the ±{} s searched about the installation's {carried_s:.2} s: \
         the clock may lie beyond the search, and a wider one may find it",
        crate::Shown(*search_s)
    )]
    AtEdge {
        found_s: f64,
        carried_s: f64,
        search_s: f64,
    },
    #[error(
        "the best time offset within ±{} s of the installation's {carried_s:.2} s, {found_s:.2} s, is not shown by the window, and there the DVL fits the installation to {fitted_cm_s:.2} cm/s (three axes), over {} times the {calibrated_cm_s:.2} cm/s its calibration left: \
         the clock may lie beyond the search, and a wider --search-s may find it (or the installation does not hold on this dive)",
        crate::Shown(*search_s),
        MISFIT_RATIO
    )]
    BeyondSearch {
        found_s: f64,
        carried_s: f64,
        search_s: f64,
        fitted_cm_s: f64,
        calibrated_cm_s: f64,
    },
    #[error(
        "the least squares of the dive's terms from the search's best, {found_s:.2} s, failed: {fault}{}",
        match fault {
            FitError::TooFewSamples { .. } | FitError::LengthMismatch { .. } => String::new(),
            _ => format!("; the clock may lie beyond the ±{} s searched, and a wider --search-s may find it", crate::Shown(*search_s)),
        }
    )]
    Fit {
        found_s: f64,
        search_s: f64,
        fault: FitError,
    },
    #[error(
        "its time offset is known only to ±{std_s} s, beyond the ±{search_s} s searched: these seconds do not show the clock"
    )]
    NotShown { std_s: f64, search_s: f64 },
}

/// The most window samples each step of the search reads: a longer window is read on
/// every few of its samples, evenly spread (an hour at 1 Hz, a minute at 60 Hz), so that
/// a step costs no more than a short window's.
const SEARCH_SAMPLES: usize = 3_600;

/// The most samples the coarse grid reads over all its steps (steps × samples): a
/// search range of an hour reads fewer samples per step, so that no search costs more
/// than about this many predictions.
const SEARCH_BUDGET: usize = 10_000_000;

/// The finest step of the search's fine grid, s: half a sample of a 500-Hz DVL.
const FINEST_STEP_S: f64 = 0.001;

/// The grid of a clock search over ±`search_s`, known before the dive is read: how many
/// offsets it tries and on how many of the window's samples at most, which bound its
/// cost whatever the window and the DVL's rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchGrid {
    pub search_s: f64,
    /// Offsets [`TIME_OFFSET_SCAN_STEP_S`] apart over ±`search_s`, its ends included.
    pub coarse: usize,
    /// The most offsets within one coarse step of the best.
    pub fine: usize,
    /// The most window samples each offset is read on.
    pub samples: usize,
}

impl SearchGrid {
    pub fn of(search_s: f64) -> SearchGrid {
        let coarse = 2 * (search_s / TIME_OFFSET_SCAN_STEP_S).ceil() as usize + 1;
        SearchGrid {
            search_s,
            coarse,
            fine: 2 * (TIME_OFFSET_SCAN_STEP_S / FINEST_STEP_S).ceil() as usize,
            samples: SEARCH_SAMPLES.min(SEARCH_BUDGET / coarse).max(1),
        }
    }
}

impl std::fmt::Display for SearchGrid {
    /// `the clock search: 241 offsets 0.25 s apart over ±30 s, then at most 500 within
    /// 0.25 s of the best, each on at most 3600 of the window's samples`
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the clock search: {} offsets {TIME_OFFSET_SCAN_STEP_S} s apart over ±{} s, then at most {} within {TIME_OFFSET_SCAN_STEP_S} s of the best, each on at most {} of the window's samples",
            self.coarse,
            crate::Shown(self.search_s),
            self.fine,
            self.samples
        )
    }
}

/// The τ (s) at which the carried installation's prediction from the reference at
/// t + τ is closest to the DVL (least RMS over the window), and that RMS (m/s): first
/// every [`TIME_OFFSET_SCAN_STEP_S`] over ±`search_s` (its ends included, nothing beyond
/// them), then within one such step of the
/// best at half the DVL's sample interval (where that is finer; never finer than
/// [`FINEST_STEP_S`]); each step on at most [`SEARCH_SAMPLES`] of the window's samples
/// evenly spread, and the coarse grid on no more than [`SEARCH_BUDGET`] in all. A step
/// counts when at least half the samples land inside the reference. `None` where no
/// step does.
pub fn search_offset(
    record: (&[f64], &[Vec3]),
    reference: &Reference,
    carried: Installation,
    search_s: f64,
) -> Option<(f64, f64)> {
    search(record, reference, carried, search_s).map(|found| found.best)
}

/// A clock search as done: its best offset and RMS, and each offset tried with the RMS
/// there (those where enough samples land inside the reference), sorted by offset.
#[derive(Debug, Clone, PartialEq)]
pub struct Search {
    /// τ, s, and the RMS of the DVL against the carried prediction there, m/s.
    pub best: (f64, f64),
    /// (τ s, RMS m/s) of each offset tried, by τ.
    pub tried: Vec<(f64, f64)>,
    /// The search's edges: the carried τ ∓ the search's range, s.
    pub edges_s: (f64, f64),
}

/// [`search_offset`]'s search, every offset it tried kept.
pub fn search(
    (time_s, dvl_m_s): (&[f64], &[Vec3]),
    reference: &Reference,
    carried: Installation,
    search_s: f64,
) -> Option<Search> {
    let grid = SearchGrid::of(search_s);
    let stride = time_s.len().div_ceil(grid.samples).max(1);
    let read: Vec<(f64, Vec3)> = (time_s.iter().zip(dvl_m_s))
        .step_by(stride)
        .map(|(&t, &v)| (t, v))
        .collect();
    // The RMS of the DVL against the carried prediction at `offset_s`, where enough of
    // the samples read land inside the reference.
    let rms_at = |offset_s: f64| {
        let (mut sum, mut count) = (0.0, 0usize);
        for (t, dvl) in &read {
            if let Some(at) = reference.at(t + offset_s) {
                let predicted = carried.predict(at);
                sum += (0..3).map(|a| (dvl[a] - predicted[a]).powi(2)).sum::<f64>();
                count += 1;
            }
        }
        let enough = count > 0 && count as f64 >= SEARCH_COVERAGE * read.len() as f64;
        enough.then(|| (sum / count as f64).sqrt())
    };
    let mut tried: Vec<(f64, f64)> = Vec::new();
    let mut best_of = |offsets: &mut dyn Iterator<Item = f64>, mut best: Option<(f64, f64)>| {
        for offset_s in offsets {
            if let Some(rms) = rms_at(offset_s) {
                tried.push((offset_s, rms));
                if best.is_none_or(|(_, lowest)| rms < lowest) {
                    best = Some((offset_s, rms));
                }
            }
        }
        best
    };
    // Every step within ±search_s of the carried τ, its ends included.
    let (lowest_s, highest_s) = (
        carried.time_offset_s - search_s,
        carried.time_offset_s + search_s,
    );
    let steps = grid.coarse as i64 / 2;
    let mut coarse = (-steps..=steps).map(|k| {
        (carried.time_offset_s + k as f64 * TIME_OFFSET_SCAN_STEP_S).clamp(lowest_s, highest_s)
    });
    let (centre_s, rms) = best_of(&mut coarse, None)?;
    let fine_s = (sample_interval(time_s) / 2.0).clamp(FINEST_STEP_S, TIME_OFFSET_SCAN_STEP_S);
    let fine_steps = (TIME_OFFSET_SCAN_STEP_S / fine_s).ceil() as i64;
    let mut fine = (-fine_steps..=fine_steps)
        .filter(|&k| k != 0)
        .map(|k| centre_s + k as f64 * fine_s)
        .filter(|offset_s| (lowest_s..=highest_s).contains(offset_s));
    let best = best_of(&mut fine, Some((centre_s, rms)))?;
    tried.sort_by(|a, b| a.0.total_cmp(&b.0));
    tried.dedup_by(|a, b| a.0 == b.0);
    Some(Search {
        best,
        tried,
        edges_s: (lowest_s, highest_s),
    })
}

/// Fits `terms` to the DVL record (`time_s`, `dvl_m_s`) against `reference` as
/// [`fit`](crate::installation::estimate::fit::fit) does, but with τ started from the
/// best of a search over ±`search_s` about zero ([`search_offset`], the installation
/// held at none: a first calibration knows no other) where a search is asked: two logs
/// whose clocks were never set alike are seconds or minutes apart, beyond the fit's own
/// scan of ±[`TIME_OFFSET_MARGIN_S`]. A best at an end of the search is refused (the
/// search did not bracket the clock). Without a search, or without τ among `terms`, the
/// plain fit.
pub fn fit_searched(
    (time_s, dvl_m_s): (&[f64], &[Vec3]),
    reference: &Reference,
    terms: TermSet,
    search_s: Option<f64>,
) -> Result<Fit, FitError> {
    let start = match search_s {
        Some(search_s) if terms.time_offset => {
            let searched = search_offset(
                (time_s, dvl_m_s),
                reference,
                Installation::default(),
                search_s,
            );
            let (tau, _) = searched.ok_or(FitError::NoClockInSearch { search_s })?;
            if inside_the_search(tau, 0.0, search_s).is_err() {
                return Err(FitError::ClockAtSearchEdge {
                    found_s: tau,
                    search_s,
                });
            }
            Installation {
                time_offset_s: tau,
                ..Installation::default()
            }
        }
        _ => Installation::default(),
    };
    fit_about(time_s, dvl_m_s, reference, terms, start)
}

/// The standard deviation of the DVL's velocity over the window, the three axes'
/// variances summed, m/s: how much the motion changes.
fn motion_std(dvl_m_s: &[Vec3]) -> f64 {
    let n = dvl_m_s.len().max(1) as f64;
    (0..3)
        .map(|a| {
            let mean = dvl_m_s.iter().map(|v| v[a]).sum::<f64>() / n;
            dvl_m_s.iter().map(|v| (v[a] - mean).powi(2)).sum::<f64>() / n
        })
        .sum::<f64>()
        .sqrt()
}

/// Re-finds the dive's terms of `search` on a dive's first seconds (`time_s`,
/// `dvl_m_s`, the caller's window) with the other terms held at `carried`'s values; the
/// bound from `noise`, the flag from `tolerances`.
pub fn refind(
    (time_s, dvl_m_s): (&[f64], &[Vec3]),
    reference: &Reference,
    carried: &Carried,
    search: ClockSearch,
    (noise, tolerances): (Noise, &Tolerances),
) -> Result<Clock, ClockError> {
    let searched = self::search(
        (time_s, dvl_m_s),
        reference,
        carried.installation,
        search.search_s,
    )
    .ok_or(ClockError::NoOverlap {
        search_s: search.search_s,
    })?;
    let (searched_offset_s, _) = searched.best;
    inside_the_search(
        searched_offset_s,
        carried.installation.time_offset_s,
        search.search_s,
    )?;
    let start = Installation {
        time_offset_s: searched_offset_s,
        ..carried.installation
    };
    let fit = fit_about(time_s, dvl_m_s, reference, search.dive_terms, start).map_err(|fault| {
        ClockError::Fit {
            found_s: searched_offset_s,
            search_s: search.search_s,
            fault,
        }
    })?;
    let bound = bound(&fit, noise, tolerances);
    // A window whose DVL moves no more than the noise its residuals show has no clock
    // to show; above it, whether the window shows τ is the bound's to say. The noise
    // is the window's own, not the DVL's specification: a quieter DVL shows its clock
    // in gentler motion.
    let shown = bound.residual_noise.std_m_s;
    let noise_shown_m_s = shown.iter().map(|s| s * s).sum::<f64>().sqrt();
    let motion_m_s = motion_std(dvl_m_s);
    if !(motion_m_s > noise_shown_m_s) {
        return Err(ClockError::FlatMotion {
            window_s: (window_length_s(time_s) * 10.0).round() / 10.0,
            std_cm_s: 100.0 * motion_m_s,
            noise_cm_s: 100.0 * noise_shown_m_s,
        });
    }
    let inherited = match &carried.uncertainty {
        Some(uncertainty) => {
            let samples = mask_about(time_s, reference, searched_offset_s);
            let window = (&time_s[samples.clone()], &dvl_m_s[samples]);
            inherited_variance(&fit, (window, reference), uncertainty)
        }
        None => vec![0.0; bound.std.len()],
    };
    let std = bound
        .std
        .iter()
        .zip(&inherited)
        .map(|(std, more)| (std * std + more).sqrt())
        .collect();
    let clock = Clock {
        installation: fit.installation,
        search: searched,
        fit,
        bound,
        std,
    };
    let std_s = clock.time_offset_std_s();
    if !(std_s <= search.search_s) {
        return Err(ClockError::NotShown {
            std_s,
            search_s: search.search_s,
        });
    }
    Ok(clock)
}

/// How many times the residual its calibration left a dive's fit may leave where the
/// window does not show its clock before the clock is taken as lying beyond the search:
/// a clock found in a side lobe leaves the turns unmatched (tens of cm/s), a dive merely
/// noisier than its calibration a few times the residual.
pub const MISFIT_RATIO: f64 = 3.0;

impl Clock {
    /// Refuses this clock where it lies more than the fit's ±3 s scan from the
    /// carried one, `carried_s`, the window does not show it, and the dive fits the
    /// installation far worse than its calibration, `calibrated_m_s` (three axes): a
    /// search whose range held no clock finds its best in a side lobe, which a dive's
    /// corrected files must not be written with. A clock found near the carried one
    /// that fits badly is a DVL that moved (remounted), which `correct` warns of.
    pub fn within_the_search(
        &self,
        carried_s: f64,
        search_s: f64,
        calibrated_m_s: f64,
    ) -> Result<(), ClockError> {
        let rms = self.fit.residual_rms_m_s;
        let fitted_m_s = (rms[0].powi(2) + rms[1].powi(2) + rms[2].powi(2)).sqrt();
        let far = (self.installation.time_offset_s - carried_s).abs() > TIME_OFFSET_MARGIN_S;
        match far && self.time_offset_unseen() && fitted_m_s > MISFIT_RATIO * calibrated_m_s {
            true => Err(ClockError::BeyondSearch {
                found_s: self.installation.time_offset_s,
                carried_s,
                search_s,
                fitted_cm_s: 100.0 * fitted_m_s,
                calibrated_cm_s: 100.0 * calibrated_m_s,
            }),
            false => Ok(()),
        }
    }
}

/// The length of the window stamped `time_s`, s: its span and one sample interval.
fn window_length_s(time_s: &[f64]) -> f64 {
    let span_s = time_s
        .last()
        .zip(time_s.first())
        .map_or(0.0, |(l, f)| l - f);
    span_s + sample_interval(time_s)
}

/// Refuses a search's best offset `found_s` at an end of the ±`search_s` about
/// `carried_s` (the very bounds its grid is clamped to): the search did not bracket it.
/// A search within one coarse step has no inside, and is not judged.
fn inside_the_search(found_s: f64, carried_s: f64, search_s: f64) -> Result<(), ClockError> {
    let at_an_end = found_s <= carried_s - search_s || found_s >= carried_s + search_s;
    match at_an_end && search_s > TIME_OFFSET_SCAN_STEP_S {
        true => Err(ClockError::AtEdge {
            found_s,
            carried_s,
            search_s,
        }),
        false => Ok(()),
    }
}

/// The variance each of `fit`'s dive terms inherits from the carried terms'
/// covariance: `G C Gᵀ` with `G = (BᵀB)⁻¹ BᵀA`, B the dive terms' Jacobian and A the
/// carried terms' (those that are not the dive's) on the same samples.
fn inherited_variance(
    fit: &Fit,
    ((time_s, dvl_m_s), reference): ((&[f64], &[Vec3]), &Reference),
    (terms, covariance): &(TermSet, DMatrix<f64>),
) -> Vec<f64> {
    let dive = fit.terms.parameter_names();
    let names = terms.parameter_names();
    let kept: Vec<usize> = (0..names.len())
        .filter(|&i| !dive.contains(&names[i]))
        .collect();
    let carried_terms = TermSet {
        time_offset: terms.time_offset && !fit.terms.time_offset,
        bias: match fit.terms.bias {
            PerAxis::Off => terms.bias,
            _ => PerAxis::Off,
        },
        ..*terms
    };
    let zero = vec![0.0; dive.len()];
    if kept.is_empty() || carried_terms.parameter_names().len() != kept.len() {
        return zero;
    }
    let (_, a) = linearised(time_s, dvl_m_s, reference, carried_terms, fit.installation);
    let b = &fit.jacobian;
    if a.nrows() != b.nrows() {
        return zero;
    }
    let Some(inverse) = (b.transpose() * b).try_inverse() else {
        return zero;
    };
    let gain = inverse * (b.transpose() * a);
    let kept_covariance = DMatrix::from_fn(kept.len(), kept.len(), |i, j| {
        covariance[(kept[i], kept[j])]
    });
    let carried = &gain * kept_covariance * gain.transpose();
    (0..dive.len()).map(|k| carried[(k, k)].max(0.0)).collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::installation::estimate::bound::DEFAULT_TOLERANCES;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// A reference of 500 s at 1 Hz with speed changes and turns (analytic, so the
    /// reference at t + τ is exact at every stamp), and the DVL that `truth` makes read
    /// on the stamps of its first 400 s with white noise of `noise_m_s` per axis.
    pub fn turning_dive(
        truth: &Installation,
        noise_m_s: f64,
        seed: u64,
    ) -> (Vec<f64>, Vec<Vec3>, Reference) {
        use std::f64::consts::TAU;
        let motion = |t: f64| {
            let velocity = [
                1.8 + 0.3 * (TAU * t / 75.0).sin(),
                0.1 * (TAU * t / 40.0).sin(),
                0.05 * (t / 13.0).sin(),
            ];
            let rate = [
                0.01 * (TAU * t / 20.0).cos(),
                0.0,
                0.15 * (TAU * t / 60.0).cos(),
            ];
            crate::installation::frames::ReferenceAt {
                velocity_body_m_s: velocity,
                rate_rad_s: rate,
            }
        };
        let time_s: Vec<f64> = (0..500).map(f64::from).collect();
        let reference = Reference {
            velocity_body_m_s: time_s
                .iter()
                .map(|&t| motion(t).velocity_body_m_s)
                .collect(),
            rate_rad_s: time_s.iter().map(|&t| motion(t).rate_rad_s).collect(),
            time_s: time_s.clone(),
            max_gap_s: 3.0,
            dvl_gap_limit_s: 3.0,
        };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, noise_m_s).unwrap();
        let stamps: Vec<f64> = time_s[..400].to_vec();
        let dvl = stamps
            .iter()
            .map(|&t| {
                let clean = truth.predict(motion(t + truth.time_offset_s));
                [0, 1, 2].map(|k| clean[k] + noise.sample(&mut rng))
            })
            .collect();
        (stamps, dvl, reference)
    }

    #[test]
    fn the_search_is_bounded_whatever_the_window_and_the_range() {
        let truth = Installation {
            lever_arm_m: [-1.9, 0.1, 0.4],
            time_offset_s: 7.3,
            ..Installation::default()
        };
        let (time_s, dvl, reference) = turning_dive(&truth, 0.01, 5);
        let carried = Installation {
            time_offset_s: 0.0,
            ..truth
        };
        // One sample: a fine step of half its interval would be zero.
        let one = search_offset((&time_s[..1], &dvl[..1]), &reference, carried, 30.0);
        assert!(one.is_some());
        // A range of an hour over the whole dive: the grid reads fewer samples a step,
        // and still finds the clock within a coarse step.
        let (found, _) = search_offset((&time_s, &dvl), &reference, carried, 3600.0).unwrap();
        assert!((found - 7.3).abs() <= 0.25, "{found}");
        // Nothing beyond the range asked for: ±0.1 s about 0 stays within it, its
        // nearer end the best.
        let (found, _) = search_offset((&time_s, &dvl), &reference, carried, 0.1).unwrap();
        assert_eq!(found, 0.1);
        // The default range finds it on the fine grid (a 1-Hz DVL's: the coarse one).
        let (found, _) = search_offset((&time_s, &dvl), &reference, carried, 30.0).unwrap();
        assert!((found - 7.3).abs() <= 0.125, "{found}");
    }

    #[test]
    fn a_clock_twenty_seconds_off_is_found_again_with_the_geometry_carried() {
        let truth = Installation {
            lever_arm_m: [-1.9, 0.1, 0.4],
            misalignment_rad: [0.0, 0.0, 0.02],
            time_offset_s: 20.3,
            ..Installation::default()
        };
        let (time_s, dvl_m_s, reference) = turning_dive(&truth, 0.01, 7);
        let window = time_s.partition_point(|&t| t - time_s[0] < 60.0);
        let noise = Noise {
            dvl_m_s: 0.01,
            reference_m_s: 0.0,
        };
        let search = ClockSearch {
            dive_terms: TermSet {
                time_offset: true,
                ..TermSet::NONE
            },
            search_s: DEFAULT_SEARCH_S,
        };
        let carried = Installation {
            time_offset_s: 0.0,
            ..truth
        };
        let clock = refind(
            (&time_s[..window], &dvl_m_s[..window]),
            &reference,
            &Carried::exact(carried),
            search,
            (noise, &DEFAULT_TOLERANCES),
        )
        .unwrap();
        let std = clock.time_offset_std_s();
        assert!(std > 0.0 && std < 0.05, "{std}");
        let error = clock.installation.time_offset_s - truth.time_offset_s;
        assert!(error.abs() < 4.0 * std, "{error} against {std}");
        assert_eq!(clock.installation.lever_arm_m, truth.lever_arm_m);
        assert!(
            (clock.search.best.0 - 20.3).abs() < 0.5,
            "{}",
            clock.search.best.0
        );
    }
}
