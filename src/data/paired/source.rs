//! One way in for a paired recording: a [`Source`] (one variant per format: CSV
//! files, or a ROS 2 bag) is read into a [`ReadRecording`]. Each of its files is read
//! from disk once and hashed as it is read: a CSV file whole, then parsed from memory
//! ([`Source::load`], then [`Loaded::parse`]); a bag streamed, its two topics decoded as
//! it goes ([`crate::data::paired::bag`]). Its samples go through the plausibility checks of
//! `checks.rs`, whatever the format. [`Recordings`] reads each source once,
//! however many times it is asked for. A DVL's own log beside an attitude alone, for a
//! fit to fixes, is read by [`read_log_beside_attitude`], through the same parsing and
//! checks.
//! In: a [`Source`]. Out: the checked [`PairedRecording`] with the SHA-256 of each of
//! its files, or the first [`PairedError`].

use super::{PairedColumns, PairedError, PairedRecording, checks};
use crate::data::csv::read_bytes;
use crate::data::paired::bag::{self, BagFrames, BagTopics};
use crate::data::paired::dvl_log::{self, DvlLog, LogFormat, Thresholds};
use crate::files::SourceFile;
use crate::files::sha256_hex;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Where a recording is, and how to read it.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Source {
    /// The DVL's columns from the CSV file `dvl`, the reference's from `reference`
    /// (the same path when one file holds both), named by `columns`.
    Csv {
        dvl: PathBuf,
        reference: PathBuf,
        columns: PairedColumns,
    },
    /// The DVL's and the reference's topics of the ROS 2 bag at `path`.
    Bag { path: PathBuf, topics: BagTopics },
    /// The DVL's own log `dvl` in `format`, each beam held to `thresholds`, beside the
    /// reference's CSV file `reference` read with `columns` (its DVL names unread).
    Log {
        dvl: PathBuf,
        format: LogFormat,
        thresholds: Thresholds,
        reference: PathBuf,
        columns: PairedColumns,
    },
}

impl Source {
    /// The CSV file `dvl` beside the reference's, the DVL's own where `reference` is
    /// `None`, read with `columns`.
    pub fn csv(dvl: &Path, reference: Option<&Path>, columns: PairedColumns) -> Source {
        Source::Csv {
            dvl: dvl.to_path_buf(),
            reference: reference.unwrap_or(dvl).to_path_buf(),
            columns,
        }
    }

    /// Its files, each once, the DVL's first.
    pub fn files(&self) -> Vec<&Path> {
        match self {
            Source::Csv { dvl, reference, .. } if dvl == reference => vec![dvl],
            Source::Csv { dvl, reference, .. } => vec![dvl, reference],
            Source::Bag { path, .. } => vec![path],
            Source::Log { dvl, reference, .. } => vec![dvl, reference],
        }
    }

    /// Reads each of its files from disk, once, and hashes it; nothing is parsed yet
    /// but a bag's two topics, decoded as it is streamed.
    pub fn load(&self) -> Result<Loaded<'_>, PairedError> {
        match self {
            Source::Bag { path, topics } => {
                let read = bag::read(path, topics)?;
                return Ok(Loaded {
                    source: self,
                    files: read.files,
                    content: Content::Bag(Box::new((read.samples, read.at, read.frames))),
                });
            }
            Source::Log {
                dvl,
                format,
                thresholds,
                reference,
                ..
            } => {
                let log = dvl_log::read(dvl, *format, *thresholds)?;
                let bytes = read_bytes(reference)?;
                let files = vec![
                    log.summary.file.clone(),
                    SourceFile {
                        path: reference.clone(),
                        sha256: sha256_hex(&bytes),
                    },
                ];
                return Ok(Loaded {
                    source: self,
                    files,
                    content: Content::Log(Box::new(log), bytes),
                });
            }
            Source::Csv { .. } => {}
        }
        let mut files = Vec::new();
        let mut bytes = Vec::new();
        for path in self.files() {
            let read = read_bytes(path)?;
            files.push(SourceFile {
                path: path.to_path_buf(),
                sha256: sha256_hex(&read),
            });
            bytes.push(read);
        }
        Ok(Loaded {
            source: self,
            files,
            content: Content::Bytes(bytes),
        })
    }

    /// Reads, parses and checks the recording.
    pub fn read(&self) -> Result<ReadRecording, PairedError> {
        self.load()?.parse()
    }
}

/// The DVL's own log `(path, format, thresholds)` beside the attitude of the file
/// `attitude` (a CSV file's columns as `columns` names them, or an NMEA file's PASHR),
/// checked as any recording: the reference has no velocity, for a calibration against
/// fixes; and the log as read.
pub fn read_log_beside_attitude(
    (dvl, format, thresholds): (&Path, LogFormat, Thresholds),
    attitude: &Path,
    columns: &PairedColumns,
) -> Result<(ReadRecording, DvlLog), PairedError> {
    let log = dvl_log::read(dvl, format, thresholds)?;
    let bytes = read_bytes(attitude)?;
    let files = vec![
        log.summary.file.clone(),
        SourceFile {
            path: attitude.to_path_buf(),
            sha256: sha256_hex(&bytes),
        },
    ];
    let (samples, at) = log_samples(log.clone(), (attitude, &bytes), columns, false)?;
    let read = ReadRecording {
        recording: checks::check(samples, &at)?,
        files,
        frames: None,
    };
    Ok((read, log))
}

/// The samples of a DVL log beside its reference's file (a path and its bytes) read
/// with `columns`, its velocity where `with_velocity`, and where each came from: a
/// ping's place is its number in the log.
fn log_samples(
    log: DvlLog,
    reference: (&Path, &[u8]),
    columns: &PairedColumns,
    with_velocity: bool,
) -> Result<(super::Unchecked, super::Locator), PairedError> {
    let (reference_samples, reference_lines) =
        super::csv::parse_reference(reference, columns, with_velocity)?;
    let mut names = super::csv::reference_names(&reference_samples, columns);
    names.dvl = dvl_log::VELOCITY_NAMES.map(String::from);
    let at = super::Locator {
        dvl: log.summary.file.path.clone(),
        reference: reference.0.to_path_buf(),
        dvl_lines: log.number,
        reference_lines,
        names,
    };
    let samples = super::Unchecked {
        dvl_time_s: log.time_s,
        dvl_m_s: log.velocity_m_s,
        dvl_stated: Some(log.stated),
        ..reference_samples
    };
    Ok((samples, at))
}

/// A source's files read and hashed, not yet parsed: what lets a caller refuse a
/// recording by its hash before its samples are read.
pub struct Loaded<'a> {
    source: &'a Source,
    files: Vec<SourceFile>,
    content: Content,
}

/// What a source's files gave before the checks.
enum Content {
    /// The bytes of each CSV file.
    Bytes(Vec<Vec<u8>>),
    /// A bag's samples, where each came from, and its frames.
    Bag(Box<(super::Unchecked, super::Locator, BagFrames)>),
    /// A DVL log as read, and the bytes of the reference's CSV file.
    Log(Box<DvlLog>, Vec<u8>),
}

impl Loaded<'_> {
    /// The SHA-256 of the DVL's file.
    pub fn dvl_sha256(&self) -> &str {
        &self.files[0].sha256
    }

    /// The samples of the files, parsed from the bytes read and checked.
    pub fn parse(self) -> Result<ReadRecording, PairedError> {
        let (samples, at, frames) = match (self.source, self.content) {
            (Source::Csv { columns, .. }, Content::Bytes(bytes)) => {
                let file = |k: usize| (self.files[k].path.as_path(), &bytes[k][..]);
                let (samples, at) = super::csv::parse(
                    file(0),
                    (self.files.len() > 1).then(|| file(1)),
                    columns,
                    true,
                )?;
                (samples, at, None)
            }
            (_, Content::Bag(read)) => {
                let (samples, at, frames) = *read;
                (samples, at, Some(frames))
            }
            (Source::Log { columns, .. }, Content::Log(log, bytes)) => {
                let (samples, at) =
                    log_samples(*log, (&self.files[1].path, &bytes), columns, true)?;
                (samples, at, None)
            }
            (_, Content::Bytes(_) | Content::Log(..)) => {
                unreachable!("a bag is loaded as samples, a log as pings")
            }
        };
        Ok(ReadRecording {
            recording: checks::check(samples, &at)?,
            files: self.files,
            frames,
        })
    }
}

/// A recording as read: its samples, checked, and the files they came from, the DVL's
/// first, each with its SHA-256.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadRecording {
    pub recording: PairedRecording,
    pub files: Vec<SourceFile>,
    /// A bag's topics and frames, as read.
    pub frames: Option<BagFrames>,
}

impl ReadRecording {
    /// The SHA-256 of the DVL's file, which the outputs computed from it record.
    pub fn dvl_sha256(&self) -> &str {
        &self.files[0].sha256
    }
}

/// Recordings read once each, however many times their source is asked for.
#[derive(Debug, Default)]
pub struct Recordings {
    read: Vec<ReadRecording>,
    index: HashMap<Source, usize>,
}

impl Recordings {
    /// The place of `source`'s recording among those read, reading it the first time.
    pub fn read(&mut self, source: &Source) -> Result<usize, PairedError> {
        if let Some(&at) = self.index.get(source) {
            return Ok(at);
        }
        self.read.push(source.read()?);
        self.index.insert(source.clone(), self.read.len() - 1);
        Ok(self.read.len() - 1)
    }

    /// The recording at `at`, as [`Recordings::read`] placed it.
    pub fn get(&self, at: usize) -> &ReadRecording {
        &self.read[at]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::paired::tests::short_columns as columns;

    const BOTH: &str = "t,u,v,w,n,e,d,roll,pitch,yaw\n\
                        0,1,0,0,1,0,0,0,0,0\n\
                        1,1,0,0,1,0,0,0,0,0\n\
                        2,1,0,0,1,0,0,0,0,0\n";

    /// The SHA-256 of each file is that of its bytes, one file listed once; the
    /// recording is the one the files hold.
    #[test]
    fn a_read_gives_the_sha256_of_each_file_it_read() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("both.csv");
        std::fs::write(&path, BOTH).unwrap();
        let source = Source::csv(&path, None, columns());
        assert_eq!(source.files(), vec![path.as_path()]);
        let read = source.read().unwrap();
        let sha256 = sha256_hex(BOTH.as_bytes());
        assert_eq!(
            read.files,
            vec![SourceFile {
                path: path.clone(),
                sha256: sha256.clone()
            }]
        );
        assert_eq!(read.frames, None);
        assert_eq!(read.dvl_sha256(), sha256);
        assert_eq!(read.recording.time_s, vec![0.0, 1.0, 2.0]);
        assert_eq!(source.load().unwrap().dvl_sha256(), sha256);
        // Two files: the DVL's first.
        let reference = dir.path().join("reference.csv");
        std::fs::write(&reference, BOTH).unwrap();
        let two = Source::Csv {
            dvl: path.clone(),
            reference: reference.clone(),
            columns: columns(),
        };
        let paths: Vec<PathBuf> = two
            .read()
            .unwrap()
            .files
            .into_iter()
            .map(|f| f.path)
            .collect();
        assert_eq!(paths, vec![path, reference]);
    }

    /// A source asked for again is not read again: its file may be gone by then.
    #[test]
    fn recordings_read_each_source_once() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("both.csv");
        std::fs::write(&path, BOTH).unwrap();
        let source = |columns| Source::Csv {
            dvl: path.clone(),
            reference: path.clone(),
            columns,
        };
        let mut recordings = Recordings::default();
        let first = recordings.read(&source(columns())).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(recordings.read(&source(columns())).unwrap(), first);
        assert_eq!(recordings.get(first).recording.len(), 3);
        // Other columns are another source.
        let mut other = columns();
        other.angles_in_degrees = true;
        let error = recordings.read(&source(other)).unwrap_err().to_string();
        assert_eq!(error, format!("{}: file not found", path.display()));
    }
}
