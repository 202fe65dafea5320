//! Checks `[recordings]`. In: the trajectories' names and files as written, relative to
//! the spec's folder, and the column names when they are not A-KIT's (or, for a ROS 2
//! bag, its topics). Out: each trajectory's name and [`Source`] (its files, read with
//! the columns, or its bag with the topics); at least two
//! trajectories, each name and each pair of files once, each column named for one
//! quantity.

use crate::data::paired::bag::{BagTopics, Stamps, is_bag};
use crate::data::paired::dvl_log::{self, LogFormat, Thresholds};
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
        if !names.insert(trajectory.name.clone()) {
            faults.add(
                format!("recordings.trajectories[{i}].name"),
                format!("{:?} is defined twice", trajectory.name),
            );
        }
        let name = trajectory.name.clone();
        trajectories.push((
            name,
            trajectory_source(i, trajectory, (folder, &columns), faults),
        ));
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

/// The [`Source`] of trajectory `i`, its files found from `folder`: a bag read with its
/// topics, or CSV files read with `columns`; a key of one given to the other is a fault.
fn trajectory_source(
    i: usize,
    trajectory: PairedTrajectoryFile,
    (folder, columns): (&Path, &PairedColumns),
    faults: &mut Faults,
) -> Source {
    let PairedTrajectoryFile {
        name: _,
        dvl,
        reference,
        dvl_topic,
        reference_topic,
        rate_topic,
        stamps,
        frame,
        dvl_format,
    } = trajectory;
    let key = |field: &str| format!("recordings.trajectories[{i}].{field}");
    let dvl = folder.join(dvl);
    let format = match dvl_format.as_deref() {
        None => dvl_log::format_of(&dvl),
        Some(named) => LogFormat::from_key(named).or_else(|| {
            let keys: Vec<&str> = LogFormat::KEYS.iter().map(|(k, _)| *k).collect();
            faults.add(
                key("dvl_format"),
                format!(
                    "{named:?}: a DVL log's format is one of {}",
                    keys.join(", ")
                ),
            );
            None
        }),
    };
    if let Some(format) = format {
        let bag_keys = [
            ("dvl_topic", dvl_topic.is_some()),
            ("reference_topic", reference_topic.is_some()),
            ("rate_topic", rate_topic.is_some()),
            ("stamps", stamps.is_some()),
            ("frame", frame.is_some()),
        ];
        for (field, _) in bag_keys.iter().filter(|(_, given)| *given) {
            faults.add(
                key(field),
                format!(
                    "{} is a {} log, not a ROS 2 bag",
                    dvl.display(),
                    format.words()
                ),
            );
        }
        let Some(reference) = reference else {
            faults.add(
                key("reference"),
                format!(
                    "{} is a {} log, which holds the DVL alone: name the reference's CSV file",
                    dvl.display(),
                    format.words()
                ),
            );
            return Source::csv(&dvl, None, columns.clone());
        };
        return Source::Log {
            reference: folder.join(reference),
            dvl,
            format,
            thresholds: Thresholds::default(),
            columns: columns.clone(),
        };
    }
    if !is_bag(&dvl) {
        let bag_keys = [
            ("dvl_topic", dvl_topic.is_some()),
            ("reference_topic", reference_topic.is_some()),
            ("rate_topic", rate_topic.is_some()),
            ("stamps", stamps.is_some()),
            ("frame", frame.is_some()),
        ];
        for (field, _) in bag_keys.iter().filter(|(_, given)| *given) {
            faults.add(key(field), format!("{} is not a ROS 2 bag (a rosbag2 folder, an .mcap or a .db3 file): a CSV recording is read by its columns", dvl.display()));
        }
        let reference = reference.map(|r| folder.join(r));
        return Source::csv(&dvl, reference.as_deref(), columns.clone());
    }
    if reference.is_some() {
        faults.add(key("reference"), format!("{} is a ROS 2 bag, which holds the reference too: name its topic with reference_topic", dvl.display()));
    }
    let stamps = match stamps.as_deref() {
        None | Some("header") => Stamps::Header,
        Some("receive") => Stamps::Receive,
        Some(other) => {
            faults.add(
                key("stamps"),
                format!("{other:?}: a bag's stamps are \"header\" or \"receive\""),
            );
            Stamps::Header
        }
    };
    Source::Bag {
        path: dvl,
        topics: BagTopics {
            dvl: dvl_topic,
            reference: reference_topic,
            rate: rate_topic,
            stamps,
            frame: frame.unwrap_or_else(|| BagTopics::default().frame),
            gap_limit_s: columns.gap_limit_s,
        },
    }
}
