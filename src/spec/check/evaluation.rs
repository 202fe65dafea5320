//! Checks `[evaluation]`. In: the test trajectories by name, and the trajectories
//! `[data]` gave. Out: their indices into the spec's trajectories.

use super::{Faults, lookup};
use crate::spec::{TrajectorySource, file};

/// Checks `[evaluation]`: at least one test trajectory, each defined.
pub(in crate::spec) fn check_evaluation(
    evaluation: file::EvaluationFile,
    sources: &[TrajectorySource],
    faults: &mut Faults,
) -> Vec<usize> {
    let file::EvaluationFile { trajectories } = evaluation;
    if trajectories.is_empty() {
        faults.add(
            "evaluation.trajectories",
            "is empty: name at least one test trajectory",
        );
    }
    trajectories
        .iter()
        .enumerate()
        .filter_map(|(i, wanted)| {
            let key = format!("evaluation.trajectories[{i}]");
            if trajectories[..i].contains(wanted) {
                faults.add(key, format!("{wanted:?} is listed twice"));
                return None;
            }
            lookup(sources, &key, wanted, faults)
        })
        .collect()
}
