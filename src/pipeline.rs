//! An experiment as a list of tasks: for every point of the spec (one, or one per
//! sweep point), a dataset, one DCNet training per error model, one Monte Carlo block
//! per DVL × estimator, and the results folder put together from them. Tasks are
//! deduplicated by their cache key ([`crate::cache`]), so sweep points that share a
//! model train it once; a task is done when its output is in the cache. [`Plan`] lists
//! the tasks and their state without touching anything; [`execute`] does what is left:
//! all of it, one shard's part (`--shard K/N`), or only the putting together
//! (`collect`).
//!
//! A shard takes whole groups: a training with every block that runs its model, or a
//! block that needs no model. Groups are dealt out round-robin in plan order, trainings
//! first, so shards need nothing from each other and each writes its own cache files.

use crate::cache::{self, BlockStore, DataHashes};
use crate::checkpoint::{ModelStore, Provenance, Stage, StageError, Summary};
use crate::data::{Trajectory, load_trajectories};
use crate::dataset::{self, TrainingSet};
use crate::estimators::{lineup, series};
use crate::evaluate::{ProtocolResult, run_block, summarize};
use crate::progress::bar;
use crate::results::{self, Manifest, StageSeconds};
use crate::spec::{Experiment, Spec};
use crate::sweep;
use crate::train::{self, Trained};
use crate::vocab::{ErrorModel, EstimatorKind, StopReason};
use indicatif::ProgressBar;
use std::path::{Path, PathBuf};
use std::time::{Instant, SystemTime};

/// A deterministic share of an experiment's tasks: shard `index` of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    /// Environment variables a job scheduler sets to the index of an array task.
    pub const INDEX_VARIABLES: [&str; 2] = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"];

    /// Reads `K/N`, or `N` with K from [`Self::INDEX_VARIABLES`] looked up in `env`.
    pub fn parse(text: &str, env: impl Fn(&str) -> Option<String>) -> Result<Shard, String> {
        let number = |part: &str, what: &str| {
            part.trim()
                .parse::<usize>()
                .map_err(|_| format!("--shard {text}: {what} {part:?} is not a whole number"))
        };
        let (index, count) = match text.split_once('/') {
            Some((index, count)) => (number(index, "shard index")?, number(count, "shard count")?),
            None => {
                let count = number(text, "shard count")?;
                let (variable, value) = Self::INDEX_VARIABLES
                    .iter()
                    .find_map(|v| env(v).map(|value| (*v, value)))
                    .ok_or_else(|| {
                        format!(
                            "--shard {text}: no shard index: write K/{text}, or set {}",
                            Self::INDEX_VARIABLES.join(" or ")
                        )
                    })?;
                let index = value.trim().parse::<usize>().map_err(|_| {
                    format!("--shard {text}: {variable}={value:?} is not a whole number")
                })?;
                (index, count)
            }
        };
        if count == 0 || index >= count {
            return Err(format!(
                "--shard {text}: shard {index} of {count} does not exist: K runs from 0 to N-1"
            ));
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

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
}

/// One estimator on one DVL, every Monte Carlo run.
pub struct Block {
    pub key: String,
    pub point: usize,
    pub dvl: usize,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    /// The training whose model it runs.
    pub training: Option<usize>,
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
    #[error("reading a data file: {0}")]
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
                let key = cache::model_key(spec, error_model, &dataset_key);
                trainings.push(find_or_push(
                    &mut self.trainings,
                    |t| &t.key,
                    &key,
                    || Training {
                        key: key.clone(),
                        dataset,
                        point: p,
                        error_model,
                    },
                ));
            }
        }
        let mut blocks = Vec::new();
        for dvl in 0..spec.dvls.len() {
            for (estimator, error_model) in series(spec) {
                let training = (estimator == EstimatorKind::Dcnet).then(|| {
                    let m = spec
                        .error_models
                        .iter()
                        .position(|&m| Some(m) == error_model);
                    trainings[m.expect("DCNet runs the spec's error models")]
                });
                let model_key = training.map(|t| self.trainings[t].key.as_str());
                let key =
                    cache::block_key(spec, &self.hashes, dvl, estimator, error_model, model_key);
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
                        training,
                    },
                ));
            }
        }
        let block_keys: Vec<&str> = blocks
            .iter()
            .map(|&b| self.blocks[b].key.as_str())
            .collect();
        let results_key = cache::hash(&(spec.resolved_toml(), block_keys));
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

    /// The tasks the shard computes: whole groups, dealt out round-robin.
    pub fn in_shard(&self, task: Task, shard: Shard) -> bool {
        let group = match task {
            Task::Training(t) => t,
            Task::Block(b) => match self.blocks[b].training {
                Some(t) => t,
                None => {
                    self.trainings.len()
                        + self.blocks[..b]
                            .iter()
                            .filter(|other| other.training.is_none())
                            .count()
                }
            },
            // Datasets go with the trainings that need them; results with collect.
            Task::Dataset(_) | Task::Results(_) | Task::Sweep => return false,
        };
        group % shard.count == shard.index
    }

    pub fn status(&self, task: Task) -> Status {
        match task {
            Task::Dataset(d) => {
                let needed = self.trainings.iter().enumerate().any(|(t, training)| {
                    training.dataset == d && !self.status(Task::Training(t)).is_settled()
                });
                if needed {
                    Status::ToDo
                } else {
                    Status::NotNeeded
                }
            }
            Task::Training(t) => {
                let training = &self.trainings[t];
                let (model, key) = (training.error_model, &training.key);
                if let Ok(Some(_)) = self.models.summary(model, key) {
                    Status::Done
                } else if self.models.failure(model, key).is_some() {
                    Status::Failed
                } else if let Some(epoch) = self.models.checkpoint_epoch(model, key) {
                    Status::Resumable(epoch)
                } else {
                    Status::ToDo
                }
            }
            Task::Block(b) => {
                if self.block_store.contains(&self.blocks[b].key) {
                    Status::Done
                } else if self.runs_failed_model(b) {
                    Status::Failed
                } else {
                    Status::ToDo
                }
            }
            Task::Results(p) => {
                let point = &self.points[p];
                let current = read_manifest(&point.folder)
                    .is_some_and(|m| m.results_key == self.results_key(p))
                    && results::TABLES
                        .iter()
                        .all(|table| point.folder.join(table).is_file());
                if current { Status::Done } else { Status::ToDo }
            }
            Task::Sweep => {
                let stored = sweep::read_index(&self.out.join(&self.experiment.name)).ok();
                let keys: Vec<String> = (0..self.points.len())
                    .map(|p| self.results_key(p))
                    .collect();
                if stored.is_some_and(|index| index.results_keys == keys) {
                    Status::Done
                } else {
                    Status::ToDo
                }
            }
        }
    }

    /// The results key point `p`'s folder has when it is current: the plan's, marked
    /// with the models that failed and are left out.
    pub fn results_key(&self, p: usize) -> String {
        let point = &self.points[p];
        let failed: Vec<&str> = point
            .trainings
            .iter()
            .filter(|&&t| self.status(Task::Training(t)) == Status::Failed)
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
    fn runs_failed_model(&self, b: usize) -> bool {
        self.blocks[b]
            .training
            .is_some_and(|t| self.status(Task::Training(t)) == Status::Failed)
    }

    /// What a task is, for people: "train DCNet EM5", "monte carlo DVL1 baseline".
    pub fn label(&self, task: Task) -> String {
        match task {
            Task::Dataset(_) => "generate dataset".into(),
            Task::Training(t) => format!("train DCNet {}", self.trainings[t].error_model),
            Task::Block(b) => {
                let block = &self.blocks[b];
                let dvl = &self.spec(block.point).dvls[block.dvl].name;
                match block.error_model {
                    Some(m) => format!("monte carlo {dvl} {} {m}", block.estimator),
                    None => format!("monte carlo {dvl} {}", block.estimator),
                }
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

/// What [`execute`] is asked to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Every task left.
    All { force: bool },
    /// The trainings and blocks of one shard, no results.
    Shard { shard: Shard, force: bool },
    /// Only the results folders, from a cache the shards have filled.
    Collect,
}

/// What [`execute`] did.
#[derive(Debug, Default)]
pub struct Outcome {
    /// Tasks computed or written.
    pub done: usize,
    /// The results folders written.
    pub written: Vec<PathBuf>,
    /// The sweep folder, when its `sweep.parquet` was written.
    pub sweep: Option<PathBuf>,
}

#[derive(Debug, thiserror::Error)]
pub enum ExecuteError {
    #[error(transparent)]
    Results(#[from] results::ResultsError),
    #[error(transparent)]
    Read(#[from] results::read::ReadError),
    #[error(transparent)]
    Checkpoint(#[from] crate::checkpoint::CheckpointError),
    #[error("{count} tasks are not done yet, so there is nothing to collect:\n{list}")]
    Incomplete { count: usize, list: String },
}

impl Mode {
    fn force(self) -> bool {
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

/// Does `to_do`, the tasks [`Plan::to_do`] gives for `mode`.
pub fn execute(plan: &Plan, mode: Mode, to_do: &[Task]) -> Result<Outcome, ExecuteError> {
    let started_at = SystemTime::now();
    if !matches!(mode, Mode::Shard { .. }) {
        // Shards may be writing beside each other on other machines; a whole run or
        // collect has the folders to itself.
        for folder in [plan.out.join(&plan.experiment.name), cache::root(&plan.out)] {
            crate::files::remove_stale_partials(&folder).map_err(|source| {
                results::ResultsError::Io {
                    path: folder.clone(),
                    source,
                }
            })?;
        }
    }
    let force = mode.force();
    let trainings: Vec<usize> = to_do
        .iter()
        .filter_map(|task| match task {
            Task::Training(t) => Some(*t),
            _ => None,
        })
        .collect();
    let blocks: Vec<usize> = to_do
        .iter()
        .filter_map(|task| match task {
            Task::Block(b) => Some(*b),
            _ => None,
        })
        .collect();
    if mode == Mode::Collect {
        let missing: Vec<Task> = plan
            .tasks()
            .into_iter()
            .filter(|&t| matches!(t, Task::Training(_) | Task::Block(_)))
            .filter(|&t| !plan.status(t).is_settled())
            .collect();
        if !missing.is_empty() {
            let list: Vec<String> = missing
                .iter()
                .map(|&t| format!("  {}", plan.label(t)))
                .collect();
            return Err(ExecuteError::Incomplete {
                count: missing.len(),
                list: list.join("\n"),
            });
        }
    }

    let mut outcome = Outcome::default();
    let mut stages = StageSeconds::default();
    train(plan, &trainings, force, &mut stages, &mut outcome)?;
    let clock = Instant::now();
    monte_carlo(plan, &blocks, &mut outcome)?;
    stages.protocol = clock.elapsed().as_secs_f64();
    if matches!(mode, Mode::Shard { .. }) {
        return Ok(outcome);
    }

    let sweep_to_do = to_do.contains(&Task::Sweep);
    let mut summaries = Vec::new();
    for (p, point) in plan.points.iter().enumerate() {
        let results_to_do = to_do.contains(&Task::Results(p));
        if !results_to_do && !sweep_to_do {
            continue;
        }
        let (result, models) = gather(plan, p)?;
        if results_to_do {
            let spec = plan.spec(p);
            let manifest = Manifest {
                name: spec.name.clone(),
                spec_sha256: crate::files::sha256_hex(spec.resolved_toml().as_bytes()),
                git_commit: env!("DCNET_GIT_COMMIT").to_string(),
                crate_version: env!("CARGO_PKG_VERSION").to_string(),
                started_at: humantime::format_rfc3339_seconds(started_at).to_string(),
                finished_at: humantime::format_rfc3339_seconds(SystemTime::now()).to_string(),
                threads: rayon::current_num_threads(),
                backend: spec.training.backend.to_string(),
                host: gethostname::gethostname().to_string_lossy().into_owned(),
                data_files: plan.hashes.files_of(spec),
                stage_seconds: stages.clone(),
                results_key: plan.results_key(p),
            };
            results::write_run(
                &point.folder,
                spec,
                &plan.trajectories[p],
                &result,
                &models,
                &manifest,
            )?;
            outcome.done += 1;
            outcome.written.push(point.folder.clone());
        }
        summaries.push((result, models));
    }
    if sweep_to_do {
        let folder = plan.out.join(&plan.experiment.name);
        let keys: Vec<String> = (0..plan.points.len())
            .map(|p| plan.results_key(p))
            .collect();
        sweep::write(&folder, plan.experiment, &summaries, &keys)?;
        outcome.done += 1;
        outcome.sweep = Some(folder);
    }
    Ok(outcome)
}

/// Trains the models `trainings` asks for; a model whose training fails is recorded as
/// failed in the store, and the others go on. Datasets are generated a few at a time,
/// enough that every thread has a model to train, and the models of those datasets then
/// train together, epoch by epoch ([`interleave_epochs`]); only those datasets are held
/// in memory.
fn train(
    plan: &Plan,
    trainings: &[usize],
    force: bool,
    stages: &mut StageSeconds,
    outcome: &mut Outcome,
) -> Result<(), ExecuteError> {
    let mut batches: Vec<Vec<(usize, Vec<usize>)>> = vec![Vec::new()];
    for d in 0..plan.datasets.len() {
        let mine: Vec<usize> = trainings
            .iter()
            .copied()
            .filter(|&t| plan.trainings[t].dataset == d)
            .collect();
        if mine.is_empty() {
            continue;
        }
        let last = batches.last_mut().expect("never empty");
        if last.iter().map(|(_, m)| m.len()).sum::<usize>() >= rayon::current_num_threads() {
            batches.push(vec![(d, mine)]);
        } else {
            last.push((d, mine));
        }
    }
    for batch in batches.into_iter().filter(|b| !b.is_empty()) {
        let sets: Vec<(usize, TrainingSet)> = batch
            .iter()
            .map(|&(d, _)| (d, generate_dataset(plan, d, stages)))
            .collect();
        outcome.done += sets.len();
        let set_of = |t: usize| {
            let dataset = plan.trainings[t].dataset;
            &sets
                .iter()
                .find(|(d, _)| *d == dataset)
                .expect("generated")
                .1
        };
        let mine: Vec<usize> = batch.iter().flat_map(|(_, m)| m.iter().copied()).collect();
        let clock = Instant::now();
        let bars = indicatif::MultiProgress::new();
        let results = interleave_epochs(&mine, |t| {
            let training = &plan.trainings[t];
            let spec = plan.spec(training.point);
            let set = set_of(t);
            let progress = bars.add(bar(
                spec.training.epochs * train::batches_per_epoch(spec, set),
                "DCNet",
            ));
            progress.set_message(format!("DCNet {}", training.error_model));
            let run = move |job: Stage, progress: &indicatif::ProgressBar| {
                job.epoch(
                    spec,
                    set,
                    training.error_model,
                    &training.key,
                    &plan.models,
                    progress,
                )
            };
            let job = Stage::start(
                spec,
                training.error_model,
                &training.key,
                &plan.models,
                force,
            )
            .map_err(StageError::from);
            if let Ok(job) = &job {
                progress
                    .set_position((job.epochs_done() * train::batches_per_epoch(spec, set)) as u64);
            }
            (job, run, progress)
        });
        stages.training += clock.elapsed().as_secs_f64();
        let mut storage_error = None;
        for (t, result) in results {
            match result {
                Ok((model, provenance)) => {
                    let model = *model;
                    let best = &model.history[model.best_epoch - 1];
                    let how = match provenance {
                        Provenance::Trained => "trained".to_string(),
                        Provenance::Resumed(epoch) => {
                            format!("resumed from the checkpoint of epoch {epoch}")
                        }
                        Provenance::Reused => "reused".to_string(),
                    };
                    let stopped = match model.stop {
                        StopReason::AllEpochs => String::new(),
                        StopReason::EarlyStopping => ", stopped early".to_string(),
                    };
                    eprintln!(
                        "DCNet {} {}: {how}; best validation loss {:.4} (cm/s)² at epoch {} of {}{stopped}",
                        model.error_model,
                        &plan.trainings[t].key[..16],
                        best.validation_loss,
                        model.best_epoch,
                        model.history.len()
                    );
                    outcome.done += 1;
                }
                // The other models' outcomes are still recorded before this is returned.
                Err(StageError::Store(error)) => {
                    storage_error.get_or_insert(error);
                }
                Err(error) => {
                    let training = &plan.trainings[t];
                    plan.models.save_failure(
                        training.error_model,
                        &training.key,
                        &error.to_string(),
                    )?;
                }
            }
        }
        if let Some(error) = storage_error {
            return Err(error.into());
        }
    }
    Ok(())
}

/// How one training ended: its model and where it came from, or the error that ended it.
type Ended = Result<(Box<Trained>, Provenance), StageError>;

/// One training's next epoch: its current stage in, its next stage out.
type EpochStep<'a> =
    Box<dyn Fn(Stage, &ProgressBar) -> Result<Stage, StageError> + Send + Sync + 'a>;

/// Runs every training of `ids` to its end, epoch by epoch, on
/// `rayon::current_num_threads()` workers. `start` gives each id its first stage, the
/// step that trains one epoch, and its progress bar. A worker takes the training at
/// the head of the queue, trains its next epoch and puts it back at the tail, so that
/// every core trains while at least as many trainings as cores are left, and the models
/// advance together. Each worker runs its epochs on [`train::one_thread_pool`], so a
/// model computes the same bytes whichever worker, and however many, train it. Returns
/// each id's trained model or the error that ended it.
fn interleave_epochs<'a, F, S>(ids: &[usize], start: S) -> Vec<(usize, Ended)>
where
    S: Fn(usize) -> (Result<Stage, StageError>, F, ProgressBar),
    F: Fn(Stage, &ProgressBar) -> Result<Stage, StageError> + Send + Sync + 'a,
{
    let queue = std::sync::Mutex::new(std::collections::VecDeque::new());
    let finished = std::sync::Mutex::new(Vec::new());
    // A running training goes to the tail of the queue; an ended one is finished.
    let place =
        |id, outcome: Result<Stage, StageError>, step: EpochStep<'a>, progress: ProgressBar| {
            let ended = match outcome {
                Ok(Stage::Done(trained, provenance)) => Ok((trained, provenance)),
                Ok(running) => {
                    let mut queue = queue.lock().expect("no worker panics");
                    queue.push_back((id, running, step, progress));
                    return;
                }
                Err(error) => Err(error),
            };
            progress.finish_and_clear();
            finished.lock().expect("no worker panics").push((id, ended));
        };
    for &id in ids {
        let (stage, step, progress) = start(id);
        place(id, stage, Box::new(step), progress);
    }
    let workers = rayon::current_num_threads().min(ids.len()).max(1);
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| {
                let pool = train::one_thread_pool();
                // The queue only shrinks while this worker is away: every training
                // not in it is held by a worker that will carry on with it.
                loop {
                    let next = queue.lock().expect("no worker panics").pop_front();
                    let Some((id, stage, step, progress)) = next else {
                        break;
                    };
                    let outcome = pool.install(|| step(stage, &progress));
                    place(id, outcome, step, progress);
                }
            });
        }
    });
    let mut finished = finished.into_inner().expect("no worker panics");
    finished.sort_by_key(|(id, _)| *id);
    finished
}

/// Generates dataset `d` from the spec of its first point.
fn generate_dataset(plan: &Plan, d: usize, stages: &mut StageSeconds) -> TrainingSet {
    let dataset = &plan.datasets[d];
    let spec = plan.spec(dataset.point);
    let clock = Instant::now();
    let progress = bar(spec.grid.points().len(), "dataset");
    let set = dataset::generate(spec, &plan.trajectories[dataset.point], &progress);
    progress.finish_and_clear();
    stages.dataset += clock.elapsed().as_secs_f64();
    eprintln!(
        "dataset {}: {} combinations × {} windows = {} windows ({} validation), {:.1} MB, in {:.2} s",
        &dataset.key[..16],
        set.points.len(),
        set.windows_per_combination,
        set.len(),
        set.validation_len(),
        TrainingSet::size_bytes(set.len(), set.window) as f64 / 1e6,
        clock.elapsed().as_secs_f64()
    );
    set
}

/// Computes the blocks `blocks` asks for, those of one DVL of one point together (they
/// share the measurements), and stores each as soon as its DVL is done. Blocks of a
/// model that failed to train are skipped.
fn monte_carlo(plan: &Plan, blocks: &[usize], outcome: &mut Outcome) -> Result<(), ExecuteError> {
    let mut groups: Vec<(usize, usize, Vec<usize>)> = Vec::new();
    for &b in blocks {
        let block = &plan.blocks[b];
        if plan.runs_failed_model(b) {
            continue;
        }
        match groups
            .iter_mut()
            .find(|(p, dvl, _)| *p == block.point && *dvl == block.dvl)
        {
            Some((_, _, members)) => members.push(b),
            None => groups.push((block.point, block.dvl, vec![b])),
        }
    }
    for (p, dvl, members) in groups {
        let spec = plan.spec(p);
        let dvl = &spec.dvls[dvl];
        let mut models = Vec::new();
        for &b in &members {
            if let Some(t) = plan.blocks[b].training {
                let training = &plan.trainings[t];
                let model = plan
                    .models
                    .load(spec, training.error_model, &training.key)?
                    .ok_or_else(|| crate::checkpoint::CheckpointError::Io {
                        path: plan.models.folder.clone(),
                        message: format!(
                            "the model of {} is not stored",
                            plan.label(Task::Training(t))
                        ),
                    })?;
                models.push(model);
            }
        }
        // Each entry with the block it computes.
        let (entries, entry_blocks): (Vec<_>, Vec<usize>) = lineup(spec, dvl, &models)
            .into_iter()
            .filter_map(|entry| {
                let block = members.iter().copied().find(|&b| {
                    plan.blocks[b].estimator == entry.kind
                        && plan.blocks[b].error_model == entry.error_model
                });
                block.map(|b| (entry, b))
            })
            .unzip();
        let progress = bar(2 * spec.calibration.monte_carlo_runs, "monte carlo");
        let rows = run_block(spec, &plan.trajectories[p], dvl, &entries, &progress);
        progress.finish_and_clear();
        for (b, rows) in entry_blocks.into_iter().zip(rows) {
            plan.block_store.save(&plan.blocks[b].key, &rows)?;
            outcome.done += 1;
        }
        eprintln!(
            "monte carlo {} {}: {} estimators × {} runs stored",
            spec.name,
            dvl.name,
            entries.len(),
            spec.calibration.monte_carlo_runs
        );
    }
    Ok(())
}

/// The tables of point `p` from the cache, and the summaries of its stored models.
/// Blocks whose model failed to train are left out.
fn gather(plan: &Plan, p: usize) -> Result<(ProtocolResult, Vec<Summary>), ExecuteError> {
    let point = &plan.points[p];
    let mut models = Vec::new();
    for &t in &point.trainings {
        let training = &plan.trainings[t];
        if let Some(summary) = plan.models.summary(training.error_model, &training.key)? {
            models.push(summary);
        }
    }
    let mut rows = Vec::new();
    for &b in &point.blocks {
        let block = &plan.blocks[b];
        if !plan.block_store.contains(&block.key) {
            continue;
        }
        let block_rows = plan.block_store.load(&block.key)?;
        rows.extend(block_rows);
    }
    Ok((summarize(rows), models))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_come_from_the_argument_or_the_scheduler() {
        let none = |_: &str| None;
        assert_eq!(Shard::parse("2/3", none), Ok(Shard { index: 2, count: 3 }));
        let slurm = |v: &str| (v == "SLURM_ARRAY_TASK_ID").then(|| "1".to_string());
        assert_eq!(Shard::parse("4", slurm), Ok(Shard { index: 1, count: 4 }));
        let kubernetes = |v: &str| (v == "JOB_COMPLETION_INDEX").then(|| "0".to_string());
        assert_eq!(
            Shard::parse("2", kubernetes),
            Ok(Shard { index: 0, count: 2 })
        );
        assert_eq!(
            Shard::parse("3/3", none).unwrap_err(),
            "--shard 3/3: shard 3 of 3 does not exist: K runs from 0 to N-1"
        );
        assert_eq!(
            Shard::parse("4", none).unwrap_err(),
            "--shard 4: no shard index: write K/4, or set SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX"
        );
        assert!(
            Shard::parse("a/2", none)
                .unwrap_err()
                .contains("\"a\" is not a whole number")
        );
    }
}
