//! The checkpoints of models in training, `<id>-<key>.checkpoint/` beside the model
//! (`OUT/.cache/models/EM5-<key>.checkpoint/`, `OUT/.cache/learned/…`):
//! every few epochs the weights, the optimizer's state and the best epoch's weights
//! (`epoch-<n>.model`, `.optimizer`, `.best`, each sealed) and a `state.json` sealed
//! inline that names the epoch, so that an interrupted training resumes where it
//! stopped. A checkpoint that fails its seal is set aside and the model trains from the
//! start. In: a training's state. Out: the state to resume from.

use super::identity::ModelId;
use super::models::{Blueprint, ModelStore, ModelStoreError, io_error, record_error, write_model};
use crate::files::{self, Seal, write_atomic};
use crate::train::{self, EpochRecord, State};
use burn::store::RecordError;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// What a checkpoint's `state.json` holds, below its inline seal; the weight files carry
/// the epoch in their name.
#[derive(Serialize, Deserialize)]
struct CheckpointState {
    epoch: usize,
    best_epoch: Option<usize>,
    best_score: Option<f64>,
    history: Vec<EpochRecord>,
}

impl ModelStore {
    /// Removes the checkpoint of `key` once its model is stored whole, as saving does,
    /// and as a kill between the two leaves undone; returns whether there was one.
    pub fn remove_spent_checkpoint(
        &self,
        id: impl Into<ModelId>,
        key: &str,
    ) -> Result<bool, ModelStoreError> {
        let id = id.into();
        if !self.has_spent_checkpoint(id, key) {
            return Ok(false);
        }
        let checkpoint = self.stem(id, key).with_extension("checkpoint");
        std::fs::remove_dir_all(&checkpoint).map_err(io_error(&checkpoint))?;
        Ok(true)
    }

    /// Whether a checkpoint of `key` is left beside its model, stored whole.
    pub fn has_spent_checkpoint(&self, id: impl Into<ModelId>, key: &str) -> bool {
        let id = id.into();
        let checkpoint = self.stem(id, key).with_extension("checkpoint");
        checkpoint.is_dir() && self.integrity(id, key) == Seal::Intact
    }

    /// The last epoch of the checkpoint of `key`, if one is waiting to be resumed, or
    /// what is wrong with it.
    pub fn checkpoint_epoch(
        &self,
        id: impl Into<ModelId>,
        key: &str,
    ) -> Result<Option<usize>, String> {
        Ok(self.checkpoint(id.into(), key)?.map(|state| state.epoch))
    }

    /// The `state.json` of the checkpoint of `key`, with every file of its last epoch
    /// checked against its seal: none when there is no checkpoint, or what is wrong
    /// with it.
    fn checkpoint(&self, id: ModelId, key: &str) -> Result<Option<CheckpointState>, String> {
        let folder = self.stem(id, key).with_extension("checkpoint");
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

    /// Writes the state after its last epoch as the checkpoint of `key`.
    pub fn save_checkpoint(
        &self,
        state: &State,
        id: impl Into<ModelId>,
        key: &str,
    ) -> Result<(), ModelStoreError> {
        let folder = self.stem(id, key).with_extension("checkpoint");
        crate::files::create_folder(&folder).map_err(io_error(&folder))?;
        let epoch = state.history.len();
        write_model(
            &folder.join(format!("epoch-{epoch}.model")),
            &state.model,
            key,
        )?;
        let optimizer_path = folder.join(format!("epoch-{epoch}.optimizer"));
        let bytes = state.optimizer.to_bytes();
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

    /// The training state of the checkpoint of `key`, or a fresh one of `blueprint`
    /// for replicate `replicate`.
    pub fn resume(
        &self,
        blueprint: &Blueprint,
        id: impl Into<ModelId>,
        replicate: usize,
        key: &str,
    ) -> Result<State, ModelStoreError> {
        let id = id.into();
        let folder = self.stem(id, key).with_extension("checkpoint");
        let record = match self.checkpoint(id, key) {
            Ok(Some(record)) => record,
            Ok(None) => return Ok(blueprint.fresh(replicate)),
            Err(why) => {
                let damaged = self.damaged_folder();
                files::set_aside(&folder, &damaged).map_err(io_error(&folder))?;
                eprintln!(
                    "DCNet {id}: damaged checkpoint {why}; moved to {} and trained from the start",
                    damaged.display()
                );
                return Ok(blueprint.fresh(replicate));
            }
        };
        let epoch = record.epoch;
        let device = blueprint.device();
        let model = blueprint.read(
            &folder.join(format!("epoch-{epoch}.model")),
            &device.clone().autodiff(),
        )?;
        let optimizer_path = folder.join(format!("epoch-{epoch}.optimizer"));
        let bytes = std::fs::read(&optimizer_path).map_err(io_error(&optimizer_path))?;
        let optimizer = train::optimizer(blueprint.recipe.training)
            .with_bytes(&bytes)
            .map_err(|why| record_error(&optimizer_path)(RecordError::Io(why)))?;
        let best = match (record.best_epoch, record.best_score) {
            (Some(best_epoch), Some(score)) => Some((
                best_epoch,
                score,
                blueprint.read(&folder.join(format!("epoch-{epoch}.best")), &device)?,
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

#[cfg(test)]
mod tests {
    use super::super::models::tests::key;
    use super::*;
    use crate::spec::quick_spec;
    use crate::train::Trained;
    use crate::train::tests::{run_epochs, training_set, weights};
    use crate::vocab::ErrorModel;

    #[test]
    fn a_training_resumed_from_a_checkpoint_ends_as_an_uninterrupted_one() {
        let spec = quick_spec(&["training.epochs=4"]);
        let set = training_set(&spec);
        let em = ErrorModel::Em5;

        let mut state = State::new(&spec, em, 0);
        run_epochs(&spec, &set, em, &mut state, 4);
        let uninterrupted = state.finish(em, crate::vocab::StopReason::AllEpochs);

        let dir = tempfile::tempdir().unwrap();
        let store = ModelStore::new(dir.path().join("models"));
        let key = key(&spec, em);
        let mut state = State::new(&spec, em, 0);
        run_epochs(&spec, &set, em, &mut state, 2);
        store.save_checkpoint(&state, em, &key).unwrap();
        drop(state);
        let mut resumed = store
            .resume(&Blueprint::paper(&spec, em), em, 0, &key)
            .unwrap();
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
        let fresh = store
            .resume(&Blueprint::paper(&spec, em), em, 0, &key)
            .unwrap();
        assert_eq!(fresh.next_epoch(), 1, "training starts again");
        assert!(!store.stem(em, &key).with_extension("checkpoint").exists());
        assert_eq!(
            std::fs::read_dir(dir.path().join("damaged"))
                .unwrap()
                .count(),
            1
        );
    }
}
