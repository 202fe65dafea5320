//! What a sweep adds to its points' results folders: `results/<name>/sweep.parquet`,
//! one row per point × DVL × estimator × error model with the swept values as columns
//! and the numbers a sweep is read by (calibration RMSE and T_conv, evaluation RMSE,
//! training time), and `sweep.json`, the index of the points, written last.

use crate::checkpoint::Summary;
use crate::estimators::{ErrorModel, EstimatorKind};
use crate::evaluate::ProtocolResult;
use crate::results::read::ReadError;
use crate::results::{ResultsError, write_atomic, write_table};
use crate::spec::Experiment;
use arrow_array::{
    Array, ArrayRef, Float64Array, RecordBatch, StringArray, cast::AsArray, types::Float64Type,
};
use arrow_schema::DataType;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
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
}

/// A swept value: a number, or any other TOML value as text.
#[derive(Debug, Clone, PartialEq)]
pub enum Swept {
    Number(f64),
    Text(String),
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
    /// Wall time of the DCNet's training, summed over its epochs.
    pub training_s: Option<f64>,
}

/// A stored sweep: its index and table.
#[derive(Debug, Clone)]
pub struct StoredSweep {
    pub index: SweepIndex,
    pub rows: Vec<SweepRow>,
}

/// The rows of `sweep.parquet` from each point's tables and model summaries.
pub fn rows(experiment: &Experiment, points: &[(ProtocolResult, Vec<Summary>)]) -> Vec<SweepRow> {
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
                    models
                        .iter()
                        .find(|m| Some(m.error_model) == at_t_conv.error_model)
                        .map(|m| m.history.iter().map(|e| e.seconds).sum())
                })
                .flatten();
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
            });
        }
    }
    rows
}

fn swept(value: &toml::Value) -> Swept {
    match value {
        toml::Value::Integer(i) => Swept::Number(*i as f64),
        toml::Value::Float(f) => Swept::Number(*f),
        toml::Value::String(s) => Swept::Text(s.clone()),
        other => Swept::Text(other.to_string()),
    }
}

/// `quick-sweep/lr=0.001` → `lr=0.001`.
fn point_folder(spec_name: &str) -> &str {
    spec_name
        .split_once('/')
        .map_or(spec_name, |(_, point)| point)
}

/// Writes `sweep.parquet` and then `sweep.json` into `folder`.
pub fn write(
    folder: &Path,
    experiment: &Experiment,
    points: &[(ProtocolResult, Vec<Summary>)],
    results_keys: &[String],
) -> Result<(), ResultsError> {
    let rows = rows(experiment, points);
    write_table(&folder.join(TABLE), &batch(&experiment.swept, &rows))?;
    let index = SweepIndex {
        name: experiment.name.clone(),
        swept: experiment.swept.clone(),
        points: experiment
            .points
            .iter()
            .map(|p| point_folder(&p.spec.name).to_string())
            .collect(),
        results_keys: results_keys.to_vec(),
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

/// The table: point, one column per swept key (numbers as Float64, anything else as
/// its TOML text), then the fixed columns.
fn batch(swept: &[String], rows: &[SweepRow]) -> RecordBatch {
    let strings = |f: &dyn Fn(&SweepRow) -> String| -> ArrayRef {
        Arc::new(StringArray::from_iter_values(rows.iter().map(f)))
    };
    let floats = |f: &dyn Fn(&SweepRow) -> Option<f64>| -> ArrayRef {
        Arc::new(Float64Array::from_iter(rows.iter().map(f)))
    };
    let mut columns: Vec<(String, ArrayRef)> =
        vec![("point".into(), strings(&|r| r.point.clone()))];
    for (k, key) in swept.iter().enumerate() {
        let numeric = rows.iter().all(|r| matches!(r.values[k], Swept::Number(_)));
        let column = if numeric {
            floats(&|r| match &r.values[k] {
                Swept::Number(n) => Some(*n),
                Swept::Text(_) => None,
            })
        } else {
            strings(&|r| match &r.values[k] {
                Swept::Number(n) => n.to_string(),
                Swept::Text(t) => t.clone(),
            })
        };
        columns.push((key.clone(), column));
    }
    columns.extend([
        ("dvl".to_string(), strings(&|r| r.dvl.clone())),
        (
            "estimator".to_string(),
            strings(&|r| r.estimator.to_string()),
        ),
        (
            "error_model".to_string(),
            Arc::new(StringArray::from_iter(
                rows.iter().map(|r| r.error_model.map(|m| m.to_string())),
            )) as ArrayRef,
        ),
        ("t_conv_s".to_string(), floats(&|r| Some(r.t_conv_s))),
        (
            "calibration_rmse_cm_s".to_string(),
            floats(&|r| Some(r.calibration_rmse_cm_s)),
        ),
        (
            "evaluation_rmse_cm_s".to_string(),
            floats(&|r| Some(r.evaluation_rmse_cm_s)),
        ),
        (
            "evaluation_improvement_pct".to_string(),
            floats(&|r| r.evaluation_improvement_pct),
        ),
        ("training_s".to_string(), floats(&|r| r.training_s)),
    ]);
    RecordBatch::try_from_iter(columns).expect("columns of one table have equal lengths")
}

/// Reads `sweep.json` of `folder`.
pub fn read_index(folder: &Path) -> Result<SweepIndex, ReadError> {
    let path = folder.join(INDEX);
    let bytes = std::fs::read(&path).map_err(|_| ReadError::Missing { path: path.clone() })?;
    serde_json::from_slice(&bytes).map_err(|e| ReadError::Invalid {
        path,
        message: e.to_string(),
    })
}

/// Reads the sweep stored in `folder`.
pub fn read(folder: &Path) -> Result<StoredSweep, ReadError> {
    let index = read_index(folder)?;
    let path = folder.join(TABLE);
    let invalid = |message: String| ReadError::Invalid {
        path: path.clone(),
        message,
    };
    let file = std::fs::File::open(&path).map_err(|_| ReadError::Missing { path: path.clone() })?;
    let reader = ParquetRecordBatchReaderBuilder::try_new(file)
        .and_then(|b| b.build())
        .map_err(|e| invalid(format!("not a Parquet file: {e}")))?;
    let mut rows = Vec::new();
    for batch in reader {
        let batch = batch.map_err(|e| invalid(e.to_string()))?;
        let column = |name: &str| {
            batch
                .column_by_name(name)
                .ok_or_else(|| invalid(format!("has no column {name:?}")))
        };
        let text = |name: &str| -> Result<Vec<Option<String>>, ReadError> {
            let column = column(name)?;
            let strings = column
                .as_string_opt::<i32>()
                .ok_or_else(|| invalid(format!("column {name:?} is not text")))?;
            Ok(strings.iter().map(|s| s.map(str::to_string)).collect())
        };
        let numbers = |name: &str| -> Result<Vec<Option<f64>>, ReadError> {
            let column = column(name)?;
            let floats = column
                .as_primitive_opt::<Float64Type>()
                .ok_or_else(|| invalid(format!("column {name:?} is not Float64")))?;
            Ok(floats.iter().collect())
        };
        let mut values: Vec<Vec<Swept>> = vec![Vec::new(); batch.num_rows()];
        for key in &index.swept {
            let column = column(key)?;
            let swept: Vec<Swept> = if column.data_type() == &DataType::Float64 {
                numbers(key)?
                    .into_iter()
                    .map(|v| Swept::Number(v.unwrap_or(f64::NAN)))
                    .collect()
            } else {
                text(key)?
                    .into_iter()
                    .map(|v| Swept::Text(v.unwrap_or_default()))
                    .collect()
            };
            for (row, value) in values.iter_mut().zip(swept) {
                row.push(value);
            }
        }
        let required = |values: Vec<Option<f64>>, name: &str| -> Result<Vec<f64>, ReadError> {
            values
                .into_iter()
                .map(|v| v.ok_or_else(|| invalid(format!("column {name:?} has an empty cell"))))
                .collect()
        };
        let point = text("point")?;
        let dvl = text("dvl")?;
        let estimator = text("estimator")?;
        let error_model = text("error_model")?;
        let t_conv = required(numbers("t_conv_s")?, "t_conv_s")?;
        let calibration = required(numbers("calibration_rmse_cm_s")?, "calibration_rmse_cm_s")?;
        let evaluation = required(numbers("evaluation_rmse_cm_s")?, "evaluation_rmse_cm_s")?;
        let improvement = numbers("evaluation_improvement_pct")?;
        let training = numbers("training_s")?;
        for (i, values) in values.into_iter().enumerate() {
            let estimator: EstimatorKind = estimator[i]
                .clone()
                .unwrap_or_default()
                .parse()
                .map_err(invalid)?;
            let error_model = match &error_model[i] {
                Some(name) => Some(name.parse().map_err(invalid)?),
                None => None,
            };
            rows.push(SweepRow {
                point: point[i].clone().unwrap_or_default(),
                values,
                dvl: dvl[i].clone().unwrap_or_default(),
                estimator,
                error_model,
                t_conv_s: t_conv[i],
                calibration_rmse_cm_s: calibration[i],
                evaluation_rmse_cm_s: evaluation[i],
                evaluation_improvement_pct: improvement[i],
                training_s: training[i],
            });
        }
    }
    Ok(StoredSweep { index, rows })
}
