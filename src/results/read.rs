//! Reads a results folder back, for `plot` and the report: the Parquet tables into the
//! rows the run computed, the resolved spec, the manifest and the published values.
//! Each table's schema is checked against the one the writer produces, so a missing
//! file or a foreign schema is an error that names the file, never a wrong figure; a
//! column that is missing, of another type, with empty values or with a value no run
//! writes is a [`ColumnError`] that names the column.

use super::{
    MANIFEST, Manifest, PUBLISHED, SPEC, TABLES, calibration_batch, evaluation_batch,
    monte_carlo_batch, training_batch, trajectories_batch,
};
use crate::Vec3;
use crate::evaluate::{CalibrationRow, EvaluationRow, RunRow};
use crate::spec::published::Published;
use crate::spec::{SpecErrors, SpecFile, TomlFile};
use crate::train::EpochRecord;
use crate::vocab::{Correction, ErrorModel, EstimatorKind, Phase, StopReason};
use arrow_array::{Array, BooleanArray, Float64Array, RecordBatch, StringArray, UInt32Array};
use arrow_schema::{DataType, Schema};
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
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
    #[error("{}", path.display())]
    Manifest {
        path: PathBuf,
        #[source]
        source: ManifestError,
    },
}

/// What is wrong with one column of a stored table: the fault itself, shown after the
/// file's path by [`ReadError::Column`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ColumnError {
    #[error("column `{column}` is missing: this is not the schema dcnet-exp writes")]
    Missing { column: String },
    #[error(
        "column `{column}` holds {found}, expected {expected}: this is not the schema dcnet-exp writes"
    )]
    Type {
        column: String,
        found: DataType,
        expected: DataType,
    },
    #[error("column `{column}` has empty values")]
    Empty { column: String },
    /// A name that does not parse; `problem` is what the name's type says of it.
    #[error("column `{column}`: {problem}")]
    Value { column: String, problem: String },
    /// A swept key of the sweep's index that the sweep table lacks.
    #[error("column `{column}`, a swept key of {index}, is missing")]
    SweptMissing { column: String, index: &'static str },
    #[error("column `{column}` holds {found}, expected Int64, Float64 or Utf8")]
    SweptType { column: String, found: DataType },
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
    pub training: Vec<StoredEpoch>,
    pub trajectories: Vec<StoredTrajectory>,
}

/// One epoch of one error model's training.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredEpoch {
    pub error_model: ErrorModel,
    /// Which replicate, when DCNet has several.
    pub replicate: Option<usize>,
    pub record: EpochRecord,
    pub is_best: bool,
    /// Why the model's training ended (the same on every row of a model).
    pub stop: StopReason,
}

/// The GT velocity of one trajectory.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredTrajectory {
    pub name: String,
    /// "train", "calibration", "test".
    pub roles: Vec<String>,
    pub time_s: Vec<f64>,
    pub velocity_m_s: Vec<Vec3>,
}

impl StoredRun {
    pub fn read(folder: &Path) -> Result<StoredRun, ReadError> {
        let spec_path = existing(&folder.join(SPEC))?;
        let spec = TomlFile::<SpecFile>::read(&spec_path)
            .map_err(|e| ReadError::Spec {
                path: spec_path.clone(),
                source: SpecErrors(vec![e]),
            })?
            .value;
        let manifest_path = existing(&folder.join(MANIFEST))?;
        let manifest = std::fs::read(&manifest_path)
            .map_err(ManifestError::from)
            .and_then(|bytes| Ok(serde_json::from_slice(&bytes)?))
            .map_err(|source| ReadError::Manifest {
                path: manifest_path.clone(),
                source,
            })?;
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
        let [runs, calibration, evaluation, training, trajectories] = TABLES;
        Ok(StoredRun {
            folder: folder.to_path_buf(),
            spec,
            manifest,
            published,
            runs: table(folder, runs, run_rows)?,
            calibration: table(folder, calibration, calibration_rows)?,
            evaluation: table(folder, evaluation, evaluation_rows)?,
            training: table(folder, training, epoch_rows)?,
            trajectories: gather_trajectories(table(folder, trajectories, trajectory_rows)?),
        })
    }

    /// The stored DVL names, in the order the spec lists them.
    pub fn dvls(&self) -> Vec<String> {
        self.spec.dvl.iter().map(|d| d.name.clone()).collect()
    }
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

/// The schema the writer gives `file`.
fn expected_schema(file: &str) -> std::sync::Arc<Schema> {
    let batch = match file {
        "monte_carlo.parquet" => monte_carlo_batch(&[]),
        "calibration.parquet" => calibration_batch(&[]),
        "evaluation.parquet" => evaluation_batch(&[]),
        "training.parquet" => training_batch(&[]),
        "trajectories.parquet" => trajectories_batch(&[], 1.0),
        other => unreachable!("{other} is not a results table"),
    };
    batch.schema()
}

/// Columns added after the first results folders were written: a folder that lacks
/// one still reads, with the value those runs implied.
const LATER_COLUMNS: [&str; 2] = ["stop_reason", "efficiency"];

fn check_schema(found: &Schema, expected: &Schema) -> Result<(), ColumnError> {
    for field in expected.fields() {
        match found.field_with_name(field.name()) {
            Err(_) if LATER_COLUMNS.contains(&field.name().as_str()) => {}
            Err(_) => {
                return Err(ColumnError::Missing {
                    column: field.name().clone(),
                });
            }
            Ok(column) if column.data_type() != field.data_type() => {
                return Err(ColumnError::Type {
                    column: field.name().clone(),
                    found: column.data_type().clone(),
                    expected: field.data_type().clone(),
                });
            }
            Ok(_) => {}
        }
    }
    Ok(())
}

/// A batch whose schema was checked, read column by column.
pub(crate) struct Batch<'a>(pub(crate) &'a RecordBatch);

impl Batch<'_> {
    pub(crate) fn column<A: Array + 'static>(&self, name: &str) -> &A {
        self.0
            .column_by_name(name)
            .and_then(|c| c.as_any().downcast_ref::<A>())
            .expect("the schema was checked")
    }

    fn no_nulls(&self, name: &str) -> Result<(), ColumnError> {
        let column = self.0.column_by_name(name).expect("the schema was checked");
        if column.null_count() > 0 {
            return Err(ColumnError::Empty {
                column: name.to_string(),
            });
        }
        Ok(())
    }

    pub(crate) fn floats(&self, name: &str) -> Result<Vec<f64>, ColumnError> {
        self.no_nulls(name)?;
        Ok(self.column::<Float64Array>(name).values().to_vec())
    }

    pub(crate) fn optional_floats(&self, name: &str) -> Vec<Option<f64>> {
        self.column::<Float64Array>(name).iter().collect()
    }

    fn uints(&self, name: &str) -> Result<Vec<usize>, ColumnError> {
        self.no_nulls(name)?;
        Ok(self
            .column::<UInt32Array>(name)
            .values()
            .iter()
            .map(|&v| v as usize)
            .collect())
    }

    /// A column that only some tables have, empty values and all; all empty when the
    /// table lacks it.
    fn optional_uints(&self, name: &str) -> Vec<Option<usize>> {
        match self.0.column_by_name(name) {
            Some(column) => column
                .as_any()
                .downcast_ref::<UInt32Array>()
                .map(|c| c.iter().map(|v| v.map(|v| v as usize)).collect())
                .unwrap_or_else(|| vec![None; self.0.num_rows()]),
            None => vec![None; self.0.num_rows()],
        }
    }

    /// Like [`Batch::optional_uints`], for floats.
    pub(crate) fn optional_float_column(&self, name: &str) -> Vec<Option<f64>> {
        match self.0.column_by_name(name) {
            Some(column) => column
                .as_any()
                .downcast_ref::<Float64Array>()
                .map(|c| c.iter().collect())
                .unwrap_or_else(|| vec![None; self.0.num_rows()]),
            None => vec![None; self.0.num_rows()],
        }
    }

    fn bools(&self, name: &str) -> Result<Vec<bool>, ColumnError> {
        self.no_nulls(name)?;
        let column = self.column::<BooleanArray>(name);
        Ok((0..column.len()).map(|i| column.value(i)).collect())
    }

    pub(crate) fn strings(&self, name: &str) -> Result<Vec<String>, ColumnError> {
        self.no_nulls(name)?;
        Ok(self
            .column::<StringArray>(name)
            .iter()
            .map(|s| s.unwrap_or_default().to_string())
            .collect())
    }

    /// A column of names parsed into `T`; `optional` allows empty values.
    pub(crate) fn parsed<T: std::str::FromStr<Err = String>>(
        &self,
        name: &str,
        optional: bool,
    ) -> Result<Vec<Option<T>>, ColumnError> {
        if !optional {
            self.no_nulls(name)?;
        }
        self.column::<StringArray>(name)
            .iter()
            .map(|value| {
                value
                    .map(|v| {
                        v.parse().map_err(|problem| ColumnError::Value {
                            column: name.to_string(),
                            problem,
                        })
                    })
                    .transpose()
            })
            .collect()
    }

    fn required<T: std::str::FromStr<Err = String>>(
        &self,
        name: &str,
    ) -> Result<Vec<T>, ColumnError> {
        Ok(self
            .parsed(name, false)?
            .into_iter()
            .map(|v| v.expect("no nulls"))
            .collect())
    }

    /// The `dvl`, `estimator` and `error_model` of each row: which series it belongs to.
    pub(crate) fn row_keys(&self) -> Result<Vec<RowKey>, ColumnError> {
        let dvl = self.strings("dvl")?;
        let estimator: Vec<EstimatorKind> = self.required("estimator")?;
        let error_model = self.parsed("error_model", true)?;
        Ok(dvl
            .into_iter()
            .zip(estimator)
            .zip(error_model)
            .map(|((dvl, estimator), error_model)| RowKey {
                dvl,
                estimator,
                error_model,
            })
            .collect())
    }
}

/// The DVL, estimator and error model a row belongs to.
pub(crate) struct RowKey {
    pub dvl: String,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
}

fn run_rows(batch: &Batch) -> Result<Vec<RunRow>, ColumnError> {
    let run = batch.uints("run")?;
    let replicate = batch.optional_uints(super::REPLICATE);
    let row_keys = batch.row_keys()?;
    let phase: Vec<Phase> = batch.required("phase")?;
    let window_s = batch.floats("window_s")?;
    let trajectory = batch.strings("trajectory")?;
    let rmse = batch.floats("rmse_cm_s")?;
    let terms = [
        "scale_x_pct",
        "scale_y_pct",
        "scale_z_pct",
        "bias_x_cm_s",
        "bias_y_cm_s",
        "bias_z_cm_s",
    ]
    .map(|name| batch.floats(name));
    let [sx, sy, sz, bx, by, bz] = terms;
    let (sx, sy, sz, bx, by, bz) = (sx?, sy?, sz?, bx?, by?, bz?);
    Ok(row_keys
        .into_iter()
        .enumerate()
        .map(|(i, series)| RunRow {
            run: run[i],
            dvl: series.dvl,
            estimator: series.estimator,
            error_model: series.error_model,
            replicate: replicate[i],
            phase: phase[i],
            window_s: window_s[i],
            trajectory: trajectory[i].clone(),
            rmse_cm_s: rmse[i],
            correction: Correction {
                scale: [sx[i] / 100.0, sy[i] / 100.0, sz[i] / 100.0],
                bias_m_s: [bx[i] / 100.0, by[i] / 100.0, bz[i] / 100.0],
            },
        })
        .collect())
}

fn calibration_rows(batch: &Batch) -> Result<Vec<CalibrationRow>, ColumnError> {
    let row_keys = batch.row_keys()?;
    let window_s = batch.floats("window_s")?;
    let rmse = batch.floats("rmse_cm_s")?;
    let std = batch.floats("rmse_std_cm_s")?;
    let is_t_conv = batch.bools("is_t_conv")?;
    let efficiency = batch.optional_float_column("efficiency");
    let ci = batch.optional_float_column(super::RMSE_CI);
    Ok(row_keys
        .into_iter()
        .enumerate()
        .map(|(i, series)| CalibrationRow {
            dvl: series.dvl,
            estimator: series.estimator,
            error_model: series.error_model,
            window_s: window_s[i],
            rmse_cm_s: rmse[i],
            rmse_std_cm_s: std[i],
            rmse_ci_cm_s: ci[i],
            is_t_conv: is_t_conv[i],
            efficiency: efficiency[i],
        })
        .collect())
}

fn evaluation_rows(batch: &Batch) -> Result<Vec<EvaluationRow>, ColumnError> {
    let row_keys = batch.row_keys()?;
    let trajectory = batch.strings("trajectory")?;
    let t_conv_s = batch.floats("t_conv_s")?;
    let rmse = batch.floats("rmse_cm_s")?;
    let std = batch.floats("rmse_std_cm_s")?;
    let improvement = batch.optional_floats("improvement_pct");
    let efficiency = batch.optional_float_column("efficiency");
    let ci = batch.optional_float_column(super::RMSE_CI);
    Ok(row_keys
        .into_iter()
        .enumerate()
        .map(|(i, series)| EvaluationRow {
            dvl: series.dvl,
            estimator: series.estimator,
            error_model: series.error_model,
            trajectory: trajectory[i].clone(),
            t_conv_s: t_conv_s[i],
            rmse_cm_s: rmse[i],
            rmse_std_cm_s: std[i],
            rmse_ci_cm_s: ci[i],
            improvement_pct: improvement[i],
            efficiency: efficiency[i],
        })
        .collect())
}

fn epoch_rows(batch: &Batch) -> Result<Vec<StoredEpoch>, ColumnError> {
    let error_model: Vec<ErrorModel> = batch.required("error_model")?;
    let epoch = batch.uints("epoch")?;
    let train_loss = batch.floats("train_loss")?;
    let validation_loss = batch.floats("validation_loss")?;
    let seconds = batch.floats("seconds")?;
    let samples_per_s = batch.floats("samples_per_s")?;
    let is_best = batch.bools("is_best")?;
    let replicate = batch.optional_uints(super::REPLICATE);
    // Runs from before early stopping trained every epoch.
    let stop: Vec<StopReason> = if batch.0.column_by_name("stop_reason").is_some() {
        batch.required("stop_reason")?
    } else {
        vec![StopReason::AllEpochs; epoch.len()]
    };
    Ok((0..epoch.len())
        .map(|i| StoredEpoch {
            error_model: error_model[i],
            replicate: replicate[i],
            record: EpochRecord {
                epoch: epoch[i],
                train_loss: train_loss[i],
                validation_loss: validation_loss[i],
                seconds: seconds[i],
                samples_per_s: samples_per_s[i],
            },
            is_best: is_best[i],
            stop: stop[i],
        })
        .collect())
}

/// One sample of one trajectory: name, roles, time, velocity.
type TrajectorySample = (String, String, f64, Vec3);

fn trajectory_rows(batch: &Batch) -> Result<Vec<TrajectorySample>, ColumnError> {
    let name = batch.strings("trajectory")?;
    let roles = batch.strings("roles")?;
    let time_s = batch.floats("time_s")?;
    let [vx, vy, vz] = crate::VELOCITY_COLUMNS.map(|c| batch.floats(c));
    let (vx, vy, vz) = (vx?, vy?, vz?);
    Ok((0..name.len())
        .map(|i| {
            (
                name[i].clone(),
                roles[i].clone(),
                time_s[i],
                [vx[i], vy[i], vz[i]],
            )
        })
        .collect())
}

/// Groups the samples by trajectory, in the order they come.
fn gather_trajectories(samples: Vec<TrajectorySample>) -> Vec<StoredTrajectory> {
    let mut trajectories: Vec<StoredTrajectory> = Vec::new();
    for (name, roles, time_s, velocity) in samples {
        if trajectories.last().is_none_or(|t| t.name != name) {
            trajectories.push(StoredTrajectory {
                name,
                roles: roles
                    .split(',')
                    .filter(|r| !r.is_empty())
                    .map(String::from)
                    .collect(),
                time_s: Vec::new(),
                velocity_m_s: Vec::new(),
            });
        }
        let trajectory = trajectories.last_mut().expect("just pushed");
        trajectory.time_s.push(time_s);
        trajectory.velocity_m_s.push(velocity);
    }
    trajectories
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::train::TrainingHistory;
    use crate::vocab::StopReason;

    fn summary(stop: StopReason) -> TrainingHistory {
        let epoch = |epoch| EpochRecord {
            epoch,
            train_loss: 1.0,
            validation_loss: 0.5,
            seconds: 1.0,
            samples_per_s: 1.0,
        };
        TrainingHistory {
            key: "k".repeat(64),
            error_model: ErrorModel::Em5,
            replicate: 0,
            best_epoch: 2,
            history: vec![epoch(1), epoch(2)],
            stop,
        }
    }

    #[test]
    fn the_stop_reason_reads_back_and_defaults_for_folders_written_before_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("training.parquet");
        super::super::write_table(
            &path,
            &training_batch(&[summary(StopReason::EarlyStopping)]),
        )
        .unwrap();
        let rows = table_at(&path, "training.parquet", epoch_rows).unwrap();
        assert!(rows.iter().all(|r| r.stop == StopReason::EarlyStopping));
        assert!(rows[1].is_best && !rows[0].is_best);

        let mut older = training_batch(&[summary(StopReason::EarlyStopping)]);
        older.remove_column(older.schema().index_of("stop_reason").unwrap());
        super::super::write_table(&path, &older).unwrap();
        let rows = table_at(&path, "training.parquet", epoch_rows).unwrap();
        assert_eq!(rows.len(), 2);
        assert!(rows.iter().all(|r| r.stop == StopReason::AllEpochs));

        older.remove_column(older.schema().index_of("is_best").unwrap());
        super::super::write_table(&path, &older).unwrap();
        let error = table_at(&path, "training.parquet", epoch_rows).unwrap_err();
        assert!(
            error.to_string().contains("column `is_best` is missing"),
            "{error}"
        );
    }

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
