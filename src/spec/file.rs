//! The experiment spec as written in TOML: plain serde types, every struct closed to
//! unknown keys, defaults filled in. Nothing here is checked beyond its type; `check`
//! turns a [`SpecFile`] into the checked [`crate::spec::Spec`].

use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// A whole spec file.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields, expecting = "a table of the spec's sections")]
pub struct SpecFile {
    /// Name of the experiment; results go to `results/<name>/`.
    pub name: String,
    /// Root of every random stream in the run.
    #[serde(default)]
    pub seed: u64,
    pub data: DataSectionFile,
    #[serde(default)]
    pub sensors: SensorsFile,
    pub grid: GridFile,
    pub dataset: DatasetFile,
    pub dvl: Vec<DvlFile>,
    pub calibration: CalibrationFile,
    pub evaluation: EvaluationFile,
    #[serde(default)]
    pub estimators: EstimatorsFile,
    #[serde(default)]
    pub model: ModelFile,
    #[serde(default)]
    pub training: TrainingFile,
    #[serde(default)]
    pub report: ReportFile,
}

/// The `[data]` section: the trajectories an experiment runs on and how they are
/// sampled (not a data file: the files are its `trajectories`). A fault's message
/// says what is expected in words.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with `sample_rate_hz` and `trajectories`"
)]
pub struct DataSectionFile {
    /// Samples per second of every trajectory.
    #[serde(default = "default_sample_rate_hz")]
    pub sample_rate_hz: f64,
    /// Length of the forward moving average that makes the ground truth.
    #[serde(default = "default_ground_truth_window_samples")]
    pub ground_truth_window_samples: usize,
    /// Parameters of the synthetic trajectory generator.
    #[serde(default)]
    pub synthetic: SyntheticFile,
    pub trajectories: Vec<TrajectoryFile>,
}

/// One named trajectory: a sample range of a `.npy` or `.csv` file, or a synthetic one.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with `name`, and `file` or `synthetic_duration_s`"
)]
pub struct TrajectoryFile {
    pub name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<PathBuf>,
    /// Half-open `[start, end)` sample range in `file` (rows below the header of a
    /// `.csv`); the whole file when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<[usize; 2]>,
    /// The x, y, z velocity columns of a `.csv` file; [`crate::VELOCITY_COLUMNS`] when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub columns: Option<[String; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub synthetic_duration_s: Option<f64>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table of the synthetic trajectories' settings"
)]
pub struct SyntheticFile {
    /// Range of cruise speeds of the straight legs.
    pub speed_m_s: [f64; 2],
    /// Range of leg durations.
    pub leg_duration_s: [f64; 2],
    /// Largest heading change rate during a turn, which shows as sway.
    pub turn_rate_deg_s: f64,
    /// Amplitude of the slow vertical oscillation.
    pub heave_amplitude_m_s: f64,
    /// Length of the surface drift at the end of each trajectory.
    pub surface_s: f64,
    /// White noise on the recorded velocity (the smoothing that makes GT removes it).
    pub recording_noise_cm_s: f64,
}

impl Default for SyntheticFile {
    fn default() -> Self {
        Self {
            speed_m_s: [1.0, 2.0],
            leg_duration_s: [60.0, 240.0],
            turn_rate_deg_s: 3.0,
            heave_amplitude_m_s: 0.05,
            surface_s: 60.0,
            recording_noise_cm_s: 0.2,
        }
    }
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with `beam_pitch_deg` and `gnss_noise_m_s`"
)]
pub struct SensorsFile {
    /// Pitch of each DVL beam from the vertical.
    pub beam_pitch_deg: f64,
    /// Standard deviation of the GNSS-RTK velocity noise, per axis.
    pub gnss_noise_cm_s: f64,
}

impl Default for SensorsFile {
    fn default() -> Self {
        Self {
            beam_pitch_deg: 20.0,
            gnss_noise_cm_s: 0.5,
        }
    }
}

/// The training grid: every combination of the three axes.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with `scale_pct`, `bias_cm_s` and `noise_cm_s`"
)]
pub struct GridFile {
    pub scale_pct: AxisFile,
    pub bias_cm_s: AxisFile,
    pub noise_cm_s: AxisFile,
}

/// One grid axis: explicit `values`, or `start`, `stop` (inclusive) and `step`.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with `values`, or `start`, `stop` and `step`"
)]
pub struct AxisFile {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub values: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stop: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step: Option<f64>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields, expecting = "a table with `trajectories`")]
pub struct DatasetFile {
    /// Trajectories the training windows are cut from.
    pub trajectories: Vec<String>,
    #[serde(default = "default_window_s")]
    pub window_s: f64,
    #[serde(default = "default_stride_s")]
    pub stride_s: f64,
    #[serde(default = "default_validation_fraction")]
    pub validation_fraction: f64,
    /// The window count a publication reports, for `data info` to compare against.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub published_windows: Option<usize>,
}

/// A DVL under test: the error terms its measurements are made with.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with `name`, `scale_pct`, `bias_cm_s` and `noise_cm_s`"
)]
pub struct DvlFile {
    pub name: String,
    pub scale_pct: f64,
    pub bias_cm_s: f64,
    pub noise_cm_s: f64,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with `trajectory`, `window_sizes_s` and `monte_carlo_runs`"
)]
pub struct CalibrationFile {
    /// The trajectory calibrated on (T10Cal in the paper).
    pub trajectory: String,
    pub window_sizes_s: Vec<f64>,
    pub monte_carlo_runs: usize,
    /// A method's calibration time is the shortest calibration after which its
    /// held-out RMSE stays within this of its value at the longest window, %.
    #[serde(default = "default_time_tolerance_pct")]
    pub time_tolerance_pct: f64,
}

fn default_time_tolerance_pct() -> f64 {
    10.0
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields, expecting = "a table with `trajectories`")]
pub struct EvaluationFile {
    pub trajectories: Vec<String>,
}

/// Each key left out takes its default: every kind, every error model.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    default,
    expecting = "a table with `kinds` and `error_models`"
)]
pub struct EstimatorsFile {
    /// Any of `baseline`, `least_squares`, `beam_wls`, `kalman`, `kalman_beam`,
    /// `dcnet`, `floor`.
    pub kinds: Vec<String>,
    /// Any of `EM1` .. `EM5`, for the kinds that take an error model.
    pub error_models: Vec<String>,
    /// The prior and random walk of the Kalman filters' terms.
    pub kalman: ScaleBiasKalmanFile,
}

/// `[estimators.kalman]`: the terms of the paper's Kalman filters (`kalman`,
/// `kalman_beam`), which estimate only the scale and bias of a simulated DVL's error
/// model: their prior standard deviation about zero (10 % and 10 cm/s by default,
/// wide over the grid's errors), and the random walk each may take, per √s (zero:
/// constant terms). Not an installation's `[calibration.kalman]`, whose filter
/// estimates five kinds of term with other keys and a 5 % scale prior.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    default,
    expecting = "a table of the Kalman filters' prior and random walk"
)]
pub struct ScaleBiasKalmanFile {
    pub prior_scale_pct: f64,
    pub prior_bias_cm_s: f64,
    pub scale_random_walk_pct_per_sqrt_s: f64,
    pub bias_random_walk_cm_s_per_sqrt_s: f64,
}

impl Default for ScaleBiasKalmanFile {
    fn default() -> Self {
        Self {
            prior_scale_pct: 10.0,
            prior_bias_cm_s: 10.0,
            scale_random_walk_pct_per_sqrt_s: 0.0,
            bias_random_walk_cm_s_per_sqrt_s: 0.0,
        }
    }
}

impl Default for EstimatorsFile {
    fn default() -> Self {
        Self {
            kinds: [
                "baseline",
                "least_squares",
                "beam_wls",
                "kalman",
                "kalman_beam",
                "dcnet",
                "floor",
            ]
            .map(String::from)
            .to_vec(),
            error_models: ["EM1", "EM2", "EM3", "EM4", "EM5"]
                .map(String::from)
                .to_vec(),
            kalman: ScaleBiasKalmanFile::default(),
        }
    }
}

/// DCNet's layer sizes (docs/paper.md gives the layout, not the sizes).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    default,
    expecting = "a table of the model's settings"
)]
pub struct ModelFile {
    /// Output channels of every convolution, in both heads.
    pub conv_channels: usize,
    /// Kernel length of the two Conv1d of the 1D head.
    pub conv1d_kernel_size: usize,
    /// Widths of the first three Linear layers of the FC batch.
    pub fc_widths: [usize; 3],
    /// Activation after each of the first three Linear layers: `tanh` or `leaky_relu`.
    pub activation: String,
    /// Negative slope of every LeakyReLU.
    pub leaky_relu_slope: f64,
    /// Dropout probability after each of the first three Linear layers.
    pub dropout: f64,
}

impl Default for ModelFile {
    fn default() -> Self {
        Self {
            conv_channels: 16,
            conv1d_kernel_size: 2,
            fc_widths: [128, 64, 32],
            activation: "tanh".into(),
            leaky_relu_slope: 0.05,
            dropout: 0.3,
        }
    }
}

/// How DCNet is trained.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    default,
    expecting = "a table of the training's settings"
)]
pub struct TrainingFile {
    /// `flex` or `ndarray` (burn's CPU backends).
    pub backend: String,
    pub epochs: usize,
    pub batch_size: usize,
    /// RMSProp learning rate per error model.
    pub learning_rate: LearningRatesFile,
    /// RMSProp smoothing constant and epsilon (PyTorch's defaults; no momentum).
    pub rmsprop_alpha: f64,
    pub rmsprop_epsilon: f64,
    /// A resumable checkpoint is written every this many epochs.
    pub checkpoint_every_epochs: usize,
    /// Stop before `epochs` once the validation loss stops improving; absent: train
    /// every epoch, as the paper does.
    pub early_stopping: Option<EarlyStoppingFile>,
    /// DCNets trained per error model, from independent seeds; left out of the
    /// resolved spec when 1, so a spec without it keeps its results key.
    #[serde(skip_serializing_if = "is_one")]
    pub replicates: usize,
}

fn is_one(value: &usize) -> bool {
    *value == 1
}

/// `[training.early_stopping]`: stop once `patience_epochs` epochs in a row have not
/// improved on the validation loss of the last improvement by more than
/// `min_improvement` (cm/s)².
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table of early stopping's settings"
)]
pub struct EarlyStoppingFile {
    pub patience_epochs: usize,
    #[serde(default)]
    pub min_improvement: f64,
}

impl Default for TrainingFile {
    fn default() -> Self {
        Self {
            backend: "flex".into(),
            epochs: 100,
            batch_size: 256,
            learning_rate: LearningRatesFile::default(),
            rmsprop_alpha: 0.99,
            rmsprop_epsilon: 1e-8,
            checkpoint_every_epochs: 5,
            early_stopping: None,
            replicates: 1,
        }
    }
}

/// RMSProp learning rate per error model: a table `{ EM1 = .., EM5 = .. }` (missing
/// models keep their default) or one number for all five.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LearningRatesFile {
    #[serde(rename = "EM1")]
    pub em1: f64,
    #[serde(rename = "EM2")]
    pub em2: f64,
    #[serde(rename = "EM3")]
    pub em3: f64,
    #[serde(rename = "EM4")]
    pub em4: f64,
    #[serde(rename = "EM5")]
    pub em5: f64,
}

/// The table form of [`LearningRatesFile`].
#[derive(Deserialize)]
#[serde(deny_unknown_fields, default)]
struct LearningRatesTable {
    #[serde(rename = "EM1")]
    em1: f64,
    #[serde(rename = "EM2")]
    em2: f64,
    #[serde(rename = "EM3")]
    em3: f64,
    #[serde(rename = "EM4")]
    em4: f64,
    #[serde(rename = "EM5")]
    em5: f64,
}

impl Default for LearningRatesTable {
    fn default() -> Self {
        let LearningRatesFile {
            em1,
            em2,
            em3,
            em4,
            em5,
        } = LearningRatesFile::default();
        Self {
            em1,
            em2,
            em3,
            em4,
            em5,
        }
    }
}

impl<'de> Deserialize<'de> for LearningRatesFile {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Rates;
        impl<'de> serde::de::Visitor<'de> for Rates {
            type Value = LearningRatesFile;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number, or a table of numbers keyed EM1 to EM5")
            }
            fn visit_f64<E: serde::de::Error>(self, rate: f64) -> Result<Self::Value, E> {
                Ok(LearningRatesFile {
                    em1: rate,
                    em2: rate,
                    em3: rate,
                    em4: rate,
                    em5: rate,
                })
            }
            fn visit_i64<E: serde::de::Error>(self, rate: i64) -> Result<Self::Value, E> {
                self.visit_f64(rate as f64)
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<Self::Value, A::Error> {
                let t = LearningRatesTable::deserialize(
                    serde::de::value::MapAccessDeserializer::new(map),
                )?;
                Ok(LearningRatesFile {
                    em1: t.em1,
                    em2: t.em2,
                    em3: t.em3,
                    em4: t.em4,
                    em5: t.em5,
                })
            }
        }
        deserializer.deserialize_any(Rates)
    }
}

impl Default for LearningRatesFile {
    fn default() -> Self {
        Self {
            em1: 5e-5,
            em2: 5e-5,
            em3: 5e-5,
            em4: 5e-5,
            em5: 5e-4,
        }
    }
}

/// What the report and the figures show beyond the tables.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields, expecting = "a table of the report's settings")]
pub struct ReportFile {
    /// TOML file of published values to put beside ours (see `crate::spec::published`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub published: Option<PathBuf>,
    /// A cell is flagged when our RMSE differs from the published one by more than
    /// this share of the published value.
    #[serde(default = "default_tolerance_pct")]
    pub tolerance_pct: f64,
    /// The two trajectories of the velocity figure; the first training and the first
    /// test trajectory when empty.
    #[serde(default)]
    pub velocity_trajectories: Vec<String>,
}

impl Default for ReportFile {
    fn default() -> Self {
        Self {
            published: None,
            tolerance_pct: default_tolerance_pct(),
            velocity_trajectories: Vec::new(),
        }
    }
}

fn default_tolerance_pct() -> f64 {
    10.0
}

fn default_sample_rate_hz() -> f64 {
    1.0
}
fn default_ground_truth_window_samples() -> usize {
    5
}
fn default_window_s() -> f64 {
    10.0
}
fn default_stride_s() -> f64 {
    9.0
}
fn default_validation_fraction() -> f64 {
    0.2
}

/// The `[sweep]` table: the values of any spec keys, whose product is the grid of
/// points to run, or a random sample of it.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields, expecting = "a table with `values`")]
pub struct SweepFile {
    /// Run this many points drawn at random from the grid instead of all of them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sample: Option<usize>,
    /// Seed of the sample; the spec's `seed` when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sample_seed: Option<u64>,
    /// Dotted spec key → list of values, e.g. `"training.learning_rate" = [1e-4, 1e-3]`.
    pub values: toml::Table,
}
