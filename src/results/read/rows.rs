//! One decoder per results table: a checked `Batch` of `monte_carlo`, `calibration`,
//! `evaluation`, `training`, `trajectories` or a table of how long to calibrate in,
//! decoded into the table's records and turned into the rows the run computed out
//! ([`RunRow`], [`CalibrationRow`], [`EvaluationRow`], [`StoredEpoch`], and samples
//! gathered into [`StoredTrajectory`]s). A column written by later versions only is
//! read with the value older runs implied. Adding a column to a table means a field
//! in its record and in the row.

use super::columns::{Batch, ColumnError};
use super::records;
use crate::Vec3;
use crate::evaluate::terms_in_time::TermInTimeRow;
use crate::evaluate::{CalibrationRow, CalibrationTimeRow, EvaluationRow, HeldOutRow, RunRow};
use crate::results::calibration_time::{CalibrationTimeRecord, HeldOutRecord, TermInTimeRecord};
pub use crate::results::tables::StoredEpoch;
use crate::results::tables::{
    CalibrationRecord, EvaluationRecord, RunRecord, SampleRecord, TrainingRecord,
};

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
    records(batch, RunRecord::row)
}

pub(super) fn calibration_rows(batch: &Batch) -> Result<Vec<CalibrationRow>, ColumnError> {
    records(batch, CalibrationRecord::row)
}

pub(super) fn evaluation_rows(batch: &Batch) -> Result<Vec<EvaluationRow>, ColumnError> {
    records(batch, EvaluationRecord::row)
}

pub(super) fn epoch_rows(batch: &Batch) -> Result<Vec<StoredEpoch>, ColumnError> {
    records(batch, TrainingRecord::row)
}

pub(super) fn held_out_rows(batch: &Batch) -> Result<Vec<HeldOutRow>, ColumnError> {
    records(batch, HeldOutRecord::row)
}

pub(super) fn calibration_time_rows(batch: &Batch) -> Result<Vec<CalibrationTimeRow>, ColumnError> {
    records(batch, CalibrationTimeRecord::row)
}

pub(super) fn terms_in_time_rows(batch: &Batch) -> Result<Vec<TermInTimeRow>, ColumnError> {
    records(batch, TermInTimeRecord::row)
}

/// One sample of one trajectory: name, roles, time, velocity.
pub(super) type TrajectorySample = (String, String, f64, Vec3);

pub(super) fn trajectory_rows(batch: &Batch) -> Result<Vec<TrajectorySample>, ColumnError> {
    records(batch, |r: SampleRecord| {
        Ok((
            r.trajectory,
            r.roles,
            r.time_s,
            [r.vx_m_s, r.vy_m_s, r.vz_m_s],
        ))
    })
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
    use crate::train::{EpochRecord, TrainingHistory};
    use crate::vocab::{ErrorModel, StopReason};

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
