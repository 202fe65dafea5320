//! What a run covers: every task, one shard's share (`--shard K/N`), or only the
//! results folders (`collect`); and of what it covers, what is left to do. In: a plan
//! and a mode. Out: tasks.

use super::Plan;
use super::task::Task;
use crate::pipeline::shard::Shard;

/// What [`execute`](super::super::execute) is asked to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Every task left.
    All { force: bool },
    /// The trainings and blocks of one shard, no results.
    Shard { shard: Shard, force: bool },
    /// Only the results folders, from a cache the shards have filled.
    Collect,
}

impl Mode {
    pub(crate) fn force(self) -> bool {
        match self {
            Mode::All { force } | Mode::Shard { force, .. } => force,
            Mode::Collect => false,
        }
    }
}

impl Plan<'_> {
    /// The tasks the shard computes: whole groups (a model's replicates, its blocks and
    /// their ensemble's), dealt out round-robin.
    pub fn in_shard(&self, task: Task, shard: Shard) -> bool {
        let group = match task {
            Task::Training(t) => self.trainings[t].group,
            Task::Block(b) => match self.blocks[b].trainings.first() {
                Some(&t) => self.trainings[t].group,
                None => {
                    self.trainings.len()
                        + self.blocks[..b]
                            .iter()
                            .filter(|other| other.trainings.is_empty())
                            .count()
                }
            },
            // Datasets go with the trainings that need them; results with collect.
            Task::Dataset(_) | Task::Results(_) | Task::Sweep => return false,
        };
        group % shard.count == shard.index
    }

    /// Why each failed training of the tasks `mode` covers failed, one line each.
    pub fn failures(&self, mode: Mode) -> Vec<String> {
        (0..self.trainings.len())
            .filter(|&t| match mode {
                Mode::Shard { shard, .. } => self.in_shard(Task::Training(t), shard),
                _ => true,
            })
            .filter_map(|t| {
                let training = &self.trainings[t];
                self.models.failure(training.error_model, &training.key)
            })
            .collect()
    }

    /// The tasks `mode` does: those it covers that are not done (all it covers with
    /// `force`). A dataset counts when a training needs it.
    pub fn to_do(&self, mode: Mode) -> Vec<Task> {
        let covers = |task: Task| match (mode, task) {
            (_, Task::Dataset(_)) => false,
            (Mode::All { .. }, _) => true,
            (Mode::Shard { shard, .. }, _) => self.in_shard(task, shard),
            (Mode::Collect, task) => matches!(task, Task::Results(_) | Task::Sweep),
        };
        let mut tasks: Vec<Task> = self
            .tasks()
            .into_iter()
            .filter(|&task| covers(task) && (mode.force() || !self.status(task).is_settled()))
            .collect();
        let datasets: Vec<Task> = (0..self.datasets.len())
            .filter(|&d| {
                tasks.iter().any(
                    |task| matches!(task, Task::Training(t) if self.trainings[*t].dataset == d),
                )
            })
            .map(Task::Dataset)
            .collect();
        tasks.splice(0..0, datasets);
        tasks
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::plan::tests::experiment;

    /// The tasks of `plan` that shard `index` of `count` computes.
    fn members(plan: &Plan, index: usize, count: usize) -> Vec<Task> {
        let shard = Shard { index, count };
        plan.tasks()
            .into_iter()
            .filter(|&task| plan.in_shard(task, shard))
            .collect()
    }

    /// Without replicates each training is a group with the blocks that run its model;
    /// each block without a model is a group after them. Groups go round-robin.
    #[test]
    fn shards_take_whole_groups_in_turn() {
        let experiment = experiment(&[
            "estimators.kinds=[\"baseline\", \"dcnet\"]",
            "estimators.error_models=[\"EM4\", \"EM5\"]",
        ]);
        let out = tempfile::tempdir().unwrap();
        let plan = Plan::new(&experiment, out.path()).unwrap();
        // Blocks: DVL1 baseline (group 2), DCNet EM4 (0), DCNet EM5 (1); DVL2 baseline
        // (3), DCNet EM4 (0), DCNet EM5 (1).
        use Task::{Block, Training};
        assert_eq!(
            members(&plan, 0, 2),
            [Training(0), Block(0), Block(1), Block(4)]
        );
        assert_eq!(
            members(&plan, 1, 2),
            [Training(1), Block(2), Block(3), Block(5)]
        );
        // Three shards: every training and block in exactly one; no dataset, results
        // folder or sweep table in any.
        let shards: Vec<Vec<Task>> = (0..3).map(|k| members(&plan, k, 3)).collect();
        for task in plan.tasks() {
            let holders = shards.iter().filter(|s| s.contains(&task)).count();
            let computed = matches!(task, Training(_) | Block(_));
            assert_eq!(holders, usize::from(computed), "{task:?}");
        }
    }

    /// A model's replicates, their blocks and their ensemble's share the group of
    /// replicate 0, so the ensemble finds every model in its shard.
    #[test]
    fn replicates_and_their_ensemble_share_a_shard() {
        let experiment = experiment(&[
            "estimators.kinds=[\"dcnet\"]",
            "estimators.error_models=[\"EM5\"]",
            "training.replicates=2",
        ]);
        let out = tempfile::tempdir().unwrap();
        let plan = Plan::new(&experiment, out.path()).unwrap();
        assert_eq!(plan.trainings.len(), 2);
        // Per DVL: replicate 1, replicate 2, the ensemble.
        assert_eq!(plan.blocks.len(), 6);
        assert_eq!(plan.blocks[2].trainings, [0, 1]);
        let all: Vec<Task> = plan
            .tasks()
            .into_iter()
            .filter(|t| matches!(t, Task::Training(_) | Task::Block(_)))
            .collect();
        assert_eq!(members(&plan, 0, 2), all);
        assert_eq!(members(&plan, 1, 2), []);
    }

    #[test]
    fn a_plan_with_nothing_stored_has_everything_to_do() {
        let experiment = experiment(&[
            "estimators.kinds=[\"baseline\", \"dcnet\"]",
            "estimators.error_models=[\"EM5\"]",
        ]);
        let out = tempfile::tempdir().unwrap();
        let plan = Plan::new(&experiment, out.path()).unwrap();
        let all = Mode::All { force: false };
        // The dataset first, then every task in plan order.
        assert_eq!(plan.to_do(all), plan.tasks());
        let shard = Mode::Shard {
            shard: Shard { index: 1, count: 2 },
            force: false,
        };
        // Group 0 is the training and its blocks; group 1 DVL1's baseline, group 2
        // DVL2's. Shard 1 has no training, so it needs no dataset.
        assert_eq!(plan.to_do(shard), [Task::Block(0)]);
        assert_eq!(plan.to_do(Mode::Collect), [Task::Results(0)]);
    }
}
