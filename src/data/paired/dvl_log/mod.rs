//! A DVL's own log as the DVL's half of a paired recording, beside a reference read
//! from CSV: Teledyne RDI's PD0 (`pd0.rs`, turned into the vehicle's axes by
//! `frames.rs`) or Water Linked's JSON reports (`water_linked.rs`); or beside the
//! attitude the log itself records ([`OwnAttitude`]), for a fit to fixes. The format
//! is found from the file's first bytes (PD0's 0x7F 0x7F, a JSON report) or named. Every ping is kept as a sample, those the instrument did not measure with
//! the reason it states (no bottom track, no velocity, too few beams of the correlation
//! or percent good asked), so that the plausibility checks count them with the
//! recording's other left-out samples; a three-beam solution is kept and counted. An
//! ensemble whose checksum fails is not a sample: it is counted in the [`LogSummary`].
//! The log's clock is read as UTC, in seconds since 1970: the reference's must be on it.
//! In: the log's path, its [`LogFormat`] and the [`Thresholds`]. Out: a [`DvlLog`], and
//! the fixes its recorder wrote into it as VmDAS navigation blocks
//! ([`navigation_fixes`]; its GGA sentences are read by [`crate::data::nmea`]).

mod frames;
pub mod pd0;
pub mod water_linked;

pub use frames::{Ping, Thresholds, instrument_to_earth, ping};

use super::{
    LeftOutWhy, Locator, PairedColumns, PairedError, ReadRecording, SourceFile, Unchecked,
};
use crate::Vec3;
use crate::data::nmea::{LoggedFix, LoggedFixes};
use std::io::Read;
use std::path::{Path, PathBuf};

/// Why a DVL log cannot be read: the file, and the ensemble's byte or the line at fault.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: the ensemble at byte {byte}: {problem}", path.display())]
    Ensemble {
        path: PathBuf,
        byte: u64,
        problem: String,
    },
    #[error("{}:{line}: {problem}", path.display())]
    Line {
        path: PathBuf,
        line: u64,
        problem: String,
    },
    #[error("{}: no PD0 ensemble (bytes 0x7F 0x7F with a checksum that holds) in {bytes} bytes", path.display())]
    Empty { path: PathBuf, bytes: u64 },
    #[error("{}: no velocity report (\"type\": \"velocity\") among its {reports} reports", path.display())]
    NoReports { path: PathBuf, reports: u64 },
    #[error("{}: this {} log records no attitude (a Water Linked log's is in its dead-reckoning reports, \"position_local\"): give the attitude's own file with --attitude", path.display(), format.words())]
    NoAttitude { path: PathBuf, format: LogFormat },
}

/// A DVL log's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LogFormat {
    /// Teledyne RDI's binary PD0.
    Pd0,
    /// Water Linked's JSON reports, one a line.
    WaterLinked,
}

impl LogFormat {
    /// The formats by the key `--dvl-format` and the spec take.
    pub const KEYS: [(&'static str, LogFormat); 2] = [
        ("pd0", LogFormat::Pd0),
        ("water-linked", LogFormat::WaterLinked),
    ];

    /// The format a key names.
    pub fn from_key(key: &str) -> Option<LogFormat> {
        (LogFormat::KEYS.iter()).find_map(|&(k, format)| (k == key).then_some(format))
    }

    pub fn words(self) -> &'static str {
        match self {
            LogFormat::Pd0 => "Teledyne RDI PD0",
            LogFormat::WaterLinked => "Water Linked JSON",
        }
    }

    /// What the log's own heading is called.
    fn own_heading(self) -> &'static str {
        match self {
            LogFormat::Pd0 => "heading",
            LogFormat::WaterLinked => "yaw",
        }
    }

    /// Where the log's own attitude comes from, in words.
    pub fn own_attitude_words(self) -> &'static str {
        match self {
            LogFormat::Pd0 => {
                "each ensemble's roll, pitch and heading: what its velocities were turned by"
            }
            LogFormat::WaterLinked => {
                "the roll, pitch and yaw of its dead-reckoning reports (\"position_local\"), the DVL's own, its yaw from its gyro: an offset from north goes into the fitted misalignment z (exactly where the vehicle is level), a drift or a reset of it is not modelled"
            }
        }
    }
}

/// How far into a file its format is looked for, bytes.
const SNIFFED: usize = 4096;

/// The DVL log format of the file at `path`, found from its first bytes: PD0 where
/// they hold 0x7F 0x7F, Water Linked's where the first is `{` and a `"type"` follows;
/// `None` for any other file (a CSV file, a folder).
pub fn format_of(path: &Path) -> Option<LogFormat> {
    let mut first = Vec::with_capacity(SNIFFED);
    let file = std::fs::File::open(path).ok()?;
    file.take(SNIFFED as u64).read_to_end(&mut first).ok()?;
    if first.windows(2).any(|pair| pair == [0x7F, 0x7F]) {
        return Some(LogFormat::Pd0);
    }
    let json =
        first.trim_ascii_start().starts_with(b"{") && first.windows(6).any(|w| w == b"\"type\"");
    json.then_some(LogFormat::WaterLinked)
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
    /// The attitude the log records, on its clock.
    pub attitude: OwnAttitude,
    /// The NMEA sentences the recorder wrote beside each ping: the ping's stamp, its
    /// number and the sentence.
    pub sentences: Vec<(f64, u64, String)>,
    /// The fixes VmDAS wrote beside each ping (its navigation block): the ping's stamp,
    /// its number and the fix.
    pub navigation: Vec<(f64, u64, pd0::NavigationFix)>,
    pub summary: LogSummary,
}

/// The attitude a DVL's log records (its own sensors', or the vehicle's it was given):
/// a PD0 ensemble's heading, pitch and roll (what its velocities were turned by), a
/// Water Linked dead-reckoning report's roll, pitch and yaw.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct OwnAttitude {
    pub time_s: Vec<f64>,
    /// Roll, pitch and yaw (the heading), degrees.
    pub roll_pitch_yaw_deg: Vec<Vec3>,
    /// Where each was read: a PD0 ensemble's number, a JSON report's line.
    pub number: Vec<u64>,
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
    /// The last line of a JSON log, where the file ends inside it.
    pub cut_short_line: Option<u64>,
    /// VmDAS navigation blocks too short to hold a fix, not read; Water Linked
    /// dead-reckoning reports with a status other than 0, not read as attitude.
    pub not_read: Vec<(&'static str, usize)>,
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
        LogFormat::WaterLinked => read_water_linked(path),
    }
}

/// Water Linked's reports: each velocity report a ping, its validity as the report
/// states it (thresholds do not apply: the DVL gives no correlation).
fn read_water_linked(path: &Path) -> Result<DvlLog, PairedError> {
    let mut log = DvlLog::empty(LogFormat::WaterLinked, path);
    let survey = water_linked::read(path, &mut |read| {
        let report = match read {
            water_linked::Read::Ping(report) => report,
            water_linked::Read::Attitude(own) => {
                log.attitude.time_s.push(own.time_s);
                log.attitude.roll_pitch_yaw_deg.push(own.roll_pitch_yaw_deg);
                log.attitude.number.push(own.line);
                return;
            }
        };
        let stated = if report.water_track {
            Some(LeftOutWhy::WaterTrack)
        } else if !report.velocity_valid {
            Some(LeftOutWhy::Flagged)
        } else {
            None
        };
        log.summary.three_beam += usize::from(stated.is_none() && report.beams_valid == 3);
        log.time_s.push(report.time_s);
        log.velocity_m_s.push(match stated {
            None => report.velocity_m_s,
            Some(_) => [f64::NAN; 3],
        });
        log.stated.push(stated);
        log.number.push(report.line);
    })?;
    if log.time_s.is_empty() {
        let reports = survey.types.values().sum::<usize>() as u64;
        return Err(LogError::NoReports {
            path: path.to_path_buf(),
            reports,
        }
        .into());
    }
    let summary = &mut log.summary;
    summary.file.sha256 = survey.sha256;
    summary.pings = log.time_s.len();
    summary.cut_short_line = survey.cut_short;
    summary.not_read = vec![(
        "dead-reckoning reports with a status other than 0, not read as attitude",
        survey.attitude_not_ok,
    )];
    summary.frames = vec![
        "the DVL's body frame (x forward, y right, z down), as its velocity reports give it".into(),
    ];
    summary.blocks = (survey
        .types
        .iter()
        .map(|(kind, &n)| (format!("\"{kind}\" reports"), n)))
    .chain(
        survey
            .formats
            .iter()
            .map(|(format, &n)| (format!("format {format}"), n)),
    )
    .collect();
    summary.validity = "a velocity report's velocity_valid (false: flagged invalid) and its type (velocity_water: water tracking, left out); three transducers with beam_valid make a three-beam solution, kept and counted".into();
    Ok(log)
}

fn read_pd0(path: &Path, thresholds: Thresholds) -> Result<DvlLog, PairedError> {
    let mut log = DvlLog::empty(LogFormat::Pd0, path);
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
            applied.get_or_insert((bottom.correlation_min, bottom.amplitude_min));
        }
        log.time_s.push(ensemble.time_s);
        log.velocity_m_s.push(velocity_m_s);
        log.stated.push(stated);
        log.number.push(u64::from(ensemble.number));
        let (time_s, number) = (ensemble.time_s, u64::from(ensemble.number));
        log.attitude.time_s.push(time_s);
        (log.attitude.roll_pitch_yaw_deg).push(frames::roll_pitch_yaw_deg(&ensemble));
        log.attitude.number.push(number);
        (log.sentences).extend(ensemble.sentences.into_iter().map(|s| (time_s, number, s)));
        (log.navigation).extend(ensemble.navigation.map(|fix| (time_s, number, fix)));
    })?;
    let summary = &mut log.summary;
    summary.file.sha256 = survey.sha256;
    summary.pings = survey.ensembles;
    summary.bad_checksums = survey.bad_checksums;
    summary.bytes_between = survey.bytes_between;
    summary.cut_short = survey.cut_short;
    summary.not_read = vec![(
        "VmDAS navigation blocks too short to hold a fix",
        survey.short_navigation,
    )];
    summary.frames = frames;
    summary.blocks = (survey.blocks.iter())
        .map(|(&id, &count)| (format!("0x{id:04X} {}", pd0::block_name(id)), count))
        .collect();
    summary.validity = validity_words(applied, thresholds);
    Ok(log)
}

/// What the checks' messages call a log's velocity, by axis: the vehicle's, from
/// bottom track.
pub const VELOCITY_NAMES: [&str; 3] = [
    "bottom track forward",
    "bottom track starboard",
    "bottom track down",
];

/// The log at `path` as a recording of the DVL beside its own attitude ([`OwnAttitude`],
/// on the log's clock), checked as any recording: the reference has no velocity, for a
/// calibration against fixes; and the log as read.
pub fn read_beside_own_attitude(
    path: &Path,
    format: LogFormat,
    thresholds: Thresholds,
) -> Result<(ReadRecording, DvlLog), PairedError> {
    let log = read(path, format, thresholds)?;
    if log.attitude.time_s.is_empty() {
        return Err(LogError::NoAttitude {
            path: path.to_path_buf(),
            format,
        }
        .into());
    }
    let samples = Unchecked {
        dvl_time_s: log.time_s.clone(),
        dvl_m_s: log.velocity_m_s.clone(),
        dvl_stated: Some(log.stated.clone()),
        reference_time_s: log.attitude.time_s.clone(),
        velocity_ned_m_s: Vec::new(),
        attitude: log.attitude.roll_pitch_yaw_deg.clone(),
        rate: None,
        angles_in_degrees: true,
        position: None,
        reference_read: None,
    };
    let mut names = PairedColumns::akit();
    names.time = "clock".into();
    names.dvl = VELOCITY_NAMES.map(String::from);
    names.attitude = ["roll", "pitch", format.own_heading()].map(String::from);
    let at = Locator {
        dvl: path.to_path_buf(),
        reference: path.to_path_buf(),
        dvl_lines: log.number.clone(),
        reference_lines: log.attitude.number.clone(),
        names,
    };
    let read = ReadRecording {
        recording: super::checks::check(samples, &at)?,
        files: vec![log.summary.file.clone()],
        frames: None,
    };
    Ok((read, log))
}

/// Why a VmDAS navigation block gives no fix.
const NAVIGATION_LEFT_OUT: [&str; 3] = [
    "a VmDAS navigation block whose position is flagged invalid",
    "a VmDAS navigation block whose date and time are flagged invalid, or no date",
    "a VmDAS navigation block whose fix is stamped at or before the previous one, at another position",
];

/// The fixes of the VmDAS navigation blocks of `log`, each block's last fix before its
/// ping, on UTC (a block repeating the fix before, where pings outpace the GNSS, is that
/// fix, read once and counted among [`LoggedFixes::others`]); `None` where no block
/// gives one.
pub fn navigation_fixes(log: &DvlLog) -> Option<LoggedFixes> {
    let (mut counts, mut repeats) = ([0usize; 3], 0);
    let mut fixes: Vec<LoggedFix> = Vec::new();
    for &(stamp_s, place, fix) in &log.navigation {
        let time_s = match (fix.position_valid, fix.time_valid, fix.time_s) {
            (false, ..) => {
                counts[0] += 1;
                continue;
            }
            (true, true, Some(time_s)) => time_s,
            (true, ..) => {
                counts[1] += 1;
                continue;
            }
        };
        let position_deg = [fix.latitude_deg, fix.longitude_deg];
        match fixes.last() {
            Some(last) if (last.time_s, last.position_deg) == (time_s, position_deg) => {
                repeats += 1;
                continue;
            }
            Some(last) if time_s <= last.time_s => {
                counts[2] += 1;
                continue;
            }
            _ => {}
        }
        fixes.push(LoggedFix {
            stamp_s,
            place,
            time_s,
            position_deg,
        });
    }
    let left_out = NAVIGATION_LEFT_OUT.into_iter().zip(counts).collect();
    LoggedFixes::new(&fixes, left_out, (repeats, 0))
}

/// What a PD0 ping's validity is read from, in words: `applied`, the instrument's
/// thresholds (BC, BA) where any ensemble has bottom track, and those set.
fn validity_words(applied: Option<(u8, u8)>, thresholds: Thresholds) -> String {
    match applied {
        Some((correlation, amplitude)) => format!(
            "bottom track (ID 0x0600): out of beam coordinates a ping counts where the instrument gave x, y and z, in beam coordinates a beam counts where it has a velocity (the instrument marks those below its own thresholds, here BC {correlation} and BA {amplitude}, with -32768); {}; three beams make a three-beam solution, fewer leave the ping out",
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
    }
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
        pd0::Frame::Ship => {
            "turned back into the instrument's by EA and, where levelled, each ensemble's pitch and roll".into()
        }
        pd0::Frame::Earth => "turned back by each ensemble's heading, pitch and roll".into(),
    };
    let alignment = format!(
        ", then into the vehicle's by the heading alignment EA {:.2}°",
        leader.heading_alignment_deg
    );
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
            cut_short_line: None,
            not_read: Vec::new(),
            frames: Vec::new(),
            blocks: Vec::new(),
            validity: String::new(),
        }
    }
}

impl DvlLog {
    fn empty(format: LogFormat, path: &Path) -> DvlLog {
        DvlLog {
            time_s: Vec::new(),
            velocity_m_s: Vec::new(),
            stated: Vec::new(),
            number: Vec::new(),
            attitude: OwnAttitude::default(),
            sentences: Vec::new(),
            navigation: Vec::new(),
            summary: LogSummary::empty(format, path),
        }
    }

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
        let rate = match self.time_s.len() {
            1 => "one ping".to_string(),
            n => format!(
                "{n} pings over {:.2} s from {} ({interval_s:.3} s between pings, median; {:.2} Hz)",
                last - first,
                utc(first),
                1.0 / interval_s
            ),
        };
        let mut lines = vec![
            format!(
                "{}: a {} log, {rate}, SHA-256 {}",
                summary.file.path.display(),
                summary.format.words(),
                summary.file.sha256
            ),
            format!(
                "pings: {kept} with bottom lock kept ({} of them on three beams), {}",
                summary.three_beam,
                super::left_out_words(&left_out)
            ),
        ];
        if summary.format == LogFormat::Pd0 {
            lines.push(format!(
                "ensembles whose checksum failed, not read: {}{}; bytes outside any ensemble: {}",
                summary.bad_checksums.len(),
                match summary.bad_checksums.first() {
                    Some(byte) => format!(" (the first at byte {byte})"),
                    None => String::new(),
                },
                summary.bytes_between
            ));
        }
        if let Some((byte, stated, held)) = summary.cut_short {
            lines.push(format!(
                "the last ensemble, at byte {byte}, is cut short by the file's end ({held} of its {stated} bytes): not read"
            ));
        }
        if let Some(line) = summary.cut_short_line {
            lines.push(format!(
                "the last line, {line}, is cut short by the file's end (no JSON report): not read"
            ));
        }
        for &(what, count) in summary.not_read.iter().filter(|(_, count)| *count > 0) {
            lines.push(format!("not read: {count} {what}"));
        }
        lines.extend(summary.frames.iter().map(|frame| format!("frame: {frame}")));
        lines.push(format!("validity: {}", summary.validity));
        lines.push(match summary.format {
            LogFormat::Pd0 => "data types (ensembles holding each):".into(),
            LogFormat::WaterLinked => "reports (lines of each type, and of each format):".into(),
        });
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
