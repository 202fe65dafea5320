//! `calibrate --fixes`: a DVL calibrated against position fixes and an attitude, for a
//! vehicle with no velocity reference, by one library call: the DVL beside the attitude
//! and the fixes are read ([`crate::data::fixes`]), the terms fitted to the fixes
//! through the dead reckoning ([`crate::installation::estimate::fixes`]), the fixes'
//! residual before and after, and the installation saved for `correct` as any other.
//! In: [`FixArgs`]. Out: a [`FixCalibration`], everything the command prints, or a
//! [`CalibrateError`] naming the argument, file or step at fault.

use crate::data::fixes::{Fixes, read_beside_attitude, read_fixes};
use crate::data::paired::{PairedRecording, ReadCounts};
use crate::installation::estimate::fixes::{DEFAULT_FIX_TERMS, FixFit, FixNoise, fit_fixes};
use crate::installation::frames::Attitude;
use crate::installation::terms::names::{TermName, term_set};
use crate::operator::calibrate::{CalibrateError, clear_of_inputs, named};
use crate::operator::inputs::{Reading, columns, fix_columns};
use crate::operator::installation_file::{SavedInstallation, SavedTerm};
use crate::results::ResultsError;
use std::path::Path;

/// What `calibrate --fixes` is asked.
pub struct FixArgs<'a> {
    pub dvl: &'a Path,
    pub attitude: &'a Path,
    pub fixes: &'a Path,
    pub columns: Option<&'a Path>,
    pub reading: Reading<'a>,
    pub terms: &'a [TermName],
    pub dive_terms: &'a [TermName],
    /// The fixes' noise per horizontal axis and in depth, m; the DVL's per axis, cm/s.
    pub fix_noise_m: f64,
    pub depth_noise_m: Option<f64>,
    pub dvl_noise_cm_s: f64,
    pub save: Option<&'a Path>,
}

/// What `calibrate --fixes` found.
pub struct FixCalibration {
    pub fit: FixFit,
    /// The DVL's samples read, kept and left out, and the fixes read.
    pub read: ReadCounts,
    pub fixes: usize,
    /// The RMS of the fixes' horizontal residual with no terms (the start positions
    /// alone fitted) and with the terms applied, m; and the distance the dead
    /// reckoning travelled over the fixes fitted, m.
    pub before_m: f64,
    pub after_m: f64,
    pub distance_m: f64,
    pub noise: FixNoise,
}

/// `calibrate --fixes`: the terms the fixes show, their bound, and the fixes' residual.
pub fn calibrate_fixes(args: &FixArgs) -> Result<FixCalibration, CalibrateError> {
    refused(args)?;
    let inputs = [
        Some(args.dvl),
        Some(args.attitude),
        Some(args.fixes),
        args.columns,
    ];
    clear_of_inputs(&inputs, &[], args.save)?;
    let columns = columns(args.columns, args.reading).map_err(CalibrateError::Columns)?;
    let fix_columns = fix_columns(args.columns).map_err(CalibrateError::Columns)?;
    let read = read_beside_attitude(args.dvl, args.attitude, &columns)?;
    let (fixes, _) = read_fixes(args.fixes, &fix_columns).map_err(CalibrateError::Fixes)?;
    let recording = &read.recording;
    let attitude = Attitude::new(&recording.reference_time_s, &recording.attitude_rad);
    let noise = FixNoise {
        fix_m: args.fix_noise_m,
        depth_m: args.depth_noise_m.unwrap_or(args.fix_noise_m),
        dvl_m_s: args.dvl_noise_cm_s / 100.0,
    };
    let fit = fit_on(recording, &attitude, &fixes, term_set(args.terms), noise)
        .map_err(|fault| fix_error(args, fault))?;
    // The fixes' residual with no terms: the start positions alone.
    let bare = fit_on(recording, &attitude, &fixes, term_set(&[]), noise)
        .map_err(|fault| fix_error(args, fault))?;
    if let Some(path) = args.save {
        save(path, args, &fit, read.dvl_sha256())?;
    }
    Ok(FixCalibration {
        read: recording.counts(),
        fixes: fixes.len(),
        before_m: horizontal(bare.residual_rms_m),
        after_m: horizontal(fit.residual_rms_m),
        distance_m: fit.distance_m,
        noise,
        fit,
    })
}

/// The fit of `terms` on `recording`'s pieces against `fixes`.
fn fit_on(
    recording: &PairedRecording,
    attitude: &Attitude,
    fixes: &Fixes,
    terms: crate::installation::terms::TermSet,
    noise: FixNoise,
) -> Result<FixFit, crate::installation::estimate::fixes::FixFitError> {
    let dvl = (&recording.time_s[..], &recording.dvl_m_s[..]);
    fit_fixes(dvl, &recording.pieces(), attitude, fixes, terms, noise)
}

/// The horizontal RMS of per-axis RMS values north and east, m.
fn horizontal(rms_m: crate::Vec3) -> f64 {
    (rms_m[0].powi(2) + rms_m[1].powi(2)).sqrt()
}

/// Refuses what the fixes cannot fit: a term other than scale, misalignment, lever arm
/// and time offset, a noise that is not a positive number.
fn refused(args: &FixArgs) -> Result<(), CalibrateError> {
    const ALLOWED: [&str; 4] = DEFAULT_FIX_TERMS;
    if let Some(term) = args.terms.iter().find(|t| !ALLOWED.contains(&t.name())) {
        return Err(CalibrateError::Terms(format!(
            "{}: fixes calibrate {} (a bias, or a scale per axis, needs a velocity reference)",
            term.name(),
            ALLOWED.join(", ")
        )));
    }
    let positive = |v: f64| v > 0.0 && v.is_finite();
    if !positive(args.fix_noise_m) {
        return Err(CalibrateError::FixNoise {
            flag: "--fix-noise-m",
            value: args.fix_noise_m,
        });
    }
    if let Some(depth) = args.depth_noise_m.filter(|&d| !positive(d)) {
        return Err(CalibrateError::FixNoise {
            flag: "--depth-noise-m",
            value: depth,
        });
    }
    if !positive(args.dvl_noise_cm_s) {
        return Err(CalibrateError::DvlNoise(args.dvl_noise_cm_s));
    }
    if let Some(term) = args.dive_terms.iter().find(|t| t.name() != "time_offset") {
        return Err(CalibrateError::DiveTerms(format!(
            "{}: of the terms fixes calibrate, only time_offset is the dive's",
            term.name()
        )));
    }
    Ok(())
}

/// The fit of `args` failed with `fault`.
fn fix_error(
    args: &FixArgs,
    fault: crate::installation::estimate::fixes::FixFitError,
) -> CalibrateError {
    CalibrateError::FixFit {
        fixes: args.fixes.to_path_buf(),
        terms: named(args.terms),
        fault,
    }
}

/// Writes the installation `fit` found to `path`: each term applied with its value and
/// standard deviation; a term not applied (or not estimated) as zero, with the standard
/// deviation the fixes gave it (infinite where they gave none).
fn save(
    path: &Path,
    args: &FixArgs,
    fit: &FixFit,
    recording_sha256: &str,
) -> Result<(), CalibrateError> {
    let saved = (fit.names.iter().enumerate())
        .map(|(k, name)| SavedTerm {
            name: name.to_string(),
            value: if fit.is_applied(name) {
                fit.value[k]
            } else {
                0.0
            },
            std: fit.std[k],
        })
        .collect();
    let recording = (args.dvl.display().to_string(), recording_sha256.to_string());
    // Fixes measure no velocity residual: what a dive this installation fits leaves is
    // the DVL's own noise, as given.
    let file = SavedInstallation::of_terms(
        (saved, fit.correlation.clone()),
        (args.terms, args.dive_terms),
        recording,
        (args.dvl_noise_cm_s, 0.0),
        [args.dvl_noise_cm_s / 100.0; 3],
    );
    file.write(path).map_err(|source| {
        CalibrateError::Write(ResultsError::Io {
            path: path.to_path_buf(),
            source,
        })
    })
}
