//! The problem a fit to position fixes solves (for `fit_fixes`): the DVL's pieces
//! that hold a fix and the fixes each holds; the residuals (the dead reckoning through
//! the terms, less the fixes) and their Jacobian; their whitening under the noise
//! ([`super::fix_noise`]), each piece's start profiled out; the fits' one solve loop
//! on them; the scan over the time offset, the robust loop, the noise read from
//! the residuals and the terms averaged over its walks; and the bound of a solution.
//! In: the DVL samples, an [`Attitude`], the [`Fixes`], the terms and the noise. Out: a
//! [`Solution`] and its bound.

use crate::Vec3;
use crate::data::fixes::Fixes;
use crate::installation::dead_reckoning::{
    AttitudeRead, Track, dead_reckon_along, interior, path_length_m,
};
use crate::installation::estimate::bound::{Unseen, whitened_bound};
use crate::installation::estimate::fit::{
    MAX_LEVER_ARM_M, MAX_SCALE, PATIENCE, TIME_OFFSET_MARGIN_S,
};
use crate::installation::estimate::fit::{
    TIME_OFFSET_SCAN_STEP_S, levenberg_marquardt, scan_offsets,
};
use crate::installation::estimate::fix_noise::{NoiseShape, Whitener, Whitening};
use crate::installation::estimate::fix_solve::Whitened;
use crate::installation::estimate::fix_terms::{
    FIX_LATENCY, FIX_TOLERANCES, FixFitError, FixNoise, FixTerms,
};
use crate::installation::estimate::robust::{Loss, gross_jumps};
use crate::installation::frames::Attitude;
use crate::installation::terms::kind::TermKind;
use crate::installation::terms::{Installation, TermSet};
use nalgebra::{DMatrix, DVector};
use std::ops::Range;

/// How many times the median jump of the fixes' distance from the dead reckoning, one
/// fix to the next, and their given noise per axis σ, a fix's jumps must be for it to be
/// left out as grossly off. White fixes jump by σ√2 per axis; one of 10 σ has odds of
/// about 1e-11. On A-KIT's positions (no noise), the uncorrected lever arm alone makes
/// the turns' jumps ten times the median, hence the floor at the noise given.
const GROSS: f64 = 10.0;

/// The relative tolerance that stops the solve loop on the fixes (on the cost, the
/// step and the gradient): their Jacobian is by central differences, good to about
/// 10⁻⁶ of a step's effect, so that a tighter one only spends evaluations.
const TOLERANCE: f64 = 1e-10;

/// The terms averaged over the noise's walks: their values, standard deviations and
/// correlations, over every parameter of the term set.
pub(super) type Averaged = (Vec<f64>, Vec<f64>, Vec<Vec<f64>>);

/// A fit's state: the term parameters (every one of the term set, those not estimated
/// zero), each block's start position (piece by piece, axis by axis, profiled), which
/// fixes it kept, the noise's shape, and its whitened residuals.
#[derive(Debug, Clone)]
pub(super) struct Solution {
    pub(super) terms: Vec<f64>,
    starts: Vec<f64>,
    pub(super) kept: Vec<bool>,
    pub(super) shape: NoiseShape,
    whitened: Vec<f64>,
    pub(super) freedom: usize,
    /// ln |J̃ᵀJ̃|, the log-determinant of the free terms' whitened information (the
    /// starts profiled out) under `shape`: what the terms take of the residuals, which
    /// the restricted likelihood gives back ([`Whitening::restricted_log_likelihood`]).
    information_log_det: f64,
}

impl Solution {
    pub(super) fn variance_factor(&self) -> f64 {
        self.cost() / self.freedom.max(1) as f64
    }

    /// The whitened residuals' sum of squares.
    fn cost(&self) -> f64 {
        self.whitened.iter().map(|w| w * w).sum()
    }

    /// Each fitted fix's weight: 1 where kept, 0 where not.
    fn weights(&self) -> Vec<f64> {
        weights_of(&self.kept)
    }

    /// The restricted log-likelihood of this fit's noise shape under `whitening` (its
    /// shape, its fixes weighed as the fit weighed them;
    /// [`Whitening::restricted_log_likelihood`]).
    fn likelihood(&self, whitening: &Whitening) -> f64 {
        whitening.restricted_log_likelihood(self.cost(), self.freedom, self.information_log_det)
    }
}

/// ln |A| of a symmetric positive semi-definite `a`, each eigenvalue floored at 1e-12 of
/// the largest (a direction no residual feels counts alike under every noise).
fn log_det_symmetric(a: &DMatrix<f64>) -> f64 {
    let eigenvalues = a.clone().symmetric_eigen().eigenvalues;
    let floor = 1e-12 * eigenvalues.iter().fold(0.0f64, |m, &l| m.max(l));
    eigenvalues
        .iter()
        .map(|&l| l.max(floor).max(f64::MIN_POSITIVE).ln())
        .sum()
}

/// The weight of each fix `kept`: 1, or 0 where left out.
fn weights_of(kept: &[bool]) -> Vec<f64> {
    kept.iter().map(|&k| f64::from(u8::from(k))).collect()
}

/// What a fit to fixes works on: the DVL's pieces with a fix, the fixes each holds
/// (indices into the fixes), the terms and which of them are estimated.
pub(super) struct Problem<'a> {
    dvl: (&'a [f64], &'a [Vec3]),
    attitude: &'a Attitude,
    fixes: &'a Fixes,
    terms: TermSet,
    /// The installation the terms are fitted around (each parameter an offset from its
    /// value): none for a calibration, the one carried to a dive for its clock.
    carried: Installation,
    noise: FixNoise,
    /// The parameters: the term set's, then the fixes' latency where it is fitted.
    pub(super) names: Vec<&'static str>,
    kinds: Vec<TermKind>,
    /// Where the fixes' latency is among the parameters, where it is fitted.
    latency: Option<usize>,
    pub(super) estimated: Vec<bool>,
    pub(super) pieces: Vec<Range<usize>>,
    /// For each piece, the fixes in it.
    held: Vec<Vec<usize>>,
    /// For each fix fitted (pieces in order), its index among the fixes.
    pub(super) fix_of: Vec<usize>,
    /// For each fix fitted, its horizontal white variance in the noise's (`fix_m`'s):
    /// 1, or its own where the fixes carry their noise.
    relative: Vec<f64>,
    pub(super) outside: usize,
    pub(super) axes: usize,
    /// The attitude read along each piece at the clocks read last.
    read: AttitudeRead,
}

impl<'a> Problem<'a> {
    pub(super) fn new(
        dvl: (&'a [f64], &'a [Vec3]),
        pieces: &[Range<usize>],
        attitude: &'a Attitude,
        fixes: &'a Fixes,
        (terms, carried): (FixTerms, Installation),
        noise: FixNoise,
    ) -> Result<Problem<'a>, FixFitError> {
        let axes = if fixes.depth_m.is_some() { 3 } else { 2 };
        let mut names = terms.set.parameter_names();
        let mut kinds = terms.set.parameter_kinds();
        let latency = terms.fix_latency.then_some(names.len());
        if latency.is_some() {
            // A time, limited, stepped and tolerated as the DVL's clock is.
            names.push(FIX_LATENCY);
            kinds.push(TermKind::TimeOffset);
        }
        let estimated = names
            .iter()
            .map(|name| match *name {
                "lever_arm_z_m" => false,
                "misalignment_x_rad" | "misalignment_y_rad" => axes == 3,
                _ => true,
            })
            .collect();
        let time_s = dvl.0;
        let centre_s = carried.time_offset_s;
        // A fix read up to a latency's limit earlier needs the track that much longer.
        let margin_s = match latency {
            Some(_) => 2.0 * TIME_OFFSET_MARGIN_S,
            None => TIME_OFFSET_MARGIN_S,
        };
        let (used, held) = pieces_with_fixes(time_s, pieces, attitude, fixes, (centre_s, margin_s));
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
                centre_s,
                margin_s,
            });
        }
        let problem = Problem {
            dvl,
            attitude,
            fixes,
            terms: terms.set,
            carried,
            noise,
            names,
            kinds,
            latency,
            estimated,
            outside: fixes.len() - fix_of.len(),
            relative: (fix_of.iter())
                .map(|&j| {
                    fixes
                        .noise_m
                        .as_ref()
                        .map_or(1.0, |n| (n[j] / noise.fix_m).powi(2))
                })
                .collect(),
            pieces: used,
            held,
            fix_of,
            axes,
            read: AttitudeRead::default(),
        };
        problem.enough(&vec![true; problem.fix_of.len()], &problem.estimated)?;
        Ok(problem)
    }

    /// Refuses a fit of the `free` terms to the fixes `kept` that leaves no residual
    /// beyond its parameters.
    fn enough(&self, kept: &[bool], free: &[bool]) -> Result<(), FixFitError> {
        let fitted = kept.iter().filter(|&&k| k).count();
        let starts = (self.whitening(&weights_of(kept), NoiseShape::GIVEN)).starts_fitted();
        let parameters = free.iter().filter(|&&f| f).count() + starts;
        let residuals = fitted * self.axes;
        if residuals <= parameters {
            return Err(FixFitError::TooFewFixes {
                fitted: kept.len(),
                outliers: kept.len() - fitted,
                residuals,
                parameters,
            });
        }
        Ok(())
    }

    /// Where the parameter named `name` is among the terms'.
    pub(super) fn position(&self, name: &str) -> usize {
        (self.names.iter())
            .position(|n| *n == name)
            .expect("a term's name")
    }

    /// The span of the attitude's (unwrapped) yaw over the times the fixes fitted span,
    /// rad: where the fixes cover only part of a dive, the turns they see.
    pub(super) fn heading_span_rad(&self) -> f64 {
        let spans = self.fix_spans();
        let yaw = (self.attitude.time_s.iter().zip(&self.attitude.angles_rad))
            .filter(|(t, _)| spans.iter().any(|span| span.contains(*t)))
            .map(|(_, angles)| angles[2]);
        let (low, high) = yaw.fold((f64::INFINITY, f64::NEG_INFINITY), |(low, high), y| {
            (low.min(y), high.max(y))
        });
        (high - low).max(0.0)
    }

    /// The times each piece's fixes span, from its first fix to its last (on the
    /// attitude's clock): what the fixes see of the dive.
    fn fix_spans(&self) -> Vec<std::ops::RangeInclusive<f64>> {
        (self.held.iter())
            .map(|held| self.fixes.time_s[held[0]]..=self.fixes.time_s[held[held.len() - 1]])
            .collect()
    }

    /// How far the dead reckoning under the term parameters `terms` travelled,
    /// horizontally, over the times its fixes span, m.
    pub(super) fn distance_m(&self, terms: &[f64]) -> Result<f64, FixFitError> {
        let tracks = self.tracks(terms)?;
        let spans = self.fix_spans();
        Ok((tracks.iter().zip(&spans))
            .map(|(track, span)| {
                let start = track.time_s.partition_point(|t| t < span.start());
                let end = track.time_s.partition_point(|t| t <= span.end());
                path_length_m(&track.position_m[start..end.max(start)])
            })
            .sum())
    }

    /// The installation of the term parameters `terms`: the carried one, each
    /// parameter moved by its term.
    pub(super) fn installation(&self, terms: &[f64]) -> Installation {
        let carried = self.carried.to_parameters(&self.terms);
        let terms = &terms[..carried.len()];
        let moved: Vec<f64> = carried.iter().zip(terms).map(|(c, t)| c + t).collect();
        self.carried.with_parameters(&self.terms, &moved)
    }

    /// Each piece's track under the term parameters `terms`.
    pub(super) fn tracks(&self, terms: &[f64]) -> Result<Vec<Track>, FixFitError> {
        let installation = self.installation(terms);
        let time_offset_s = installation.time_offset_s;
        let along = (self.read)
            .along((self.dvl.0, &self.pieces), time_offset_s, self.attitude)
            .ok_or(FixFitError::NoAttitude { time_offset_s })?;
        let tracks = (self.pieces.iter().zip(along.iter()))
            .map(|(piece, body_to_ned)| {
                let dvl = (&self.dvl.0[piece.clone()], &self.dvl.1[piece.clone()]);
                dead_reckon_along(&installation, dvl, body_to_ned)
            })
            .collect();
        Ok(tracks)
    }

    /// The residuals before the start positions (the track less the fix), in blocks of
    /// one piece and one axis, fixes in order; a fix's place in its block is its place
    /// in the piece.
    fn residuals(&self, terms: &[f64]) -> Result<Vec<f64>, FixFitError> {
        let tracks = self.tracks(terms)?;
        let time_offset_s = self.installation(terms).time_offset_s;
        let latency_s = self.latency.map_or(0.0, |k| terms[k]);
        let mut residuals = Vec::with_capacity(self.fix_of.len() * self.axes);
        for (track, held) in tracks.iter().zip(&self.held) {
            for axis in 0..self.axes {
                for &j in held {
                    let position = (track.at(self.fixes.time_s[j] - latency_s))
                        .ok_or(FixFitError::NoAttitude { time_offset_s })?;
                    let fix = match axis {
                        2 => self.fixes.depth_m.as_ref().expect("a depth")[j],
                        _ => self.fixes.north_east_m[j][axis],
                    };
                    residuals.push(position[axis] - fix);
                }
            }
        }
        Ok(residuals)
    }

    /// The residuals of `terms` with each block's start added: `starts` per block.
    fn with_starts(&self, residuals: &[f64], starts: &[f64]) -> Vec<f64> {
        let mut out = residuals.to_vec();
        let mut row = 0;
        let mut block = 0;
        for held in &self.held {
            for _ in 0..self.axes {
                for value in &mut out[row..row + held.len()] {
                    *value += starts[block];
                }
                row += held.len();
                block += 1;
            }
        }
        out
    }

    /// The whitening of the residuals with the fixes weighed by `weights` (one per
    /// fitted fix; a fix of weight w has σ_f² / w, one of weight zero is left out)
    /// under the noise of `shape`, its variances in the horizontal fix noise's (so that
    /// the variance factor is 1 where the noise is as given, and no noise given, however
    /// far from the fixes', overflows).
    fn whitening(&self, weights: &[f64], shape: NoiseShape) -> Whitening {
        let step_s = crate::data::paired::sample_interval(self.dvl.0);
        let walk_m2_s = (self.noise.dvl_m_s / self.noise.fix_m).powi(2) * step_s;
        let mut blocks = Vec::new();
        let (mut row, mut offset) = (0, 0);
        for (piece, held) in self.pieces.iter().zip(&self.held) {
            let start_s = self.dvl.0[piece.start];
            let time_s: Vec<f64> = held.iter().map(|&j| self.fixes.time_s[j]).collect();
            let fixes = offset..offset + held.len();
            let (weights, ones) = (&weights[fixes.clone()], vec![1.0; held.len()]);
            for axis in 0..self.axes {
                // The fixes' own noise is horizontal; their depth's is one.
                let (fix, relative) = match axis {
                    2 => (self.noise.depth_m / self.noise.fix_m, &ones[..]),
                    _ => (1.0, &self.relative[fixes.clone()]),
                };
                let model = shape.model(fix * fix, walk_m2_s);
                blocks.push((
                    row..row + held.len(),
                    Whitener::new(&model, start_s, &time_s, (weights, relative)),
                ));
                row += held.len();
            }
            offset += held.len();
        }
        Whitening::new(blocks, self.noise.fix_m)
    }

    /// The Jacobian of the residuals in the free term parameters (central differences),
    /// a column per free term.
    pub(super) fn jacobian(
        &self,
        terms: &[f64],
        free: &[bool],
    ) -> Result<Vec<Vec<f64>>, FixFitError> {
        (0..free.len())
            .filter(|&k| free[k])
            .map(|k| {
                let step = self.difference_step(k);
                let moved = |by: f64| {
                    let mut terms = terms.to_vec();
                    terms[k] += by;
                    self.residuals(&terms)
                };
                let (up, down) = (moved(step)?, moved(-step)?);
                Ok((up.iter().zip(&down))
                    .map(|(u, d)| (u - d) / (2.0 * step))
                    .collect())
            })
            .collect()
    }

    /// The fit's solve loop ([`levenberg_marquardt`]) on the whitened residuals from
    /// `solution`, with the `free` terms and each fix weighed by `weights` (one per
    /// fitted fix), under `shape`.
    fn solve(
        &self,
        mut solution: Solution,
        free: &[bool],
        weights: &[f64],
        shape: NoiseShape,
    ) -> Result<Solution, FixFitError> {
        let whitening = self.whitening(weights, shape);
        let free_terms: Vec<usize> = (0..free.len()).filter(|&k| free[k]).collect();
        solution.information_log_det = 0.0;
        if !free_terms.is_empty() {
            let residuals = |terms: &[f64]| self.residuals(terms);
            let jacobian = |terms: &[f64], free: &[bool]| self.jacobian(terms, free);
            let limits = (0..self.names.len()).map(|k| self.limit(k)).collect();
            let whitened = Whitened::new(
                (&residuals, &jacobian),
                limits,
                &whitening,
                free,
                solution.terms,
            );
            let (solved, termination) = levenberg_marquardt(whitened, TOLERANCE, PATIENCE);
            if let Some(error) = solved.failed.into_inner() {
                return Err(error);
            }
            termination.map_err(|termination| FixFitError::NotConverged { termination })?;
            solution.terms = solved.terms;
            let columns: Vec<DVector<f64>> = (self.jacobian(&solution.terms, free)?.iter())
                .map(|column| DVector::from_vec(whitening.whiten(column)))
                .collect();
            let normal = DMatrix::from_fn(columns.len(), columns.len(), |a, b| {
                columns[a].dot(&columns[b])
            });
            solution.information_log_det = log_det_symmetric(&normal);
        }
        let residuals = self.residuals(&solution.terms)?;
        solution.starts = whitening.starts(&residuals);
        solution.whitened = whitening.whiten(&residuals);
        solution.shape = shape;
        let kept_rows = weights.iter().filter(|&&w| w > 0.0).count() * self.axes;
        solution.freedom = kept_rows.saturating_sub(free_terms.len() + whitening.starts_fitted());
        Ok(solution)
    }

    /// Where the time offset is among the terms', if asked for.
    fn time_offset(&self) -> Option<usize> {
        let latency = self.latency;
        (0..self.kinds.len()).find(|&k| self.kinds[k] == TermKind::TimeOffset && Some(k) != latency)
    }

    /// The largest magnitude parameter `k` may take: the time offset within the margin
    /// its fixes were chosen for, the others within any installation's
    /// ([`MAX_SCALE`], [`MAX_LEVER_ARM_M`], a quarter turn).
    pub(super) fn limit(&self, k: usize) -> f64 {
        match self.kinds[k] {
            // Inside the margin by more than the Jacobian's step.
            TermKind::TimeOffset => TIME_OFFSET_MARGIN_S - 0.01,
            TermKind::Scale => MAX_SCALE,
            TermKind::LeverArm => MAX_LEVER_ARM_M,
            TermKind::Misalignment | TermKind::Bias => std::f64::consts::FRAC_PI_2,
        }
    }

    /// The step of parameter `k`'s central difference.
    fn difference_step(&self, k: usize) -> f64 {
        match self.kinds[k] {
            TermKind::TimeOffset | TermKind::LeverArm => 1e-3,
            _ => 1e-6,
        }
    }

    /// Least squares of the `free` terms (the time offset from the best of a scan) and
    /// the noise's shape read from its residuals, the fixes grossly off left out
    /// ([`Self::not_gross`]); Huber's and Tukey's weights under it;
    /// then least squares on the fixes kept, the noise's shape read again.
    pub(super) fn robust_fit(&self, free: &[bool]) -> Result<Solution, FixFitError> {
        let blank = Solution {
            terms: vec![0.0; self.names.len()],
            starts: Vec::new(),
            kept: vec![true; self.fix_of.len()],
            shape: NoiseShape::GIVEN,
            whitened: Vec::new(),
            freedom: 0,
            information_log_det: 0.0,
        };
        // Fixes grossly off pull least squares across the scan: left out before it.
        let not_gross = self.not_gross(free)?;
        let screened = Solution {
            kept: not_gross.clone(),
            ..blank
        };
        let scanned = self.scan_time_offset(screened, free)?;
        // A latency run to its edge leaves most fixes outliers: refused as what it is.
        self.latency_within_the_search(&scanned)?;
        let mut solution = self.read_noise(&scanned, free, false)?;
        let shape = solution.shape;
        let tukey = Loss::TUKEY_MODELLED;
        for loss in [Loss::Huber, Loss::Huber, tukey, tukey, tukey] {
            let u = self.standardised(&solution, shape)?;
            let weights: Vec<f64> = (u.iter().zip(&not_gross))
                .map(|(&u, &fit)| if fit { loss.weight(u) } else { 0.0 })
                .collect();
            solution = self.solve(solution, free, &weights, shape)?;
            solution.kept = weights.iter().map(|&w| w > 0.0).collect();
            let outliers = solution.kept.iter().filter(|&&k| !k).count();
            if 4 * outliers > self.fix_of.len() {
                // A clock run to the scan's edge leaves most fixes outliers: said as such.
                self.within_the_scan(&solution)?;
                return Err(FixFitError::Outliers {
                    outliers,
                    within: self.fix_of.len(),
                });
            }
            self.enough(&solution.kept, free)?;
        }
        let mut last = self.read_noise(&solution, free, true)?;
        last.kept = solution.kept;
        self.within_the_scan(&last)?;
        Ok(last)
    }

    /// Which fixes to fit: all but those grossly off ([`gross_jumps`]), read from their
    /// distances from the dead reckoning under the installation carried (each in its
    /// own noise where the fixes carry theirs), beyond
    /// [`GROSS`] times the fixes' given noise. Such fixes stay out of the robust loop:
    /// one fix hundreds of metres off made the scan's least squares run to its edge,
    /// or the noise read a walk under which most good fixes were outliers.
    fn not_gross(&self, free: &[bool]) -> Result<Vec<bool>, FixFitError> {
        let residuals = self.residuals(&vec![0.0; self.names.len()])?;
        let blocks: Vec<usize> = self.held.iter().map(Vec::len).collect();
        let floor = GROSS * self.noise.fix_m;
        // Each fix's jumps in its own noise, so that a fix whose covariance says metres
        // is not gross beside centimetres.
        let noise: Vec<f64> = self.relative.iter().map(|r| r.sqrt()).collect();
        let kept = gross_jumps(&residuals, (&blocks, self.axes, &noise), (GROSS, floor));
        Ok(match self.enough(&kept, free) {
            Ok(()) => kept,
            Err(_) => vec![true; self.fix_of.len()],
        })
    }

    /// The noise's shape under which the fixes `solution` kept are likeliest, each
    /// shape's terms fitted again from `solution`'s (by their restricted likelihood:
    /// the variance factor profiled out, the starts and terms restricted), less
    /// Schwarz's penalty for the noise's parameters it reads (½ ln n each), so that the
    /// noise as given stands unless the residuals show otherwise: of the walks
    /// ([`NoiseShape::walks`]), then of the wandering errors beside the best
    /// ([`NoiseShape::wanders`]) where `wandering` (the robust loop's first reading, on
    /// residuals an outlier may still pull, reads the walk alone); with its fit.
    fn read_noise(
        &self,
        solution: &Solution,
        free: &[bool],
        wandering: bool,
    ) -> Result<Solution, FixFitError> {
        let weights = solution.weights();
        let rows = weights.iter().filter(|&&w| w > 0.0).count() * self.axes;
        let likelihood = |solved: &Solution| -> Result<f64, FixFitError> {
            let penalty = 0.5 * solved.shape.parameters() as f64 * (rows as f64).ln();
            Ok(solved.likelihood(&self.whitening(&weights, solved.shape)) - penalty)
        };
        let consider = |shapes: Vec<NoiseShape>, best: &mut Option<(f64, Solution)>| {
            for shape in shapes {
                let solved = self.solve(solution.clone(), free, &weights, shape)?;
                let score = likelihood(&solved)?;
                if best.as_ref().is_none_or(|(b, _)| score > *b) {
                    *best = Some((score, solved));
                }
            }
            Ok::<(), FixFitError>(())
        };
        let mut best = None;
        consider(NoiseShape::walks(), &mut best)?;
        let walk = best.as_ref().expect("walks to choose among").1.shape;
        if wandering {
            consider(walk.wanders(), &mut best)?;
        }
        Ok(best.expect("shapes to choose among").1)
    }

    /// Each fitted fix's innovation in its own standard deviations under `shape`, the
    /// fixes `solution` kept observed: the root mean square over its axes.
    fn standardised(
        &self,
        solution: &Solution,
        shape: NoiseShape,
    ) -> Result<Vec<f64>, FixFitError> {
        let whitening = self.whitening(&solution.weights(), shape);
        let residuals = self.with_starts(&self.residuals(&solution.terms)?, &solution.starts);
        let u = whitening.standardised(&residuals);
        let mut squares = vec![0.0; self.fix_of.len()];
        let (mut row, mut offset) = (0, 0);
        for held in &self.held {
            for _ in 0..self.axes {
                for a in 0..held.len() {
                    squares[offset + a] += u[row + a].powi(2);
                }
                row += held.len();
            }
            offset += held.len();
        }
        Ok(squares
            .iter()
            .map(|s| (s / self.axes as f64).sqrt())
            .collect())
    }

    /// The fit from the best time offset of the scan every fit starts from
    /// ([`scan_offsets`], each trial a least-squares fit of the other terms to the
    /// fixes `start` keeps), then of every free term; without a free time offset,
    /// least squares from zero. A best at the scan's end is refused.
    fn scan_time_offset(&self, start: Solution, free: &[bool]) -> Result<Solution, FixFitError> {
        let ones = start.weights();
        let given = NoiseShape::GIVEN;
        let Some(offset) = self.time_offset().filter(|&k| free[k]) else {
            return self.solve(start, free, &ones, given);
        };
        let mut others = free.to_vec();
        others[offset] = false;
        let limit = self.limit(offset);
        let scanned = scan_offsets(0.0, |time_offset_s| {
            let mut trial = start.clone();
            trial.terms[offset] = time_offset_s.clamp(-limit, limit);
            let solved = self.solve(trial, &others, &ones, given).ok();
            Ok::<_, FixFitError>(solved.map(|solved| (solved.cost(), solved)))
        })?;
        let scanned = scanned.ok_or(FixFitError::NoAttitude { time_offset_s: 0.0 })?;
        if scanned.at_an_end {
            return Err(FixFitError::ClockAtScanEdge {
                time_offset_s: scanned.best.terms[offset],
            });
        }
        self.solve(scanned.best, free, &ones, given)
    }

    /// Refuses a fit whose time offset, or the fixes' latency, went to the edge of the
    /// scan.
    fn within_the_scan(&self, solution: &Solution) -> Result<(), FixFitError> {
        if let Some(k) = self.time_offset().filter(|&k| self.at_edge(solution, k)) {
            let time_offset_s = solution.terms[k];
            return Err(FixFitError::ClockAtScanEdge { time_offset_s });
        }
        self.latency_within_the_search(solution)
    }

    /// Refuses a fit whose fixes' latency went to the edge of its search.
    fn latency_within_the_search(&self, solution: &Solution) -> Result<(), FixFitError> {
        match self.latency.filter(|&k| self.at_edge(solution, k)) {
            Some(k) => Err(FixFitError::LatencyAtScanEdge {
                latency_s: solution.terms[k],
            }),
            None => Ok(()),
        }
    }

    /// Whether `solution`'s parameter `k` lies within a scan step of its limit.
    fn at_edge(&self, solution: &Solution, k: usize) -> bool {
        solution.terms[k].abs() >= self.limit(k) - TIME_OFFSET_SCAN_STEP_S
    }

    /// `solution`'s fixes under no terms at all, only each piece's start fitted, under
    /// its noise: the fit's own fixes, to set its residual beside.
    pub(super) fn bare(&self, solution: &Solution) -> Result<Solution, FixFitError> {
        let blank = Solution {
            terms: vec![0.0; self.names.len()],
            ..solution.clone()
        };
        let none = vec![false; self.names.len()];
        self.solve(blank, &none, &solution.weights(), solution.shape)
    }

    /// Refuses `solution` where the fixes it kept lie further from the dead reckoning
    /// with its terms than with none (the start positions alone), under its noise, by
    /// more than one in the whitened sum of squares (what one parameter is expected to
    /// explain): where no term was already best (a dive corrected by its own
    /// calibration), the solve loop's last step may leave it a hair above.
    pub(super) fn better_than_none(&self, solution: &Solution) -> Result<(), FixFitError> {
        let whitening = self.whitening(&solution.weights(), solution.shape);
        let bare = whitening.whiten(&self.residuals(&vec![0.0; self.names.len()])?);
        let without: f64 = bare.iter().map(|w| w * w).sum();
        let with = solution.cost();
        match with > without + 1.0 {
            true => Err(FixFitError::WorseThanNone { with, without }),
            false => Ok(()),
        }
    }

    /// The standard deviations, correlations and unseen terms of `solution` over the
    /// term parameters (infinite or NaN where not `free`), under the noise of `shape`
    /// scaled by `factor` (its variance factor; the noise as given and 1: the Fisher
    /// bound, [`Self::fisher_bound`]).
    pub(super) fn bound(
        &self,
        solution: &Solution,
        free: &[bool],
        shape: NoiseShape,
        factor: f64,
    ) -> (Vec<f64>, Vec<Vec<f64>>, Vec<Unseen>) {
        let free_terms: Vec<usize> = (0..free.len()).filter(|&k| free[k]).collect();
        let whitening = self.whitening(&solution.weights(), shape);
        let columns: Vec<DVector<f64>> = (self.jacobian(&solution.terms, free))
            .expect("the solution's residuals were read")
            .iter()
            .map(|column| DVector::from_vec(whitening.whiten(column)))
            .collect();
        let normal = DMatrix::from_fn(columns.len(), columns.len(), |a, b| {
            columns[a].dot(&columns[b])
        });
        let names: Vec<&'static str> = free_terms.iter().map(|&k| self.names[k]).collect();
        let tolerance = |c: usize| FIX_TOLERANCES.of(self.kinds[free_terms[c]]);
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

    /// The terms, their standard deviations and correlations averaged over the walks
    /// ([`NoiseShape::walks`], beside `solution`'s wandering error), each walk's fit
    /// weighed by its restricted likelihood: the mean of the fits' terms, and the mean
    /// of their covariances plus the spread of their terms about that mean. A walk read
    /// from the residuals of one dive is uncertain (at ρ = 0.8 over 600 s, between a quarter
    /// and twice the truth's), and the terms' intervals carry that. The terms `free` are
    /// fitted; the covariance is that of `bounded`, those and any held at its value whose
    /// uncertainty the others carry (marginalised over it).
    pub(super) fn averaged(
        &self,
        solution: &Solution,
        (free, bounded): (&[bool], &[bool]),
    ) -> Result<Averaged, FixFitError> {
        let weights = solution.weights();
        let mut fits = Vec::new();
        for walk in NoiseShape::walks() {
            let shape = NoiseShape {
                walk_scale: walk.walk_scale,
                ..solution.shape
            };
            let solved = self.solve(solution.clone(), free, &weights, shape)?;
            let likelihood = solved.likelihood(&self.whitening(&weights, shape));
            let (std, correlation, _) =
                self.bound(&solved, bounded, shape, solved.variance_factor());
            fits.push((likelihood, solved.terms, std, correlation));
        }
        let best = fits.iter().map(|f| f.0).fold(f64::NEG_INFINITY, f64::max);
        let total: f64 = fits.iter().map(|f| (f.0 - best).exp()).sum();
        let n = self.names.len();
        let mut mean = vec![0.0; n];
        for (likelihood, terms, _, _) in &fits {
            let p = (likelihood - best).exp() / total;
            for k in 0..n {
                mean[k] += p * terms[k];
            }
        }
        let mut covariance = vec![vec![0.0; n]; n];
        for (likelihood, terms, std, correlation) in &fits {
            let p = (likelihood - best).exp() / total;
            for j in (0..n).filter(|&j| bounded[j]) {
                for k in (0..n).filter(|&k| bounded[k]) {
                    let own = correlation[j][k] * std[j] * std[k];
                    let spread = (terms[j] - mean[j]) * (terms[k] - mean[k]);
                    covariance[j][k] += p * (own + spread);
                }
            }
        }
        let std: Vec<f64> = (0..n)
            .map(|k| match bounded[k] {
                true => covariance[k][k].sqrt(),
                false => f64::INFINITY,
            })
            .collect();
        let correlation = (0..n)
            .map(|j| {
                (0..n)
                    .map(|k| match (bounded[j], bounded[k]) {
                        (true, true) => covariance[j][k] / (std[j] * std[k]),
                        _ if j == k => 1.0,
                        _ => f64::NAN,
                    })
                    .collect()
            })
            .collect();
        Ok((mean, std, correlation))
    }

    /// The standard deviations of `solution`'s terms under the noise as given: the
    /// Fisher bound.
    pub(super) fn fisher_bound(&self, solution: &Solution, free: &[bool]) -> Vec<f64> {
        self.bound(solution, free, NoiseShape::GIVEN, 1.0).0
    }

    /// Each fitted fix's residual under `solution` (the dead reckoning, its piece placed
    /// at the start fitted, less the fix), north, east and depth (NaN where not
    /// fitted), m, in the order of [`Self::fix_of`].
    pub(super) fn fix_residuals(&self, solution: &Solution) -> Result<Vec<Vec3>, FixFitError> {
        let residuals = self.with_starts(&self.residuals(&solution.terms)?, &solution.starts);
        let mut out = Vec::with_capacity(self.fix_of.len());
        let mut row = 0;
        for held in &self.held {
            for a in 0..held.len() {
                let mut residual = [f64::NAN; 3];
                for (axis, value) in residual.iter_mut().enumerate().take(self.axes) {
                    *value = residuals[row + axis * held.len() + a];
                }
                out.push(residual);
            }
            row += self.axes * held.len();
        }
        Ok(out)
    }

    /// The RMS of the residuals of the fixes kept, per axis, m (NaN on an axis not
    /// fitted).
    pub(super) fn residual_rms(&self, solution: &Solution) -> Result<Vec3, FixFitError> {
        let residuals = self.fix_residuals(solution)?;
        let (mut sums, mut counts) = ([0.0; 3], [0usize; 3]);
        for (residual, _) in residuals
            .iter()
            .zip(&solution.kept)
            .filter(|(_, kept)| **kept)
        {
            for axis in 0..self.axes {
                sums[axis] += residual[axis].powi(2);
                counts[axis] += 1;
            }
        }
        Ok([0, 1, 2].map(|k| match counts[k] {
            0 => f64::NAN,
            count => (sums[k] / count as f64).sqrt(),
        }))
    }
}

/// The pieces of the DVL record stamped `time_s` that hold a fix, each cut to the
/// samples whose t + τ reads `attitude` whatever τ within [`TIME_OFFSET_MARGIN_S`] of
/// `centre_s` (so that every trial time offset reads it over the same samples), and
/// the fixes each holds: those at least `margin_s` inside it about `centre_s` (the
/// time offset's margin, and the latency's beside it where that is fitted).
fn pieces_with_fixes(
    time_s: &[f64],
    pieces: &[Range<usize>],
    attitude: &Attitude,
    fixes: &Fixes,
    (centre_s, margin_s): (f64, f64),
) -> (Vec<Range<usize>>, Vec<Vec<usize>>) {
    let inside = interior(attitude, time_s, centre_s);
    let (mut used, mut held) = (Vec::new(), Vec::new());
    for piece in pieces {
        let piece = piece.start.max(inside.start)..piece.end.min(inside.end);
        if piece.len() < 2 {
            continue;
        }
        let (first, last) = (
            time_s[piece.start] + centre_s,
            time_s[piece.end - 1] + centre_s,
        );
        let from = fixes.time_s.partition_point(|&t| t < first + margin_s);
        let to = fixes.time_s.partition_point(|&t| t <= last - margin_s);
        if from < to {
            used.push(piece);
            held.push((from..to).collect());
        }
    }
    (used, held)
}
