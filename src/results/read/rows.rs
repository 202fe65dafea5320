//! One decoder per results table: a checked `Batch` of `monte_carlo`, `calibration`,
//! `evaluation`, `training` or `trajectories` in, the rows the run computed out
//! ([`RunRow`], [`CalibrationRow`], [`EvaluationRow`], [`StoredEpoch`], and samples
//! gathered into [`StoredTrajectory`]s). A column written by later versions only is
//! read with the value older runs implied. Adding a column to a table means an edit
//! here and one in the writer.

use super::columns::{Batch, ColumnError};
use crate::Vec3;
use crate::evaluate::terms_in_time::TermInTimeRow;
use crate::evaluate::{CalibrationRow, CalibrationTimeRow, EvaluationRow, HeldOutRow, RunRow};
use crate::results::{REPLICATE, RMSE_CI};
use crate::train::EpochRecord;
use crate::vocab::{Correction, ErrorModel, Phase, StopReason};

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

pub(super) fn run_rows(batch: &Batch) -> Result<Vec<RunRow>, ColumnError> {
    let run = batch.uints("run")?;
    let replicate = batch.optional_uints(REPLICATE);
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

pub(super) fn calibration_rows(batch: &Batch) -> Result<Vec<CalibrationRow>, ColumnError> {
    let row_keys = batch.row_keys()?;
    let window_s = batch.floats("window_s")?;
    let rmse = batch.floats("rmse_cm_s")?;
    let std = batch.floats("rmse_std_cm_s")?;
    let is_t_conv = batch.bools("is_t_conv")?;
    let efficiency = batch.optional_float_column("efficiency");
    let ci = batch.optional_float_column(RMSE_CI);
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

pub(super) fn evaluation_rows(batch: &Batch) -> Result<Vec<EvaluationRow>, ColumnError> {
    let row_keys = batch.row_keys()?;
    let trajectory = batch.strings("trajectory")?;
    let t_conv_s = batch.floats("t_conv_s")?;
    let rmse = batch.floats("rmse_cm_s")?;
    let std = batch.floats("rmse_std_cm_s")?;
    let improvement = batch.optional_floats("improvement_pct");
    let efficiency = batch.optional_float_column("efficiency");
    let ci = batch.optional_float_column(RMSE_CI);
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

pub(super) fn epoch_rows(batch: &Batch) -> Result<Vec<StoredEpoch>, ColumnError> {
    let error_model: Vec<ErrorModel> = batch.required("error_model")?;
    let epoch = batch.uints("epoch")?;
    let train_loss = batch.floats("train_loss")?;
    let validation_loss = batch.floats("validation_loss")?;
    let seconds = batch.floats("seconds")?;
    let samples_per_s = batch.floats("samples_per_s")?;
    let is_best = batch.bools("is_best")?;
    let replicate = batch.optional_uints(REPLICATE);
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
pub(super) type TrajectorySample = (String, String, f64, Vec3);

pub(super) fn trajectory_rows(batch: &Batch) -> Result<Vec<TrajectorySample>, ColumnError> {
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
pub(super) fn gather_trajectories(samples: Vec<TrajectorySample>) -> Vec<StoredTrajectory> {
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
pub(super) mod tests {
    use super::super::table_at;
    use super::*;
    use crate::results::{training_batch, write_table};
    use crate::train::TrainingHistory;

    /// A two-epoch training history, its best epoch the second, that ended for `stop`.
    pub(in crate::results::read) fn summary(stop: StopReason) -> TrainingHistory {
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
        write_table(
            &path,
            &training_batch(&[summary(StopReason::EarlyStopping)]),
        )
        .unwrap();
        let rows = table_at(&path, "training.parquet", epoch_rows).unwrap();
        assert!(rows.iter().all(|r| r.stop == StopReason::EarlyStopping));
        assert!(rows[1].is_best && !rows[0].is_best);

        let mut older = training_batch(&[summary(StopReason::EarlyStopping)]);
        older.remove_column(older.schema().index_of("stop_reason").unwrap());
        write_table(&path, &older).unwrap();
        let rows = table_at(&path, "training.parquet", epoch_rows).unwrap();
        assert_eq!(rows.len(), 2);
        assert!(rows.iter().all(|r| r.stop == StopReason::AllEpochs));

        older.remove_column(older.schema().index_of("is_best").unwrap());
        write_table(&path, &older).unwrap();
        let error = table_at(&path, "training.parquet", epoch_rows).unwrap_err();
        assert!(
            error.to_string().contains("column `is_best` is missing"),
            "{error}"
        );
    }
}

pub(super) fn held_out_rows(batch: &Batch) -> Result<Vec<HeldOutRow>, ColumnError> {
    let length_s = batch.floats("length_s")?;
    let rmse = batch.floats("rmse_cm_s")?;
    let std = batch.floats("rmse_std_cm_s")?;
    Ok(batch
        .row_keys()?
        .into_iter()
        .enumerate()
        .map(|(i, key)| HeldOutRow {
            dvl: key.dvl,
            estimator: key.estimator,
            error_model: key.error_model,
            length_s: length_s[i],
            rmse_cm_s: rmse[i],
            rmse_std_cm_s: std[i],
        })
        .collect())
}

pub(super) fn calibration_time_rows(batch: &Batch) -> Result<Vec<CalibrationTimeRow>, ColumnError> {
    let t_conv_s = batch.floats("t_conv_s")?;
    let time_s = batch.optional_floats("calibration_time_s");
    let to_bound = batch.optional_floats("time_to_bound_s");
    let at_time = batch.floats("rmse_at_time_cm_s")?;
    let long_s = batch.floats("long_window_s")?;
    let long = batch.floats("long_window_rmse_cm_s")?;
    let tolerance = batch.floats("tolerance_pct")?;
    Ok(batch
        .row_keys()?
        .into_iter()
        .enumerate()
        .map(|(i, key)| CalibrationTimeRow {
            dvl: key.dvl,
            estimator: key.estimator,
            error_model: key.error_model,
            t_conv_s: t_conv_s[i],
            calibration_time_s: time_s[i],
            time_to_bound_s: to_bound[i],
            rmse_at_time_cm_s: at_time[i],
            long_window_rmse_cm_s: long[i],
            long_window_s: long_s[i],
            tolerance_pct: tolerance[i],
        })
        .collect())
}

pub(super) fn terms_in_time_rows(batch: &Batch) -> Result<Vec<TermInTimeRow>, ColumnError> {
    let time_s = batch.floats("time_s")?;
    let term = batch.strings("term")?;
    let estimate = batch.floats("estimate")?;
    let std = batch.floats("std")?;
    let true_value = batch.optional_floats("true_value");
    let bound_std = batch.floats("bound_std")?;
    Ok(batch
        .row_keys()?
        .into_iter()
        .enumerate()
        .map(|(i, key)| TermInTimeRow {
            dvl: key.dvl,
            estimator: key.estimator,
            error_model: key.error_model,
            time_s: time_s[i],
            term: term[i].clone(),
            estimate: estimate[i],
            std: std[i],
            true_value: true_value[i],
            bound_std: bound_std[i],
        })
        .collect())
}
