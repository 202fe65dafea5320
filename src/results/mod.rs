//! What a run leaves in `results/<name>/`: the resolved spec, `manifest.json` with the
//! provenance, the Parquet tables (`monte_carlo`, `calibration`, `evaluation`,
//! `training`, and `trajectories` with the GT velocity the figures draw) and a copy of
//! the published values the report compares with. Every file is written to a
//! temporary file beside it and renamed into place, so a reader never sees half a file
//! (a writer killed mid-write leaves a hidden `.partial-<pid>-*` file, which the next
//! run removes); the manifest is written last. In: the protocol's tables and the models'
//! training histories. Out: the folder; [`read`] reads it back, and [`sweep`] writes
//! and reads the table that sets a sweep's points side by side.

pub mod calibration_time;
pub mod held;
pub mod record;
pub mod study;
pub mod read;
pub mod corrected;
pub mod sweep;
pub mod tables;
pub mod study_sweep;

use crate::data::Trajectory;
use crate::evaluate::ProtocolResult;
use crate::files::{sha256_hex, write_atomic};
use crate::spec::Spec;
use crate::train::TrainingHistory;
use arrow_array::RecordBatch;
use parquet::arrow::ArrowWriter;
use parquet::basic::Compression;
use parquet::file::properties::WriterProperties;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::SystemTime;
pub use tables::{
    REPLICATE, RMSE_CI, calibration_batch, evaluation_batch, monte_carlo_batch, training_batch,
    trajectories_batch,
};

#[derive(Debug, thiserror::Error)]
pub enum ResultsError {
    #[error("writing {}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("encoding {}", path.display())]
    Parquet {
        path: PathBuf,
        source: parquet::errors::ParquetError,
    },
}

/// Provenance of a run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Manifest {
    pub name: String,
    pub spec_sha256: String,
    pub git_commit: String,
    pub crate_version: String,
    pub started_at: String,
    pub finished_at: String,
    pub threads: usize,
    /// burn backend DCNet trained and ran on.
    pub backend: String,
    pub host: String,
    /// The widest vector instructions this machine's matrix products use
    /// ([`crate::kernels::instruction_set`]): models trained on machines with different
    /// ones round their products differently and differ in their last bits.
    #[serde(default)]
    pub instruction_set: String,
    pub data_files: Vec<DataFile>,
    /// Wall time this process spent in each stage, on every point of the spec; a model
    /// or block taken from the cache adds nothing.
    pub stage_seconds: StageSeconds,
    /// The hash of the resolved spec and of the cache keys of every block the tables
    /// were put together from: the folder is current while it matches.
    #[serde(default)]
    pub results_key: String,
    /// The SHA-256 of every file written before the manifest, by name: the folder is
    /// intact while its files have them.
    #[serde(default)]
    pub files_sha256: BTreeMap<String, String>,
    /// The spec file the run was read from, by its path from the output folder: the
    /// folder belongs to it, and a run of another file with the same `name` is refused
    /// unless `--force`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub spec_file: String,
}

/// What a manifest records of one run: the rest is this process's and this machine's.
pub struct RunRecord<'a> {
    pub name: String,
    /// The resolved spec, whose SHA-256 the manifest holds.
    pub resolved_toml: &'a str,
    pub started_at: SystemTime,
    pub backend: String,
    pub data_files: Vec<DataFile>,
    pub stage_seconds: StageSeconds,
    pub results_key: String,
    pub spec_file: String,
}

impl Manifest {
    /// The manifest of `run`, with this build's commit and version, the threads, the
    /// host and its instruction set; no files yet, and not finished (see
    /// [`Manifest::finished_now`]).
    pub fn of_run(run: RunRecord) -> Manifest {
        let RunRecord {
            name,
            resolved_toml,
            started_at,
            backend,
            data_files,
            stage_seconds,
            results_key,
            spec_file,
        } = run;
        Manifest {
            name,
            spec_sha256: sha256_hex(resolved_toml.as_bytes()),
            git_commit: env!("DCNET_GIT_COMMIT").to_string(),
            crate_version: env!("CARGO_PKG_VERSION").to_string(),
            started_at: humantime::format_rfc3339_seconds(started_at).to_string(),
            finished_at: String::new(),
            threads: rayon::current_num_threads(),
            backend,
            host: gethostname::gethostname().to_string_lossy().into_owned(),
            instruction_set: crate::kernels::instruction_set().to_string(),
            data_files,
            stage_seconds,
            results_key,
            files_sha256: Default::default(),
            spec_file,
        }
    }

    /// The same manifest, finished now.
    pub fn finished_now(self) -> Manifest {
        Manifest {
            finished_at: humantime::format_rfc3339_seconds(SystemTime::now()).to_string(),
            ..self
        }
    }
}

/// Wall time of each stage of a run.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct StageSeconds {
    pub load: f64,
    pub dataset: f64,
    pub training: f64,
    pub protocol: f64,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DataFile {
    pub path: PathBuf,
    pub sha256: String,
}

/// The Parquet tables of a results folder, in the order they are written.
pub const TABLES: [&str; 8] = [
    "monte_carlo.parquet",
    "calibration.parquet",
    "evaluation.parquet",
    calibration_time::HELD_OUT,
    calibration_time::CALIBRATION_TIME,
    calibration_time::TERMS_IN_TIME,
    "training.parquet",
    "trajectories.parquet",
];
pub const SPEC: &str = "spec.toml";
pub const MANIFEST: &str = "manifest.json";
/// The published values the report compares with, copied from `report.published`.
pub const PUBLISHED: &str = "published.toml";

/// Writes the tables, the published values, the resolved spec, then the manifest
/// into `folder`.
pub fn write_run(
    folder: &Path,
    spec: &Spec,
    trajectories: &[Trajectory],
    result: &ProtocolResult,
    dcnets: &[TrainingHistory],
    manifest: &Manifest,
) -> Result<(), ResultsError> {
    let batches = [
        monte_carlo_batch(&result.runs),
        calibration_batch(&result.calibration),
        evaluation_batch(&result.evaluation),
        calibration_time::held_out_batch(&result.held_out),
        calibration_time::calibration_time_batch(&result.calibration_time),
        calibration_time::terms_in_time_batch(&result.terms_in_time),
        training_batch(dcnets),
        trajectories_batch(
            &trajectories
                .iter()
                .enumerate()
                .map(|(i, t)| (t, spec.roles(i).join(",")))
                .collect::<Vec<_>>(),
            spec.sample_rate_hz,
        ),
    ];
    let mut files = Vec::new();
    for (file, batch) in TABLES.iter().zip(batches) {
        files.push((file.to_string(), table_bytes(&folder.join(file), &batch)?));
    }
    let published_path = folder.join(PUBLISHED);
    match &spec.resolved.report.published {
        Some(source) => files.push((
            PUBLISHED.to_string(),
            std::fs::read(source).map_err(io(source))?,
        )),
        None => match std::fs::remove_file(&published_path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(io(&published_path)(e));
            }
            _ => {}
        },
    }
    files.push((SPEC.to_string(), spec.resolved_toml().into_bytes()));
    write_folder(folder, &files, manifest.clone())
}

/// Writes a results folder of any kind: creates `folder`, writes each of `files`
/// (name, bytes) atomically in turn, then `manifest`, last, with the SHA-256 of each.
pub fn write_folder(
    folder: &Path,
    files: &[(String, Vec<u8>)],
    manifest: Manifest,
) -> Result<(), ResultsError> {
    crate::files::create_folder(folder).map_err(io(folder))?;
    let mut files_sha256 = BTreeMap::new();
    for (name, bytes) in files {
        let path = folder.join(name);
        write_atomic(&path, bytes).map_err(io(&path))?;
        files_sha256.insert(name.clone(), sha256_hex(bytes));
    }
    let manifest = Manifest {
        files_sha256,
        ..manifest
    };
    let path = folder.join(MANIFEST);
    let json = serde_json::to_string_pretty(&manifest).expect("a manifest always serializes");
    write_atomic(&path, json.as_bytes()).map_err(io(&path))
}

/// Whether every file `manifest` names in `folder` still has the SHA-256 it was written
/// with.
pub fn is_intact(folder: &Path, manifest: &Manifest) -> bool {
    !manifest.files_sha256.is_empty()
        && files_intact(
            folder,
            manifest
                .files_sha256
                .iter()
                .map(|(name, digest)| (name.as_str(), digest.as_str())),
        )
}

/// Whether each `(path from folder, SHA-256 in hex)` of `digests` names a file of
/// `folder` that still has that SHA-256; the check of the manifest's files and of the
/// report's seal.
pub fn files_intact<'a>(
    folder: &Path,
    digests: impl IntoIterator<Item = (&'a str, &'a str)>,
) -> bool {
    digests.into_iter().all(|(path, digest)| {
        std::fs::read(folder.join(path)).is_ok_and(|bytes| sha256_hex(&bytes) == digest)
    })
}

/// Writes `batch` to `path` as Parquet, atomically.
pub fn write_table(path: &Path, batch: &RecordBatch) -> Result<(), ResultsError> {
    write_atomic(path, &table_bytes(path, batch)?).map_err(io(path))
}

/// `batch` as the bytes of the Parquet file at `path`.
pub fn table_bytes(path: &Path, batch: &RecordBatch) -> Result<Vec<u8>, ResultsError> {
    parquet_bytes(batch).map_err(|source| ResultsError::Parquet {
        path: path.to_path_buf(),
        source,
    })
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ResultsError + '_ {
    move |source| ResultsError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn parquet_bytes(batch: &RecordBatch) -> Result<Vec<u8>, parquet::errors::ParquetError> {
    let properties = WriterProperties::builder()
        .set_compression(Compression::SNAPPY)
        .build();
    let mut bytes = Vec::new();
    let mut writer = ArrowWriter::try_new(&mut bytes, batch.schema(), Some(properties))?;
    writer.write(batch)?;
    writer.close()?;
    Ok(bytes)
}
