//! An installation study as a run: reads the paired recordings (hashing each file),
//! skips the study when its results folder is current and intact, else runs it
//! (with the DCNet models a paper spec trained, when the spec asks for them), writes
//! the results folder (the resolved spec, the Parquet tables, both reports, the
//! manifest last, each file atomically) and draws its figures.
//! In: an [`InstallationSpec`] and the output folder. Out: the folder, or why not.

use super::{Plan, owner};
use crate::Vec3;
use crate::data::paired;
use crate::estimators::DcnetEstimator;
use crate::estimators::Estimator;
use crate::files::{sha256_hex, write_atomic};
use crate::installation::rows::{NO_CALIBRATION, Study, TracePoint};
use crate::installation::spec::InstallationSpec;
use crate::installation::study::{self, Estimated, Segment};
use crate::model::Settings;
use crate::results::{self, DataFile, Manifest, StageSeconds};
use crate::vocab::{Correction, ErrorModel};
use std::path::{Path, PathBuf};
use std::time::{Instant, SystemTime};

#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The reader's error says the file, line and column; the spec's key follows.
    #[error("{error} (the spec's recordings.trajectories[{index}], {name})")]
    Recording {
        index: usize,
        name: String,
        error: paired::PairedError,
    },
    #[error(transparent)]
    Owner(#[from] owner::OwnerError),
    #[error(
        "{method} could not be fitted on any calibration trajectory with a window of {window_s} s ({why}); nothing is written: give calibration.window_s values that leave samples for its terms, or fewer terms"
    )]
    NoFit {
        method: String,
        window_s: f64,
        why: String,
    },
    #[error("the DCNet models of {}", spec.display())]
    DcnetSpec {
        spec: PathBuf,
        #[source]
        source: anyhow::Error,
    },
    #[error(
        "the DCNet {error_model} model of {} is not trained: run `dcnet-exp run {} --out {}` first, or leave \"dcnet\" out of calibration.methods",
        spec.display(), spec.display(), out.display()
    )]
    DcnetMissing {
        spec: PathBuf,
        out: PathBuf,
        error_model: ErrorModel,
    },
    #[error("writing {}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Results(#[from] results::ResultsError),
}

/// What a study run did.
pub enum Outcome {
    /// The folder was current and intact.
    Current(PathBuf),
    Written {
        folder: PathBuf,
        study: Study,
    },
}

/// Runs the study of `spec`, read from `spec_file` (as a manifest records it, see
/// [`owner::recorded`]), into `out/<name>/` unless that folder is current (or `force`);
/// a folder another spec file wrote is refused unless `force`.
pub fn run_study(
    spec: &InstallationSpec,
    spec_file: &str,
    out: &Path,
    force: bool,
) -> Result<Outcome, StudyError> {
    let started_at = SystemTime::now();
    let clock = Instant::now();
    let folder = out.join(&spec.name);
    let spec_sha256 = sha256_hex(spec.resolved_toml.as_bytes());
    owner::check_study(&folder, out, spec_file, &spec.name, &spec_sha256, force)?;
    let mut segments = Vec::new();
    let mut data_files = Vec::new();
    for (index, (name, files)) in spec.trajectories.iter().enumerate() {
        let recording =
            paired::read(files, &spec.columns).map_err(|error| StudyError::Recording {
                index,
                name: name.clone(),
                error,
            })?;
        // One file may hold both the DVL and the reference.
        for path in crate::first_seen([&files.dvl, &files.reference]) {
            let bytes = std::fs::read(path).map_err(|source| StudyError::Io {
                path: path.clone(),
                source,
            })?;
            data_files.push(DataFile {
                path: path.clone(),
                sha256: sha256_hex(&bytes),
            });
        }
        segments.push(Segment::new(name.clone(), recording));
    }
    let dcnets = match &spec.dcnet_spec {
        Some(paper) => dcnet_models(paper, out)?,
        None => Vec::new(),
    };
    let results_key = sha256_hex(
        serde_json::to_string(&(
            &spec.resolved_toml,
            data_files.iter().map(|f| &f.sha256).collect::<Vec<_>>(),
            dcnets.iter().map(|(_, key)| key).collect::<Vec<_>>(),
            env!("DCNET_GIT_COMMIT"),
        ))
        .expect("strings serialize")
        .as_bytes(),
    );
    if !force && is_current(&folder, &results_key) {
        return Ok(Outcome::Current(folder));
    }
    let load_s = clock.elapsed().as_secs_f64();
    let estimators: Vec<DcnetEstimator> = dcnets.into_iter().map(|(e, _)| e).collect();
    let dcnet = |model: ErrorModel, dvl: &[Vec3], reference: &[Vec3]| -> Option<Correction> {
        let estimator = estimators.iter().find(|e| e.error_model == model)?;
        // A window shorter than the network's gives DCNet nothing to estimate from.
        (dvl.len() >= estimator.window).then(|| estimator.estimate(dvl, reference))
    };
    let (mut study, estimates) = study::run(spec, &segments, &dcnet);
    no_window_without_a_fit(spec, &study)?;
    study.trace = trace(&study, &estimates, &segments);
    let protocol_s = clock.elapsed().as_secs_f64() - load_s;
    write_folder(
        spec,
        &folder,
        &study,
        Manifest {
            name: spec.name.clone(),
            spec_sha256,
            git_commit: env!("DCNET_GIT_COMMIT").to_string(),
            crate_version: env!("CARGO_PKG_VERSION").to_string(),
            started_at: humantime::format_rfc3339_seconds(started_at).to_string(),
            finished_at: String::new(),
            threads: rayon::current_num_threads(),
            backend: String::new(),
            host: gethostname::gethostname().to_string_lossy().into_owned(),
            data_files,
            stage_seconds: StageSeconds {
                load: load_s,
                protocol: protocol_s,
                ..StageSeconds::default()
            },
            results_key,
            files_sha256: Default::default(),
            spec_file: spec_file.to_string(),
        },
    )?;
    Ok(Outcome::Written { folder, study })
}

/// Refuses a study in which a method fitted on no calibration trajectory at some
/// window: it would have no row at all there.
fn no_window_without_a_fit(spec: &InstallationSpec, study: &Study) -> Result<(), StudyError> {
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
                return Err(StudyError::NoFit {
                    method: label,
                    window_s,
                    why: failure.why.clone(),
                });
            }
        }
    }
    Ok(())
}

/// Whether `folder` holds the results of `results_key`, every file intact.
fn is_current(folder: &Path, results_key: &str) -> bool {
    let Ok(bytes) = std::fs::read(folder.join(results::MANIFEST)) else {
        return false;
    };
    let Ok(manifest) = serde_json::from_slice::<Manifest>(&bytes) else {
        return false;
    };
    manifest.results_key == results_key && results::is_intact(folder, &manifest)
}

/// The paper spec's DCNet models (replicate 0 of each error model), set up to estimate,
/// each with its cache key.
fn dcnet_models(paper: &Path, out: &Path) -> Result<Vec<(DcnetEstimator, String)>, StudyError> {
    let dcnet_error = |source: anyhow::Error| StudyError::DcnetSpec {
        spec: paper.to_path_buf(),
        source,
    };
    let experiment = crate::spec::load_experiment(paper, &[]).map_err(|e| dcnet_error(e.into()))?;
    let plan = Plan::new(&experiment, out).map_err(|e| dcnet_error(e.into()))?;
    let spec = plan.spec(0);
    let mut models = Vec::new();
    for training in plan.trainings.iter().filter(|t| t.replicate == 0) {
        let trained = plan
            .models
            .load(spec, training.error_model, &training.key)
            .map_err(|e| dcnet_error(e.into()))?
            .ok_or_else(|| StudyError::DcnetMissing {
                spec: paper.to_path_buf(),
                out: out.to_path_buf(),
                error_model: training.error_model,
            })?;
        let estimator = DcnetEstimator {
            model: trained.model,
            error_model: training.error_model,
            window: spec.dataset.window_samples,
            settings: Settings::from(&spec.model),
            device: spec.training.backend.device(),
        };
        models.push((estimator, training.key.clone()));
    }
    Ok(models)
}

/// The residual figure's samples: the trajectory (other than the first, which
/// calibrates) with the largest uncalibrated RMSE, corrected by the terms the method
/// with the lowest mean held-out RMSE at the largest window estimated on the first
/// trajectory over that window.
fn trace(study: &Study, estimates: &[Estimated], segments: &[Segment]) -> Vec<TracePoint> {
    let Some(largest) = study.summary.iter().map(|s| s.window_s).reduce(f64::max) else {
        return Vec::new();
    };
    let best = study
        .summary
        .iter()
        .filter(|s| s.window_s == largest)
        .min_by(|a, b| a.mean_cm_s.total_cmp(&b.mean_cm_s));
    let calibration = &segments[0];
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
    let Some(segment) = segments.iter().find(|s| s.name == scored.scored) else {
        return Vec::new();
    };
    let Some(installation) = estimates
        .iter()
        .find(|e| {
            e.method == best.method && e.calibration == calibration.name && e.window_s == largest
        })
        .map(|e| e.installation)
    else {
        return Vec::new();
    };
    let recording = &segment.recording;
    (0..recording.time_s.len())
        .filter_map(|i| {
            let t = recording.time_s[i];
            let before = segment.reference.at(t)?;
            let after_t = t + installation.time_offset_s;
            let after = segment.reference.at(after_t)?;
            let corrected = installation.correct(recording.dvl_m_s[i], after.rate_rad_s);
            let residual =
                |v: Vec3, r: Vec3| -> Vec3 { std::array::from_fn(|a| 100.0 * (v[a] - r[a])) };
            Some(TracePoint {
                trajectory: segment.name.clone(),
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

/// The study's two reports, named as its folder holds them: a pure function of its
/// tables, so `plot` writes them again to the same bytes.
pub fn reports(study: &Study, name: &str) -> [(String, Vec<u8>); 2] {
    [
        (
            "report.md".into(),
            crate::report::installation::markdown(study).into_bytes(),
        ),
        (
            "report.tex".into(),
            crate::report::installation::latex(study, name).into_bytes(),
        ),
    ]
}

/// Writes the folder: the resolved spec, the tables, both reports, then the manifest
/// with every file's SHA-256.
fn write_folder(
    spec: &InstallationSpec,
    folder: &Path,
    study: &Study,
    manifest: Manifest,
) -> Result<(), StudyError> {
    crate::files::create_folder(folder).map_err(|source| StudyError::Io {
        path: folder.to_path_buf(),
        source,
    })?;
    let mut files: Vec<(String, Vec<u8>)> = vec![(
        results::SPEC.to_string(),
        spec.resolved_toml.clone().into_bytes(),
    )];
    for (name, bytes) in results::installation::table_bytes(study)? {
        files.push((name.to_string(), bytes));
    }
    files.extend(reports(study, &spec.name));
    let mut digests = std::collections::BTreeMap::new();
    for (name, bytes) in &files {
        let path = folder.join(name);
        write_atomic(&path, bytes).map_err(|source| StudyError::Io { path, source })?;
        digests.insert(name.clone(), sha256_hex(bytes));
    }
    let manifest = Manifest {
        finished_at: humantime::format_rfc3339_seconds(SystemTime::now()).to_string(),
        files_sha256: digests,
        ..manifest
    };
    let path = folder.join(results::MANIFEST);
    let json = serde_json::to_string_pretty(&manifest).expect("a manifest always serializes");
    write_atomic(&path, json.as_bytes()).map_err(|source| StudyError::Io { path, source })
}
