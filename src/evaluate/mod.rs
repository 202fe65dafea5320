//! The paper's protocol. For each DVL under test, each Monte Carlo run measures the
//! calibration trajectory with fresh noise, every estimator estimates its terms from the
//! first w seconds for every window size w, and the RMSE of the corrected remainder is
//! taken. T_conv is the window with the lowest mean RMSE over runs. Each run's T_conv
//! terms then correct freshly measured test trajectories. The tables set each DVL's
//! information bound after its estimators and give every estimator its efficiency
//! against it. In: the spec, the trajectories. Out: per-run rows and the calibration
//! and evaluation tables.
//!
//! With `training.replicates` above 1, each DCNet replicate runs the protocol as its
//! own method (its own T_conv); the tables then hold one row per window or trajectory
//! for DCNet: the mean over replicates with a 95 % Student t confidence interval
//! across them, T_conv the argmin of the replicate-mean curve in calibration and the
//! mean of the replicates' T_conv in evaluation.
//!
//! Runs go in parallel; every measurement draws from a generator seeded by (seed, DVL,
//! run, trajectory) and every mean is summed in run order, so the numbers do not
//! depend on the thread count.
//!
//! - [`rows`]: what the protocol gives: one row per run, and the calibration and
//!   evaluation tables;
//! - [`protocol`]: the Monte Carlo runs of every estimator on one DVL, and their score;
//! - [`summary`]: the per-run rows summed into the tables: means over runs, replicates
//!   combined, the bound and every estimator's efficiency against it;
//! - [`calibration_time`]: the held-out RMSE against the calibration length, and each
//!   method's calibration time beside its T_conv;
//! - [`statistics`]: the mean, standard deviation and confidence interval they use;
//! - [`terms_in_time`]: the Kalman filters' terms, sample by sample, on the first run.

pub mod calibration_time;
pub mod protocol;
pub mod rows;
pub mod statistics;
pub mod summary;
pub mod terms_in_time;

pub use protocol::{rmse_cm_s, run_on_dvl, run_protocol};
pub use rows::{
    CalibrationRow, CalibrationTimeRow, EvaluationRow, HeldOutRow, ProtocolResult, RunRow,
};
pub use statistics::{mean_ci95, mean_std};
