//! Checks `[recordings]`. In: the trajectories' names and files as written, relative to
//! the spec's folder, and the column names when they are not A-KIT's. Out: each
//! trajectory's name and [`Source`] (its files, read with the columns); at least two
//! trajectories, each name and each pair of files once, each column named for one
//! quantity.

use crate::data::paired::{PairedColumns, Source};
use crate::installation::study::spec::file::{PairedTrajectoryFile, RecordingsFile};
use crate::spec::check::Faults;
use std::collections::HashSet;
use std::path::Path;

/// Checks `[recordings]`, its files found from `folder`: names defined once, at least
/// two trajectories (one to calibrate on, another to score on).
pub(in crate::installation::study::spec) fn check_recordings(
    recordings: RecordingsFile,
    folder: &Path,
    faults: &mut Faults,
) -> Vec<(String, Source)> {
    let RecordingsFile {
        columns,
        trajectories: listed,
    } = recordings;
    let columns = columns.unwrap_or_else(PairedColumns::akit);
    let mut names = HashSet::new();
    let mut trajectories = Vec::new();
    for (i, trajectory) in listed.into_iter().enumerate() {
        let PairedTrajectoryFile {
            name,
            dvl,
            reference,
        } = trajectory;
        if !names.insert(name.clone()) {
            faults.add(
                format!("recordings.trajectories[{i}].name"),
                format!("{name:?} is defined twice"),
            );
        }
        let reference = reference.map(|r| folder.join(r));
        let source = Source::csv(&folder.join(dvl), reference.as_deref(), columns.clone());
        trajectories.push((name, source));
    }
    if trajectories.len() < 2 {
        faults.add(
            "recordings.trajectories",
            format!(
                "has {} trajectories: held-out scores need at least two (one to calibrate on, another to score on)",
                trajectories.len()
            ),
        );
    }
    let mut sources = HashSet::new();
    for (i, (name, source)) in trajectories.iter().enumerate() {
        if !sources.insert(source) {
            faults.add(
                format!("recordings.trajectories[{i}].dvl"),
                format!(
                    "{name:?} reads the same files as a trajectory before it: a study would score a recording on itself"
                ),
            );
        }
    }
    if let Some((key, why)) = columns.named_twice() {
        faults.add(format!("recordings.columns.{key}"), why);
    }
    trajectories
}
