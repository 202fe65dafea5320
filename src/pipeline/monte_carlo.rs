//! The Monte Carlo stage of a run: the blocks of one DVL computed together and
//! stored one by one, and a point's tables gathered back from the stored blocks.

use super::cache::ModelStoreError;
use super::plan::{Plan, Task};
use super::{ExecuteError, Executed};
use crate::bound::bounds;
use crate::estimators::set_up;
use crate::evaluate::terms_in_time::terms_in_time;
use crate::evaluate::{ProtocolResult, RunRow, run_on_dvl};
use crate::progress::Progress;
use crate::spec::Spec;
use crate::train::{Trained, TrainingHistory};
use crate::vocab::{EstimatorKind, Phase};

/// Computes the blocks `blocks` asks for, those of one DVL of one point together (they
/// share the measurements), and stores each as soon as its DVL is done. Blocks of a
/// model that failed to train are skipped.
pub(super) fn run(
    plan: &Plan,
    blocks: &[usize],
    executed: &mut Executed,
) -> Result<(), ExecuteError> {
    for (p, dvl, members) in group_by_dvl(plan, blocks) {
        for &b in &members {
            if let Some(damage) = plan.block_store.set_aside_damaged(&plan.blocks[b].key)? {
                eprintln!("{damage}");
            }
        }
        let spec = plan.spec(p);
        let dvl = &spec.dvls[dvl];
        let models = load_models(plan, spec, &members)?;
        // Each estimator with the block it computes.
        let (estimators, estimator_blocks): (Vec<_>, Vec<usize>) = set_up(spec, dvl, &models)
            .into_iter()
            .filter_map(|estimator| {
                let block = members.iter().copied().find(|&b| {
                    plan.blocks[b].estimator == estimator.kind
                        && plan.blocks[b].error_model == estimator.error_model
                        && plan.blocks[b].replicate == estimator.replicate
                });
                block.map(|b| (estimator, b))
            })
            .unzip();
        // Each run is a pass of calibration, then a pass of evaluation.
        let task = format!("monte carlo {} {}", spec.name, dvl.name);
        let progress = Progress::new(
            task.clone(),
            2 * spec.calibration.monte_carlo_runs,
            "passes",
        );
        let rows = run_on_dvl(spec, &plan.trajectories[p], dvl, &estimators, &progress);
        progress.finish();
        for (b, mut rows) in estimator_blocks.into_iter().zip(rows) {
            // A held-out curve may start where a method cannot yet estimate (one sample
            // for a scale and a bias); the tables' own rows must be finite.
            let tabled = |row: &&RunRow| row.phase != Phase::HeldOut;
            if let Some(row) = rows
                .iter()
                .filter(tabled)
                .find(|row| !row.rmse_cm_s.is_finite())
            {
                return Err(ExecuteError::NonFinite(describe(spec, row)));
            }
            // A block does not name its replicate (gather does), so replicate 0 shares
            // the block of a run without replicates.
            for row in &mut rows {
                row.replicate = None;
            }
            plan.block_store.save(&plan.blocks[b].key, &rows)?;
            executed.done += 1;
        }
        eprintln!(
            "{task}: {} × {} stored",
            crate::count(estimators.len(), "estimator"),
            crate::count(spec.calibration.monte_carlo_runs, "run")
        );
    }
    Ok(())
}

/// Where a Monte Carlo row came from: its point, DVL, estimator, run, and window or
/// trajectory.
fn describe(spec: &Spec, row: &RunRow) -> String {
    let estimator = match row.error_model {
        Some(error_model) => format!("{} {error_model}", row.estimator),
        None => row.estimator.to_string(),
    };
    format!(
        "{} {} {estimator}, Monte Carlo run {}, {} on {} ({} s window): RMSE {} cm/s",
        spec.name,
        row.dvl,
        row.run,
        row.phase.as_str(),
        row.trajectory,
        row.window_s,
        row.rmse_cm_s
    )
}

/// `blocks` grouped by point and DVL, in the order they first appear, without those
/// of a model that failed to train: (point, DVL, blocks).
fn group_by_dvl(plan: &Plan, blocks: &[usize]) -> Vec<(usize, usize, Vec<usize>)> {
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
    groups
}

/// The stored models that the DCNet blocks among `blocks` of `spec` run, each once, in
/// their order.
fn load_models(plan: &Plan, spec: &Spec, blocks: &[usize]) -> Result<Vec<Trained>, ExecuteError> {
    let trainings = crate::first_seen(
        blocks
            .iter()
            .flat_map(|&b| plan.blocks[b].trainings.iter().copied()),
    );
    let mut models = Vec::new();
    for t in trainings {
        let training = &plan.trainings[t];
        let model = plan
            .models
            .load(spec, training.error_model, &training.key)?
            .ok_or_else(|| ModelStoreError::NotStored {
                folder: plan.models.folder.clone(),
                task: plan.label(Task::Training(t)),
            })?;
        models.push(model);
    }
    Ok(models)
}

/// The tables of point `p` from the cache, and the summaries of its stored models.
/// Blocks whose model failed to train are left out.
pub(super) fn gather(
    plan: &Plan,
    p: usize,
) -> Result<(ProtocolResult, Vec<TrainingHistory>), ExecuteError> {
    let point = &plan.points[p];
    let mut models = Vec::new();
    for &t in &point.trainings {
        let training = &plan.trainings[t];
        if let Some(summary) = plan.models.history(training.error_model, &training.key)? {
            models.push(summary);
        }
    }
    let mut rows = Vec::new();
    for &b in &point.blocks {
        let block = &plan.blocks[b];
        if !plan.block_store.contains(&block.key) {
            continue;
        }
        // The replicate as this point counts them: a block may be shared with a point
        // without replicates.
        let replicate = (block.estimator == EstimatorKind::Dcnet
            && plan.spec(p).training.replicates > 1)
            .then(|| plan.trainings[block.trainings[0]].replicate);
        let block_rows = plan.block_store.load(&block.key)?;
        rows.extend(
            block_rows
                .into_iter()
                .map(|row| RunRow { replicate, ..row }),
        );
    }
    let bounds = bounds(plan.spec(p), &plan.trajectories[p]);
    let spec = plan.spec(p);
    let result = ProtocolResult {
        terms_in_time: terms_in_time(spec, &plan.trajectories[p]),
        ..ProtocolResult::from_runs(rows, &bounds, spec.calibration.time_tolerance)
    };
    Ok((result, models))
}
