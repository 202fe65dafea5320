//! Nonlinear least squares of the selected terms (Levenberg–Marquardt), τ included:
//! the terms that make the model's prediction from the reference closest to the DVL
//! over a calibration window.
//! In: a DVL record, its reference, a [`TermSet`]. Out: a [`Fit`] (the
//! [`Installation`], the Jacobian at the solution for the bound, the residuals).
//!
//! The residual of sample i is `v_dvl(t_i) − predict(reference at t_i + τ)`, three
//! components, over the samples at least [`TIME_OFFSET_MARGIN_S`] inside the
//! reference at both ends: a fixed mask, so costs at different τ compare. Every term
//! starts at zero; τ, whose cost has many local minima a sample period apart, starts
//! from the best of a scan over ±[`TIME_OFFSET_MARGIN_S`] in steps of
//! [`TIME_OFFSET_SCAN_STEP_S`], with the other terms solved at each step. The Jacobian
//! is analytic; its τ column is the reference's slope (a central difference of the
//! linear interpolation, [`SLOPE_STEP_S`] each side). From the least-squares solution,
//! the fit goes on under a robust loss ([`super::robust`]: Huber's, then Tukey's), so
//! that outliers pull nothing; its residuals are then the M-estimator's
//! pseudo-residuals and its `curvature` the bread's weights.

use crate::Vec3;
use crate::installation::estimate::residual_noise::ResidualNoise;
use crate::installation::estimate::robust::{Loss, Robust, RobustFit, scales};
use crate::installation::frames::{Reference, ReferenceAt};
use crate::installation::terms::{Installation, TermSet};
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::storage::Owned;
use nalgebra::{DMatrix, DVector, Dyn};

/// The largest time offset a fit considers, s; also the margin of the fixed mask: the
/// samples stamped within it of either end of the reference are not fitted (nor, as
/// the recording is read, those within it of a gap in the reference).
pub const TIME_OFFSET_MARGIN_S: f64 = crate::data::paired::GAP_MARGIN_S;

/// The step of the scan over τ that gives LM its start, s: a quarter of A-KIT's 1 s
/// sample period, so the scan's best lies in the basin of the best minimum.
pub const TIME_OFFSET_SCAN_STEP_S: f64 = 0.25;

/// Half the step of the central difference that gives the reference's slope, s.
pub const SLOPE_STEP_S: f64 = 1e-4;

/// The most samples the scan over τ fits at each of its steps: a longer recording is
/// scanned on every few of its samples, evenly spread (36,000 is ten hours at 1 Hz, six
/// minutes at 100 Hz).
const SCAN_SAMPLES: usize = 36_000;

/// LM's patience: it gives up after this many times (parameters + 1) evaluations. A
/// pair of terms a window hardly tells apart (a scale and a bias at constant speed)
/// makes a long, flat valley, which LM's default of 100 does not always cross; so does a
/// clock and a fix latency that the fixes' turns hardly tell apart.
pub(super) const PATIENCE: usize = 2000;

/// The relative tolerances that stop LM (on the cost, the step and the gradient).
const TOLERANCE: f64 = 1e-12;

/// The relative tolerances that stop LM in a trial of the scan over τ, which only
/// ranks the trials' costs for the fit's start: on the coverage test's 4,000 fits
/// (white, correlated and spiked noise) its tables are those of [`TOLERANCE`] to the
/// last digit, in three fifths of the time.
const SCAN_TOLERANCE: f64 = 1e-6;

/// A calibration: the terms that fit a window best, with what the bound needs.
#[derive(Debug, Clone)]
pub struct Fit {
    pub terms: TermSet,
    pub installation: Installation,
    /// The estimated parameters, in the order of [`TermSet::parameter_names`].
    pub parameters: Vec<f64>,
    /// ∂(v_dvl − predict)/∂θ at the solution, `[3 · sample_count, parameters]`, rows
    /// sample by sample, x, y, z within a sample.
    pub jacobian: DMatrix<f64>,
    /// The residuals v_dvl − predict at the solution, x, y, z of each sample in order,
    /// m/s; under a robust loss, its pseudo-residuals σ · ψ(r / σ) (an outlier's is
    /// zero), whose spread is the meat of the sandwich.
    pub residuals: DVector<f64>,
    /// Under a robust loss, the loss and what it made of the residuals: the weights D
    /// of the information JᵀDJ ([`Fit::information`]) and the outliers; `None` for
    /// least squares (every weight 1, no outlier).
    pub robust: Option<RobustFit>,
    /// The RMS of the residual v_dvl − predict per DVL axis, m/s.
    pub residual_rms_m_s: Vec3,
    /// How many DVL samples were fitted (those inside the fixed mask).
    pub sample_count: usize,
    /// The time offset the fixed mask lies about, s: its samples are those whose
    /// t + this lies inside the reference's interior (0 for a fit from no clock, the
    /// search's best or the carried τ otherwise); `None` for a joint fit, each of whose
    /// recordings has its own.
    pub mask_centre_s: Option<f64>,
    /// Whether each fitted sample follows the one before it within a piece
    /// ([`Reference::follows`]): the noise's correlation in time is read within pieces.
    pub follows: Vec<bool>,
    /// How LM stopped ("none" when nothing was estimated).
    pub termination: String,
}

impl Fit {
    /// The information JᵀDJ of the fitted terms: the bread of the sandwich (JᵀJ for
    /// least squares).
    pub fn information(&self) -> DMatrix<f64> {
        self.jacobian.transpose() * self.curved(&self.jacobian)
    }

    /// D · `rows` (rows as the Jacobian's), D the robust loss's curvature (`rows`
    /// itself for least squares).
    pub fn curved(&self, rows: &DMatrix<f64>) -> DMatrix<f64> {
        match &self.robust {
            None => rows.clone(),
            Some(robust) => DMatrix::from_fn(rows.nrows(), rows.ncols(), |i, j| {
                robust.curvature[i] * rows[(i, j)]
            }),
        }
    }

    /// The noise its residuals show, read within pieces.
    pub fn residual_noise(&self) -> ResidualNoise {
        ResidualNoise::of(&self.residuals, self.parameters.len(), &self.follows)
    }

    /// The samples the robust loss rejected as outliers (none for least squares).
    pub fn outliers(&self) -> usize {
        self.robust.as_ref().map_or(0, |r| r.outliers)
    }
}

#[derive(Debug, thiserror::Error)]
pub enum FitError {
    #[error("{time} time stamps but {dvl} DVL samples")]
    LengthMismatch { time: usize, dvl: usize },
    #[error(
        "{} more than {margin_s} s inside the reference, too few for {}",
        match usable { 1 => "1 DVL sample lies".to_string(), n => format!("{n} DVL samples lie") },
        crate::count(*parameters, "parameter")
    )]
    TooFewSamples {
        usable: usize,
        parameters: usize,
        margin_s: f64,
    },
    #[error(
        "{outliers} of the {samples} samples fitted have a residual beyond {} scales of the rest: more than a quarter are outliers, so the recording does not show its installation (a DVL reading another vehicle's motion, or the wrong reference)",
        super::robust::TUKEY_C
    )]
    Outliers { outliers: usize, samples: usize },
    #[error(
        "no time offset within ±{search_s} s puts half the DVL's samples inside the reference: the recordings do not overlap that near"
    )]
    NoClockInSearch { search_s: f64 },
    #[error(
        "the search's best time offset, {found_s:.2} s, lies at the edge of the ±{} s searched: the clock may lie beyond it, and a wider --search-s may find it",
        crate::Shown(*search_s)
    )]
    ClockAtSearchEdge { found_s: f64, search_s: f64 },
    #[error("the fit did not converge: {termination}")]
    NotConverged { termination: String },
    #[error(
        "the fitted time offset {time_offset_s:.3} s lies more than {margin_s} s from the {centre_s:.3} s the fit started from, \
         outside what the window can show"
    )]
    TimeOffsetBeyondMargin {
        time_offset_s: f64,
        centre_s: f64,
        margin_s: f64,
    },
    /// A term fitted beyond what any DVL installation is off by: the recording does not
    /// show the installation (a DVL that reads no motion fits a scale of −100 %).
    #[error(
        "the fitted {term} is {value}, beyond the {limit} any installation is off by: the recording does not show it{}",
        if term.starts_with("scale") { " (a DVL that reads no motion, all zeros, fits a scale of -100 %)" } else { "" }
    )]
    Unphysical {
        term: String,
        /// With its unit.
        value: String,
        limit: String,
    },
}

impl FitError {
    /// What to try instead, for a fit that failed on a window too short or terms it
    /// cannot tell apart; none where the recording itself is at fault.
    pub fn advice(&self) -> &'static str {
        match self {
            FitError::Unphysical { .. }
            | FitError::ClockAtSearchEdge { .. }
            | FitError::NoClockInSearch { .. } => "",
            _ => {
                "; a window too short for its terms, terms it cannot tell apart (a scale and a bias at constant speed, say), or a time offset beyond the ±3 s the fit scans fail this way: give a longer --window-s or fewer --terms, or where the clocks may be further apart let --search-s look for them (--search-s 60 looks ±60 s)"
            }
        }
    }
}

/// The largest scale error a fit may find, as a fraction: beyond it, a DVL does not
/// measure the motion it rides.
pub const MAX_SCALE: f64 = 0.5;

/// The largest lever arm a fit may find, per axis, m.
pub const MAX_LEVER_ARM_M: f64 = 100.0;

/// The first term of `installation` beyond what an installation is off by, or not
/// finite. A fit may find such a value for a term the window cannot show (the bound
/// flags it); one applied to a recording would correct it into nonsense (a scale of
/// −100 % divides by zero).
pub fn beyond_any_installation(installation: &Installation) -> Option<FitError> {
    let axes = ["x", "y", "z"];
    for k in 0..3 {
        let scale = installation.scale[k];
        if !(scale.abs() < MAX_SCALE) {
            return Some(FitError::Unphysical {
                term: format!("scale {}", axes[k]),
                value: format!("{} %", crate::Shown(100.0 * scale)),
                limit: format!("±{} %", 100.0 * MAX_SCALE),
            });
        }
        let lever = installation.lever_arm_m[k];
        if !(lever.abs() <= MAX_LEVER_ARM_M) {
            return Some(FitError::Unphysical {
                term: format!("lever arm {}", axes[k]),
                value: format!("{} m", crate::Shown(lever)),
                limit: format!("±{MAX_LEVER_ARM_M} m"),
            });
        }
        let other = [installation.misalignment_rad[k], installation.bias_m_s[k]];
        if other.iter().any(|v| !v.is_finite()) {
            return Some(FitError::Unphysical {
                term: format!("misalignment or bias {}", axes[k]),
                value: "not a number".into(),
                limit: "finite value".into(),
            });
        }
    }
    None
}

/// The reference at `time_s`, held at its ends when a τ reaches beyond them (LM's
/// fit then fails with [`FitError::TimeOffsetBeyondMargin`]).
pub fn reference_held(reference: &Reference, time_s: f64) -> ReferenceAt {
    let first = reference.time_s[0];
    let last = reference.time_s[reference.time_s.len() - 1];
    reference
        .across_gaps(time_s.clamp(first, last))
        .expect("a time inside the reference")
}

/// The time derivative of the reference at `time_s`: a central difference of the
/// linear interpolation, [`SLOPE_STEP_S`] each side, held at its ends.
pub fn slope_held(reference: &Reference, time_s: f64) -> ReferenceAt {
    let first = reference.time_s[0];
    let last = reference.time_s[reference.time_s.len() - 1];
    let (before, after) = (
        (time_s - SLOPE_STEP_S).clamp(first, last),
        (time_s + SLOPE_STEP_S).clamp(first, last),
    );
    let (a, b) = (
        reference_held(reference, before),
        reference_held(reference, after),
    );
    let span = after - before;
    let rate = |x: Vec3, y: Vec3| [0, 1, 2].map(|k| (y[k] - x[k]) / span);
    ReferenceAt {
        velocity_body_m_s: rate(a.velocity_body_m_s, b.velocity_body_m_s),
        rate_rad_s: rate(a.rate_rad_s, b.rate_rad_s),
    }
}

/// The least-squares problem LM solves: `terms` are free, the rest of `base` is held.
struct Problem<'a> {
    time_s: &'a [f64],
    dvl_m_s: &'a [Vec3],
    reference: &'a Reference,
    terms: TermSet,
    base: Installation,
    parameters: DVector<f64>,
    /// The robust loss minimised, where not least squares.
    robust: Option<Robust>,
}

impl Problem<'_> {
    fn installation(&self) -> Installation {
        self.base
            .with_parameters(&self.terms, self.parameters.as_slice())
    }

    fn reference_at(&self, time_s: f64) -> ReferenceAt {
        reference_held(self.reference, time_s)
    }

    fn slope_at(&self, time_s: f64) -> ReferenceAt {
        slope_held(self.reference, time_s)
    }

    /// The residuals LM minimises: v_dvl − predict, or under a robust loss their
    /// transform whose squares sum to 2 Σ ρ.
    fn residual_vector(&self) -> DVector<f64> {
        let raw = self.raw_residuals();
        match self.robust {
            None => raw,
            Some(robust) => DVector::from_fn(raw.len(), |i, _| {
                let axis = i % 3;
                robust
                    .loss
                    .residual(robust.scaled(raw[i], axis), robust.scale_m_s[axis])
            }),
        }
    }

    /// v_dvl − predict, x, y, z of each sample in order, m/s.
    fn raw_residuals(&self) -> DVector<f64> {
        let installation = self.installation();
        let mut residuals = DVector::zeros(3 * self.time_s.len());
        for (i, (&t, dvl)) in self.time_s.iter().zip(self.dvl_m_s).enumerate() {
            let predicted = installation.predict(self.reference_at(t + installation.time_offset_s));
            for k in 0..3 {
                residuals[3 * i + k] = dvl[k] - predicted[k];
            }
        }
        residuals
    }

    /// The Jacobian of [`Self::residual_vector`].
    fn jacobian_matrix(&self) -> DMatrix<f64> {
        let (raw, mut jacobian) = self.raw_linearised();
        if let Some(robust) = self.robust {
            for (i, mut row) in jacobian.row_iter_mut().enumerate() {
                row *= robust.loss.slope(robust.scaled(raw[i], i % 3));
            }
        }
        jacobian
    }

    /// v_dvl − predict (as [`Self::raw_residuals`]) and its Jacobian ∂(v_dvl −
    /// predict)/∂θ (rows as [`Fit::jacobian`]'s), from one reading of the reference
    /// per sample.
    fn raw_linearised(&self) -> (DVector<f64>, DMatrix<f64>) {
        let installation = self.installation();
        let mut residuals = DVector::zeros(3 * self.time_s.len());
        let mut jacobian = DMatrix::zeros(3 * self.time_s.len(), self.terms.parameter_count());
        for (i, (&t, dvl)) in self.time_s.iter().zip(self.dvl_m_s).enumerate() {
            let time_s = t + installation.time_offset_s;
            let at = self.reference_at(time_s);
            let columns = installation.predict_jacobian(&self.terms, at, self.slope_at(time_s));
            let predicted = installation.predict(at);
            for k in 0..3 {
                residuals[3 * i + k] = dvl[k] - predicted[k];
            }
            for (column, derivative) in columns.iter().enumerate() {
                for k in 0..3 {
                    jacobian[(3 * i + k, column)] = -derivative[k];
                }
            }
        }
        (residuals, jacobian)
    }

    fn cost(&self) -> f64 {
        self.residual_vector().norm_squared()
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, parameters: &DVector<f64>) {
        self.parameters.copy_from(parameters);
    }

    fn params(&self) -> DVector<f64> {
        self.parameters.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        Some(self.residual_vector())
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        Some(self.jacobian_matrix())
    }
}

/// Runs LM on `problem` from its current parameters, to [`TOLERANCE`].
fn minimize(problem: Problem<'_>) -> Result<(Problem<'_>, String), FitError> {
    minimize_to(problem, TOLERANCE)
}

/// Runs LM on `problem` from its current parameters, to the relative `tolerance`.
fn minimize_to(problem: Problem<'_>, tolerance: f64) -> Result<(Problem<'_>, String), FitError> {
    let (problem, termination) = levenberg_marquardt(problem, tolerance, PATIENCE);
    termination
        .map(|termination| (problem, termination))
        .map_err(|termination| FitError::NotConverged { termination })
}

/// The solve loop of every fit: Levenberg–Marquardt on `problem` from its parameters,
/// stopped at the relative `tolerance` (on the cost, the step and the gradient) or
/// after `patience` times (parameters + 1) evaluations; with how it stopped, an error
/// where it did not converge.
pub fn levenberg_marquardt<P: LeastSquaresProblem<f64, Dyn, Dyn>>(
    problem: P,
    tolerance: f64,
    patience: usize,
) -> (P, Result<String, String>) {
    let (problem, report) = LevenbergMarquardt::new()
        .with_ftol(tolerance)
        .with_xtol(tolerance)
        .with_gtol(tolerance)
        .with_patience(patience)
        .minimize(problem);
    let termination = format!("{:?}", report.termination);
    match report.termination.was_successful() {
        true => (problem, Ok(termination)),
        false => (problem, Err(termination)),
    }
}

/// Fits the terms of `terms` to the DVL record (`time_s`, `dvl_m_s`) against the
/// `reference`, every term starting at zero. With nothing to estimate, the fit is the
/// zero installation and its residuals.
pub fn fit(
    time_s: &[f64],
    dvl_m_s: &[Vec3],
    reference: &Reference,
    terms: TermSet,
) -> Result<Fit, FitError> {
    fit_about(time_s, dvl_m_s, reference, terms, Installation::default())
}

/// Fits the terms of `terms`, every other term held at its value in `base` (the terms
/// a calibration carries to a dive): the free terms start from `base`'s values, τ (when
/// free) from the best of the scan over `base`'s τ ± [`TIME_OFFSET_MARGIN_S`], and it
/// must end within that margin; the fixed mask is the samples whose t + τ lies inside
/// the reference for every τ of the scan.
pub fn fit_about(
    time_s: &[f64],
    dvl_m_s: &[Vec3],
    reference: &Reference,
    terms: TermSet,
    base: Installation,
) -> Result<Fit, FitError> {
    if time_s.len() != dvl_m_s.len() {
        return Err(FitError::LengthMismatch {
            time: time_s.len(),
            dvl: dvl_m_s.len(),
        });
    }
    let parameter_count = terms.parameter_count();
    let centre_s = base.time_offset_s;
    let mask = mask_about(time_s, reference, centre_s);
    if 3 * mask.len() <= parameter_count || mask.is_empty() {
        return Err(FitError::TooFewSamples {
            usable: mask.len(),
            parameters: parameter_count,
            margin_s: TIME_OFFSET_MARGIN_S,
        });
    }
    let problem = |terms: TermSet, base: Installation| Problem {
        time_s: &time_s[mask.clone()],
        dvl_m_s: &dvl_m_s[mask.clone()],
        reference,
        terms,
        base,
        parameters: DVector::from_vec(base.to_parameters(&terms)),
        robust: None,
    };

    let (solved, termination) = if parameter_count == 0 {
        (problem(terms, base), "none".to_string())
    } else if terms.time_offset {
        let start = scan_start(
            (&time_s[mask.clone()], &dvl_m_s[mask.clone()]),
            reference,
            terms,
            base,
        )?;
        robustly(minimize(problem(terms, start))?)?
    } else {
        robustly(minimize(problem(terms, base))?)?
    };

    let installation = solved.installation();
    if (installation.time_offset_s - centre_s).abs() > TIME_OFFSET_MARGIN_S {
        return Err(FitError::TimeOffsetBeyondMargin {
            time_offset_s: installation.time_offset_s,
            centre_s,
            margin_s: TIME_OFFSET_MARGIN_S,
        });
    }
    solution(solved, termination, (mask.len(), centre_s))
}

/// The fit of the solved `problem` over its `sample_count` samples: its raw residuals'
/// RMS, and under a robust loss its pseudo-residuals, curvature and outliers (more
/// than a quarter of them refused).
fn solution(
    solved: Problem<'_>,
    termination: String,
    (sample_count, centre_s): (usize, f64),
) -> Result<Fit, FitError> {
    let (terms, installation) = (solved.terms, solved.installation());
    let follows = solved.reference.follows(solved.time_s);
    let (raw, jacobian) = solved.raw_linearised();
    let residual_rms_m_s = residual_rms(&raw, sample_count);
    let robust = solved.robust.map(|loss| loss.fitted(&raw));
    let residuals = match solved.robust {
        None => raw,
        Some(loss) => loss.pseudo_residuals(&raw),
    };
    let outliers = robust.as_ref().map_or(0, |r| r.outliers);
    if 4 * outliers > sample_count {
        return Err(FitError::Outliers {
            outliers,
            samples: sample_count,
        });
    }
    Ok(Fit {
        terms,
        installation,
        parameters: installation.to_parameters(&terms),
        jacobian,
        residual_rms_m_s,
        residuals,
        robust,
        sample_count,
        mask_centre_s: Some(centre_s),
        follows,
        termination,
    })
}

/// From the least-squares solution `(solved, termination)`, LM under Huber's loss,
/// then under Tukey's from there, each with the scales of the residuals it starts
/// from; least squares where the residuals have no scale (a noise-free record).
fn robustly(
    (solved, termination): (Problem<'_>, String),
) -> Result<(Problem<'_>, String), FitError> {
    let mut current = (solved, termination);
    for loss in [Loss::Huber, Loss::TUKEY] {
        let Some(scale_m_s) = scales(&current.0.raw_residuals()) else {
            return Ok(current);
        };
        let mut next = current.0;
        next.robust = Some(Robust { loss, scale_m_s });
        current = minimize(next)?;
    }
    Ok(current)
}

/// Where Levenberg–Marquardt starts when τ is free: the best of the scan over `base`'s
/// τ ± [`TIME_OFFSET_MARGIN_S`]. On a long recording the scan reads every few samples
/// of the fitted ones `(time_s, dvl_m_s)` (at most SCAN_SAMPLES), so that its steps
/// cost no more than a short one's.
fn scan_start(
    (time_s, dvl_m_s): (&[f64], &[Vec3]),
    reference: &Reference,
    terms: TermSet,
    base: Installation,
) -> Result<Installation, FitError> {
    let stride = time_s.len().div_ceil(SCAN_SAMPLES);
    let scan_time_s: Vec<f64> = time_s.iter().copied().step_by(stride).collect();
    let scan_dvl_m_s: Vec<Vec3> = dvl_m_s.iter().copied().step_by(stride).collect();
    let scanned = |terms: TermSet, base: Installation| Problem {
        time_s: &scan_time_s,
        dvl_m_s: &scan_dvl_m_s,
        reference,
        terms,
        base,
        parameters: DVector::from_vec(base.to_parameters(&terms)),
        robust: None,
    };
    scan_time_offset(&scanned, terms, base)
}

/// The residuals v_dvl − predict of `installation` on every sample of the record (x,
/// y, z of each in order, m/s) and their Jacobian in `terms`, rows as
/// [`Fit::jacobian`]'s: one step of a fit the caller runs, on the samples it chose.
pub fn linearised(
    time_s: &[f64],
    dvl_m_s: &[Vec3],
    reference: &Reference,
    terms: TermSet,
    installation: Installation,
) -> (DVector<f64>, DMatrix<f64>) {
    let problem = Problem {
        time_s,
        dvl_m_s,
        reference,
        terms,
        base: installation,
        parameters: DVector::from_vec(installation.to_parameters(&terms)),
        robust: None,
    };
    problem.raw_linearised()
}

/// The samples a fit about a time offset of `centre_s` fits: those whose t + τ lies
/// inside the reference for every τ within [`TIME_OFFSET_MARGIN_S`] of it.
pub fn mask_about(time_s: &[f64], reference: &Reference, centre_s: f64) -> std::ops::Range<usize> {
    let shifted: Vec<f64> = time_s.iter().map(|t| t + centre_s).collect();
    reference.interior(&shifted, TIME_OFFSET_MARGIN_S)
}

/// The Jacobian of `terms` at `installation` over the samples a fit of this record
/// fits (the fixed mask about `centre_s`, [`Fit::mask_centre_s`]), rows as
/// [`Fit::jacobian`]'s: what the residuals of a fit would feel of terms it left out.
pub fn jacobian_at(
    (time_s, dvl_m_s): (&[f64], &[Vec3]),
    reference: &Reference,
    terms: TermSet,
    installation: Installation,
    centre_s: f64,
) -> DMatrix<f64> {
    let mask = mask_about(time_s, reference, centre_s);
    Problem {
        time_s: &time_s[mask.clone()],
        dvl_m_s: &dvl_m_s[mask],
        reference,
        terms,
        base: installation,
        parameters: DVector::from_vec(installation.to_parameters(&terms)),
        robust: None,
    }
    .jacobian_matrix()
}

/// The start of LM when τ is fitted: τ held at each step of the scan over `base`'s τ
/// ([`scan_offsets`]), the other terms of `terms` solved from `base`'s values, and the
/// installation of the lowest cost kept. `problem` makes the problem of free terms and
/// held ones.
fn scan_time_offset<'a>(
    problem: &impl Fn(TermSet, Installation) -> Problem<'a>,
    terms: TermSet,
    base: Installation,
) -> Result<Installation, FitError> {
    let others = TermSet {
        time_offset: false,
        ..terms
    };
    let scanned = scan_offsets(base.time_offset_s, |time_offset_s| {
        let held = Installation {
            time_offset_s,
            ..base
        };
        let candidate = if others.parameter_count() == 0 {
            problem(others, held)
        } else {
            minimize_to(problem(others, held), SCAN_TOLERANCE)?.0
        };
        Ok(Some((candidate.cost(), candidate.installation())))
    })?;
    Ok(scanned.expect("the scan has steps").best)
}

/// The best of a scan over a time offset: the trial of the lowest cost, and whether it
/// lies at an end of the scan (where the scan did not bracket the offset).
pub struct Scanned<T> {
    pub best: T,
    pub at_an_end: bool,
}

/// The scan every fit starts a free time offset from: `trial` at each offset over
/// `centre_s` ± [`TIME_OFFSET_MARGIN_S`] in steps of [`TIME_OFFSET_SCAN_STEP_S`], ends
/// included, gives the cost of the other terms solved there and what it solved (nothing
/// where it could not); the trial of the lowest cost is kept. Nothing where no trial
/// gave a cost; a trial's error ends the scan.
pub fn scan_offsets<T, E>(
    centre_s: f64,
    mut trial: impl FnMut(f64) -> Result<Option<(f64, T)>, E>,
) -> Result<Option<Scanned<T>>, E> {
    let steps = (TIME_OFFSET_MARGIN_S / TIME_OFFSET_SCAN_STEP_S).round() as i64;
    let mut best: Option<(f64, i64, T)> = None;
    for step in -steps..=steps {
        let Some((cost, solved)) = trial(centre_s + step as f64 * TIME_OFFSET_SCAN_STEP_S)? else {
            continue;
        };
        if best.as_ref().is_none_or(|(lowest, _, _)| cost < *lowest) {
            best = Some((cost, step, solved));
        }
    }
    Ok(best.map(|(_, step, best)| Scanned {
        best,
        at_an_end: step.abs() == steps,
    }))
}

/// The RMS per axis of `residuals` (x, y, z of each of `sample_count` samples).
pub fn residual_rms(residuals: &DVector<f64>, sample_count: usize) -> Vec3 {
    [0, 1, 2].map(|k| {
        let sum: f64 = (0..sample_count)
            .map(|i| residuals[3 * i + k].powi(2))
            .sum();
        (sum / sample_count as f64).sqrt()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::installation::terms::PerAxis;

    /// The weaving vehicle of the simulation's tests, 300 s at 1 Hz, and its DVL as the
    /// model predicts it from the sampled reference (no noise; t + τ held inside it).
    fn weaving(truth: &Installation) -> (Vec<f64>, Vec<Vec3>, Reference) {
        let segment = crate::installation::learned::simulate::tests::weaving("W", 300, 0.0);
        let (time_s, reference) = (segment.recording.time_s, segment.reference);
        let last = *time_s.last().unwrap();
        let dvl = time_s
            .iter()
            .map(|&t| {
                truth.predict(
                    reference
                        .at((t + truth.time_offset_s).clamp(0.0, last))
                        .unwrap(),
                )
            })
            .collect();
        (time_s, dvl, reference)
    }

    #[test]
    fn noiseless_terms_are_recovered_exactly() {
        let truth = Installation {
            scale: [0.01; 3],
            misalignment_rad: [0.0, 0.01, -0.02],
            lever_arm_m: [-1.9, 0.05, 0.4],
            time_offset_s: 0.6,
            bias_m_s: [0.01, -0.01, 0.005],
        };
        let terms = TermSet {
            scale: PerAxis::Scalar,
            misalignment: true,
            lever_arm: true,
            time_offset: true,
            bias: PerAxis::PerAxis,
        };
        let (time_s, dvl, reference) = weaving(&truth);
        let fit = fit(&time_s, &dvl, &reference, terms).unwrap();
        let expected = truth.to_parameters(&terms);
        for (name, (got, want)) in terms
            .parameter_names()
            .iter()
            .zip(fit.parameters.iter().zip(&expected))
        {
            assert!((got - want).abs() < 1e-6, "{name}: {got} against {want}");
        }
        assert!(fit.residual_rms_m_s.iter().all(|r| *r < 1e-8));
        assert_eq!(fit.sample_count, 294);
        assert_eq!(fit.jacobian.shape(), (3 * 294, 11));
    }

    #[test]
    fn nothing_to_estimate_gives_the_zero_installation_and_the_raw_residual() {
        let truth = Installation {
            bias_m_s: [0.03, 0.0, -0.04],
            ..Installation::default()
        };
        let (time_s, dvl, reference) = weaving(&truth);
        let fit = fit(&time_s, &dvl, &reference, TermSet::NONE).unwrap();
        assert_eq!(fit.installation, Installation::default());
        assert!((fit.residual_rms_m_s[0] - 0.03).abs() < 1e-12);
        assert!((fit.residual_rms_m_s[2] - 0.04).abs() < 1e-12);
        assert_eq!(fit.jacobian.ncols(), 0);
    }

    #[test]
    fn a_record_shorter_than_the_margins_is_refused() {
        let (time_s, dvl, reference) = weaving(&Installation::default());
        let error = fit(
            &time_s[..4],
            &dvl[..4],
            &reference,
            TermSet::of_error_model(crate::vocab::ErrorModel::Em4),
        )
        .unwrap_err();
        assert!(
            matches!(error, FitError::TooFewSamples { usable: 1, .. }),
            "{error}"
        );
        let error = fit(&time_s, &dvl[..5], &reference, TermSet::NONE).unwrap_err();
        assert!(matches!(
            error,
            FitError::LengthMismatch { time: 300, dvl: 5 }
        ));
    }
}
