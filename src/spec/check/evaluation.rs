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

#[cfg(test)]
mod tests {
    use crate::spec::fixture::{quick_faults, quick_spec};

    #[test]
    fn test_trajectories_are_found_by_name() {
        assert_eq!(quick_spec(&[]).evaluation, [2, 3]);
        let set = "evaluation.trajectories=[\"S9\"]";
        assert_eq!(
            quick_faults(&[set]),
            format!(
                "--set {set}: evaluation.trajectories[0]: unknown trajectory \"S9\"; data.trajectories defines S1, S2, S3, S4, SCal"
            )
        );
    }
}
