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
use std::path::{Path, PathBuf};

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

/// The format of the DVL log `dvl`, as `named` (a fault at `key("dvl_format")` where it
/// names none) or found from its content; `None` for a file that is no log.
fn log_format(
    dvl: &Path,
    named: Option<&str>,
    key: &dyn Fn(&str) -> String,
    faults: &mut Faults,
) -> Option<LogFormat> {
    let Some(named) = named else {
        return dvl_log::format_of(dvl);
    };
    let format = LogFormat::from_key(named);
    if format.is_none() {
        let keys: Vec<&str> = LogFormat::KEYS.iter().map(|(k, _)| *k).collect();
        faults.add(
            key("dvl_format"),
            format!(
                "{named:?}: a DVL log's format is one of {}",
                keys.join(", ")
            ),
        );
    }
    format
}

/// A bag's stamps as the key `stamps` names them (the headers' where not given); a
/// fault at it where it names neither.
fn bag_stamps(named: Option<&str>, key: &dyn Fn(&str) -> String, faults: &mut Faults) -> Stamps {
    match named {
        None | Some("header") => Stamps::Header,
        Some("receive") => Stamps::Receive,
        Some(other) => {
            faults.add(
                key("stamps"),
                format!("{other:?}: a bag's stamps are \"header\" or \"receive\""),
            );
            Stamps::Header
        }
    }
}

/// The [`Source`] of the DVL log `dvl` in `format` beside its reference's CSV file
/// `reference`, read with `columns`; a fault at `key("reference")` where none is named.
fn log_source(
    dvl: PathBuf,
    format: LogFormat,
    reference: Option<PathBuf>,
    columns: &PairedColumns,
    key: &dyn Fn(&str) -> String,
    faults: &mut Faults,
) -> Source {
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
    Source::Log {
        dvl,
        format,
        thresholds: Thresholds::default(),
        reference,
        columns: columns.clone(),
    }
}

/// The [`Source`] of trajectory `i`, its files found from `folder`: a DVL log beside its
/// reference's CSV file, a bag read with its topics, or CSV files read with `columns`;
/// a key of one given to another is a fault.
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
    let bag_keys_given = [
        ("dvl_topic", dvl_topic.is_some()),
        ("reference_topic", reference_topic.is_some()),
        ("rate_topic", rate_topic.is_some()),
        ("stamps", stamps.is_some()),
        ("frame", frame.is_some()),
    ]
    .into_iter()
    .filter_map(|(field, given)| given.then_some(field));
    let not_a_bag = |why: String, faults: &mut Faults| {
        for field in bag_keys_given.clone() {
            faults.add(key(field), why.clone());
        }
    };
    if let Some(format) = log_format(&dvl, dvl_format.as_deref(), &key, faults) {
        not_a_bag(
            format!(
                "{} is a {} log, not a ROS 2 bag",
                dvl.display(),
                format.words()
            ),
            faults,
        );
        return log_source(
            dvl,
            format,
            reference.map(|r| folder.join(r)),
            columns,
            &key,
            faults,
        );
    }
    if !is_bag(&dvl) {
        not_a_bag(
            format!(
                "{} is not a ROS 2 bag (a rosbag2 folder, an .mcap or a .db3 file): a CSV recording is read by its columns",
                dvl.display()
            ),
            faults,
        );
        let reference = reference.map(|r| folder.join(r));
        return Source::csv(&dvl, reference.as_deref(), columns.clone());
    }
    if reference.is_some() {
        faults.add(key("reference"), format!("{} is a ROS 2 bag, which holds the reference too: name its topic with reference_topic", dvl.display()));
    }
    let stamps = bag_stamps(stamps.as_deref(), &key, faults);
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
