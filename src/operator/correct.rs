//! `correct` as one library call: an installation file that `calibrate --save` wrote
//! is applied to another dive. The vehicle's terms are carried; the dive's (its clock,
//! and the bias where the file says so) are found again from the dive's first w
//! seconds against its reference ([`crate::installation::estimate::clock`]), or taken as given.
//! The dive is written corrected (CSV and Parquet, as `calibrate` writes), and how well
//! the carried installation fits it is measured after those w seconds, whole and in
//! blocks of w seconds, against the specified noise and the residual at calibration:
//! a DVL remounted or a clock that jumped mid-dive shows as a residual far above them.
//! In: [`CorrectArgs`]. Out: a [`Correction`], or a [`CorrectError`] naming the file
//! and what to do; nothing is written unless everything before the writing succeeded.

use crate::Vec3;
use crate::data::paired::bag::BagFrames;
use crate::data::paired::{PairedError, PairedRecording, ReadCounts};
use crate::installation::dead_reckoning::{Reckoning, reckonings_of};
use crate::installation::estimate::bound::{DEFAULT_TOLERANCES, Noise};
use crate::installation::estimate::clock::{
    Carried, Clock, ClockError, ClockSearch, MAX_SEARCH_S, SearchGrid, refind,
};
use crate::installation::estimate::fit::TIME_OFFSET_MARGIN_S;
use crate::installation::estimate::robust::outliers_among;
use crate::installation::frames::Reference;
use crate::installation::terms::{AxisRmse, Installation, corrected_error};
use crate::operator::cost::{BeyondMemory, CORRECT, Cost};
use crate::operator::inputs::{Reading, not_over_an_input, source};
use crate::operator::installation_file::SavedMount;
use crate::operator::installation_file::{InstallationFileError, SavedInstallation};
use crate::operator::residual::Trace;
use crate::results::ResultsError;
use crate::results::corrected::{
    CorrectedSample, OtherRecording, Outputs, corrected_samples, stem, write, write_bag,
};
use crate::spec::SpecError;
use std::path::{Path, PathBuf};

/// How far above the residual at calibration (and above the specified noise) the
/// dive's residual, whole or in a block, must be to be warned of.
pub const WARNING_RATIO: f64 = 1.5;

/// What `correct` is asked.
pub struct CorrectArgs<'a> {
    pub dvl: &'a Path,
    /// The reference's file; the DVL's own when `None`.
    pub reference: Option<&'a Path>,
    pub columns: Option<&'a Path>,
    /// How to read the recordings beyond their columns (over the columns file).
    pub reading: Reading<'a>,
    pub installation: &'a Path,
    /// The first seconds of the dive that find its clock again.
    pub window_s: f64,
    /// How far from the calibration's time offset the search looks, s.
    pub search_s: f64,
    /// The dive's time offset, s, where it is known: no search.
    pub time_offset_s: Option<f64>,
    pub out: &'a Path,
}

impl CorrectArgs<'_> {
    /// What correcting the dive will ask of this machine.
    pub fn cost(&self) -> Result<Cost, CorrectError> {
        Cost::of(CORRECT, &[(self.dvl, self.reference)]).map_err(CorrectError::Read)
    }
}

#[derive(Debug, thiserror::Error)]
pub enum CorrectError {
    #[error(transparent)]
    Installation(#[from] InstallationFileError),
    #[error(
        "{}: its /tf_static places {dvl_frame} in {body} at roll, pitch, yaw {dive} deg, but the installation {} was found with it at {saved} deg: its misalignment is a turn from that mount, and would be applied to another ({why})",
        dvl.display(),
        installation.display()
    )]
    Mount {
        dvl: PathBuf,
        installation: PathBuf,
        body: String,
        dvl_frame: String,
        dive: String,
        saved: String,
        why: &'static str,
    },
    #[error("--window-s {}: give a positive number of seconds", crate::Shown(*.0))]
    Window(f64),
    #[error("--search-s {}: give a positive number of seconds, at most {MAX_SEARCH_S}", crate::Shown(*.0))]
    Search(f64),
    #[error("--time-offset-s {}: give a finite number of seconds", crate::Shown(*.0))]
    TimeOffset(f64),
    #[error("{0}")]
    Columns(SpecError),
    #[error(transparent)]
    Read(#[from] PairedError),
    #[error(
        "{}: the dive lasts {duration_s:.1} s, not more than the {window_s} s that find its clock: give a shorter --window-s, or its clock with --time-offset-s",
        dvl.display()
    )]
    TooShort {
        dvl: PathBuf,
        duration_s: f64,
        window_s: f64,
    },
    #[error("{}: its clock cannot be found from its first {} s: {fault}; give a longer --window-s, or its clock with --time-offset-s", dvl.display(), crate::Shown(*window_s))]
    Clock {
        dvl: PathBuf,
        window_s: f64,
        fault: ClockError,
    },
    #[error(
        "{}: with a time offset of {time_offset_s} s, no sample of the dive lies inside its reference: give the dive's clock (--time-offset-s) in seconds, or let correct find it",
        dvl.display()
    )]
    NoOverlap { dvl: PathBuf, time_offset_s: f64 },
    #[error(
        "{}: correct would write over its input {}: give another --out, or rename the file",
        output.display(),
        input.display()
    )]
    OverInput { output: PathBuf, input: PathBuf },
    #[error(transparent)]
    Memory(#[from] BeyondMemory),
    #[error(transparent)]
    Fixes(#[from] Box<crate::operator::calibrate::CalibrateError>),
    #[error(
        "{fixes}: the installation applied (time offset {time_offset_s:.3} s, found from the fixes) leaves the fixes further from the dead reckoning than no terms do ({after_m:.2} m RMS horizontally against {before_m:.2} m): it does not carry to this dive (the DVL remounted, the fixes on another clock, or the dive's clock more than 3 s from the installation's, beyond the fit's search: give it with --time-offset-s); nothing written: calibrate this dive with calibrate --fixes"
    )]
    FixesFitWorse {
        fixes: String,
        time_offset_s: f64,
        before_m: f64,
        after_m: f64,
    },
    #[error(
        "{fixes}: the dive's clock cannot be found from the fixes of its first {} s (--window-s): {fault}; give a longer --window-s (without it, every fix of the dive), or its clock with --time-offset-s",
        crate::Shown(*window_s)
    )]
    FixWindow {
        fixes: String,
        window_s: f64,
        fault: Box<crate::installation::estimate::fixes::FixFitError>,
    },
    #[error(
        "--window-s {}: with --time-offset-s there is no clock to find, and against fixes the window is only where it is found: leave one of them out",
        crate::Shown(*.0)
    )]
    WindowWithClock(f64),
    #[error(
        "--time-offset-s {}: the installation at the clock given leaves the fixes further from the dead reckoning than no terms do ({after_m:.2} m RMS horizontally against {before_m:.2} m): the clock is not this dive's, or the installation does not carry to it; nothing written: leave --time-offset-s out to find the clock from the fixes, or calibrate this dive with calibrate --fixes",
        crate::Shown(*time_offset_s)
    )]
    GivenClockFitsWorse {
        time_offset_s: f64,
        before_m: f64,
        after_m: f64,
    },
    #[error(
        "{fixes}: the first {} s of the dive (--window-s) hold no fix the fit can read (it reads those at least {} s inside the DVL's pieces, about the installation's clock): give a longer --window-s, or the dive's clock with --time-offset-s",
        crate::Shown(*window_s),
        crate::installation::estimate::fit::TIME_OFFSET_MARGIN_S
    )]
    WindowHoldsNoFix { fixes: String, window_s: f64 },
    #[error(
        "--time-offset-s {}: the installation at the clock given does not fit the dive's fixes: {fault}; give the dive's clock in seconds, or leave it out and let correct find it from the fixes",
        crate::Shown(*time_offset_s)
    )]
    GivenClock {
        time_offset_s: f64,
        fault: Box<crate::installation::estimate::fixes::FixFitError>,
    },
    #[error("{fixes}: the dive's dead reckoning cannot be fitted to its fixes: {fault}")]
    FixFit {
        fixes: String,
        fault: Box<crate::installation::estimate::fixes::FixFitError>,
    },
    #[error(transparent)]
    OtherRecording(#[from] OtherRecording),
    #[error(transparent)]
    Write(#[from] ResultsError),
}

/// The most the DVL's mount in a dive's `/tf_static` may differ from the one the
/// installation was found on, degrees: beyond it, the misalignment found (a turn from
/// that mount) would be applied to another.
pub const MOUNT_TOLERANCE_DEG: f64 = 0.01;

impl CorrectError {
    /// Whether the fault lies in what was given rather than in writing the results.
    pub fn is_input(&self) -> bool {
        match self {
            CorrectError::Fixes(fault) => fault.is_input(),
            _ => !matches!(self, CorrectError::Write(_)),
        }
    }
}

/// The residual of the carried installation over one stretch of the dive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stretch {
    pub from_s: f64,
    pub to_s: f64,
    pub rmse: AxisRmse,
}

/// Everything `correct` found and wrote.
pub struct Correction {
    pub saved: SavedInstallation,
    /// The clock found again, where it was searched.
    pub clock: Option<Clock>,
    /// The installation applied: the carried terms with the dive's.
    pub applied: Installation,
    /// The residual after the first w seconds, whole and in blocks of w seconds; the
    /// totals it is held against, cm/s: the specified noise's and the calibration's.
    pub after: Option<AxisRmse>,
    pub blocks: Vec<Stretch>,
    /// The samples after the first w seconds left out of `after` and `blocks` as
    /// outliers.
    pub outliers: usize,
    /// The residual on each of those samples, with no terms and with the installation
    /// applied: what `after` is of, and the report draws.
    pub trace: Trace,
    pub noise_cm_s: f64,
    pub calibration_cm_s: f64,
    pub window_s: f64,
    pub search_s: f64,
    pub installation_file: PathBuf,
    pub written: Vec<PathBuf>,
    /// How many samples the dive read, kept and left out.
    pub read: ReadCounts,
    /// The dead reckoning's drift over the whole dive with no terms and with the
    /// installation applied, where the reference records positions.
    pub drift: Option<(Reckoning, Reckoning)>,
}

impl Correction {
    /// The total, cm/s, above which a residual is warned of.
    pub fn warning_cm_s(&self) -> f64 {
        WARNING_RATIO * self.noise_cm_s.max(self.calibration_cm_s)
    }

    /// Whether the dive's residual after its first w seconds is far above the noise and
    /// the calibration's.
    pub fn fits_far_worse(&self) -> bool {
        self.after
            .is_some_and(|r| 100.0 * r.total_m_s > self.warning_cm_s())
    }

    /// The first block whose residual is far above the noise and the calibration's,
    /// where the first block after the clock was found is not: the fit that held at the
    /// dive's start broke later.
    pub fn jumped(&self) -> Option<&Stretch> {
        let bad = |b: &&Stretch| 100.0 * b.rmse.total_m_s > self.warning_cm_s();
        match self.blocks.first() {
            Some(first) if !bad(&first) => self.blocks.iter().find(bad),
            _ => None,
        }
    }
}

/// `correct`: the installation file applied to the dive of `args`.
pub fn correct(args: &CorrectArgs) -> Result<Correction, CorrectError> {
    refused(args)?;
    let saved = SavedInstallation::read(args.installation)?;
    let outputs = Outputs::of(args.out, &stem(args.dvl));
    let inputs = [
        Some(args.dvl),
        args.reference,
        args.columns,
        Some(args.installation),
    ];
    let bag_output = outputs.csv.with_extension("mcap");
    let mut written = outputs.all().to_vec();
    written.push(&bag_output);
    if let Some((output, input)) = not_over_an_input(&inputs, &written) {
        return Err(CorrectError::OverInput { output, input });
    }
    let source = source(args.dvl, args.reference, args.columns, args.reading)
        .map_err(CorrectError::Columns)?;
    args.cost()?.state()?;
    if args.time_offset_s.is_none() {
        eprintln!("{}", SearchGrid::of(args.search_s));
    }
    let loaded = source.load()?;
    let recording_sha256 = loaded.dvl_sha256().to_string();
    outputs.not_another_recordings(args.dvl, &recording_sha256)?;
    let read = loaded.parse()?;
    let counts = read.recording.counts();
    let (recording, frames) = (read.recording, read.frames);
    if let (Some(frames), Some(mount)) = (&frames, &saved.mount) {
        on_the_same_mount(args, frames, mount)?;
    }
    let reference = Reference::new(&recording);
    let noise = Noise {
        dvl_m_s: saved.dvl_noise_cm_s / 100.0,
        reference_m_s: saved.reference_noise_cm_s / 100.0,
    };
    let (applied, clock) = applied(args, &saved, (&recording, &reference), noise)?;
    let (after, blocks, outliers, trace) = fit_after(args, &recording, &reference, &applied);
    let samples = corrected_samples(&applied, &recording, &reference);
    if samples.iter().all(|s| s.velocity_m_s.is_err()) {
        return Err(CorrectError::NoOverlap {
            dvl: args.dvl.to_path_buf(),
            time_offset_s: applied.time_offset_s,
        });
    }
    let mut files = write(&outputs, &samples, &recording_sha256)?;
    if let Some(frames) = &frames {
        files.push(write_corrected_bag(bag_output, &samples, frames, &saved)?);
    }
    let total = |v: crate::Vec3| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    Ok(Correction {
        noise_cm_s: 3f64.sqrt() * 100.0 * noise.per_axis_m_s(),
        calibration_cm_s: total(saved.residual_cm_s),
        saved,
        clock,
        applied,
        after,
        blocks,
        outliers,
        trace,
        window_s: args.window_s,
        search_s: args.search_s,
        installation_file: args.installation.to_path_buf(),
        written: files,
        read: counts,
        drift: reckonings_of([&Installation::default(), &applied], &recording).map(Into::into),
    })
}

/// The installation applied to the dive: the saved one with the clock `args` give, or
/// with the dive's terms found again from its first seconds (and that clock); refused
/// where the dive is not longer than those seconds.
fn applied(
    args: &CorrectArgs,
    saved: &SavedInstallation,
    (recording, reference): (&PairedRecording, &Reference),
    noise: Noise,
) -> Result<(Installation, Option<Clock>), CorrectError> {
    if let Some(time_offset_s) = args.time_offset_s {
        let given = Installation {
            time_offset_s,
            ..saved.installation()
        };
        return Ok((given, None));
    }
    let duration_s = recording.duration_s();
    if duration_s <= args.window_s {
        return Err(CorrectError::TooShort {
            dvl: args.dvl.to_path_buf(),
            duration_s,
            window_s: args.window_s,
        });
    }
    let clock = find_clock(args, saved, (recording, reference), noise)?;
    Ok((clock.installation, Some(clock)))
}

/// The first argument of `args` at fault, where one is.
fn refused(args: &CorrectArgs) -> Result<(), CorrectError> {
    if !(args.window_s.is_finite() && args.window_s > 0.0) {
        return Err(CorrectError::Window(args.window_s));
    }
    if !(args.search_s > 0.0 && args.search_s <= MAX_SEARCH_S) {
        return Err(CorrectError::Search(args.search_s));
    }
    if let Some(tau) = args.time_offset_s
        && !tau.is_finite()
    {
        return Err(CorrectError::TimeOffset(tau));
    }
    Ok(())
}

/// The dive's terms found again from its first `args.window_s` seconds.
fn find_clock(
    args: &CorrectArgs,
    saved: &SavedInstallation,
    (recording, reference): (&PairedRecording, &Reference),
    noise: Noise,
) -> Result<Clock, CorrectError> {
    let start = recording.time_s[0];
    let end = recording
        .time_s
        .partition_point(|&t| t - start < args.window_s);
    let search = ClockSearch {
        dive_terms: saved.dive_term_set(),
        search_s: args.search_s,
    };
    let std: Vec<f64> = saved.terms.iter().map(|t| t.std).collect();
    let carried = Carried::with(
        saved.installation(),
        saved.term_set(),
        &std,
        &saved.correlation,
    );
    let calibrated = saved
        .residual_cm_s
        .iter()
        .map(|r| r * r)
        .sum::<f64>()
        .sqrt()
        / 100.0;
    refind(
        (&recording.time_s[..end], &recording.dvl_m_s[..end]),
        reference,
        &carried,
        search,
        (noise, &DEFAULT_TOLERANCES),
    )
    .and_then(|clock| {
        let carried_s = saved.installation().time_offset_s;
        clock.within_the_search(carried_s, args.search_s, calibrated)?;
        Ok(clock)
    })
    .map_err(|fault| CorrectError::Clock {
        dvl: args.dvl.to_path_buf(),
        window_s: args.window_s,
        fault,
    })
}

/// The residual of `applied` after the first `args.window_s` seconds, whole and in
/// blocks of that length (a last block shorter than half of it joins the one before),
/// the outliers among those samples aside (a component beyond the fits' `TUKEY_C`
/// scales of the rest): a spike is not a DVL that fits worse. Also how many there were,
/// and the residual on each sample, before and after, that the whole is of.
fn fit_after(
    args: &CorrectArgs,
    recording: &PairedRecording,
    reference: &Reference,
    applied: &Installation,
) -> (Option<AxisRmse>, Vec<Stretch>, usize, Trace) {
    let time = &recording.time_s;
    let inside = reference.interior(time, TIME_OFFSET_MARGIN_S);
    let index = |seconds: f64| time.partition_point(|&t| t - time[0] < seconds);
    let begin = index(args.window_s).max(inside.start);
    let record = (time.as_slice(), recording.dvl_m_s.as_slice());
    let errors: Vec<Option<Vec3>> = (begin..inside.end.max(begin))
        .map(|i| corrected_error(applied, record, reference, i))
        .collect();
    let scored: Vec<Vec3> = errors.iter().flatten().copied().collect();
    let mut flags = outliers_among(&scored).into_iter();
    let kept: Vec<Option<Vec3>> = (errors.iter())
        .map(|e| e.filter(|_| !flags.next().expect("a flag per error")))
        .collect();
    let outliers = scored.len() - kept.iter().flatten().count();
    let outlier_at: Vec<usize> = (begin..inside.end.max(begin))
        .filter(|&i| errors[i - begin].is_some() && kept[i - begin].is_none())
        .collect();
    let trace = Trace::of(
        (recording, reference),
        (begin..inside.end.max(begin), &outlier_at),
        applied,
    );
    let rmse =
        |range: std::ops::Range<usize>| AxisRmse::of_errors(range.filter_map(|i| kept[i - begin]));
    let after = rmse(begin..inside.end.max(begin));
    let mut blocks = Vec::new();
    let mut from = begin;
    while from < inside.end {
        let mut to = index(time[from] - time[0] + args.window_s)
            .min(inside.end)
            .max(from + 1);
        if to < inside.end && time[inside.end - 1] - time[to] < args.window_s / 2.0 {
            to = inside.end;
        }
        if let Some(r) = rmse(from..to) {
            blocks.push(Stretch {
                from_s: time[from] - time[0],
                to_s: time[to - 1] - time[0],
                rmse: r,
            });
        }
        from = to;
    }
    (after, blocks, outliers, trace)
}

/// The matrix with `values` on its diagonal.
fn diagonal(values: crate::Vec3) -> [[f64; 3]; 3] {
    let mut matrix = [[0.0; 3]; 3];
    for k in 0..3 {
        matrix[k][k] = values[k];
    }
    matrix
}

/// Writes the corrected `samples` of a dive read from a bag of `frames` as a bag at
/// `path`, its covariance the calibration's residual noise in `saved`, and says how many
/// samples it holds.
fn write_corrected_bag(
    path: PathBuf,
    samples: &[CorrectedSample],
    frames: &BagFrames,
    saved: &SavedInstallation,
) -> Result<PathBuf, CorrectError> {
    let topic = format!("{}/corrected", frames.dvl_topic.trim_end_matches('/'));
    let covariance = diagonal(saved.residual_cm_s.map(|r| (r / 100.0).powi(2)));
    let messages = write_bag(&path, &topic, samples, frames, covariance)?;
    eprintln!(
        "{} of the dive's {} samples written to {} on {topic} (those with no velocity are in the CSV with their reasons)",
        messages,
        samples.len(),
        path.display()
    );
    Ok(path)
}

/// Refuses a dive whose `/tf_static` mounts the DVL otherwise than the bag the
/// installation was found on (other frames, or a turn beyond [`MOUNT_TOLERANCE_DEG`]).
fn on_the_same_mount(
    args: &CorrectArgs,
    frames: &BagFrames,
    mount: &SavedMount,
) -> Result<(), CorrectError> {
    use crate::data::paired::bag::euler_zyx;
    use crate::rotation::{body_to_ned, multiply, transpose};
    let dive = euler_zyx(&frames.mount.rotation);
    let between = multiply(
        &transpose(&body_to_ned(mount.rpy_rad)),
        &frames.mount.rotation,
    );
    let trace = between[0][0] + between[1][1] + between[2][2];
    let turned_deg = ((trace - 1.0) / 2.0).clamp(-1.0, 1.0).acos().to_degrees();
    let why = if frames.body != mount.body || frames.dvl_frame != mount.dvl_frame {
        "other frames"
    } else if turned_deg > MOUNT_TOLERANCE_DEG {
        "another turn: calibrate on this mount, or correct a dive recorded with the mount the installation was found on"
    } else {
        return Ok(());
    };
    let degrees = |rpy: crate::Vec3| {
        let [r, p, y] = rpy.map(f64::to_degrees);
        format!("{r:.2}, {p:.2}, {y:.2}")
    };
    Err(CorrectError::Mount {
        dvl: args.dvl.to_path_buf(),
        installation: args.installation.to_path_buf(),
        body: frames.body.clone(),
        dvl_frame: frames.dvl_frame.clone(),
        dive: degrees(dive),
        saved: degrees(mount.rpy_rad),
        why,
    })
}
