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
    /// in one column.
    pub fn named_twice(&self) -> Option<(String, String)> {
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
    /// Yaw [rad]` (its position columns are not read); no angular rate.
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
