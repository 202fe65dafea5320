//! A DVL recorded beside a reference with attitude: per sample, the time, the DVL's
//! velocity in its body frame, and the reference's NED velocity, roll, pitch and yaw
//! (optionally its body angular rate). A recording is read through one way in, a
//! [`Source`] (`source.rs`): one or two CSV files whose columns the spec names, or a
//! ROS 2 bag ([`bag`], its own room)
//! (`columns.rs`, the A-KIT names by default, [`PairedColumns::akit`]), parsed by
//! `csv.rs`; each file is read from disk once and hashed as it is read. Every sample is
//! checked, whatever the format (`checks.rs`): a field that is missing, empty, not a
//! number or not finite (as [`crate::data::csv`] checks it), time stamps that go back
//! or repeat, roll or pitch out of range, a velocity beyond a vehicle's, a body rate or
//! an attitude jump beyond a vehicle's turn, a DVL and a reference of other lengths or
//! times, fewer than 3 samples: each is an error (`error.rs`) naming the file, the line
//! (the header is line 1) and the column, and nothing is returned.
//! In: a [`Source`]. Out: a [`ReadRecording`]: the [`PairedRecording`], angles in
//! radians, and the SHA-256 of each of its files.

pub mod bag;
mod checks;
pub mod dvl_log;
mod columns;
mod csv;
mod error;
mod source;

pub use crate::files::SourceFile;
pub use checks::{Locator, Unchecked};
pub use columns::{GapLimit, PairedColumns, PairedFiles};
pub use error::{PairedError, left_out_words};
pub use source::{Loaded, ReadRecording, Recordings, Source, read_log_beside_attitude};

use crate::Vec3;
use std::ops::Range;
use std::path::Path;

/// The fewest samples a recording may have.
pub const MIN_SAMPLES: usize = 3;

/// The largest DVL velocity component read as data, m/s: beyond it a value is a
/// bad-velocity marker or another unit, not a vehicle's motion.
pub const MAX_DVL_SPEED_M_S: f64 = 20.0;

/// The fastest turn read as data, rad/s (115 °/s): a recorded body rate beyond it, or
/// an attitude that changes faster between two samples, is a glitch or another unit,
/// not a vehicle's motion.
pub const MAX_BODY_RATE_RAD_S: f64 = 2.0;

/// The smallest share of a DVL's samples a recording must keep: below it the DVL
/// mostly did not measure (or its validity column, or `zero_is_valid`, is read wrongly),
/// and what is left does not stand for the dive.
pub const MIN_KEPT_SHARE: f64 = 0.25;

/// A gap in the reference longer than this many of its median sample intervals is not
/// read across.
pub const REFERENCE_GAP_INTERVALS: f64 = 3.0;

/// A step between two of the DVL's valid samples longer than this many of its median
/// sample intervals cuts the recording into pieces (where the recording sets no gap
/// limit of its own): a few missed pings are noise, a longer silence a lost bottom lock.
pub const DVL_GAP_INTERVALS: f64 = 3.0;

/// How far from a reference gap a DVL sample is left out, s: the largest time offset a
/// fit considers, so that no t + τ it tries falls in the gap.
pub const GAP_MARGIN_S: f64 = 3.0;

/// The velocity a Teledyne RDI DVL (PD0) sends for an axis it did not measure, m/s
/// (−32768 mm/s).
pub const INVALID_MARKER_M_S: f64 = -32.768;

/// Why a DVL sample is left out of the recording, counted, never repaired: the DVL did
/// not measure it (it lost bottom lock, mostly), or the reference has a gap where it
/// would be read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum LeftOutWhy {
    /// Its validity column says so.
    Flagged,
    /// A velocity cell empty or NaN.
    NoVelocity,
    /// The invalid marker, [`INVALID_MARKER_M_S`], on an axis (in a DVL's log: no
    /// velocity on an axis, or on more than one beam).
    Marker,
    /// Exactly 0, 0, 0: what many DVLs and drivers send without bottom lock (unless
    /// the recording says zero is a valid reading).
    AllZero,
    /// Fewer than three beams with the correlation the thresholds ask (a DVL's log).
    LowCorrelation,
    /// Fewer than three beams with the percent good the thresholds ask (a DVL's log).
    LowPercentGood,
    /// Tracking the water, not the bottom (a DVL's log).
    WaterTrack,
    /// The DVL looking up (a PD0 ensemble's system configuration): no bottom below.
    LookingUp,
    /// Stamped within [`GAP_MARGIN_S`] of a gap in the reference longer than
    /// [`REFERENCE_GAP_INTERVALS`] of its median sample intervals: its t + τ may fall in
    /// the gap, where the reference is not read.
    ReferenceGap,
}

impl LeftOutWhy {
    /// Every reason, in the order they are tested and reported.
    pub const ALL: [LeftOutWhy; 9] = [
        LeftOutWhy::Flagged,
        LeftOutWhy::NoVelocity,
        LeftOutWhy::Marker,
        LeftOutWhy::AllZero,
        LeftOutWhy::LowCorrelation,
        LeftOutWhy::LowPercentGood,
        LeftOutWhy::WaterTrack,
        LeftOutWhy::LookingUp,
        LeftOutWhy::ReferenceGap,
    ];

    /// The reason as a key, the corrected recording's `left_out` column.
    pub fn key(self) -> &'static str {
        match self {
            LeftOutWhy::Flagged => "flagged",
            LeftOutWhy::NoVelocity => "no_velocity",
            LeftOutWhy::Marker => "invalid_marker",
            LeftOutWhy::AllZero => "all_zero",
            LeftOutWhy::LowCorrelation => "low_correlation",
            LeftOutWhy::LowPercentGood => "low_percent_good",
            LeftOutWhy::WaterTrack => "water_track",
            LeftOutWhy::LookingUp => "looking_up",
            LeftOutWhy::ReferenceGap => "reference_gap",
        }
    }

    /// The reason in words, as a count of them reads it ("3 flagged invalid").
    pub fn words(self) -> &'static str {
        match self {
            LeftOutWhy::Flagged => "flagged invalid",
            LeftOutWhy::NoVelocity => "with no velocity",
            LeftOutWhy::Marker => "with the invalid marker -32.768 m/s",
            LeftOutWhy::AllZero => "of exactly 0, 0, 0",
            LeftOutWhy::LowCorrelation => "with fewer than 3 beams of the correlation asked",
            LeftOutWhy::LowPercentGood => "with fewer than 3 beams of the percent good asked",
            LeftOutWhy::WaterTrack => "tracking the water, not the bottom",
            LeftOutWhy::LookingUp => "with the DVL looking up",
            LeftOutWhy::ReferenceGap => "beside a gap in the reference",
        }
    }
}

/// How many samples a recording read: the DVL's kept, those left out per reason, and
/// the reference's; and the pieces its gaps cut it into. Shown as `the DVL's 400
/// samples, 370 kept (30 left out: 30 with no velocity), beside the reference's 4000 on
/// its own stamps; 2 pieces (gaps over 3.00 s cut it), the longest loss 31.00 s`.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadCounts {
    pub kept: usize,
    pub left_out: Vec<(LeftOutWhy, usize)>,
    pub reference: usize,
    /// What the reference's samples are: `reference`, or `attitude` where a calibration
    /// against fixes reads only the attitude of the second file.
    pub beside: &'static str,
    pub pieces: usize,
    pub gap_limit_s: f64,
    /// The longest step between two kept DVL samples, s.
    pub longest_loss_s: f64,
    /// What an NMEA reference gave, and left out.
    pub reference_read: Option<crate::data::nmea::reference::SentencesRead>,
}

impl ReadCounts {
    /// How many DVL samples were read: those kept and those left out.
    pub fn read(&self) -> usize {
        self.kept + self.left_out.iter().map(|(_, n)| n).sum::<usize>()
    }

    /// The same counts, the second file read as the attitude beside fixes.
    pub fn beside_attitude(self) -> ReadCounts {
        ReadCounts {
            beside: "attitude",
            ..self
        }
    }
}

impl std::fmt::Display for ReadCounts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the DVL's {} samples, {} kept ({}), beside the {}'s {} on its own stamps; {} (gaps over {:.2} s cut it), the longest loss {:.2} s",
            self.read(),
            self.kept,
            left_out_words(&self.left_out),
            self.beside,
            self.reference,
            match self.pieces {
                1 => "one piece".to_string(),
                n => format!("{n} pieces"),
            },
            self.gap_limit_s,
            self.longest_loss_s,
        )?;
        match &self.reference_read {
            Some(read) => write!(f, "; the {}: {read}", self.beside),
            None => Ok(()),
        }
    }
}

/// A DVL sample left out of a recording: its stamp, the line (or message) it came from,
/// and why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeftOut {
    pub time_s: f64,
    pub line: u64,
    pub why: LeftOutWhy,
}

/// The median interval between two samples, s (0 with fewer than two).
pub fn sample_interval(time: &[f64]) -> f64 {
    let mut steps: Vec<f64> = time.windows(2).map(|w| w[1] - w[0]).collect();
    if steps.is_empty() {
        return 0.0;
    }
    steps.sort_by(f64::total_cmp);
    steps[steps.len() / 2]
}

/// Where the DVL record stamped `time_s` (strictly increasing) is cut into pieces: the
/// ranges of its samples between steps longer than `gap_limit_s`, in order (none for
/// an empty record).
pub fn pieces(time_s: &[f64], gap_limit_s: f64) -> Vec<Range<usize>> {
    let mut pieces = Vec::new();
    let mut start = 0;
    for i in 1..=time_s.len() {
        if i == time_s.len() || time_s[i] - time_s[i - 1] > gap_limit_s {
            pieces.push(start..i);
            start = i;
        }
    }
    pieces
}

/// The gap limit of a DVL stamped `time_s` (all its samples, kept or not) that sets
/// none of its own: [`DVL_GAP_INTERVALS`] of its median interval.
pub fn default_gap_limit_s(time_s: &[f64]) -> f64 {
    DVL_GAP_INTERVALS * sample_interval(time_s)
}

/// One recording: the DVL as measured, on its own clock and at its own rate, and the
/// reference, on its own.
#[derive(Debug, Clone, PartialEq)]
pub struct PairedRecording {
    /// The DVL's valid samples' stamps, seconds on its clock, strictly increasing.
    pub time_s: Vec<f64>,
    /// The DVL's velocity in its body frame (x forward, y starboard, z down), m/s, at
    /// `time_s`.
    pub dvl_m_s: Vec<Vec3>,
    /// The DVL's samples it did not measure, left out of `time_s` and `dvl_m_s`, in
    /// the order of their stamps.
    pub left_out: Vec<LeftOut>,
    /// The reference's stamps, seconds on its clock, strictly increasing; the fields
    /// below are on them.
    pub reference_time_s: Vec<f64>,
    /// The reference's velocity, north, east, down, m/s; empty where the reference is an
    /// attitude alone (beside position fixes, `data::fixes`), which nothing
    /// compares a DVL's velocity with.
    pub velocity_ned_m_s: Vec<Vec3>,
    /// Roll, pitch, yaw in radians, as recorded (yaw may wrap at ±π, or run on unwrapped).
    pub attitude_rad: Vec<Vec3>,
    /// The reference's body angular rate (p, q, r) in rad/s, when recorded.
    pub rate_rad_s: Option<Vec<Vec3>>,
    /// The reference's position, when recorded: north and east, metres, of its first
    /// sample where it records latitude and longitude (or of the point its north and
    /// east are from): what a dead reckoning's drift is scored against.
    pub position_ne_m: Option<Vec<[f64; 2]>>,
    /// The longest step between two kept DVL samples of one piece, s: everything that
    /// runs in time runs within pieces ([`pieces`]).
    pub gap_limit_s: f64,
    /// What an NMEA reference's file gave, and left out, sentence by sentence (of the
    /// whole file, in a window of it too); `None` for any other reference.
    pub reference_read: Option<crate::data::nmea::reference::SentencesRead>,
}

/// How close two recordings' stamps (s) and DVL velocities (m/s) lie, each sample's,
/// for them to be one recording written twice: a millisecond and a millimetre per
/// second, far below any DVL's noise and rate, far above the rounding of a file written
/// again with other digits.
pub const SAME_SAMPLES_WITHIN: (f64, f64) = (1e-3, 1e-3);

impl PairedRecording {
    /// Whether `other` holds the same DVL samples, each stamp and velocity within
    /// [`SAME_SAMPLES_WITHIN`] of its own: one recording written twice.
    pub fn same_samples(&self, other: &PairedRecording) -> bool {
        let (time_s, velocity_m_s) = SAME_SAMPLES_WITHIN;
        self.len() == other.len()
            && (self.time_s.iter().zip(&other.time_s)).all(|(a, b)| (a - b).abs() <= time_s)
            && (self.dvl_m_s.iter().zip(&other.dvl_m_s))
                .all(|(a, b)| (0..3).all(|k| (a[k] - b[k]).abs() <= velocity_m_s))
    }

    /// How many samples it has.
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// From its first time stamp to its last, seconds.
    pub fn duration_s(&self) -> f64 {
        match (self.time_s.first(), self.time_s.last()) {
            (Some(first), Some(last)) => last - first,
            _ => 0.0,
        }
    }

    /// How many samples it read, kept and left out, and its pieces.
    pub fn counts(&self) -> ReadCounts {
        ReadCounts {
            kept: self.len(),
            left_out: self.left_out_counts(),
            reference: self.reference_time_s.len(),
            beside: "reference",
            pieces: self.pieces().len(),
            gap_limit_s: self.gap_limit_s,
            longest_loss_s: (self.time_s.windows(2))
                .map(|pair| pair[1] - pair[0])
                .fold(0.0, f64::max),
            reference_read: self.reference_read.clone(),
        }
    }

    /// Its kept DVL samples cut at every step longer than its gap limit.
    pub fn pieces(&self) -> Vec<Range<usize>> {
        pieces(&self.time_s, self.gap_limit_s)
    }

    /// How many DVL samples were left out for each reason, in [`LeftOutWhy::ALL`]'s order
    /// (the reasons with none left out are not listed).
    pub fn left_out_counts(&self) -> Vec<(LeftOutWhy, usize)> {
        LeftOutWhy::ALL
            .into_iter()
            .map(|why| (why, self.left_out.iter().filter(|l| l.why == why).count()))
            .filter(|&(_, count)| count > 0)
            .collect()
    }

    /// The samples, of the DVL and of the reference, stamped less than `window_s`
    /// after the DVL's first valid sample: the first `window_s` seconds (all of it
    /// where the recording is shorter).
    pub fn first_seconds(&self, window_s: f64) -> PairedRecording {
        let start = self.time_s.first().copied().unwrap_or_default();
        let within = |time: &[f64]| time.partition_point(|t| t - start < window_s);
        let (dvl_end, reference_end) = (within(&self.time_s), within(&self.reference_time_s));
        let reference = 0..reference_end;
        PairedRecording {
            time_s: self.time_s[..dvl_end].to_vec(),
            dvl_m_s: self.dvl_m_s[..dvl_end].to_vec(),
            left_out: (self.left_out.iter())
                .filter(|l| l.time_s - start < window_s)
                .copied()
                .collect(),
            reference_time_s: self.reference_time_s[reference.clone()].to_vec(),
            velocity_ned_m_s: self.velocity_ned_m_s[reference.clone()].to_vec(),
            attitude_rad: self.attitude_rad[reference.clone()].to_vec(),
            rate_rad_s: self
                .rate_rad_s
                .as_ref()
                .map(|rate| rate[reference.clone()].to_vec()),
            position_ne_m: (self.position_ne_m.as_ref())
                .map(|position| position[reference].to_vec()),
            gap_limit_s: self.gap_limit_s,
            reference_read: self.reference_read.clone(),
        }
    }
}

/// The DVL of the CSV file `dvl` beside the reference of `reference` that records an
/// attitude and no velocity, read with `columns` (whose velocity names are not read)
/// and checked as any recording's: `velocity_ned_m_s` is empty.
pub fn read_without_velocity(
    dvl: &Path,
    reference: &Path,
    columns: &PairedColumns,
) -> Result<ReadRecording, PairedError> {
    let mut files = Vec::new();
    let mut bytes = Vec::new();
    for path in [dvl, reference] {
        let read = crate::data::csv::read_bytes(path)?;
        files.push(SourceFile {
            path: path.to_path_buf(),
            sha256: crate::files::sha256_hex(&read),
        });
        bytes.push(read);
    }
    let (samples, at) = csv::parse(
        (dvl, &bytes[0]),
        Some((reference, &bytes[1])),
        columns,
        false,
    )?;
    Ok(ReadRecording {
        recording: checks::check(samples, &at)?,
        files,
        frames: None,
    })
}

/// The DVL and the reference's attitude of the bag at `path`, read as `topics` says and
/// checked as [`read_without_velocity`] checks a CSV recording: the reference's
/// velocity is not read (an AHRS's odometry may carry none worth the name).
pub fn read_bag_without_velocity(
    path: &Path,
    topics: &bag::BagTopics,
) -> Result<ReadRecording, PairedError> {
    let read = bag::read(path, topics)?;
    let mut samples = read.samples;
    samples.velocity_ned_m_s.clear();
    Ok(ReadRecording {
        recording: checks::check(samples, &read.at)?,
        files: read.files,
        frames: Some(read.frames),
    })
}

/// The checked samples of the CSV files `files` with `columns`: a shorthand of
/// [`Source::read`] for a caller that wants neither the files' hashes nor a cache.
pub fn read(files: &PairedFiles, columns: &PairedColumns) -> Result<PairedRecording, PairedError> {
    Source::csv(&files.dvl, Some(&files.reference), columns.clone())
        .read()
        .map(|read| read.recording)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::catalogue;
    use std::f64::consts::PI;
    use std::path::{Path, PathBuf};

    /// Columns of a small recording in one file: `t, u, v, w, n, e, d, roll, pitch, yaw`.
    pub(super) fn short_columns() -> PairedColumns {
        let names = |names: [&str; 3]| names.map(String::from);
        PairedColumns {
            time: "t".into(),
            dvl: names(["u", "v", "w"]),
            velocity_ned: names(["n", "e", "d"]),
            attitude: names(["roll", "pitch", "yaw"]),
            rate: None,
            angles_in_degrees: false,
            valid: None,
            zero_is_valid: false,
            gap_limit_s: None,
            latitude_longitude: None,
            north_east: None,
        }
    }

    const DVL_HEADER: &str = "Time [s],DVL X [m/s],DVL Y [m/s],DVL Z [m/s]\r\n";
    const GT_HEADER: &str = "Time [s],Longitude [rad],Latitude [rad],Altitude [m],V North [m/s],V East [m/s],V Down [m/s],Roll [rad],Pitch [rad],Yaw [rad]\r\n";

    /// Four rows of an A-KIT DVL file, half a second apart.
    const DVL_ROWS: &str = "0,1.5,0.1,-0.01\r\n\
                            0.5,2.5,0.1,-0.01\r\n\
                            1,3.5,0.1,-0.01\r\n\
                            1.5,4.5,0.1,-0.01\r\n";

    /// Four rows of an A-KIT reference (GT) file, on the time stamps of [`DVL_ROWS`].
    const GT_ROWS: &str = "0,0.6,0.57,-19.8,-1.9,-0.6,0.01,0.01,-0.02,-3\r\n\
                           0.5,0.6,0.57,-19.8,-2.9,-0.6,0.01,0.01,-0.02,-2.5\r\n\
                           1,0.6,0.57,-19.8,-3.9,-0.6,0.01,0.01,-0.02,-2\r\n\
                           1.5,0.6,0.57,-19.8,-4.9,-0.6,0.01,0.01,-0.02,-1.5\r\n";

    /// `header` and the first `count` lines of `rows`.
    fn file(header: &str, rows: &str, count: usize) -> String {
        let rows: String = rows.split_inclusive('\n').take(count).collect();
        format!("{header}{rows}")
    }

    fn assert_close(actual: Vec3, expected: Vec3) {
        for (a, e) in actual.iter().zip(expected) {
            assert!((a - e).abs() < 1e-12, "{actual:?} against {expected:?}");
        }
    }
    /// Reads `dvl` and `gt` as the two files of an A-KIT segment; errors with the
    /// files' paths shown as DVL and GT.
    fn read_two(dvl: &str, gt: &str) -> Result<PairedRecording, String> {
        let dir = tempfile::tempdir().unwrap();
        let files = PairedFiles {
            dvl: dir.path().join("dvl.csv"),
            reference: dir.path().join("gt.csv"),
        };
        std::fs::write(&files.dvl, dvl).unwrap();
        std::fs::write(&files.reference, gt).unwrap();
        read(&files, &PairedColumns::akit()).map_err(|e| {
            e.to_string()
                .replace(&files.dvl.display().to_string(), "DVL")
                .replace(&files.reference.display().to_string(), "GT")
        })
    }

    /// Reads `text` as one file holding the DVL and the reference, with `columns`;
    /// errors with the file's path shown as FILE.
    fn read_one(text: &str, columns: &PairedColumns) -> Result<PairedRecording, String> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("both.csv");
        std::fs::write(&path, text).unwrap();
        let files = PairedFiles {
            dvl: path.clone(),
            reference: path.clone(),
        };
        read(&files, columns)
            .map_err(|e| e.to_string().replace(&path.display().to_string(), "FILE"))
    }

    #[test]
    fn reads_the_akit_layout_from_two_files() {
        let recording =
            read_two(&file(DVL_HEADER, DVL_ROWS, 3), &file(GT_HEADER, GT_ROWS, 3)).unwrap();
        assert_eq!(recording.time_s, vec![0.0, 0.5, 1.0]);
        assert_eq!(recording.dvl_m_s[2], [3.5, 0.1, -0.01]);
        assert_eq!(recording.velocity_ned_m_s[1], [-2.9, -0.6, 0.01]);
        assert_eq!(recording.attitude_rad[2], [0.01, -0.02, -2.0]);
        assert_eq!(recording.rate_rad_s, None);
        assert_eq!(recording.len(), 3);
        assert_eq!(recording.duration_s(), 1.0);
    }

    #[test]
    fn reads_one_file_in_degrees_with_a_rate_and_cuts_it() {
        let mut columns = short_columns();
        columns.rate = Some(["p", "q", "r"].map(String::from));
        columns.angles_in_degrees = true;
        // Seconds apart, so that no angle turns faster than a vehicle between them.
        let text = "t,u,v,w,n,e,d,roll,pitch,yaw,p,q,r\n\
                    0,1,2,3,4,5,6,180,-90,-360,0,0,90\n\
                    5,1,2,3,4,5,6,0,45,270,0,0,-90\n\
                    10,1,2,3,4,5,6,0,0,0,0,0,0\n\
                    15,1,2,3,4,5,6,0,0,0,0,0,0\n";
        let recording = read_one(text, &columns).unwrap();
        assert_eq!(recording.dvl_m_s[0], [1.0, 2.0, 3.0]);
        assert_eq!(recording.velocity_ned_m_s[0], [4.0, 5.0, 6.0]);
        assert_close(recording.attitude_rad[0], [PI, -PI / 2.0, -2.0 * PI]);
        assert_close(recording.attitude_rad[1], [0.0, PI / 4.0, 1.5 * PI]);
        let rate = recording.rate_rad_s.as_ref().unwrap();
        assert_close(rate[0], [0.0, 0.0, PI / 2.0]);
        assert_close(rate[1], [0.0, 0.0, -PI / 2.0]);
        let first = recording.first_seconds(6.0);
        assert_eq!(first.time_s, vec![0.0, 5.0]);
        assert_eq!(first.rate_rad_s.as_ref().unwrap().len(), 2);
        assert_eq!(recording.first_seconds(100.0), recording);
    }

    #[test]
    fn a_missing_file_or_column_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let files = PairedFiles::akit(dir.path(), 4);
        let error = read(&files, &PairedColumns::akit())
            .unwrap_err()
            .to_string();
        assert_eq!(
            error,
            format!(
                "{}: file not found; run `dcnet-exp data fetch akit --dest {}` to download the A-KIT recordings there",
                files.dvl.display(),
                dir.path().display()
            )
        );
        let files = PairedFiles {
            dvl: dir.path().join("mine.csv"),
            reference: dir.path().join("mine.csv"),
        };
        assert_eq!(
            read(&files, &PairedColumns::akit())
                .unwrap_err()
                .to_string(),
            format!("{}: file not found", files.dvl.display())
        );
        // The reference is missing where the DVL is there.
        let dvl_only = tempfile::tempdir().unwrap();
        let files = PairedFiles::akit(dvl_only.path(), 12);
        std::fs::create_dir(files.dvl.parent().unwrap()).unwrap();
        std::fs::write(&files.dvl, file(DVL_HEADER, DVL_ROWS, 4)).unwrap();
        assert!(
            read(&files, &PairedColumns::akit())
                .unwrap_err()
                .to_string()
                .starts_with(&format!(
                    "{}: file not found; run",
                    files.reference.display()
                ))
        );
        let gt = GT_HEADER.replace(",Pitch [rad]", ",Pitch[rad]");
        assert_eq!(
            read_two(&file(DVL_HEADER, DVL_ROWS, 3), &file(&gt, GT_ROWS, 3)).unwrap_err(),
            "GT:1: Pitch [rad]: not in the header, which has Time [s], Longitude [rad], Latitude [rad], Altitude [m], V North [m/s], V East [m/s], V Down [m/s], Roll [rad], Pitch[rad], Yaw [rad]"
        );
    }

    #[test]
    fn a_bad_field_names_the_line_the_column_and_what_it_holds() {
        let dvl = file(DVL_HEADER, DVL_ROWS, 4);
        let gt = file(GT_HEADER, GT_ROWS, 4);
        for (dvl, gt, expected) in [
            (
                dvl.replace("\r\n1,", "\r\n,"),
                gt.clone(),
                "DVL:4: Time [s]: empty: every row needs a time stamp",
            ),
            (
                dvl.replace(",2.5,", ",fast,"),
                gt.clone(),
                "DVL:3: DVL X [m/s]: \"fast\" is not a number",
            ),
            (
                dvl.clone(),
                gt.replace(",-2.9,", ",inf,"),
                "GT:3: V North [m/s]: \"inf\" is not finite: every velocity must be a finite number",
            ),
            (
                dvl.clone(),
                gt.replace(",-2.5\r\n", ",NaN\r\n"),
                "GT:3: Yaw [rad]: \"NaN\" is not finite: every angle must be a finite number",
            ),
            (
                dvl.clone(),
                gt.replace(",-0.02,-2.5\r\n", ",,-2.5\r\n"),
                "GT:3: Pitch [rad]: empty: every row needs an angle",
            ),
        ] {
            assert_eq!(read_two(&dvl, &gt).unwrap_err(), expected);
        }
        let mut columns = short_columns();
        columns.rate = Some(["p", "q", "r"].map(String::from));
        assert_eq!(
            read_one(
                "t,u,v,w,n,e,d,roll,pitch,yaw,p,q,r\n0,1,2,3,4,5,6,0,0,0,0,-inf,0\n",
                &columns
            )
            .unwrap_err(),
            "FILE:2: q: \"-inf\" is not finite: every angular rate must be a finite number"
        );
    }

    #[test]
    fn time_stamps_that_go_back_or_repeat_name_both_lines() {
        let dvl = file(DVL_HEADER, DVL_ROWS, 4);
        let gt = file(GT_HEADER, GT_ROWS, 4);
        assert_eq!(
            read_two(&dvl.replace("\r\n1,", "\r\n0.5,"), &gt).unwrap_err(),
            "DVL:4: Time [s]: 0.5 s follows 0.5 s of line 3: time stamps must increase"
        );
        assert_eq!(
            read_two(&dvl, &gt.replace("\r\n1.5,", "\r\n0.25,")).unwrap_err(),
            "GT:5: Time [s]: 0.25 s follows 1 s of line 4: time stamps must increase"
        );
    }

    /// A velocity, a recorded rate or a turn between two samples beyond a vehicle's is
    /// refused at its line; a heading that runs on beyond a turn is not.
    #[test]
    fn motion_beyond_a_vehicles_is_refused_at_its_line() {
        let dvl = file(DVL_HEADER, DVL_ROWS, 4);
        let gt = file(GT_HEADER, GT_ROWS, 4);
        for (gt, expected) in [
            (
                gt.replace(",-2.9,", ",1e200,"),
                "GT:3: V North [m/s]: 1e200 m/s is beyond 20 m/s, faster than any vehicle a DVL rides: a bad value or a unit other than m/s; remove the row before calibrating",
            ),
            (
                gt.replace(",-2\r\n", ",1\r\n"),
                "GT:4: Yaw [rad]: 1 rad after -2.5 rad on line 3, 0.5 s before: a turn of 5.566 rad/s, beyond the 2 rad/s any vehicle a DVL rides turns: a glitch in the attitude; remove the row before calibrating",
            ),
            (
                gt.replace(",-2\r\n", ",120\r\n"),
                "GT:4: Yaw [rad]: 120 rad after -2.5 rad on line 3, 0.5 s before: a turn of 6.239 rad/s, beyond the 2 rad/s any vehicle a DVL rides turns: a glitch in the attitude; remove the row before calibrating; if the file's angles are in degrees, set angles_in_degrees = true",
            ),
        ] {
            assert_eq!(read_two(&dvl, &gt).unwrap_err(), expected);
        }
        // Yaw unwrapped beyond 2π, turning at 1 rad/s.
        let unwrapped = gt
            .replace(",-3\r\n", ",6\r\n")
            .replace(",-2.5\r\n", ",6.5\r\n")
            .replace(",-2\r\n", ",7\r\n")
            .replace(",-1.5\r\n", ",7.5\r\n");
        assert!(read_two(&dvl, &unwrapped).is_ok());
        let mut columns = short_columns();
        columns.rate = Some(["p", "q", "r"].map(String::from));
        assert_eq!(
            read_one(
                "t,u,v,w,n,e,d,roll,pitch,yaw,p,q,r\n0,1,2,3,4,5,6,0,0,0,0,0,0\n1,1,2,3,4,5,6,0,0,0,0,1e6,0\n2,1,2,3,4,5,6,0,0,0,0,0,0\n",
                &columns
            )
            .unwrap_err(),
            "FILE:3: q: 1000000 rad/s is beyond 2 rad/s, faster than any vehicle a DVL rides turns: a bad value or a unit other than rad/s"
        );
    }

    #[test]
    fn attitude_out_of_range_names_the_angle_and_its_range() {
        let dvl = file(DVL_HEADER, DVL_ROWS, 3);
        let gt = file(GT_HEADER, GT_ROWS, 3);
        let hint = "; if the file's angles are in degrees, set angles_in_degrees = true";
        for (gt, expected) in [
            (
                gt.replace("0.01,-0.02,-2.5", "3.2,-0.02,-2.5"),
                format!(
                    "GT:3: Roll [rad]: 3.2 rad is out of range: roll lies in [-π, π] rad{hint}"
                ),
            ),
            (
                gt.replace("-0.02,-3\r\n", "-1.6,-3\r\n"),
                format!(
                    "GT:2: Pitch [rad]: -1.6 rad is out of range: pitch lies in [-π/2, π/2] rad{hint}"
                ),
            ),
        ] {
            assert_eq!(read_two(&dvl, &gt).unwrap_err(), expected);
        }
        let mut columns = short_columns();
        columns.angles_in_degrees = true;
        assert_eq!(
            read_one(
                "t,u,v,w,n,e,d,roll,pitch,yaw\n0,1,2,3,4,5,6,0,90.5,0\n",
                &columns
            )
            .unwrap_err(),
            "FILE:2: pitch: 90.5 deg is out of range: pitch lies in [-90, 90] deg"
        );
    }

    #[test]
    fn a_dvl_and_a_reference_each_on_its_own_stamps_and_rate_are_read_as_they_are() {
        // The DVL at half the reference's rate, its clock 0.25 s off.
        let dvl = "Time [s],DVL X [m/s],DVL Y [m/s],DVL Z [m/s]\n\
                   0.25,1.5,0.1,-0.01\n1.25,2.5,0.1,-0.01\n2.25,3.5,0.1,-0.01\n";
        let gt: String = (0..8)
            .map(|i| {
                format!(
                    "{},0.6,0.57,-19.8,-1.9,-0.6,0.01,0.01,-0.02,{}\r\n",
                    0.5 * f64::from(i),
                    -3.0 + 0.1 * f64::from(i)
                )
            })
            .collect();
        let recording = read_two(dvl, &format!("{GT_HEADER}{gt}")).unwrap();
        assert_eq!(recording.time_s, [0.25, 1.25, 2.25]);
        assert_eq!(recording.reference_time_s.len(), 8);
        assert_eq!(recording.reference_time_s[7], 3.5);
        assert!(recording.left_out.is_empty());
        // Never overlapping in time: refused, naming both spans.
        let late = dvl
            .replace("\n0.25,", "\n100.25,")
            .replace("\n1.25,", "\n101.25,")
            .replace("\n2.25,", "\n102.25,");
        assert_eq!(
            read_two(&late, &format!("{GT_HEADER}{gt}")).unwrap_err(),
            "DVL: the DVL's stamps run from 100.25 s to 102.25 s, but GT: the reference's from 0 s to 3.5 s: they never overlap, so there is nothing to calibrate against (is one file's clock in other units, or the wrong file given?)"
        );
    }

    #[test]
    fn the_samples_a_dvl_did_not_measure_are_left_out_each_with_its_line_and_reason() {
        let mut columns = short_columns();
        columns.valid = Some("ok".into());
        let row = |t: u32, dvl: &str, ok: &str| format!("{t},{dvl},2,0,0,0,0,{}.0,{ok}\n", t);
        let text = format!(
            "t,u,v,w,n,e,d,roll,pitch,yaw,ok\n{}{}{}{}{}{}{}{}",
            row(0, "2,0,0.1", "1"),
            row(1, ",0,0.1", "1"),
            row(2, "NaN,0,0.1", "true"),
            row(3, "-32.768,0,0.1", "1"),
            row(4, "0,0,0", "1"),
            row(5, "2,0,0.1", "0"),
            row(6, "2,0,0.1", "1"),
            row(7, "2,0,0.1", "1"),
        );
        let recording = read_one(&text, &columns).unwrap();
        assert_eq!(recording.time_s, [0.0, 6.0, 7.0]);
        let left: Vec<(f64, u64, LeftOutWhy)> = recording
            .left_out
            .iter()
            .map(|l| (l.time_s, l.line, l.why))
            .collect();
        assert_eq!(
            left,
            [
                (1.0, 3, LeftOutWhy::NoVelocity),
                (2.0, 4, LeftOutWhy::NoVelocity),
                (3.0, 5, LeftOutWhy::Marker),
                (4.0, 6, LeftOutWhy::AllZero),
                (5.0, 7, LeftOutWhy::Flagged),
            ]
        );
        // The reference keeps every row: only the DVL lost its samples.
        assert_eq!(recording.reference_time_s.len(), 8);
        assert_eq!(
            left_out_words(&recording.left_out_counts()),
            "5 left out: 1 flagged invalid, 2 with no velocity, 1 with the invalid marker -32.768 m/s, 1 of exactly 0, 0, 0"
        );
        // A vehicle that truly stops: 0, 0, 0 is a reading.
        columns.zero_is_valid = true;
        assert_eq!(
            read_one(&text, &columns).unwrap().time_s,
            [0.0, 4.0, 6.0, 7.0]
        );
        // A flag that is not one, and too few valid samples, are refused.
        assert_eq!(
            read_one(&text.replace(",1\n", ",yes\n"), &columns).unwrap_err(),
            "FILE:2: ok: \"yes\" is not a validity flag: give 1 or true for a valid sample, 0 or false for one that is not"
        );
        // Three of thirteen kept: under a quarter is refused, with what to check.
        let mostly: String = (0..13)
            .map(|t| row(t, "2,0,0.1", if t < 2 || t == 12 { "1" } else { "0" }))
            .collect();
        assert_eq!(
            read_one(
                &format!("t,u,v,w,n,e,d,roll,pitch,yaw,ok\n{mostly}"),
                &columns
            )
            .unwrap_err(),
            "FILE: 3 of the DVL's 13 samples kept, 10 left out: 10 flagged invalid: under a quarter, so what is left does not stand for the dive; check the validity column and zero_is_valid, or cut the recording to where the DVL held bottom lock"
        );
        let dead = text.replace(",1\n", ",0\n");
        assert_eq!(
            read_one(&dead, &columns).unwrap_err(),
            "FILE: 0 valid DVL samples, 8 left out: 7 flagged invalid, 1 with no velocity: a calibration needs at least 3 (the DVL lost bottom lock, or its validity column or zero_is_valid is set wrongly)"
        );
    }

    #[test]
    fn lost_bottom_lock_cuts_the_recording_into_pieces_at_the_gap_limit() {
        // A 1 Hz DVL that loses its samples from 10 s to 14 s (empty cells) and from
        // 30 s to 31 s: 3 s of silence is three intervals, the default limit, and
        // cuts nothing; 6 s cuts.
        let row = |t: u32| {
            let dvl = if (10..15).contains(&t) || (30..32).contains(&t) {
                ",,"
            } else {
                "2,0,0.1"
            };
            format!("{t},{dvl},2,0,0,0,0,{}\n", f64::from(t) / 100.0)
        };
        let text: String = (0..40).map(row).collect();
        let text = format!("t,u,v,w,n,e,d,roll,pitch,yaw\n{text}");
        let mut columns = short_columns();
        let recording = read_one(&text, &columns).unwrap();
        assert_eq!(recording.gap_limit_s, 3.0);
        assert_eq!(recording.pieces(), [0..10, 10..33]);
        let counts = recording.counts();
        assert_eq!((counts.pieces, counts.longest_loss_s), (2, 6.0));
        assert_eq!(
            counts.to_string(),
            "the DVL's 40 samples, 33 kept (7 left out: 7 with no velocity), beside the reference's 40 on its own stamps; 2 pieces (gaps over 3.00 s cut it), the longest loss 6.00 s"
        );
        // A limit of the recording's own: 2 s cuts the second gap too, 10 s neither.
        for (limit_s, expected) in [
            (2.0, vec![0..10, 10..25, 25..33]),
            (10.0, Vec::from([0..33])),
        ] {
            columns.gap_limit_s = Some(GapLimit(limit_s));
            assert_eq!(read_one(&text, &columns).unwrap().pieces(), expected);
        }
        for limit_s in [0.0, -1.0, f64::NAN] {
            columns.gap_limit_s = Some(GapLimit(limit_s));
            assert_eq!(
                read_one(&text, &columns).unwrap_err(),
                format!(
                    "FILE: gap_limit_s = {limit_s}: a gap limit must be a positive number of seconds (the longest step between two DVL samples that does not cut the recording into pieces; by default three of the DVL's sample intervals)"
                )
            );
        }
        assert_eq!(pieces(&[], 1.0), Vec::<Range<usize>>::new());
    }

    #[test]
    fn a_gap_in_the_reference_leaves_out_the_dvl_samples_beside_it() {
        // The reference at 1 Hz with 10 s missing (from 20 s to 30 s); the DVL at 1 Hz
        // throughout: the samples within 3 s of the gap (17 s to 33 s) are left out.
        let gt: String = (0..60)
            .filter(|t| !(21..30).contains(t))
            .map(|t| {
                format!(
                    "{t},0.6,0.57,-19.8,-1.9,-0.6,0.01,0.01,-0.02,{}\r\n",
                    -3.0 + 0.01 * f64::from(t)
                )
            })
            .collect();
        let dvl: String = (0..60).map(|t| format!("{t},1.5,0.1,-0.01\r\n")).collect();
        let recording =
            read_two(&format!("{DVL_HEADER}{dvl}"), &format!("{GT_HEADER}{gt}")).unwrap();
        let left: Vec<f64> = recording.left_out.iter().map(|l| l.time_s).collect();
        assert_eq!(left, (18..33).map(f64::from).collect::<Vec<_>>());
        assert!(
            recording
                .left_out
                .iter()
                .all(|l| l.why == LeftOutWhy::ReferenceGap)
        );
        assert_eq!(recording.len(), 60 - 15);
    }

    #[test]
    fn a_recording_of_fewer_than_three_samples_is_refused() {
        assert_eq!(
            read_two(&file(DVL_HEADER, DVL_ROWS, 2), &file(GT_HEADER, GT_ROWS, 2)).unwrap_err(),
            "DVL: 2 samples below the header: a recording of a DVL beside a reference needs at least 3"
        );
        assert_eq!(
            read_one("t,u,v,w,n,e,d,roll,pitch,yaw\n", &short_columns()).unwrap_err(),
            "FILE: 0 samples below the header: a recording of a DVL beside a reference needs at least 3"
        );
    }

    #[test]
    fn the_akit_files_are_the_ones_fetched() {
        let root = Path::new("data/akit");
        let fetched: Vec<PathBuf> = catalogue::AKIT_FILES
            .iter()
            .map(|file| root.join(file.name))
            .collect();
        let read: Vec<PathBuf> = (1..=catalogue::AKIT_SEGMENTS)
            .flat_map(|segment| {
                let files = PairedFiles::akit(root, segment);
                [files.dvl, files.reference]
            })
            .collect();
        assert_eq!(fetched, read);
    }
}
