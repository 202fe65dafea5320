//! What a vehicle with no velocity reference calibrates its DVL against: position fixes
//! (a USBL's, or a surface GNSS's) and, beside the DVL, an attitude (an AHRS's), each
//! file on its own clock and at its own rate. The DVL beside the attitude is read as a
//! paired recording whose reference has no velocity ([`read_beside_attitude`]: the same
//! columns, checks and samples left out as any recording); the fixes
//! ([`read_fixes`]) are a time and north and east in metres (or a latitude and
//! longitude, carried to metres on the plane tangent at the first fix), and optionally a
//! depth, each field a finite number, the stamps increasing. The fixes' and the
//! attitude's clocks are taken to be one (the vehicle's navigation clock); the DVL's may
//! lead or lag it, by the time offset the calibration finds. A bag gives all three
//! ([`crate::data::paired::bag::read_bag_beside_attitude`]: its odometry's attitude, and the fixes of a topic,
//! each with its own noise where its covariance gives one).
//! In: the files and the columns that name their fields. Out: a [`PairedRecording`]
//! with no reference velocity, and [`Fixes`].

use crate::data::csv::{Column, Quantity, parse_columns, read_bytes};
use crate::data::interpolate::Between;
use crate::data::local_plane::{north_east_m, off_the_globe};
use crate::data::paired::{PairedColumns, PairedError, ReadRecording, SourceFile};
pub use crate::data::position_fixes::Fixes;
use crate::files::sha256_hex;
use std::path::{Path, PathBuf};

/// Where a fixes file holds each quantity, by column name: A-KIT's reference file's by
/// default (its latitude and longitude in radians), so that a reference's own positions
/// can stand in for fixes.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FixColumns {
    /// The time stamp, s, on the attitude's clock.
    pub time: String,
    /// Latitude and longitude, in degrees where `angles_in_degrees`, radians otherwise ...
    #[serde(default)]
    pub latitude_longitude: Option<[String; 2]>,
    /// ... or north and east of any fixed point, metres.
    #[serde(default)]
    pub north_east: Option<[String; 2]>,
    /// The depth, metres, positive down, where the fixes have one.
    pub depth: Option<String>,
    pub angles_in_degrees: bool,
}

impl Default for FixColumns {
    fn default() -> Self {
        FixColumns {
            time: "Time [s]".into(),
            latitude_longitude: Some(["Latitude [rad]", "Longitude [rad]"].map(String::from)),
            north_east: None,
            depth: None,
            angles_in_degrees: false,
        }
    }
}

/// Why a fixes file cannot be read: the fault of the file, line and column.
#[derive(Debug, thiserror::Error)]
pub enum FixesError {
    #[error(transparent)]
    Read(#[from] PairedError),
    #[error("{}: [fix_columns]: give the fixes' position as latitude_longitude or as north_east, one of them", path.display())]
    NoPosition { path: PathBuf },
    #[error("{}: [fix_columns]: the position is named both by latitude_longitude and by north_east: give one", path.display())]
    PositionTwice { path: PathBuf },
    #[error("{}: no fixes: the file has a header and no rows", path.display())]
    Empty { path: PathBuf },
}

/// The fixes of the CSV file `path`, read with `columns` (every field a finite number,
/// the stamps increasing, a latitude within the poles), and the file with its SHA-256.
pub fn read_fixes(path: &Path, columns: &FixColumns) -> Result<(Fixes, SourceFile), FixesError> {
    let (names, geographic) = match (&columns.latitude_longitude, &columns.north_east) {
        (Some(names), None) => (names, true),
        (None, Some(names)) => (names, false),
        (None, None) => return Err(FixesError::NoPosition { path: path.into() }),
        (Some(_), Some(_)) => return Err(FixesError::PositionTwice { path: path.into() }),
    };
    let column = |name, holds| Column { name, holds };
    let mut wanted = vec![column(&columns.time, Quantity::Time)];
    wanted.extend(names.iter().map(|name| column(name, Quantity::Position)));
    wanted.extend(
        columns
            .depth
            .iter()
            .map(|name| column(name, Quantity::Position)),
    );
    let bytes = read_bytes(path).map_err(PairedError::from)?;
    let rows = parse_columns(path, &bytes, &wanted).map_err(PairedError::from)?;
    if rows.is_empty() {
        return Err(FixesError::Empty { path: path.into() });
    }
    let time_s: Vec<f64> = rows.column(0).collect();
    for row in 1..time_s.len() {
        if time_s[row] <= time_s[row - 1] {
            return Err(PairedError::TimeNotIncreasing {
                path: path.into(),
                line: rows.lines[row],
                column: columns.time.clone(),
                time_s: time_s[row],
                previous_line: rows.lines[row - 1],
                previous_s: time_s[row - 1],
            }
            .into());
        }
    }
    let position: Vec<[f64; 2]> = (0..rows.len())
        .map(|row| [rows.row(row)[1], rows.row(row)[2]])
        .collect();
    let north_east_m = if geographic {
        let to_rad = if columns.angles_in_degrees {
            1f64.to_radians()
        } else {
            1.0
        };
        if let Some((row, axis)) = off_the_globe(&position, columns.angles_in_degrees) {
            return Err(PairedError::OffTheGlobe {
                path: path.into(),
                line: rows.lines[row],
                column: names[axis].clone(),
                value: position[row][axis],
                degrees: columns.angles_in_degrees,
                longitude: axis == 1,
            }
            .into());
        }
        let radians: Vec<[f64; 2]> = position.iter().map(|p| p.map(|v| v * to_rad)).collect();
        north_east_m(radians[0], &radians)
    } else {
        position
    };
    let file = SourceFile {
        path: path.into(),
        sha256: sha256_hex(&bytes),
    };
    let fixes = Fixes {
        depth_m: columns.depth.as_ref().map(|_| rows.column(3).collect()),
        lines: rows.lines,
        time_s,
        north_east_m,
        noise_m: None,
    };
    Ok((fixes, file))
}

/// The DVL of the CSV file `dvl` beside the attitude of `attitude`, read with
/// `columns` (its DVL's and attitude's names, its validity, gap limit and angle unit;
/// no velocity and no position is read from the attitude's file), and checked as any
/// recording: a [`PairedRecording`](crate::data::paired::PairedRecording) whose
/// reference has no velocity (`velocity_ned_m_s` empty), calibrated against fixes alone.
pub fn read_beside_attitude(
    dvl: &Path,
    attitude: &Path,
    columns: &PairedColumns,
) -> Result<ReadRecording, PairedError> {
    let columns = PairedColumns {
        latitude_longitude: None,
        north_east: None,
        ..columns.clone()
    };
    crate::data::paired::read_without_velocity(dvl, attitude, &columns)
}

/// How fixes are simulated from a reference's positions: one every `interval_s`, each
/// with white Gaussian noise of `noise_m` per horizontal axis, and a share
/// `outlier_share` of them displaced `outlier_m` further in a random direction (a
/// USBL's multipath).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FixSimulation {
    pub interval_s: f64,
    pub noise_m: f64,
    pub outlier_share: f64,
    pub outlier_m: f64,
}

/// Fixes simulated by `simulation` from the positions `north_east_m` recorded at
/// `time_s`, drawn from `rng`: the first at the first position's time, each linearly
/// interpolated between the two recorded around it; no depth.
pub fn simulate_fixes(
    (time_s, north_east_m): (&[f64], &[[f64; 2]]),
    simulation: &FixSimulation,
    rng: &mut impl rand::Rng,
) -> Fixes {
    use rand::RngExt;
    use rand_distr::{Distribution, StandardNormal};
    let (Some(&first), Some(&last)) = (time_s.first(), time_s.last()) else {
        return Fixes {
            lines: Vec::new(),
            time_s: Vec::new(),
            north_east_m: Vec::new(),
            depth_m: None,
            noise_m: None,
        };
    };
    let count = ((last - first) / simulation.interval_s).floor() as usize + 1;
    let mut fixes = Fixes {
        lines: (1..=count as u64).collect(),
        time_s: Vec::with_capacity(count),
        north_east_m: Vec::with_capacity(count),
        depth_m: None,
        noise_m: None,
    };
    for k in 0..count {
        let t = first + k as f64 * simulation.interval_s;
        let at = Between::locate(time_s, t.min(last), f64::INFINITY)
            .expect("a time inside the positions")
            .of(north_east_m);
        let mut position = [0, 1].map(|axis| {
            let noise: f64 = StandardNormal.sample(rng);
            at[axis] + simulation.noise_m * noise
        });
        if rng.random::<f64>() < simulation.outlier_share {
            let direction = rng.random::<f64>() * std::f64::consts::TAU;
            position[0] += simulation.outlier_m * direction.cos();
            position[1] += simulation.outlier_m * direction.sin();
        }
        fixes.time_s.push(t);
        fixes.north_east_m.push(position);
    }
    fixes
}
