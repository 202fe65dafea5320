//! The tables of how long to calibrate: `held_out.parquet` (each method's held-out
//! RMSE against the calibration length, the bound's among them),
//! `calibration_time.parquet` (each method's calibration time beside its T_conv) and
//! `terms_in_time.parquet` (the Kalman filters' terms after every sample of the first
//! run, in the stored units of the terms: a scale as a fraction, a bias in m/s). In:
//! the protocol's rows. Out: Arrow batches, and the rows read back from them.

use super::read::{Batch, ColumnError};
use super::{batch, error_models, floats, optional_floats, strings};
use crate::evaluate::calibration_time::{CalibrationTimeRow, HeldOutRow};
use crate::evaluate::terms_in_time::TermInTimeRow;
use arrow_array::RecordBatch;

pub const HELD_OUT: &str = "held_out.parquet";
pub const CALIBRATION_TIME: &str = "calibration_time.parquet";
pub const TERMS_IN_TIME: &str = "terms_in_time.parquet";

pub fn held_out_batch(rows: &[HeldOutRow]) -> RecordBatch {
    batch(vec![
        ("dvl", strings(rows, |r| r.dvl.clone())),
        ("estimator", strings(rows, |r| r.estimator.to_string())),
        ("error_model", error_models(rows, |r| r.error_model)),
        ("length_s", floats(rows, |r| r.length_s)),
        ("rmse_cm_s", floats(rows, |r| r.rmse_cm_s)),
        ("rmse_std_cm_s", floats(rows, |r| r.rmse_std_cm_s)),
    ])
}

pub fn calibration_time_batch(rows: &[CalibrationTimeRow]) -> RecordBatch {
    batch(vec![
        ("dvl", strings(rows, |r| r.dvl.clone())),
        ("estimator", strings(rows, |r| r.estimator.to_string())),
        ("error_model", error_models(rows, |r| r.error_model)),
        ("t_conv_s", floats(rows, |r| r.t_conv_s)),
        (
            "calibration_time_s",
            optional_floats(rows, |r| r.calibration_time_s),
        ),
        ("rmse_at_time_cm_s", floats(rows, |r| r.rmse_at_time_cm_s)),
        ("long_window_s", floats(rows, |r| r.long_window_s)),
        (
            "long_window_rmse_cm_s",
            floats(rows, |r| r.long_window_rmse_cm_s),
        ),
        ("tolerance_pct", floats(rows, |r| r.tolerance_pct)),
    ])
}

pub fn terms_in_time_batch(rows: &[TermInTimeRow]) -> RecordBatch {
    batch(vec![
        ("dvl", strings(rows, |r| r.dvl.clone())),
        ("estimator", strings(rows, |r| r.estimator.to_string())),
        ("error_model", error_models(rows, |r| r.error_model)),
        ("time_s", floats(rows, |r| r.time_s)),
        ("term", strings(rows, |r| r.term.clone())),
        ("estimate", floats(rows, |r| r.estimate)),
        ("std", floats(rows, |r| r.std)),
        ("true_value", optional_floats(rows, |r| r.true_value)),
        ("bound_std", floats(rows, |r| r.bound_std)),
    ])
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
