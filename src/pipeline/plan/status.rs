//! The state of each task as the cache on disk tells it: a stored model or block and
//! its seal, a failure record, a checkpoint to resume, a results folder made from the
//! plan's blocks. In: a plan. Out: a [`Status`] per task; nothing is written.
//! [`model_status`] also tells the state of an installation study's `[learned]` models.

use super::Plan;
use super::task::Task;
use crate::files::Seal;
use crate::pipeline::cache::{self, ModelId, ModelStore};
use crate::results::{self, Manifest, sweep};
use std::path::Path;

/// The state of a task.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    Done,
    /// A training that failed (its loss diverged), or a block of its model: left out
    /// of the results until `--force` tries again.
    Failed,
    ToDo,
    /// A training with a checkpoint after this many epochs.
    Resumable(usize),
    /// A dataset no training left to do needs.
    NotNeeded,
    /// A model or block in the cache that fails its seal: it is set aside and
    /// computed again.
    Damaged,
}

impl Status {
    /// Whether there is nothing left to do: done, or failed for good.
    pub fn is_settled(self) -> bool {
        matches!(self, Status::Done | Status::Failed)
    }
}

impl std::fmt::Display for Status {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Status::Done => f.write_str("done"),
            Status::Failed => f.write_str("failed (--force tries again)"),
            Status::ToDo => f.write_str("to do"),
            Status::Resumable(epoch) => write!(f, "to do (resumes after epoch {epoch})"),
            Status::NotNeeded => f.write_str("not needed"),
            Status::Damaged => f.write_str("to do (damaged)"),
        }
    }
}

impl Plan<'_> {
    /// The state of `task` as the cache on disk tells it. Each call reads each file it
    /// needs once: a dataset's or a results folder's state asks its trainings once.
    pub fn status(&self, task: Task) -> Status {
        match task {
            Task::Dataset(d) => {
                let needed = self.trainings.iter().enumerate().any(|(t, training)| {
                    training.dataset == d && !self.training_status(t).is_settled()
                });
                if needed {
                    Status::ToDo
                } else {
                    Status::NotNeeded
                }
            }
            Task::Training(t) => self.training_status(t),
            Task::Block(b) => {
                let integrity = self.block_store.integrity(&self.blocks[b].key);
                if integrity == Seal::Intact {
                    Status::Done
                } else if matches!(integrity, Seal::Damaged(_)) {
                    Status::Damaged
                } else if self.runs_failed_model(b) {
                    Status::Failed
                } else {
                    Status::ToDo
                }
            }
            Task::Results(p) => {
                let point = &self.points[p];
                // Current: made from these blocks, every file as written, and the
                // reports and their figures there (a run killed before them, or whose
                // figures could not be written, writes them again).
                let current = read_manifest(&point.folder).is_some_and(|m| {
                    m.results_key == self.results_key(p) && results::is_intact(&point.folder, &m)
                }) && crate::report::is_complete(&point.folder);
                if current { Status::Done } else { Status::ToDo }
            }
            Task::Sweep => {
                let folder = self.out.join(&self.experiment.name);
                let stored = sweep::read_index(&folder).ok();
                let keys: Vec<String> = (0..self.points.len())
                    .map(|p| self.results_key(p))
                    .collect();
                if stored.is_some_and(|index| {
                    index.results_keys == keys && index.table_is_intact(&folder)
                }) {
                    Status::Done
                } else {
                    Status::ToDo
                }
            }
        }
    }

    /// The state of training `t`: its model stored, its failure recorded, a checkpoint
    /// to resume, or nothing yet.
    fn training_status(&self, t: usize) -> Status {
        let training = &self.trainings[t];
        model_status(&self.models, training.error_model, &training.key)
    }

    /// The results key point `p`'s folder has when it is current: the plan's, marked
    /// with the models that failed and are left out.
    pub fn results_key(&self, p: usize) -> String {
        let point = &self.points[p];
        let failed: Vec<&str> = point
            .trainings
            .iter()
            .filter(|&&t| self.training_status(t) == Status::Failed)
            .map(|&t| self.trainings[t].key.as_str())
            .collect();
        if failed.is_empty() {
            return point.results_key.clone();
        }
        cache::hash(&(&point.results_key, "without", failed))
    }

    /// Whether block `b` runs a model whose training failed.
    pub(crate) fn runs_failed_model(&self, b: usize) -> bool {
        self.blocks[b]
            .trainings
            .iter()
            .any(|&t| self.training_status(t) == Status::Failed)
    }
}

/// The state of the model of `id` with this key in `store`: stored, its failure
/// recorded, a checkpoint to resume, or nothing yet. The paper's trainings and an
/// installation study's `[learned]` models are told alike.
pub fn model_status(store: &ModelStore, id: impl Into<ModelId>, key: &str) -> Status {
    let id = id.into();
    match store.integrity(id, key) {
        Seal::Intact => return Status::Done,
        Seal::Damaged(_) => return Status::Damaged,
        Seal::Absent => {}
    }
    if store.failure(id, key).is_some() {
        return Status::Failed;
    }
    match store.checkpoint_epoch(id, key) {
        Ok(Some(epoch)) => Status::Resumable(epoch),
        Ok(None) => Status::ToDo,
        Err(_) => Status::Damaged,
    }
}

fn read_manifest(folder: &Path) -> Option<Manifest> {
    let bytes = std::fs::read(folder.join(results::MANIFEST)).ok()?;
    serde_json::from_slice(&bytes).ok()
}
