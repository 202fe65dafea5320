//! One model's training job: its stored model loaded, or its checkpoint resumed, or
//! its training started, then one epoch at a time (checkpointed every few epochs) until
//! it ends and its model is stored, so that a scheduler can interleave the epochs of
//! many models. The paper's DCNets and an installation study's `[learned]` models go
//! through the same job; a [`ModelTask`] says which model and how it trains.
//! In: the task, its training windows, the model store. Out: a stored model and where
//! it came from ([`Provenance`]).

use crate::pipeline::cache::{Blueprint, ModelId, ModelStore, ModelStoreError, StoredModel};
use crate::train::{self, State, Windowed};

/// How a model came to be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Provenance {
    Trained,
    /// Trained further from a checkpoint at this epoch.
    Resumed(usize),
    /// Loaded from the store without training.
    Reused,
}

/// Why a step of [`TrainingJob`] failed: the training itself, or storing its model.
#[derive(Debug, thiserror::Error)]
pub enum TrainingJobError {
    #[error(transparent)]
    Train(#[from] train::TrainError),
    #[error(transparent)]
    Store(#[from] ModelStoreError),
}

/// One model to train: which it is, its key, how it trains, and the store it goes to.
pub struct ModelTask<'a> {
    pub blueprint: Blueprint<'a>,
    pub id: ModelId,
    /// Which of `training.replicates` it is; it seeds the streams.
    pub replicate: usize,
    pub key: &'a str,
    pub store: &'a ModelStore,
}

/// One model's way through training, one epoch at a time, so that a scheduler can
/// interleave the epochs of several models: [`TrainingJob::start`] loads the stored model
/// or resumes its checkpoint, [`TrainingJob::epoch`] trains one epoch and checkpoints
/// every `training.checkpoint_every_epochs`, and the last epoch stores the model.
pub enum TrainingJob {
    Running {
        state: Box<State>,
        provenance: Provenance,
    },
    Done(Box<StoredModel>, Provenance),
}

impl TrainingJob {
    /// The stored model of `task`, or its training from the checkpoint if there is
    /// one. `fresh` trains from scratch whatever is stored.
    pub fn start(task: &ModelTask, fresh: bool) -> Result<Self, ModelStoreError> {
        let (id, key, store) = (task.id, task.key, task.store);
        if let Some(damage) = store.set_aside_damaged(id, key)? {
            eprintln!("DCNet {id}: {damage}");
        }
        if !fresh && let Some(stored) = store.load_model(&task.blueprint, id, key)? {
            store.remove_spent_checkpoint(id, key)?;
            return Ok(Self::Done(Box::new(stored), Provenance::Reused));
        }
        let state = if fresh {
            task.blueprint.fresh(task.replicate)
        } else {
            store.resume(&task.blueprint, id, task.replicate, key)?
        };
        let provenance = match state.history.len() {
            0 => Provenance::Trained,
            epoch => Provenance::Resumed(epoch),
        };
        Self::running(task, state, provenance)
    }

    /// `state` as a running training, or as done (and stored) if it has ended.
    fn running(
        task: &ModelTask,
        state: State,
        provenance: Provenance,
    ) -> Result<Self, ModelStoreError> {
        Ok(match state.stop(task.blueprint.recipe.training) {
            Some(stop) => {
                let stored = StoredModel::finish(state, task.id, stop);
                task.store.save(&stored, task.key)?;
                Self::Done(Box::new(stored), provenance)
            }
            None => Self::Running {
                state: Box::new(state),
                provenance,
            },
        })
    }

    /// Trains the next epoch of a running training on `data`; a done one is returned as
    /// it is.
    pub fn epoch(
        self,
        task: &ModelTask,
        data: &impl Windowed,
        progress: &crate::progress::Progress,
    ) -> Result<Self, TrainingJobError> {
        let Self::Running {
            mut state,
            provenance,
        } = self
        else {
            return Ok(self);
        };
        let training = task.blueprint.recipe.training;
        train::run_epoch(&task.blueprint.recipe, data, &mut state, progress)?;
        let epoch = state.history.len();
        if epoch % training.checkpoint_every_epochs == 0 && state.stop(training).is_none() {
            task.store.save_checkpoint(&state, task.id, task.key)?;
        }
        Ok(Self::running(task, *state, provenance)?)
    }

    /// Epochs trained so far.
    pub fn epochs_done(&self) -> usize {
        match self {
            Self::Running { state, .. } => state.history.len(),
            Self::Done(stored, _) => stored.history.len(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::cache::models::tests::key;
    use crate::progress::Progress;
    use crate::spec::{Spec, quick_spec};
    use crate::train::tests::{training_set, weights};
    use crate::vocab::ErrorModel;

    /// Loads `error_model`'s stored model under `key`, or trains it to the end on this
    /// thread (see [`TrainingJob`]).
    fn train_cached(
        spec: &Spec,
        set: &crate::dataset::TrainingSet,
        error_model: ErrorModel,
        key: &str,
        store: &ModelStore,
        fresh: bool,
        progress: &crate::progress::Progress,
    ) -> Result<(StoredModel, Provenance), TrainingJobError> {
        let task = ModelTask {
            blueprint: Blueprint::paper(spec, error_model),
            id: error_model.into(),
            replicate: 0,
            key,
            store,
        };
        let data = train::PaperWindows { set, error_model };
        let mut training = TrainingJob::start(&task, fresh)?;
        loop {
            match training {
                TrainingJob::Done(trained, provenance) => return Ok((*trained, provenance)),
                running => training = running.epoch(&task, &data, progress)?,
            }
        }
    }

    #[test]
    fn stored_models_are_reused_and_keyed_by_their_training_inputs() {
        let spec = quick_spec(&["training.epochs=2"]);
        let set = training_set(&spec);
        let dir = tempfile::tempdir().unwrap();
        let store = ModelStore::new(dir.path().join("models"));
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
