//! A DVL's own log as the DVL's half of a paired recording, beside a reference read
//! from CSV: Teledyne RDI's PD0 (`pd0.rs`, turned into the vehicle's axes by
//! `frames.rs`). The format is found from the file's first bytes (PD0's 0x7F 0x7F) or
//! named. Every ping is kept as a sample, those the instrument did not measure with
//! the reason it states (no bottom track, no velocity, too few beams of the correlation
//! or percent good asked), so that the plausibility checks count them with the
//! recording's other left-out samples; a three-beam solution is kept and counted. An
//! ensemble whose checksum fails is not a sample: it is counted in the [`LogSummary`].
//! The log's clock is read as UTC, in seconds since 1970: the reference's must be on it.
//! In: the log's path, its [`LogFormat`] and the [`Thresholds`]. Out: a [`DvlLog`].

mod frames;
pub mod pd0;

pub use frames::{Ping, Thresholds, instrument_to_earth, ping};

use super::{LeftOutWhy, PairedError, SourceFile};
use crate::Vec3;
use std::io::Read;
use std::path::{Path, PathBuf};

/// A DVL log's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LogFormat {
    /// Teledyne RDI's binary PD0.
    Pd0,
}

impl LogFormat {
    /// The formats by the key `--dvl-format` and the spec take.
    pub const KEYS: [(&'static str, LogFormat); 1] = [("pd0", LogFormat::Pd0)];

    /// The format a key names.
    pub fn from_key(key: &str) -> Option<LogFormat> {
        (LogFormat::KEYS.iter()).find_map(|&(k, format)| (k == key).then_some(format))
    }

    pub fn words(self) -> &'static str {
        match self {
            LogFormat::Pd0 => "Teledyne RDI PD0",
        }
    }
}

/// How far into a file its format is looked for, bytes.
const SNIFFED: usize = 4096;

/// The DVL log format of the file at `path`, found from its first bytes: PD0 where
/// they hold 0x7F 0x7F; `None` for any other file (a CSV file, a folder).
pub fn format_of(path: &Path) -> Option<LogFormat> {
    let mut first = Vec::with_capacity(SNIFFED);
    let file = std::fs::File::open(path).ok()?;
    file.take(SNIFFED as u64).read_to_end(&mut first).ok()?;
    first
        .windows(2)
        .any(|pair| pair == [0x7F, 0x7F])
        .then_some(LogFormat::Pd0)
}

/// A DVL log as read: each ping's stamp, the vehicle's velocity in the DVL's axes
/// (forward, starboard, down; m/s, NaN where it has none) and why the instrument says
/// it is not a measurement, where it says so.
#[derive(Debug, Clone, PartialEq)]
pub struct DvlLog {
    pub time_s: Vec<f64>,
    pub velocity_m_s: Vec<Vec3>,
    pub stated: Vec<Option<LeftOutWhy>>,
    /// Each ping's number in the log (a PD0 ensemble's), where messages place it.
    pub number: Vec<u64>,
    pub summary: LogSummary,
}

/// What a log held, beyond its pings: what `data info` says of it.
#[derive(Debug, Clone, PartialEq)]
pub struct LogSummary {
    pub format: LogFormat,
    pub file: SourceFile,
    pub pings: usize,
    /// Pings kept on a three-beam solution (the instrument's or this reader's).
    pub three_beam: usize,
    /// Where each ensemble whose checksum failed starts, bytes.
    pub bad_checksums: Vec<u64>,
    /// Bytes outside any ensemble.
    pub bytes_between: u64,
    /// The last ensemble, where the file ends inside it (`pd0::Pd0Survey::cut_short`).
    pub cut_short: Option<(u64, usize, usize)>,
    /// The frames the velocities were recorded in, and how they were turned.
    pub frames: Vec<String>,
    /// The data types present, each with the count of ensembles holding it.
    pub blocks: Vec<(String, usize)>,
    /// What a ping's validity was read from, thresholds included.
    pub validity: String,
}

/// Reads the log at `path` in `format`, each beam held to `thresholds`.
pub fn read(path: &Path, format: LogFormat, thresholds: Thresholds) -> Result<DvlLog, PairedError> {
    match format {
        LogFormat::Pd0 => read_pd0(path, thresholds),
    }
}

fn read_pd0(path: &Path, thresholds: Thresholds) -> Result<DvlLog, PairedError> {
    let mut log = DvlLog {
        time_s: Vec::new(),
        velocity_m_s: Vec::new(),
        stated: Vec::new(),
        number: Vec::new(),
        summary: LogSummary::empty(LogFormat::Pd0, path),
    };
    let (mut frames, mut applied) = (Vec::new(), None);
    let survey = pd0::read(path, &mut |ensemble| {
        let ping = frames::ping(&ensemble, thresholds);
        let (velocity_m_s, stated) = match ping {
            Ping::Kept {
                velocity_m_s,
                three_beam,
            } => {
                log.summary.three_beam += usize::from(three_beam);
                (velocity_m_s, None)
            }
            Ping::LeftOut(why) => ([f64::NAN; 3], Some(why)),
        };
        let frame = frame_words(&ensemble.leader);
        if !frames.contains(&frame) {
            frames.push(frame);
        }
        if let Some(bottom) = &ensemble.bottom {
            applied.get_or_insert((bottom.correlation_min, bottom.percent_good_min));
        }
        log.time_s.push(ensemble.time_s);
        log.velocity_m_s.push(velocity_m_s);
        log.stated.push(stated);
        log.number.push(u64::from(ensemble.number));
    })?;
    let summary = &mut log.summary;
    summary.file.sha256 = survey.sha256;
    summary.pings = survey.ensembles;
    summary.bad_checksums = survey.bad_checksums;
    summary.bytes_between = survey.bytes_between;
    summary.cut_short = survey.cut_short;
    summary.frames = frames;
    summary.blocks = (survey.blocks.iter())
        .map(|(&id, &count)| (format!("0x{id:04X} {}", pd0::block_name(id)), count))
        .collect();
    summary.validity = match applied {
        Some((correlation, percent_good)) => format!(
            "bottom track (ID 0x0600): out of beam coordinates a ping counts where the instrument gave x, y and z, in beam coordinates a beam counts where it has a velocity (the instrument marks those below its own thresholds, here BC {correlation} and BG {percent_good} %, with -32768); {}; three beams make a three-beam solution, fewer leave the ping out",
            match thresholds {
                Thresholds {
                    correlation_min: None,
                    percent_good_min: None,
                } => "no thresholds of this reader's own".to_string(),
                Thresholds {
                    correlation_min,
                    percent_good_min,
                } => format!(
                    "and where it reaches the thresholds set: correlation {}, percent good {} (in beam coordinates)",
                    correlation_min.map_or("none".into(), |c| c.to_string()),
                    percent_good_min.map_or("none".into(), |p| format!("{p} %"))
                ),
            }
        ),
        None => "no ensemble has bottom track (ID 0x0600): no ping measured the vehicle".into(),
    };
    Ok(log)
}

/// The frame an ensemble's velocities are in, and how they are turned into the DVL's
/// axes.
fn frame_words(leader: &pd0::FixedLeader) -> String {
    let turned = match leader.frame {
        pd0::Frame::Beam => format!(
            "turned by its beams ({}°, {})",
            leader.beam_angle_deg,
            if leader.convex { "convex" } else { "concave" }
        ),
        pd0::Frame::Instrument => "as the instrument's axes".into(),
        pd0::Frame::Ship => "turned back by each ensemble's pitch and roll where levelled".into(),
        pd0::Frame::Earth => "turned back by each ensemble's heading, pitch and roll".into(),
    };
    let alignment = match leader.frame {
        pd0::Frame::Ship | pd0::Frame::Earth => String::new(),
        _ => format!(
            ", then by the heading alignment EA {:.2}°",
            leader.heading_alignment_deg
        ),
    };
    format!("{} coordinates, {turned}{alignment}", leader.frame.words())
}

impl LogSummary {
    fn empty(format: LogFormat, path: &Path) -> LogSummary {
        LogSummary {
            format,
            file: SourceFile {
                path: PathBuf::from(path),
                sha256: String::new(),
            },
            pings: 0,
            three_beam: 0,
            bad_checksums: Vec::new(),
            bytes_between: 0,
            cut_short: None,
            frames: Vec::new(),
            blocks: Vec::new(),
            validity: String::new(),
        }
    }
}

impl DvlLog {
    /// What `data info` prints of it: the span and rate, the pings kept and left out
    /// per reason, the frames, the data types and what a ping's validity is read from.
    pub fn describe(&self) -> String {
        let summary = &self.summary;
        let left_out: Vec<(LeftOutWhy, usize)> = (LeftOutWhy::ALL.into_iter())
            .map(|why| (why, self.stated.iter().filter(|&&s| s == Some(why)).count()))
            .filter(|&(_, count)| count > 0)
            .collect();
        let kept = self.stated.iter().filter(|s| s.is_none()).count();
        let (first, last) = (self.time_s[0], self.time_s[self.time_s.len() - 1]);
        let interval_s = super::sample_interval(&self.time_s);
        let mut lines = vec![
            format!(
                "{}: a {} log, {} pings over {:.2} s from {} ({:.3} s between pings, median; {:.2} Hz), SHA-256 {}",
                summary.file.path.display(),
                summary.format.words(),
                summary.pings,
                last - first,
                utc(first),
                interval_s,
                1.0 / interval_s,
                summary.file.sha256
            ),
            format!(
                "pings: {kept} with bottom lock kept ({} of them on three beams), {}",
                summary.three_beam,
                super::left_out_words(&left_out)
            ),
            format!(
                "ensembles whose checksum failed, not read: {}{}; bytes outside any ensemble: {}",
                summary.bad_checksums.len(),
                match summary.bad_checksums.first() {
                    Some(byte) => format!(" (the first at byte {byte})"),
                    None => String::new(),
                },
                summary.bytes_between
            ),
        ];
        if let Some((byte, stated, held)) = summary.cut_short {
            lines.push(format!(
                "the last ensemble, at byte {byte}, is cut short by the file's end ({held} of its {stated} bytes): not read"
            ));
        }
        lines.extend(summary.frames.iter().map(|frame| format!("frame: {frame}")));
        lines.push(format!("validity: {}", summary.validity));
        lines.push("data types (ensembles holding each):".into());
        lines.extend((summary.blocks.iter()).map(|(name, count)| format!("  {name}: {count}")));
        lines.join("\n")
    }
}

/// A time in seconds since 1970 as UTC, to the hundredth of a second.
fn utc(time_s: f64) -> String {
    chrono::DateTime::from_timestamp_millis((time_s * 1000.0).round() as i64).map_or_else(
        || format!("{time_s} s"),
        |t| t.format("%Y-%m-%d %H:%M:%S%.3f UTC").to_string(),
    )
}
