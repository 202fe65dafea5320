//! A DVL recorded beside a reference with attitude: per sample, the time, the DVL's
//! velocity in its body frame, and the reference's NED velocity, roll, pitch and yaw
//! (optionally its body angular rate), read from one or two CSV files whose columns the
//! spec names (the A-KIT names by default). Every row is checked: time stamps that go
//! back or repeat, attitude out of range or not finite, a DVL and a reference of other
//! lengths or times are errors naming the file, the line and the column.
//! In: the file paths and column names. Out: a [`PairedRecording`].

use crate::Vec3;
use std::path::{Path, PathBuf};

/// One recording: the DVL as measured and the reference, on the same time stamps.
#[derive(Debug, Clone, PartialEq)]
pub struct PairedRecording {
    /// Seconds, strictly increasing.
    pub time_s: Vec<f64>,
    /// The DVL's velocity in its body frame (x forward, y starboard, z down), m/s.
    pub dvl_m_s: Vec<Vec3>,
    /// The reference's velocity, north, east, down, m/s.
    pub velocity_ned_m_s: Vec<Vec3>,
    /// Roll, pitch, yaw in radians, as recorded (yaw may wrap at ±π).
    pub attitude_rad: Vec<Vec3>,
    /// The reference's body angular rate (p, q, r) in rad/s, when recorded.
    pub rate_rad_s: Option<Vec<Vec3>>,
}

/// Where each quantity is, by column name; angles in radians or degrees.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PairedColumns {
    pub time: String,
    pub dvl: [String; 3],
    pub velocity_ned: [String; 3],
    pub attitude: [String; 3],
    pub rate: Option<[String; 3]>,
    pub angles_in_degrees: bool,
}

impl PairedColumns {
    /// The A-KIT recordings' column names.
    pub fn akit() -> Self {
        todo!("issue 26: the A-KIT column names")
    }
}

/// The files of one recording: the DVL's and the reference's (the same file when both
/// are in one).
#[derive(Debug, Clone, PartialEq)]
pub struct PairedFiles {
    pub dvl: PathBuf,
    pub reference: PathBuf,
}

#[derive(Debug, thiserror::Error)]
pub enum PairedError {}

/// Reads and checks one recording.
pub fn read(files: &PairedFiles, columns: &PairedColumns) -> Result<PairedRecording, PairedError> {
    let _ = (files, columns, Path::new(""));
    todo!("issue 26: the paired recording reader")
}
