//! The faults of a paired recording: a file or column that is not there, a field that
//! is not a finite number, and every plausibility check's refusal, each naming the
//! file, the line (the header is line 1) and the column. In: what a check found. Out:
//! the message.

use super::{LeftOutWhy, MAX_BODY_RATE_RAD_S, MAX_DVL_SPEED_M_S, MIN_SAMPLES, ReadCounts};
use crate::data::catalogue;
use crate::data::csv::CsvError;
use std::f64::consts::PI;
use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum PairedError {
    #[error("{}: file not found{hint}", path.display())]
    Missing { path: PathBuf, hint: String },
    #[error(transparent)]
    Csv(CsvError),
    #[error(transparent)]
    Bag(#[from] crate::data::paired::bag::BagError),
    #[error(transparent)]
    Log(#[from] crate::data::paired::dvl_log::LogError),
    #[error(transparent)]
    Nmea(#[from] crate::data::nmea::NmeaError),
    #[error(
        "{}:{line}: {column}: {time_s} s follows {previous_s} s of line {previous_line}: time stamps must increase",
        path.display()
    )]
    TimeNotIncreasing {
        path: PathBuf,
        line: u64,
        column: String,
        time_s: f64,
        previous_line: u64,
        previous_s: f64,
    },
    #[error(
        "{}:{line}: {column}: {} m/s is beyond {MAX_DVL_SPEED_M_S} m/s, faster than any vehicle a DVL rides: another vendor's bad-velocity marker or a unit other than m/s; mark the sample invalid (an empty cell, or the validity column) or give the velocity in m/s",
        path.display(),
        crate::Shown(*value)
    )]
    DvlOutOfRange {
        path: PathBuf,
        line: u64,
        column: String,
        value: f64,
    },
    #[error(
        "{}:{line}: {column}: a {} of {} {}, {}: {}",
        path.display(),
        if *.longitude { "longitude" } else { "latitude" },
        crate::Shown(*value),
        if *.degrees { "deg" } else { "rad" },
        if *.longitude { "off the globe (beyond -180 to 360 deg)" } else { "beyond the pole" },
        match (*.degrees, *.longitude) {
            (true, false) => "the latitude is the first of latitude_longitude",
            (true, true) => "a bad value; remove the row before calibrating",
            (false, _) => "if the file's angles are in degrees, set angles_in_degrees = true",
        }
    )]
    OffTheGlobe {
        path: PathBuf,
        line: u64,
        column: String,
        value: f64,
        degrees: bool,
        /// Whether the value is the longitude (the latitude otherwise).
        longitude: bool,
    },
    #[error(
        "{}:{line}: {column}: {} m/s is beyond {MAX_DVL_SPEED_M_S} m/s, faster than any vehicle a DVL rides: a bad value or a unit other than m/s; remove the row before calibrating",
        path.display(),
        crate::Shown(*value)
    )]
    ReferenceOutOfRange {
        path: PathBuf,
        line: u64,
        column: String,
        value: f64,
    },
    #[error(
        "{}:{line}: {column}: {} rad/s is beyond {MAX_BODY_RATE_RAD_S} rad/s, faster than any vehicle a DVL rides turns: a bad value or a unit other than rad/s",
        path.display(),
        crate::Shown(*value)
    )]
    RateOutOfRange {
        path: PathBuf,
        line: u64,
        column: String,
        value: f64,
    },
    #[error(
        "{}:{line}: {column}: {} {unit} after {} {unit} on line {previous_line}, {dt_s} s before: a turn of {rate_rad_s:.3} rad/s, beyond the {MAX_BODY_RATE_RAD_S} rad/s any vehicle a DVL rides turns: a glitch in the attitude; remove the row before calibrating{hint}",
        path.display(),
        crate::Shown(*value),
        crate::Shown(*previous),
        unit = if *.degrees { "deg" } else { "rad" },
        hint = if !*.degrees
            && value.abs().max(previous.abs()) > 2.0 * PI
            && rate_rad_s.to_radians() <= MAX_BODY_RATE_RAD_S
        {
            "; if the file's angles are in degrees, set angles_in_degrees = true"
        } else {
            ""
        },
    )]
    AttitudeJump {
        path: PathBuf,
        line: u64,
        previous_line: u64,
        column: String,
        value: f64,
        previous: f64,
        dt_s: f64,
        rate_rad_s: f64,
        degrees: bool,
    },
    #[error(
        "{}:{line}: {column}: {value} {unit} is out of range: {angle} lies in [-{limit}, {limit}] {unit}{hint}",
        path.display(),
        unit = if *.degrees { "deg" } else { "rad" },
        limit = angle_limit(*.angle, *.degrees).1,
        angle = angle_limit(*.angle, *.degrees).0,
        hint = degrees_hint(*.value, *.degrees),
    )]
    AttitudeOutOfRange {
        path: PathBuf,
        line: u64,
        column: String,
        /// 0 roll, 1 pitch, 2 yaw.
        angle: usize,
        value: f64,
        degrees: bool,
    },
    #[error(
        "{}: the DVL's stamps run from {} s to {} s, but {}: the reference's from {} s to {} s: they never overlap, so there is nothing to calibrate against (is one file's clock in other units, or the wrong file given?)",
        dvl.display(),
        dvl_span_s.0,
        dvl_span_s.1,
        reference.display(),
        reference_span_s.0,
        reference_span_s.1
    )]
    NoOverlap {
        dvl: PathBuf,
        dvl_span_s: (f64, f64),
        reference: PathBuf,
        reference_span_s: (f64, f64),
    },
    #[error(
        "{}: {} valid DVL samples, {}: a calibration needs at least {MIN_SAMPLES} (the DVL lost bottom lock, or its validity column or zero_is_valid is set wrongly)",
        path.display(),
        counts.kept,
        left_out_words(&counts.left_out)
    )]
    TooFewValid { path: PathBuf, counts: ReadCounts },
    #[error(
        "{}: {} of the DVL's {} samples kept, {}: under a quarter, so what is left does not stand for the dive; check the validity column and zero_is_valid, or cut the recording to where the DVL held bottom lock",
        path.display(),
        counts.kept,
        counts.read(),
        left_out_words(&counts.left_out)
    )]
    MostlyLeftOut { path: PathBuf, counts: ReadCounts },
    #[error(
        "{}: {samples} samples below the header: a recording of a DVL beside a reference needs at least {MIN_SAMPLES}",
        path.display()
    )]
    TooShort { path: PathBuf, samples: usize },
    #[error(
        "{}: gap_limit_s = {limit_s}: a gap limit must be a positive number of seconds (the longest step between two DVL samples that does not cut the recording into pieces; by default three of the DVL's sample intervals)",
        path.display()
    )]
    GapLimit { path: PathBuf, limit_s: f64 },
}

impl From<CsvError> for PairedError {
    fn from(error: CsvError) -> PairedError {
        match error {
            CsvError::Missing { path } => PairedError::Missing {
                hint: catalogue::akit_hint(&path),
                path,
            },
            error => PairedError::Csv(error),
        }
    }
}

/// The name of angle `angle` (0 roll, 1 pitch, 2 yaw) and the bound of its range, in
/// degrees or radians.
fn angle_limit(angle: usize, degrees: bool) -> (&'static str, &'static str) {
    match (angle, degrees) {
        (0, false) => ("roll", "π"),
        (1, false) => ("pitch", "π/2"),
        (_, false) => ("yaw", "2π"),
        (0, true) => ("roll", "180"),
        (1, true) => ("pitch", "90"),
        (_, true) => ("yaw", "360"),
    }
}

/// A hint for an angle out of range in radians that would be in range in degrees.
fn degrees_hint(value: f64, degrees: bool) -> &'static str {
    if !degrees && value.abs() <= 360.0 {
        "; if the file's angles are in degrees, set angles_in_degrees = true"
    } else {
        ""
    }
}

/// The DVL samples left out, in words: "4 left out: 3 with no velocity, 1 of exactly
/// 0, 0, 0", or "none left out".
pub fn left_out_words(counts: &[(LeftOutWhy, usize)]) -> String {
    let total: usize = counts.iter().map(|(_, count)| count).sum();
    if total == 0 {
        return "none left out".to_string();
    }
    let each: Vec<String> = counts
        .iter()
        .map(|(why, count)| format!("{count} {}", why.words()))
        .collect();
    format!("{total} left out: {}", each.join(", "))
}
