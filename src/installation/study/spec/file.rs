//! An installation spec as written in TOML: plain serde types, every struct closed to
//! unknown keys, defaults filled in. Nothing here is checked beyond its type; the
//! checks in `check/`, one file a section, turn an [`StudyFile`] into the
//! checked `StudySpec`. `[calibration.kalman]` is
//! [`StudyKalmanFile`] and `[learned]` is [`LearnedFile`], beside the types they
//! share with the rest of the installation.

use crate::data::paired::PairedColumns;
use crate::installation::estimate::bound::{DEFAULT_TOLERANCES, Tolerances};
use crate::installation::learned::spec::LearnedFile;
use crate::installation::study::spec::kalman::StudyKalmanFile;
use crate::installation::terms::TermKind;
use crate::installation::terms::names::TermName;
use std::path::PathBuf;

/// The file as written.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    pub name: String,
    pub kind: String,
    pub recordings: RecordingsFile,
    pub noise: NoiseFile,
    pub calibration: StudyCalibrationFile,
    #[serde(default)]
    pub observability: ObservabilityFile,
    pub dcnet: Option<DcnetModelsFile>,
    pub learned: Option<LearnedFile>,
}

#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordingsFile {
    /// The column names, when they are not A-KIT's.
    pub columns: Option<PairedColumns>,
    pub trajectories: Vec<PairedTrajectoryFile>,
}

#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairedTrajectoryFile {
    pub name: String,
    /// The DVL's CSV file, relative to the spec.
    pub dvl: PathBuf,
    /// The reference's CSV file; the DVL's when it holds both.
    pub reference: Option<PathBuf>,
    /// Where `dvl` is a ROS 2 bag: its DVL topic and reference topic (each its only
    /// one of its type where not named), an IMU topic for the body rate,
    /// `"header"` or `"receive"` stamps, and the body
    /// frame, as `calibrate`'s flags of the same names.
    pub dvl_topic: Option<String>,
    pub reference_topic: Option<String>,
    pub rate_topic: Option<String>,
    pub stamps: Option<String>,
    pub frame: Option<String>,
    /// Where `dvl` is the DVL's own log: its format, `"pd0"` or `"water-linked"` (found
    /// from the file's content where not given), as `calibrate --dvl-format`.
    pub dvl_format: Option<String>,
}

#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseFile {
    /// The DVL's white noise per axis, cm/s.
    pub dvl_cm_s: f64,
    /// The reference velocity's white noise per axis, cm/s.
    pub reference_cm_s: f64,
}

#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyCalibrationFile {
    /// Calibration windows: the first w seconds of the calibration trajectory; a w at
    /// least its length takes all of it.
    pub window_s: Vec<f64>,
    /// The paper's methods: "baseline", "EM1" to "EM5" (least squares), "dcnet".
    pub methods: Vec<String>,
    /// Named term sets of the installation model, fitted by nonlinear least squares.
    #[serde(default)]
    pub models: Vec<TermSetFile>,
    /// The models the extended Kalman filter runs too, and its prior.
    #[serde(default)]
    pub kalman: StudyKalmanFile,
    /// A method's calibration time is the shortest window after which its held-out
    /// RMSE stays within this of its value at the longest window, %.
    #[serde(default = "StudyCalibrationFile::default_time_tolerance_pct")]
    pub time_tolerance_pct: f64,
    /// The terms of the dive, found again on each scored trajectory; none when absent.
    pub dive: Option<DiveFile>,
    /// The method calibrated against fixes simulated from the recordings' positions;
    /// none when absent.
    pub fixes: Option<FixesFile>,
}

/// `[calibration.fixes]`: fixes simulated from each calibration recording's positions,
/// one every `interval_s` seconds with `noise_m` metres of white noise per horizontal
/// axis, a share `outlier_share` of them displaced `outlier_m` further (multipath),
/// drawn from the stream of `seed` and the recording's name.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FixesFile {
    pub interval_s: f64,
    pub noise_m: f64,
    #[serde(default)]
    pub outlier_share: f64,
    #[serde(default = "FixesFile::default_outlier_m")]
    pub outlier_m: f64,
    #[serde(default)]
    pub seed: u64,
}

impl FixesFile {
    /// A multipath fix's displacement, m, where the spec gives none: ten times a USBL's
    /// typical 2.5 m.
    fn default_outlier_m() -> f64 {
        25.0
    }
}

/// `[calibration.dive]`: which terms belong to the dive (its clock, and the bias where
/// it is listed) and are found again at the start of each scored trajectory, over how
/// many seconds, and how far the search for its time offset looks.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiveFile {
    /// "time_offset", and "bias" or "bias_scalar" where the bias is the dive's too.
    #[serde(default = "DiveFile::default_terms")]
    pub terms: Vec<TermName>,
    /// The first w seconds of a scored trajectory the dive's terms are found from; the
    /// trajectory is scored after them.
    pub window_s: Vec<f64>,
    /// How far from the carried time offset the search looks, s.
    #[serde(default = "DiveFile::default_search_s")]
    pub search_s: f64,
}

impl DiveFile {
    fn default_terms() -> Vec<TermName> {
        vec![TermName::TimeOffset]
    }

    fn default_search_s() -> f64 {
        crate::installation::estimate::clock::DEFAULT_SEARCH_S
    }
}

impl StudyCalibrationFile {
    fn default_time_tolerance_pct() -> f64 {
        10.0
    }
}

#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TermSetFile {
    pub name: String,
    pub terms: Vec<TermName>,
}

/// The standard deviation past which a term counts as not seen (a pair correlated
/// beyond [`CORRELATION_LIMIT`](crate::installation::estimate::bound::CORRELATION_LIMIT) is not
/// seen either).
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ObservabilityFile {
    pub scale_pct: f64,
    pub misalignment_deg: f64,
    pub lever_arm_m: f64,
    pub time_offset_s: f64,
    pub bias_cm_s: f64,
}

impl Default for ObservabilityFile {
    /// [`DEFAULT_TOLERANCES`] in the file's units.
    fn default() -> Self {
        ObservabilityFile::from(DEFAULT_TOLERANCES)
    }
}

impl From<Tolerances> for ObservabilityFile {
    /// The tolerances in the file's units: the inverse of
    /// [`ObservabilityFile::tolerances`].
    fn from(tolerances: Tolerances) -> Self {
        let shown = |kind: TermKind| tolerances.of(kind) * kind.table().unit.factor();
        ObservabilityFile {
            scale_pct: shown(TermKind::Scale),
            misalignment_deg: shown(TermKind::Misalignment),
            lever_arm_m: shown(TermKind::LeverArm),
            time_offset_s: shown(TermKind::TimeOffset),
            bias_cm_s: shown(TermKind::Bias),
        }
    }
}

impl ObservabilityFile {
    /// The tolerance of a kind of term as the file gives it, in the kind's shown unit
    /// (under the key [`KindOfTerm::spec_key`](crate::installation::terms::KindOfTerm::spec_key) gives).
    pub fn of(&self, kind: TermKind) -> f64 {
        match kind {
            TermKind::Scale => self.scale_pct,
            TermKind::Misalignment => self.misalignment_deg,
            TermKind::LeverArm => self.lever_arm_m,
            TermKind::TimeOffset => self.time_offset_s,
            TermKind::Bias => self.bias_cm_s,
        }
    }

    /// The tolerances in the bound's units.
    pub fn tolerances(&self) -> Tolerances {
        Tolerances::from_fn(|kind| kind.table().unit.to_stored(self.of(kind)))
    }
}

/// The DCNet models a paper spec trained, applied to these recordings.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DcnetModelsFile {
    /// The paper spec whose models are used, relative to this spec.
    pub spec: PathBuf,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The default `[observability]` is the bound's default tolerances in the file's
    /// units, exactly: the numbers a spec without the table resolves to, and back.
    #[test]
    fn default_observability_is_the_bounds_default_in_file_units() {
        let file = ObservabilityFile::default();
        let in_file_units = [
            file.scale_pct,
            file.misalignment_deg,
            file.lever_arm_m,
            file.time_offset_s,
            file.bias_cm_s,
        ];
        assert_eq!(in_file_units, [0.5, 0.5, 0.1, 0.05, 1.0]);
        assert_eq!(file.tolerances(), DEFAULT_TOLERANCES);
    }
}
