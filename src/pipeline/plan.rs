//! The plan: every task of an experiment (datasets, trainings, Monte Carlo blocks,
//! results folders, the sweep table), deduplicated by cache key, and the state of each
//! as the cache on disk tells it. In: the experiment and its trajectories. Out: the
//! tasks and what is left to do; nothing is written.

use super::cache::{self, BlockStore, DataHashes, ModelStore};
use super::shard::Shard;
use crate::data::{Trajectory, load_trajectories};
use crate::estimators::{Requested, requested};
use crate::files::Seal;
use crate::results::{self, Manifest, sweep};
use crate::spec::{Experiment, Spec};
use crate::vocab::{ErrorModel, EstimatorKind};
use std::path::{Path, PathBuf};

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

/// One estimator on one DVL, every Monte Carlo run.
pub struct Block {
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

/// The state of a task.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    Done,
    /// A training that failed (its loss diverged), or a block of its model: left out
    /// of the results until `--force` tries again.
    Failed,
    ToDo,
    /// A training with a checkpoint after this many epochs.
    Resumable(usize),
    /// A dataset no training left to do needs.
    NotNeeded,
    /// A model or block in the cache that fails its seal: it is set aside and
    /// computed again.
    Damaged,
}

impl Status {
    /// Whether there is nothing left to do: done, or failed for good.
    pub fn is_settled(self) -> bool {
        matches!(self, Status::Done | Status::Failed)
    }
}

impl std::fmt::Display for Status {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Status::Done => f.write_str("done"),
            Status::Failed => f.write_str("failed (--force tries again)"),
            Status::ToDo => f.write_str("to do"),
            Status::Resumable(epoch) => write!(f, "to do (resumes after epoch {epoch})"),
            Status::NotNeeded => f.write_str("not needed"),
            Status::Damaged => f.write_str("to do (damaged)"),
        }
    }
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

/// Every task of an experiment, written to `out`.
pub struct Plan<'a> {
    pub experiment: &'a Experiment,
    pub out: PathBuf,
    pub trajectories: Vec<Vec<Trajectory>>,
    pub hashes: DataHashes,
    pub datasets: Vec<Dataset>,
    pub trainings: Vec<Training>,
    pub blocks: Vec<Block>,
    pub points: Vec<PointPlan>,
    pub models: ModelStore,
    pub block_store: BlockStore,
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
        };
        for (p, point) in experiment.points.iter().enumerate() {
            plan.add_point(p, &point.spec);
        }
        Ok(plan)
    }

    fn add_point(&mut self, p: usize, spec: &Spec) {
        let dataset_key = cache::dataset_key(spec, &self.hashes);
        let mut trainings = Vec::new();
        if spec.kinds.contains(&EstimatorKind::Dcnet) {
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
        }
        let mut blocks = Vec::new();
        for dvl in 0..spec.dvls.len() {
            for Requested {
                kind: estimator,
                error_model,
                replicate,
            } in requested(spec)
            {
                let runs: Vec<usize> = trainings
                    .iter()
                    .copied()
                    .filter(|&t| {
                        let training = &self.trainings[t];
                        Some(training.error_model) == error_model
                            && match estimator {
                                EstimatorKind::Dcnet => {
                                    training.replicate == replicate.unwrap_or(0)
                                }
                                EstimatorKind::DcnetEnsemble => true,
                                _ => false,
                            }
                    })
                    .collect();
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
                    || Block {
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

    /// The tasks the shard computes: whole groups (a model's replicates, its blocks and
    /// their ensemble's), dealt out round-robin.
    pub fn in_shard(&self, task: Task, shard: Shard) -> bool {
        let group = match task {
            Task::Training(t) => self.trainings[t].group,
            Task::Block(b) => match self.blocks[b].trainings.first() {
                Some(&t) => self.trainings[t].group,
                None => {
                    self.trainings.len()
                        + self.blocks[..b]
                            .iter()
                            .filter(|other| other.trainings.is_empty())
                            .count()
                }
            },
            // Datasets go with the trainings that need them; results with collect.
            Task::Dataset(_) | Task::Results(_) | Task::Sweep => return false,
        };
        group % shard.count == shard.index
    }

    /// The state of `task` as the cache on disk tells it. Each call reads each file it
    /// needs once: a dataset's or a results folder's state asks its trainings once.
    pub fn status(&self, task: Task) -> Status {
        match task {
            Task::Dataset(d) => {
                let needed = self.trainings.iter().enumerate().any(|(t, training)| {
                    training.dataset == d && !self.training_status(t).is_settled()
                });
                if needed {
                    Status::ToDo
                } else {
                    Status::NotNeeded
                }
            }
            Task::Training(t) => self.training_status(t),
            Task::Block(b) => {
                let integrity = self.block_store.integrity(&self.blocks[b].key);
                if integrity == Seal::Intact {
                    Status::Done
                } else if matches!(integrity, Seal::Damaged(_)) {
                    Status::Damaged
                } else if self.runs_failed_model(b) {
                    Status::Failed
                } else {
                    Status::ToDo
                }
            }
            Task::Results(p) => {
                let point = &self.points[p];
                // Current: made from these blocks, every file as written, and the
                // reports and their figures there (a run killed before them, or whose
                // figures could not be written, writes them again).
                let current = read_manifest(&point.folder).is_some_and(|m| {
                    m.results_key == self.results_key(p) && results::is_intact(&point.folder, &m)
                }) && crate::report::is_complete(&point.folder);
                if current { Status::Done } else { Status::ToDo }
            }
            Task::Sweep => {
                let folder = self.out.join(&self.experiment.name);
                let stored = sweep::read_index(&folder).ok();
                let keys: Vec<String> = (0..self.points.len())
                    .map(|p| self.results_key(p))
                    .collect();
                if stored.is_some_and(|index| {
                    index.results_keys == keys && index.table_is_intact(&folder)
                }) {
                    Status::Done
                } else {
                    Status::ToDo
                }
            }
        }
    }

    /// The state of training `t`: its model stored, its failure recorded, a checkpoint
    /// to resume, or nothing yet.
    fn training_status(&self, t: usize) -> Status {
        let training = &self.trainings[t];
        let (model, key) = (training.error_model, &training.key);
        match self.models.integrity(model, key) {
            Seal::Intact => return Status::Done,
            Seal::Damaged(_) => return Status::Damaged,
            Seal::Absent => {}
        }
        if self.models.failure(model, key).is_some() {
            return Status::Failed;
        }
        match self.models.checkpoint_epoch(model, key) {
            Ok(Some(epoch)) => Status::Resumable(epoch),
            Ok(None) => Status::ToDo,
            Err(_) => Status::Damaged,
        }
    }

    /// The results key point `p`'s folder has when it is current: the plan's, marked
    /// with the models that failed and are left out.
    pub fn results_key(&self, p: usize) -> String {
        let point = &self.points[p];
        let failed: Vec<&str> = point
            .trainings
            .iter()
            .filter(|&&t| self.training_status(t) == Status::Failed)
            .map(|&t| self.trainings[t].key.as_str())
            .collect();
        if failed.is_empty() {
            return point.results_key.clone();
        }
        cache::hash(&(&point.results_key, "without", failed))
    }

    /// Why each failed training of the tasks `mode` covers failed, one line each.
    pub fn failures(&self, mode: Mode) -> Vec<String> {
        (0..self.trainings.len())
            .filter(|&t| match mode {
                Mode::Shard { shard, .. } => self.in_shard(Task::Training(t), shard),
                _ => true,
            })
            .filter_map(|t| {
                let training = &self.trainings[t];
                self.models.failure(training.error_model, &training.key)
            })
            .collect()
    }

    /// Whether block `b` runs a model whose training failed.
    pub(super) fn runs_failed_model(&self, b: usize) -> bool {
        self.blocks[b]
            .trainings
            .iter()
            .any(|&t| self.training_status(t) == Status::Failed)
    }

    /// What a task is, for people: "train DCNet EM5", "train DCNet EM5 replicate 2/3",
    /// "monte carlo DVL1 baseline".
    pub fn label(&self, task: Task) -> String {
        match task {
            Task::Dataset(_) => "generate dataset".into(),
            Task::Training(t) => {
                let training = &self.trainings[t];
                let replicates = self.spec(training.point).training.replicates;
                let label = format!("train DCNet {}", training.error_model);
                if replicates > 1 {
                    format!("{label} replicate {}/{replicates}", training.replicate + 1)
                } else {
                    label
                }
            }
            Task::Block(b) => {
                let block = &self.blocks[b];
                let dvl = &self.spec(block.point).dvls[block.dvl].name;
                let mut label = format!("monte carlo {dvl} {}", block.estimator);
                if let Some(m) = block.error_model {
                    label += &format!(" {m}");
                }
                if let Some(r) = block.replicate {
                    label += &format!(
                        " replicate {}/{}",
                        r + 1,
                        self.spec(block.point).training.replicates
                    );
                }
                label
            }
            Task::Results(_) if self.experiment.is_sweep() => "write results".into(),
            Task::Results(p) => format!("write {}", self.points[p].folder.display()),
            Task::Sweep => format!(
                "write {}",
                self.out
                    .join(&self.experiment.name)
                    .join(sweep::TABLE)
                    .display()
            ),
        }
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

fn read_manifest(folder: &Path) -> Option<Manifest> {
    let bytes = std::fs::read(folder.join(results::MANIFEST)).ok()?;
    serde_json::from_slice(&bytes).ok()
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

/// What [`execute`](super::execute) is asked to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Every task left.
    All { force: bool },
    /// The trainings and blocks of one shard, no results.
    Shard { shard: Shard, force: bool },
    /// Only the results folders, from a cache the shards have filled.
    Collect,
}

impl Mode {
    pub(super) fn force(self) -> bool {
        match self {
            Mode::All { force } | Mode::Shard { force, .. } => force,
            Mode::Collect => false,
        }
    }
}

impl Plan<'_> {
    /// The tasks `mode` does: those it covers that are not done (all it covers with
    /// `force`). A dataset counts when a training needs it.
    pub fn to_do(&self, mode: Mode) -> Vec<Task> {
        let covers = |task: Task| match (mode, task) {
            (_, Task::Dataset(_)) => false,
            (Mode::All { .. }, _) => true,
            (Mode::Shard { shard, .. }, _) => self.in_shard(task, shard),
            (Mode::Collect, task) => matches!(task, Task::Results(_) | Task::Sweep),
        };
        let mut tasks: Vec<Task> = self
            .tasks()
            .into_iter()
            .filter(|&task| covers(task) && (mode.force() || !self.status(task).is_settled()))
            .collect();
        let datasets: Vec<Task> = (0..self.datasets.len())
            .filter(|&d| {
                tasks.iter().any(
                    |task| matches!(task, Task::Training(t) if self.trainings[*t].dataset == d),
                )
            })
            .map(Task::Dataset)
            .collect();
        tasks.splice(0..0, datasets);
        tasks
    }
}
