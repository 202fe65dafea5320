//! The paper run's tables as typed rows: one flat record per table, one field per
//! column (a correction's terms in % and cm/s, a name as its text), made from the
//! rows the protocol computed and turned back into them. In: [`RunRow`],
//! [`CalibrationRow`], [`EvaluationRow`], training histories and trajectories. Out:
//! Arrow batches through [`super::record`]; `read` turns the records back into rows, a
//! name that does not parse a fault naming its column.

use super::record::{ColumnError, Record, encode, optional, parsed};
use crate::data::Trajectory;
use crate::evaluate::{CalibrationRow, EvaluationRow, RunRow};
use crate::train::{EpochRecord, TrainingHistory};
use crate::vocab::{Correction, ErrorModel, StopReason};
use arrow_array::RecordBatch;
use serde::{Deserialize, Serialize};

/// The column of a DCNet row's replicate, in `monte_carlo.parquet` and
/// `training.parquet` when there are several.
pub const REPLICATE: &str = "replicate";

/// The column of the 95 % confidence interval over DCNet replicates, in the
/// calibration and evaluation tables when there are several.
pub const RMSE_CI: &str = "rmse_ci_cm_s";

/// A row of `monte_carlo.parquet`: a [`RunRow`], its correction in % and cm/s.
#[derive(Serialize, Deserialize)]
pub(super) struct RunRecord {
    run: u32,
    dvl: String,
    estimator: String,
    error_model: Option<String>,
    phase: String,
    window_s: f64,
    trajectory: String,
    rmse_cm_s: f64,
    scale_x_pct: f64,
    scale_y_pct: f64,
    scale_z_pct: f64,
    bias_x_cm_s: f64,
    bias_y_cm_s: f64,
    bias_z_cm_s: f64,
    replicate: Option<u32>,
}

impl Record for RunRecord {
    const SOMETIMES: &'static [&'static str] = &[REPLICATE];
}

impl From<&RunRow> for RunRecord {
    fn from(row: &RunRow) -> Self {
        let [scale_x_pct, scale_y_pct, scale_z_pct] = row.correction.scale.map(|s| 100.0 * s);
        let [bias_x_cm_s, bias_y_cm_s, bias_z_cm_s] = row.correction.bias_m_s.map(|b| 100.0 * b);
        RunRecord {
            run: row.run as u32,
            dvl: row.dvl.clone(),
            estimator: row.estimator.to_string(),
            error_model: row.error_model.map(|m| m.to_string()),
            phase: row.phase.as_str().to_string(),
            window_s: row.window_s,
            trajectory: row.trajectory.clone(),
            rmse_cm_s: row.rmse_cm_s,
            scale_x_pct,
            scale_y_pct,
            scale_z_pct,
            bias_x_cm_s,
            bias_y_cm_s,
            bias_z_cm_s,
            replicate: row.replicate.map(|r| r as u32),
        }
    }
}

impl RunRecord {
    pub(super) fn row(self) -> Result<RunRow, ColumnError> {
        Ok(RunRow {
            run: self.run as usize,
            dvl: self.dvl,
            estimator: parsed("estimator", &self.estimator)?,
            error_model: optional("error_model", self.error_model.as_deref())?,
            replicate: self.replicate.map(|r| r as usize),
            phase: parsed("phase", &self.phase)?,
            window_s: self.window_s,
            trajectory: self.trajectory,
            rmse_cm_s: self.rmse_cm_s,
            correction: Correction {
                scale: [self.scale_x_pct, self.scale_y_pct, self.scale_z_pct].map(|s| s / 100.0),
                bias_m_s: [self.bias_x_cm_s, self.bias_y_cm_s, self.bias_z_cm_s].map(|b| b / 100.0),
            },
        })
    }
}

/// One row per run × DVL × estimator × error model × (window or trajectory), and a
/// `replicate` column (empty but for DCNet) when DCNet has several replicates.
pub fn monte_carlo_batch(rows: &[RunRow]) -> RecordBatch {
    encode(&rows.iter().map(RunRecord::from).collect::<Vec<_>>())
}

/// A row of `calibration.parquet`.
#[derive(Serialize, Deserialize)]
pub(super) struct CalibrationRecord {
    dvl: String,
    estimator: String,
    error_model: Option<String>,
    window_s: f64,
    rmse_cm_s: f64,
    rmse_std_cm_s: f64,
    is_t_conv: bool,
    efficiency: Option<f64>,
    rmse_ci_cm_s: Option<f64>,
}

impl Record for CalibrationRecord {
    const SOMETIMES: &'static [&'static str] = &[RMSE_CI];
}

impl From<&CalibrationRow> for CalibrationRecord {
    fn from(row: &CalibrationRow) -> Self {
        CalibrationRecord {
            dvl: row.dvl.clone(),
            estimator: row.estimator.to_string(),
            error_model: row.error_model.map(|m| m.to_string()),
            window_s: row.window_s,
            rmse_cm_s: row.rmse_cm_s,
            rmse_std_cm_s: row.rmse_std_cm_s,
            is_t_conv: row.is_t_conv,
            efficiency: row.efficiency,
            rmse_ci_cm_s: row.rmse_ci_cm_s,
        }
    }
}

impl CalibrationRecord {
    pub(super) fn row(self) -> Result<CalibrationRow, ColumnError> {
        Ok(CalibrationRow {
            dvl: self.dvl,
            estimator: parsed("estimator", &self.estimator)?,
            error_model: optional("error_model", self.error_model.as_deref())?,
            window_s: self.window_s,
            rmse_cm_s: self.rmse_cm_s,
            rmse_std_cm_s: self.rmse_std_cm_s,
            rmse_ci_cm_s: self.rmse_ci_cm_s,
            is_t_conv: self.is_t_conv,
            efficiency: self.efficiency,
        })
    }
}

pub fn calibration_batch(rows: &[CalibrationRow]) -> RecordBatch {
    encode(&rows.iter().map(CalibrationRecord::from).collect::<Vec<_>>())
}

/// A row of `evaluation.parquet`.
#[derive(Serialize, Deserialize)]
pub(super) struct EvaluationRecord {
    dvl: String,
    estimator: String,
    error_model: Option<String>,
    trajectory: String,
    t_conv_s: f64,
    rmse_cm_s: f64,
    rmse_std_cm_s: f64,
    improvement_pct: Option<f64>,
    efficiency: Option<f64>,
    rmse_ci_cm_s: Option<f64>,
}

impl Record for EvaluationRecord {
    const SOMETIMES: &'static [&'static str] = &[RMSE_CI];
}

impl From<&EvaluationRow> for EvaluationRecord {
    fn from(row: &EvaluationRow) -> Self {
        EvaluationRecord {
            dvl: row.dvl.clone(),
            estimator: row.estimator.to_string(),
            error_model: row.error_model.map(|m| m.to_string()),
            trajectory: row.trajectory.clone(),
            t_conv_s: row.t_conv_s,
            rmse_cm_s: row.rmse_cm_s,
            rmse_std_cm_s: row.rmse_std_cm_s,
            improvement_pct: row.improvement_pct,
            efficiency: row.efficiency,
            rmse_ci_cm_s: row.rmse_ci_cm_s,
        }
    }
}

impl EvaluationRecord {
    pub(super) fn row(self) -> Result<EvaluationRow, ColumnError> {
        Ok(EvaluationRow {
            dvl: self.dvl,
            estimator: parsed("estimator", &self.estimator)?,
            error_model: optional("error_model", self.error_model.as_deref())?,
            trajectory: self.trajectory,
            t_conv_s: self.t_conv_s,
            rmse_cm_s: self.rmse_cm_s,
            rmse_std_cm_s: self.rmse_std_cm_s,
            rmse_ci_cm_s: self.rmse_ci_cm_s,
            improvement_pct: self.improvement_pct,
            efficiency: self.efficiency,
        })
    }
}

pub fn evaluation_batch(rows: &[EvaluationRow]) -> RecordBatch {
    encode(&rows.iter().map(EvaluationRecord::from).collect::<Vec<_>>())
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

/// A row of `training.parquet`: one epoch of one model's training.
#[derive(Serialize, Deserialize)]
pub(super) struct TrainingRecord {
    error_model: String,
    epoch: u32,
    train_loss: f64,
    validation_loss: f64,
    seconds: f64,
    samples_per_s: f64,
    is_best: bool,
    /// Runs from before early stopping lack it: they trained every epoch.
    stop_reason: Option<String>,
    replicate: Option<u32>,
}

impl Record for TrainingRecord {
    const SOMETIMES: &'static [&'static str] = &[REPLICATE];
}

impl TrainingRecord {
    pub(super) fn row(self) -> Result<StoredEpoch, ColumnError> {
        let stop = match self.stop_reason {
            Some(stop) => parsed("stop_reason", &stop)?,
            None => StopReason::AllEpochs,
        };
        Ok(StoredEpoch {
            error_model: parsed("error_model", &self.error_model)?,
            replicate: self.replicate.map(|r| r as usize),
            record: EpochRecord {
                epoch: self.epoch as usize,
                train_loss: self.train_loss,
                validation_loss: self.validation_loss,
                seconds: self.seconds,
                samples_per_s: self.samples_per_s,
            },
            is_best: self.is_best,
            stop,
        })
    }
}

/// One row per error model × epoch of DCNet training, and a `replicate` column when
/// DCNet has several replicates.
pub fn training_batch(dcnets: &[TrainingHistory]) -> RecordBatch {
    let replicates = dcnets.iter().any(|t| t.replicate > 0);
    let records: Vec<TrainingRecord> = dcnets
        .iter()
        .flat_map(|t| {
            t.history.iter().map(move |e| TrainingRecord {
                error_model: t.error_model.to_string(),
                epoch: e.epoch as u32,
                train_loss: e.train_loss,
                validation_loss: e.validation_loss,
                seconds: e.seconds,
                samples_per_s: e.samples_per_s,
                is_best: e.epoch == t.best_epoch,
                stop_reason: Some(t.stop.to_string()),
                replicate: replicates.then_some(t.replicate as u32),
            })
        })
        .collect();
    encode(&records)
}

/// A row of `trajectories.parquet`: one GT velocity sample of one trajectory.
#[derive(Serialize, Deserialize)]
pub(super) struct SampleRecord {
    pub(super) trajectory: String,
    /// What the trajectory is used for, comma-separated ("train,test", say).
    pub(super) roles: String,
    pub(super) time_s: f64,
    pub(super) vx_m_s: f64,
    pub(super) vy_m_s: f64,
    pub(super) vz_m_s: f64,
}

impl Record for SampleRecord {}

/// The GT velocity of each trajectory, one row per sample, with what the trajectory is
/// used for ("train,test", say).
pub fn trajectories_batch(
    trajectories: &[(&Trajectory, String)],
    sample_rate_hz: f64,
) -> RecordBatch {
    let records: Vec<SampleRecord> = trajectories
        .iter()
        .flat_map(|(t, roles)| {
            t.ground_truth
                .iter()
                .enumerate()
                .map(move |(i, v)| SampleRecord {
                    trajectory: t.name.clone(),
                    roles: roles.clone(),
                    time_s: i as f64 / sample_rate_hz,
                    vx_m_s: v[0],
                    vy_m_s: v[1],
                    vz_m_s: v[2],
                })
        })
        .collect();
    encode(&records)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::read::run_rows_at;
    use crate::results::write_table;
    use crate::vocab::{ErrorModel, EstimatorKind, Phase};

    /// A row whose correction survives the trip through % and cm/s exactly.
    fn run(estimator: EstimatorKind, error_model: Option<ErrorModel>) -> RunRow {
        RunRow {
            run: 3,
            dvl: "DVL1".into(),
            estimator,
            error_model,
            replicate: None,
            phase: Phase::Evaluation,
            window_s: 100.0,
            trajectory: "S3".into(),
            rmse_cm_s: 1.0 / 3.0,
            correction: Correction {
                scale: [0.25, -0.5, 0.0],
                bias_m_s: [0.125, 0.0, -0.75],
            },
        }
    }

    fn names(batch: &RecordBatch) -> Vec<String> {
        let schema = batch.schema();
        schema.fields().iter().map(|f| f.name().clone()).collect()
    }

    fn nullable(batch: &RecordBatch, name: &str) -> bool {
        let schema = batch.schema();
        schema.field_with_name(name).unwrap().is_nullable()
    }

    #[test]
    fn the_replicate_column_is_written_only_with_replicates_and_rows_read_back() {
        let folder = tempfile::tempdir().unwrap();
        let path = folder.path().join("monte_carlo.parquet");
        let single = vec![run(EstimatorKind::LeastSquares, Some(ErrorModel::Em5))];
        let batch = monte_carlo_batch(&single);
        assert!(!names(&batch).contains(&REPLICATE.to_string()));
        assert!(!nullable(&batch, "error_model"));
        write_table(&path, &batch).unwrap();
        assert_eq!(run_rows_at(&path).unwrap(), single);

        let mut replicated = single.clone();
        replicated.push(run(EstimatorKind::Baseline, None));
        replicated.push(RunRow {
            replicate: Some(1),
            ..run(EstimatorKind::Dcnet, Some(ErrorModel::Em5))
        });
        let batch = monte_carlo_batch(&replicated);
        assert_eq!(names(&batch).last().map(String::as_str), Some(REPLICATE));
        assert!(nullable(&batch, "error_model"));
        write_table(&path, &batch).unwrap();
        assert_eq!(run_rows_at(&path).unwrap(), replicated);
    }

    #[test]
    fn the_velocity_columns_are_named_as_a_recording_reads_them() {
        let names = names(&trajectories_batch(&[], 1.0));
        assert_eq!(names[3..], crate::VELOCITY_COLUMNS.map(String::from));
    }
}
