//! The installation fitted to position fixes, for a vehicle with no velocity reference:
//! the DVL dead-reckoned through the installation
//! ([`crate::installation::dead_reckoning`]) and its track fitted to the fixes by
//! least squares, each piece of the DVL record (between losses of bottom lock) with a
//! start position of its own, a nuisance term.
//! In: the DVL samples and their pieces, an [`Attitude`], the [`Fixes`], the terms and
//! the noise. Out: a [`FixFit`]: the terms, their standard deviations and Fisher bound,
//! the terms the fixes cannot show, the fixes left out.
//!
//! The terms: the scale (one for all axes), the misalignment's yaw (and its roll and
//! pitch where the fixes have a depth: horizontal fixes do not feel them), the time
//! offset and the horizontal lever arm (its depth part moves a fix only through roll
//! and pitch, and is not estimated); and where asked ([`FixTerms`]), the fixes' own
//! latency, [`FIX_LATENCY`]: the fix stamped t gives the position at t − L, so the
//! dead reckoning is read there. The clock both reads the attitude at another time
//! and shifts the track; the latency only shifts it.
//!
//! The noise of a fix's residual ([`super::fix_noise`]): the dead reckoning's random
//! walk (the DVL's noise summed, its level read from the residuals by their restricted
//! likelihood, so that a DVL noise correlated in time walks as far as it does), the
//! fix's white error, and its slowly wandering one (a Gauss–Markov error, its variance
//! and correlation time read from the residuals), whitened by a Kalman filter over each
//! piece's fixes on each axis, in time and memory linear in the fixes; each piece's
//! start position is profiled out of the whitened residuals. The fit is the velocity
//! fit's solve loop (Levenberg–Marquardt) on them, a Jacobian of central differences.
//! The time offset starts from the best of a scan over
//! ±[`TIME_OFFSET_MARGIN_S`](super::fit::TIME_OFFSET_MARGIN_S); a best at the scan's
//! edge is held or refused (below), and a fit that leaves the fixes further from the
//! track than no terms do is refused. A fix grossly off is left out before the scan, and stays out.
//!
//! A USBL's multipath outliers: after least squares, each fix's distance from the dead
//! reckoning in its own standard deviations u (the walk since its piece's start, the
//! wandering error and its own; the root mean square over its axes) weighs it by Huber's
//! loss, then by Tukey's bisquare ([`super::robust`]); a fix beyond Tukey's constant is
//! an outlier, left out and counted, and the terms are fitted again by least squares on
//! the fixes kept.
//!
//! Standard deviations: the whitened information JᵀΣ⁻¹J gives the Fisher bound (at the
//! noise as given); under the noise the residuals chose, scaled by the variance factor
//! they show (their whitened sum of squares over n − p), the standard deviations, whose
//! 95 % interval takes Student's t on n − p degrees of freedom. No term is held at zero
//! for being known loosely: every term is applied at its estimate with its standard
//! deviation (one beyond its tolerance in [`FIX_TOLERANCES`], or tied beyond
//! [`CORRELATION_LIMIT`] to another, is said to be seen poorly), but where the fixes
//! cannot show it at all: over headings spanning under a quarter turn, the lever arm and
//! the clock (the yaw is applied there, said to be seen poorly: at few headings it holds
//! the attitude's heading error there too); or a direction the residuals do not feel. Such a term is
//! held at zero, as the dead reckoning's start absorbs it exactly, and the rest fitted
//! again. A clock or a latency run to the edge of its search, where that edge lies
//! within its 95 % interval of zero, is not placed by the fixes: it is held at zero and
//! the others' intervals carry its uncertainty (marginalised over it); where the two
//! are tied, the latency is held and the clock is their sum.

use crate::Vec3;
use crate::data::fixes::Fixes;
use crate::evaluate::statistics::student_t_975;
use crate::installation::estimate::bound::{CORRELATION_LIMIT, TermBound, Unseen, Why};
use crate::installation::estimate::fix_noise::FixResidualNoise;
use crate::installation::estimate::fix_problem::{Problem, Solution};
pub use crate::installation::estimate::fix_terms::{
    FIX_LATENCY, FIX_TOLERANCES, FixFitError, FixNoise, FixTerms,
};
use crate::installation::frames::Attitude;
use crate::installation::terms::names::TermName;
use crate::installation::terms::{Installation, TermSet};
use std::ops::Range;

/// The terms a fit to fixes estimates when none are named: every term it can.
pub const DEFAULT_FIX_TERMS: [&str; 4] = ["scale", "misalignment", "lever_arm", "time_offset"];

/// [`DEFAULT_FIX_TERMS`] as names.
pub fn default_fix_terms() -> Vec<TermName> {
    DEFAULT_FIX_TERMS
        .iter()
        .map(|t| t.parse().expect("a term's name"))
        .collect()
}

/// The least span of headings over which the terms only turns show
/// ([`SHOWN_BY_TURNS`]) are fitted to fixes, rad (a quarter turn): at one heading the
/// lever arm (C_b^n l) and the clock (a shift along the track) move the track as its
/// start does. On A-KIT a straight segment's lever arm and clock, fitted where they were
/// barely tied to the start, applied to the turning ones, left twice the drift of none.
/// Below it the yaw is fitted and applied, but said to be seen poorly
/// ([`Why::FewHeadings`]): at one heading it is the DVL's yaw and the attitude's heading
/// error there together.
pub const MIN_HEADING_SPAN_RAD: f64 = std::f64::consts::FRAC_PI_2;

/// The terms only a turning vehicle shows to fixes (a latency shifts the track along
/// itself, as its start does on a straight run).
const SHOWN_BY_TURNS: [&str; 4] = [
    "lever_arm_x_m",
    "lever_arm_y_m",
    "time_offset_s",
    FIX_LATENCY,
];

/// The yaw, which any heading shows (the track's direction against the DVL's), but
/// which holds at other headings only as far as the attitude's heading error is the same.
const YAW: &str = "misalignment_z_rad";

/// The terms fitted to fixes, their bound, and the fixes used.
#[derive(Debug, Clone, PartialEq)]
pub struct FixFit {
    /// The terms asked for, and the installation applied: every term the fixes cannot
    /// show held at zero.
    pub terms: TermSet,
    pub installation: Installation,
    /// Each parameter of `terms`, in their order, then the fixes' latency
    /// ([`FIX_LATENCY`]) where it was fitted: its value (for a term not applied, that of
    /// the fit it was left out of), standard deviations, correlations, whether it is
    /// applied and why any is seen poorly or not at all.
    pub bound: TermBound<FixResidualNoise>,
    /// Whether each parameter was estimated at all (a horizontal fit does not estimate
    /// roll, pitch or the lever arm's depth).
    pub estimated: Vec<bool>,
    /// The fixes fitted, those left out as outliers (their indices in the fixes), and
    /// those outside every piece of the DVL record (beyond its margin).
    pub fitted: usize,
    pub outliers: Vec<usize>,
    pub outside: usize,
    /// How many pieces of the DVL record the fixes cover (a start position each).
    pub pieces: usize,
    /// The RMS of the residuals of the fixes fitted, north, east and depth (NaN without
    /// one), m; and of the same fixes with no term, each piece's start alone fitted.
    pub residual_rms_m: Vec3,
    pub bare_residual_rms_m: Vec3,
    /// Each fitted fix's horizontal residual with no terms and with them (those
    /// `residual_rms_m` and `bare_residual_rms_m` are the RMS of, over the fixes kept).
    pub residuals: Vec<FixResidual>,
    /// The axes fitted: 2 (north, east) or 3 (and depth).
    pub axes: usize,
    /// How far the dead reckoning with the terms applied travelled, horizontally, over
    /// the times the fixes fitted span (each piece from its first fix to its last), m.
    pub distance_m: f64,
}

/// A fitted fix's residual: the dead reckoning, its piece placed at the start fitted,
/// less the fix, north and east, m, with no terms (each piece's start alone fitted) and
/// with the terms applied.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixResidual {
    /// Its index among the fixes.
    pub fix: usize,
    pub before_m: [f64; 2],
    pub after_m: [f64; 2],
    /// Whether the fit kept it (an outlier is not).
    pub kept: bool,
}

/// Each fitted fix's residual under the `bare` fit (no terms) and the `last` one.
fn fix_residuals(
    problem: &Problem,
    bare: &Solution,
    last: &Solution,
) -> Result<Vec<FixResidual>, FixFitError> {
    let (before, after) = (problem.fix_residuals(bare)?, problem.fix_residuals(last)?);
    Ok((problem.fix_of.iter().enumerate())
        .map(|(j, &fix)| FixResidual {
            fix,
            before_m: [before[j][0], before[j][1]],
            after_m: [after[j][0], after[j][1]],
            kept: last.kept[j],
        })
        .collect())
}

impl FixFit {
    /// Whether the clock applied is the sum of the DVL's clock and the fixes' latency,
    /// the latency held at zero: the fixes placed the track's shift against them, not
    /// how the two split it.
    pub fn clock_is_the_sum(&self) -> bool {
        !self.bound.is_applied(FIX_LATENCY)
            && (self.bound.unseen.iter()).any(|u| {
                u.term == FIX_LATENCY
                    && matches!(u.why, Why::Correlated { with, .. } if with == "time_offset_s")
            })
    }
}

/// Fits `terms` (scale, misalignment, lever arm, time offset; any other is refused by
/// the caller; and the fixes' latency where asked) to `fixes` from the DVL samples
/// `dvl` cut into `pieces`, under `noise`.
pub fn fit_fixes(
    dvl: (&[f64], &[Vec3]),
    pieces: &[Range<usize>],
    attitude: &Attitude,
    fixes: &Fixes,
    terms: impl Into<FixTerms>,
    noise: FixNoise,
) -> Result<FixFit, FixFitError> {
    let carried = (terms.into(), Installation::default());
    fit_fixes_around(dvl, pieces, attitude, fixes, carried, noise)
}

/// [`fit_fixes`] around the installation `carried`: each of `terms` fitted as an offset
/// from its carried value (the rest held at theirs), its time offset scanned within
/// ±[`TIME_OFFSET_MARGIN_S`](super::fit::TIME_OFFSET_MARGIN_S) of the carried clock
/// (the DVL's samples read where the attitude covers every clock so scanned); the fit's
/// values are those offsets, and its installation the carried one moved by them. A
/// dive's clock found again from its fixes, the vehicle's terms carried.
pub fn fit_fixes_around(
    dvl: (&[f64], &[Vec3]),
    pieces: &[Range<usize>],
    attitude: &Attitude,
    fixes: &Fixes,
    (terms, carried): (FixTerms, Installation),
    noise: FixNoise,
) -> Result<FixFit, FixFitError> {
    let problem = Problem::new(dvl, pieces, attitude, fixes, (terms, carried), noise)?;
    let mut shown = Shown::of(&problem);
    let last = shown.eliminate(&problem)?;
    problem.better_than_none(&last)?;
    let bounded = shown.bounded();
    let (value, mut last_std, mut correlation) =
        problem.averaged(&last, (&shown.applied, &bounded))?;
    let mut last_bound = problem.fisher_bound(&last, &bounded);
    let bare = problem.bare(&last)?;
    if let Some((clock, latency)) = shown.tied {
        clock_as_the_sum(&mut last_std, &mut correlation, (clock, latency));
        last_bound[clock] = problem.fisher_bound(&last, &shown.applied)[clock];
        shown.keep(latency, (0.0, last_std[latency], last_bound[latency]));
    }
    for k in shown.held.clone() {
        shown.keep(k, (0.0, last_std[k], last_bound[k]));
    }
    for k in 0..problem.names.len() {
        if shown.applied[k] {
            shown.keep(k, (value[k], last_std[k], last_bound[k]));
        }
    }
    Ok(FixFit {
        terms: terms.set,
        installation: problem.installation(&value),
        bound: TermBound {
            names: problem.names.clone(),
            value: shown.value,
            std: shown.std,
            bound_std: shown.bound_std,
            correlation,
            unseen: shown.unseen,
            applied: shown.applied,
            residual_noise: FixResidualNoise {
                shape: last.shape,
                variance_factor: last.variance_factor(),
                freedom: last.freedom,
            },
        },
        estimated: problem.estimated.clone(),
        fitted: last.kept.iter().filter(|&&kept| kept).count(),
        outliers: (last.kept.iter().enumerate())
            .filter(|(_, kept)| !**kept)
            .map(|(j, _)| problem.fix_of[j])
            .collect(),
        outside: problem.outside,
        pieces: problem.pieces.len(),
        residual_rms_m: problem.residual_rms(&last)?,
        bare_residual_rms_m: problem.residual_rms(&bare)?,
        residuals: fix_residuals(&problem, &bare, &last)?,
        axes: problem.axes,
        distance_m: problem.distance_m(&last.terms)?,
    })
}

/// Which terms the fixes show: those applied, why each other is not (and why one
/// applied is seen poorly), and each term's value and standard deviations (a term not
/// applied keeps those of the fit it was left out of).
struct Shown {
    applied: Vec<bool>,
    unseen: Vec<Unseen>,
    value: Vec<f64>,
    std: Vec<f64>,
    bound_std: Vec<f64>,
    /// Where the fixes did not tell the DVL's clock from their own latency: the places
    /// of the clock, which carries their sum, and of the latency, held at zero.
    tied: Option<(usize, usize)>,
    /// The clock or the latency held at zero where the fixes do not place it within its
    /// search.
    held: Vec<usize>,
}

impl Shown {
    /// Every term estimated, but those only turns show where the headings span under
    /// [`MIN_HEADING_SPAN_RAD`] (and there the yaw said to be seen poorly).
    fn of(problem: &Problem) -> Shown {
        let n = problem.names.len();
        let mut shown = Shown {
            applied: problem.estimated.clone(),
            unseen: Vec::new(),
            value: vec![0.0; n],
            std: vec![f64::INFINITY; n],
            bound_std: vec![f64::INFINITY; n],
            tied: None,
            held: Vec::new(),
        };
        let span_rad = problem.heading_span_rad();
        if span_rad < MIN_HEADING_SPAN_RAD {
            for (k, name) in problem.names.iter().enumerate() {
                if shown.applied[k] && SHOWN_BY_TURNS.contains(name) {
                    shown.applied[k] = false;
                    shown.unseen.push(Unseen {
                        term: name,
                        why: Why::OneHeading { span_rad },
                    });
                } else if shown.applied[k] && *name == YAW {
                    shown.unseen.push(Unseen {
                        term: name,
                        why: Why::FewHeadings { span_rad },
                    });
                }
            }
        }
        shown
    }

    /// Term `k`'s value, standard deviation and bound.
    fn keep(&mut self, k: usize, (value, std, bound_std): (f64, f64, f64)) {
        (self.value[k], self.std[k], self.bound_std[k]) = (value, std, bound_std);
    }

    /// The terms on a direction the residuals do not feel, left out one at a time (the
    /// first named) and the rest fitted again, until none is; the last fit. A term
    /// known loosely or tied to another stays, said to be seen poorly.
    fn eliminate(&mut self, problem: &Problem) -> Result<Solution, FixFitError> {
        loop {
            let solution = match problem.robust_fit(&self.applied) {
                Err(
                    edge @ (FixFitError::ClockAtScanEdge { .. }
                    | FixFitError::LatencyAtScanEdge { .. }),
                ) => self.hold_at_the_edge(problem, edge)?,
                fitted => fitted?,
            };
            let factor = solution.variance_factor();
            let (term_std, _, found) =
                problem.bound(&solution, &self.applied, solution.shape, factor);
            let flat = found.iter().find(|u| matches!(u.why, Why::Flat { .. }));
            let Some(flat) = flat else {
                self.unseen.extend(found);
                return Ok(solution);
            };
            let k = problem.position(flat.term);
            let bound = problem.fisher_bound(&solution, &self.applied)[k];
            self.keep(k, (solution.terms[k], term_std[k], bound));
            self.unseen.push(flat.clone());
            self.applied[k] = false;
        }
    }

    /// Where a fit ran the clock or the fixes' latency to the edge of its search
    /// (`edge`), and the fit with that term held at zero places the edge within its 95 %
    /// interval of zero (at 2 m every 5 s each is known to 2–3 s, and ±3 s is searched):
    /// that fit, the term held with its uncertainty carried ([`Shown::bounded`]). Where
    /// the clock and the latency are then tied beyond [`CORRELATION_LIMIT`], it is the
    /// latency that is held, and the clock is their sum, the track's shift against the
    /// fixes, which they place where they place neither alone. Otherwise `edge`, the
    /// refusal it was: fixes stamped 5 s late place their shift far beyond the search.
    fn hold_at_the_edge(
        &mut self,
        problem: &Problem,
        edge: FixFitError,
    ) -> Result<Solution, FixFitError> {
        let applied = |name: &str| {
            (problem.names.iter())
                .position(|n| *n == name)
                .filter(|&k| self.applied[k])
        };
        let (clock, latency) = (applied("time_offset_s"), applied(FIX_LATENCY));
        let ran = match edge {
            FixFitError::ClockAtScanEdge { .. } => clock,
            FixFitError::LatencyAtScanEdge { .. } => latency,
            _ => None,
        };
        let Some(ran) = ran else {
            return Err(edge);
        };
        let hold = |k: usize| {
            let mut held = self.applied.clone();
            held[k] = false;
            let solution = problem.robust_fit(&held).ok()?;
            let factor = solution.variance_factor();
            let (std, correlation, _) =
                problem.bound(&solution, &self.applied, solution.shape, factor);
            Some((held, solution, std, correlation))
        };
        let Some((mut held, mut solution, std, correlation)) = hold(ran) else {
            return Err(edge);
        };
        if let (Some(clock), Some(latency)) = (clock, latency) {
            let tied = correlation[clock][latency];
            if tied.abs() > CORRELATION_LIMIT {
                if ran == clock {
                    let Some(by_latency) = hold(latency) else {
                        return Err(edge);
                    };
                    (held, solution, _, _) = by_latency;
                }
                self.applied = held;
                let why = Why::Correlated {
                    with: "time_offset_s",
                    correlation: tied,
                };
                self.unseen.push(Unseen {
                    term: FIX_LATENCY,
                    why,
                });
                self.tied = Some((clock, latency));
                return Ok(solution);
            }
        }
        let edge_s = problem.limit(ran);
        if edge_s > student_t_975(solution.freedom as f64) * std[ran] {
            return Err(edge);
        }
        self.applied = held;
        let why = Why::BeyondSearch {
            edge_s,
            std_s: std[ran],
        };
        self.unseen.push(Unseen {
            term: problem.names[ran],
            why,
        });
        self.held.push(ran);
        Ok(solution)
    }

    /// The terms whose uncertainty the intervals carry: those applied, and a clock or a
    /// latency held at zero at the edge of its search.
    fn bounded(&self) -> Vec<bool> {
        let mut bounded = self.applied.clone();
        for &k in self
            .held
            .iter()
            .chain(self.tied.as_ref().map(|(_, latency)| latency))
        {
            bounded[k] = true;
        }
        bounded
    }
}

/// The standard deviations `std` and `correlation`s of a fit whose `clock`, the latency
/// held at zero, is the sum of itself and the `latency`, taken from those of both (the
/// covariance marginalised over the latency): the clock's variance that of the sum, its
/// covariance with each other term the sum of theirs; the latency keeps its standard
/// deviation and correlates with nothing (it is not applied).
fn clock_as_the_sum(
    std: &mut [f64],
    correlation: &mut [Vec<f64>],
    (clock, latency): (usize, usize),
) {
    let covariance = |j: usize, k: usize| correlation[j][k] * std[j] * std[k];
    let with_sum: Vec<f64> = (0..std.len())
        .map(|k| covariance(clock, k) + covariance(latency, k))
        .collect();
    let sum_variance = with_sum[clock] + with_sum[latency];
    let sum_std = sum_variance.max(0.0).sqrt();
    for k in (0..std.len()).filter(|&k| k != clock && k != latency) {
        correlation[clock][k] = with_sum[k] / (sum_std * std[k]);
        correlation[k][clock] = correlation[clock][k];
    }
    for k in (0..std.len()).filter(|&k| k != latency) {
        correlation[latency][k] = f64::NAN;
        correlation[k][latency] = f64::NAN;
    }
    std[clock] = sum_std;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::installation::frames::Reference;
    use crate::installation::terms::names::term_set;

    /// The simulation's weaving vehicle for 400 s at 1 Hz, its DVL as `truth` makes it
    /// (no noise; t + τ held inside the reference), its attitude, and a fix every 5 s of
    /// its reference point's position (its NED velocity summed by the trapezoidal rule,
    /// as the dead reckoning sums) stamped `late_s` late.
    fn dive(truth: &Installation, late_s: f64) -> (Vec<f64>, Vec<Vec3>, Attitude, Fixes) {
        let segment = crate::installation::learned::simulate::tests::weaving("W", 400, 0.0);
        let recording = &segment.recording;
        let reference = Reference::new(recording);
        let last = *recording.time_s.last().unwrap();
        let dvl = (recording.time_s.iter())
            .map(|&t| {
                truth.predict(
                    reference
                        .at((t + truth.time_offset_s).clamp(0.0, last))
                        .unwrap(),
                )
            })
            .collect();
        let mut position = [0.0; 2];
        let mut positions = vec![position];
        for pair in recording.velocity_ned_m_s.windows(2) {
            for k in 0..2 {
                position[k] += 0.5 * (pair[0][k] + pair[1][k]);
            }
            positions.push(position);
        }
        let chosen: Vec<usize> = (0..400).step_by(5).collect();
        let fixes = Fixes {
            lines: (0..chosen.len() as u64).collect(),
            time_s: chosen.iter().map(|&i| i as f64 + late_s).collect(),
            north_east_m: chosen.iter().map(|&i| positions[i]).collect(),
            depth_m: None,
            noise_m: None,
        };
        (
            recording.time_s.clone(),
            dvl,
            Attitude::of(recording),
            fixes,
        )
    }

    const NOISE: FixNoise = FixNoise {
        fix_m: 0.1,
        depth_m: 0.1,
        dvl_m_s: 0.01,
    };

    const TRUTH: Installation = Installation {
        scale: [0.01; 3],
        misalignment_rad: [0.0, 0.0, 0.02],
        lever_arm_m: [0.8, -0.5, 0.0],
        time_offset_s: 1.0,
        bias_m_s: [0.0; 3],
    };

    #[test]
    fn noiseless_fixes_give_the_installation_back() {
        let (time_s, dvl, attitude, fixes) = dive(&TRUTH, 0.0);
        let terms = term_set(&default_fix_terms());
        let pieces = [0..time_s.len()];
        let fit = fit_fixes((&time_s, &dvl), &pieces, &attitude, &fixes, terms, NOISE).unwrap();
        let found = fit.installation;
        assert!((found.scale[0] - 0.01).abs() < 1e-3, "{found:?}");
        assert!((found.misalignment_rad[2] - 0.02).abs() < 1e-3, "{found:?}");
        assert!((found.lever_arm_m[0] - 0.8).abs() < 0.05, "{found:?}");
        assert!((found.lever_arm_m[1] + 0.5).abs() < 0.05, "{found:?}");
        assert!((found.time_offset_s - 1.0).abs() < 0.02, "{found:?}");
        assert!(
            fit.bound
                .applied
                .iter()
                .zip(&fit.estimated)
                .all(|(a, e)| a == e)
        );
        assert!(fit.outliers.is_empty());
    }

    /// Fixes stamped a second after the positions they give: with the latency fitted,
    /// the installation and the latency come back; without it, the lever arm takes up
    /// most of the shift (2.8 m for 0.8 m) and the fixes lie far further from the track.
    #[test]
    fn fixes_stamped_late_give_their_latency_and_the_installation_back() {
        let (time_s, dvl, attitude, fixes) = dive(&TRUTH, 1.0);
        let pieces = [0..time_s.len()];
        let set = term_set(&default_fix_terms());
        let terms = FixTerms {
            set,
            fix_latency: true,
        };
        let fit = fit_fixes((&time_s, &dvl), &pieces, &attitude, &fixes, terms, NOISE).unwrap();
        let found = fit.installation;
        let latency = fit.bound.value[fit.bound.names.len() - 1];
        assert_eq!(fit.bound.names.last(), Some(&FIX_LATENCY));
        // Both applied, each its own: the clock is not their sum, however tied they are.
        assert!(fit.bound.is_applied(FIX_LATENCY) && !fit.clock_is_the_sum());
        assert!((latency - 1.0).abs() < 0.02, "{latency} {found:?}");
        assert!((found.time_offset_s - 1.0).abs() < 0.02, "{found:?}");
        assert!((found.lever_arm_m[0] - 0.8).abs() < 0.05, "{found:?}");
        assert!((found.misalignment_rad[2] - 0.02).abs() < 1e-3, "{found:?}");
        let blind = fit_fixes((&time_s, &dvl), &pieces, &attitude, &fixes, set, NOISE).unwrap();
        // The shift along the track is mostly taken up by the lever arm's x (C_b^n l
        // moves a fix along the body's x as a latency does at a steady speed).
        let lever_x = blind.installation.lever_arm_m[0];
        assert!((lever_x - 0.8).abs() > 1.0, "{:?}", blind.installation);
        let rms = |fit: &FixFit| fit.residual_rms_m[0].hypot(fit.residual_rms_m[1]);
        assert!(
            rms(&blind) > 10.0 * rms(&fit),
            "{} {}",
            rms(&blind),
            rms(&fit)
        );
    }

    /// A known covariance over (scale, clock, latency): the clock read as the sum takes
    /// var(c) + var(l) + 2 cov(c, l) and cov(s, c) + cov(s, l); the latency keeps its
    /// standard deviation and correlates with nothing.
    #[test]
    fn a_clock_read_as_the_sum_takes_the_sums_covariance() {
        let mut std = vec![2.0, 3.0, 4.0];
        let mut correlation = vec![
            vec![1.0, 0.5, -0.25],
            vec![0.5, 1.0, -0.9],
            vec![-0.25, -0.9, 1.0],
        ];
        clock_as_the_sum(&mut std, &mut correlation, (1, 2));
        // var = 9 + 16 − 2 · 0.9 · 12 = 3.4; cov(s, c + l) = 0.5 · 6 − 0.25 · 8 = 1.
        assert!((std[1] - 3.4f64.sqrt()).abs() < 1e-12, "{std:?}");
        assert!((correlation[0][1] - 1.0 / (2.0 * 3.4f64.sqrt())).abs() < 1e-12);
        assert_eq!(correlation[0][1], correlation[1][0]);
        assert_eq!((std[0], std[2], correlation[2][2]), (2.0, 4.0, 1.0));
        assert!(correlation[2][0].is_nan() && correlation[1][2].is_nan());
    }

    #[test]
    fn fixes_on_a_clock_beyond_the_scan_are_refused_not_fitted() {
        let (time_s, dvl, attitude, fixes) = dive(&TRUTH, 5.0);
        let terms = term_set(&default_fix_terms());
        let pieces = [0..time_s.len()];
        let error =
            fit_fixes((&time_s, &dvl), &pieces, &attitude, &fixes, terms, NOISE).unwrap_err();
        assert!(
            matches!(
                error,
                FixFitError::ClockAtScanEdge { .. }
                    | FixFitError::WorseThanNone { .. }
                    | FixFitError::Outliers { .. }
            ),
            "{error}"
        );
        let terms = FixTerms {
            set: terms,
            fix_latency: true,
        };
        let error =
            fit_fixes((&time_s, &dvl), &pieces, &attitude, &fixes, terms, NOISE).unwrap_err();
        assert!(
            matches!(error, FixFitError::LatencyAtScanEdge { .. }),
            "{error}"
        );
    }
}
