//! Trained models on disk, under `OUT/.cache/models/`. A finished model is stored at
//! full precision as `<EM>-<key>.bin` (weights) and `<EM>-<key>.json` (history), where
//! the key, made by the content-addressed cache, is the hash of everything that
//! determined it. A later run with the same key loads it instead of training. A
//! training that failed leaves `<EM>-<key>.failed`, its reason, so that later runs leave
//! the model out. While a model trains, its checkpoint lives beside it
//! (`checkpoints`). In: trained models and keys. Out: the stored models.

use crate::files::{self, Seal, write_atomic};
use crate::model::{Dcnet, NetworkIo};
use crate::spec::{ModelSpec, Spec};
use crate::train::{Trained, TrainingHistory};
use crate::vocab::ErrorModel;
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

/// The models folder of one run.
pub struct ModelStore {
    pub folder: PathBuf,
}

impl ModelStore {
    pub fn new(folder: PathBuf) -> Self {
        Self { folder }
    }

    pub(super) fn stem(&self, error_model: ErrorModel, key: &str) -> PathBuf {
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
    ) -> Result<Option<String>, ModelStoreError> {
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
    ) -> Result<Option<TrainingHistory>, ModelStoreError> {
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
    ) -> Result<(), ModelStoreError> {
        crate::files::create_folder(&self.folder).map_err(io_error(&self.folder))?;
        let path = self.stem(error_model, key).with_extension("failed");
        let sealed = files::inline_sealed(message.as_bytes(), key);
        write_atomic(&path, &sealed).map_err(io_error(&path))
    }

    /// Why the training of `key` failed, if it did; a record whose seal does not hold
    /// is no record, so the training is tried again.
    pub fn failure(&self, error_model: ErrorModel, key: &str) -> Option<String> {
        let bytes = std::fs::read(self.stem(error_model, key).with_extension("failed")).ok()?;
        let message = files::open_inline_sealed(&bytes, key).ok()?;
        Some(String::from_utf8_lossy(message).into_owned())
    }

    /// The stored model with this key, if there is one.
    pub fn load(
        &self,
        spec: &Spec,
        error_model: ErrorModel,
        key: &str,
    ) -> Result<Option<Trained>, ModelStoreError> {
        let Some(history) = self.history(error_model, key)? else {
            return Ok(None);
        };
        let stem = self.stem(error_model, key);
        let model = read_model(
            &stem.with_extension("bin"),
            &spec.model,
            error_model,
            spec.dataset.window_samples,
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
    pub fn save(&self, trained: &Trained, key: &str) -> Result<(), ModelStoreError> {
        let stem = self.stem(trained.error_model, key);
        crate::files::create_folder(&self.folder).map_err(io_error(&self.folder))?;
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
}
