//! Trained models on disk: the paper's under `OUT/.cache/models/`, an installation
//! study's `[learned]` under `OUT/.cache/learned/` (see [`ModelId`]). A finished model
//! is stored at full precision as `<id>-<key>.bin` (weights) and `<id>-<key>.json`
//! (history), where `<id>` is `EM5` or `simulated-fold1-replicate1` and the key, made by
//! the content-addressed cache, is the hash of everything that determined it. A later
//! run with the same key loads it instead of training. A training that failed leaves
//! `<id>-<key>.failed`, its reason, so that later runs leave the model out. While a
//! model trains, its checkpoint lives beside it (`checkpoints`). In: trained models,
//! their identities and keys. Out: the stored models.

use super::identity::ModelId;
use crate::files::{self, Seal, write_atomic};
use crate::model::{Dcnet, NetworkIo};
use crate::spec::{ModelSpec, Spec};
use crate::train::{EpochRecord, Recipe, State, Trained, TrainingHistory};
use crate::vocab::{ErrorModel, StopReason};
use burn::module::Module;
use burn::store::{ModuleRecord, RecordError};
use burn::tensor::{Bytes, Device};
use std::path::{Path, PathBuf};
/// What went wrong reading or writing a stored model or its checkpoint, with the path.
#[derive(Debug, thiserror::Error)]
pub enum ModelStoreError {
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

pub(super) fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> ModelStoreError {
    let path = path.to_path_buf();
    |source| ModelStoreError::Io { path, source }
}

fn json_error(path: &Path) -> impl FnOnce(serde_json::Error) -> ModelStoreError {
    let path = path.to_path_buf();
    |source| ModelStoreError::Json { path, source }
}

pub(super) fn record_error(path: &Path) -> impl FnOnce(RecordError) -> ModelStoreError {
    let path = path.to_path_buf();
    |source| ModelStoreError::Record { path, source }
}

/// A model's network and how it trains: what the store needs to build its fresh
/// weights, to read stored ones back and to resume its optimizer.
pub struct Blueprint<'a> {
    /// The sizes, training settings and seeds of its training.
    pub recipe: Recipe<'a>,
    /// Its inputs and outputs.
    pub io: NetworkIo,
    /// The samples of one of its windows.
    pub window: usize,
}

impl<'a> Blueprint<'a> {
    /// The paper's DCNet of `error_model`.
    pub fn paper(spec: &'a Spec, error_model: ErrorModel) -> Self {
        Blueprint {
            recipe: Recipe::paper(spec, error_model),
            io: error_model.into(),
            window: spec.dataset.window_samples,
        }
    }

    /// Fresh weights and optimizer for replicate `replicate`.
    pub fn fresh(&self, replicate: usize) -> State {
        State::of(&self.recipe, self.io, self.window, replicate)
    }

    /// The device the trained model infers on.
    pub fn device(&self) -> Device {
        self.recipe.training.backend.device()
    }

    /// Reads the weights at `path` into this network, on `device`.
    pub(super) fn read(&self, path: &Path, device: &Device) -> Result<Dcnet, ModelStoreError> {
        read_model(path, self.recipe.model, self.io, self.window, device)
    }
}

/// A trained model as the store keeps it, whichever its kind: the weights of its best
/// validation epoch (plain device), every epoch's losses and why it stopped.
#[derive(Debug, Clone)]
pub struct StoredModel {
    pub id: ModelId,
    /// Which of `training.replicates` it is.
    pub replicate: usize,
    pub model: Dcnet,
    pub history: Vec<EpochRecord>,
    pub best_epoch: usize,
    pub stop: StopReason,
}

impl StoredModel {
    /// The best weights and the history of `state`, once it stopped for `stop`.
    pub fn finish(state: State, id: ModelId, stop: StopReason) -> Self {
        let (best_epoch, _, model) = state.best.expect("at least one epoch ran");
        StoredModel {
            id,
            replicate: state.replicate,
            model,
            history: state.history,
            best_epoch,
            stop,
        }
    }

    /// The paper's model of `error_model`, as the Monte Carlo runs it.
    fn into_trained(self, error_model: ErrorModel) -> Trained {
        Trained {
            error_model,
            replicate: self.replicate,
            model: self.model,
            history: self.history,
            best_epoch: self.best_epoch,
            stop: self.stop,
        }
    }
}

/// The `.json` beside a `[learned]` model: its key, identity and training (the paper's
/// models keep [`TrainingHistory`]). Fold and replicate count from 0, as the
/// paper's `replicate` does.
#[derive(serde::Serialize)]
struct LearnedHistory<'a> {
    key: &'a str,
    source: &'static str,
    fold: usize,
    replicate: usize,
    best_epoch: usize,
    history: &'a [EpochRecord],
    stop: StopReason,
}

/// What every model's `.json` holds, whichever its kind.
#[derive(serde::Deserialize)]
struct Summary {
    key: String,
    #[serde(default)]
    replicate: usize,
    best_epoch: usize,
    history: Vec<EpochRecord>,
    stop: StopReason,
}

/// The models of one run: `folder` holds the paper's; each other kind has the folder
/// beside it that its [`ModelId::folder`] names.
pub struct ModelStore {
    pub folder: PathBuf,
}

impl ModelStore {
    /// The store whose paper models are in `folder` (`OUT/.cache/models`).
    pub fn new(folder: PathBuf) -> Self {
        Self { folder }
    }

    /// Where the files of `id`'s model with this key start, without an extension.
    pub(super) fn stem(&self, id: impl Into<ModelId>, key: &str) -> PathBuf {
        let id = id.into();
        self.folder
            .with_file_name(id.folder())
            .join(format!("{}-{}", id.file_prefix(), &key[..16]))
    }

    /// Where damaged entries are set aside: `damaged/` beside the models.
    pub(super) fn damaged_folder(&self) -> PathBuf {
        self.folder.with_file_name("damaged")
    }

    /// Whether the stored model of `key`, weights and history, is there and has the
    /// bytes its seals name.
    pub fn integrity(&self, id: impl Into<ModelId>, key: &str) -> Seal {
        let stem = self.stem(id, key);
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
        id: impl Into<ModelId>,
        key: &str,
    ) -> Result<Option<String>, ModelStoreError> {
        let id = id.into();
        let Seal::Damaged(why) = self.integrity(id, key) else {
            return Ok(None);
        };
        let damaged = self.move_to_damaged(id, key)?;
        Ok(Some(format!(
            "damaged model {why}; moved to {} and trained again",
            damaged.display()
        )))
    }

    /// Moves the stored model of `id` and `key`, weights and history with their seals,
    /// into the cache's `damaged/` folder; that folder.
    fn move_to_damaged(&self, id: ModelId, key: &str) -> Result<PathBuf, ModelStoreError> {
        let damaged = self.damaged_folder();
        let stem = self.stem(id, key);
        for ext in ["bin", "json"] {
            let path = stem.with_extension(ext);
            files::set_aside(&path, &damaged).map_err(io_error(&path))?;
        }
        Ok(damaged)
    }

    /// How the paper's stored model with this key trained, if there is one and it is
    /// intact.
    pub fn history(
        &self,
        error_model: ErrorModel,
        key: &str,
    ) -> Result<Option<TrainingHistory>, ModelStoreError> {
        self.read_json(error_model.into(), key)
    }

    /// The `.json` of the stored model of `key`, if it is there, intact and of this key.
    fn read_json<T: serde::de::DeserializeOwned + HasKey>(
        &self,
        id: ModelId,
        key: &str,
    ) -> Result<Option<T>, ModelStoreError> {
        if self.integrity(id, key) != Seal::Intact {
            return Ok(None);
        }
        let path = self.stem(id, key).with_extension("json");
        let Ok(text) = std::fs::read_to_string(&path) else {
            return Ok(None);
        };
        let summary: T = serde_json::from_str(&text).map_err(json_error(&path))?;
        Ok((summary.key() == key).then_some(summary))
    }

    /// Records that the training of `key` failed and why, so that later runs and
    /// `collect` leave the model out instead of training it again.
    pub fn save_failure(
        &self,
        id: impl Into<ModelId>,
        key: &str,
        message: &str,
    ) -> Result<(), ModelStoreError> {
        let path = self.stem(id, key).with_extension("failed");
        let folder = path.parent().expect("a stem has a folder");
        crate::files::create_folder(folder).map_err(io_error(folder))?;
        let sealed = files::inline_sealed(message.as_bytes(), key);
        write_atomic(&path, &sealed).map_err(io_error(&path))
    }

    /// Why the training of `key` failed, if it did; a record whose seal does not hold
    /// is no record, so the training is tried again.
    pub fn failure(&self, id: impl Into<ModelId>, key: &str) -> Option<String> {
        let bytes = std::fs::read(self.stem(id, key).with_extension("failed")).ok()?;
        let message = files::open_inline_sealed(&bytes, key).ok()?;
        Some(String::from_utf8_lossy(message).into_owned())
    }

    /// The paper's stored model with this key, if there is one.
    pub fn load(
        &self,
        spec: &Spec,
        error_model: ErrorModel,
        key: &str,
    ) -> Result<Option<Trained>, ModelStoreError> {
        let blueprint = Blueprint::paper(spec, error_model);
        let stored = self.load_model(&blueprint, error_model.into(), key)?;
        Ok(stored.map(|stored| stored.into_trained(error_model)))
    }

    /// The stored model of `id` with this key, shaped by `blueprint`, if there is one.
    pub fn load_model(
        &self,
        blueprint: &Blueprint,
        id: ModelId,
        key: &str,
    ) -> Result<Option<StoredModel>, ModelStoreError> {
        let Some(summary) = self.read_json::<Summary>(id, key)? else {
            return Ok(None);
        };
        let weights = self.stem(id, key).with_extension("bin");
        let model = blueprint.read(&weights, &blueprint.device())?;
        Ok(Some(StoredModel {
            id,
            replicate: summary.replicate,
            model,
            history: summary.history,
            best_epoch: summary.best_epoch,
            stop: summary.stop,
        }))
    }

    /// [`ModelStore::load_model`], but a stored model whose seals hold and whose bytes
    /// are no model of `blueprint` (forged, or written by another build) is set aside
    /// as a damaged one is, said so, and not returned, so that it is trained again.
    pub fn load_or_set_aside(
        &self,
        blueprint: &Blueprint,
        id: ModelId,
        key: &str,
    ) -> Result<Option<StoredModel>, ModelStoreError> {
        match self.load_model(blueprint, id, key) {
            Err(error @ (ModelStoreError::Json { .. } | ModelStoreError::Record { .. })) => {
                let damaged = self.move_to_damaged(id, key)?;
                let cause = std::error::Error::source(&error).map(ToString::to_string);
                eprintln!(
                    "DCNet {id}: sealed, but not a model of this version ({}); moved to {} and trained again",
                    cause.unwrap_or_default(),
                    damaged.display()
                );
                Ok(None)
            }
            other => other,
        }
    }

    /// Stores a finished model and removes its checkpoint and any failure record.
    pub fn save(&self, trained: &StoredModel, key: &str) -> Result<(), ModelStoreError> {
        let stem = self.stem(trained.id, key);
        let folder = stem.parent().expect("a stem has a folder");
        crate::files::create_folder(folder).map_err(io_error(folder))?;
        write_model(&stem.with_extension("bin"), &trained.model, key)?;
        let path = stem.with_extension("json");
        files::write_sealed(&path, history_json(trained, key).as_bytes(), key)
            .map_err(io_error(&path))?;
        self.remove_spent_checkpoint(trained.id, key)?;
        let failed = stem.with_extension("failed");
        if failed.exists() {
            std::fs::remove_file(&failed).map_err(io_error(&failed))?;
        }
        Ok(())
    }
}

/// The `.json` stored beside `trained`'s weights: the paper's [`TrainingHistory`] (the
/// bytes it always had), or a [`LearnedHistory`].
fn history_json(trained: &StoredModel, key: &str) -> String {
    let json = match trained.id {
        ModelId::Paper(error_model) => serde_json::to_string_pretty(&TrainingHistory {
            key: key.to_string(),
            error_model,
            replicate: trained.replicate,
            best_epoch: trained.best_epoch,
            history: trained.history.clone(),
            stop: trained.stop,
        }),
        ModelId::Learned(model) => serde_json::to_string_pretty(&LearnedHistory {
            key,
            source: model.source.name(),
            fold: model.fold,
            replicate: model.replicate,
            best_epoch: trained.best_epoch,
            history: &trained.history,
            stop: trained.stop,
        }),
    };
    json.expect("summary serializes")
}

/// A stored `.json` that names the key it was stored under.
trait HasKey {
    fn key(&self) -> &str;
}

impl HasKey for TrainingHistory {
    fn key(&self) -> &str {
        &self.key
    }
}

impl HasKey for Summary {
    fn key(&self) -> &str {
        &self.key
    }
}

/// Writes `model`'s weights to `path`, sealed for `key`.
pub(crate) fn write_model(path: &Path, model: &Dcnet, key: &str) -> Result<(), ModelStoreError> {
    let bytes = model
        .clone()
        .into_record()
        .into_bytes()
        .map_err(record_error(path))?;
    files::write_sealed(path, &bytes, key).map_err(io_error(path))
}

/// Reads the weights at `path` into a network of `model`'s sizes and shape `io` on
/// windows of `window` samples.
pub(crate) fn read_model(
    path: &Path,
    model: &ModelSpec,
    io: impl Into<NetworkIo>,
    window: usize,
    device: &Device,
) -> Result<Dcnet, ModelStoreError> {
    let bytes = std::fs::read(path).map_err(io_error(path))?;
    let record =
        ModuleRecord::from_bytes(Bytes::from_bytes_vec(bytes)).map_err(record_error(path))?;
    // The skeleton's own weights are all overwritten by the record.
    let mut rng = crate::rng::task_rng(0, &[&"skeleton"]);
    let skeleton = Dcnet::new(model, io, window, device, &mut rng);
    skeleton.try_load_record(record).map_err(record_error(path))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The key of `error_model`'s model trained on `spec`, its data files unhashed.
    pub(crate) fn key(spec: &Spec, error_model: ErrorModel) -> String {
        let hashes = crate::pipeline::cache::DataHashes::default();
        crate::pipeline::cache::model_key(
            spec,
            error_model,
            0,
            &crate::pipeline::cache::dataset_key(spec, &hashes),
        )
    }

    #[test]
    fn a_failure_record_holds_only_for_its_key_and_its_bytes() {
        let folder = tempfile::tempdir().unwrap();
        let store = ModelStore::new(folder.path().join("models"));
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
}
