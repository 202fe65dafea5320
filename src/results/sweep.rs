//! What a sweep adds to its points' results folders: `results/<name>/sweep.parquet`,
//! one row per point × DVL × estimator × error model with the swept values as columns
//! and the numbers a sweep is read by (calibration RMSE and T_conv, evaluation RMSE,
//! training time; with DCNet replicates, the 95 % confidence intervals of DCNet's RMSEs
//! across them), and `sweep.json`, the index of the points, written last. The point
//! and swept columns are built by hand (their names are the swept keys); the fixed
//! columns are one flat record per row.

use crate::evaluate::{ProtocolResult, mean_ci95};
use crate::files::write_atomic;
use crate::results::read::{Batch, ColumnError, ReadError, read_rows, records};
use crate::results::record::{self, Record, encode, optional, parsed};
use crate::results::{ResultsError, table_bytes};
use crate::spec::Experiment;
use crate::train::TrainingHistory;
use crate::vocab::{ErrorModel, EstimatorKind, Phase};
use arrow_array::types::{Float64Type, Int64Type};
use arrow_array::{ArrayRef, Float64Array, Int64Array, RecordBatch, StringArray, cast::AsArray};
use arrow_schema::DataType;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::Arc;

pub const TABLE: &str = "sweep.parquet";
pub const INDEX: &str = "sweep.json";

/// `sweep.json`: the swept keys, the points, and the results key of each point's
/// folder when the table was written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepIndex {
    pub name: String,
    pub swept: Vec<String>,
    /// Each point's folder name under `results/<name>/`.
    pub points: Vec<String>,
    pub results_keys: Vec<String>,
    /// The SHA-256 of the table it was written with; empty in an index from before
    /// the table was hashed.
    #[serde(default)]
    pub table_sha256: String,
    /// The kind of spec swept: empty for the paper's experiments, `"installation"` for
    /// installation studies.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub kind: String,
}

impl SweepIndex {
    /// Whether the table in `folder` has the bytes this index was written with.
    pub fn table_is_intact(&self, folder: &Path) -> bool {
        std::fs::read(folder.join(TABLE))
            .is_ok_and(|bytes| crate::files::sha256_hex(&bytes) == self.table_sha256)
    }
}

/// A swept value: an integer, a number, or any other TOML value as text.
#[derive(Debug, Clone, PartialEq)]
pub enum Swept {
    Integer(i64),
    Number(f64),
    Text(String),
}

impl Swept {
    /// Its value on a numeric axis, if it has one.
    pub fn number(&self) -> Option<f64> {
        match self {
            Swept::Integer(i) => Some(*i as f64),
            Swept::Number(n) => Some(*n),
            Swept::Text(_) => None,
        }
    }
}

impl std::fmt::Display for Swept {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Swept::Integer(i) => write!(f, "{i}"),
            Swept::Number(n) => write!(f, "{n}"),
            Swept::Text(t) => f.write_str(t),
        }
    }
}

/// One row of `sweep.parquet`.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepRow {
    pub point: String,
    /// One per swept key.
    pub values: Vec<Swept>,
    pub dvl: String,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    pub t_conv_s: f64,
    /// Mean RMSE over runs at T_conv on the calibration trajectory.
    pub calibration_rmse_cm_s: f64,
    /// Mean over the test trajectories of the mean RMSE over runs.
    pub evaluation_rmse_cm_s: f64,
    pub evaluation_improvement_pct: Option<f64>,
    /// Wall time of the DCNet's training, summed over its epochs (and replicates).
    pub training_s: Option<f64>,
    /// With DCNet replicates: the half-width of the 95 % confidence interval across
    /// them of the calibration RMSE at T_conv, and of the evaluation RMSE.
    pub calibration_rmse_ci_cm_s: Option<f64>,
    pub evaluation_rmse_ci_cm_s: Option<f64>,
}

/// A stored sweep: its index and table.
#[derive(Debug, Clone)]
pub struct StoredSweep {
    pub index: SweepIndex,
    pub rows: Vec<SweepRow>,
}

/// The rows of `sweep.parquet` from each point's tables and model summaries.
pub fn rows(
    experiment: &Experiment,
    points: &[(ProtocolResult, Vec<TrainingHistory>)],
) -> Vec<SweepRow> {
    let mut rows = Vec::new();
    for (point, (result, models)) in experiment.points.iter().zip(points) {
        let name = point_folder(&point.spec.name);
        let values: Vec<Swept> = point.values.iter().map(swept).collect();
        for at_t_conv in result.calibration.iter().filter(|r| r.is_t_conv) {
            let evaluation: Vec<_> = result
                .evaluation
                .iter()
                .filter(|r| {
                    r.dvl == at_t_conv.dvl
                        && r.estimator == at_t_conv.estimator
                        && r.error_model == at_t_conv.error_model
                })
                .collect();
            let mean = |values: Vec<f64>| values.iter().sum::<f64>() / values.len() as f64;
            let improvements: Option<Vec<f64>> =
                evaluation.iter().map(|r| r.improvement_pct).collect();
            let training_s = (at_t_conv.estimator == EstimatorKind::Dcnet)
                .then(|| {
                    let trained: Vec<_> = models
                        .iter()
                        .filter(|m| Some(m.error_model) == at_t_conv.error_model)
                        .collect();
                    (!trained.is_empty()).then(|| {
                        trained
                            .iter()
                            .flat_map(|m| &m.history)
                            .map(|e| e.seconds)
                            .sum()
                    })
                })
                .flatten();
            // Each replicate's evaluation RMSE, its mean over runs and test trajectories.
            let evaluation_rmse_ci_cm_s = at_t_conv.rmse_ci_cm_s.map(|_| {
                let series = result.runs.iter().filter(|r| {
                    r.phase == Phase::Evaluation
                        && r.dvl == at_t_conv.dvl
                        && r.estimator == at_t_conv.estimator
                        && r.error_model == at_t_conv.error_model
                });
                let per_replicate: Vec<f64> =
                    crate::first_seen(series.clone().map(|r| r.replicate))
                        .into_iter()
                        .map(|replicate| {
                            mean(
                                series
                                    .clone()
                                    .filter(|r| r.replicate == replicate)
                                    .map(|r| r.rmse_cm_s)
                                    .collect(),
                            )
                        })
                        .collect();
                mean_ci95(&per_replicate).1
            });
            rows.push(SweepRow {
                point: name.to_string(),
                values: values.clone(),
                dvl: at_t_conv.dvl.clone(),
                estimator: at_t_conv.estimator,
                error_model: at_t_conv.error_model,
                t_conv_s: at_t_conv.window_s,
                calibration_rmse_cm_s: at_t_conv.rmse_cm_s,
                evaluation_rmse_cm_s: mean(evaluation.iter().map(|r| r.rmse_cm_s).collect()),
                evaluation_improvement_pct: improvements.filter(|i| !i.is_empty()).map(mean),
                training_s,
                calibration_rmse_ci_cm_s: at_t_conv.rmse_ci_cm_s,
                evaluation_rmse_ci_cm_s,
            });
        }
    }
    rows
}

/// A swept TOML value as the table stores it.
pub fn swept(value: &toml::Value) -> Swept {
    match value {
        toml::Value::Integer(i) => Swept::Integer(*i),
        toml::Value::Float(f) => Swept::Number(*f),
        toml::Value::String(s) => Swept::Text(s.clone()),
        other => Swept::Text(other.to_string()),
    }
}

/// The folder of a sweep point under the sweep's: `quick-sweep/lr=0.001` → `lr=0.001`.
pub fn point_folder(spec_name: &str) -> &str {
    spec_name
        .split_once('/')
        .map_or(spec_name, |(_, point)| point)
}

/// Writes `sweep.parquet` and then `sweep.json` into `folder`.
pub fn write(
    folder: &Path,
    experiment: &Experiment,
    points: &[(ProtocolResult, Vec<TrainingHistory>)],
    results_keys: &[String],
) -> Result<(), ResultsError> {
    let rows = rows(experiment, points);
    let index = SweepIndex {
        name: experiment.name.clone(),
        swept: experiment.swept.clone(),
        points: experiment
            .points
            .iter()
            .map(|p| point_folder(&p.spec.name).to_string())
            .collect(),
        results_keys: results_keys.to_vec(),
        table_sha256: String::new(),
        kind: String::new(),
    };
    write_table_and_index(folder, &batch(&experiment.swept, &rows), index)
}

/// Writes `batch` as `sweep.parquet` into `folder`, then `index`, with the table's
/// SHA-256, as `sweep.json`: the index last, so that it names a table that is there.
pub fn write_table_and_index(
    folder: &Path,
    batch: &RecordBatch,
    index: SweepIndex,
) -> Result<(), ResultsError> {
    let table = folder.join(TABLE);
    let bytes = table_bytes(&table, batch)?;
    write_atomic(&table, &bytes).map_err(|source| ResultsError::Io {
        path: table.clone(),
        source,
    })?;
    let index = SweepIndex {
        table_sha256: crate::files::sha256_hex(&bytes),
        ..index
    };
    let path = folder.join(INDEX);
    write_atomic(
        &path,
        serde_json::to_string_pretty(&index)
            .expect("an index serializes")
            .as_bytes(),
    )
    .map_err(|source| ResultsError::Io { path, source })
}

/// The first columns of a sweep's table, one value per row: the point, then one column
/// per swept key (integers as Int64, other numbers as Float64, anything else as its
/// TOML text).
pub fn point_columns(swept: &[String], rows: &[(&str, &[Swept])]) -> Vec<(String, ArrayRef)> {
    let mut columns: Vec<(String, ArrayRef)> = vec![(
        "point".into(),
        Arc::new(StringArray::from_iter_values(
            rows.iter().map(|(point, _)| *point),
        )),
    )];
    for (k, key) in swept.iter().enumerate() {
        let all = |f: fn(&Swept) -> bool| rows.iter().all(|(_, values)| f(&values[k]));
        let column: ArrayRef = if all(|v| matches!(v, Swept::Integer(_))) {
            Arc::new(Int64Array::from_iter_values(rows.iter().map(
                |(_, values)| match values[k] {
                    Swept::Integer(i) => i,
                    _ => unreachable!("every value is an integer"),
                },
            )))
        } else if all(|v| v.number().is_some()) {
            Arc::new(Float64Array::from_iter(
                rows.iter().map(|(_, values)| values[k].number()),
            ))
        } else {
            Arc::new(StringArray::from_iter_values(
                rows.iter().map(|(_, values)| values[k].to_string()),
            ))
        };
        columns.push((key.clone(), column));
    }
    columns
}

/// A row of `sweep.parquet` after its point columns: a [`SweepRow`]'s fixed columns.
#[derive(Serialize, Deserialize)]
struct SweepRecord {
    dvl: String,
    estimator: String,
    error_model: Option<String>,
    t_conv_s: f64,
    calibration_rmse_cm_s: f64,
    evaluation_rmse_cm_s: f64,
    evaluation_improvement_pct: Option<f64>,
    training_s: Option<f64>,
    calibration_rmse_ci_cm_s: Option<f64>,
    evaluation_rmse_ci_cm_s: Option<f64>,
}

impl Record for SweepRecord {
    const SOMETIMES: &'static [&'static str] = &[CALIBRATION_CI, EVALUATION_CI];
}

impl From<&SweepRow> for SweepRecord {
    fn from(row: &SweepRow) -> Self {
        SweepRecord {
            dvl: row.dvl.clone(),
            estimator: row.estimator.to_string(),
            error_model: row.error_model.map(|m| m.to_string()),
            t_conv_s: row.t_conv_s,
            calibration_rmse_cm_s: row.calibration_rmse_cm_s,
            evaluation_rmse_cm_s: row.evaluation_rmse_cm_s,
            evaluation_improvement_pct: row.evaluation_improvement_pct,
            training_s: row.training_s,
            calibration_rmse_ci_cm_s: row.calibration_rmse_ci_cm_s,
            evaluation_rmse_ci_cm_s: row.evaluation_rmse_ci_cm_s,
        }
    }
}

impl SweepRecord {
    /// The row of `point` with the swept `values`.
    fn row(self, point: String, values: Vec<Swept>) -> Result<SweepRow, ColumnError> {
        Ok(SweepRow {
            point,
            values,
            dvl: self.dvl,
            estimator: parsed("estimator", &self.estimator)?,
            error_model: optional("error_model", self.error_model.as_deref())?,
            t_conv_s: self.t_conv_s,
            calibration_rmse_cm_s: self.calibration_rmse_cm_s,
            evaluation_rmse_cm_s: self.evaluation_rmse_cm_s,
            evaluation_improvement_pct: self.evaluation_improvement_pct,
            training_s: self.training_s,
            calibration_rmse_ci_cm_s: self.calibration_rmse_ci_cm_s,
            evaluation_rmse_ci_cm_s: self.evaluation_rmse_ci_cm_s,
        })
    }
}

/// The point of a row of a sweep's table, its first column.
#[derive(Serialize, Deserialize)]
pub(super) struct PointRecord {
    pub(super) point: String,
}

impl Record for PointRecord {}

/// The table: point, one column per swept key (see [`point_columns`]), then the fixed
/// columns, the confidence intervals' when DCNet has replicates.
fn batch(swept: &[String], rows: &[SweepRow]) -> RecordBatch {
    let mut columns = point_columns(
        swept,
        &rows
            .iter()
            .map(|r| (r.point.as_str(), &r.values[..]))
            .collect::<Vec<_>>(),
    );
    let fixed = encode(&rows.iter().map(SweepRecord::from).collect::<Vec<_>>());
    columns.extend(record::columns(&fixed));
    record::batch(columns)
}

/// The confidence interval columns, in the table when DCNet has replicates.
const CALIBRATION_CI: &str = "calibration_rmse_ci_cm_s";
const EVALUATION_CI: &str = "evaluation_rmse_ci_cm_s";

/// Reads `sweep.json` of `folder`.
pub fn read_index(folder: &Path) -> Result<SweepIndex, ReadError> {
    let path = folder.join(INDEX);
    let bytes = std::fs::read(&path).map_err(|_| ReadError::Missing { path: path.clone() })?;
    serde_json::from_slice(&bytes).map_err(|source| ReadError::Json { path, source })
}

/// Reads the sweep stored in `folder`.
pub fn read(folder: &Path) -> Result<StoredSweep, ReadError> {
    let index = read_index(folder)?;
    // The fixed columns; the swept ones are read by their names in the index.
    let expected = batch(&[], &[]).schema();
    let rows = read_rows(&folder.join(TABLE), &expected, |b| {
        sweep_rows(b, &index.swept)
    })?;
    Ok(StoredSweep { index, rows })
}

fn sweep_rows(batch: &Batch, swept: &[String]) -> Result<Vec<SweepRow>, ColumnError> {
    let points = records(batch, |r: PointRecord| Ok(r.point))?;
    let mut values: Vec<Vec<Swept>> = vec![Vec::new(); points.len()];
    for key in swept {
        for (row, value) in values.iter_mut().zip(swept_column(batch, key)?) {
            row.push(value);
        }
    }
    let mut rows = points.into_iter().zip(values);
    records(batch, |record: SweepRecord| {
        let (point, values) = rows.next().expect("one point per row");
        record.row(point, values)
    })
}

/// The values of the swept key `key`, by their column's type.
fn swept_column(batch: &Batch, key: &str) -> Result<Vec<Swept>, ColumnError> {
    let column = batch
        .0
        .column_by_name(key)
        .ok_or_else(|| ColumnError::SweptMissing {
            column: key.to_string(),
            index: INDEX,
        })?;
    Ok(match column.data_type() {
        DataType::Int64 => column
            .as_primitive::<Int64Type>()
            .iter()
            .map(|v| Swept::Integer(v.unwrap_or_default()))
            .collect(),
        DataType::Float64 => column
            .as_primitive::<Float64Type>()
            .iter()
            .map(|v| Swept::Number(v.unwrap_or(f64::NAN)))
            .collect(),
        DataType::Utf8 => column
            .as_string::<i32>()
            .iter()
            .map(|v| Swept::Text(v.unwrap_or_default().to_string()))
            .collect(),
        other => {
            return Err(ColumnError::SweptType {
                column: key.to_string(),
                found: other.clone(),
            });
        }
    })
}
