//! Reads a results folder back, for `plot` and the report: the Parquet tables into the
//! rows the run computed, the resolved spec, the manifest and the published values.
//! Each table's schema is checked against the one the writer produces, so a missing
//! file or a foreign schema is an error that names the file, never a wrong figure; a
//! column that is missing, of another type, with empty values or with a value no run
//! writes is a [`ColumnError`] that names the column.
//!
//! - this module: [`StoredRun`], the folder read whole, and [`ReadError`], which puts
//!   the path of the file in front of whatever went wrong with it;
//! - [`columns`]: the schema check, and `Batch`, a batch that passed it;
//! - [`rows`]: one decoder per table, from its records to the rows the run computed;
//!   [`read_records`] and [`records`] decode a checked batch into a table's records.

pub mod columns;
pub mod rows;

pub(crate) use columns::Batch;
pub use columns::ColumnError;
pub use rows::{StoredEpoch, StoredTrajectory};

use super::calibration_time::{
    CALIBRATION_TIME, HELD_OUT, TERMS_IN_TIME, calibration_time_batch, held_out_batch,
    terms_in_time_batch,
};
use super::record::{self, Record};
use super::{
    MANIFEST, Manifest, PUBLISHED, SPEC, TABLES, calibration_batch, evaluation_batch,
    monte_carlo_batch, training_batch, trajectories_batch,
};
use crate::evaluate::rows::{CalibrationTimeRow, HeldOutRow};
use crate::evaluate::terms_in_time::TermInTimeRow;
use crate::evaluate::{CalibrationRow, EvaluationRow, RunRow};
use crate::spec::published::Published;
use crate::spec::{SpecErrors, SpecFile, TomlFile};
use crate::vocab::ErrorModel;
use arrow_schema::Schema;
use columns::check_schema;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use rows::{
    calibration_rows, calibration_time_rows, epoch_rows, evaluation_rows, gather_trajectories,
    held_out_rows, run_rows, terms_in_time_rows, trajectory_rows,
};
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error("{}: missing; a results folder written by `dcnet-exp run` holds it", path.display())]
    Missing { path: PathBuf },
    /// A table with a column that is not as dcnet-exp writes it; [`ColumnError`] says how.
    #[error("{}: {fault}", path.display())]
    Column { path: PathBuf, fault: ColumnError },
    /// A JSON file beside the tables (`sweep.json`) that does not parse.
    #[error("{}", path.display())]
    Json {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
    #[error("{}", path.display())]
    Spec {
        path: PathBuf,
        #[source]
        source: SpecErrors,
    },
    #[error("{}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: not a Parquet file", path.display())]
    NotParquet {
        path: PathBuf,
        #[source]
        source: parquet::errors::ParquetError,
    },
    #[error("{}", path.display())]
    Parquet {
        path: PathBuf,
        #[source]
        source: parquet::errors::ParquetError,
    },
    #[error("{}", path.display())]
    Arrow {
        path: PathBuf,
        #[source]
        source: arrow_schema::ArrowError,
    },
    /// A file of another kind of results than the one asked for.
    #[error("{}: {why}", path.display())]
    OtherKind { path: PathBuf, why: String },
    #[error(transparent)]
    Altered(#[from] Box<Altered>),
    #[error("{}", path.display())]
    Manifest {
        path: PathBuf,
        #[source]
        source: ManifestError,
    },
}

/// A file of the folder whose bytes are not those the run wrote.
#[derive(Debug, thiserror::Error)]
#[error(
    "{}: its SHA-256 is {found}, not the {recorded} that {MANIFEST} records: it was changed after the run wrote it; run the spec again to write it anew",
    path.display()
)]
pub struct Altered {
    pub path: PathBuf,
    pub found: String,
    pub recorded: String,
}

/// Why a manifest could not be read.
#[derive(Debug, thiserror::Error)]
pub enum ManifestError {
    #[error(transparent)]
    Io(#[from] std::io::Error),
    #[error(transparent)]
    Json(#[from] serde_json::Error),
}

/// Everything a run stored.
#[derive(Debug, Clone)]
pub struct StoredRun {
    pub folder: PathBuf,
    pub spec: SpecFile,
    pub manifest: Manifest,
    pub published: Option<Published>,
    pub runs: Vec<RunRow>,
    pub calibration: Vec<CalibrationRow>,
    pub evaluation: Vec<EvaluationRow>,
    pub held_out: Vec<HeldOutRow>,
    pub calibration_time: Vec<CalibrationTimeRow>,
    pub terms_in_time: Vec<TermInTimeRow>,
    pub training: Vec<StoredEpoch>,
    pub trajectories: Vec<StoredTrajectory>,
}

impl StoredRun {
    /// Checks the Parquet tables against the SHA-256 the manifest records for each: the
    /// first that differs (a table edited by hand, say) is an error naming it. The
    /// published values may be edited (`plot` then compares with the new ones); a
    /// manifest from before digests records none and is not checked.
    pub fn check_tables(&self) -> Result<(), ReadError> {
        check_files(&self.folder, &self.manifest, &TABLES)
    }

    pub fn read(folder: &Path) -> Result<StoredRun, ReadError> {
        let spec_path = existing(&folder.join(SPEC))?;
        let spec = TomlFile::<SpecFile>::read(&spec_path)
            .map_err(|e| ReadError::Spec {
                path: spec_path.clone(),
                source: SpecErrors(vec![e]),
            })?
            .value;
        let manifest = manifest(folder)?;
        let published_path = folder.join(PUBLISHED);
        let published = if published_path.exists() {
            Some(
                Published::read(&published_path).map_err(|source| ReadError::Spec {
                    path: published_path.clone(),
                    source,
                })?,
            )
        } else {
            None
        };
        let [
            runs,
            calibration,
            evaluation,
            held_out,
            calibration_time,
            terms_in_time,
            training,
            trajectories,
        ] = TABLES;
        Ok(StoredRun {
            folder: folder.to_path_buf(),
            spec,
            manifest,
            published,
            runs: table(folder, runs, run_rows)?,
            calibration: table(folder, calibration, calibration_rows)?,
            evaluation: table(folder, evaluation, evaluation_rows)?,
            held_out: later_table(folder, held_out, held_out_rows)?,
            calibration_time: later_table(folder, calibration_time, calibration_time_rows)?,
            terms_in_time: later_table(folder, terms_in_time, terms_in_time_rows)?,
            training: table(folder, training, epoch_rows)?,
            trajectories: gather_trajectories(table(folder, trajectories, trajectory_rows)?),
        })
    }

    /// The stored DVL names, in the order the spec lists them.
    pub fn dvls(&self) -> Vec<String> {
        self.spec.dvl.iter().map(|d| d.name.clone()).collect()
    }

    /// The DCNets trained, (error model, replicate), in the order of `training.parquet`.
    pub fn trained_models(&self) -> Vec<(ErrorModel, Option<usize>)> {
        let mut models: Vec<_> = self
            .training
            .iter()
            .map(|e| (e.error_model, e.replicate))
            .collect();
        models.dedup();
        models
    }
}

/// The manifest of `folder`, named where it is missing or cannot be read.
pub fn manifest(folder: &Path) -> Result<Manifest, ReadError> {
    let manifest_path = existing(&folder.join(MANIFEST))?;
    std::fs::read(&manifest_path)
        .map_err(ManifestError::from)
        .and_then(|bytes| Ok(serde_json::from_slice(&bytes)?))
        .map_err(|source| ReadError::Manifest {
            path: manifest_path.clone(),
            source,
        })
}

/// Each of `names` that `manifest` records in `folder` with the bytes it recorded:
/// the first altered one named, with both digests.
pub fn check_files(folder: &Path, manifest: &Manifest, names: &[&str]) -> Result<(), ReadError> {
    let recorded = names
        .iter()
        .filter_map(|name| Some((name, manifest.files_sha256.get(*name)?)));
    for (name, recorded) in recorded {
        let path = folder.join(name);
        let bytes = std::fs::read(&path).map_err(|source| ReadError::Io {
            path: path.clone(),
            source,
        })?;
        let found = crate::files::sha256_hex(&bytes);
        if &found != recorded {
            return Err(Box::new(Altered {
                path,
                found,
                recorded: recorded.clone(),
            })
            .into());
        }
    }
    Ok(())
}

fn existing(path: &Path) -> Result<PathBuf, ReadError> {
    if path.is_file() {
        Ok(path.to_path_buf())
    } else {
        Err(ReadError::Missing {
            path: path.to_path_buf(),
        })
    }
}

/// The per-run rows of a Parquet file written by [`super::monte_carlo_batch`].
pub fn run_rows_at(path: &Path) -> Result<Vec<RunRow>, ReadError> {
    table_at(path, TABLES[0], run_rows)
}

/// Reads the table `file` of `folder`, checks its schema and turns each batch into rows.
fn table<T>(
    folder: &Path,
    file: &str,
    rows: fn(&Batch) -> Result<Vec<T>, ColumnError>,
) -> Result<Vec<T>, ReadError> {
    table_at(&folder.join(file), file, rows)
}

/// Like [`table`], for a table that folders written before it lack: none of its rows
/// there.
fn later_table<T>(
    folder: &Path,
    file: &str,
    rows: fn(&Batch) -> Result<Vec<T>, ColumnError>,
) -> Result<Vec<T>, ReadError> {
    if folder.join(file).exists() {
        table(folder, file, rows)
    } else {
        Ok(Vec::new())
    }
}

/// Reads `path` as the results table `file`.
fn table_at<T>(
    path: &Path,
    file: &str,
    rows: fn(&Batch) -> Result<Vec<T>, ColumnError>,
) -> Result<Vec<T>, ReadError> {
    read_rows(path, &expected_schema(file), rows)
}

/// Reads the Parquet file at `path`, checks that it has the columns of `expected`, and
/// turns each batch into rows.
pub(crate) fn read_rows<T>(
    path: &Path,
    expected: &Schema,
    rows: impl Fn(&Batch) -> Result<Vec<T>, ColumnError>,
) -> Result<Vec<T>, ReadError> {
    let path = existing(path)?;
    let invalid = |fault| ReadError::Column {
        path: path.clone(),
        fault,
    };
    let opened = std::fs::File::open(&path).map_err(|source| ReadError::Io {
        path: path.clone(),
        source,
    })?;
    let builder = ParquetRecordBatchReaderBuilder::try_new(opened).map_err(|source| {
        ReadError::NotParquet {
            path: path.clone(),
            source,
        }
    })?;
    check_schema(builder.schema(), expected).map_err(invalid)?;
    let mut out = Vec::new();
    let batches = builder.build().map_err(|source| ReadError::Parquet {
        path: path.clone(),
        source,
    })?;
    for batch in batches {
        let batch = batch.map_err(|source| ReadError::Arrow {
            path: path.clone(),
            source,
        })?;
        out.extend(rows(&Batch(&batch)).map_err(invalid)?);
    }
    Ok(out)
}

/// Reads the Parquet file at `path` as a table of records `R`, checked against `R`'s
/// columns (those it writes only sometimes may be missing), each turned into a row by
/// `row`.
pub(crate) fn read_records<R: Record, T>(
    path: &Path,
    row: impl Fn(R) -> Result<T, ColumnError>,
) -> Result<Vec<T>, ReadError> {
    read_rows(path, &record::expected::<R>(), |batch| records(batch, &row))
}

/// The records `R` of a checked `batch`, each turned into a row by `row`.
pub(crate) fn records<R: Record, T>(
    batch: &Batch,
    row: impl FnMut(R) -> Result<T, ColumnError>,
) -> Result<Vec<T>, ColumnError> {
    record::decode::<R>(batch.0)?.into_iter().map(row).collect()
}

/// The schema the writer gives `file`.
fn expected_schema(file: &str) -> std::sync::Arc<Schema> {
    let batch = match file {
        "monte_carlo.parquet" => monte_carlo_batch(&[]),
        "calibration.parquet" => calibration_batch(&[]),
        "evaluation.parquet" => evaluation_batch(&[]),
        HELD_OUT => held_out_batch(&[]),
        CALIBRATION_TIME => calibration_time_batch(&[]),
        TERMS_IN_TIME => terms_in_time_batch(&[]),
        "training.parquet" => training_batch(&[]),
        "trajectories.parquet" => trajectories_batch(&[], 1.0),
        other => unreachable!("{other} is not a results table"),
    };
    batch.schema()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::training_batch;
    use crate::vocab::StopReason;
    use arrow_array::{RecordBatch, StringArray};
    use arrow_schema::DataType;
    use rows::tests::summary;

    /// `batch` with its column `name` replaced by `values`, as text.
    fn with_text_column(batch: &RecordBatch, name: &str, values: &[&str]) -> RecordBatch {
        use arrow_schema::Field;
        use std::sync::Arc;
        let index = batch.schema().index_of(name).unwrap();
        let mut columns = batch.columns().to_vec();
        let mut fields: Vec<_> = batch.schema().fields().iter().cloned().collect();
        columns[index] = Arc::new(StringArray::from(values.to_vec()));
        fields[index] = Arc::new(Field::new(name, DataType::Utf8, false));
        RecordBatch::try_new(Arc::new(Schema::new(fields)), columns).unwrap()
    }

    #[test]
    fn a_foreign_column_is_named_after_its_file_once() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("training.parquet");
        let batch = training_batch(&[summary(StopReason::AllEpochs)]);
        let shown = |error: ReadError| format!("{:#}", anyhow::Error::from(error));

        super::super::write_table(&path, &with_text_column(&batch, "epoch", &["1", "2"])).unwrap();
        let error = table_at(&path, "training.parquet", epoch_rows).unwrap_err();
        assert!(
            matches!(&error, ReadError::Column {
                fault: ColumnError::Type { column, found: DataType::Utf8, expected: DataType::UInt32 },
                ..
            } if column == "epoch"),
            "{error:?}"
        );
        assert_eq!(
            shown(error),
            format!(
                "{}: column `epoch` holds Utf8, expected UInt32: this is not the schema dcnet-exp writes",
                path.display()
            )
        );

        let bogus = with_text_column(&batch, "stop_reason", &["bogus", "bogus"]);
        super::super::write_table(&path, &bogus).unwrap();
        let error = table_at(&path, "training.parquet", epoch_rows).unwrap_err();
        let ReadError::Column {
            fault: ColumnError::Value { column, problem },
            ..
        } = &error
        else {
            panic!("{error:?}")
        };
        assert_eq!(column, "stop_reason");
        assert!(problem.contains("bogus"), "{problem}");
        let expected = format!("{}: column `stop_reason`: {problem}", path.display());
        assert_eq!(shown(error), expected);
    }

    #[test]
    fn a_damaged_file_names_its_cause_once() {
        let folder = tempfile::tempdir().unwrap();
        let path = folder.path().join("block.parquet");
        std::fs::write(&path, "not parquet").unwrap();
        let error = run_rows_at(&path).unwrap_err();
        assert!(matches!(error, ReadError::NotParquet { .. }), "{error:?}");
        let shown = format!("{:#}", anyhow::Error::from(error));
        assert!(
            shown.starts_with(&format!("{}: not a Parquet file: ", path.display())),
            "{shown}"
        );
        assert_eq!(shown.matches("Parquet error").count(), 1, "{shown}");
    }
}
