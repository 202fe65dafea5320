//! The models of a study's `[learned]`: one per fold and source, each stored in the
//! cache under its own key (`OUT/.cache/learned/<source>-fold<k>-<key>.bin`, sealed), so
//! a later run, a shard or another point of a sweep with the same settings loads it
//! instead of training it. Trainings run one per core, each on one thread.
//! In: a point's spec, its segments and its recordings' SHA-256. Out: [`LearnedModels`].

use super::ExecuteError;
use crate::files::{self, Seal};
use crate::installation::learned::{LearnedWindows, training_windows};
use crate::installation::learned_spec::{LearnedSpec, TrainingSource};
use crate::installation::network::network_io;
use crate::installation::protocol::{LearnedModel, Segment, sample_interval};
use crate::installation::simulate::REFERENCE_MARGIN;
use crate::installation::spec::InstallationSpec;
use crate::installation::term_names::term_set;
use crate::model::Dcnet;
use crate::pipeline::cache::{self, models};
use crate::progress::Progress;
use crate::train::{self, Recipe, State};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// One model of `[learned]` and its cache key.
#[derive(Debug, Clone, PartialEq)]
pub struct LearnedKey {
    pub model: LearnedModel,
    pub key: String,
}

/// Every model a point's `[learned]` asks for, in fold, source, then replicate order.
pub fn keys(spec: &InstallationSpec, data_sha256: &[&str]) -> Vec<LearnedKey> {
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

fn path(out: &Path, key: &LearnedKey) -> PathBuf {
    let model = &key.model;
    out.join(".cache/learned").join(format!(
        "{}-fold{}-replicate{}-{}.bin",
        model.source.name(),
        model.fold + 1,
        model.replicate + 1,
        &key.key[..16]
    ))
}

/// The models of `keys`, each loaded from the cache under `out` or trained (and stored)
/// there; a damaged stored model is set aside and trained again.
pub fn train_or_load(
    spec: &InstallationSpec,
    segments: &[&Segment],
    keys: &[LearnedKey],
    out: &Path,
) -> Result<LearnedModels, ExecuteError> {
    let Some(learned) = &spec.learned else {
        return Ok(LearnedModels(Vec::new()));
    };
    // The loss reads the reference at t + τ within the window's margin.
    let step_s = segments
        .iter()
        .map(|s| sample_interval(&s.recording.time_s))
        .fold(f64::INFINITY, f64::min);
    let reach_s = REFERENCE_MARGIN as f64 * step_s;
    if learned.sources.contains(&TrainingSource::Simulated)
        && let Some(tau) = learned
            .simulation
            .time_offset_s
            .iter()
            .find(|t| t.abs() > reach_s)
    {
        return Err(ExecuteError::Learned {
            model: "learned.simulation.time_offset_s".into(),
            why: format!(
                "{tau} s is beyond the {reach_s} s at which the loss can read the reference ({REFERENCE_MARGIN} samples of {step_s} s): simulate time offsets within it"
            ),
        });
    }
    let store_error = |path: &Path| {
        let path = path.to_path_buf();
        move |error: models::ModelStoreError| ExecuteError::Learned {
            model: path.display().to_string(),
            why: error.to_string(),
        }
    };
    let one = |key: &LearnedKey| -> Result<Dcnet, ExecuteError> {
        let path = path(out, key);
        let device = learned.training.backend.device();
        let io = network_io(&term_set(&learned.terms));
        if let Some(said) = files::set_aside_if_damaged(
            &path,
            &key.key,
            &out.join(".cache/damaged"),
            "learned model",
        )
        .map_err(|source| ExecuteError::Io {
            path: path.clone(),
            source,
        })? {
            eprintln!("{said}");
        }
        if files::check_seal(&path, &key.key) == Seal::Intact {
            return models::read_model(&path, &learned.model, io, learned.window_samples, &device)
                .map_err(store_error(&path));
        }
        let model = train::one_thread_pool().install(|| train_one(spec, learned, segments, key))?;
        files::create_folder(path.parent().expect("a folder")).map_err(|source| {
            ExecuteError::Io {
                path: path.clone(),
                source,
            }
        })?;
        models::write_model(&path, &model, &key.key).map_err(store_error(&path))?;
        Ok(model)
    };
    // One worker per core takes the next model, so that no more training sets are in
    // memory than cores train (rayon would start every training while one waits).
    let next = AtomicUsize::new(0);
    let done: Mutex<Vec<Option<Result<Dcnet, ExecuteError>>>> =
        Mutex::new(keys.iter().map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..rayon::current_num_threads().min(keys.len()) {
            scope.spawn(|| {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(key) = keys.get(k) else { break };
                    let result = one(key);
                    done.lock().expect("no worker panicked")[k] = Some(result);
                }
            });
        }
    });
    let models = keys
        .iter()
        .cloned()
        .zip(done.into_inner().expect("no worker panicked"))
        .map(|(key, result)| Ok((key, result.expect("every key taken")?)))
        .collect::<Result<Vec<_>, ExecuteError>>()?;
    Ok(LearnedModels(models))
}

/// Trains the model of `key` on the windows of its fold and source: every epoch of
/// `learned.training` (or until early stopping), keeping the weights of the epoch with
/// the lowest validation loss.
fn train_one(
    spec: &InstallationSpec,
    learned: &LearnedSpec,
    segments: &[&Segment],
    key: &LearnedKey,
) -> Result<Dcnet, ExecuteError> {
    let clock = Instant::now();
    let LearnedModel {
        source,
        replicate,
        fold,
    } = key.model;
    let windows = training_windows(spec, learned, segments, fold, source);
    let name = format!("installation {} fold {}", source.name(), fold + 1);
    let shown = match replicate {
        0 => name.clone(),
        r => format!("{name} replicate {}", r + 1),
    };
    let recipe = Recipe {
        seed: learned.seed,
        model: &learned.model,
        training: &learned.training,
        learning_rate: learned.training.learning_rates[0],
        name,
        learning_rate_key: "learned.training.learning_rate".into(),
        validation_key: "learned.validation_fraction".into(),
    };
    let data = LearnedWindows {
        windows,
        terms: term_set(&learned.terms),
    };
    // The streams are named by source and fold; the replicate seeds them as the paper's.
    let mut state = State::of(
        &recipe,
        network_io(&data.terms),
        learned.window_samples,
        replicate,
    );
    let hidden = Progress::hidden();
    while state.stop(&learned.training).is_none() {
        train::run_epoch(&recipe, &data, &mut state, &hidden).map_err(|error| {
            ExecuteError::Learned {
                model: shown.clone(),
                why: error.to_string(),
            }
        })?;
    }
    let (best_epoch, best_loss, model) = state.best.expect("at least one epoch ran");
    eprintln!(
        "DCNet {shown}: {} windows, {} epochs, best {best_epoch} (validation loss {best_loss:.3} (cm/s)²), {:.1} s",
        data.windows.len(),
        state.history.len(),
        clock.elapsed().as_secs_f64()
    );
    Ok(model)
}
