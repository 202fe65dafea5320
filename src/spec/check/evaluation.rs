//! Checks `[evaluation]`. In: the test trajectories by name, and the trajectories
//! `[data]` gave. Out: their indices into the spec's trajectories.

use super::{Defined, Faults};
use crate::spec::file;
use std::collections::HashSet;

/// Checks `[evaluation]`: at least one test trajectory, each defined.
pub(in crate::spec) fn check_evaluation(
    evaluation: file::EvaluationFile,
    sources: &Defined,
    faults: &mut Faults,
) -> Vec<usize> {
    let file::EvaluationFile { trajectories } = evaluation;
    if trajectories.is_empty() {
        faults.add(
            "evaluation.trajectories",
            "is empty: name at least one test trajectory",
        );
    }
    let mut listed = HashSet::new();
    trajectories
        .iter()
        .enumerate()
        .filter_map(|(i, wanted)| {
            let key = format!("evaluation.trajectories[{i}]");
            if !listed.insert(wanted) {
                faults.add(key, format!("{wanted:?} is listed twice"));
                return None;
            }
            sources.lookup(&key, wanted, faults)
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
