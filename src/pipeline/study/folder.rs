//! A point's results folder: the study put together from its calibrations (the fits
//! that failed kept beside it, and the residual figure's samples), the resolved spec,
//! and the Parquet tables, handed to the one writer of results folders
//! (`results::write_folder`: each file atomically, the manifest last), whose reports
//! are then written and sealed as a paper run's are; and whether a folder already holds
//! the results of a key, intact and reported.
//! In: a point's spec, its calibrations and recordings. Out: the folder, or why not.

use crate::Vec3;
use crate::installation::study::rows::{NO_CALIBRATION, StudyResults, TracePoint};
use crate::installation::study::spec::StudySpec;
use crate::installation::study::{Estimated, Recording};
use crate::pipeline::study::ExecuteError;
use crate::results::{self, Manifest};
use std::path::Path;

/// Refuses a study in which a method fitted on no calibration trajectory at some
/// window: it would have no row at all there. `point` opens the message in a sweep.
pub fn no_window_without_a_fit(
    spec: &StudySpec,
    study: &StudyResults,
    point: &str,
) -> Result<(), ExecuteError> {
    for &window_s in &spec.windows_s {
        for method in &spec.methods {
            let label = method.label();
            let fitted = study
                .summary
                .iter()
                .any(|row| row.method == label && row.window_s == window_s);
            let failure = study
                .failures
                .iter()
                .find(|f| f.method == label && f.window_s == window_s);
            if let (false, Some(failure)) = (fitted, failure) {
                return Err(ExecuteError::NoFit {
                    point: point.to_string(),
                    method: label,
                    window_s,
                    why: failure.why.clone(),
                });
            }
        }
    }
    Ok(())
}

/// Whether `folder` holds the results of `results_key`, every file intact, and its
/// reports sealed (`report::is_complete`).
pub fn is_current(folder: &Path, results_key: &str) -> bool {
    let Ok(manifest) = results::read::manifest(folder) else {
        return false;
    };
    manifest.results_key == results_key
        && results::is_intact(folder, &manifest)
        && crate::report::is_complete(folder)
}

/// The residual figure's samples: the trajectory (other than the first, which
/// calibrates) with the largest uncalibrated RMSE, corrected by the terms estimated on
/// the first trajectory over the largest window by the method with the lowest mean
/// held-out RMSE there, among those that calibrate on one trajectory (a joint fit's
/// terms come from all but one, a re-found clock's rows from no fit of their own).
pub fn trace(
    study: &StudyResults,
    estimates: &[Estimated],
    recordings: &[&Recording],
) -> Vec<TracePoint> {
    let Some(largest) = study.summary.iter().map(|s| s.window_s).reduce(f64::max) else {
        return Vec::new();
    };
    let calibration = &recordings[0];
    let estimate_of = |method: &str| {
        estimates.iter().find(|e| {
            e.method == method && e.calibration == calibration.name && e.window_s == largest
        })
    };
    let best = study
        .summary
        .iter()
        .filter(|s| s.window_s == largest && estimate_of(&s.method).is_some())
        .min_by(|a, b| a.mean_cm_s.total_cmp(&b.mean_cm_s));
    let scored = study
        .heldout
        .iter()
        .filter(|r| {
            r.method == NO_CALIBRATION && r.calibration == calibration.name && r.window_s == largest
        })
        .max_by(|a, b| a.total_cm_s.total_cmp(&b.total_cm_s));
    let (Some(best), Some(scored)) = (best, scored) else {
        return Vec::new();
    };
    let Some(drawn) = recordings.iter().find(|s| s.name == scored.scored) else {
        return Vec::new();
    };
    let Some(installation) = estimate_of(&best.method).map(|e| e.installation) else {
        return Vec::new();
    };
    let recording = &drawn.recording;
    (0..recording.time_s.len())
        .filter_map(|i| {
            let t = recording.time_s[i];
            let before = drawn.reference.at(t)?;
            let after_t = t + installation.time_offset_s;
            let after = drawn.reference.at(after_t)?;
            let corrected = installation.correct(recording.dvl_m_s[i], after.rate_rad_s);
            let residual =
                |v: Vec3, r: Vec3| -> Vec3 { std::array::from_fn(|a| 100.0 * (v[a] - r[a])) };
            Some(TracePoint {
                trajectory: drawn.name.clone(),
                method: best.method.clone(),
                calibration: calibration.name.clone(),
                time_s: t,
                before_cm_s: residual(recording.dvl_m_s[i], before.velocity_body_m_s),
                after_cm_s: residual(corrected, after.velocity_body_m_s),
                yaw_rate_deg_s: before.rate_rad_s[2].to_degrees(),
            })
        })
        .collect()
}

/// Writes the folder through [`results::write_folder`]: the resolved spec, the
/// tables, then the manifest with every file's SHA-256.
pub fn write_folder(
    spec: &StudySpec,
    folder: &Path,
    study: &StudyResults,
    manifest: Manifest,
) -> Result<(), ExecuteError> {
    let mut files: Vec<(String, Vec<u8>)> = vec![(
        results::SPEC.to_string(),
        spec.resolved_toml.clone().into_bytes(),
    )];
    for (name, bytes) in results::study::table_bytes(study)? {
        files.push((name.to_string(), bytes));
    }
    // A study without `[learned]` leaves no fold table of an earlier one behind.
    let folds = folder.join(results::study::FOLDS);
    if study.folds.is_empty() && folds.exists() {
        std::fs::remove_file(&folds).map_err(|source| crate::results::ResultsError::Io {
            path: folds.clone(),
            source,
        })?;
    }
    Ok(results::write_folder(
        folder,
        &files,
        manifest.finished_now(),
    )?)
}
