//! What a task is called, for people: in `plan`'s table, in the log, in the list of
//! what `collect` still waits for. In: a plan and a task. Out: a line of text.

use super::Plan;
use super::task::Task;
use crate::results::sweep;

impl Plan<'_> {
    /// What a task is, for people: "train DCNet EM5", "train DCNet EM5 replicate 2/3",
    /// "monte carlo DVL1 baseline".
    pub fn label(&self, task: Task) -> String {
        match task {
            Task::Dataset(_) => "generate dataset".into(),
            Task::Training(t) => {
                let training = &self.trainings[t];
                let replicates = self.spec(training.point).training.replicates;
                let label = format!("train DCNet {}", training.error_model);
                if replicates > 1 {
                    format!("{label} replicate {}/{replicates}", training.replicate + 1)
                } else {
                    label
                }
            }
            Task::Block(b) => {
                let block = &self.blocks[b];
                let dvl = &self.spec(block.point).dvls[block.dvl].name;
                let mut label = format!("monte carlo {dvl} {}", block.estimator);
                if let Some(m) = block.error_model {
                    label += &format!(" {m}");
                }
                if let Some(r) = block.replicate {
                    label += &format!(
                        " replicate {}/{}",
                        r + 1,
                        self.spec(block.point).training.replicates
                    );
                }
                label
            }
            Task::Results(_) if self.experiment.is_sweep() => "write results".into(),
            Task::Results(p) => format!("write {}", self.points[p].folder.display()),
            Task::Sweep => format!(
                "write {}",
                self.out
                    .join(&self.experiment.name)
                    .join(sweep::TABLE)
                    .display()
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::plan::tests::experiment;

    #[test]
    fn a_label_names_the_model_the_dvl_and_the_replicate() {
        let experiment = experiment(&[
            "estimators.kinds=[\"baseline\", \"dcnet\"]",
            "estimators.error_models=[\"EM5\"]",
            "training.replicates=2",
        ]);
        let out = tempfile::tempdir().unwrap();
        let plan = Plan::new(&experiment, out.path()).unwrap();
        let labels: Vec<String> = plan.tasks().into_iter().map(|t| plan.label(t)).collect();
        let results = format!("write {}", out.path().join("quick").display());
        assert_eq!(
            labels,
            [
                "generate dataset",
                "train DCNet EM5 replicate 1/2",
                "train DCNet EM5 replicate 2/2",
                "monte carlo DVL1 baseline",
                "monte carlo DVL1 dcnet EM5 replicate 1/2",
                "monte carlo DVL1 dcnet EM5 replicate 2/2",
                "monte carlo DVL1 dcnet_ensemble EM5",
                "monte carlo DVL2 baseline",
                "monte carlo DVL2 dcnet EM5 replicate 1/2",
                "monte carlo DVL2 dcnet EM5 replicate 2/2",
                "monte carlo DVL2 dcnet_ensemble EM5",
                &results,
            ]
        );
    }

    #[test]
    fn a_sweep_labels_its_points_and_its_table() {
        let experiment = experiment(&[
            "estimators.kinds=[\"baseline\", \"dcnet\"]",
            "estimators.error_models=[\"EM4\"]",
            "sweep.values={\"calibration.monte_carlo_runs\" = [3, 4]}",
        ]);
        let out = tempfile::tempdir().unwrap();
        let plan = Plan::new(&experiment, out.path()).unwrap();
        assert_eq!(plan.label(Task::Training(0)), "train DCNet EM4");
        assert_eq!(plan.label(Task::Results(1)), "write results");
        let table = out.path().join("quick").join("sweep.parquet");
        assert_eq!(
            plan.label(Task::Sweep),
            format!("write {}", table.display())
        );
    }
}
