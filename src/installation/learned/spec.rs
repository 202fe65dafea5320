//! `[learned]` of an installation spec: DCNets that learn the installation's terms, the
//! installations they train on when simulated, and what they train on. In: the table as
//! written ([`LearnedFile`]). Out: its checked form, [`LearnedSpec`], which the check
//! of the section (`installation/spec/check/learned.rs`) makes, or every fault at its
//! key.

use crate::installation::terms::Installation;
use crate::installation::terms::names::TermName;

/// `[learned]`: DCNets that learn the installation's terms, trained fold by fold on the
/// trajectories outside the fold (simulated installations over their reference, or
/// their real DVL), and scored on the trajectories inside it.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LearnedFile {
    /// The terms the network outputs.
    pub terms: Vec<TermName>,
    /// Folds over the trajectories, round robin in spec order.
    pub folds: usize,
    /// What the models train on: "simulated" installations, the "vehicle"'s own DVL.
    #[serde(default = "LearnedFile::default_sources")]
    pub sources: Vec<String>,
    /// Samples per network window.
    #[serde(default = "LearnedFile::default_window")]
    pub window_samples: usize,
    /// A training window starts every this many samples.
    #[serde(default = "LearnedFile::default_stride")]
    pub stride_samples: usize,
    /// The share of each trajectory's (and installation's) windows, its last ones, kept
    /// for validation.
    #[serde(default = "LearnedFile::default_validation")]
    pub validation_fraction: f64,
    #[serde(default = "LearnedFile::default_seed")]
    pub seed: u64,
    pub simulation: SimulationGrid,
    #[serde(default)]
    pub model: crate::spec::file::ModelFile,
    #[serde(default)]
    pub training: crate::spec::file::TrainingFile,
}

impl LearnedFile {
    fn default_sources() -> Vec<String> {
        vec!["simulated".into(), "vehicle".into()]
    }
    fn default_window() -> usize {
        10
    }
    fn default_stride() -> usize {
        5
    }
    fn default_validation() -> f64 {
        0.2
    }
    fn default_seed() -> u64 {
        2024
    }
}

/// The installations a model trains on: every combination of the lists, in the spec's
/// units (lever arm in m, time offset in s, misalignment in degrees, scale in %, bias in
/// cm/s, one value for the three axes of a scale or a bias).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationGrid {
    pub lever_arm_x_m: Vec<f64>,
    pub lever_arm_y_m: Vec<f64>,
    pub lever_arm_z_m: Vec<f64>,
    pub time_offset_s: Vec<f64>,
    pub misalignment_z_deg: Vec<f64>,
    pub scale_pct: Vec<f64>,
    pub bias_cm_s: Vec<f64>,
}

impl SimulationGrid {
    /// Every combination, the lever arm's x outermost and the bias innermost.
    pub fn installations(&self) -> Vec<Installation> {
        let mut all = Vec::new();
        for &x in &self.lever_arm_x_m {
            for &y in &self.lever_arm_y_m {
                for &z in &self.lever_arm_z_m {
                    for &time_offset_s in &self.time_offset_s {
                        for &yaw_deg in &self.misalignment_z_deg {
                            for &scale_pct in &self.scale_pct {
                                for &bias_cm_s in &self.bias_cm_s {
                                    all.push(Installation {
                                        scale: [scale_pct / 100.0; 3],
                                        misalignment_rad: [0.0, 0.0, yaw_deg.to_radians()],
                                        lever_arm_m: [x, y, z],
                                        time_offset_s,
                                        bias_m_s: [bias_cm_s / 100.0; 3],
                                    });
                                }
                            }
                        }
                    }
                }
            }
        }
        all
    }
}

/// How the labels of `[learned]`'s methods begin.
pub const LEARNED_LABEL: &str = "DCNet trained on ";

/// What a learned model trains on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TrainingSource {
    /// Simulated installations over the reference of the trajectories outside the fold.
    Simulated,
    /// The real DVL and reference of the trajectories outside the fold.
    Vehicle,
}

impl TrainingSource {
    pub fn name(self) -> &'static str {
        match self {
            TrainingSource::Simulated => "simulated",
            TrainingSource::Vehicle => "vehicle",
        }
    }
}

/// `[learned]`, checked.
#[derive(Debug, Clone)]
pub struct LearnedSpec {
    pub terms: Vec<TermName>,
    pub folds: usize,
    pub sources: Vec<TrainingSource>,
    pub window_samples: usize,
    pub stride_samples: usize,
    pub validation_fraction: f64,
    pub seed: u64,
    pub simulation: SimulationGrid,
    pub model: crate::spec::ModelSpec,
    pub training: crate::spec::TrainingSpec,
}

impl LearnedSpec {
    /// The fold of the trajectory at `index`: round robin in spec order.
    pub fn fold_of(&self, index: usize) -> usize {
        index % self.folds
    }
}
