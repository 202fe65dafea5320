//! The tables of how long to calibrate: `held_out.parquet` (each method's held-out
//! RMSE against the calibration length, the bound's among them),
//! `calibration_time.parquet` (each method's calibration time beside its T_conv) and
//! `terms_in_time.parquet` (the Kalman filters' terms after every sample of the first
//! run, in the stored units of the terms: a scale as a fraction, a bias in m/s). In:
//! the protocol's rows. Out: Arrow batches; `read::rows` reads them back.

use super::{batch, error_models, floats, optional_floats, strings};
use crate::evaluate::rows::{CalibrationTimeRow, HeldOutRow};
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
        (
            "time_to_bound_s",
            optional_floats(rows, |r| r.time_to_bound_s),
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
