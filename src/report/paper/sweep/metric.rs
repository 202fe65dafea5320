//! The metric a sweep figure plots against the swept values: its name on the command
//! line, its description, its value in a row of `sweep.parquet` and its axis label.
//! Both sweep figures (the metric against each key, and the parallel coordinates) read
//! it.
//! In: a row of `sweep.parquet`, or the command line's name. Out: the metric, its
//! value and its label.

use crate::results::sweep::SweepRow;

/// What a sweep figure plots against the swept values.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Metric {
    /// Mean RMSE over the test trajectories
    EvaluationRmse,
    /// Mean RMSE at T_conv on the calibration trajectory
    CalibrationRmse,
    /// The convergence window
    TConv,
    /// DCNet training wall time
    TrainingTime,
}

impl Metric {
    pub const ALL: [Metric; 4] = [
        Metric::EvaluationRmse,
        Metric::CalibrationRmse,
        Metric::TConv,
        Metric::TrainingTime,
    ];

    /// How the command line spells it.
    pub fn name(self) -> &'static str {
        match self {
            Metric::EvaluationRmse => "evaluation-rmse",
            Metric::CalibrationRmse => "calibration-rmse",
            Metric::TConv => "t-conv",
            Metric::TrainingTime => "training-time",
        }
    }

    /// What it is, in a sentence's words.
    pub fn description(self) -> &'static str {
        match self {
            Metric::EvaluationRmse => "Mean RMSE over the test trajectories",
            Metric::CalibrationRmse => "Mean RMSE at T_conv on the calibration trajectory",
            Metric::TConv => "The convergence window",
            Metric::TrainingTime => "DCNet training wall time",
        }
    }

    pub(super) fn of(self, row: &SweepRow) -> Option<f64> {
        match self {
            Metric::EvaluationRmse => Some(row.evaluation_rmse_cm_s),
            Metric::CalibrationRmse => Some(row.calibration_rmse_cm_s),
            Metric::TConv => Some(row.t_conv_s),
            Metric::TrainingTime => row.training_s,
        }
    }

    pub(super) fn axis(self) -> &'static str {
        match self {
            Metric::EvaluationRmse => "evaluation RMSE [cm/s]",
            Metric::CalibrationRmse => "calibration RMSE at T_conv [cm/s]",
            Metric::TConv => "T_conv [s]",
            Metric::TrainingTime => "training time [s]",
        }
    }
}
