//! Trained models on disk, under `results/<name>/models/`. A finished model is stored
//! at full precision as `<EM>-<key>.bin` (weights) and `<EM>-<key>.json` (history),
//! where the key is the hash of everything that determined it: the training, model
//! and dataset settings, the seed, the data the training windows were cut from, and
//! the training code version. A later run with the same key loads it instead of
//! training. While a model trains, a checkpoint in `<EM>-<key>.checkpoint/` is written
//! every few epochs, and an interrupted training resumes from it.

use crate::estimators::ErrorModel;
use crate::model::Dcnet;
use crate::results::write_atomic;
use crate::spec::{Origin, Spec};
use crate::train::{self, EpochRecord, State, Trained};
use burn::module::Module;
use burn::store::ModuleRecord;
use burn::tensor::{Bytes, Device};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Bumped whenever training changes in a way that changes the weights.
const TRAINING_CODE_VERSION: u32 = 1;

#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("{}: {message}", path.display())]
    Io { path: PathBuf, message: String },
}

fn io_error(path: &Path, error: impl std::fmt::Display) -> CheckpointError {
    CheckpointError::Io {
        path: path.to_path_buf(),
        message: error.to_string(),
    }
}

/// Everything a trained model depends on, hashed into its key.
#[derive(Serialize)]
struct KeyInputs<'a> {
    code: (u32, &'a str),
    error_model: String,
    seed: u64,
    model: &'a crate::spec::file::ModelFile,
    backend: &'a str,
    epochs: usize,
    batch_size: usize,
    learning_rate: f64,
    rmsprop: (f64, f64),
    sample_rate_hz: f64,
    ground_truth_window_samples: usize,
    sensors: &'a crate::spec::file::SensorsFile,
    grid: &'a crate::spec::file::GridFile,
    window_s: f64,
    stride_s: f64,
    validation_fraction: f64,
    /// Each training trajectory: name and where its samples come from.
    trajectories: Vec<(String, String)>,
}

/// The hash of the inputs of `error_model`'s training, in hex.
pub fn key(spec: &Spec, error_model: ErrorModel) -> Result<String, CheckpointError> {
    let resolved = &spec.resolved;
    let mut trajectories = Vec::new();
    for &index in &spec.dataset.trajectories {
        let source = &spec.trajectories[index];
        let origin = match &source.origin {
            Origin::File { path, samples } => {
                let bytes = std::fs::read(path).map_err(|e| io_error(path, e))?;
                format!(
                    "sha256 {} samples {samples:?}",
                    crate::data::fetch::sha256_hex(&bytes)
                )
            }
            Origin::Synthetic { samples } => {
                format!("synthetic {samples} {:?}", resolved.data.synthetic)
            }
        };
        trajectories.push((source.name.clone(), origin));
    }
    let inputs = KeyInputs {
        code: (TRAINING_CODE_VERSION, env!("CARGO_PKG_VERSION")),
        error_model: error_model.to_string(),
        seed: spec.seed,
        model: &resolved.model,
        backend: &resolved.training.backend,
        epochs: spec.training.epochs,
        batch_size: spec.training.batch_size,
        learning_rate: spec.training.learning_rate(error_model),
        rmsprop: (spec.training.rmsprop_alpha, spec.training.rmsprop_epsilon),
        sample_rate_hz: resolved.data.sample_rate_hz,
        ground_truth_window_samples: resolved.data.ground_truth_window_samples,
        sensors: &resolved.sensors,
        grid: &resolved.grid,
        window_s: resolved.dataset.window_s,
        stride_s: resolved.dataset.stride_s,
        validation_fraction: resolved.dataset.validation_fraction,
        trajectories,
    };
    let json = serde_json::to_string(&inputs).expect("key inputs serialize");
    Ok(crate::data::fetch::sha256_hex(json.as_bytes()))
}

/// What the `.json` beside a stored model holds.
#[derive(Serialize, Deserialize)]
struct Summary {
    key: String,
    error_model: String,
    best_epoch: usize,
    history: Vec<EpochRecord>,
}

/// What a checkpoint's `state.json` holds; the weight files carry the epoch in their name.
#[derive(Serialize, Deserialize)]
struct CheckpointState {
    epoch: usize,
    best_epoch: Option<usize>,
    best_score: Option<f64>,
    history: Vec<EpochRecord>,
}

/// The models folder of one run.
pub struct ModelStore {
    pub folder: PathBuf,
}

impl ModelStore {
    pub fn new(folder: PathBuf) -> Self {
        Self { folder }
    }

    fn stem(&self, error_model: ErrorModel, key: &str) -> PathBuf {
        self.folder.join(format!("{error_model}-{}", &key[..16]))
    }

    /// The stored model with this key, if there is one.
    pub fn load(
        &self,
        spec: &Spec,
        error_model: ErrorModel,
        key: &str,
    ) -> Result<Option<Trained>, CheckpointError> {
        let stem = self.stem(error_model, key);
        let summary_path = stem.with_extension("json");
        let Ok(text) = std::fs::read_to_string(&summary_path) else {
            return Ok(None);
        };
        let summary: Summary =
            serde_json::from_str(&text).map_err(|e| io_error(&summary_path, e))?;
        if summary.key != key {
            return Ok(None);
        }
        let model = read_model(
            &stem.with_extension("bin"),
            spec,
            error_model,
            &spec.training.backend.device(),
        )?;
        Ok(Some(Trained {
            error_model,
            model,
            history: summary.history,
            best_epoch: summary.best_epoch,
        }))
    }

    /// Stores a finished model and removes its checkpoint.
    pub fn save(&self, trained: &Trained, key: &str) -> Result<(), CheckpointError> {
        let stem = self.stem(trained.error_model, key);
        std::fs::create_dir_all(&self.folder).map_err(|e| io_error(&self.folder, e))?;
        write_model(&stem.with_extension("bin"), &trained.model)?;
        let summary = Summary {
            key: key.to_string(),
            error_model: trained.error_model.to_string(),
            best_epoch: trained.best_epoch,
            history: trained.history.clone(),
        };
        let path = stem.with_extension("json");
        write_atomic(
            &path,
            serde_json::to_string_pretty(&summary)
                .expect("summary serializes")
                .as_bytes(),
        )
        .map_err(|e| io_error(&path, e))?;
        let checkpoint = stem.with_extension("checkpoint");
        if checkpoint.exists() {
            std::fs::remove_dir_all(&checkpoint).map_err(|e| io_error(&checkpoint, e))?;
        }
        Ok(())
    }

    /// Writes the state after its last epoch as the checkpoint of `key`.
    pub fn save_checkpoint(
        &self,
        state: &State,
        error_model: ErrorModel,
        key: &str,
    ) -> Result<(), CheckpointError> {
        let folder = self.stem(error_model, key).with_extension("checkpoint");
        std::fs::create_dir_all(&folder).map_err(|e| io_error(&folder, e))?;
        let epoch = state.history.len();
        write_model(&folder.join(format!("epoch-{epoch}.model")), &state.model)?;
        let optimizer_path = folder.join(format!("epoch-{epoch}.optimizer"));
        let bytes = state
            .optimizer
            .into_bytes()
            .map_err(|e| io_error(&optimizer_path, format!("{e:?}")))?;
        write_atomic(&optimizer_path, &bytes).map_err(|e| io_error(&optimizer_path, e))?;
        if let Some((_, _, best)) = &state.best {
            write_model(&folder.join(format!("epoch-{epoch}.best")), best)?;
        }
        let record = CheckpointState {
            epoch,
            best_epoch: state.best.as_ref().map(|b| b.0),
            best_score: state.best.as_ref().map(|b| b.1),
            history: state.history.clone(),
        };
        let path = folder.join("state.json");
        write_atomic(
            &path,
            serde_json::to_string(&record)
                .expect("state serializes")
                .as_bytes(),
        )
        .map_err(|e| io_error(&path, e))?;
        // Older epochs are superseded once state.json names this one.
        for entry in std::fs::read_dir(&folder)
            .map_err(|e| io_error(&folder, e))?
            .flatten()
        {
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.starts_with("epoch-") && !name.starts_with(&format!("epoch-{epoch}.")) {
                std::fs::remove_file(entry.path()).map_err(|e| io_error(&entry.path(), e))?;
            }
        }
        Ok(())
    }

    /// The training state of the checkpoint of `key`, or a fresh one.
    pub fn resume(
        &self,
        spec: &Spec,
        error_model: ErrorModel,
        key: &str,
    ) -> Result<State, CheckpointError> {
        let folder = self.stem(error_model, key).with_extension("checkpoint");
        let state_path = folder.join("state.json");
        let Ok(text) = std::fs::read_to_string(&state_path) else {
            return Ok(State::new(spec, error_model));
        };
        let record: CheckpointState =
            serde_json::from_str(&text).map_err(|e| io_error(&state_path, e))?;
        let epoch = record.epoch;
        let device = spec.training.backend.device();
        let model = read_model(
            &folder.join(format!("epoch-{epoch}.model")),
            spec,
            error_model,
            &device.clone().autodiff(),
        )?;
        let optimizer_path = folder.join(format!("epoch-{epoch}.optimizer"));
        let bytes = std::fs::read(&optimizer_path).map_err(|e| io_error(&optimizer_path, e))?;
        let optimizer = train::optimizer(spec)
            .from_bytes(Bytes::from_bytes_vec(bytes))
            .map_err(|e| io_error(&optimizer_path, format!("{e:?}")))?;
        let best = match (record.best_epoch, record.best_score) {
            (Some(best_epoch), Some(score)) => Some((
                best_epoch,
                score,
                read_model(
                    &folder.join(format!("epoch-{epoch}.best")),
                    spec,
                    error_model,
                    &device,
                )?,
            )),
            _ => None,
        };
        Ok(State {
            model,
            optimizer,
            best,
            history: record.history,
        })
    }
}

/// How a model came to be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Provenance {
    Trained,
    /// Trained further from a checkpoint at this epoch.
    Resumed(usize),
    /// Loaded from the store without training.
    Reused,
}

/// Loads `error_model`'s stored model, or trains it (from its checkpoint if there is
/// one), checkpointing every `training.checkpoint_every_epochs` and storing the result.
pub fn train_cached(
    spec: &Spec,
    set: &crate::dataset::TrainingSet,
    error_model: ErrorModel,
    store: &ModelStore,
    progress: &indicatif::ProgressBar,
) -> Result<(Trained, Provenance), train::TrainError> {
    let key = key(spec, error_model)?;
    if let Some(trained) = store.load(spec, error_model, &key)? {
        return Ok((trained, Provenance::Reused));
    }
    let mut state = store.resume(spec, error_model, &key)?;
    let provenance = match state.history.len() {
        0 => Provenance::Trained,
        epoch => Provenance::Resumed(epoch),
    };
    progress.inc((state.history.len() * train::batches_per_epoch(spec, set)) as u64);
    while state.next_epoch() <= spec.training.epochs {
        train::run_epoch(spec, set, error_model, &mut state, progress)?;
        let epoch = state.history.len();
        if epoch % spec.training.checkpoint_every_epochs == 0 && epoch < spec.training.epochs {
            store.save_checkpoint(&state, error_model, &key)?;
        }
    }
    let trained = state.finish(error_model);
    store.save(&trained, &key)?;
    Ok((trained, provenance))
}

fn write_model(path: &Path, model: &Dcnet) -> Result<(), CheckpointError> {
    let bytes = model
        .clone()
        .into_record()
        .into_bytes()
        .map_err(|e| io_error(path, format!("{e:?}")))?;
    write_atomic(path, &bytes).map_err(|e| io_error(path, e))
}

fn read_model(
    path: &Path,
    spec: &Spec,
    error_model: ErrorModel,
    device: &Device,
) -> Result<Dcnet, CheckpointError> {
    let bytes = std::fs::read(path).map_err(|e| io_error(path, e))?;
    let record = ModuleRecord::from_bytes(Bytes::from_bytes_vec(bytes))
        .map_err(|e| io_error(path, format!("{e:?}")))?;
    // The skeleton's own weights are all overwritten by the record.
    let mut rng = crate::rng::task_rng(0, &[&"skeleton"]);
    let skeleton = Dcnet::new(
        &spec.model,
        error_model,
        spec.dataset.window,
        device,
        &mut rng,
    );
    skeleton
        .try_load_record(record)
        .map_err(|e| io_error(path, format!("{e:?}")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::quick_spec;
    use crate::train::tests::{run_epochs, training_set, weights};
    use indicatif::ProgressBar;

    #[test]
    fn a_training_resumed_from_a_checkpoint_ends_as_an_uninterrupted_one() {
        let spec = quick_spec(&["training.epochs=4"]);
        let set = training_set(&spec);
        let em = ErrorModel::Em5;

        let mut state = State::new(&spec, em);
        run_epochs(&spec, &set, em, &mut state, 4);
        let uninterrupted = state.finish(em);

        let dir = tempfile::tempdir().unwrap();
        let store = ModelStore::new(dir.path().to_path_buf());
        let key = key(&spec, em).unwrap();
        let mut state = State::new(&spec, em);
        run_epochs(&spec, &set, em, &mut state, 2);
        store.save_checkpoint(&state, em, &key).unwrap();
        drop(state);
        let mut resumed = store.resume(&spec, em, &key).unwrap();
        assert_eq!(resumed.next_epoch(), 3);
        run_epochs(&spec, &set, em, &mut resumed, 2);
        let resumed = resumed.finish(em);
        assert_eq!(resumed.best_epoch, uninterrupted.best_epoch);
        let losses = |t: &Trained| {
            t.history
                .iter()
                .map(|e| (e.train_loss, e.validation_loss))
                .collect::<Vec<_>>()
        };
        assert_eq!(losses(&resumed), losses(&uninterrupted));
        assert!(
            weights(&resumed.model) == weights(&uninterrupted.model),
            "resumed weights differ"
        );
    }

    #[test]
    fn stored_models_are_reused_and_keyed_by_their_training_inputs() {
        let spec = quick_spec(&["training.epochs=2"]);
        let set = training_set(&spec);
        let dir = tempfile::tempdir().unwrap();
        let store = ModelStore::new(dir.path().to_path_buf());
        let hidden = ProgressBar::hidden();
        let (first, provenance) =
            train_cached(&spec, &set, ErrorModel::Em4, &store, &hidden).unwrap();
        assert_eq!(provenance, Provenance::Trained);
        let (again, provenance) =
            train_cached(&spec, &set, ErrorModel::Em4, &store, &hidden).unwrap();
        assert_eq!(provenance, Provenance::Reused);
        assert!(weights(&again.model) == weights(&first.model));
        assert_eq!(again.history, first.history);

        // Monte Carlo and evaluation settings do not touch the key; training settings do.
        let key_of = |overrides: &[&str]| {
            key(
                &quick_spec(&[&["training.epochs=2"], overrides].concat()),
                ErrorModel::Em4,
            )
            .unwrap()
        };
        let base = key_of(&[]);
        assert_eq!(
            base,
            key_of(&[
                "calibration.monte_carlo_runs=3",
                "evaluation.trajectories=[\"S3\"]"
            ])
        );
        assert_eq!(
            base,
            key_of(&[
                "training.checkpoint_every_epochs=1",
                "training.learning_rate.EM5=1e-2"
            ])
        );
        for changed in [
            "training.learning_rate.EM4=1e-3",
            "training.batch_size=32",
            "model.dropout=0.1",
            "seed=8",
            "grid.noise_cm_s.values=[0.03]",
        ] {
            assert_ne!(base, key_of(&[changed]), "{changed} must change the key");
        }
    }
}
