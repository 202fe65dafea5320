//! The names of a CSV recording's columns ([`PairedColumns`], A-KIT's by default) and
//! its files ([`PairedFiles`], the DVL's and the reference's, or one file holding both).
//! In: the names a spec or a `[columns]` table gives. Out: the columns and files a
//! [`Source::Csv`](super::Source::Csv) reads.

use std::path::{Path, PathBuf};

/// Where each quantity is, by column name; angles (and the angular rate) in radians
/// (rad/s) or, with `angles_in_degrees`, degrees (deg/s).
#[derive(Debug, Clone, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairedColumns {
    /// The time stamp, in seconds, in the DVL's file and the reference's.
    pub time: String,
    /// The DVL's body-frame x, y, z velocity, m/s.
    pub dvl: [String; 3],
    /// The reference's north, east, down velocity, m/s.
    pub velocity_ned: [String; 3],
    /// The reference's roll, pitch, yaw.
    pub attitude: [String; 3],
    /// The reference's body angular rate p, q, r, when recorded.
    #[serde(default)]
    pub rate: Option<[String; 3]>,
    #[serde(default)]
    pub angles_in_degrees: bool,
    /// The DVL's validity column, when it has one: 1 or `true` where the sample is
    /// valid, 0 or `false` where it is not (lost bottom lock).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub valid: Option<String>,
    /// Whether a DVL sample of exactly 0, 0, 0 is a vehicle at rest rather than a lost
    /// bottom lock (what many DVLs and drivers send): off by default.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub zero_is_valid: bool,
    /// The longest step between two of the DVL's valid samples that does not cut the
    /// recording into pieces, s, where the recording sets it: by default
    /// [`DVL_GAP_INTERVALS`](super::DVL_GAP_INTERVALS) of the DVL's median interval.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gap_limit_s: Option<GapLimit>,
    /// The reference's position, where it records one, for the dead-reckoning drift:
    /// its latitude and longitude (in the unit of its angles) ...
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub latitude_longitude: Option<[String; 2]>,
    /// ... or its north and east of any fixed point, metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub north_east: Option<[String; 2]>,
}

/// A gap limit in seconds, as a recording's reading sets it: compared and hashed by its
/// bits, so that the columns stay a key of the read recordings.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct GapLimit(pub f64);

impl Eq for GapLimit {}

impl std::hash::Hash for GapLimit {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.0.to_bits().hash(state);
    }
}

impl PairedColumns {
    /// The first column named for two quantities, as the key of the second
    /// (`velocity_ned[1]`, say) and what is wrong with it: a recording cannot hold both
    /// in one column; or the position named both ways.
    pub fn named_twice(&self) -> Option<(String, String)> {
        if self.latitude_longitude.is_some() && self.north_east.is_some() {
            let why = "the position is named both by latitude and longitude and by north and east: give one".to_string();
            return Some(("north_east".into(), why));
        }
        let mut named: Vec<(String, &String)> = vec![("time".into(), &self.time)];
        let triples = [
            ("dvl", Some(&self.dvl)),
            ("velocity_ned", Some(&self.velocity_ned)),
            ("attitude", Some(&self.attitude)),
            ("rate", self.rate.as_ref()),
        ];
        for (key, names) in triples {
            for (i, name) in names.into_iter().flatten().enumerate() {
                named.push((format!("{key}[{i}]"), name));
            }
        }
        for (key, names) in [
            ("latitude_longitude", &self.latitude_longitude),
            ("north_east", &self.north_east),
        ] {
            for (i, name) in names.iter().flatten().enumerate() {
                named.push((format!("{key}[{i}]"), name));
            }
        }
        if let Some(valid) = &self.valid {
            named.push(("valid".into(), valid));
        }
        named.iter().enumerate().find_map(|(i, (key, name))| {
            named[..i]
                .iter()
                .any(|(_, earlier)| earlier == name)
                .then(|| {
                    let why = format!("{name:?} is named for another quantity too: each quantity needs a column of its own");
                    (key.clone(), why)
                })
        })
    }

    /// The columns of the A-KIT recordings, as their headers spell them: the DVL file's
    /// `Time [s], DVL X [m/s], DVL Y [m/s], DVL Z [m/s]`, the reference (GT) file's
    /// `Time [s], V North [m/s], V East [m/s], V Down [m/s], Roll [rad], Pitch [rad],
    /// Yaw [rad]`; no angular rate, and not its position (a file of A-KIT's columns
    /// may not hold one: [`Self::akit_with_positions`] reads it).
    pub fn akit() -> PairedColumns {
        let names = |names: [&str; 3]| names.map(String::from);
        PairedColumns {
            time: "Time [s]".into(),
            dvl: names(["DVL X [m/s]", "DVL Y [m/s]", "DVL Z [m/s]"]),
            velocity_ned: names(["V North [m/s]", "V East [m/s]", "V Down [m/s]"]),
            attitude: names(["Roll [rad]", "Pitch [rad]", "Yaw [rad]"]),
            rate: None,
            angles_in_degrees: false,
            valid: None,
            zero_is_valid: false,
            gap_limit_s: None,
            latitude_longitude: None,
            north_east: None,
        }
    }

    /// A-KIT's columns with its reference's position, `Latitude [rad], Longitude [rad]`.
    pub fn akit_with_positions() -> PairedColumns {
        PairedColumns {
            latitude_longitude: Some(["Latitude [rad]", "Longitude [rad]"].map(String::from)),
            ..PairedColumns::akit()
        }
    }

    /// The reference's position columns and whether they are latitude and longitude.
    pub fn position(&self) -> Option<(&[String; 2], bool)> {
        match (&self.latitude_longitude, &self.north_east) {
            (Some(names), _) => Some((names, true)),
            (None, Some(names)) => Some((names, false)),
            (None, None) => None,
        }
    }
}

/// The files of one recording: the DVL's and the reference's (the same file when both
/// are in one).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct PairedFiles {
    pub dvl: PathBuf,
    pub reference: PathBuf,
}

impl PairedFiles {
    /// The files of A-KIT segment `segment` (1 to 13) below `folder`, where
    /// `dcnet-exp data fetch akit` puts them: `TrajectoryN/DVL_trajectoryN.csv` and
    /// `TrajectoryN/GT_trajectoryN.csv`.
    pub fn akit(folder: &Path, segment: usize) -> PairedFiles {
        let segment_folder = folder.join(format!("Trajectory{segment}"));
        PairedFiles {
            dvl: segment_folder.join(format!("DVL_trajectory{segment}.csv")),
            reference: segment_folder.join(format!("GT_trajectory{segment}.csv")),
        }
    }
}
