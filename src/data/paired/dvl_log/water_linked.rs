//! Water Linked's DVL reports (A50, A125), one JSON object a line, as the DVL's TCP
//! API sends them and loggers store them, read with serde_json. A `velocity` report is a
//! ping: its `time_of_validity` (the middle of the ping, µs since 1970 UTC) the stamp,
//! `vx`, `vy`, `vz` the DVL's own velocity in its body frame (x forward, y right, z down),
//! `velocity_valid` whether it had lock, each transducer's `beam_valid` how many beams it
//! used (three make a three-beam solution, kept and counted). A `velocity_water` report
//! (water tracking, from json_v3.2) is a ping left out as such. A `position_local`
//! report (dead reckoning) gives the DVL's own attitude: `roll`, `pitch`, `yaw` in
//! degrees at `ts` (s since 1970 UTC), where its `status` is 0 (others counted). Other reports (responses) are counted by type
//! and not read. The file is read a line at
//! a time; a line that is no JSON report, or a format other than json_v3 to json_v3.3,
//! is refused naming its line, but for a last line the file ends inside (a logger
//! stopped mid-write), which is counted.
//! In: a file's path. Out: each [`Report`] and [`DeadReckoning`] handed to a visitor,
//! then a [`ReportSurvey`] with the file's SHA-256.

use super::LogError;
use crate::files::read_lines;
use std::collections::BTreeMap;
use std::path::Path;

/// The report formats read.
const FORMATS: [&str; 4] = ["json_v3", "json_v3.1", "json_v3.2", "json_v3.3"];

/// A ping as a velocity report gives it.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// Its line in the file (the first is 1).
    pub line: u64,
    /// The middle of the ping, s since 1970 UTC.
    pub time_s: f64,
    /// The DVL's velocity, m/s, forward, right, down.
    pub velocity_m_s: [f64; 3],
    pub velocity_valid: bool,
    /// How many transducers' beams were valid.
    pub beams_valid: usize,
    /// Tracking the water (`velocity_water`), not the bottom.
    pub water_track: bool,
}

/// The DVL's own attitude as a dead-reckoning report gives it.
#[derive(Debug, Clone, PartialEq)]
pub struct DeadReckoning {
    /// Its line in the file (the first is 1).
    pub line: u64,
    /// s since 1970 UTC.
    pub time_s: f64,
    /// Roll, pitch and yaw, degrees: about the DVL's x (forward), y (right), z (down).
    pub roll_pitch_yaw_deg: [f64; 3],
}

/// A report read: a ping, or the DVL's attitude.
#[derive(Debug, Clone, PartialEq)]
pub enum Read {
    Ping(Report),
    Attitude(DeadReckoning),
}

/// What a whole file held beyond its pings.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ReportSurvey {
    pub sha256: String,
    /// How many lines held each type of report.
    pub types: BTreeMap<String, usize>,
    /// The formats the reports state.
    pub formats: BTreeMap<String, usize>,
    /// The last line, where the file ends inside it: its number. Not read.
    pub cut_short: Option<u64>,
    /// Dead-reckoning reports whose status is not 0 (the DVL's error): not read.
    pub attitude_not_ok: usize,
}

#[derive(serde::Deserialize)]
struct Kind {
    #[serde(rename = "type")]
    kind: String,
    format: Option<String>,
}

#[derive(serde::Deserialize)]
struct Velocity {
    vx: f64,
    vy: f64,
    vz: f64,
    velocity_valid: bool,
    time_of_validity: u64,
    #[serde(default)]
    transducers: Vec<Transducer>,
}

#[derive(serde::Deserialize)]
struct Position {
    #[serde(default)]
    status: i64,
    ts: f64,
    roll: f64,
    pitch: f64,
    yaw: f64,
}

#[derive(serde::Deserialize)]
struct Transducer {
    beam_valid: bool,
}

/// Reads `path` a line at a time, handing each ping and attitude to `visit`.
pub fn read(path: &Path, visit: &mut dyn FnMut(Read)) -> Result<ReportSurvey, LogError> {
    let io = |source| LogError::Io {
        path: path.to_path_buf(),
        source,
    };
    let refuse = |line: u64, problem: String| LogError::Line {
        path: path.to_path_buf(),
        line,
        problem,
    };
    let mut survey = ReportSurvey::default();
    survey.sha256 = read_lines(path, io, |line, text| {
        let complete = text.ends_with(b"\n");
        let trimmed = text.trim_ascii();
        if trimmed.is_empty() {
            return Ok(());
        }
        let kind: Kind = match serde_json::from_slice(trimmed) {
            Ok(kind) => kind,
            Err(_) if !complete => {
                survey.cut_short = Some(line);
                return Ok(());
            }
            Err(error) => {
                return Err(refuse(
                    line,
                    format!("not a JSON report with a type: {error}"),
                ));
            }
        };
        *survey.types.entry(kind.kind.clone()).or_default() += 1;
        if let Some(format) = &kind.format {
            if !FORMATS.contains(&format.as_str()) {
                return Err(refuse(
                    line,
                    format!(
                        "format {format:?}: the reports read are {}",
                        FORMATS.join(", ")
                    ),
                ));
            }
            *survey.formats.entry(format.clone()).or_default() += 1;
        }
        let malformed = |error| refuse(line, format!("a {} report: {error}", kind.kind));
        if kind.kind == "position_local" {
            let report: Position = serde_json::from_slice(trimmed).map_err(malformed)?;
            if report.status != 0 {
                survey.attitude_not_ok += 1;
                return Ok(());
            }
            visit(Read::Attitude(DeadReckoning {
                line,
                time_s: report.ts,
                roll_pitch_yaw_deg: [report.roll, report.pitch, report.yaw],
            }));
            return Ok(());
        }
        if kind.kind != "velocity" && kind.kind != "velocity_water" {
            return Ok(());
        }
        let report: Velocity = serde_json::from_slice(trimmed).map_err(malformed)?;
        visit(Read::Ping(Report {
            line,
            time_s: report.time_of_validity as f64 * 1e-6,
            velocity_m_s: [report.vx, report.vy, report.vz],
            velocity_valid: report.velocity_valid,
            beams_valid: report.transducers.iter().filter(|t| t.beam_valid).count(),
            water_track: kind.kind == "velocity_water",
        }));
        Ok(())
    })?;
    Ok(survey)
}
