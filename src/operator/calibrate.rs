//! `calibrate` as one library call: one recording of a DVL beside a reference with
//! attitude is read, the terms asked for are fitted (on its first `window_s` seconds
//! where that is asked) and bounded, scored on every sample before and after, the
//! installation's Kalman filter runs over the same samples and says how much of the
//! recording its terms needed ([`crate::installation::estimate::settling`]), and the recording is
//! written corrected beside the filter's terms against time ([`crate::results::corrected`]).
//! In: [`CalibrateArgs`]. Out: a [`Calibration`], everything the command prints, or a
//! [`CalibrateError`] that names the argument, file or step at fault.

use crate::data::paired::bag::{BagFrames, is_bag};
use crate::data::paired::{PairedError, PairedRecording, ReadCounts, Source};
use crate::installation::dead_reckoning::{Reckoning, reckonings_of};
use crate::installation::estimate::bound::{Noise, TermBound, bound};
use crate::installation::estimate::clock::{MAX_SEARCH_S, fit_searched};
use crate::installation::estimate::filter::{FilterSettings, run_filter_from};
use crate::installation::estimate::fit::{
    Fit, FitError, TIME_OFFSET_MARGIN_S, beyond_any_installation, mask_about,
};
use crate::installation::estimate::missing::{Asked, asked_for};
use crate::installation::estimate::settling::{SettlingPoint, settling_curve, settling_time};
use crate::installation::frames::Reference;
use crate::installation::study::filters::FilterRun;
use crate::installation::study::spec::{ObservabilityFile, default_filter_settings};
use crate::installation::terms::names::{TermName, term_list_faults, term_set};
use crate::installation::terms::{AxisRmse, Installation, TermSet, score};
use crate::operator::cost::{BeyondMemory, CALIBRATE, Cost};
use crate::operator::inputs::{Reading, not_over_an_input, source};
use crate::operator::installation_file::SavedInstallation;
use crate::operator::residual::Trace;
use crate::operator::ros::RosInstallation;
use crate::results::ResultsError;
use crate::results::corrected::{
    OtherRecording, Outputs, corrected_samples, stem, write, write_terms_in_time,
};
use crate::spec::SpecError;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// What `calibrate` is asked.
pub struct CalibrateArgs<'a> {
    pub dvl: &'a Path,
    /// The reference's file; the DVL's own when `None`.
    pub reference: Option<&'a Path>,
    /// A TOML file whose `[columns]` table names the columns; A-KIT's when `None`.
    pub columns: Option<&'a Path>,
    /// How to read the recordings beyond their columns (over the columns file).
    pub reading: Reading<'a>,
    pub terms: &'a [TermName],
    /// Calibrate on the first this many seconds only.
    pub window_s: Option<f64>,
    pub dvl_noise_cm_s: f64,
    pub reference_noise_cm_s: f64,
    /// How close to its value after every sample the filter's RMSE must stay, %.
    pub tolerance_pct: f64,
    /// The folder the corrected recording and the terms against time go to.
    pub out: &'a Path,
    /// Where the installation is saved for `correct`, with the terms of `terms` that
    /// are the dive's (found again on each dive), the rest the vehicle's.
    pub save: Option<&'a Path>,
    pub dive_terms: &'a [TermName],
    /// How far from zero a search for τ looks, s, before the fit; the fit's own scan
    /// alone where `None`.
    pub search_s: Option<f64>,
}

/// How far the noise a fit to fixes reads may lie from the noise given, as a factor
/// on the standard deviation, before the noise given is refused: a USBL's noise given
/// to a few times over is a judgement; a hundred times is a unit or a digit wrong.
pub const NOISE_RATIO_LIMIT: f64 = 100.0;

/// Why `calibrate` did not finish: an argument, the columns file, the recording or the
/// fit at fault (bad input), or a file that could not be written (a failure while
/// running, [`CalibrateError::Write`]).
#[derive(Debug, thiserror::Error)]
pub enum CalibrateError {
    #[error("--terms: {0}")]
    Terms(String),
    #[error("--search-s {}: give a positive number of seconds, at most {MAX_SEARCH_S}", crate::Shown(*.0))]
    Search(f64),
    #[error("--dive-terms: {0}")]
    DiveTerms(String),
    #[error("--save {}: {why}: give the path of a file", path.display())]
    Save { path: PathBuf, why: &'static str },
    #[error("--save {}: is also where the corrected recording goes: give another --save", path.display())]
    SaveOverOutput { path: PathBuf },
    #[error("{} and {} hold the same recording (the same SHA-256): a joint calibration counts each recording once", first.display(), again.display())]
    Duplicate { first: PathBuf, again: PathBuf },
    #[error("{} and {} hold the same DVL samples (each stamp within a millisecond and each velocity within a millimetre per second of the other's, though not the same bytes: other line endings, the digits written otherwise or rounded): a joint calibration counts each recording once", first.display(), again.display())]
    SameSamples { first: PathBuf, again: PathBuf },
    #[error(
        "--reference: {references} files for {dvls} DVL files: give one --reference per DVL file, in the same order, or none where each DVL file holds its reference"
    )]
    References { dvls: usize, references: usize },
    #[error("--dvl-noise-cm-s {}: give a positive number: the bound divides by it", crate::Shown(*.0))]
    DvlNoise(f64),
    #[error("--reference-noise-cm-s {}: give zero or a positive number", crate::Shown(*.0))]
    ReferenceNoise(f64),
    #[error("--window-s {}: give a positive number of seconds", crate::Shown(*.0))]
    Window(f64),
    #[error("--blackout-s {0}")]
    Blackout(String),
    #[error("{flag} {}: give a positive number of metres, under 10,000 km: the fit weighs the fixes by it", crate::Shown(*value))]
    FixNoise { flag: &'static str, value: f64 },
    #[error("{flag}: give the fixes' noise per horizontal axis with --fix-noise-m (metres): {why}")]
    NoFixNoise { flag: String, why: String },
    #[error("--depth-noise-m: {} gives no depth, so there is no depth noise to weigh: leave it out, or name the fixes' depth column in [fix_columns]", fixes.display())]
    NoDepths { fixes: PathBuf },
    #[error(
        "{fixes}: {outliers} of the {within} fixes within the DVL's pieces lie beyond the robust fit's reach of the dead reckoning: more than a quarter are outliers, so the fixes do not show the installation (fixes of another vehicle or dive, a clock beyond the fit's scan, or a DVL bias, which fixes do not calibrate)"
    )]
    FixOutliers {
        fixes: String,
        outliers: usize,
        within: usize,
    },
    #[error(
        "{noise}: the fixes' residuals are {} m RMS per horizontal axis, {} times the noise given, beyond a factor of {NOISE_RATIO_LIMIT} either way: the fit weighs the fixes and reads its intervals by it, so give the noise of these fixes (a USBL's metres, a GNSS's decimetres)",
        crate::ThreeFigures(*read_m),
        crate::ThreeFigures(*ratio)
    )]
    FixNoiseContradicted {
        /// The noise given: the flag and its value, or the fixes' own.
        noise: String,
        read_m: f64,
        ratio: f64,
    },
    #[error(
        "{fixes}: the fixes move {fixes_m:.1} m and the DVL {dvl_m:.1} m in the median step of {step_s} s over their span{hint}: no installation makes one of the other"
    )]
    FixesOtherMotion {
        fixes: String,
        step_s: f64,
        fixes_m: f64,
        dvl_m: f64,
        hint: &'static str,
    },
    /// The fixes file, placed at its line and column.
    #[error(transparent)]
    Fixes(#[from] crate::data::fixes::FixesError),
    /// An NMEA file of fixes that gives none.
    #[error(transparent)]
    Nmea(#[from] crate::data::nmea::NmeaError),
    #[error("{fixes}: calibrating {terms} against these fixes: {fault}")]
    FixFit {
        fixes: String,
        terms: String,
        fault: crate::installation::estimate::fixes::FixFitError,
    },
    #[error(
        "--tolerance-pct {}: give a positive percentage, at most 100 (how close to its last value the filter's RMSE must stay)",
        crate::Shown(*.0)
    )]
    Tolerance(f64),
    /// The `--columns` file, placed at its line and key.
    #[error("{0}")]
    Columns(SpecError),
    #[error(transparent)]
    Read(#[from] PairedError),
    /// The fit failed; its fault is kept, and shown inside the message (not as a source,
    /// which would print it twice).
    #[error(
        "{}: calibrating {terms} on {samples} samples: {fault}{}",
        dvl.display(),
        fault.advice()
    )]
    Fit {
        dvl: PathBuf,
        /// The terms asked for, comma-separated.
        terms: String,
        samples: usize,
        fault: FitError,
    },
    #[error(transparent)]
    Memory(#[from] BeyondMemory),
    /// An output (of `--out`, or `--save`) would replace a file `calibrate` reads.
    #[error(
        "{}: calibrate would write over its input {}: give another {flag}, or rename the file",
        output.display(),
        input.display()
    )]
    OverInput {
        output: PathBuf,
        input: PathBuf,
        flag: &'static str,
    },
    #[error(transparent)]
    OtherRecording(#[from] OtherRecording),
    #[error(transparent)]
    Write(#[from] ResultsError),
}

impl CalibrateError {
    /// Whether the fault lies in what was given (arguments, files, recording) rather
    /// than in writing the results.
    pub fn is_input(&self) -> bool {
        !matches!(self, CalibrateError::Write(_))
    }

    /// An output that would replace an input: `--save`'s where it is that file,
    /// otherwise one under `--out`.
    pub(super) fn over_input((output, input): (PathBuf, PathBuf), saved: &[&Path]) -> Self {
        let flag = if saved.contains(&output.as_path()) {
            "--save"
        } else {
            "--out"
        };
        CalibrateError::OverInput {
            output,
            input,
            flag,
        }
    }
}

/// Everything `calibrate` found and wrote.
pub struct Calibration {
    /// The fit of the terms asked for, and its bound under `noise`.
    pub fitted: Fit,
    pub bound: TermBound,
    /// The kinds of term the fit left out that its residuals still follow.
    pub asked: Vec<Asked>,
    /// The fit's terms with those the residuals do not depend on at all at zero: what
    /// the RMSE after and the corrected recording apply.
    pub applied: Installation,
    pub noise: Noise,
    /// The samples scored (those [`TIME_OFFSET_MARGIN_S`] inside the reference, the
    /// fit's outliers aside) and those recorded.
    pub scored: usize,
    pub recorded: usize,
    /// How many samples the recording read, kept and left out.
    pub read: ReadCounts,
    /// The RMSE against the reference on the scored samples with no terms and with the
    /// fit's; `None` with no sample to score.
    pub before: Option<AxisRmse>,
    pub after: Option<AxisRmse>,
    /// The residual on each sample scored, before and after, that these RMSE are of.
    pub trace: Trace,
    /// The dead reckoning's drift over the recording with no terms and with the terms
    /// applied, where the reference records positions.
    pub drift: Option<(Reckoning, Reckoning)>,
    /// The Kalman filter, its run over the samples fitted, and its settling curve
    /// (scored on every sample) with the length after which it settles.
    pub settings: FilterSettings,
    pub filter: FilterRun,
    pub curve: Vec<SettlingPoint>,
    pub settled_s: Option<f64>,
    /// As asked: the tolerance of the settling time, %, and the window, s.
    pub tolerance_pct: f64,
    pub window_s: Option<f64>,
    /// The corrected recording's CSV and Parquet files, and the filter's terms
    /// against time.
    pub corrected: Vec<PathBuf>,
    pub terms_in_time: PathBuf,
    /// A bag's topics and frames, and the installation as ROS uses it.
    pub frames: Option<BagFrames>,
    pub ros: Option<RosInstallation>,
}

/// The recording read, its reference, the samples scored (those
/// [`TIME_OFFSET_MARGIN_S`] inside the reference) and the samples calibrated on (the
/// first `window_s` seconds, or all).
struct Read {
    recording: PairedRecording,
    /// The SHA-256 of the DVL's file, as read.
    dvl_sha256: String,
    reference: Reference,
    frames: Option<BagFrames>,
    /// How many samples were read, and left out (of an NMEA reference, sentences).
    counts: ReadCounts,
    scored: Range<usize>,
    /// The samples of `scored` the fit found outliers (see [`Read::without_outliers`]),
    /// which no score counts.
    outliers: Vec<usize>,
    window: Option<PairedRecording>,
}

impl Read {
    fn calibrating(&self) -> &PairedRecording {
        self.window.as_ref().unwrap_or(&self.recording)
    }

    /// The RMSE `installation` leaves on the samples scored, outliers aside.
    fn score(&self, installation: &Installation) -> Option<AxisRmse> {
        let recording = &self.recording;
        let kept = self
            .scored
            .clone()
            .filter(|i| self.outliers.binary_search(i).is_err());
        score(
            installation,
            &recording.time_s,
            &recording.dvl_m_s,
            &self.reference,
            kept,
        )
    }

    /// The residual `applied` leaves on each sample scored, and none.
    fn trace(&self, applied: &Installation) -> Trace {
        let scored = (self.scored.clone(), &self.outliers[..]);
        Trace::of((&self.recording, &self.reference), scored, applied)
    }

    /// This read scored about `fitted`'s clock (the samples whose t + the τ its mask
    /// lies about is inside the reference: with a clock searched seconds away, not
    /// those at τ = 0), the samples whose residual under `fitted`'s terms is an outlier
    /// by its robust loss set aside.
    fn without_outliers(mut self, fitted: &Fit) -> Read {
        let centre_s = fitted.mask_centre_s.unwrap_or(0.0);
        self.scored = mask_about(&self.recording.time_s, &self.reference, centre_s);
        let Some(robust) = fitted.robust.as_ref().map(|r| r.loss) else {
            return self;
        };
        let recording = &self.recording;
        self.outliers = self
            .scored
            .clone()
            .filter(|&i| {
                let t = recording.time_s[i] + fitted.installation.time_offset_s;
                self.reference.at(t).is_some_and(|at| {
                    let predicted = fitted.installation.predict(at);
                    robust.is_outlier([0, 1, 2].map(|k| recording.dvl_m_s[i][k] - predicted[k]))
                })
            })
            .collect();
        self
    }
}

/// `calibrate`: the terms of one recording, their bound, how long the recording needed,
/// and the recording corrected.
pub fn calibrate(args: &CalibrateArgs) -> Result<Calibration, CalibrateError> {
    refused(args.request())?;
    let outputs = outputs(args);
    let inputs = [Some(args.dvl), args.reference, args.columns];
    clear_of_inputs(&inputs, &outputs.all(), (args.save, is_bag(args.dvl)))?;
    let source = source(args.dvl, args.reference, args.columns, args.reading)
        .map_err(CalibrateError::Columns)?;
    let read = read(args, source)?;
    let recording_sha256 = read.dvl_sha256.clone();
    outputs.not_another_recordings(args.dvl, &recording_sha256)?;
    let terms = term_set(args.terms);
    let fitted = fit_terms(args, &read, terms)?;
    let read = read.without_outliers(&fitted);
    let noise = args.noise();
    let bounded = bound(&fitted, noise, &ObservabilityFile::default().tolerances());
    let applied = seen_terms(&fitted, &bounded);
    if let Some(fault) = beyond_any_installation(&applied) {
        return Err(fit_error(args, &read, fault));
    }
    let calibrating = read.calibrating();
    let asked = asked_for(
        &fitted,
        (&calibrating.time_s, &calibrating.dvl_m_s),
        &read.reference,
        &bounded.residual_noise,
    );
    let trace = read.trace(&applied);
    let (before, after) = (trace.rmse(true), trace.rmse(false));
    // The filter starts from the clock the search found, where one was asked for.
    let from = Installation {
        time_offset_s: fitted.mask_centre_s.unwrap_or(0.0),
        ..Installation::default()
    };
    let (settings, filter, curve) = settle(&read, (terms, from), noise);
    let change = (
        before.map_or(f64::NAN, |r| 100.0 * r.total_m_s),
        after.map_or(f64::NAN, |r| 100.0 * r.total_m_s),
    );
    let settled_s = settling_time(&curve, args.tolerance_pct / 100.0, change).map(|p| p.length_s);
    let (corrected, terms_in_time) =
        write_files(&outputs, &recording_sha256, &read, &applied, &filter)?;
    let ros =
        (read.frames.as_ref()).map(|frames| ros_installation(args, frames, &applied, &fitted));
    if let Some(path) = args.save {
        save(
            path,
            args,
            (&fitted, &bounded),
            &recording_sha256,
            ros.as_ref(),
        )?;
    }
    Ok(Calibration {
        fitted,
        bound: bounded,
        asked,
        applied,
        noise,
        scored: read.scored.len() - read.outliers.len(),
        recorded: read.recording.time_s.len(),
        read: read.counts.clone(),
        before,
        after,
        trace,
        drift: reckonings_of([&Installation::default(), &applied], &read.recording).map(Into::into),
        settings,
        filter,
        curve,
        settled_s,
        tolerance_pct: args.tolerance_pct,
        window_s: args.window_s,
        corrected,
        terms_in_time,
        frames: read.frames,
        ros,
    })
}

/// Refuses a calibration whose `corrected` files or `save` would write over one of its
/// `inputs` (every file a bag is read from), or whose `save` is one of its `corrected`
/// files; where the calibration `writes_ros` (one recording, a bag), the URDF and ROS
/// text `--save` writes beside its file count as `save` too.
pub(crate) fn clear_of_inputs(
    inputs: &[Option<&Path>],
    corrected: &[&Path],
    (save, writes_ros): (Option<&Path>, bool),
) -> Result<(), CalibrateError> {
    let beside: Vec<PathBuf> = match save {
        Some(save) if writes_ros => RosInstallation::paths(save).to_vec(),
        _ => Vec::new(),
    };
    let saved: Vec<&Path> = save
        .into_iter()
        .chain(beside.iter().map(PathBuf::as_path))
        .collect();
    let written: Vec<&Path> = corrected
        .iter()
        .copied()
        .chain(saved.iter().copied())
        .collect();
    if let Some(over) = not_over_an_input(inputs, &written) {
        return Err(CalibrateError::over_input(over, &saved));
    }
    let saved: Vec<Option<&Path>> = saved.into_iter().map(Some).collect();
    match not_over_an_input(&saved, corrected) {
        Some((_, path)) => Err(CalibrateError::SaveOverOutput { path }),
        None => Ok(()),
    }
}

/// What a calibration is asked beyond its files, one recording's or several's: what
/// [`refused`] checks, the same for both.
pub(super) struct Request<'a> {
    pub(super) terms: &'a [TermName],
    pub(super) dive_terms: &'a [TermName],
    pub(super) window_s: Option<f64>,
    pub(super) dvl_noise_cm_s: f64,
    pub(super) reference_noise_cm_s: f64,
    pub(super) tolerance_pct: f64,
    pub(super) save: Option<&'a Path>,
    pub(super) search_s: Option<f64>,
}

impl CalibrateArgs<'_> {
    /// What calibrating the recording will ask of this machine.
    /// The noise the bound is under, m/s.
    fn noise(&self) -> Noise {
        Noise {
            dvl_m_s: self.dvl_noise_cm_s / 100.0,
            reference_m_s: self.reference_noise_cm_s / 100.0,
        }
    }

    pub fn cost(&self) -> Result<Cost, CalibrateError> {
        Cost::of(CALIBRATE, &[(self.dvl, self.reference)]).map_err(CalibrateError::Read)
    }

    fn request(&self) -> Request<'_> {
        Request {
            terms: self.terms,
            dive_terms: self.dive_terms,
            window_s: self.window_s,
            dvl_noise_cm_s: self.dvl_noise_cm_s,
            reference_noise_cm_s: self.reference_noise_cm_s,
            tolerance_pct: self.tolerance_pct,
            save: self.save,
            search_s: self.search_s,
        }
    }
}

/// The first argument of `args` at fault, where one is.
pub(super) fn refused(args: Request) -> Result<(), CalibrateError> {
    if let Some((_, message)) = term_list_faults(args.terms).first() {
        return Err(CalibrateError::Terms(message.clone()));
    }
    if !(args.dvl_noise_cm_s.is_finite() && args.dvl_noise_cm_s > 0.0) {
        return Err(CalibrateError::DvlNoise(args.dvl_noise_cm_s));
    }
    if !(args.reference_noise_cm_s.is_finite() && args.reference_noise_cm_s >= 0.0) {
        return Err(CalibrateError::ReferenceNoise(args.reference_noise_cm_s));
    }
    if let Some(w) = args.window_s
        && !(w.is_finite() && w > 0.0)
    {
        return Err(CalibrateError::Window(w));
    }
    if !(args.tolerance_pct > 0.0 && args.tolerance_pct <= 100.0) {
        return Err(CalibrateError::Tolerance(args.tolerance_pct));
    }
    if let Some(search_s) = args.search_s {
        if !(search_s > 0.0 && search_s <= MAX_SEARCH_S) {
            return Err(CalibrateError::Search(search_s));
        }
        if !args.terms.contains(&TermName::TimeOffset) {
            return Err(CalibrateError::Terms(
                "--search-s looks for the time offset, which is not among them: add time_offset"
                    .into(),
            ));
        }
    }
    dive_terms_refused(args.terms, args.dive_terms, args.save.is_some())
        .map_err(CalibrateError::DiveTerms)?;
    if let Some(path) = args.save {
        save_refused(path)?;
    }
    Ok(())
}

/// What is wrong with `dive` as the dive's terms of a calibration of `terms`: each
/// must be a dive's kind of term (the time offset or a bias); and where the
/// installation is saved for `correct`, which finds each dive's clock again, the time
/// offset must be among them and each must be among `terms`.
fn dive_terms_refused(terms: &[TermName], dive: &[TermName], saving: bool) -> Result<(), String> {
    if let Some(term) = dive.iter().find(|t| !t.may_be_the_dives()) {
        return Err(format!(
            "{:?} belongs to the vehicle, not the dive: give time_offset, and bias or bias_scalar",
            term.name()
        ));
    }
    if !saving {
        return Ok(());
    }
    if !dive.contains(&TermName::TimeOffset) {
        return Err("must hold time_offset: the clock is what a dive sets again".into());
    }
    if let Some(term) = dive.iter().find(|t| !terms.contains(t)) {
        return Err(format!(
            "{:?} is not among --terms: a saved dive's term must be one the calibration fits",
            term.name()
        ));
    }
    Ok(())
}

/// Refuses, before anything is read, a `--save` path that cannot be a file: a folder,
/// or one under a file (its missing folders are made when it is written).
fn save_refused(path: &Path) -> Result<(), CalibrateError> {
    let under_a_file = path.ancestors().skip(1).any(|a| a.is_file());
    let why = if path.is_dir() {
        "is a folder"
    } else if under_a_file {
        "is under a file, not a folder"
    } else {
        return Ok(());
    };
    Err(CalibrateError::Save {
        path: path.to_path_buf(),
        why,
    })
}

/// The terms of `fitted`, those on which the residuals do not depend at all (their
/// value is noise, not the installation's) at zero. A term correlated with another, or
/// known only loosely, is applied: together with the others it still corrects.
fn seen_terms(fitted: &Fit, bounded: &TermBound) -> Installation {
    let parameters: Vec<f64> = (fitted.parameters.iter().zip(&bounded.applied))
        .map(|(&value, &applied)| if applied { value } else { 0.0 })
        .collect();
    Installation::from_parameters(&fitted.terms, &parameters)
}

/// Writes the installation file of `fitted` and its bound, from the DVL file whose
/// SHA-256 is `recording_sha256`, to `path`; and beside it, for a bag, the installation
/// as ROS uses it.
fn save(
    path: &Path,
    args: &CalibrateArgs,
    (fitted, bounded): (&Fit, &TermBound),
    recording_sha256: &str,
    ros: Option<&RosInstallation>,
) -> Result<(), CalibrateError> {
    let mut saved = SavedInstallation::of(
        bounded,
        (args.terms, args.dive_terms),
        (args.dvl, recording_sha256),
        (args.dvl_noise_cm_s, args.reference_noise_cm_s),
        fitted.residual_rms_m_s,
    );
    if let Some(ros) = ros {
        saved = saved.with_mount(ros.tf_static.clone());
    }
    let io = |source| ResultsError::Io {
        path: path.to_path_buf(),
        source,
    };
    saved.write(path).map_err(io)?;
    if let Some(ros) = ros {
        ros.write(path).map_err(io)?;
    }
    Ok(())
}

/// A bag's installation as ROS uses it: `frames`' mount turned by `applied`, its
/// lever arm where `args` estimated one.
fn ros_installation(
    args: &CalibrateArgs,
    frames: &BagFrames,
    applied: &Installation,
    fitted: &Fit,
) -> RosInstallation {
    let lever_arm_found = args.terms.iter().any(|t| t.name() == "lever_arm");
    RosInstallation::of(frames, applied, lever_arm_found, fitted.residual_rms_m_s)
}

/// The files written for `args`, named after the DVL's file.
fn outputs(args: &CalibrateArgs) -> Outputs {
    Outputs::of(args.out, &stem(args.dvl))
}

/// The recording of `args` from its `source`, its reference, and its window where one
/// is asked, its cost stated first.
fn read(args: &CalibrateArgs, source: Source) -> Result<Read, CalibrateError> {
    args.cost()?.state()?;
    let read = source.read()?;
    let dvl_sha256 = read.dvl_sha256().to_string();
    let counts = read.recording.counts();
    let frames = read.frames;
    let recording = read.recording;
    let reference = Reference::new(&recording);
    let scored = reference.interior(&recording.time_s, TIME_OFFSET_MARGIN_S);
    let window = args.window_s.map(|w| recording.first_seconds(w));
    Ok(Read {
        recording,
        dvl_sha256,
        reference,
        frames,
        counts,
        scored,
        outliers: Vec::new(),
        window,
    })
}

/// The fit of `terms` on the samples calibrated on.
fn fit_terms(args: &CalibrateArgs, read: &Read, terms: TermSet) -> Result<Fit, CalibrateError> {
    let calibrating = read.calibrating();
    fit_searched(
        (&calibrating.time_s, &calibrating.dvl_m_s),
        &read.reference,
        terms,
        args.search_s,
    )
    .map_err(|fault| fit_error(args, read, fault))
}

/// The names of `terms`, comma-separated, as a message gives them.
pub(super) fn named(terms: &[TermName]) -> String {
    terms
        .iter()
        .map(|t| t.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The fit of `args` on the samples of `read` failed with `fault`.
fn fit_error(args: &CalibrateArgs, read: &Read, fault: FitError) -> CalibrateError {
    CalibrateError::Fit {
        dvl: args.dvl.to_path_buf(),
        terms: named(args.terms),
        samples: read.calibrating().time_s.len(),
        fault,
    }
}

/// The filter of an installation spec's `[calibration.kalman]` as it comes, run over the
/// samples calibrated on, and its settling curve scored on every sample.
fn settle(
    read: &Read,
    (terms, from): (TermSet, Installation),
    noise: Noise,
) -> (FilterSettings, FilterRun, Vec<SettlingPoint>) {
    let settings = default_filter_settings();
    let calibrating = read.calibrating();
    let filter = FilterRun {
        label: "Kalman filter".into(),
        terms,
        steps: run_filter_from(
            (&calibrating.time_s, &calibrating.dvl_m_s, &read.reference),
            (terms, from),
            &settings,
            noise,
        ),
    };
    let curve = settling_curve(&filter.steps, |installation| {
        read.score(installation)
            .map_or(f64::NAN, |rmse| 100.0 * rmse.total_m_s)
    });
    (settings, filter, curve)
}

/// Writes the recording corrected by the terms applied and the filter's terms against time into
/// `outputs`, each recording `recording_sha256`; the corrected files' paths, and the
/// terms'.
fn write_files(
    outputs: &Outputs,
    recording_sha256: &str,
    read: &Read,
    applied: &Installation,
    filter: &FilterRun,
) -> Result<(Vec<PathBuf>, PathBuf), CalibrateError> {
    let corrected = corrected_samples(applied, &read.recording, &read.reference);
    let written = write(outputs, &corrected, recording_sha256)?;
    let points = filter.points(&outputs.stem);
    let terms_in_time = write_terms_in_time(outputs, &points, recording_sha256)?;
    Ok((written, terms_in_time))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::operator::cost::Rows;

    /// A straight, level recording of 300 s at 1 Hz in A-KIT's two files, the vehicle
    /// heading north at a varying speed, its DVL off by `bias_m_s`; the DVL file's path.
    fn straight_recording(folder: &Path, bias_m_s: [f64; 3]) -> PathBuf {
        straight_recording_swinging(folder, bias_m_s, 0.2)
    }

    /// [`straight_recording`] whose speed swings by `swing_m_s` about 1 m/s (at 0, a
    /// constant speed, where nothing shows a time offset).
    fn straight_recording_swinging(folder: &Path, bias_m_s: [f64; 3], swing_m_s: f64) -> PathBuf {
        let mut dvl = String::from("Time [s],DVL X [m/s],DVL Y [m/s],DVL Z [m/s]\n");
        let mut reference = String::from(
            "Time [s],V North [m/s],V East [m/s],V Down [m/s],Roll [rad],Pitch [rad],Yaw [rad]\n",
        );
        for i in 0..300 {
            let t = i as f64;
            let speed = 1.0 + swing_m_s * (t / 20.0).sin();
            let [bx, by, bz] = bias_m_s;
            dvl.push_str(&format!("{t},{},{by},{bz}\n", speed + bx));
            reference.push_str(&format!("{t},{speed},0,0,0,0,0\n"));
        }
        std::fs::write(folder.join("GT.csv"), reference).unwrap();
        std::fs::write(folder.join("DVL.csv"), dvl).unwrap();
        folder.join("DVL.csv")
    }

    fn args<'a>(
        dvl: &'a Path,
        reference: &'a Path,
        out: &'a Path,
        terms: &'a [TermName],
    ) -> CalibrateArgs<'a> {
        CalibrateArgs {
            dvl,
            reference: Some(reference),
            columns: None,
            reading: Reading::default(),
            terms,
            window_s: None,
            dvl_noise_cm_s: 2.0,
            reference_noise_cm_s: 0.0,
            tolerance_pct: 10.0,
            out,
            save: None,
            dive_terms: &[TermName::TimeOffset],
            search_s: None,
        }
    }

    /// The one call recovers a known bias, settles, and names the three files it wrote.
    #[test]
    fn one_call_fits_settles_and_writes() {
        let folder = tempfile::tempdir().unwrap();
        let bias = [0.03, -0.02, 0.01];
        let dvl = straight_recording(folder.path(), bias);
        let (reference, out) = (folder.path().join("GT.csv"), folder.path().join("out"));
        let terms = [TermName::Bias];
        let calibration = calibrate(&args(&dvl, &reference, &out, &terms)).unwrap();
        for k in 0..3 {
            assert!((calibration.fitted.installation.bias_m_s[k] - bias[k]).abs() < 1e-9);
        }
        assert_eq!((calibration.scored, calibration.recorded), (294, 300));
        assert!(calibration.after.unwrap().total_m_s < 1e-9);
        // The filter takes the samples 3 s inside the reference, the last at 296 s.
        assert_eq!(calibration.curve.last().unwrap().length_s, 297.0);
        assert!(calibration.settled_s.is_some_and(|s| s < 300.0));
        assert_eq!(
            calibration.corrected,
            [
                out.join("DVL-corrected.csv"),
                out.join("DVL-corrected.parquet")
            ]
        );
        assert_eq!(
            calibration.terms_in_time,
            out.join("DVL-terms-in-time.parquet")
        );
        assert!(calibration.corrected.iter().all(|p| p.is_file()));
        assert!(calibration.terms_in_time.is_file());
    }

    /// On a straight line at constant speed the time offset cannot be seen: it is
    /// printed as not seen and neither scored nor applied, where the fit's value (noise)
    /// once shifted every corrected sample's `valid_at_s`.
    #[test]
    fn a_term_the_recording_cannot_show_is_not_applied() {
        let folder = tempfile::tempdir().unwrap();
        let bias = [0.03, -0.02, 0.01];
        let dvl = straight_recording_swinging(folder.path(), bias, 0.0);
        let (reference, out) = (folder.path().join("GT.csv"), folder.path().join("out"));
        let terms = [TermName::TimeOffset, TermName::Bias];
        let calibration = calibrate(&args(&dvl, &reference, &out, &terms)).unwrap();
        assert!(
            calibration.bound.is_unseen("time_offset_s"),
            "{:?}",
            calibration.bound.unseen
        );
        assert_eq!(calibration.applied.time_offset_s, 0.0);
        assert_eq!(
            calibration.applied.bias_m_s,
            calibration.fitted.installation.bias_m_s
        );
        let csv = std::fs::read_to_string(&calibration.corrected[0]).unwrap();
        for line in csv.lines().skip(1) {
            let fields: Vec<&str> = line.split(',').collect();
            assert_eq!(
                fields[0], fields[1],
                "valid_at_s moved by an unseen τ: {line}"
            );
        }
    }

    /// Ten million rows under a 2.5 GiB limit aborted on a failed allocation: refused
    /// before the recording is read, saying how much it needs.
    #[test]
    fn a_recording_beyond_the_machines_memory_is_refused_before_it_is_read() {
        let limit = 2.5 * 1024.0 * 1024.0 * 1024.0;
        let rows = |dvl_rows| Rows {
            dvl: PathBuf::from("dive.csv"),
            dvl_rows,
            reference_rows: None,
            fix_rows: None,
        };
        let refused = Cost::on(CALIBRATE, vec![rows(10_000_000)], limit)
            .refused()
            .expect_err("refused");
        assert!(CalibrateError::from(refused.clone()).is_input());
        assert_eq!(
            refused.to_string(),
            "dive.csv: 10000000 rows need about 33.5 GiB of memory to calibrate and this process may use 2.5 GiB: calibrate a part of it, a file of fewer rows"
        );
        assert!(
            Cost::on(CALIBRATE, vec![rows(400)], limit)
                .refused()
                .is_ok()
        );
    }

    /// A bad argument is bad input and writes nothing; a folder that cannot be made is a
    /// failure while running.
    #[test]
    fn a_bad_argument_is_input_and_an_unwritable_folder_a_failure() {
        let folder = tempfile::tempdir().unwrap();
        let dvl = straight_recording(folder.path(), [0.0; 3]);
        let reference = folder.path().join("GT.csv");
        let out = folder.path().join("out");
        let refused = calibrate(&args(&dvl, &reference, &out, &[])).err().unwrap();
        assert!(matches!(refused, CalibrateError::Terms(_)) && refused.is_input());
        assert!(!out.exists());
        let below_a_file = dvl.join("out");
        let terms = [TermName::Bias];
        let failed = calibrate(&args(&dvl, &reference, &below_a_file, &terms))
            .err()
            .unwrap();
        assert!(matches!(failed, CalibrateError::Write(_)) && !failed.is_input());
    }
}
