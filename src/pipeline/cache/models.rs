//! Trained models on disk, under `OUT/.cache/models/`. A finished model is stored at
//! full precision as `<EM>-<key>.bin` (weights) and `<EM>-<key>.json` (history), where
//! the key, made by the content-addressed cache, is the hash of everything that
//! determined it. A later run with the same key loads it instead of training. While a
//! model trains, a checkpoint in `<EM>-<key>.checkpoint/` is written every few epochs,
//! and an interrupted training resumes from it. [`Stage`] walks one model through this an
//! epoch at a time, so that the pipeline can interleave the epochs of many models.

use crate::files::{self, Seal, write_atomic};
use crate::model::Dcnet;
use crate::spec::Spec;
use crate::train::{self, EpochRecord, State, Trained, TrainingHistory};
use crate::vocab::ErrorModel;
use burn::module::Module;
use burn::store::{ModuleRecord, RecordError};
use burn::tensor::{Bytes, Device};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("{}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}", path.display())]
    Json {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
    #[error("{}", path.display())]
    Record {
        path: PathBuf,
        #[source]
        source: RecordError,
    },
    #[error("{}: the model of {task} is not stored", folder.display())]
    NotStored { folder: PathBuf, task: String },
}

fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> CheckpointError {
    let path = path.to_path_buf();
    |source| CheckpointError::Io { path, source }
}

fn json_error(path: &Path) -> impl FnOnce(serde_json::Error) -> CheckpointError {
    let path = path.to_path_buf();
    |source| CheckpointError::Json { path, source }
}

fn record_error(path: &Path) -> impl FnOnce(RecordError) -> CheckpointError {
    let path = path.to_path_buf();
    |source| CheckpointError::Record { path, source }
}

/// What a checkpoint's `state.json` holds, below its inline seal; the weight files carry
/// the epoch in their name.
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

    /// Whether the stored model of `key`, weights and history, is there and has the
    /// bytes its seals name.
    pub fn integrity(&self, error_model: ErrorModel, key: &str) -> Seal {
        let stem = self.stem(error_model, key);
        let [weights, history] = ["bin", "json"].map(|ext| {
            let path = stem.with_extension(ext);
            (files::check_seal(&path, key), path)
        });
        match (weights, history) {
            ((Seal::Absent, _), (Seal::Absent, _)) => Seal::Absent,
            ((Seal::Intact, _), (Seal::Intact, _)) => Seal::Intact,
            ((Seal::Damaged(why), path), _) | (_, (Seal::Damaged(why), path)) => {
                Seal::Damaged(format!("{}: {why}", path.display()))
            }
            ((Seal::Absent, path), _) | (_, (Seal::Absent, path)) => Seal::Damaged(format!(
                "{}: it is missing beside the rest of the model",
                path.display()
            )),
        }
    }

    /// Moves a damaged stored model of `key` into the cache's `damaged/` folder, so that
    /// it is trained again; returns what was wrong with it.
    pub fn set_aside_damaged(
        &self,
        error_model: ErrorModel,
        key: &str,
    ) -> Result<Option<String>, CheckpointError> {
        let Seal::Damaged(why) = self.integrity(error_model, key) else {
            return Ok(None);
        };
        let damaged = self.folder.with_file_name("damaged");
        let stem = self.stem(error_model, key);
        for ext in ["bin", "json"] {
            let path = stem.with_extension(ext);
            files::set_aside(&path, &damaged).map_err(io_error(&path))?;
        }
        Ok(Some(format!(
            "damaged model {why}; moved to {} and trained again",
            damaged.display()
        )))
    }

    /// How the stored model with this key trained, if there is one and it is intact.
    pub fn history(
        &self,
        error_model: ErrorModel,
        key: &str,
    ) -> Result<Option<TrainingHistory>, CheckpointError> {
        if self.integrity(error_model, key) != Seal::Intact {
            return Ok(None);
        }
        let path = self.stem(error_model, key).with_extension("json");
        let Ok(text) = std::fs::read_to_string(&path) else {
            return Ok(None);
        };
        let history: TrainingHistory = serde_json::from_str(&text).map_err(json_error(&path))?;
        Ok((history.key == key).then_some(history))
    }

    /// Records that the training of `key` failed and why, so that later runs and
    /// `collect` leave the model out instead of training it again.
    pub fn save_failure(
        &self,
        error_model: ErrorModel,
        key: &str,
        message: &str,
    ) -> Result<(), CheckpointError> {
        std::fs::create_dir_all(&self.folder).map_err(io_error(&self.folder))?;
        let path = self.stem(error_model, key).with_extension("failed");
        let sealed = files::inline_sealed(message.as_bytes(), key);
        write_atomic(&path, &sealed).map_err(io_error(&path))
    }

    /// Removes the checkpoint of `key` once its model is stored whole, as saving does,
    /// and as a kill between the two leaves undone; returns whether there was one.
    pub fn remove_spent_checkpoint(
        &self,
        error_model: ErrorModel,
        key: &str,
    ) -> Result<bool, CheckpointError> {
        if !self.has_spent_checkpoint(error_model, key) {
            return Ok(false);
        }
        let checkpoint = self.stem(error_model, key).with_extension("checkpoint");
        std::fs::remove_dir_all(&checkpoint).map_err(io_error(&checkpoint))?;
        Ok(true)
    }

    /// Whether a checkpoint of `key` is left beside its model, stored whole.
    pub fn has_spent_checkpoint(&self, error_model: ErrorModel, key: &str) -> bool {
        let checkpoint = self.stem(error_model, key).with_extension("checkpoint");
        checkpoint.is_dir() && self.integrity(error_model, key) == Seal::Intact
    }

    /// Why the training of `key` failed, if it did; a record whose seal does not hold
    /// is no record, so the training is tried again.
    pub fn failure(&self, error_model: ErrorModel, key: &str) -> Option<String> {
        let bytes = std::fs::read(self.stem(error_model, key).with_extension("failed")).ok()?;
        let message = files::open_inline_sealed(&bytes, key).ok()?;
        Some(String::from_utf8_lossy(message).into_owned())
    }

    /// The last epoch of the checkpoint of `key`, if one is waiting to be resumed, or
    /// what is wrong with it.
    pub fn checkpoint_epoch(
        &self,
        error_model: ErrorModel,
        key: &str,
    ) -> Result<Option<usize>, String> {
        Ok(self.checkpoint(error_model, key)?.map(|state| state.epoch))
    }

    /// The `state.json` of the checkpoint of `key`, with every file of its last epoch
    /// checked against its seal: none when there is no checkpoint, or what is wrong
    /// with it.
    fn checkpoint(
        &self,
        error_model: ErrorModel,
        key: &str,
    ) -> Result<Option<CheckpointState>, String> {
        let folder = self.stem(error_model, key).with_extension("checkpoint");
        let state_path = folder.join("state.json");
        let damaged =
            |path: &Path, why: &dyn std::fmt::Display| format!("{}: {why}", path.display());
        let Ok(bytes) = std::fs::read(&state_path) else {
            // Epoch files without the state that names their epoch: a checkpoint whose
            // state.json was lost, or whose first write was cut short.
            return match folder.is_dir() {
                true => Err(damaged(
                    &state_path,
                    &"it is missing beside the epoch files",
                )),
                false => Ok(None),
            };
        };
        let state: CheckpointState = files::open_inline_sealed(&bytes, key)
            .and_then(|body| serde_json::from_slice(body).map_err(|e| e.to_string()))
            .map_err(|why| damaged(&state_path, &why))?;
        let epoch = state.epoch;
        let mut parts = vec!["model", "optimizer"];
        if state.best_epoch.is_some() {
            parts.push("best");
        }
        for part in parts {
            let path = folder.join(format!("epoch-{epoch}.{part}"));
            let why = match files::check_seal(&path, key) {
                Seal::Intact => continue,
                Seal::Absent => "it is missing".to_string(),
                Seal::Damaged(why) => why,
            };
            return Err(damaged(&path, &why));
        }
        Ok(Some(state))
    }

    /// The stored model with this key, if there is one.
    pub fn load(
        &self,
        spec: &Spec,
        error_model: ErrorModel,
        key: &str,
    ) -> Result<Option<Trained>, CheckpointError> {
        let Some(history) = self.history(error_model, key)? else {
            return Ok(None);
        };
        let stem = self.stem(error_model, key);
        let model = read_model(
            &stem.with_extension("bin"),
            spec,
            error_model,
            &spec.training.backend.device(),
        )?;
        Ok(Some(Trained {
            error_model,
            replicate: history.replicate,
            model,
            history: history.history,
            best_epoch: history.best_epoch,
            stop: history.stop,
        }))
    }

    /// Stores a finished model and removes its checkpoint and any failure record.
    pub fn save(&self, trained: &Trained, key: &str) -> Result<(), CheckpointError> {
        let stem = self.stem(trained.error_model, key);
        std::fs::create_dir_all(&self.folder).map_err(io_error(&self.folder))?;
        let weights = stem.with_extension("bin");
        write_model(&weights, &trained.model, key)?;
        let summary = TrainingHistory {
            key: key.to_string(),
            error_model: trained.error_model,
            replicate: trained.replicate,
            best_epoch: trained.best_epoch,
            history: trained.history.clone(),
            stop: trained.stop,
        };
        let path = stem.with_extension("json");
        files::write_sealed(
            &path,
            serde_json::to_string_pretty(&summary)
                .expect("summary serializes")
                .as_bytes(),
            key,
        )
        .map_err(io_error(&path))?;
        self.remove_spent_checkpoint(trained.error_model, key)?;
        let failed = stem.with_extension("failed");
        if failed.exists() {
            std::fs::remove_file(&failed).map_err(io_error(&failed))?;
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
        std::fs::create_dir_all(&folder).map_err(io_error(&folder))?;
        let epoch = state.history.len();
        write_model(
            &folder.join(format!("epoch-{epoch}.model")),
            &state.model,
            key,
        )?;
        let optimizer_path = folder.join(format!("epoch-{epoch}.optimizer"));
        let bytes = state
            .optimizer
            .into_bytes()
            .map_err(record_error(&optimizer_path))?;
        files::write_sealed(&optimizer_path, &bytes, key).map_err(io_error(&optimizer_path))?;
        if let Some((_, _, best)) = &state.best {
            write_model(&folder.join(format!("epoch-{epoch}.best")), best, key)?;
        }
        let record = CheckpointState {
            epoch,
            best_epoch: state.best.as_ref().map(|b| b.0),
            best_score: state.best.as_ref().map(|b| b.1),
            history: state.history.clone(),
        };
        // Sealed inline, so that one rename replaces it whole: a kill leaves the last
        // state.json, whose epoch files are still there, or this one.
        let path = folder.join("state.json");
        let body = serde_json::to_string(&record).expect("state serializes");
        write_atomic(&path, &files::inline_sealed(body.as_bytes(), key))
            .map_err(io_error(&path))?;
        // Older epochs are superseded once state.json names this one.
        for entry in std::fs::read_dir(&folder)
            .map_err(io_error(&folder))?
            .flatten()
        {
            let name = entry.file_name().to_string_lossy().into_owned();
            if name.starts_with("epoch-") && !name.starts_with(&format!("epoch-{epoch}.")) {
                std::fs::remove_file(entry.path()).map_err(io_error(&entry.path()))?;
            }
        }
        Ok(())
    }

    /// The training state of the checkpoint of `key`, or a fresh one for replicate
    /// `replicate`.
    pub fn resume(
        &self,
        spec: &Spec,
        error_model: ErrorModel,
        replicate: usize,
        key: &str,
    ) -> Result<State, CheckpointError> {
        let folder = self.stem(error_model, key).with_extension("checkpoint");
        let record = match self.checkpoint(error_model, key) {
            Ok(Some(record)) => record,
            Ok(None) => return Ok(State::new(spec, error_model, replicate)),
            Err(why) => {
                let damaged = self.folder.with_file_name("damaged");
                files::set_aside(&folder, &damaged).map_err(io_error(&folder))?;
                eprintln!(
                    "DCNet {error_model}: damaged checkpoint {why}; moved to {} and trained from the start",
                    damaged.display()
                );
                return Ok(State::new(spec, error_model, replicate));
            }
        };
        let epoch = record.epoch;
        let device = spec.training.backend.device();
        let model = read_model(
            &folder.join(format!("epoch-{epoch}.model")),
            spec,
            error_model,
            &device.clone().autodiff(),
        )?;
        let optimizer_path = folder.join(format!("epoch-{epoch}.optimizer"));
        let bytes = std::fs::read(&optimizer_path).map_err(io_error(&optimizer_path))?;
        let optimizer = train::optimizer(spec)
            .from_bytes(Bytes::from_bytes_vec(bytes))
            .map_err(record_error(&optimizer_path))?;
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
            replicate,
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

/// Why a step of [`Stage`] failed: the training itself, or storing its model.
#[derive(Debug, thiserror::Error)]
pub enum StageError {
    #[error(transparent)]
    Train(#[from] train::TrainError),
    #[error(transparent)]
    Store(#[from] CheckpointError),
}

/// One model's way through training, one epoch at a time, so that a scheduler can
/// interleave the epochs of several models: [`Stage::start`] loads the stored model
/// or resumes its checkpoint, [`Stage::epoch`] trains one epoch and checkpoints
/// every `training.checkpoint_every_epochs`, and the last epoch stores the model.
pub enum Stage {
    Running {
        state: Box<State>,
        provenance: Provenance,
    },
    Done(Box<Trained>, Provenance),
}

impl Stage {
    /// `error_model`'s stored model under `key`, or the training of its replicate
    /// `replicate` from the checkpoint if there is one. `fresh` trains from scratch
    /// whatever is stored.
    pub fn start(
        spec: &Spec,
        error_model: ErrorModel,
        replicate: usize,
        key: &str,
        store: &ModelStore,
        fresh: bool,
    ) -> Result<Self, CheckpointError> {
        if let Some(damage) = store.set_aside_damaged(error_model, key)? {
            eprintln!("DCNet {error_model}: {damage}");
        }
        if !fresh && let Some(trained) = store.load(spec, error_model, key)? {
            store.remove_spent_checkpoint(error_model, key)?;
            return Ok(Self::Done(Box::new(trained), Provenance::Reused));
        }
        let state = if fresh {
            State::new(spec, error_model, replicate)
        } else {
            store.resume(spec, error_model, replicate, key)?
        };
        let provenance = match state.history.len() {
            0 => Provenance::Trained,
            epoch => Provenance::Resumed(epoch),
        };
        Self::running(spec, error_model, key, store, state, provenance)
    }

    /// `state` as a running training, or as done (and stored) if it has ended.
    fn running(
        spec: &Spec,
        error_model: ErrorModel,
        key: &str,
        store: &ModelStore,
        state: State,
        provenance: Provenance,
    ) -> Result<Self, CheckpointError> {
        Ok(match state.stop(spec) {
            Some(stop) => {
                let trained = state.finish(error_model, stop);
                store.save(&trained, key)?;
                Self::Done(Box::new(trained), provenance)
            }
            None => Self::Running {
                state: Box::new(state),
                provenance,
            },
        })
    }

    /// Trains the next epoch of a running training; a done one is returned as it is.
    pub fn epoch(
        self,
        spec: &Spec,
        set: &crate::dataset::TrainingSet,
        error_model: ErrorModel,
        key: &str,
        store: &ModelStore,
        progress: &crate::progress::Progress,
    ) -> Result<Self, StageError> {
        let Self::Running {
            mut state,
            provenance,
        } = self
        else {
            return Ok(self);
        };
        train::run_epoch(spec, set, error_model, &mut state, progress)?;
        let epoch = state.history.len();
        if epoch % spec.training.checkpoint_every_epochs == 0 && state.stop(spec).is_none() {
            store.save_checkpoint(&state, error_model, key)?;
        }
        Ok(Self::running(
            spec,
            error_model,
            key,
            store,
            *state,
            provenance,
        )?)
    }

    /// Epochs trained so far.
    pub fn epochs_done(&self) -> usize {
        match self {
            Self::Running { state, .. } => state.history.len(),
            Self::Done(trained, _) => trained.history.len(),
        }
    }
}

/// Writes `model`'s weights to `path`, sealed for `key`.
fn write_model(path: &Path, model: &Dcnet, key: &str) -> Result<(), CheckpointError> {
    let bytes = model
        .clone()
        .into_record()
        .into_bytes()
        .map_err(record_error(path))?;
    files::write_sealed(path, &bytes, key).map_err(io_error(path))
}

fn read_model(
    path: &Path,
    spec: &Spec,
    error_model: ErrorModel,
    device: &Device,
) -> Result<Dcnet, CheckpointError> {
    let bytes = std::fs::read(path).map_err(io_error(path))?;
    let record =
        ModuleRecord::from_bytes(Bytes::from_bytes_vec(bytes)).map_err(record_error(path))?;
    // The skeleton's own weights are all overwritten by the record.
    let mut rng = crate::rng::task_rng(0, &[&"skeleton"]);
    let skeleton = Dcnet::new(
        &spec.model,
        error_model,
        spec.dataset.window_samples,
        device,
        &mut rng,
    );
    skeleton.try_load_record(record).map_err(record_error(path))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Progress;
    use crate::spec::quick_spec;
    use crate::train::tests::{run_epochs, training_set, weights};

    /// Loads `error_model`'s stored model under `key`, or trains it to the end on this
    /// thread (see [`Stage`]).
    fn train_cached(
        spec: &Spec,
        set: &crate::dataset::TrainingSet,
        error_model: ErrorModel,
        key: &str,
        store: &ModelStore,
        fresh: bool,
        progress: &crate::progress::Progress,
    ) -> Result<(Trained, Provenance), StageError> {
        let mut training = Stage::start(spec, error_model, 0, key, store, fresh)?;
        loop {
            match training {
                Stage::Done(trained, provenance) => return Ok((*trained, provenance)),
                running => {
                    training = running.epoch(spec, set, error_model, key, store, progress)?
                }
            }
        }
    }

    fn key(spec: &Spec, error_model: ErrorModel) -> String {
        let hashes = crate::pipeline::cache::DataHashes::default();
        crate::pipeline::cache::model_key(
            spec,
            error_model,
            0,
            &crate::pipeline::cache::dataset_key(spec, &hashes),
        )
    }

    #[test]
    fn a_training_resumed_from_a_checkpoint_ends_as_an_uninterrupted_one() {
        let spec = quick_spec(&["training.epochs=4"]);
        let set = training_set(&spec);
        let em = ErrorModel::Em5;

        let mut state = State::new(&spec, em, 0);
        run_epochs(&spec, &set, em, &mut state, 4);
        let uninterrupted = state.finish(em, crate::vocab::StopReason::AllEpochs);

        let dir = tempfile::tempdir().unwrap();
        let store = ModelStore::new(dir.path().to_path_buf());
        let key = key(&spec, em);
        let mut state = State::new(&spec, em, 0);
        run_epochs(&spec, &set, em, &mut state, 2);
        store.save_checkpoint(&state, em, &key).unwrap();
        drop(state);
        let mut resumed = store.resume(&spec, em, 0, &key).unwrap();
        assert_eq!(resumed.next_epoch(), 3);
        run_epochs(&spec, &set, em, &mut resumed, 2);
        let resumed = resumed.finish(em, crate::vocab::StopReason::AllEpochs);
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
    fn a_damaged_checkpoint_is_set_aside_and_training_starts_again() {
        let spec = quick_spec(&["training.epochs=4"]);
        let set = training_set(&spec);
        let em = ErrorModel::Em2;
        let dir = tempfile::tempdir().unwrap();
        let store = ModelStore::new(dir.path().join("models"));
        let key = key(&spec, em);
        let mut state = State::new(&spec, em, 0);
        run_epochs(&spec, &set, em, &mut state, 2);
        store.save_checkpoint(&state, em, &key).unwrap();
        assert_eq!(store.checkpoint_epoch(em, &key), Ok(Some(2)));

        let optimizer_path = store
            .stem(em, &key)
            .with_extension("checkpoint")
            .join("epoch-2.optimizer");
        let mut bytes = std::fs::read(&optimizer_path).unwrap();
        let middle = bytes.len() / 2;
        bytes[middle] ^= 1;
        std::fs::write(&optimizer_path, bytes).unwrap();
        assert!(
            matches!(store.checkpoint_epoch(em, &key), Err(why) if why.contains("epoch-2.optimizer"))
        );
        let fresh = store.resume(&spec, em, 0, &key).unwrap();
        assert_eq!(fresh.next_epoch(), 1, "training starts again");
        assert!(!store.stem(em, &key).with_extension("checkpoint").exists());
        assert_eq!(
            std::fs::read_dir(dir.path().join("damaged"))
                .unwrap()
                .count(),
            1
        );
    }

    #[test]
    fn a_failure_record_holds_only_for_its_key_and_its_bytes() {
        let folder = tempfile::tempdir().unwrap();
        let store = ModelStore::new(folder.path().to_path_buf());
        let key = "0123456789abcdef0123456789abcdef";
        store
            .save_failure(ErrorModel::Em3, key, "loss is NaN at epoch 2")
            .unwrap();
        let failure = store.failure(ErrorModel::Em3, key);
        assert_eq!(failure.as_deref(), Some("loss is NaN at epoch 2"));
        let path = store.stem(ErrorModel::Em3, key).with_extension("failed");
        let other = "fedcba9876543210fedcba9876543210";
        let other_path = store.stem(ErrorModel::Em3, other).with_extension("failed");
        std::fs::copy(&path, &other_path).unwrap();
        let mut bytes = std::fs::read(&path).unwrap();
        *bytes.last_mut().unwrap() ^= 1;
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(store.failure(ErrorModel::Em3, key), None, "flipped");
        assert_eq!(store.failure(ErrorModel::Em3, other), None, "swapped");
    }

    #[test]
    fn stored_models_are_reused_and_keyed_by_their_training_inputs() {
        let spec = quick_spec(&["training.epochs=2"]);
        let set = training_set(&spec);
        let dir = tempfile::tempdir().unwrap();
        let store = ModelStore::new(dir.path().to_path_buf());
        let hidden = Progress::hidden();
        let em4 = key(&spec, ErrorModel::Em4);
        let (first, provenance) =
            train_cached(&spec, &set, ErrorModel::Em4, &em4, &store, false, &hidden).unwrap();
        assert_eq!(provenance, Provenance::Trained);
        let (again, provenance) =
            train_cached(&spec, &set, ErrorModel::Em4, &em4, &store, false, &hidden).unwrap();
        assert_eq!(provenance, Provenance::Reused);
        assert!(weights(&again.model) == weights(&first.model));
        assert_eq!(again.history, first.history);

        // Monte Carlo and evaluation settings do not touch the key; training settings do.
        let key_of = |overrides: &[&str]| {
            key(
                &quick_spec(&[&["training.epochs=2"], overrides].concat()),
                ErrorModel::Em4,
            )
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
