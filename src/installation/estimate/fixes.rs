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
//! and pitch, and is not estimated).
//!
//! The noise of a fix's residual on each axis is the fix's own (white, σ_f) and the
//! dead reckoning's: the DVL's white noise σ_v summed over its samples, a random walk
//! of variance σ_v² Δt per second from the piece's start. Within a piece the residuals
//! of an axis are so correlated, Σ = σ_f² I + σ_v² Δt · min(tᵢ, tⱼ); each block is
//! whitened by its Cholesky factor and the fit is Gauss–Newton on the whitened
//! residuals (a Jacobian of central differences; the start positions enter linearly).
//! The time offset starts from the best of a scan over ±[`TIME_OFFSET_MARGIN_S`].
//!
//! A USBL's multipath outliers: after least squares, each fix's residual in its own
//! standard deviations u (the root mean square over its axes) weighs it by Huber's
//! loss, then by Tukey's bisquare (c = 4.685, 95 % efficient on Gaussian noise); a fix
//! beyond c is an outlier, left out and counted, and the terms are fitted again by
//! least squares on the fixes kept.
//!
//! Standard deviations: the whitened information JᵀΣ⁻¹J gives the Fisher bound; scaled
//! by the variance factor the residuals show (their whitened sum of squares over n − p),
//! the standard deviations, whose 95 % interval takes Student's t on n − p degrees of
//! freedom. A term the fixes do not show (over headings spanning under a quarter turn,
//! the yaw, the lever arm and the clock; or flat, correlated beyond
//! [`CORRELATION_LIMIT`] with a start position, or beyond its tolerance in
//! [`FIX_TOLERANCES`]) is not applied, held at zero: the one shown least is left out and
//! the rest fitted again, until none is left (a term nearly flat with another inflates
//! that one's standard deviation too, which the next fit no longer does). The others'
//! intervals then take it to be zero. A term tied beyond the limit to another term but
//! within its tolerance is seen poorly, said, and applied.
//! lever arm (C_b^n l does not change) nor the clock (a shift in time is one along the
//! track).

use crate::Vec3;
use crate::data::fixes::Fixes;
use crate::data::paired::GAP_MARGIN_S;
use crate::installation::dead_reckoning::{Track, dead_reckon, interior};
use crate::installation::estimate::bound::{
    CORRELATION_LIMIT, Tolerances, Unseen, Why, whitened_bound,
};
use crate::installation::estimate::fit::{MAX_LEVER_ARM_M, MAX_SCALE};
use crate::installation::frames::Attitude;
use crate::installation::terms::names::TermName;
use crate::installation::terms::{Installation, PerKind, TermSet};
use nalgebra::{DMatrix, DVector};
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

/// The largest time offset considered, s: fixes within it of a piece's ends are not
/// fitted, so that every trial offset reads the attitude over the same fixes.
pub const TIME_OFFSET_MARGIN_S: f64 = GAP_MARGIN_S;

/// The least span of headings over which the terms only turns show
/// ([`SHOWN_BY_TURNS`]) are fitted to fixes, rad (a quarter turn): at one heading the
/// DVL's yaw and the attitude's heading error there are one, and the lever arm (C_b^n l)
/// and the clock (a shift along the track) move the track as its start does. On A-KIT a
/// straight segment's yaw, applied to the turning ones, left more drift than none, and
/// its lever arm and clock, fitted where they were barely tied to the start, twice as
/// much.
pub const MIN_HEADING_SPAN_RAD: f64 = std::f64::consts::FRAC_PI_2;

/// The terms only a turning vehicle shows to fixes.
const SHOWN_BY_TURNS: [&str; 4] = [
    "misalignment_z_rad",
    "lever_arm_x_m",
    "lever_arm_y_m",
    "time_offset_s",
];

/// The dead reckoning's random walks considered, in the white DVL noise's: a DVL noise
/// of AR(1) correlation ρ from one sample to the next walks (1 + ρ)/(1 − ρ) times as far
/// in variance (9 at ρ = 0.8, 39 at 0.95).
const WALK_SCALES: [f64; 8] = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0];

/// The scan's step for the time offset's start, s.
const SCAN_STEP_S: f64 = 0.25;

/// Huber's and Tukey's tuning constants, in a fix's standard deviations.
const HUBER_C: f64 = 1.345;
const TUKEY_C: f64 = 4.685;

/// The tolerance of each term fitted to fixes: beyond it a term is not applied. Fixes
/// of metres place a scale and a yaw well (they grow with the distance travelled), a
/// lever arm and a clock only as well as the turns show them; a lever arm within half
/// a metre and a clock within half a second move a dead reckoning by less than the
/// fixes' noise.
pub const FIX_TOLERANCES: Tolerances = PerKind {
    scale: 0.005,
    misalignment_rad: 0.5 * (std::f64::consts::PI / 180.0),
    lever_arm_m: 0.5,
    time_offset_s: 0.5,
    bias_m_s: 0.01,
};

/// The names of a piece's start position, north, east and depth, m, as the bound names
/// them, each beginning with [`START`].
const START: &str = "start_";
const START_NORTH: &str = "start_north_m";
const START_EAST: &str = "start_east_m";
const START_DEPTH: &str = "start_depth_m";

/// The noise of a fit to fixes: a fix's per horizontal axis and in depth, m, and the
/// DVL's white noise per axis, m/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixNoise {
    pub fix_m: f64,
    pub depth_m: f64,
    pub dvl_m_s: f64,
}

/// The terms fitted to fixes, their bound, and the fixes used.
#[derive(Debug, Clone, PartialEq)]
pub struct FixFit {
    /// The terms asked for, and the installation applied: every term the fixes cannot
    /// show held at zero.
    pub terms: TermSet,
    pub installation: Installation,
    /// Each parameter of `terms`, in their order: its name, its value (for a term not
    /// applied, that of the fit it was left out of), its standard deviation and Fisher bound, and whether it
    /// was estimated at all (a horizontal fit does not estimate roll, pitch or the
    /// lever arm's depth).
    pub names: Vec<&'static str>,
    pub value: Vec<f64>,
    pub std: Vec<f64>,
    pub bound_std: Vec<f64>,
    pub estimated: Vec<bool>,
    /// Whether each parameter is applied: estimated, and not left out as one the fixes
    /// do not show.
    pub applied: Vec<bool>,
    /// The correlations of the parameters applied, `[term][term]` over `names`; NaN
    /// with one not applied.
    pub correlation: Vec<Vec<f64>>,
    /// Why each term not applied could not be seen (from the fit it was left out of).
    pub unseen: Vec<Unseen>,
    /// The dead reckoning's random walk the residuals read, in the white DVL noise's.
    pub walk_scale: f64,
    /// The variance factor of the whitened residuals, and its degrees of freedom n − p.
    pub variance_factor: f64,
    pub freedom: usize,
    /// The fixes fitted, those left out as outliers (their indices in the fixes), and
    /// those outside every piece of the DVL record (beyond its margin).
    pub fitted: usize,
    pub outliers: Vec<usize>,
    pub outside: usize,
    /// How many pieces of the DVL record the fixes cover (a start position each).
    pub pieces: usize,
    /// The RMS of the residuals of the fixes fitted, north, east and depth (NaN without
    /// one), m.
    pub residual_rms_m: Vec3,
    /// The axes fitted: 2 (north, east) or 3 (and depth).
    pub axes: usize,
    /// How far the dead reckoning with the terms applied travelled over the pieces
    /// fitted, horizontally, m.
    pub distance_m: f64,
}

impl FixFit {
    /// The half-width of the 95 % interval of parameter `k`: Student's t on
    /// [`Self::freedom`] times its standard deviation.
    pub fn half_width_95(&self, k: usize) -> f64 {
        use statrs::distribution::{ContinuousCDF, StudentsT};
        let t = StudentsT::new(0.0, 1.0, self.freedom.max(1) as f64).expect("positive freedom");
        t.inverse_cdf(0.975) * self.std[k]
    }

    /// Whether the parameter named `name` was applied.
    pub fn is_applied(&self, name: &str) -> bool {
        let k = self.names.iter().position(|n| *n == name);
        k.is_some_and(|k| self.applied[k])
    }
}

/// Why the terms cannot be fitted to the fixes.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FixFitError {
    #[error(
        "no fix lies within a piece of the DVL record ({fixes} fixes from {fix_span_s:?} s, the DVL's {pieces} pieces from {dvl_span_s:?} s on its clock, each less {TIME_OFFSET_MARGIN_S} s at its ends): the fixes do not overlap the DVL; give fixes of the same dive, on the attitude's clock"
    )]
    NoOverlap {
        fixes: usize,
        fix_span_s: (f64, f64),
        pieces: usize,
        dvl_span_s: (f64, f64),
    },
    #[error(
        "{fitted} fixes within the DVL's pieces give {residuals} residuals for {parameters} parameters (the terms and a start position per piece): a fit needs more; give more fixes, or fewer terms"
    )]
    TooFewFixes {
        fitted: usize,
        residuals: usize,
        parameters: usize,
    },
    #[error(
        "the attitude does not cover the DVL's samples at the time offset {time_offset_s} s: give the attitude of the whole dive"
    )]
    NoAttitude { time_offset_s: f64 },
}

/// Fits `terms` (scale, misalignment, lever arm, time offset; any other is refused by
/// the caller) to `fixes` from the DVL samples `dvl` cut into `pieces`, under `noise`.
pub fn fit_fixes(
    dvl: (&[f64], &[Vec3]),
    pieces: &[Range<usize>],
    attitude: &Attitude,
    fixes: &Fixes,
    terms: TermSet,
    noise: FixNoise,
) -> Result<FixFit, FixFitError> {
    let problem = Problem::new(dvl, pieces, attitude, fixes, terms, noise)?;
    let mut shown = Shown::of(&problem);
    let last = shown.eliminate(&problem)?;
    let (last_std, correlation, _) = problem.bound(&last, &shown.applied);
    let last_bound = problem.bound_at(&last, &shown.applied, 1.0).0;
    for k in 0..problem.names.len() {
        if shown.applied[k] {
            shown.keep(k, (last.terms[k], last_std[k], last_bound[k]));
        }
    }
    Ok(FixFit {
        terms,
        installation: Installation::from_parameters(&terms, &last.terms),
        names: problem.names.clone(),
        value: shown.value,
        std: shown.std,
        bound_std: shown.bound_std,
        estimated: problem.estimated.clone(),
        applied: shown.applied,
        correlation,
        unseen: shown.unseen,
        walk_scale: problem.walk_scale.get(),
        variance_factor: last.variance_factor(),
        freedom: last.freedom,
        fitted: last.kept.iter().filter(|&&kept| kept).count(),
        outliers: (last.kept.iter().enumerate())
            .filter(|(_, kept)| !**kept)
            .map(|(j, _)| problem.fix_of[j])
            .collect(),
        outside: problem.outside,
        pieces: problem.pieces.len(),
        residual_rms_m: problem.residual_rms(&last),
        axes: problem.axes,
        distance_m: (problem.tracks(&last.terms)?.iter())
            .map(|track| {
                (track.position_m.windows(2))
                    .map(|pair| (pair[1][0] - pair[0][0]).hypot(pair[1][1] - pair[0][1]))
                    .sum::<f64>()
            })
            .sum(),
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
}

impl Shown {
    /// Every term estimated, but those only turns show where the headings span under
    /// [`MIN_HEADING_SPAN_RAD`].
    fn of(problem: &Problem) -> Shown {
        let n = problem.names.len();
        let mut shown = Shown {
            applied: problem.estimated.clone(),
            unseen: Vec::new(),
            value: vec![0.0; n],
            std: vec![f64::INFINITY; n],
            bound_std: vec![f64::INFINITY; n],
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
                }
            }
        }
        shown
    }

    /// Term `k`'s value, standard deviation and bound.
    fn keep(&mut self, k: usize, (value, std, bound_std): (f64, f64, f64)) {
        (self.value[k], self.std[k], self.bound_std[k]) = (value, std, bound_std);
    }

    /// Backward elimination: the term the fixes show least (flat, or furthest beyond
    /// the correlation limit with a start or its tolerance) is left out and the rest
    /// fitted again, until no term left is one the fixes do not show; the last fit.
    fn eliminate(&mut self, problem: &Problem) -> Result<Solution, FixFitError> {
        loop {
            let solution = problem.robust_fit(&self.applied)?;
            let (term_std, _, found) = problem.bound(&solution, &self.applied);
            let found: Vec<Unseen> = (found.into_iter())
                .filter(|u| problem.names.contains(&u.term))
                .collect();
            let worst = (found.iter())
                .map(|u| (u.term, unseen_by(u, &term_std, problem)))
                .filter(|(_, by)| *by > 1.0)
                .max_by(|a, b| a.1.total_cmp(&b.1));
            let Some((term, _)) = worst else {
                // Seen, if poorly: tied to another term.
                self.unseen.extend(found);
                return Ok(solution);
            };
            let k = problem.position(term);
            let bound = problem.bound_at(&solution, &self.applied, 1.0).0[k];
            self.keep(k, (solution.terms[k], term_std[k], bound));
            self.unseen
                .extend(found.into_iter().filter(|u| u.term == term));
            self.applied[k] = false;
        }
    }
}

/// How far beyond being shown `unseen` puts its term, where above 1 the fixes do not
/// show it: infinite on a flat direction, its correlation with a start position over
/// the limit, or its standard deviation over its tolerance. A term tied to another term
/// within its tolerance is seen, if poorly, and applied.
fn unseen_by(unseen: &Unseen, std: &[f64], problem: &Problem) -> f64 {
    let k = problem.position(unseen.term);
    let beyond = std[k] / FIX_TOLERANCES.of(problem.terms.parameter_kinds()[k]);
    match &unseen.why {
        Why::Flat { .. } => f64::INFINITY,
        // Tied to a start position, a term moves the track as the start does, and the
        // start takes its place; tied to another term, it is left in, or the other
        // would take its true value.
        Why::Correlated { correlation, with } if with.starts_with(START) => {
            beyond.max(correlation.abs() / CORRELATION_LIMIT)
        }
        _ => beyond,
    }
}

/// A fit's state: the term parameters (every one of the term set, those not estimated
/// zero), the start positions (piece by piece, axis by axis), which fixes it kept, and
/// its whitened residuals.
#[derive(Debug, Clone)]
struct Solution {
    terms: Vec<f64>,
    starts: Vec<f64>,
    kept: Vec<bool>,
    whitened: DVector<f64>,
    freedom: usize,
}

impl Solution {
    fn variance_factor(&self) -> f64 {
        self.whitened.norm_squared() / self.freedom.max(1) as f64
    }
}

/// What a fit to fixes works on: the DVL's pieces with a fix, the fixes each holds
/// (indices into the fixes), the terms and which of them are estimated.
struct Problem<'a> {
    dvl: (&'a [f64], &'a [Vec3]),
    attitude: &'a Attitude,
    fixes: &'a Fixes,
    terms: TermSet,
    noise: FixNoise,
    names: Vec<&'static str>,
    estimated: Vec<bool>,
    pieces: Vec<Range<usize>>,
    /// For each piece, the fixes in it.
    held: Vec<Vec<usize>>,
    /// For each fix fitted (pieces in order), its index among the fixes.
    fix_of: Vec<usize>,
    outside: usize,
    axes: usize,
    /// The dead reckoning's random walk over the white DVL noise's, as the residuals
    /// read it ([`Problem::read_walk`]): a DVL noise correlated in time walks further.
    walk_scale: std::cell::Cell<f64>,
}

impl<'a> Problem<'a> {
    fn new(
        dvl: (&'a [f64], &'a [Vec3]),
        pieces: &[Range<usize>],
        attitude: &'a Attitude,
        fixes: &'a Fixes,
        terms: TermSet,
        noise: FixNoise,
    ) -> Result<Problem<'a>, FixFitError> {
        let axes = if fixes.depth_m.is_some() { 3 } else { 2 };
        let names = terms.parameter_names();
        let estimated = names
            .iter()
            .map(|name| match *name {
                "lever_arm_z_m" => false,
                "misalignment_x_rad" | "misalignment_y_rad" => axes == 3,
                _ => true,
            })
            .collect();
        let time_s = dvl.0;
        let (used, held) = pieces_with_fixes(time_s, pieces, attitude, fixes);
        let fix_of: Vec<usize> = held.iter().flatten().copied().collect();
        if fix_of.is_empty() {
            let span = |t: &[f64]| {
                (
                    t.first().copied().unwrap_or(f64::NAN),
                    t.last().copied().unwrap_or(f64::NAN),
                )
            };
            return Err(FixFitError::NoOverlap {
                fixes: fixes.len(),
                fix_span_s: span(&fixes.time_s),
                pieces: pieces.len(),
                dvl_span_s: span(time_s),
            });
        }
        let problem = Problem {
            dvl,
            attitude,
            fixes,
            terms,
            noise,
            names,
            estimated,
            outside: fixes.len() - fix_of.len(),
            pieces: used,
            held,
            fix_of,
            axes,
            walk_scale: std::cell::Cell::new(1.0),
        };
        let parameters = problem.free_count(&problem.estimated);
        let residuals = problem.fix_of.len() * axes;
        if residuals <= parameters {
            return Err(FixFitError::TooFewFixes {
                fitted: problem.fix_of.len(),
                residuals,
                parameters,
            });
        }
        Ok(problem)
    }

    /// Where the parameter named `name` is among the terms'.
    fn position(&self, name: &str) -> usize {
        (self.names.iter())
            .position(|n| *n == name)
            .expect("a term's name")
    }

    /// The span of the attitude's (unwrapped) yaw over the pieces fitted, rad.
    fn heading_span_rad(&self) -> f64 {
        let (first, last) = (self.pieces[0].start, self.pieces[self.pieces.len() - 1].end);
        let (from, to) = (self.dvl.0[first], self.dvl.0[last - 1]);
        let yaw = (self.attitude.time_s.iter().zip(&self.attitude.angles_rad))
            .filter(|(t, _)| (from..=to).contains(*t))
            .map(|(_, angles)| angles[2]);
        let (low, high) = yaw.fold((f64::INFINITY, f64::NEG_INFINITY), |(low, high), y| {
            (low.min(y), high.max(y))
        });
        (high - low).max(0.0)
    }

    /// How many parameters a fit of the `free` terms estimates, the starts with them.
    fn free_count(&self, free: &[bool]) -> usize {
        free.iter().filter(|&&f| f).count() + self.pieces.len() * self.axes
    }

    /// Each piece's track under the term parameters `terms`.
    fn tracks(&self, terms: &[f64]) -> Result<Vec<Track>, FixFitError> {
        let installation = Installation::from_parameters(&self.terms, terms);
        (self.pieces.iter())
            .map(|piece| {
                let dvl = (&self.dvl.0[piece.clone()], &self.dvl.1[piece.clone()]);
                dead_reckon(&installation, dvl, self.attitude).ok_or(FixFitError::NoAttitude {
                    time_offset_s: installation.time_offset_s,
                })
            })
            .collect()
    }

    /// The residuals (track plus start, less the fix), in blocks of one piece and one
    /// axis, fixes in order; a fix's place in its block is its place in the piece.
    fn residuals(&self, terms: &[f64], starts: &[f64]) -> Result<DVector<f64>, FixFitError> {
        let tracks = self.tracks(terms)?;
        let mut residuals = Vec::with_capacity(self.fix_of.len() * self.axes);
        for (p, (track, held)) in tracks.iter().zip(&self.held).enumerate() {
            for axis in 0..self.axes {
                for &j in held {
                    let fix_time = self.fixes.time_s[j];
                    let position = track.at(fix_time).ok_or(FixFitError::NoAttitude {
                        time_offset_s: track.time_s[0] - self.dvl.0[self.pieces[p].start],
                    })?;
                    let fix = match axis {
                        2 => self.fixes.depth_m.as_ref().expect("a depth")[j],
                        _ => self.fixes.north_east_m[j][axis],
                    };
                    residuals.push(position[axis] + starts[p * self.axes + axis] - fix);
                }
            }
        }
        Ok(DVector::from_vec(residuals))
    }

    /// The lower Cholesky factor of each block's covariance (piece, then axis) with the
    /// fixes weighed by `weights` (a fix of weight w has σ_f² / w; one of weight zero
    /// is left out, its variance far beyond any other).
    fn whiteners(&self, weights: &[f64]) -> Vec<DMatrix<f64>> {
        let step_s = crate::data::paired::sample_interval(self.dvl.0);
        let walk = self.walk_scale.get() * self.noise.dvl_m_s.powi(2) * step_s;
        let mut offset = 0;
        let mut factors = Vec::new();
        for (piece, held) in self.pieces.iter().zip(&self.held) {
            let start_s = self.dvl.0[piece.start];
            for axis in 0..self.axes {
                let fix_m = if axis == 2 {
                    self.noise.depth_m
                } else {
                    self.noise.fix_m
                };
                let covariance = DMatrix::from_fn(held.len(), held.len(), |a, b| {
                    let (ta, tb) = (self.fixes.time_s[held[a]], self.fixes.time_s[held[b]]);
                    let own = if a == b {
                        fix_m.powi(2) / weights[offset + a].max(1e-12)
                    } else {
                        0.0
                    };
                    own + walk * (ta.min(tb) - start_s)
                });
                let factor = covariance
                    .cholesky()
                    .expect("a covariance with a positive diagonal")
                    .l();
                factors.push(factor);
            }
            offset += held.len();
        }
        factors
    }

    /// `vector`'s blocks (or each column's, for a matrix) whitened by `factors`.
    fn whiten(&self, factors: &[DMatrix<f64>], matrix: &DMatrix<f64>) -> DMatrix<f64> {
        let mut out = matrix.clone();
        let mut row = 0;
        for factor in factors {
            let n = factor.nrows();
            let block = matrix.rows(row, n).into_owned();
            let solved = factor
                .solve_lower_triangular(&block)
                .expect("a Cholesky factor is invertible");
            out.rows_mut(row, n).copy_from(&solved);
            row += n;
        }
        out
    }

    /// The Jacobian of the residuals in the free term parameters (central differences)
    /// and the starts (each residual moves one for one with its piece's start on its
    /// axis).
    fn jacobian(&self, solution: &Solution, free: &[bool]) -> Result<DMatrix<f64>, FixFitError> {
        let rows = self.fix_of.len() * self.axes;
        let free_terms: Vec<usize> = (0..free.len()).filter(|&k| free[k]).collect();
        let mut jacobian = DMatrix::zeros(rows, free_terms.len() + self.pieces.len() * self.axes);
        for (column, &k) in free_terms.iter().enumerate() {
            let step = match self.names[k] {
                "time_offset_s" => 1e-3,
                name if name.starts_with("lever_arm") => 1e-3,
                _ => 1e-6,
            };
            let moved = |by: f64| {
                let mut terms = solution.terms.clone();
                terms[k] += by;
                self.residuals(&terms, &solution.starts)
            };
            let (up, down) = (moved(step)?, moved(-step)?);
            jacobian.set_column(column, &((up - down) / (2.0 * step)));
        }
        let mut row = 0;
        for (p, held) in self.held.iter().enumerate() {
            for axis in 0..self.axes {
                let column = free_terms.len() + p * self.axes + axis;
                for r in row..row + held.len() {
                    jacobian[(r, column)] = 1.0;
                }
                row += held.len();
            }
        }
        Ok(jacobian)
    }

    /// Each fitted fix's weight: 1 where kept, 0 where not, per block row.
    fn weights(&self, kept: &[bool]) -> Vec<f64> {
        kept.iter().map(|&k| f64::from(u8::from(k))).collect()
    }

    /// Gauss–Newton on the whitened residuals from `start`, with the `free` terms and
    /// each fix weighed by `weights` (one per fitted fix).
    fn solve(
        &self,
        mut solution: Solution,
        free: &[bool],
        weights: &[f64],
    ) -> Result<Solution, FixFitError> {
        let factors = self.whiteners(weights);
        let free_terms: Vec<usize> = (0..free.len()).filter(|&k| free[k]).collect();
        for _ in 0..30 {
            let residuals = self.residuals(&solution.terms, &solution.starts)?;
            let jacobian = self.jacobian(&solution, free)?;
            let whitened = self.whiten(
                &factors,
                &DMatrix::from_column_slice(residuals.len(), 1, residuals.as_slice()),
            );
            let whitened_jacobian = self.whiten(&factors, &jacobian);
            let step = least_squares_step(&whitened_jacobian, &whitened.column(0).into_owned());
            for (column, &k) in free_terms.iter().enumerate() {
                let limit = self.limit(k);
                solution.terms[k] = (solution.terms[k] - step[column]).clamp(-limit, limit);
            }
            for (s, start) in solution.starts.iter_mut().enumerate() {
                *start -= step[free_terms.len() + s];
            }
            let scale_of_step = free_terms
                .iter()
                .enumerate()
                .map(|(column, &k)| step[column].abs() / self.step_tolerance(k))
                .fold(0.0, f64::max);
            if scale_of_step < 1.0 {
                break;
            }
        }
        let residuals = self.residuals(&solution.terms, &solution.starts)?;
        solution.whitened = self
            .whiten(
                &factors,
                &DMatrix::from_column_slice(residuals.len(), 1, residuals.as_slice()),
            )
            .column(0)
            .into_owned();
        let kept_rows = weights.iter().filter(|&&w| w > 0.0).count() * self.axes;
        solution.freedom = kept_rows.saturating_sub(self.free_count(free));
        Ok(solution)
    }

    /// The largest magnitude parameter `k` may take: the time offset within the margin
    /// its fixes were chosen for, the others within any installation's
    /// ([`MAX_SCALE`], [`MAX_LEVER_ARM_M`], a quarter turn); a term along a direction
    /// the fixes barely feel stops there, and is then found unseen.
    fn limit(&self, k: usize) -> f64 {
        match self.names[k] {
            // Inside the margin by more than the Jacobian's step.
            "time_offset_s" => TIME_OFFSET_MARGIN_S - 0.01,
            "scale" => MAX_SCALE,
            name if name.starts_with("lever_arm") => MAX_LEVER_ARM_M,
            _ => std::f64::consts::FRAC_PI_2,
        }
    }

    /// A step in parameter `k` below which Gauss–Newton has converged.
    fn step_tolerance(&self, k: usize) -> f64 {
        match self.names[k] {
            "time_offset_s" => 1e-5,
            name if name.starts_with("lever_arm") => 1e-5,
            _ => 1e-8,
        }
    }

    /// Least squares of the `free` terms (the time offset from the best of a scan),
    /// then Huber's and Tukey's weights, then least squares on the fixes kept.
    fn robust_fit(&self, free: &[bool]) -> Result<Solution, FixFitError> {
        let blank = Solution {
            terms: vec![0.0; self.names.len()],
            starts: vec![0.0; self.pieces.len() * self.axes],
            kept: vec![true; self.fix_of.len()],
            whitened: DVector::zeros(0),
            freedom: 0,
        };
        let mut solution = self.scan_time_offset(blank, free)?;
        for loss in [
            Loss::Huber,
            Loss::Huber,
            Loss::Tukey,
            Loss::Tukey,
            Loss::Tukey,
        ] {
            let u = self.standardised(&solution)?;
            let weights: Vec<f64> = u.iter().map(|&u| loss.weight(u)).collect();
            solution = self.solve(solution, free, &weights)?;
            solution.kept = weights.iter().map(|&w| w > 0.0).collect();
        }
        let kept = solution.kept.clone();
        let weights = self.weights(&kept);
        self.read_walk(&solution, free, &weights)?;
        let mut last = self.solve(solution, free, &weights)?;
        last.kept = kept;
        Ok(last)
    }

    /// Reads the dead reckoning's random walk from the residuals: of the walks
    /// [`WALK_SCALES`] times the white DVL noise's, the one under which the fixes kept are
    /// likeliest (the Gaussian likelihood, its scale profiled out), kept for the fits
    /// and bounds that follow.
    fn read_walk(
        &self,
        start: &Solution,
        free: &[bool],
        weights: &[f64],
    ) -> Result<(), FixFitError> {
        let mut best = (f64::NEG_INFINITY, 1.0);
        for scale in WALK_SCALES {
            self.walk_scale.set(scale);
            let solved = self.solve(start.clone(), free, weights)?;
            let factors = self.whiteners(weights);
            let kept = weights.iter().filter(|&&w| w > 0.0).count() * self.axes;
            // Of the fixes kept: a fix left out has a variance beyond all others, the
            // same under every walk, and drops out of the comparison.
            let mut log_det = 0.0;
            let (mut block, mut offset) = (0, 0);
            for held in &self.held {
                for _ in 0..self.axes {
                    let diagonal = factors[block].diagonal();
                    for a in (0..held.len()).filter(|&a| weights[offset + a] > 0.0) {
                        log_det += 2.0 * diagonal[a].ln();
                    }
                    block += 1;
                }
                offset += held.len();
            }
            let n = kept as f64;
            let likelihood = -0.5 * (n * (solved.whitened.norm_squared() / n).ln() + log_det);
            if likelihood > best.0 {
                best = (likelihood, scale);
            }
        }
        self.walk_scale.set(best.1);
        Ok(())
    }

    /// Each fitted fix's residual in its own standard deviations: the root mean square
    /// over its axes of the residual over √(σ_f² + σ_v² Δt · t).
    fn standardised(&self, solution: &Solution) -> Result<Vec<f64>, FixFitError> {
        let residuals = self.residuals(&solution.terms, &solution.starts)?;
        let step_s = crate::data::paired::sample_interval(self.dvl.0);
        let walk = self.walk_scale.get() * self.noise.dvl_m_s.powi(2) * step_s;
        let mut squares = vec![0.0; self.fix_of.len()];
        let (mut row, mut offset) = (0, 0);
        for (piece, held) in self.pieces.iter().zip(&self.held) {
            let start_s = self.dvl.0[piece.start];
            for axis in 0..self.axes {
                let fix_m = if axis == 2 {
                    self.noise.depth_m
                } else {
                    self.noise.fix_m
                };
                for (a, &j) in held.iter().enumerate() {
                    let variance = fix_m.powi(2) + walk * (self.fixes.time_s[j] - start_s);
                    squares[offset + a] += residuals[row].powi(2) / variance;
                    row += 1;
                }
            }
            offset += held.len();
        }
        Ok(squares
            .iter()
            .map(|s| (s / self.axes as f64).sqrt())
            .collect())
    }

    /// The fit from the best time offset of a scan over ±[`TIME_OFFSET_MARGIN_S`]
    /// (each trial a least-squares fit of the other terms), then of every free term;
    /// without a free time offset, least squares from zero.
    fn scan_time_offset(&self, start: Solution, free: &[bool]) -> Result<Solution, FixFitError> {
        let ones = vec![1.0; self.fix_of.len()];
        let Some(offset) = self.names.iter().position(|n| *n == "time_offset_s") else {
            return self.solve(start, free, &ones);
        };
        if !free[offset] {
            return self.solve(start, free, &ones);
        }
        let mut others = free.to_vec();
        others[offset] = false;
        let steps = (TIME_OFFSET_MARGIN_S / SCAN_STEP_S).round() as i64;
        let mut best: Option<(f64, Solution)> = None;
        for step in -steps..=steps {
            let mut trial = start.clone();
            let limit = self.limit(offset);
            trial.terms[offset] = (step as f64 * SCAN_STEP_S).clamp(-limit, limit);
            let Ok(solved) = self.solve(trial, &others, &ones) else {
                continue;
            };
            let cost = solved.whitened.norm_squared();
            if best.as_ref().is_none_or(|(c, _)| cost < *c) {
                best = Some((cost, solved));
            }
        }
        let (_, best) = best.ok_or(FixFitError::NoAttitude { time_offset_s: 0.0 })?;
        self.solve(best, free, &ones)
    }

    /// The standard deviations, correlations and unseen terms of `solution` over the
    /// term parameters (NaN or infinite where not `free`), scaled by its variance
    /// factor.
    fn bound(&self, solution: &Solution, free: &[bool]) -> (Vec<f64>, Vec<Vec<f64>>, Vec<Unseen>) {
        self.bound_at(solution, free, solution.variance_factor())
    }

    /// [`Self::bound`] with the variance factor `factor` (1: the Fisher bound).
    fn bound_at(
        &self,
        solution: &Solution,
        free: &[bool],
        factor: f64,
    ) -> (Vec<f64>, Vec<Vec<f64>>, Vec<Unseen>) {
        let free_terms: Vec<usize> = (0..free.len()).filter(|&k| free[k]).collect();
        let weights = self.weights(&solution.kept);
        let factors = self.whiteners(&weights);
        let jacobian = self
            .jacobian(solution, free)
            .expect("the solution's residuals were read");
        let whitened = self.whiten(&factors, &jacobian);
        let normal = whitened.transpose() * &whitened;
        let mut names: Vec<&'static str> = free_terms.iter().map(|&k| self.names[k]).collect();
        let start_names = [START_NORTH, START_EAST, START_DEPTH];
        for _ in 0..self.pieces.len() {
            names.extend(&start_names[..self.axes]);
        }
        let kinds = self.terms.parameter_kinds();
        let tolerance = |c: usize| match free_terms.get(c) {
            Some(&k) => FIX_TOLERANCES.of(kinds[k]),
            None => f64::INFINITY,
        };
        let (std, correlation, unseen) = whitened_bound(&normal, &names, factor, tolerance);
        let n = self.names.len();
        let place = |k: usize| free_terms.iter().position(|&f| f == k);
        let term_std = (0..n)
            .map(|k| place(k).map_or(f64::INFINITY, |c| std[c]))
            .collect();
        let term_correlation = (0..n)
            .map(|j| {
                (0..n)
                    .map(|k| match (place(j), place(k)) {
                        (Some(a), Some(b)) => correlation[a][b],
                        _ if j == k => 1.0,
                        _ => f64::NAN,
                    })
                    .collect()
            })
            .collect();
        (term_std, term_correlation, unseen)
    }

    /// The RMS of the residuals of the fixes kept, per axis, m (NaN on an axis not
    /// fitted).
    fn residual_rms(&self, solution: &Solution) -> Vec3 {
        let residuals = self
            .residuals(&solution.terms, &solution.starts)
            .expect("the solution's residuals were read");
        let (mut sums, mut counts) = ([0.0; 3], [0usize; 3]);
        let (mut row, mut offset) = (0, 0);
        for held in &self.held {
            for axis in 0..self.axes {
                for a in 0..held.len() {
                    if solution.kept[offset + a] {
                        sums[axis] += residuals[row].powi(2);
                        counts[axis] += 1;
                    }
                    row += 1;
                }
            }
            offset += held.len();
        }
        [0, 1, 2].map(|k| {
            if counts[k] == 0 {
                f64::NAN
            } else {
                (sums[k] / counts[k] as f64).sqrt()
            }
        })
    }
}

/// The pieces of the DVL record stamped `time_s` that hold a fix, each cut to the
/// samples whose t + τ reads `attitude` whatever τ (so that every trial time offset
/// reads it over the same samples), and the fixes each holds: those at least
/// [`TIME_OFFSET_MARGIN_S`] inside it.
fn pieces_with_fixes(
    time_s: &[f64],
    pieces: &[Range<usize>],
    attitude: &Attitude,
    fixes: &Fixes,
) -> (Vec<Range<usize>>, Vec<Vec<usize>>) {
    let inside = interior(attitude, time_s);
    let (mut used, mut held) = (Vec::new(), Vec::new());
    for piece in pieces {
        let piece = piece.start.max(inside.start)..piece.end.min(inside.end);
        if piece.len() < 2 {
            continue;
        }
        let (first, last) = (time_s[piece.start], time_s[piece.end - 1]);
        let within: Vec<usize> = (0..fixes.len())
            .filter(|&j| {
                let t = fixes.time_s[j];
                t >= first + TIME_OFFSET_MARGIN_S && t <= last - TIME_OFFSET_MARGIN_S
            })
            .collect();
        if !within.is_empty() {
            used.push(piece);
            held.push(within);
        }
    }
    (used, held)
}

/// The Gauss–Newton step of whitened residuals `r` with Jacobian `j`: the least-squares
/// solution of j · step = r, on the columns scaled to unit norm, by the singular value
/// decomposition (no step along a direction the residuals do not feel).
fn least_squares_step(j: &DMatrix<f64>, r: &DVector<f64>) -> DVector<f64> {
    let norms: Vec<f64> = j.column_iter().map(|c| c.norm().max(1e-300)).collect();
    let scaled = DMatrix::from_fn(j.nrows(), j.ncols(), |a, b| j[(a, b)] / norms[b]);
    let svd = scaled.svd(true, true);
    let largest = svd.singular_values.max();
    let step = svd
        .solve(r, 1e-10 * largest)
        .expect("the decomposition has both factors");
    DVector::from_fn(step.len(), |k, _| step[k] / norms[k])
}

/// The robust loss of a fix's standardised residual u: each fix's weight ψ(u)/u.
#[derive(Debug, Clone, Copy)]
enum Loss {
    Huber,
    Tukey,
}

impl Loss {
    fn weight(self, u: f64) -> f64 {
        match self {
            Loss::Huber => (HUBER_C / u.abs()).min(1.0),
            Loss::Tukey if u.abs() < TUKEY_C => (1.0 - (u / TUKEY_C).powi(2)).powi(2),
            Loss::Tukey => 0.0,
        }
    }
}
