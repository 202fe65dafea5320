//! One model's training job: its stored model loaded, or its checkpoint resumed, or
//! its training started, then one epoch at a time (checkpointed every few epochs) until
//! it ends and its model is stored, so that the scheduler can interleave the epochs of
//! many models. In: the spec, the training set, the model store. Out: a trained model
//! and where it came from ([`Provenance`]).

use crate::pipeline::cache::{ModelStore, ModelStoreError};
use crate::spec::Spec;
use crate::train::{self, State, Trained};
use crate::vocab::ErrorModel;

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

/// One model's way through training, one epoch at a time, so that a scheduler can
/// interleave the epochs of several models: [`TrainingJob::start`] loads the stored model
/// or resumes its checkpoint, [`TrainingJob::epoch`] trains one epoch and checkpoints
/// every `training.checkpoint_every_epochs`, and the last epoch stores the model.
pub enum TrainingJob {
    Running {
        state: Box<State>,
        provenance: Provenance,
    },
    Done(Box<Trained>, Provenance),
}

impl TrainingJob {
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
    ) -> Result<Self, ModelStoreError> {
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
    ) -> Result<Self, ModelStoreError> {
        Ok(match state.stop(&spec.training) {
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
    ) -> Result<Self, TrainingJobError> {
        let Self::Running {
            mut state,
            provenance,
        } = self
        else {
            return Ok(self);
        };
        let recipe = train::Recipe::paper(spec, error_model);
        let data = train::PaperWindows { set, error_model };
        train::run_epoch(&recipe, &data, &mut state, progress)?;
        let epoch = state.history.len();
        if epoch % spec.training.checkpoint_every_epochs == 0
            && state.stop(&spec.training).is_none()
        {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::cache::models::tests::key;
    use crate::progress::Progress;
    use crate::spec::quick_spec;
    use crate::train::tests::{training_set, weights};

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
    ) -> Result<(Trained, Provenance), TrainingJobError> {
        let mut training = TrainingJob::start(spec, error_model, 0, key, store, fresh)?;
        loop {
            match training {
                TrainingJob::Done(trained, provenance) => return Ok((*trained, provenance)),
                running => {
                    training = running.epoch(spec, set, error_model, key, store, progress)?
                }
            }
        }
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
