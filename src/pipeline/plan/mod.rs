//! The plan: every task of an experiment (datasets, trainings, Monte Carlo blocks,
//! results folders, the sweep table), deduplicated by cache key, and the state of each
//! as the cache on disk tells it. In: the experiment and its trajectories. Out: the
//! tasks and what is left to do; nothing is written.
//!
//! - [`task`]: the kinds of task and what each is made of;
//! - this module: the tasks of every point, each listed once however many points share
//!   its cache key;
//! - [`status`]: the state of a task, read from the cache;
//! - [`mode`]: what a run, a shard or `collect` covers, and what of it is left;
//! - [`label`]: what a task is called in the log and in `plan`.
//!
//! A block, here and in the cache, is one estimator on one DVL over every Monte Carlo
//! run: a task of the plan, stored as one Parquet file of its per-run rows.

pub mod label;
pub mod mode;
pub mod status;
pub mod task;

pub use mode::Mode;
pub use status::Status;
pub use task::{Dataset, MonteCarloBlock, PointPlan, Task, Training};

use super::cache::{self, BlockStore, DataHashes, ModelStore};
use crate::data::{Trajectory, load_trajectories};
use crate::estimators::{Requested, requested};
use crate::spec::{Experiment, Spec};
use crate::vocab::{ErrorModel, EstimatorKind};
use std::path::{Path, PathBuf};

/// Every task of an experiment, written to `out`.
pub struct Plan<'a> {
    pub experiment: &'a Experiment,
    pub out: PathBuf,
    pub trajectories: Vec<Vec<Trajectory>>,
    pub hashes: DataHashes,
    pub datasets: Vec<Dataset>,
    pub trainings: Vec<Training>,
    pub blocks: Vec<MonteCarloBlock>,
    pub points: Vec<PointPlan>,
    pub models: ModelStore,
    pub block_store: BlockStore,
    /// The spec file the experiment was read from, as its results folders record it
    /// (its path from `out`): a folder written from another file is not replaced
    /// without `--force`.
    pub spec_file: Option<String>,
}

#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    #[error(transparent)]
    Data(#[from] crate::data::DataError),
    #[error("reading a data file")]
    Hash(#[from] std::io::Error),
}

impl<'a> Plan<'a> {
    /// Lists the tasks of `experiment`; reads the data files, writes nothing.
    pub fn new(experiment: &'a Experiment, out: &Path) -> Result<Self, PlanError> {
        let trajectories = experiment
            .points
            .iter()
            .map(|p| load_trajectories(&p.spec))
            .collect::<Result<Vec<_>, _>>()?;
        let hashes = DataHashes::of(experiment.points.iter().map(|p| &p.spec))?;
        let cache = cache::root(out);
        let mut plan = Plan {
            experiment,
            out: out.to_path_buf(),
            trajectories,
            hashes,
            datasets: Vec::new(),
            trainings: Vec::new(),
            blocks: Vec::new(),
            points: Vec::new(),
            models: ModelStore::new(cache.join("models")),
            block_store: BlockStore::new(cache.join("monte_carlo")),
            spec_file: None,
        };
        for (p, point) in experiment.points.iter().enumerate() {
            plan.add_point(p, &point.spec);
        }
        Ok(plan)
    }

    /// Adds the tasks of point `p`, those another point already listed only by index.
    fn add_point(&mut self, p: usize, spec: &Spec) {
        let trainings = self.add_trainings(p, spec);
        let blocks = self.add_blocks(p, spec, &trainings);
        let block_keys: Vec<&str> = blocks
            .iter()
            .map(|&b| self.blocks[b].key.as_str())
            .collect();
        let results_key = cache::results_key(spec, &block_keys);
        self.points.push(PointPlan {
            folder: self.out.join(&spec.name),
            blocks,
            trainings,
            results_key,
        });
    }

    /// The dataset and the models of point `p` where it runs DCNet (none where it does
    /// not): the indices of its trainings, every replicate of an error model in a row.
    fn add_trainings(&mut self, p: usize, spec: &Spec) -> Vec<usize> {
        let mut trainings = Vec::new();
        if !spec.kinds.contains(&EstimatorKind::Dcnet) {
            return trainings;
        }
        let dataset_key = cache::dataset_key(spec, &self.hashes);
        let dataset = find_or_push(
            &mut self.datasets,
            |d| &d.key,
            &dataset_key,
            || Dataset {
                key: dataset_key.clone(),
                point: p,
            },
        );
        for &error_model in &spec.error_models {
            // Replicate 0 is pushed next, or was by an earlier point.
            let mut group = self.trainings.len();
            for replicate in 0..spec.training.replicates {
                let key = cache::model_key(spec, error_model, replicate, &dataset_key);
                let t = find_or_push(
                    &mut self.trainings,
                    |t| &t.key,
                    &key,
                    || Training {
                        key: key.clone(),
                        dataset,
                        point: p,
                        error_model,
                        replicate,
                        group,
                    },
                );
                if replicate == 0 {
                    group = self.trainings[t].group;
                }
                trainings.push(t);
            }
        }
        trainings
    }

    /// The Monte Carlo blocks of point `p`, one per DVL and requested method, in that
    /// order: their indices. `trainings` are the point's.
    fn add_blocks(&mut self, p: usize, spec: &Spec, trainings: &[usize]) -> Vec<usize> {
        let mut blocks = Vec::new();
        for dvl in 0..spec.dvls.len() {
            for Requested {
                kind: estimator,
                error_model,
                replicate,
            } in requested(spec)
            {
                let runs = self.models_of_block(trainings, estimator, error_model, replicate);
                let model_keys: Vec<&str> = runs
                    .iter()
                    .map(|&t| self.trainings[t].key.as_str())
                    .collect();
                let key =
                    cache::block_key(spec, &self.hashes, dvl, estimator, error_model, &model_keys);
                blocks.push(find_or_push(
                    &mut self.blocks,
                    |b| &b.key,
                    &key,
                    || MonteCarloBlock {
                        key: key.clone(),
                        point: p,
                        dvl,
                        estimator,
                        error_model,
                        replicate,
                        trainings: runs,
                    },
                ));
            }
        }
        blocks
    }

    /// Which of `trainings` the block of `estimator` runs: DCNet the model of its
    /// replicate, the ensemble every replicate of its error model, the others none.
    fn models_of_block(
        &self,
        trainings: &[usize],
        estimator: EstimatorKind,
        error_model: Option<ErrorModel>,
        replicate: Option<usize>,
    ) -> Vec<usize> {
        trainings
            .iter()
            .copied()
            .filter(|&t| {
                let training = &self.trainings[t];
                Some(training.error_model) == error_model
                    && match estimator {
                        EstimatorKind::Dcnet => training.replicate == replicate.unwrap_or(0),
                        EstimatorKind::DcnetEnsemble => true,
                        _ => false,
                    }
            })
            .collect()
    }

    pub fn spec(&self, point: usize) -> &'a Spec {
        &self.experiment.points[point].spec
    }

    /// Every task in the order a run does them.
    pub fn tasks(&self) -> Vec<Task> {
        let mut tasks: Vec<Task> = (0..self.datasets.len()).map(Task::Dataset).collect();
        tasks.extend((0..self.trainings.len()).map(Task::Training));
        tasks.extend((0..self.blocks.len()).map(Task::Block));
        tasks.extend((0..self.points.len()).map(Task::Results));
        if self.experiment.is_sweep() {
            tasks.push(Task::Sweep);
        }
        tasks
    }

    /// The point a task was planned from (the first of those that share it).
    pub fn point_of(&self, task: Task) -> Option<usize> {
        match task {
            Task::Dataset(d) => Some(self.datasets[d].point),
            Task::Training(t) => Some(self.trainings[t].point),
            Task::Block(b) => Some(self.blocks[b].point),
            Task::Results(p) => Some(p),
            Task::Sweep => None,
        }
    }

    /// The cache key of a task, where it has one.
    pub fn key(&self, task: Task) -> Option<&str> {
        match task {
            Task::Dataset(d) => Some(&self.datasets[d].key),
            Task::Training(t) => Some(&self.trainings[t].key),
            Task::Block(b) => Some(&self.blocks[b].key),
            Task::Results(p) => Some(&self.points[p].results_key),
            Task::Sweep => None,
        }
    }
}

/// The index of the item of `items` whose key is `key`, pushing `make()` when none is.
fn find_or_push<T>(
    items: &mut Vec<T>,
    key_of: impl Fn(&T) -> &String,
    key: &str,
    make: impl FnOnce() -> T,
) -> usize {
    items
        .iter()
        .position(|item| key_of(item) == key)
        .unwrap_or_else(|| {
            items.push(make());
            items.len() - 1
        })
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// quick.toml with `overrides`, as `run --set` reads it.
    pub(in crate::pipeline) fn experiment(overrides: &[&str]) -> Experiment {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quick.toml");
        let overrides: Vec<String> = overrides.iter().map(ToString::to_string).collect();
        crate::spec::load_experiment(&path, &overrides).unwrap()
    }

    #[test]
    fn an_item_with_the_key_is_found_and_a_new_key_is_pushed() {
        let mut items = vec!["a".to_string(), "b".to_string()];
        assert_eq!(find_or_push(&mut items, |s| s, "b", || unreachable!()), 1);
        assert_eq!(find_or_push(&mut items, |s| s, "c", || "c".to_string()), 2);
        assert_eq!(find_or_push(&mut items, |s| s, "c", || unreachable!()), 2);
        assert_eq!(items, ["a", "b", "c"]);
    }

    /// Two sweep points that differ in their epochs share the dataset and the blocks
    /// of the methods without a model, each listed once; each trains its own model and
    /// has its own DCNet blocks.
    #[test]
    fn tasks_that_sweep_points_share_are_planned_once() {
        let experiment = experiment(&[
            "estimators.kinds=[\"baseline\", \"dcnet\"]",
            "estimators.error_models=[\"EM5\"]",
            "sweep.values={\"training.epochs\" = [2, 3]}",
        ]);
        let out = tempfile::tempdir().unwrap();
        let plan = Plan::new(&experiment, out.path()).unwrap();
        assert_eq!(plan.points.len(), 2);
        assert_eq!(plan.datasets.len(), 1);
        assert_eq!(plan.trainings.len(), 2);
        assert_eq!(plan.points[0].trainings, [0]);
        assert_eq!(plan.points[1].trainings, [1]);
        // Point 0: DVL1 baseline, DVL1 DCNet, DVL2 baseline, DVL2 DCNet; point 1 reuses
        // the baselines and adds its own DCNet blocks.
        assert_eq!(plan.points[0].blocks, [0, 1, 2, 3]);
        assert_eq!(plan.points[1].blocks, [0, 4, 2, 5]);
        assert_eq!(plan.blocks[4].trainings, [1]);
        assert_eq!(plan.blocks[4].point, 1);
        assert_eq!(plan.blocks[2].point, 0);
        assert_ne!(plan.points[0].results_key, plan.points[1].results_key);
        // A dataset, two trainings, six blocks, two results folders and the sweep table.
        assert_eq!(plan.tasks().len(), 1 + 2 + 6 + 2 + 1);
        assert_eq!(plan.tasks().last(), Some(&Task::Sweep));
    }
}
