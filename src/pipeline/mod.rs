//! The one front door of a run, for either kind of spec: a spec is [`Planned`] as its
//! kind plans it, and [`execute`] does what a [`Mode`] asks of it (everything not
//! current, one shard's share, or `collect`), each result computed once into the
//! content-addressed [`cache`], then the results folders written, with one
//! [`Executed`] and one [`ExecuteError`] for both kinds. In: a checked experiment and an
//! output folder. Out: the results folders, every intermediate kept in the cache.
//!
//! - The paper's experiment: [`plan`] lists its tasks (for every point of the spec, a
//!   dataset, one DCNet training per error model, one Monte Carlo block per DVL ×
//!   estimator, the results folder), deduplicated by their cache key so that sweep
//!   points that share a model train it once; [`training`] trains the models (each
//!   model's [`TrainingJob`](training::job::TrainingJob) interleaved epoch by epoch) and
//!   [`monte_carlo`] runs the protocol.
//! - The installation study: [`study`] plans one calibration per point and
//!   trajectory and runs them.
//! - Shared by both: [`shard`], one machine's share (`--shard K/N`); [`cache`], the
//!   store of models, Monte Carlo blocks and calibrations; [`claim`], the locks that
//!   keep processes sharing a folder from computing the same task; [`owner`], whose a
//!   results folder is.
//!
//! A shard of the paper's experiment takes whole groups: a training with every block
//! that runs its model, or a block that needs no model. Groups are dealt out
//! round-robin in plan order, trainings first, so shards need nothing from each other
//! and each writes its own cache files.

pub mod cache;
pub mod claim;
pub mod error;
pub mod study;
pub mod monte_carlo;
pub mod owner;
pub mod plan;
pub mod training;
pub mod shard;

pub use error::ExecuteError;
pub use plan::{Mode, Plan, Status, Task};
pub use shard::Shard;
pub use study::StudyPlan;

use crate::results::{self, Manifest, RunRecord, StageSeconds, sweep};
use cache::Blueprint;
use std::path::PathBuf;
use std::time::{Instant, SystemTime};

/// A spec of either kind, planned: what goes through the one front door, [`execute`].
pub enum Planned<'a> {
    /// The paper's Monte Carlo experiment: datasets, DCNet trainings, Monte Carlo blocks
    /// and the results folders put together from them; `to_do` is what
    /// [`Plan::to_do`] gave for the mode, as the caller announced it (its status read
    /// once, each seal hashed once).
    Paper {
        plan: &'a Plan<'a>,
        to_do: &'a [Task],
    },
    /// The study of a real installation: a calibration on every paired recording, each
    /// scored on the others, and the results folders put together from them.
    Study(&'a StudyPlan<'a>),
}

/// What [`execute`] did.
#[derive(Debug, Default)]
pub struct Executed {
    /// Tasks computed or written (for an installation study: the calibrations computed
    /// here, not taken from the cache).
    pub done: usize,
    /// The results folders written, in spec order.
    pub written: Vec<PathBuf>,
    /// The sweep folder, when its table was written.
    pub sweep: Option<PathBuf>,
}

/// Does what `mode` asks of a planned spec of either kind: computes what the cache
/// lacks (all of it, or one shard's share), then writes the results folders that are
/// not current (not for a shard).
pub fn execute(planned: &Planned, mode: Mode) -> Result<Executed, ExecuteError> {
    match planned {
        Planned::Paper { plan, to_do } => execute_tasks(plan, mode, to_do),
        Planned::Study(plan) => plan.execute(mode),
    }
}

/// Does `to_do`, the tasks [`Plan::to_do`] gives for `mode`.
fn execute_tasks(plan: &Plan, mode: Mode, to_do: &[Task]) -> Result<Executed, ExecuteError> {
    let started_at = SystemTime::now();
    if !matches!(mode, Mode::Shard { .. }) {
        // Shards may be writing beside each other on other machines; a whole run or
        // collect has the folders to itself.
        remove_stale_partials(plan)?;
    }
    if mode == Mode::Collect {
        check_collectable(plan)?;
    }
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

    let mut executed = Executed::default();
    let mut stages = StageSeconds::default();
    // Each stage does the tasks it can claim, then those another process held that it
    // left undone; blocks start once every model they need is settled.
    let force = mode.force();
    plan_claimed_then_left(plan, &trainings, Task::Training, |ids| {
        training::train(plan, ids, force, &mut stages, &mut executed)
    })?;
    let clock = Instant::now();
    plan_claimed_then_left(plan, &blocks, Task::Block, |ids| {
        monte_carlo::run(plan, ids, &mut executed)
    })?;
    stages.protocol = clock.elapsed().as_secs_f64();
    if !matches!(mode, Mode::Shard { .. }) {
        write_results(plan, to_do, force, started_at, &stages, &mut executed)?;
    }
    Ok(executed)
}

/// Tidies the stored models before a plan's tasks are told, each under its training's
/// claim (a process holding it is finishing that model): removes the checkpoints that
/// kills left beside stored models, and sets aside a stored model whose seals hold but
/// whose bytes are no model of its spec (forged, or another build's), so that the plan
/// trains it again where it would stop the first block that runs it.
pub fn tidy_models(plan: &Plan) -> Result<(), ExecuteError> {
    for training in &plan.trainings {
        let (error_model, key) = (training.error_model, &training.key);
        let spent = plan.models.has_spent_checkpoint(error_model, key);
        let stored = plan.models.integrity(error_model, key) == crate::files::Seal::Intact;
        if !spent && !stored {
            continue;
        }
        let Some(_claim) = claim::try_claim(&plan.out, key).map_err(lock_error)? else {
            continue;
        };
        if spent {
            plan.models.remove_spent_checkpoint(error_model, key)?;
        }
        if stored {
            let blueprint = Blueprint::paper(plan.spec(training.point), error_model);
            plan.models
                .load_or_set_aside(&blueprint, error_model.into(), key)?;
        }
    }
    Ok(())
}

/// [`claimed_then_left`] on the tasks `task` makes of `ids`, keyed, named and settled
/// as `plan` has them.
fn plan_claimed_then_left(
    plan: &Plan,
    ids: &[usize],
    task: fn(usize) -> Task,
    work: impl FnMut(&[usize]) -> Result<(), ExecuteError>,
) -> Result<(), ExecuteError> {
    let key = |id: usize| {
        plan.key(task(id))
            .expect("computed tasks have keys")
            .to_string()
    };
    let label = |id: usize| plan.label(task(id));
    let settled = |id: usize| plan.status(task(id)).is_settled();
    claimed_then_left(&plan.out, ids, (key, label, settled), work)
}

/// Does `work` on `ids` in two passes, each holding the claims (under `out`) of its
/// tasks: first those it can claim at once, then those another process held, each
/// waited for and done only when that process left it unsettled. `(key, label,
/// settled)` give a task's claim key, its name for people, and whether it is settled.
pub(crate) fn claimed_then_left<K, L, S>(
    out: &std::path::Path,
    ids: &[usize],
    (key, label, settled): (K, L, S),
    mut work: impl FnMut(&[usize]) -> Result<(), ExecuteError>,
) -> Result<(), ExecuteError>
where
    K: Fn(usize) -> String,
    L: Fn(usize) -> String,
    S: Fn(usize) -> bool,
{
    let (claimed, busy) = claim::split(out, ids, &key).map_err(lock_error)?;
    let (now, claims): (Vec<usize>, Vec<claim::Claim>) = claimed.into_iter().unzip();
    work(&now)?;
    drop(claims);
    if busy.is_empty() {
        return Ok(());
    }
    eprintln!(
        "waiting for another process computing {} of these tasks ({}{})",
        busy.len(),
        label(busy[0]),
        if busy.len() > 1 { ", …" } else { "" }
    );
    let (mut left, mut claims) = (Vec::new(), Vec::new());
    for &id in &busy {
        let held = claim::claim(out, &key(id)).map_err(lock_error)?;
        if !settled(id) {
            left.push(id);
            claims.push(held);
        }
    }
    eprintln!(
        "the other process did {} of them; {} left to do here",
        busy.len() - left.len(),
        left.len()
    );
    work(&left)
}

/// An I/O error of the claims' locks, naming the lock file.
fn lock_error(error: claim::ClaimError) -> results::ResultsError {
    results::ResultsError::Io {
        path: error.path,
        source: error.source,
    }
}

/// Collect puts together what the shards computed: every training and block must be
/// settled first.
fn check_collectable(plan: &Plan) -> Result<(), ExecuteError> {
    let missing: Vec<String> = plan
        .tasks()
        .into_iter()
        .filter(|&t| matches!(t, Task::Training(_) | Task::Block(_)))
        .filter(|&t| !plan.status(t).is_settled())
        .map(|t| format!("  {}", plan.label(t)))
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    Err(ExecuteError::Incomplete {
        count: missing.len(),
        list: missing.join("\n"),
    })
}

/// Removes what an interrupted run left half-written in the experiment's folder and
/// the cache.
fn remove_stale_partials(plan: &Plan) -> Result<(), ExecuteError> {
    for folder in [plan.out.join(&plan.experiment.name), cache::root(&plan.out)] {
        crate::files::remove_stale_partials(&folder).map_err(|source| {
            results::ResultsError::Io {
                path: folder,
                source,
            }
        })?;
    }
    Ok(())
}

/// Writes the results folders and the sweep table that `to_do` asks for, from the
/// cache; with `force`, a folder that is current is written again.
fn write_results(
    plan: &Plan,
    to_do: &[Task],
    force: bool,
    started_at: SystemTime,
    stages: &StageSeconds,
    executed: &mut Executed,
) -> Result<(), ExecuteError> {
    let sweep_to_do = to_do.contains(&Task::Sweep);
    let mut points = Vec::new();
    for (p, point) in plan.points.iter().enumerate() {
        let results_to_do = to_do.contains(&Task::Results(p));
        if !results_to_do && !sweep_to_do {
            continue;
        }
        let (result, models) = monte_carlo::gather(plan, p)?;
        // Another process writing the same folder is waited for: its folder is kept
        // when it is this one's, refused when another spec wrote it.
        let _claim = claim::claim(&plan.out, &owner::folder_key(plan, p)).map_err(lock_error)?;
        if results_to_do {
            owner::check(&owner::Writer::point(plan, p, force))?;
        }
        if results_to_do && !force && plan.status(Task::Results(p)) == Status::Done {
            eprintln!(
                "{}: written by another process meanwhile",
                point.folder.display()
            );
        } else if results_to_do {
            let spec = plan.spec(p);
            let manifest = manifest(plan, p, started_at, stages);
            results::write_run(
                &point.folder,
                spec,
                &plan.trajectories[p],
                &result,
                &models,
                &manifest,
            )?;
            executed.done += 1;
            executed.written.push(point.folder.clone());
        }
        points.push((result, models));
    }
    if sweep_to_do {
        let folder = plan.out.join(&plan.experiment.name);
        let keys: Vec<String> = (0..plan.points.len())
            .map(|p| plan.results_key(p))
            .collect();
        sweep::write(&folder, plan.experiment, &points, &keys)?;
        executed.done += 1;
        executed.sweep = Some(folder);
    }
    Ok(())
}

/// The manifest of point `p`'s results folder.
fn manifest(plan: &Plan, p: usize, started_at: SystemTime, stages: &StageSeconds) -> Manifest {
    let spec = plan.spec(p);
    Manifest::of_run(RunRecord {
        name: spec.name.clone(),
        resolved_toml: &spec.resolved_toml(),
        started_at,
        backend: spec.training.backend.to_string(),
        data_files: plan.hashes.files_of(spec),
        stage_seconds: stages.clone(),
        results_key: plan.results_key(p),
        spec_file: plan.spec_file.clone().unwrap_or_default(),
    })
    .finished_now()
}
