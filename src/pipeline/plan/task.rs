//! The tasks of a plan: a dataset, a DCNet training, a Monte Carlo block (one
//! estimator on one DVL, every run), a point's results folder and a sweep's table, each
//! named by its kind and its index in the plan. In: nothing. Out: the task types.

use crate::vocab::{ErrorModel, EstimatorKind};
use std::path::PathBuf;

/// One training set, generated from the spec of its first point.
pub struct Dataset {
    pub key: String,
    pub point: usize,
}

/// One DCNet training.
pub struct Training {
    pub key: String,
    pub dataset: usize,
    pub point: usize,
    pub error_model: ErrorModel,
    /// Which of `training.replicates` it trains.
    pub replicate: usize,
    /// The training of its replicate 0 (itself without replicates): the replicates of a
    /// model share a shard, so the ensemble's block finds every model it runs there.
    pub group: usize,
}

/// A Monte Carlo block: one estimator on one DVL, every Monte Carlo run.
pub struct MonteCarloBlock {
    pub key: String,
    pub point: usize,
    pub dvl: usize,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    /// The DCNet replicate it runs, when `training.replicates` is above 1.
    pub replicate: Option<usize>,
    /// The trainings whose models it runs: one for DCNet, every replicate's for the
    /// ensemble, none for the other methods.
    pub trainings: Vec<usize>,
}

/// What one point is made of.
pub struct PointPlan {
    pub folder: PathBuf,
    /// Its blocks in table order: DVL, then estimator and error model as the spec lists.
    pub blocks: Vec<usize>,
    pub trainings: Vec<usize>,
    /// The results key its folder has when it is current.
    pub results_key: String,
}

/// A task of the plan, by kind and index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Task {
    Dataset(usize),
    Training(usize),
    Block(usize),
    Results(usize),
    /// The `sweep.parquet` of a sweep.
    Sweep,
}
