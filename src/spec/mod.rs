//! The experiment spec. In: a TOML file and `--set` overrides. Out: an [`Experiment`],
//! one checked [`Spec`] per point, whose every value is known good, or every fault at
//! its file, line and key.
//!
//! The rooms, in the order a spec passes through them:
//! - [`mod@file`] holds the serde types read from TOML, one `…File` type per section
//!   (`[data]` is [`file::DataSectionFile`]);
//! - [`mod@toml_file`] reads TOML files and places a fault on its key's line, for the
//!   spec, its overrides and the published values alike;
//! - [`mod@load`] reads a spec ([`load::source`]: where each value came from, so a fault
//!   lands on its line, `--set` or sweep value), applies `--set` overrides
//!   ([`load::overrides`]) and expands a `[sweep]` into its named points
//!   ([`load::sweep`]);
//! - this module holds the checked types, [`Spec`] and one type per section, and
//!   [`SpecFile::check`], which destructures the whole file spec and hands each section
//!   to its check in [`mod@check`]: one file per section ([`check::data`],
//!   [`check::sensors`], [`check::grid`], [`check::dataset`], [`check::calibration`],
//!   [`check::evaluation`], [`check::estimators`], [`check::model`],
//!   [`check::training`], [`check::report`]), each beside its tests. Seconds become
//!   sample counts there, percent and cm/s become fractions and m/s; a new spec key is
//!   a field in [`mod@file`], its check in its section's file, and its checked field
//!   here;
//! - [`ranges`] holds the upper end of every value, with the reason;
//! - [`windows`] holds the sample arithmetic: seconds to samples, and the windows cut
//!   from a trajectory;
//! - [`published`] reads the published values a spec names, and [`recordings`] lists
//!   the Snapir recordings a spec may name and where to download them.
//!
//! Tests across the crate build their spec with `fixture::quick_spec`
//! (`src/spec/fixture.rs`): experiments/quick.toml with overrides.

pub mod file;
pub mod toml_file;
pub mod load;
pub mod check;
pub mod ranges;
pub mod windows;
pub mod published;
pub mod recordings;

pub use file::SpecFile;
pub use load::{Document, Experiment, Point, declared_kind, load, load_documents, load_experiment};
pub use toml_file::{SpecError, SpecErrors, TomlFile};
pub use windows::{seconds_to_samples, window_count, window_starts};

use crate::vocab::{Activation, Backend, ErrorModel, EstimatorKind, SensorErrors};
use check::calibration::{check_calibration, check_dcnet_windows, check_fitted_windows};
use check::data::check_data;
use check::dataset::check_dataset;
use check::estimators::check_estimators;
use check::evaluation::check_evaluation;
use check::grid::check_grid;
use check::model::check_model;
use check::report::check_report;
use check::sensors::{check_dvls, check_sensors};
use check::training::check_training;
use check::{Faults, is_folder_name};
use file::SyntheticFile;
use published::Published;
use std::path::{Path, PathBuf};

/// The longest name (or sweep point name) a results folder may have.
pub const MAX_NAME_CHARS: usize = 200;

/// A checked spec, in the units the pipeline computes in.
#[derive(Debug, Clone)]
pub struct Spec {
    pub name: String,
    pub seed: u64,
    pub sample_rate_hz: f64,
    pub ground_truth_window_samples: usize,
    pub synthetic: SyntheticFile,
    pub trajectories: Vec<TrajectorySource>,
    pub beam_pitch_deg: f64,
    pub gnss_noise_m_s: f64,
    pub grid: Grid,
    pub dataset: DatasetSpec,
    pub dvls: Vec<Dvl>,
    pub calibration: CalibrationSpec,
    /// Indices into `trajectories`.
    pub evaluation: Vec<usize>,
    pub kinds: Vec<EstimatorKind>,
    pub error_models: Vec<ErrorModel>,
    pub kalman: KalmanSpec,
    pub model: ModelSpec,
    pub training: TrainingSpec,
    pub report: ReportSpec,
    /// The spec as resolved (defaults and overrides applied, paths absolute).
    pub resolved: SpecFile,
}

#[derive(Debug, Clone, PartialEq)]
pub struct TrajectorySource {
    pub name: String,
    pub origin: Origin,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Origin {
    /// `[start, end)` of a recording, or all of it.
    File {
        path: PathBuf,
        format: FileFormat,
        samples: Option<[usize; 2]>,
    },
    Synthetic {
        samples: usize,
    },
}

/// How a recording's file is read, chosen by its extension.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
pub enum FileFormat {
    /// A NumPy array, (3, N) or (N, 3).
    Npy,
    /// A CSV file with a header; the x, y, z velocity columns by name.
    Csv { columns: [String; 3] },
}

impl Spec {
    /// The error models a DCNet is trained for: every one the spec lists when DCNet is
    /// among its estimators, none otherwise.
    pub fn trained_models(&self) -> &[ErrorModel] {
        if self.kinds.contains(&EstimatorKind::Dcnet) {
            &self.error_models
        } else {
            &[]
        }
    }

    /// How many DCNets the spec trains: one per trained error model and replicate.
    pub fn model_count(&self) -> usize {
        self.trained_models().len() * self.training.replicates
    }

    /// The resolved spec as TOML, as stored beside the results.
    pub fn resolved_toml(&self) -> String {
        toml::to_string_pretty(&self.resolved).expect("a spec always serializes")
    }

    /// What the trajectory at `index` is used for: "train", "calibration", "test".
    pub fn roles(&self, index: usize) -> Vec<&'static str> {
        let mut roles = Vec::new();
        if self.dataset.trajectories.contains(&index) {
            roles.push("train");
        }
        if self.calibration.trajectory == index {
            roles.push("calibration");
        }
        if self.evaluation.contains(&index) {
            roles.push("test");
        }
        roles
    }
}

impl TrajectorySource {
    /// Length in samples, when the spec alone tells it (not for a range that ends
    /// before it starts, which the check refuses).
    pub fn known_len(&self) -> Option<usize> {
        match &self.origin {
            Origin::File { samples, .. } => samples.and_then(|[start, end]| end.checked_sub(start)),
            Origin::Synthetic { samples } => Some(*samples),
        }
    }
}

/// The training grid, one list per axis, in the spec's units.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    pub scale_pct: Vec<f64>,
    pub bias_cm_s: Vec<f64>,
    pub noise_cm_s: Vec<f64>,
}

#[derive(Debug, Clone)]
pub struct DatasetSpec {
    /// Indices into `Spec::trajectories`.
    pub trajectories: Vec<usize>,
    pub window_samples: usize,
    pub stride_samples: usize,
    pub validation_fraction: f64,
    pub published_windows: Option<usize>,
}

impl DatasetSpec {
    /// The windows that one grid combination yields from training trajectories of
    /// these lengths, in samples.
    pub fn windows_per_combination(&self, lengths: impl IntoIterator<Item = usize>) -> usize {
        lengths
            .into_iter()
            .map(|len| window_count(len, self.window_samples, self.stride_samples))
            .fold(0, usize::saturating_add)
    }

    /// How many of one combination's `windows` are kept for validation.
    pub fn validation_windows(&self, windows: usize) -> usize {
        (self.validation_fraction * windows as f64).round() as usize
    }
}

#[derive(Debug, Clone)]
pub struct Dvl {
    pub name: String,
    pub errors: SensorErrors,
}

#[derive(Debug, Clone)]
pub struct CalibrationSpec {
    /// Index into `Spec::trajectories`.
    pub trajectory: usize,
    /// Window sizes in samples.
    pub window_sizes: Vec<usize>,
    pub monte_carlo_runs: usize,
    /// The calibration time's tolerance, a fraction (0.1 for 10 %).
    pub time_tolerance: f64,
}

/// The Kalman filters' prior and random walk, as fractions and m/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KalmanSpec {
    /// The terms' prior standard deviation about zero.
    pub prior: TermSettings,
    /// The random walk's standard deviation per √s.
    pub random_walk: TermSettings,
}

/// A scale and a bias setting (a prior's standard deviation, or a random walk's per
/// √s): a fraction, and m/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TermSettings {
    pub scale: f64,
    pub bias_m_s: f64,
}

/// DCNet's sizes, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelSpec {
    pub conv_channels: usize,
    pub conv1d_kernel_size: usize,
    pub fc_widths: [usize; 3],
    pub activation: Activation,
    pub leaky_relu_slope: f64,
    pub dropout: f64,
}

/// DCNet training settings, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct TrainingSpec {
    pub backend: Backend,
    pub epochs: usize,
    pub batch_size: usize,
    /// Indexed by `ErrorModel as usize`.
    pub learning_rates: [f64; 5],
    pub rmsprop_alpha: f64,
    pub rmsprop_epsilon: f64,
    pub checkpoint_every_epochs: usize,
    pub early_stopping: Option<EarlyStopping>,
    /// DCNets trained per error model, each from its own seeds (replicate 0 from the
    /// seeds of a run without replicates).
    pub replicates: usize,
}

/// Training stops once `patience` epochs in a row have not improved on the validation
/// loss of the last improvement by more than `min_improvement` (cm/s)²
/// (counted as `train::epochs_without_improvement` counts).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EarlyStopping {
    pub patience: usize,
    pub min_improvement: f64,
}

impl TrainingSpec {
    pub fn learning_rate(&self, model: ErrorModel) -> f64 {
        self.learning_rates[model as usize]
    }
}

/// What the report and figures show beyond the tables.
#[derive(Debug, Clone)]
pub struct ReportSpec {
    /// The published values, read and checked.
    pub published: Option<Published>,
    pub tolerance_pct: f64,
    pub velocity_trajectories: Vec<String>,
}

impl SpecFile {
    /// Checks every value; `spec_dir` is where relative paths start.
    /// Returns the faults as (key path, message) pairs.
    pub fn check(self, spec_dir: &Path) -> Result<Spec, Vec<(String, String)>> {
        let mut faults = Faults::default();
        let SpecFile {
            name,
            seed,
            data,
            sensors,
            grid,
            dataset,
            dvl,
            calibration,
            evaluation,
            estimators,
            model,
            training,
            report,
        } = self.clone();
        let mut resolved = self;

        if !is_folder_name(&name) {
            faults.add("name", format!("{name:?} must be non-empty, at most {MAX_NAME_CHARS} characters, use only letters, digits, '-', '_' and '.', and not start with '.' (it names the results folder)"));
        }
        let data = check_data(data, spec_dir, &mut resolved.data.trajectories, &mut faults);
        let (rate, sources) = (data.rate, &check::Defined::new(&data.trajectories));
        let (beam_pitch_deg, gnss_noise_m_s) = check_sensors(sensors, &mut faults);
        let grid = check_grid(grid, &mut faults);
        let (dataset, window) = check_dataset(dataset, sources, rate, &mut faults);
        let dvls = check_dvls(&dvl, &mut faults);
        let calibration = check_calibration(calibration, sources, rate, &mut faults);
        let evaluation = check_evaluation(evaluation, sources, &mut faults);
        let (kinds, error_models, kalman) = check_estimators(estimators, &mut faults);
        if kinds.contains(&EstimatorKind::Dcnet) {
            check_dcnet_windows(window, &calibration.window_sizes, rate, &mut faults);
        }
        if kinds
            .iter()
            .any(|k| matches!(k, EstimatorKind::LeastSquares | EstimatorKind::BeamWls))
        {
            check_fitted_windows(&error_models, &calibration.window_sizes, rate, &mut faults);
        }
        let model = check_model(model, window.samples, &mut faults);
        let training = check_training(training, &mut faults);
        let report = check_report(report, spec_dir, sources, &mut resolved, &mut faults);

        if !faults.0.is_empty() {
            return Err(faults.0);
        }
        Ok(Spec {
            name,
            seed,
            sample_rate_hz: data.sample_rate_hz,
            ground_truth_window_samples: data.ground_truth_window_samples,
            synthetic: data.synthetic,
            trajectories: data.trajectories,
            beam_pitch_deg,
            gnss_noise_m_s,
            grid,
            dataset,
            dvls,
            calibration,
            evaluation,
            kinds,
            error_models,
            kalman,
            model,
            training,
            report,
            resolved,
        })
    }
}

#[cfg(test)]
pub(crate) mod fixture;
#[cfg(test)]
pub(crate) use fixture::quick_spec;
