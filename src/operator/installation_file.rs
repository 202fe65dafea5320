//! The installation file: what `calibrate --save` found, for `correct` to apply to
//! another dive. TOML a person can read: the terms with their standard deviations and
//! correlations, which are the vehicle's (carried to every dive) and which the dive's
//! (found again on each), the noise they were bounded with and the residual they left,
//! the recording's SHA-256 and the tool's version; its first line the SHA-256 of the
//! rest, so that a file damaged or edited by hand is refused rather than applied.
//! In: a calibration's terms. Out: the file, or its terms read back and checked.

use crate::Vec3;
use crate::installation::estimate::bound::TermBound;
use crate::installation::estimate::fit::{TIME_OFFSET_MARGIN_S, beyond_any_installation};
use crate::installation::estimate::fixes::FIX_LATENCY;
use crate::installation::terms::names::{TermName, term_list_faults, term_set};
use crate::installation::terms::{Installation, TermSet};
use std::path::{Path, PathBuf};

/// The first line's key: the SHA-256 of every line after it.
const CHECKSUM_KEY: &str = "checksum_sha256";

/// The largest installation file read, bytes: one of every term with its correlations
/// is a few kB; a larger file (or a device that never ends) is not one.
const MAX_FILE_BYTES: u64 = 1 << 20;

/// The tool that writes and reads installation files, and its version.
const TOOL: &str = "dcnet-exp";
pub const TOOL_VERSION: &str = env!("CARGO_PKG_VERSION");

/// An installation file's contents as its TOML holds them, unchecked: what is
/// written, and what [`InstallationFile::check`] turns into a [`SavedInstallation`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InstallationFile {
    pub tool: String,
    pub version: String,
    /// The DVL file calibrated on, as given, and its SHA-256.
    pub recording: String,
    pub recording_sha256: String,
    /// The noise the bound was taken at, per axis, cm/s.
    pub dvl_noise_cm_s: f64,
    pub reference_noise_cm_s: f64,
    /// The RMS of the residual per DVL axis at calibration, cm/s: what a dive the
    /// installation fits as well leaves.
    pub residual_cm_s: Vec3,
    /// Whether `residual_cm_s` was measured (against a velocity reference), or is the
    /// DVL's noise as given, standing for it (a calibration against fixes, which
    /// measure no velocity).
    #[serde(default = "measured", skip_serializing_if = "is_measured")]
    pub residual_measured: bool,
    /// The terms carried to every dive, and those found again on each.
    pub vehicle_terms: Vec<TermName>,
    pub dive_terms: Vec<TermName>,
    /// Each estimated parameter by name (`lever_arm_x_m`), its value, its standard
    /// deviation, in the unit its name says (a scale as a fraction, angles in radians).
    pub terms: Vec<SavedTerm>,
    /// The correlation coefficients of the terms, in their order.
    pub correlation: Vec<Vec<f64>>,
    /// How many dives (recordings) the terms were calibrated on together.
    #[serde(default = "one_dive")]
    pub dives: usize,
    /// Of a joint calibration over three dives or more, how far each vehicle term moves
    /// from one dive to the next, and where a next dive's own calibration should find
    /// it; empty for fewer dives, whose terms may differ on the next dive by more than
    /// their standard deviations.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub between_dives: Vec<SavedSpread>,
    /// Of a calibration against fixes that estimated their latency (`--fix-latency`):
    /// the fixes' own latency, s, with its standard deviation. Not a term of the DVL's
    /// installation; `correct --fixes` reads the next dive's fixes by it, as fixes of
    /// the same system.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fix_latency: Option<SavedTerm>,
    /// Of a calibration against fixes whose clock and latency the fixes placed only
    /// as their sum (the latency held at zero): the time offset saved is that sum, the
    /// shift of the whole track against the fixes, and not the DVL's clock alone;
    /// against a velocity reference it would read the DVL late by the fixes' latency.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub time_offset_includes_fix_latency: bool,
    /// For a calibration read from a ROS 2 bag: the frames, and the mount of the
    /// DVL's frame `/tf_static` gave, which the misalignment is a turn from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mount: Option<SavedMount>,
}

/// What a file that does not say whether its residual was measured holds: a measured
/// one (a velocity reference's).
fn measured() -> bool {
    true
}

/// Whether the residual is measured, which the file then leaves unsaid.
fn is_measured(measured: &bool) -> bool {
    *measured
}

/// What a file that does not say how many dives it was calibrated on was: one.
fn one_dive() -> usize {
    1
}

/// The DVL's frame as `/tf_static` placed it in the body's, when a calibration read a
/// bag: roll, pitch, yaw (ZYX), radians.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SavedMount {
    pub body: String,
    pub dvl_frame: String,
    pub rpy_rad: Vec3,
}

/// An installation, checked: its terms named in the order of its term lists, each
/// value finite and each standard deviation zero or more, its correlations a square
/// matrix within ±1, its noise positive. Only a calibration ([`SavedInstallation::of`])
/// or a file that passes [`InstallationFile::check`] makes one; its contents are read
/// through [`InstallationFile`]'s fields.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedInstallation {
    file: InstallationFile,
}

impl std::ops::Deref for SavedInstallation {
    type Target = InstallationFile;

    fn deref(&self) -> &InstallationFile {
        &self.file
    }
}

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SavedTerm {
    pub name: String,
    pub value: f64,
    pub std: f64,
}

/// One vehicle term's spread between the dives of a joint calibration, in the term's
/// unit: its standard deviation from dive to dive beyond their noise, and the 95 %
/// interval of a next dive's own estimate
/// ([`crate::installation::estimate::between_dives`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SavedSpread {
    pub name: String,
    pub std: f64,
    pub next_dive: [f64; 2],
}

/// Why an installation file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum InstallationFileError {
    #[error("{}: cannot be read ({source}): give the file `calibrate --save` wrote", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "{}: {}: not an installation file, which is a regular file of a few kB; give the file `calibrate --save` wrote",
        path.display(),
        match bytes { Some(bytes) => format!("{bytes} bytes"), None => "not a regular file".to_string() }
    )]
    NotOne { path: PathBuf, bytes: Option<u64> },
    #[error("{}: its first line is not `{CHECKSUM_KEY} = \"…\"`: not an installation file, or damaged; write it again with `calibrate --save`", path.display())]
    NoChecksum { path: PathBuf },
    #[error("{}: its checksum does not match its contents: the file was edited or damaged after `calibrate --save` wrote it; write it again with `calibrate --save` (an installation is not edited by hand)", path.display())]
    Edited { path: PathBuf },
    #[error("{}: {message}; write it again with `calibrate --save`", path.display())]
    Malformed { path: PathBuf, message: String },
    #[error("{}: written by {tool} {version}, and this is {TOOL} {TOOL_VERSION}: calibrate again with this version (`calibrate --save`)", path.display())]
    OtherVersion {
        path: PathBuf,
        tool: String,
        version: String,
    },
    #[error("{}: terms[{index}] ({name}): {what}: calibrate again with `calibrate --save`", path.display())]
    BadTerm {
        path: PathBuf,
        index: usize,
        name: String,
        what: String,
    },
}

impl SavedInstallation {
    /// This installation with the mount `/tf_static` gave the bag it was found on.
    pub fn with_mount(mut self, mount: SavedMount) -> SavedInstallation {
        self.file.mount = Some(mount);
        self
    }

    /// This installation with the spread between the `dives` it was calibrated on.
    pub fn with_spread(
        mut self,
        dives: usize,
        between_dives: Vec<SavedSpread>,
    ) -> SavedInstallation {
        self.file.dives = dives;
        self.file.between_dives = between_dives;
        self
    }

    /// This installation calibrated against fixes: its residual the DVL's noise given,
    /// not measured.
    pub fn of_fixes(mut self) -> SavedInstallation {
        self.file.residual_measured = false;
        self
    }

    /// This installation with the fixes' latency estimated beside it, s, and its
    /// standard deviation.
    pub fn with_fix_latency(mut self, value_s: f64, std_s: f64) -> SavedInstallation {
        self.file.fix_latency = Some(SavedTerm {
            name: FIX_LATENCY.to_string(),
            value: value_s,
            std: std_s,
        });
        self
    }

    /// This installation with its time offset the sum of the DVL's clock and the
    /// fixes' latency, which the fixes could not tell apart.
    pub fn with_time_offset_including_fix_latency(mut self) -> SavedInstallation {
        self.file.time_offset_includes_fix_latency = true;
        self
    }

    /// The spread between dives of the term named `name`, where the file holds one.
    pub fn spread_of(&self, name: &str) -> Option<&SavedSpread> {
        self.between_dives.iter().find(|s| s.name == name)
    }

    /// The installation of a calibration against any reference: `terms` fitted, with
    /// `bound`'s values (a term not applied at zero), standard deviations and
    /// correlations, those of `dive_terms` the dive's, the rest the vehicle's.
    pub fn of<N>(
        bound: &TermBound<N>,
        terms: (&[TermName], &[TermName]),
        recording: (&Path, &str),
        noise_cm_s: (f64, f64),
        residual_m_s: Vec3,
    ) -> SavedInstallation {
        let saved = (bound.names.iter().enumerate())
            .map(|(i, name)| SavedTerm {
                name: name.to_string(),
                value: if bound.applied[i] {
                    bound.value[i]
                } else {
                    0.0
                },
                std: bound.std[i],
            })
            .collect();
        let recording = (recording.0.display().to_string(), recording.1.to_string());
        Self::of_terms(
            (saved, bound.correlation.clone()),
            terms,
            recording,
            noise_cm_s,
            residual_m_s,
        )
    }

    /// [`Self::of`] from the terms and their correlations as saved; `recording` the
    /// file (or files) calibrated on and its SHA-256 (theirs).
    pub fn of_terms(
        (saved, correlation): (Vec<SavedTerm>, Vec<Vec<f64>>),
        (terms, dive_terms): (&[TermName], &[TermName]),
        (recording, recording_sha256): (String, String),
        (dvl_noise_cm_s, reference_noise_cm_s): (f64, f64),
        residual_m_s: Vec3,
    ) -> SavedInstallation {
        let vehicle_terms = terms
            .iter()
            .copied()
            .filter(|t| !dive_terms.contains(t))
            .collect();
        let file = InstallationFile {
            tool: TOOL.into(),
            version: TOOL_VERSION.into(),
            recording,
            recording_sha256,
            dvl_noise_cm_s,
            reference_noise_cm_s,
            residual_cm_s: residual_m_s.map(|r| 100.0 * r),
            residual_measured: true,
            vehicle_terms,
            dive_terms: dive_terms
                .iter()
                .copied()
                .filter(|t| terms.contains(t))
                .collect(),
            terms: saved,
            correlation,
            dives: 1,
            between_dives: Vec::new(),
            fix_latency: None,
            time_offset_includes_fix_latency: false,
            mount: None,
        };
        SavedInstallation { file }
    }

    /// Every term, vehicle's and dive's.
    pub fn term_set(&self) -> TermSet {
        let all: Vec<TermName> = self
            .vehicle_terms
            .iter()
            .chain(&self.dive_terms)
            .copied()
            .collect();
        term_set(&all)
    }

    /// The dive's terms, found again on each dive.
    pub fn dive_term_set(&self) -> TermSet {
        term_set(&self.dive_terms)
    }

    /// The terms' values as an installation.
    pub fn installation(&self) -> Installation {
        let values: Vec<f64> = self.terms.iter().map(|t| t.value).collect();
        Installation::from_parameters(&self.term_set(), &values)
    }

    /// Writes the file at `path`, atomically, its folder made where it is missing.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        self.file.write(path)
    }

    /// Reads and checks the file at `path`: its checksum, the tool's version, every
    /// term known, finite and in the order of its terms, standard deviations not
    /// negative.
    pub fn read(path: &Path) -> Result<SavedInstallation, InstallationFileError> {
        let io = |source| InstallationFileError::Io {
            path: path.to_path_buf(),
            source,
        };
        let metadata = std::fs::metadata(path).map_err(io)?;
        if !metadata.is_file() || metadata.len() > MAX_FILE_BYTES {
            return Err(InstallationFileError::NotOne {
                path: path.to_path_buf(),
                bytes: metadata.is_file().then_some(metadata.len()),
            });
        }
        let text = std::fs::read_to_string(path).map_err(|source| InstallationFileError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let no_checksum = || InstallationFileError::NoChecksum {
            path: path.to_path_buf(),
        };
        let (first, body) = text.split_once('\n').ok_or_else(no_checksum)?;
        let written = first
            .strip_prefix(&format!("{CHECKSUM_KEY} = \""))
            .and_then(|rest| rest.strip_suffix('"'))
            .ok_or_else(no_checksum)?;
        if crate::files::sha256_hex(body.as_bytes()) != written {
            return Err(InstallationFileError::Edited {
                path: path.to_path_buf(),
            });
        }
        let file: InstallationFile =
            toml::from_str(body).map_err(|error| InstallationFileError::Malformed {
                path: path.to_path_buf(),
                message: error.message().to_string(),
            })?;
        if file.tool != TOOL || file.version != TOOL_VERSION {
            return Err(InstallationFileError::OtherVersion {
                path: path.to_path_buf(),
                tool: file.tool,
                version: file.version,
            });
        }
        file.check(path)
    }
}

/// Why an installation calibrated on `dives` holds no spread between dives, and what
/// to do.
pub fn no_spread_why(dives: usize) -> String {
    match dives {
        1 | 2 => format!(
            "calibrated on {dives} dive{}; calibrate jointly over three dives or more",
            if dives == 1 { "" } else { "s" }
        ),
        _ => format!(
            "calibrated on {dives} dives, no vehicle term seen on three of them; calibrate jointly over dives that turn"
        ),
    }
}

impl InstallationFile {
    /// The file's text: the checksum line, then the contents.
    pub fn to_text(&self) -> String {
        let body = toml::to_string(self).expect("an installation serialises");
        let spread = match self.between_dives.is_empty() {
            true => format!(
                "# It holds no spread between dives ({}): on another dive the vehicle's terms\n# may differ by more than their standard deviations.\n",
                no_spread_why(self.dives)
            ),
            false => String::new(),
        };
        let body = format!(
            "# The installation `dcnet-exp calibrate --save` found, for `dcnet-exp correct`.\n# Edited by hand, it is refused: calibrate again instead.\n{spread}{body}"
        );
        format!(
            "{CHECKSUM_KEY} = \"{}\"\n{body}",
            crate::files::sha256_hex(body.as_bytes())
        )
    }

    /// Writes the file at `path`, atomically, its folder made where it is missing.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        if let Some(folder) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(folder)?;
        }
        crate::files::write_atomic(path, self.to_text().as_bytes())
    }

    /// The file's contents as a [`SavedInstallation`], where they hold one: the names
    /// its term lists give, in their order, each value finite and each standard
    /// deviation zero or more; the file at `path` named where they do not.
    pub fn check(self, path: &Path) -> Result<SavedInstallation, InstallationFileError> {
        let malformed = |message: String| InstallationFileError::Malformed {
            path: path.to_path_buf(),
            message,
        };
        let names: Vec<TermName> = self
            .vehicle_terms
            .iter()
            .chain(&self.dive_terms)
            .copied()
            .collect();
        self.check_lists().map_err(malformed)?;
        let expected = term_set(&names).parameter_names();
        if self.terms.len() != expected.len() {
            return Err(malformed(format!(
                "{} terms for the {} parameters of {:?}",
                self.terms.len(),
                expected.len(),
                names.iter().map(|t| t.name()).collect::<Vec<_>>()
            )));
        }
        self.check_numbers(expected.len()).map_err(malformed)?;
        self.check_spread().map_err(malformed)?;
        if let Some(mount) = &self.mount
            && !mount.rpy_rad.iter().all(|a| a.is_finite())
        {
            return Err(malformed(format!(
                "mount.rpy_rad {:?} is not three finite angles",
                mount.rpy_rad
            )));
        }
        if let Some(latency) = &self.fix_latency {
            latency
                .check(FIX_LATENCY)
                .map_err(|(name, what)| malformed(format!("fix_latency ({name}): {what}")))?;
            if latency.value.abs() > TIME_OFFSET_MARGIN_S {
                return Err(malformed(format!(
                    "fix_latency: {} s lies beyond the ±{TIME_OFFSET_MARGIN_S} s a fit allows a latency",
                    latency.value
                )));
            }
        }
        for (index, (term, name)) in self.terms.iter().zip(&expected).enumerate() {
            term.check(name)
                .map_err(|(name, what)| InstallationFileError::BadTerm {
                    path: path.to_path_buf(),
                    index,
                    name,
                    what,
                })?;
        }
        let saved = SavedInstallation { file: self };
        match beyond_any_installation(&saved.installation()) {
            // A file `calibrate` could not have written: it refuses such a fit.
            Some(fault) => Err(malformed(fault.to_string())),
            None => Ok(saved),
        }
    }

    /// The lists `calibrate` could have written: no term twice, nor a term with its
    /// per-axis form, no term both the vehicle's and the dive's, each of the dive's a
    /// dive's kind (the time offset or a bias), and the time offset among them.
    fn check_lists(&self) -> Result<(), String> {
        if let Some(term) = self
            .dive_terms
            .iter()
            .find(|t| self.vehicle_terms.contains(t))
        {
            return Err(format!(
                "{:?} is both a vehicle's and a dive's term",
                term.name()
            ));
        }
        let all: Vec<TermName> = (self.vehicle_terms.iter())
            .chain(&self.dive_terms)
            .copied()
            .collect();
        if let Some((_, fault)) = term_list_faults(&all).first() {
            return Err(format!("vehicle_terms and dive_terms together: {fault}"));
        }
        if let Some(term) = self.dive_terms.iter().find(|t| !t.may_be_the_dives()) {
            return Err(format!(
                "dive_terms: {:?} belongs to the vehicle, not the dive",
                term.name()
            ));
        }
        if !self.dive_terms.contains(&TermName::TimeOffset) {
            return Err("its dive_terms do not hold \"time_offset\"".into());
        }
        Ok(())
    }

    /// The spread between dives as a joint calibration writes it: of three dives or
    /// more, each entry a vehicle term's once, its standard deviation zero or more and
    /// its interval finite and in order.
    fn check_spread(&self) -> Result<(), String> {
        if self.dives == 0 {
            return Err("dives is 0: an installation is calibrated on one dive or more".into());
        }
        if !self.between_dives.is_empty() && self.dives < 3 {
            return Err(format!(
                "between_dives holds a spread, but dives is {}: a spread needs three dives or more",
                self.dives
            ));
        }
        let vehicle = term_set(&self.vehicle_terms).parameter_names();
        for (index, spread) in self.between_dives.iter().enumerate() {
            let [low, high] = spread.next_dive;
            let fault = if !vehicle.contains(&spread.name.as_str()) {
                Some("not one of the vehicle's terms".to_string())
            } else if self.between_dives[..index]
                .iter()
                .any(|s| s.name == spread.name)
            {
                Some("listed twice".to_string())
            } else if !(spread.std.is_finite() && spread.std >= 0.0) {
                Some(format!("its std is {}", spread.std))
            } else if !(low.is_finite() && high.is_finite() && low <= high) {
                Some(format!(
                    "its next_dive [{low}, {high}] is not a finite interval"
                ))
            } else {
                None
            };
            if let Some(fault) = fault {
                return Err(format!("between_dives[{index}] ({}): {fault}", spread.name));
            }
        }
        Ok(())
    }

    /// The correlations an `n × n` matrix within ±1, the noise positive (the
    /// reference's zero or more), the residual finite and zero or more.
    fn check_numbers(&self, n: usize) -> Result<(), String> {
        if self.correlation.len() != n || self.correlation.iter().any(|row| row.len() != n) {
            return Err(format!(
                "its correlation is not a {n} × {n} matrix, one row and column per term"
            ));
        }
        if self
            .correlation
            .iter()
            .flatten()
            .any(|r| r.abs() > 1.0 + 1e-9)
        {
            return Err("a correlation beyond ±1".into());
        }
        if !(self.dvl_noise_cm_s.is_finite() && self.dvl_noise_cm_s > 0.0)
            || !(self.reference_noise_cm_s.is_finite() && self.reference_noise_cm_s >= 0.0)
        {
            return Err(format!(
                "its noise ({} and {} cm/s) is not a positive DVL noise and a reference noise of zero or more",
                self.dvl_noise_cm_s, self.reference_noise_cm_s
            ));
        }
        if self
            .residual_cm_s
            .iter()
            .any(|r| !(r.is_finite() && *r >= 0.0))
        {
            return Err(format!(
                "its residual_cm_s {:?} is not three finite values of zero or more",
                self.residual_cm_s
            ));
        }
        Ok(())
    }
}

impl SavedTerm {
    /// The term named `name`, its value finite, its standard deviation zero or more;
    /// else the name it has and what is wrong.
    fn check(&self, name: &str) -> Result<(), (String, String)> {
        if self.name != *name {
            return Err((self.name.clone(), format!("expected {name} here")));
        }
        if !self.value.is_finite() {
            return Err((name.to_string(), format!("its value is {}", self.value)));
        }
        if !(self.std >= 0.0) {
            return Err((
                name.to_string(),
                format!("its standard deviation is {}", self.std),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file() -> InstallationFile {
        InstallationFile {
            tool: TOOL.into(),
            version: TOOL_VERSION.into(),
            recording: "DVL_trajectory1.csv".into(),
            recording_sha256: "ab".repeat(32),
            dvl_noise_cm_s: 2.0,
            reference_noise_cm_s: 0.5,
            residual_cm_s: [1.0, 2.0, 0.5],
            residual_measured: true,
            vehicle_terms: vec![TermName::LeverArm],
            dive_terms: vec![TermName::TimeOffset],
            terms: [
                "lever_arm_x_m",
                "lever_arm_y_m",
                "lever_arm_z_m",
                "time_offset_s",
            ]
            .iter()
            .zip([-1.9, 0.05, 0.4, 1.45])
            .map(|(name, value)| SavedTerm {
                name: name.to_string(),
                value,
                std: 0.01,
            })
            .collect(),
            correlation: (0..4)
                .map(|i| (0..4).map(|j| f64::from(u8::from(i == j))).collect())
                .collect(),
            dives: 1,
            between_dives: Vec::new(),
            fix_latency: None,
            time_offset_includes_fix_latency: false,
            mount: None,
        }
    }

    fn saved() -> SavedInstallation {
        SavedInstallation { file: file() }
    }

    #[test]
    fn a_file_reads_back_as_written_and_an_edited_damaged_foreign_or_nan_one_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("installation.toml");
        saved().write(&path).unwrap();
        let read = SavedInstallation::read(&path).unwrap();
        assert_eq!(read, saved());
        // Of one dive, the file says it holds no spread between dives.
        let written = std::fs::read_to_string(&path).unwrap();
        assert!(
            written.contains("# It holds no spread between dives (calibrated on 1 dive; "),
            "{written}"
        );
        assert_eq!(read.installation().lever_arm_m, [-1.9, 0.05, 0.4]);
        assert_eq!(read.installation().time_offset_s, 1.45);
        let text = std::fs::read_to_string(&path).unwrap();
        let refusal = |text: &str| {
            std::fs::write(&path, text).unwrap();
            SavedInstallation::read(&path).unwrap_err().to_string()
        };
        // Edited by hand.
        let edited = refusal(&text.replace("-1.9", "-2.1"));
        assert!(edited.contains("edited or damaged"), "{edited}");
        // Damaged: cut short.
        let cut = refusal(&text[..text.len() / 2]);
        assert!(cut.contains("edited or damaged"), "{cut}");
        // Not an installation file.
        let foreign = refusal("name = \"paper\"\n");
        assert!(foreign.contains("not an installation file"), "{foreign}");
        // Another version, and a NaN, each with a checksum that matches.
        let mut other = file();
        other.version = "0.0.1".into();
        let message = refusal(&other.to_text());
        assert!(message.contains("written by dcnet-exp 0.0.1"), "{message}");
        let mut nan = file();
        nan.terms[3].value = f64::NAN;
        let message = refusal(&nan.to_text());
        assert!(
            message.contains("terms[3] (time_offset_s): its value is NaN"),
            "{message}"
        );
        assert!(message.contains("installation.toml"), "{message}");
        // A correlation of the wrong size, a negative noise, a term both the
        // vehicle's and the dive's: each with a checksum that matches.
        let mut small = file();
        small.correlation = vec![vec![1.0]];
        assert!(refusal(&small.to_text()).contains("not a 4 × 4 matrix"));
        let mut negative = file();
        negative.dvl_noise_cm_s = -2.0;
        assert!(refusal(&negative.to_text()).contains("is not a positive DVL noise"));
        let mut both = file();
        both.vehicle_terms.push(TermName::TimeOffset);
        assert!(refusal(&both.to_text()).contains("is both a vehicle's and a dive's term"));
        // Lists `calibrate` could not have written, named by their key.
        let mut twice = file();
        twice.dive_terms.push(TermName::TimeOffset);
        let message = refusal(&twice.to_text());
        assert!(
            message
                .contains("vehicle_terms and dive_terms together: \"time_offset\" is listed twice"),
            "{message}"
        );
        let mut both_biases = file();
        both_biases.vehicle_terms.push(TermName::Bias);
        both_biases.dive_terms.push(TermName::BiasScalar);
        let message = refusal(&both_biases.to_text());
        assert!(message.contains("lists bias and bias_scalar"), "{message}");
        let mut lever = file();
        lever.vehicle_terms.retain(|t| *t != TermName::LeverArm);
        lever.dive_terms.push(TermName::LeverArm);
        let message = refusal(&lever.to_text());
        assert!(
            message.contains("dive_terms: \"lever_arm\" belongs to the vehicle, not the dive"),
            "{message}"
        );
        // A term beyond any installation, which `calibrate` refuses to fit.
        let mut far = file();
        far.terms[0].value = -1e6;
        let message = refusal(&far.to_text());
        assert!(
            message.contains("the fitted lever arm x is -1000000 m, beyond the ±100 m"),
            "{message}"
        );
        // The fixes' latency: read back, and refused beyond the fit's reach or named
        // as another.
        let latency = (file().check(Path::new("a.toml")))
            .unwrap()
            .with_fix_latency(0.4, 0.1);
        let read = InstallationFile::clone(&latency)
            .check(Path::new("a.toml"))
            .unwrap();
        assert_eq!(read.fix_latency.as_ref().map(|l| l.value), Some(0.4));
        // A time offset that is the clock and the latency summed says so; others say
        // nothing of it.
        let summed = (file().check(Path::new("a.toml")))
            .unwrap()
            .with_time_offset_including_fix_latency();
        let text = InstallationFile::clone(&summed).to_text();
        assert!(
            text.contains("time_offset_includes_fix_latency = true"),
            "{text}"
        );
        std::fs::write(&path, &text).unwrap();
        let read = SavedInstallation::read(&path).unwrap();
        assert!(read.time_offset_includes_fix_latency);
        assert!(!file().to_text().contains("includes_fix_latency"));
        let mut far = InstallationFile::clone(&latency);
        far.fix_latency.as_mut().unwrap().value = 5.0;
        let message = refusal(&far.to_text());
        assert!(
            message.contains("fix_latency: 5 s lies beyond the ±3 s"),
            "{message}"
        );
        let mut other = InstallationFile::clone(&latency);
        other.fix_latency.as_mut().unwrap().name = "time_offset_s".into();
        let message = refusal(&other.to_text());
        assert!(
            message.contains("fix_latency (time_offset_s): expected fix_latency_s"),
            "{message}"
        );
        // A spread between dives of too few dives, or of a term not the vehicle's.
        let mut two = file();
        two.dives = 2;
        two.between_dives = vec![SavedSpread {
            name: "lever_arm_x_m".into(),
            std: 0.01,
            next_dive: [-1.95, -1.85],
        }];
        assert!(refusal(&two.to_text()).contains("a spread needs three dives or more"));
        let mut clock = file();
        clock.dives = 4;
        clock.between_dives = vec![SavedSpread {
            name: "time_offset_s".into(),
            std: 0.01,
            next_dive: [1.0, 2.0],
        }];
        let message = refusal(&clock.to_text());
        assert!(
            message.contains("between_dives[0] (time_offset_s): not one of the vehicle's terms"),
            "{message}"
        );
        // Not a file, or far too large for one.
        let not_one = SavedInstallation::read(Path::new("/dev/zero"))
            .unwrap_err()
            .to_string();
        assert!(
            not_one.contains("/dev/zero: not a regular file"),
            "{not_one}"
        );
        std::fs::write(&path, vec![b'#'; 2 << 20]).unwrap();
        let large = SavedInstallation::read(&path).unwrap_err().to_string();
        assert!(
            large.contains(": 2097152 bytes: not an installation file"),
            "{large}"
        );
    }
}
