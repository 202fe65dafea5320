//! The models of a study's `[learned]`: one per fold, source and replicate, each stored
//! in the [`ModelStore`] beside the paper's models under its own key
//! (`OUT/.cache/learned/<source>-fold<k>-replicate<r>-<key>.bin` and `.json`, sealed),
//! so that a later run, a shard or another point of a sweep with the same settings
//! loads it instead of training it. Those not stored train through the paper's
//! scheduler ([`crate::pipeline::training`]): the windows of a few (fold, source) pairs
//! at a time, their models interleaved epoch by epoch over the cores, each epoch on one
//! thread, checkpointed every `learned.training.checkpoint_every_epochs` so that a
//! killed run resumes them. `plan` lists them with their status ([`ModelRow`]).
//! In: a point's spec, its recordings and their SHA-256. Out: [`LearnedModels`].

use crate::files::Seal;
use crate::installation::learned::network::network_io;
use crate::installation::learned::spec::{LearnedSpec, TrainingSource};
use crate::installation::learned::{LearnedWindows, beyond_the_recordings, training_windows};
use crate::installation::study::spec::StudySpec;
use crate::installation::study::{LearnedModel, Recording};
use crate::installation::terms::names::term_set;
use crate::model::Dcnet;
use crate::pipeline::ExecuteError;
use crate::pipeline::Shard;
use crate::pipeline::cache::{self, Blueprint, ModelId, ModelStore};
use crate::pipeline::plan::status::{Status, model_status};
use crate::pipeline::study::StudyPlan;
use crate::pipeline::training::job::{ModelTask, Provenance, TrainingJob, TrainingJobError};
use crate::pipeline::training::{Ended, in_batches, interleave_epochs};
use crate::progress::Progress;
use crate::train::Recipe;
use rayon::prelude::*;
use std::path::Path;
use std::time::Instant;

/// One model of `[learned]` and its cache key.
#[derive(Debug, Clone, PartialEq)]
pub struct LearnedKey {
    pub model: LearnedModel,
    pub key: String,
}

/// Every model a point's `[learned]` asks for, in fold, source, then replicate order.
pub fn keys(spec: &StudySpec, data_sha256: &[&str]) -> Vec<LearnedKey> {
    let Some(learned) = &spec.learned else {
        return Vec::new();
    };
    let mut keys = Vec::new();
    for fold in 0..learned.folds {
        for &source in &learned.sources {
            for replicate in 0..learned.training.replicates.max(1) {
                let model = LearnedModel {
                    source,
                    replicate,
                    fold,
                };
                keys.push(LearnedKey {
                    model,
                    key: cache::learned_key(&spec.resolved_toml, data_sha256, &model),
                });
            }
        }
    }
    keys
}

/// A point's trained models.
pub struct LearnedModels(Vec<(LearnedKey, Dcnet)>);

impl LearnedModels {
    pub fn model(&self, model: LearnedModel) -> Option<&Dcnet> {
        self.0
            .iter()
            .find(|(key, _)| key.model == model)
            .map(|(_, dcnet)| dcnet)
    }
}

/// The store of the models under `out`: `[learned]`'s are in `.cache/learned/`.
pub fn store(out: &Path) -> ModelStore {
    ModelStore::new(cache::root(out).join("models"))
}

/// How `model` of `learned` trains: the paper's loop on the network of
/// `learned.terms`, its streams named by source and fold (the replicate seeds them as
/// the paper's).
fn blueprint(learned: &LearnedSpec, model: LearnedModel) -> Blueprint<'_> {
    Blueprint {
        recipe: Recipe {
            seed: learned.seed,
            model: &learned.model,
            training: &learned.training,
            learning_rate: learned.training.learning_rates[0],
            name: format!(
                "installation {} fold {}",
                model.source.name(),
                model.fold + 1
            ),
            learning_rate_key: "learned.training.learning_rate".into(),
            validation_key: "learned.validation_fraction".into(),
        },
        io: network_io(&term_set(&learned.terms)),
        window: learned.window_samples,
    }
}

/// The models of `keys`, each loaded from the store under `out` or trained (and stored)
/// there, resumed from its checkpoint where a killed run left one; a damaged stored
/// model or checkpoint is set aside and trained again.
pub fn train_or_load(
    spec: &StudySpec,
    recordings: &[&Recording],
    keys: &[LearnedKey],
    out: &Path,
) -> Result<LearnedModels, ExecuteError> {
    let Some(learned) = &spec.learned else {
        return Ok(LearnedModels(Vec::new()));
    };
    within_reach(learned, recordings)?;
    let store = store(out);
    let task = |k: usize| ModelTask {
        blueprint: blueprint(learned, keys[k].model),
        id: keys[k].model.into(),
        replicate: keys[k].model.replicate,
        key: &keys[k].key,
        store: &store,
    };
    let mut models = Vec::with_capacity(keys.len());
    for k in 0..keys.len() {
        let task = task(k);
        if let Some(damage) = store.set_aside_damaged(task.id, task.key)? {
            eprintln!("DCNet {}: {damage}", task.id);
        }
        models.push(store.load_or_set_aside(&task.blueprint, task.id, task.key)?);
    }
    let to_train: Vec<usize> = (0..keys.len()).filter(|&k| models[k].is_none()).collect();
    // Each model trained under its claim, as the paper's are: one that another process
    // sharing OUT is training is waited for and taken from the store.
    let key = |k: usize| keys[k].key.clone();
    let label = |k: usize| format!("DCNet {}", ModelId::from(keys[k].model));
    let settled = |k: usize| store.integrity(task(k).id, task(k).key) == Seal::Intact;
    crate::pipeline::claimed_then_left(out, &to_train, (key, label, settled), |ids| {
        for batch in in_batches(sets(learned, keys, ids)) {
            for (k, ended) in train_batch(spec, learned, recordings, &batch, &task) {
                let (stored, _) = ended.map_err(|source| ExecuteError::Training {
                    model: ModelId::from(keys[k].model).to_string(),
                    source,
                })?;
                models[k] = Some(*stored);
            }
        }
        Ok(())
    })?;
    for k in to_train {
        if models[k].is_none() {
            let task = task(k);
            models[k] = store.load_model(&task.blueprint, task.id, task.key)?;
        }
    }
    let models = keys.iter().cloned().zip(models);
    let models = models.map(|(key, stored)| (key, stored.expect("loaded or trained").model));
    Ok(LearnedModels(models.collect()))
}

/// The models of `ids` in the sets they train on, source by source, so that the models
/// that train together have sets of a size (a simulated set is hundreds of times a
/// vehicle's) and end together.
fn sets(
    learned: &LearnedSpec,
    keys: &[LearnedKey],
    ids: &[usize],
) -> Vec<((usize, TrainingSource), Vec<usize>)> {
    let mut sets = crate::first_seen(
        ids.iter()
            .map(|&k| (keys[k].model.fold, keys[k].model.source)),
    );
    sets.sort_by_key(|&(fold, source)| (learned.sources.iter().position(|&s| s == source), fold));
    sets.into_iter()
        .map(|set| {
            let mine = ids.iter().copied();
            let mine = mine.filter(|&k| (keys[k].model.fold, keys[k].model.source) == set);
            (set, mine.collect())
        })
        .collect()
}

/// Refuses what `[learned]` asks that the recordings cannot give
/// ([`beyond_the_recordings`]).
fn within_reach(learned: &LearnedSpec, recordings: &[&Recording]) -> Result<(), ExecuteError> {
    let recordings: Vec<(&str, &[f64])> = recordings
        .iter()
        .map(|s| (s.name.as_str(), s.recording.time_s.as_slice()))
        .collect();
    match beyond_the_recordings(learned, &recordings) {
        Some((model, why)) => Err(ExecuteError::Learned { model, why }),
        None => Ok(()),
    }
}

/// Trains the models of `batch` (each (fold, source) with the keys that train on its
/// windows) together, epoch by epoch; says how each trained one ended.
fn train_batch<'a>(
    spec: &StudySpec,
    learned: &LearnedSpec,
    recordings: &[&Recording],
    batch: &[((usize, TrainingSource), Vec<usize>)],
    task: &(dyn Fn(usize) -> ModelTask<'a> + Sync),
) -> Vec<(usize, Ended)> {
    let clock = Instant::now();
    let sets: Vec<LearnedWindows> = batch
        .par_iter()
        .map(|&((fold, source), _)| LearnedWindows {
            windows: training_windows(spec, learned, recordings, fold, source),
            terms: term_set(&learned.terms),
        })
        .collect();
    let set_of = |k: usize| {
        let i = batch.iter().position(|(_, mine)| mine.contains(&k));
        &sets[i.expect("every key has its set")]
    };
    let ids: Vec<usize> = batch
        .iter()
        .flat_map(|(_, mine)| mine.iter().copied())
        .collect();
    let bars = indicatif::MultiProgress::new();
    let announce = |k: usize, ended: &Ended| {
        if let Some(line) = describe(task(k).id, set_of(k).windows.len(), ended, clock) {
            eprintln!("{line}");
        }
    };
    interleave_epochs(&ids, announce, |k| {
        let task = task(k);
        let data = set_of(k);
        let samples_per_epoch = (0..data.windows.len())
            .filter(|&w| !data.windows.validation[w])
            .count();
        let epochs = task.blueprint.recipe.training.epochs;
        let progress = Progress::new(
            format!("train {}", task.id),
            epochs * samples_per_epoch,
            "samples",
        )
        .shown_in(&bars);
        let job = TrainingJob::start(&task, false).map_err(TrainingJobError::from);
        if let Ok(job) = &job {
            progress.set_position(job.epochs_done() * samples_per_epoch);
        }
        let run = move |job: TrainingJob, progress: &Progress| job.epoch(&task, data, progress);
        (job, run, progress)
    })
}

/// The line that says how model `id`, trained on `windows` windows, ended: none for a
/// model another run stored meanwhile, nor for a failure (the run stops with it).
fn describe(id: ModelId, windows: usize, ended: &Ended, clock: Instant) -> Option<String> {
    let (stored, provenance) = ended.as_ref().ok()?;
    let resumed = match provenance {
        Provenance::Reused => return None,
        Provenance::Trained => String::new(),
        Provenance::Resumed(epoch) => format!(", resumed after epoch {epoch}"),
    };
    let best = &stored.history[stored.best_epoch - 1];
    // Without validation windows the training loss chose the best epoch.
    let (which, loss) = match best.validation_loss.is_nan() {
        true => ("training", best.train_loss),
        false => ("validation", best.validation_loss),
    };
    Some(format!(
        "DCNet {id}: {windows} windows, {} epochs, best {} ({which} loss {loss:.3} (cm/s)²){resumed}, {:.1} s",
        stored.history.len(),
        stored.best_epoch,
        clock.elapsed().as_secs_f64()
    ))
}

/// One model of `[learned]` as `plan` lists it.
pub struct ModelRow {
    /// "train DCNet installation simulated fold 1", "… replicate 2/3", after its point
    /// in a sweep.
    pub label: String,
    pub key: String,
    pub status: Status,
}

impl StudyPlan<'_> {
    /// The models of `[learned]` that the points with a calibration in `shard` (every
    /// point without one) train, each once, fold by fold, with their status.
    pub fn learned_rows(&self, shard: Option<Shard>) -> Vec<ModelRow> {
        let points = crate::first_seen(
            (0..self.units.len())
                .filter(|&u| shard.is_none_or(|shard| self.in_shard(u, shard)))
                .map(|u| self.units[u].point),
        );
        let store = store(&self.out);
        let mut rows: Vec<ModelRow> = Vec::new();
        for p in points {
            let replicates = self
                .spec(p)
                .learned
                .as_ref()
                .map_or(1, |l| l.training.replicates);
            for key in &self.learned[p] {
                if rows.iter().any(|row| row.key == key.key) {
                    continue;
                }
                let LearnedModel {
                    source,
                    replicate,
                    fold,
                } = key.model;
                let mut label = format!(
                    "train DCNet installation {} fold {}",
                    source.name(),
                    fold + 1
                );
                if replicates > 1 {
                    label += &format!(" replicate {}/{replicates}", replicate + 1);
                }
                if self.experiment.is_sweep() {
                    let point = crate::results::sweep::point_folder(&self.spec(p).name);
                    label = format!("{point}: {label}");
                }
                let status = model_status(&store, key.model, &key.key);
                rows.push(ModelRow {
                    label,
                    key: key.key.clone(),
                    status,
                });
            }
        }
        rows
    }
}
