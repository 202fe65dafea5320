//! The tables of how long to calibrate: `held_out.parquet` (each method's held-out
//! RMSE against the calibration length, the bound's among them),
//! `calibration_time.parquet` (each method's calibration time beside its T_conv) and
//! `terms_in_time.parquet` (the Kalman filters' terms after every sample of the first
//! run, in the stored units of the terms: a scale as a fraction, a bias in m/s). In:
//! the protocol's rows. Out: Arrow batches of one flat record per row; `read` turns
//! the records back into the rows.

use super::record::{ColumnError, Record, encode, optional, parsed};
use crate::evaluate::rows::{CalibrationTimeRow, HeldOutRow};
use crate::evaluate::terms_in_time::TermInTimeRow;
use arrow_array::RecordBatch;
use serde::{Deserialize, Serialize};

pub const HELD_OUT: &str = "held_out.parquet";
pub const CALIBRATION_TIME: &str = "calibration_time.parquet";
pub const TERMS_IN_TIME: &str = "terms_in_time.parquet";

/// A row of `held_out.parquet`.
#[derive(Serialize, Deserialize)]
pub(super) struct HeldOutRecord {
    dvl: String,
    estimator: String,
    error_model: Option<String>,
    length_s: f64,
    rmse_cm_s: f64,
    rmse_std_cm_s: f64,
}

impl Record for HeldOutRecord {}

impl HeldOutRecord {
    pub(super) fn row(self) -> Result<HeldOutRow, ColumnError> {
        Ok(HeldOutRow {
            dvl: self.dvl,
            estimator: parsed("estimator", &self.estimator)?,
            error_model: optional("error_model", self.error_model.as_deref())?,
            length_s: self.length_s,
            rmse_cm_s: self.rmse_cm_s,
            rmse_std_cm_s: self.rmse_std_cm_s,
        })
    }
}

pub fn held_out_batch(rows: &[HeldOutRow]) -> RecordBatch {
    let records: Vec<HeldOutRecord> = rows
        .iter()
        .map(|r| HeldOutRecord {
            dvl: r.dvl.clone(),
            estimator: r.estimator.to_string(),
            error_model: r.error_model.map(|m| m.to_string()),
            length_s: r.length_s,
            rmse_cm_s: r.rmse_cm_s,
            rmse_std_cm_s: r.rmse_std_cm_s,
        })
        .collect();
    encode(&records)
}

/// A row of `calibration_time.parquet`.
#[derive(Serialize, Deserialize)]
pub(super) struct CalibrationTimeRecord {
    dvl: String,
    estimator: String,
    error_model: Option<String>,
    t_conv_s: f64,
    calibration_time_s: Option<f64>,
    time_to_bound_s: Option<f64>,
    rmse_at_time_cm_s: f64,
    long_window_s: f64,
    long_window_rmse_cm_s: f64,
    tolerance_pct: f64,
}

impl Record for CalibrationTimeRecord {}

impl CalibrationTimeRecord {
    pub(super) fn row(self) -> Result<CalibrationTimeRow, ColumnError> {
        Ok(CalibrationTimeRow {
            dvl: self.dvl,
            estimator: parsed("estimator", &self.estimator)?,
            error_model: optional("error_model", self.error_model.as_deref())?,
            t_conv_s: self.t_conv_s,
            calibration_time_s: self.calibration_time_s,
            time_to_bound_s: self.time_to_bound_s,
            rmse_at_time_cm_s: self.rmse_at_time_cm_s,
            long_window_rmse_cm_s: self.long_window_rmse_cm_s,
            long_window_s: self.long_window_s,
            tolerance_pct: self.tolerance_pct,
        })
    }
}

pub fn calibration_time_batch(rows: &[CalibrationTimeRow]) -> RecordBatch {
    let records: Vec<CalibrationTimeRecord> = rows
        .iter()
        .map(|r| CalibrationTimeRecord {
            dvl: r.dvl.clone(),
            estimator: r.estimator.to_string(),
            error_model: r.error_model.map(|m| m.to_string()),
            t_conv_s: r.t_conv_s,
            calibration_time_s: r.calibration_time_s,
            time_to_bound_s: r.time_to_bound_s,
            rmse_at_time_cm_s: r.rmse_at_time_cm_s,
            long_window_s: r.long_window_s,
            long_window_rmse_cm_s: r.long_window_rmse_cm_s,
            tolerance_pct: r.tolerance_pct,
        })
        .collect();
    encode(&records)
}

/// A row of `terms_in_time.parquet`.
#[derive(Serialize, Deserialize)]
pub(super) struct TermInTimeRecord {
    dvl: String,
    estimator: String,
    error_model: Option<String>,
    time_s: f64,
    term: String,
    estimate: f64,
    std: f64,
    true_value: Option<f64>,
    bound_std: f64,
}

impl Record for TermInTimeRecord {}

impl TermInTimeRecord {
    pub(super) fn row(self) -> Result<TermInTimeRow, ColumnError> {
        Ok(TermInTimeRow {
            dvl: self.dvl,
            estimator: parsed("estimator", &self.estimator)?,
            error_model: optional("error_model", self.error_model.as_deref())?,
            time_s: self.time_s,
            term: self.term,
            estimate: self.estimate,
            std: self.std,
            true_value: self.true_value,
            bound_std: self.bound_std,
        })
    }
}

pub fn terms_in_time_batch(rows: &[TermInTimeRow]) -> RecordBatch {
    let records: Vec<TermInTimeRecord> = rows
        .iter()
        .map(|r| TermInTimeRecord {
            dvl: r.dvl.clone(),
            estimator: r.estimator.to_string(),
            error_model: r.error_model.map(|m| m.to_string()),
            time_s: r.time_s,
            term: r.term.clone(),
            estimate: r.estimate,
            std: r.std,
            true_value: r.true_value,
            bound_std: r.bound_std,
        })
        .collect();
    encode(&records)
}
