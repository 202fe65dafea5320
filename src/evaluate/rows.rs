//! The rows the protocol gives: one per estimator, run and window or trajectory
//! ([`RunRow`]), and the calibration and evaluation tables summed from them
//! ([`CalibrationRow`], [`EvaluationRow`]), all three in a [`ProtocolResult`]. In:
//! nothing. Out: the types that `results` writes as Parquet and `report` reads back.

use super::terms_in_time::TermInTimeRow;
use crate::vocab::{Correction, ErrorModel, EstimatorKind, Phase};

/// One estimator's result in one run, on one window (calibration), trajectory
/// (evaluation at T_conv), or calibration length (held out: `window_s` is the length,
/// `trajectory` the pooled test trajectories).
#[derive(Debug, Clone, PartialEq)]
pub struct RunRow {
    pub run: usize,
    pub dvl: String,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    /// The DCNet replicate, when `training.replicates` is above 1.
    pub replicate: Option<usize>,
    pub phase: Phase,
    pub window_s: f64,
    pub trajectory: String,
    pub rmse_cm_s: f64,
    pub correction: Correction,
}

#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationRow {
    pub dvl: String,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    pub window_s: f64,
    pub rmse_cm_s: f64,
    pub rmse_std_cm_s: f64,
    /// Half-width of the 95 % confidence interval of the mean over DCNet replicates,
    /// when there are several.
    pub rmse_ci_cm_s: Option<f64>,
    pub is_t_conv: bool,
    /// The bound at this window over this RMSE; absent for the floor and the bound.
    pub efficiency: Option<f64>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct EvaluationRow {
    pub dvl: String,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    pub trajectory: String,
    pub t_conv_s: f64,
    pub rmse_cm_s: f64,
    pub rmse_std_cm_s: f64,
    /// Half-width of the 95 % confidence interval of the mean over DCNet replicates,
    /// when there are several.
    pub rmse_ci_cm_s: Option<f64>,
    /// `(baseline − this) / baseline · 100`; absent when the spec runs no baseline.
    pub improvement_pct: Option<f64>,
    /// The bound at this T_conv on this trajectory over this RMSE; absent for the floor
    /// and the bound.
    pub efficiency: Option<f64>,
}

/// One point of a held-out curve: the mean and spread over runs (and DCNet replicates)
/// of the RMSE on the test trajectories of terms from `length_s` of calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct HeldOutRow {
    pub dvl: String,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    pub length_s: f64,
    pub rmse_cm_s: f64,
    pub rmse_std_cm_s: f64,
}

/// A method's calibration time beside its T_conv.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationTimeRow {
    pub dvl: String,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    /// The paper's T_conv: the window of lowest mean RMSE on the rest of the
    /// calibration trajectory.
    pub t_conv_s: f64,
    /// The shortest calibration after which the held-out RMSE stays within the
    /// tolerance of its value at the longest window; `None` where even that value is
    /// not finite.
    pub calibration_time_s: Option<f64>,
    /// The shortest calibration after which the held-out RMSE stays within the
    /// tolerance of the bound's at the longest window; `None` where it never does.
    pub time_to_bound_s: Option<f64>,
    /// The held-out RMSE at the calibration time and at the longest window, cm/s.
    pub rmse_at_time_cm_s: f64,
    pub long_window_rmse_cm_s: f64,
    pub long_window_s: f64,
    pub tolerance_pct: f64,
}

#[derive(Debug, Clone, PartialEq, Default)]
pub struct ProtocolResult {
    pub runs: Vec<RunRow>,
    pub calibration: Vec<CalibrationRow>,
    pub evaluation: Vec<EvaluationRow>,
    pub held_out: Vec<HeldOutRow>,
    pub calibration_time: Vec<CalibrationTimeRow>,
    /// The Kalman filters' terms on the first run; not from the runs' rows.
    pub terms_in_time: Vec<TermInTimeRow>,
}
