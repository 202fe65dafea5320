//! `correct --fixes`: an installation that `calibrate --save` wrote carried to a dive of
//! a vehicle with no velocity reference, only an attitude and position fixes. The
//! vehicle's terms are carried; the dive's clock is found again from its fixes (the
//! time offset alone fitted around the carried installation through the dead
//! reckoning, [`crate::installation::estimate::fixes::fit_fixes_around`]), from all of
//! them or those of its first `--window-s` seconds, or taken as given. The dive is
//! written corrected (CSV and Parquet, as `correct` writes), and how well the
//! installation carries is measured against the fixes: their horizontal residual, each
//! piece of the DVL record started where the fixes put it, with no terms and with the
//! installation applied, in metres and in % of the distance travelled.
//! In: [`FixCorrectArgs`]. Out: a [`FixCorrection`], or a [`CorrectError`] naming the
//! file and what to do; nothing is written unless everything before the writing
//! succeeded.

use crate::data::fixes::Fixes;
use crate::data::paired::{PairedRecording, ReadCounts};
use crate::installation::estimate::fixes::FixResidual as FixResidualOf;
use crate::installation::estimate::fixes::{FixFit, FixFitError, FixNoise, fit_fixes_around};
use crate::installation::frames::{Attitude, Reference};
use crate::installation::terms::Installation;
use crate::installation::terms::names::term_set;
use crate::operator::calibrate::CalibrateError;
use crate::operator::calibrate_fixes::{FixFiles, FixReading};
use crate::operator::correct::CorrectError;
use crate::operator::cost::CORRECT_FIXES;
use crate::operator::fix_drifts::{FixDrifts, drifts};
use crate::operator::inputs::not_over_an_input;
use crate::operator::installation_file::SavedInstallation;
use crate::results::corrected::{NotCorrected, Outputs, corrected_samples, stem, write};
use std::path::{Path, PathBuf};

/// What `correct --fixes` is asked.
pub struct FixCorrectArgs<'a> {
    pub files: FixFiles<'a>,
    pub installation: &'a Path,
    /// The fixes' noise per horizontal axis, m, where given (each fix's own, from its
    /// covariance, otherwise).
    pub fix_noise_m: Option<f64>,
    /// The first seconds of the dive whose fixes find its clock again; all of them
    /// where `None`.
    pub window_s: Option<f64>,
    /// The dive's time offset, s, where it is known: no fit.
    pub time_offset_s: Option<f64>,
    pub out: &'a Path,
}

/// The dive's clock found again from its fixes: the fit of its offset from the carried
/// clock (one parameter), and how many fixes it read.
pub struct FixClock {
    pub fit: FixFit,
    pub carried_s: f64,
    pub fixes_used: usize,
}

impl FixClock {
    /// The time offset found, s: the carried one moved by the fit, or the carried one
    /// where the fixes cannot show a clock at all.
    pub fn time_offset_s(&self) -> f64 {
        self.fit.installation.time_offset_s
    }
}

/// The fixes' horizontal residual RMS under an installation, each piece started where
/// the fixes put it, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixResidual {
    pub rms_m: f64,
    /// How far the dead reckoning travelled over the fixes fitted, m.
    pub distance_m: f64,
}

impl FixResidual {
    /// The RMS in % of the distance travelled.
    pub fn pct(&self) -> f64 {
        100.0 * self.rms_m / self.distance_m
    }
}

/// Everything `correct --fixes` found and wrote.
pub struct FixCorrection {
    pub saved: SavedInstallation,
    pub installation_file: PathBuf,
    /// The clock found again, where it was not given.
    pub clock: Option<FixClock>,
    /// The installation applied: the carried terms with the dive's clock.
    pub applied: Installation,
    /// The fixes' residual with no terms and with `applied`.
    pub before: FixResidual,
    pub after: FixResidual,
    /// The fixes' noise per horizontal axis, m: as given, or the median of their own
    /// where `own_noise` (each fix weighed by its covariance).
    pub fix_noise_m: f64,
    pub own_noise: bool,
    /// The horizontal residual RMS white fixes of that noise alone leave, m.
    pub white_fixes_leave_m: f64,
    /// The DVL's samples read, kept and left out, and the fixes read, those left out
    /// with their reasons.
    pub read: ReadCounts,
    pub fixes: usize,
    pub fixes_left_out: Vec<(&'static str, usize)>,
    /// The fixes' latency, s, each read this long before its stamp, and whether it was
    /// given or carried with the installation; `None` where neither.
    pub fix_latency: Option<(f64, LatencyFrom)>,
    /// From a bag: the topics and frames read, in words.
    pub read_from: Option<String>,
    /// The dive's samples whose t + τ lies outside the attitude, or in a gap of it:
    /// written without a velocity.
    pub outside: usize,
    pub written: Vec<PathBuf>,
    /// The DVL's first sample's stamp, s: the figures count from it.
    pub record_start_s: f64,
    /// The dead reckoning scored against the fixes, with no terms and with `applied`.
    pub drifts: FixDrifts,
    /// Each fix's residual with no terms and with `applied`, each fit's own (each piece
    /// placed at the start it fitted; the `after_m` of each), of the fixes
    /// `fitted_fixes` (the latency taken off their stamps).
    pub before_residuals: Vec<FixResidualOf>,
    pub after_residuals: Vec<FixResidualOf>,
    pub fitted_fixes: Fixes,
}

/// Where the fixes' latency a correction reads them by comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LatencyFrom {
    /// `--fix-latency-s`.
    Given,
    /// The installation file, whose calibration estimated it (`--fix-latency`).
    Carried,
}

/// How far above the fixes' residual with no terms the installation's may lie before
/// the correction is refused, as a ratio: the RMS of a few hundred fixes varies by a few
/// per cent from noise alone, and an installation that fits a dive worse than none
/// does not carry to it.
pub const WORSE_RATIO: f64 = 1.1;

/// `correct --fixes`: the installation file applied to the dive of `args`, its clock
/// found again from its fixes.
pub fn correct_fixes(args: &FixCorrectArgs) -> Result<FixCorrection, CorrectError> {
    refused(args)?;
    let saved = SavedInstallation::read(args.installation)?;
    // The fixes' latency: as given, or as the calibration estimated it for fixes of
    // the same system.
    let carried = saved.fix_latency.as_ref().map(|latency| latency.value);
    let files = &FixFiles {
        fix_latency_s: args.files.fix_latency_s.or(carried),
        ..args.files
    };
    let outputs = Outputs::of(args.out, &stem(files.dvl));
    let mut inputs = files.inputs().to_vec();
    inputs.push(Some(args.installation));
    if let Some((output, input)) = not_over_an_input(&inputs, &outputs.all()) {
        return Err(CorrectError::OverInput { output, input });
    }
    files.cost(CORRECT_FIXES)?.state()?;
    let (reading, fix_m) = (files.read_with_noise(false, args.fix_noise_m)).map_err(Box::new)?;
    let FixReading {
        read,
        fixes,
        left_out,
        read_from,
        ..
    } = reading;
    let recording_sha256 = read.dvl_sha256().to_string();
    outputs.not_another_recordings(files.dvl, &recording_sha256)?;
    let recording = &read.recording;
    let attitude = Attitude::of(recording);
    let noise = FixNoise {
        fix_m,
        depth_m: fix_m,
        dvl_m_s: saved.dvl_noise_cm_s / 100.0,
    };
    let dive = FixDive {
        args,
        recording,
        attitude: &attitude,
        fixes: &fixes,
        noise,
    };
    let (applied, clock) = dive.applied(&saved)?;
    let [(before, before_fit), (after, after_fit)] = dive.residuals(applied)?;
    let drifts = drifts((recording, &fixes, &after_fit), None);
    let samples = corrected_samples(&applied, recording, &Reference::new(recording));
    let outside = (samples.iter())
        .filter(|s| matches!(s.velocity_m_s, Err(NotCorrected::OutsideReference)))
        .count();
    if samples.iter().all(|s| s.velocity_m_s.is_err()) {
        return Err(CorrectError::NoOverlap {
            dvl: files.dvl.to_path_buf(),
            time_offset_s: applied.time_offset_s,
        });
    }
    let written = write(&outputs, &samples, &recording_sha256)?;
    Ok(FixCorrection {
        saved,
        installation_file: args.installation.to_path_buf(),
        clock,
        applied,
        before,
        after,
        fix_noise_m: fix_m,
        own_noise: fixes.noise_m.is_some(),
        white_fixes_leave_m: std::f64::consts::SQRT_2 * fixes.rms_noise_m().unwrap_or(fix_m),
        read: recording.counts().beside_attitude(),
        fixes: fixes.len(),
        fixes_left_out: left_out,
        fix_latency: latency_read(files.fix_latency_s, args.files.fix_latency_s),
        read_from,
        outside,
        written,
        record_start_s: recording.time_s[0],
        drifts,
        before_residuals: before_fit.residuals,
        after_residuals: after_fit.residuals,
        fitted_fixes: fixes,
    })
}

/// The fixes' latency a correction reads them by (`read`), and whence: given where it
/// is the one `given`, carried with the installation otherwise.
fn latency_read(read: Option<f64>, given: Option<f64>) -> Option<(f64, LatencyFrom)> {
    let from = match given {
        Some(_) => LatencyFrom::Given,
        None => LatencyFrom::Carried,
    };
    read.map(|latency_s| (latency_s, from))
}

/// The first argument of `args` at fault, where one is.
fn refused(args: &FixCorrectArgs) -> Result<(), CorrectError> {
    // Beyond the Earth's size, no fix's noise.
    if let Some(fix) = args.fix_noise_m.filter(|f| !(*f > 0.0 && *f < 1e7)) {
        return Err(Box::new(CalibrateError::FixNoise {
            flag: "--fix-noise-m",
            value: fix,
        })
        .into());
    }
    if let Some(window_s) = args.window_s.filter(|w| !(w.is_finite() && *w > 0.0)) {
        return Err(CorrectError::Window(window_s));
    }
    if let (Some(window_s), Some(_)) = (args.window_s, args.time_offset_s) {
        return Err(CorrectError::WindowWithClock(window_s));
    }
    match args.time_offset_s {
        Some(tau) if !tau.is_finite() => Err(CorrectError::TimeOffset(tau)),
        _ => Ok(()),
    }
}

/// A dive read beside its attitude and fixes.
struct FixDive<'a> {
    args: &'a FixCorrectArgs<'a>,
    recording: &'a PairedRecording,
    attitude: &'a Attitude,
    fixes: &'a Fixes,
    noise: FixNoise,
}

impl FixDive<'_> {
    /// The dive's clock: its offset from the saved one fitted to the fixes of the
    /// window, the vehicle's terms carried.
    fn clock(&self, saved: &SavedInstallation) -> Result<FixClock, CorrectError> {
        let fixes = match self.args.window_s {
            Some(window_s) => {
                let end = self.recording.time_s[0] + window_s;
                self.fixes.select(|k| self.fixes.time_s[k] < end)
            }
            None => self.fixes.clone(),
        };
        let terms = term_set(&["time_offset".parse().expect("a term's name")]);
        let carried = saved.installation();
        let fit = match (self.fit(&fixes, (terms, carried)), self.args.window_s) {
            (Err(CorrectError::FixFit { fixes, fault }), Some(window_s)) => {
                return Err(match *fault {
                    FixFitError::NoOverlap { .. } => {
                        CorrectError::WindowHoldsNoFix { fixes, window_s }
                    }
                    _ => CorrectError::FixWindow {
                        fixes,
                        window_s,
                        fault,
                    },
                });
            }
            (fit, _) => fit?,
        };
        Ok(FixClock {
            fixes_used: fit.fitted,
            carried_s: carried.time_offset_s,
            fit,
        })
    }

    /// The installation applied to the dive: the saved one at the clock given, or at
    /// the clock found again from the fixes (and that clock).
    fn applied(
        &self,
        saved: &SavedInstallation,
    ) -> Result<(Installation, Option<FixClock>), CorrectError> {
        Ok(match self.args.time_offset_s {
            Some(time_offset_s) => {
                let given = Installation {
                    time_offset_s,
                    ..saved.installation()
                };
                (given, None)
            }
            None => {
                let clock = self.clock(saved)?;
                (clock.fit.installation, Some(clock))
            }
        })
    }

    /// The fixes' residual with no terms and with `applied`, and each one's fit; refused
    /// where `applied` leaves it more than [`WORSE_RATIO`] times the other, and where
    /// the fixes cannot be fitted about a clock given (the flag named).
    fn residuals(&self, applied: Installation) -> Result<[(FixResidual, FixFit); 2], CorrectError> {
        let (before, before_fit) = self.residual(Installation::default())?;
        let after = match (self.residual(applied), self.args.time_offset_s) {
            (Err(CorrectError::FixFit { fault, .. }), Some(time_offset_s)) => {
                return Err(CorrectError::GivenClock {
                    time_offset_s,
                    fault,
                });
            }
            (after, _) => after?,
        };
        let (after, after_fit) = after;
        if after.rms_m > WORSE_RATIO * before.rms_m {
            return Err(match self.args.time_offset_s {
                Some(time_offset_s) => CorrectError::GivenClockFitsWorse {
                    time_offset_s,
                    before_m: before.rms_m,
                    after_m: after.rms_m,
                },
                None => CorrectError::FixesFitWorse {
                    fixes: self.args.files.fixes_named(),
                    time_offset_s: applied.time_offset_s,
                    before_m: before.rms_m,
                    after_m: after.rms_m,
                },
            });
        }
        Ok([(before, before_fit), (after, after_fit)])
    }

    /// The fixes' horizontal residual under `installation`, no term fitted, and that fit.
    fn residual(&self, installation: Installation) -> Result<(FixResidual, FixFit), CorrectError> {
        let fit = self.fit(self.fixes, (term_set(&[]), installation))?;
        let residual = FixResidual {
            rms_m: fit.residual_rms_m[0].hypot(fit.residual_rms_m[1]),
            distance_m: fit.distance_m,
        };
        Ok((residual, fit))
    }

    /// `terms` fitted to `fixes` around the installation carried.
    fn fit(
        &self,
        fixes: &Fixes,
        carried: (crate::installation::terms::TermSet, Installation),
    ) -> Result<FixFit, CorrectError> {
        let dvl = (&self.recording.time_s[..], &self.recording.dvl_m_s[..]);
        let pieces = self.recording.pieces();
        let carried = (carried.0.into(), carried.1);
        fit_fixes_around(dvl, &pieces, self.attitude, fixes, carried, self.noise).map_err(
            |fault: FixFitError| CorrectError::FixFit {
                fixes: self.args.files.fixes_named(),
                fault: Box::new(fault),
            },
        )
    }
}
