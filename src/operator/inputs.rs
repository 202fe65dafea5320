//! What the operator's commands share about their inputs: the columns a `--columns`
//! file names (A-KIT's without one), and the check that no file a command writes is one
//! it reads.
//! In: the paths given on the command line. Out: the columns, or the file at fault.

use crate::data::fixes::FixColumns;
use crate::data::paired::bag::{Bag, BagTopics, Stamps, is_bag};
use crate::data::paired::dvl_log::{self, LogFormat, Thresholds};
use crate::data::paired::{GapLimit, PairedColumns, Source};
use crate::spec::{SpecError, TomlFile};
use std::path::{Path, PathBuf};

/// The first of `outputs` that would replace one of `inputs`, and that input: the same
/// file by [`identity`], however each is spelled. A bag's input is each file it is read
/// from ([`files_read`]), so no output replaces its `metadata.yaml` or a data file.
pub fn not_over_an_input(
    inputs: &[Option<&Path>],
    outputs: &[&Path],
) -> Option<(PathBuf, PathBuf)> {
    let read: Vec<(PathBuf, PathBuf)> = (inputs.iter().flatten())
        .flat_map(|input| files_read(input))
        .map(|file| (identity(&file), file))
        .collect();
    for output in outputs {
        let written = identity(output);
        if let Some((_, input)) = read.iter().find(|(same, _)| *same == written) {
            return Some((output.to_path_buf(), input.clone()));
        }
    }
    None
}

/// Every file the input at `path` is read from: the path itself and, for a rosbag2
/// folder, its `metadata.yaml` and each data file it lists (a folder that cannot be
/// opened as a bag is refused later, where it is read).
pub fn files_read(path: &Path) -> Vec<PathBuf> {
    let mut files = vec![path.to_path_buf()];
    if path.is_dir() && is_bag(path) {
        files.push(path.join("metadata.yaml"));
        if let Ok(bag) = Bag::open(path) {
            files.extend(bag.files);
        }
    }
    files
}

/// A file's identity, whether it exists yet or not: the deepest folder or file of its
/// path that exists, with its links resolved (its canonical path), then the rest of the
/// path as written, `.` dropped and `..` taken back (no link can lie in what does not
/// exist yet). `./out/a.csv`, `out/../out/a.csv` and `out/a.csv` are one file.
pub fn identity(path: &Path) -> PathBuf {
    use std::path::Component;
    let absolute = match std::env::current_dir() {
        Ok(here) if path.is_relative() => here.join(path),
        _ => path.to_path_buf(),
    };
    let mut existing = absolute.as_path();
    let mut rest = Vec::new();
    while !existing.exists() {
        match (existing.parent(), existing.components().next_back()) {
            (Some(parent), Some(last)) => {
                rest.push(last);
                existing = parent;
            }
            _ => break,
        }
    }
    let mut identity = std::fs::canonicalize(existing).unwrap_or_else(|_| existing.to_path_buf());
    for component in rest.into_iter().rev() {
        match component {
            Component::CurDir => {}
            Component::ParentDir => {
                identity.pop();
            }
            other => identity.push(other),
        }
    }
    identity
}

/// What the command line says of how to read a recording, beyond its columns: each
/// as the `[columns]` table's key of the same name, and over it; and, for a bag, its
/// topics, stamps and body frame.
#[derive(Debug, Clone, Copy, Default)]
pub struct Reading<'a> {
    /// The DVL's validity column (`--valid-column`, the table's `valid`).
    pub valid_column: Option<&'a str>,
    /// The gap limit, s (`--gap-limit-s`, the table's `gap_limit_s`).
    pub gap_limit_s: Option<f64>,
    /// A bag's DVL topic (`--dvl-topic`), reference topic (`--reference-topic`).
    pub dvl_topic: Option<&'a str>,
    pub reference_topic: Option<&'a str>,
    /// A bag's IMU topic for the body rate (`--rate-topic`).
    pub rate_topic: Option<&'a str>,
    /// A bag's stamps (`--stamps`; the headers' where not given).
    pub stamps: Option<Stamps>,
    /// A bag's body frame, the frame the installation is reported in (`--frame`;
    /// `base_link` where not given).
    pub frame: Option<&'a str>,
    /// A DVL log's format (`--dvl-format`; found from the file's content where not
    /// given), and the thresholds a beam must reach.
    pub dvl_format: Option<LogFormat>,
    pub thresholds: Thresholds,
}

/// The flag of the bottom-track threshold set in `thresholds` (the correlation's where
/// both are).
fn threshold_flag(thresholds: Thresholds) -> &'static str {
    match thresholds.correlation_min {
        Some(_) => "--bt-correlation-min",
        None => "--bt-percent-good-min",
    }
}

/// The refusal of the command-line flag `flag`, saying why.
pub fn refused(flag: &str, message: String) -> SpecError {
    SpecError {
        location: flag.into(),
        key: String::new(),
        message,
    }
}

/// The recording of the DVL file (or bag) `dvl`, its reference's file where that is
/// another, read with the columns of `columns_file` (a CSV recording) or the topics of
/// `reading` (a bag); a flag that does not apply to it is refused by name.
pub fn source(
    dvl: &Path,
    reference: Option<&Path>,
    columns_file: Option<&Path>,
    reading: Reading,
) -> Result<Source, SpecError> {
    if !is_bag(dvl) {
        return file_source(dvl, reference, columns_file, reading);
    }
    let not_for_a_bag = [
        (
            "--reference",
            reference.is_some(),
            "it holds the reference too: name its topic with --reference-topic",
        ),
        (
            "--columns",
            columns_file.is_some(),
            "its fields are named by its types: name the topics with --dvl-topic and --reference-topic",
        ),
        (
            "--valid-column",
            reading.valid_column.is_some(),
            "a ping's validity is read from its message (bottom track, good beams, beam velocities valid)",
        ),
        (
            "--dvl-format",
            reading.dvl_format.is_some(),
            "its DVL is read from its topic",
        ),
        (
            threshold_flag(reading.thresholds),
            reading.thresholds != Thresholds::default(),
            "a ping's validity is read from its message",
        ),
    ];
    if let Some((flag, _, why)) = not_for_a_bag.iter().find(|(_, given, _)| *given) {
        return Err(refused(flag, format!("{} is a bag: {why}", dvl.display())));
    }
    if let (Some(dvl_topic), Some(reference_topic)) = (reading.dvl_topic, reading.reference_topic)
        && dvl_topic == reference_topic
    {
        return Err(refused(
            "--reference-topic",
            format!(
                "{reference_topic} is also --dvl-topic: the DVL is calibrated against another sensor, so name the reference's own topic (data info {} lists them)",
                dvl.display()
            ),
        ));
    }
    Ok(Source::Bag {
        path: dvl.to_path_buf(),
        topics: BagTopics {
            dvl: reading.dvl_topic.map(String::from),
            reference: reading.reference_topic.map(String::from),
            rate: reading.rate_topic.map(String::from),
            stamps: reading.stamps.unwrap_or_default(),
            frame: reading
                .frame
                .map_or_else(|| BagTopics::default().frame, String::from),
            gap_limit_s: reading.gap_limit_s.map(GapLimit),
        },
    })
}

/// The recording of the DVL file `dvl` that is no bag: a DVL's own log (its format
/// named or found from its content), or a CSV file; a bag's flag is refused by name.
fn file_source(
    dvl: &Path,
    reference: Option<&Path>,
    columns_file: Option<&Path>,
    reading: Reading,
) -> Result<Source, SpecError> {
    for (flag, given) in [
        ("--dvl-topic", reading.dvl_topic),
        ("--reference-topic", reading.reference_topic),
        ("--rate-topic", reading.rate_topic),
        ("--stamps", reading.stamps.map(|_| "")),
        ("--frame", reading.frame),
    ] {
        if given.is_some() {
            return Err(refused(
                flag,
                format!(
                    "{} is not a bag (a rosbag2 folder, an .mcap or a .db3 file): a CSV recording is read by its columns",
                    dvl.display()
                ),
            ));
        }
    }
    if let Some(format) = reading.dvl_format.or_else(|| dvl_log::format_of(dvl)) {
        return log_source(dvl, format, reference, columns_file, reading);
    }
    for (flag, given) in [
        (
            "--bt-correlation-min",
            reading.thresholds.correlation_min.is_some(),
        ),
        (
            "--bt-percent-good-min",
            reading.thresholds.percent_good_min.is_some(),
        ),
    ] {
        if given {
            return Err(refused(
                flag,
                format!(
                    "{} is not a DVL's own log (PD0): a CSV recording's validity is its --valid-column",
                    dvl.display()
                ),
            ));
        }
    }
    return Ok(Source::csv(dvl, reference, columns(columns_file, reading)?));
}

/// The recording of the DVL log `dvl` in `format` beside the reference's CSV file,
/// read with the columns of `columns_file` (whose DVL columns are not read).
fn log_source(
    dvl: &Path,
    format: LogFormat,
    reference: Option<&Path>,
    columns_file: Option<&Path>,
    reading: Reading,
) -> Result<Source, SpecError> {
    let Some(reference) = reference else {
        return Err(refused(
            "--reference",
            format!(
                "{} is a {} log, which holds the DVL alone: name the reference's CSV file with --reference",
                dvl.display(),
                format.words()
            ),
        ));
    };
    if format == LogFormat::WaterLinked && reading.thresholds != Thresholds::default() {
        return Err(refused(
            threshold_flag(reading.thresholds),
            format!(
                "{} is a {} log: its reports carry no correlation or percent good; a ping's validity is its velocity_valid",
                dvl.display(),
                format.words()
            ),
        ));
    }
    if reading.valid_column.is_some() {
        return Err(refused(
            "--valid-column",
            format!(
                "{} is a {} log: a ping's validity is read from the log (data info {} says from what)",
                dvl.display(),
                format.words(),
                dvl.display()
            ),
        ));
    }
    Ok(Source::Log {
        dvl: dvl.to_path_buf(),
        format,
        thresholds: reading.thresholds,
        reference: reference.to_path_buf(),
        columns: columns(columns_file, reading)?,
    })
}

/// The columns of `path`'s `[columns]` table, or A-KIT's, with what the command line
/// says of the `reading` over them.
pub fn columns(path: Option<&Path>, reading: Reading) -> Result<PairedColumns, SpecError> {
    let Reading {
        valid_column: valid,
        gap_limit_s,
        ..
    } = reading;
    let gap_limit_s = gap_limit_s.map(GapLimit);
    let Some(path) = path else {
        let mut columns = PairedColumns::akit();
        columns.valid = valid.map(String::from);
        columns.gap_limit_s = gap_limit_s;
        return match columns.named_twice() {
            Some((_, why)) => Err(SpecError {
                location: "--valid-column".into(),
                key: String::new(),
                message: why,
            }),
            None => Ok(columns),
        };
    };
    let file = TomlFile::<ColumnsFile>::read(path)?;
    let mut columns = file
        .value
        .columns
        .clone()
        .unwrap_or_else(PairedColumns::akit);
    if let Some(valid) = valid {
        columns.valid = Some(valid.to_string());
    }
    if gap_limit_s.is_some() {
        columns.gap_limit_s = gap_limit_s;
    }
    if let Some((key, why)) = columns.named_twice() {
        let fault = file.fault(&format!("columns.{key}"), why);
        return Err(fault);
    }
    Ok(columns)
}

/// A `--columns` file: its `[columns]` table (a recording's, A-KIT's without one) and
/// its `[fix_columns]` table (a fixes file's, A-KIT's reference's without one).
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ColumnsFile {
    columns: Option<PairedColumns>,
    fix_columns: Option<FixColumns>,
}

/// The columns of a fixes file: `path`'s `[fix_columns]` table, or A-KIT's reference
/// file's latitude and longitude.
pub fn fix_columns(path: Option<&Path>) -> Result<FixColumns, SpecError> {
    let Some(path) = path else {
        return Ok(FixColumns::default());
    };
    let file = TomlFile::<ColumnsFile>::read(path)?;
    let columns = file.value.fix_columns.clone().unwrap_or_default();
    if columns.latitude_longitude.is_some() == columns.north_east.is_some() {
        let why = "name the fixes' position as latitude_longitude or as north_east, one of them";
        return Err(file.fault("fix_columns.north_east", why.to_string()));
    }
    Ok(columns)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_is_the_same_however_spelled_there_or_not_yet() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("here")).unwrap();
        #[cfg(unix)]
        std::os::unix::fs::symlink(d.join("here"), d.join("link")).unwrap();
        let one = identity(&d.join("here/out/a.csv"));
        for spelled in [
            "here/./out/a.csv",
            "here/out/../out/a.csv",
            "here/x/../out/./a.csv",
        ] {
            assert_eq!(identity(&d.join(spelled)), one, "{spelled}");
        }
        #[cfg(unix)]
        assert_eq!(identity(&d.join("link/out/a.csv")), one);
        assert_ne!(identity(&d.join("here/out/b.csv")), one);
        let inputs = [Some(d.join("here/in.csv"))];
        let inputs: Vec<Option<&Path>> = inputs.iter().map(|p| p.as_deref()).collect();
        let over = d.join("here/./in.csv");
        assert_eq!(
            not_over_an_input(&inputs, &[over.as_path()]),
            Some((over.clone(), d.join("here/in.csv")))
        );
    }
}
