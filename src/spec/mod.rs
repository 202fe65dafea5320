//! The experiment spec. In: a TOML file and `--set` overrides. Out: an [`Experiment`],
//! one checked [`Spec`] per point, whose every value is known good, or every fault at
//! its file, line and key.
//!
//! - [`mod@file`] holds the serde types read from TOML;
//! - [`mod@toml_file`] reads TOML files and places a fault on its key's line, for the
//!   spec, its overrides and the published values alike;
//! - [`mod@load`] reads a spec, applies `--set` overrides and expands a `[sweep]` into its
//!   points;
//! - this module checks a [`SpecFile`] into a [`Spec`], one section at a time. Seconds
//!   become sample counts here, percent and cm/s become fractions and m/s;
//! - [`published`] reads the published values a spec names, and [`recordings`] lists
//!   the Snapir recordings a spec may name and where to download them.

pub mod file;
pub mod load;
pub mod published;
pub mod ranges;
pub mod recordings;
pub mod toml_file;

pub use file::SpecFile;
pub use load::{Experiment, Point, load, load_experiment};
pub use toml_file::{SpecError, SpecErrors, TomlFile};

use crate::vocab::{Activation, Backend, ErrorModel, EstimatorKind, SensorErrors};
use file::{AxisFile, SyntheticFile};
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

/// Start samples of the windows of a trajectory of `len` samples: every `stride`
/// samples, as long as a whole window fits.
pub fn window_starts(len: usize, window: usize, stride: usize) -> impl Iterator<Item = usize> {
    (0..)
        .map(move |i| i * stride)
        .take_while(move |start| start + window <= len)
}

/// How many windows [`window_starts`] gives, counted without walking them.
pub fn window_count(len: usize, window: usize, stride: usize) -> usize {
    match len.checked_sub(window) {
        Some(room) if stride > 0 => room / stride + 1,
        _ => 0,
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

/// A key path such as `data.trajectories[2].samples`, and what is wrong there.
type Fault = (String, String);

/// Collects faults while checking, keyed by their path in the spec.
#[derive(Default)]
struct Faults(Vec<Fault>);

impl Faults {
    fn add(&mut self, key: impl Into<String>, message: impl Into<String>) {
        self.0.push((key.into(), message.into()));
    }
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
        let (rate, sources) = (data.rate, &data.trajectories);
        let (beam_pitch_deg, gnss_noise_m_s) = check_sensors(sensors, &mut faults);
        let grid = check_grid(grid, &mut faults);
        let (dataset, window) = check_dataset(dataset, sources, rate, &mut faults);
        let dvls = check_dvls(&dvl, &mut faults);
        let calibration = check_calibration(calibration, sources, rate, &mut faults);
        let evaluation = check_evaluation(evaluation, sources, &mut faults);
        let (kinds, error_models) = check_estimators(estimators, &mut faults);
        if kinds.contains(&EstimatorKind::Dcnet) {
            check_dcnet_windows(window, &calibration.window_sizes, rate, &mut faults);
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
            model,
            training,
            report,
            resolved,
        })
    }
}

/// The `[data]` section, checked.
struct Data {
    sample_rate_hz: f64,
    /// The rate seconds are counted in samples with: 1 Hz when `sample_rate_hz` is
    /// outside its range, so that the other checks still run.
    rate: f64,
    ground_truth_window_samples: usize,
    synthetic: SyntheticFile,
    trajectories: Vec<TrajectorySource>,
}

/// Checks `[data]`: the sample rate, the ground truth's window, the synthetic
/// generator and every trajectory; `resolved` gets the trajectories' absolute paths.
fn check_data(
    data: file::DataFile,
    spec_dir: &Path,
    resolved: &mut [file::TrajectoryFile],
    faults: &mut Faults,
) -> Data {
    let file::DataFile {
        sample_rate_hz,
        ground_truth_window_samples,
        synthetic,
        trajectories,
    } = data;
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        faults.add(
            "data.sample_rate_hz",
            format!("{sample_rate_hz} must be a positive number"),
        );
    }
    let rate = if sample_rate_hz > 0.0 && sample_rate_hz <= ranges::SAMPLE_RATE_HZ.max {
        sample_rate_hz
    } else {
        1.0
    };
    ranges::SAMPLE_RATE_HZ.check("data.sample_rate_hz", sample_rate_hz, faults);
    if ground_truth_window_samples == 0 {
        faults.add("data.ground_truth_window_samples", "0 must be at least 1");
    }
    let ground_truth_s = ground_truth_window_samples as f64 / rate;
    if let Some(why) = ranges::GROUND_TRUTH_WINDOW_S.exceeded(ground_truth_s) {
        faults.add(
            "data.ground_truth_window_samples",
            format!("{ground_truth_window_samples} samples at {rate} Hz: {why}"),
        );
    }
    check_synthetic(&synthetic, faults);
    let trajectories = check_trajectories(&trajectories, spec_dir, rate, resolved, faults);
    Data {
        sample_rate_hz,
        rate,
        ground_truth_window_samples,
        synthetic,
        trajectories,
    }
}

/// Checks `data.trajectories`: at least one, each named once and with one origin.
fn check_trajectories(
    trajectories: &[file::TrajectoryFile],
    spec_dir: &Path,
    rate: f64,
    resolved: &mut [file::TrajectoryFile],
    faults: &mut Faults,
) -> Vec<TrajectorySource> {
    let mut sources: Vec<TrajectorySource> = Vec::new();
    if trajectories.is_empty() {
        faults.add("data.trajectories", "no trajectory is defined");
    }
    for (i, trajectory) in trajectories.iter().enumerate() {
        let key = format!("data.trajectories[{i}]");
        let name = &trajectory.name;
        if sources.iter().any(|s| &s.name == name) {
            faults.add(format!("{key}.name"), format!("{name:?} is defined twice"));
        }
        let origin = check_origin(&key, trajectory, spec_dir, rate, &mut resolved[i], faults);
        // A trajectory whose origin is at fault stands in as a file of unknown length,
        // so that the checks of the windows cut from it add no faults of their own.
        let origin = origin.unwrap_or(Origin::File {
            path: PathBuf::new(),
            format: FileFormat::Npy,
            samples: None,
        });
        sources.push(TrajectorySource {
            name: name.clone(),
            origin,
        });
    }
    sources
}

/// Where one trajectory's samples come from: a file, or the synthetic generator (its
/// name is checked by [`check_trajectories`]).
fn check_origin(
    key: &str,
    trajectory: &file::TrajectoryFile,
    spec_dir: &Path,
    rate: f64,
    resolved: &mut file::TrajectoryFile,
    faults: &mut Faults,
) -> Option<Origin> {
    let file::TrajectoryFile {
        name: _,
        file,
        samples,
        columns,
        synthetic_duration_s,
    } = trajectory;
    match (file, synthetic_duration_s) {
        (Some(file), None) => Some(check_file_trajectory(
            key,
            spec_dir.join(file),
            *samples,
            columns,
            resolved,
            faults,
        )),
        (None, Some(duration_s)) => {
            check_synthetic_trajectory(key, *duration_s, samples, columns, rate, faults)
        }
        (Some(_), Some(_)) => {
            faults.add(
                format!("{key}.file"),
                "give either file (with samples) or synthetic_duration_s, not both",
            );
            None
        }
        (None, None) => {
            faults.add(
                key,
                "needs either file (with samples) or synthetic_duration_s",
            );
            None
        }
    }
}

/// A trajectory read from the file at `path`: it exists, its sample range is not
/// empty, and a `.csv` names its columns; `resolved` gets the path and the columns.
fn check_file_trajectory(
    key: &str,
    path: PathBuf,
    samples: Option<[usize; 2]>,
    columns: &Option<[String; 3]>,
    resolved: &mut file::TrajectoryFile,
    faults: &mut Faults,
) -> Origin {
    resolved.file = Some(path.clone());
    if path.is_dir() {
        faults.add(
            format!("{key}.file"),
            format!(
                "{} is a folder: name the recording file in it",
                path.display()
            ),
        );
    } else if !path.is_file() {
        faults.add(
            format!("{key}.file"),
            format!(
                "{} does not exist{}",
                path.display(),
                recordings::hint_for(&path)
            ),
        );
    }
    if let Some([start, end]) = samples
        && start >= end
    {
        faults.add(
            format!("{key}.samples"),
            format!("[{start}, {end}] is empty: start must be below end"),
        );
    }
    let is_csv = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let format = match (is_csv, columns) {
        (true, columns) => {
            let columns = columns
                .clone()
                .unwrap_or_else(|| crate::VELOCITY_COLUMNS.map(String::from));
            check_columns(&format!("{key}.columns"), &columns, faults);
            resolved.columns = Some(columns.clone());
            FileFormat::Csv { columns }
        }
        (false, Some(_)) => {
            faults.add(
                format!("{key}.columns"),
                format!("is for .csv files; {} is read as .npy", path.display()),
            );
            FileFormat::Npy
        }
        (false, None) => FileFormat::Npy,
    };
    Origin::File {
        path,
        format,
        samples,
    }
}

/// A synthetic trajectory of `duration_s`: a positive whole number of samples, and no
/// keys that only a file takes.
fn check_synthetic_trajectory(
    key: &str,
    duration_s: f64,
    samples: &Option<[usize; 2]>,
    columns: &Option<[String; 3]>,
    rate: f64,
    faults: &mut Faults,
) -> Option<Origin> {
    if samples.is_some() {
        faults.add(
            format!("{key}.samples"),
            "is for file trajectories; a synthetic one has synthetic_duration_s only",
        );
    }
    if columns.is_some() {
        faults.add(
            format!("{key}.columns"),
            "is for .csv files; a synthetic trajectory has synthetic_duration_s only",
        );
    }
    let key = format!("{key}.synthetic_duration_s");
    if let Some(why) = ranges::TRAJECTORY_S.exceeded(duration_s) {
        faults.add(key, why);
        return None;
    }
    match seconds_to_samples(duration_s, rate) {
        Some(samples) if samples > 0 => Some(Origin::Synthetic { samples }),
        _ => {
            faults.add(
                key,
                format!("{duration_s} must be a positive whole number of samples"),
            );
            None
        }
    }
}

/// The index of the trajectory named `wanted`; a fault at `key` when none is.
fn lookup(
    sources: &[TrajectorySource],
    key: &str,
    wanted: &str,
    faults: &mut Faults,
) -> Option<usize> {
    let found = sources.iter().position(|s| s.name == wanted);
    if found.is_none() {
        let known: Vec<&str> = sources.iter().map(|s| s.name.as_str()).collect();
        let known = if known.is_empty() {
            "none".to_string()
        } else {
            known.join(", ")
        };
        faults.add(
            key,
            format!("unknown trajectory {wanted:?}; data.trajectories defines {known}"),
        );
    }
    found
}

/// Checks `[sensors]`; returns the beam pitch in degrees and the GNSS noise in m/s.
fn check_sensors(sensors: file::SensorsFile, faults: &mut Faults) -> (f64, f64) {
    let file::SensorsFile {
        beam_pitch_deg,
        gnss_noise_cm_s,
    } = sensors;
    if !(beam_pitch_deg > 0.0 && beam_pitch_deg < 90.0) {
        faults.add(
            "sensors.beam_pitch_deg",
            format!("{beam_pitch_deg} must lie strictly between 0 and 90"),
        );
    }
    non_negative("sensors.gnss_noise_cm_s", gnss_noise_cm_s, faults);
    ranges::VELOCITY_ERROR_CM_S.check("sensors.gnss_noise_cm_s", gnss_noise_cm_s, faults);
    (beam_pitch_deg, gnss_noise_cm_s / 100.0)
}

/// Checks `[grid]`: each axis expanded, error terms in their ranges, and not too many
/// combinations.
fn check_grid(grid: file::GridFile, faults: &mut Faults) -> Grid {
    let file::GridFile {
        scale_pct,
        bias_cm_s,
        noise_cm_s,
    } = grid;
    let grid = Grid {
        scale_pct: expand_axis("grid.scale_pct", &scale_pct, faults),
        bias_cm_s: expand_axis("grid.bias_cm_s", &bias_cm_s, faults),
        noise_cm_s: expand_axis("grid.noise_cm_s", &noise_cm_s, faults),
    };
    // Values that are not finite numbers are reported by `expand_axis`.
    let finite = |values: &[f64]| -> Vec<(usize, f64)> {
        values
            .iter()
            .copied()
            .enumerate()
            .filter(|(_, v)| v.is_finite())
            .collect()
    };
    for (i, value) in finite(&grid.scale_pct) {
        check_scale(&format!("grid.scale_pct[{i}]"), value, faults);
    }
    for (i, value) in finite(&grid.bias_cm_s) {
        ranges::VELOCITY_ERROR_CM_S.check(&format!("grid.bias_cm_s[{i}]"), value.abs(), faults);
    }
    for (i, value) in finite(&grid.noise_cm_s) {
        check_noise(&format!("grid.noise_cm_s[{i}]"), value, faults);
    }
    let combinations = grid.scale_pct.len() * grid.bias_cm_s.len() * grid.noise_cm_s.len();
    ranges::GRID_COMBINATIONS.check("grid", combinations as f64, faults);
    grid
}

/// DCNet's input window: as written, in seconds, and in samples when that is good.
#[derive(Clone, Copy)]
struct Window {
    seconds: f64,
    samples: Option<usize>,
}

/// Checks `[dataset]`: window, stride and validation share, and training trajectories
/// that each hold one window.
fn check_dataset(
    dataset: file::DatasetFile,
    sources: &[TrajectorySource],
    rate: f64,
    faults: &mut Faults,
) -> (DatasetSpec, Window) {
    let file::DatasetFile {
        trajectories: names,
        window_s,
        stride_s,
        validation_fraction,
        published_windows,
    } = dataset;
    let window = match ranges::DCNET_WINDOW_S.exceeded(window_s) {
        Some(why) => {
            faults.add("dataset.window_s", why);
            None
        }
        None => positive_samples("dataset.window_s", window_s, rate, faults),
    };
    let stride = positive_samples("dataset.stride_s", stride_s, rate, faults);
    if names.is_empty() {
        faults.add(
            "dataset.trajectories",
            "is empty: name at least one training trajectory",
        );
    }
    let mut trajectories = Vec::new();
    for (i, wanted) in names.iter().enumerate() {
        let key = format!("dataset.trajectories[{i}]");
        if names[..i].contains(wanted) {
            faults.add(key, format!("{wanted:?} is listed twice"));
            continue;
        }
        if let Some(index) = lookup(sources, &key, wanted, faults) {
            if let (Some(len), Some(window)) = (sources[index].known_len(), window)
                && len < window
            {
                faults.add(
                    key,
                    format!("{wanted} has {len} samples, fewer than one window of {window_s} s"),
                );
            }
            trajectories.push(index);
        }
    }
    let valid_fraction = validation_fraction > 0.0 && validation_fraction < 1.0;
    if !valid_fraction {
        faults.add(
            "dataset.validation_fraction",
            format!(
                "{validation_fraction} must be above 0 and below 1: training keeps the epoch with the best validation loss"
            ),
        );
    }
    let dataset = DatasetSpec {
        trajectories,
        window_samples: window.unwrap_or_default(),
        stride_samples: stride.unwrap_or_default(),
        validation_fraction,
        published_windows,
    };
    if valid_fraction && window.is_some() && stride.is_some() {
        check_split(&dataset, sources, faults);
    }
    let window = Window {
        seconds: window_s,
        samples: window,
    };
    (dataset, window)
}

/// Where the training trajectories' lengths are known, checks that
/// `validation_fraction` leaves each grid combination at least one validation window
/// and at least one training window.
fn check_split(dataset: &DatasetSpec, sources: &[TrajectorySource], faults: &mut Faults) {
    let lengths: Option<Vec<usize>> = dataset
        .trajectories
        .iter()
        .map(|&t| sources[t].known_len())
        .collect();
    let Some(lengths) = lengths else { return };
    let windows = dataset.windows_per_combination(lengths);
    let validation = dataset.validation_windows(windows);
    if windows > 0 && (validation == 0 || validation == windows) {
        faults.add(
            "dataset.validation_fraction",
            format!(
                "{} of {windows} windows per combination leaves {validation} for validation and {} for training: each needs at least one",
                dataset.validation_fraction,
                windows - validation
            ),
        );
    }
}

/// Checks `[[dvl]]`: at least one, each named once, with error terms in range.
fn check_dvls(units: &[file::DvlFile], faults: &mut Faults) -> Vec<Dvl> {
    if units.is_empty() {
        faults.add("dvl", "no DVL under test is defined");
    }
    let mut dvls: Vec<Dvl> = Vec::new();
    for (i, unit) in units.iter().enumerate() {
        let file::DvlFile {
            name,
            scale_pct,
            bias_cm_s,
            noise_cm_s,
        } = unit;
        let key = format!("dvl[{i}]");
        if dvls.iter().any(|d| &d.name == name) {
            faults.add(format!("{key}.name"), format!("{name:?} is defined twice"));
        }
        check_scale(&format!("{key}.scale_pct"), *scale_pct, faults);
        if !bias_cm_s.is_finite() {
            faults.add(
                format!("{key}.bias_cm_s"),
                format!("{bias_cm_s} must be a finite number"),
            );
        }
        ranges::VELOCITY_ERROR_CM_S.check(&format!("{key}.bias_cm_s"), bias_cm_s.abs(), faults);
        check_noise(&format!("{key}.noise_cm_s"), *noise_cm_s, faults);
        dvls.push(Dvl {
            name: name.clone(),
            errors: SensorErrors::from_spec_units(*scale_pct, *bias_cm_s, *noise_cm_s),
        });
    }
    dvls
}

/// Checks `[calibration]`: its trajectory, window sizes that each leave samples to
/// evaluate on, and at least one Monte Carlo run.
fn check_calibration(
    calibration: file::CalibrationFile,
    sources: &[TrajectorySource],
    rate: f64,
    faults: &mut Faults,
) -> CalibrationSpec {
    let file::CalibrationFile {
        trajectory,
        window_sizes_s,
        monte_carlo_runs,
    } = calibration;
    let index = lookup(sources, "calibration.trajectory", &trajectory, faults);
    let segment = index.and_then(|i| sources[i].known_len());
    if window_sizes_s.is_empty() {
        faults.add(
            "calibration.window_sizes_s",
            "is empty: give at least one window size",
        );
    }
    let mut window_sizes = Vec::new();
    let mut first_of_size: Vec<(usize, usize)> = Vec::new();
    for (i, &size_s) in window_sizes_s.iter().enumerate() {
        let key = format!("calibration.window_sizes_s[{i}]");
        if let Some(size) = positive_samples(&key, size_s, rate, faults) {
            if let Some(&(first, _)) = first_of_size.iter().find(|&&(_, s)| s == size) {
                faults.add(
                    key,
                    format!("{size_s} s is calibration.window_sizes_s[{first}] again: each window size is calibrated once"),
                );
                continue;
            }
            first_of_size.push((i, size));
            match segment {
                Some(len) if size >= len => faults.add(
                    key,
                    format!("{size_s} s is not shorter than {trajectory} ({} s): no samples would be left to evaluate on", len as f64 / rate),
                ),
                _ => window_sizes.push(size),
            }
        }
    }
    if monte_carlo_runs == 0 {
        faults.add("calibration.monte_carlo_runs", "0 must be at least 1");
    }
    ranges::MONTE_CARLO_RUNS.check(
        "calibration.monte_carlo_runs",
        monte_carlo_runs as f64,
        faults,
    );
    CalibrationSpec {
        trajectory: index.unwrap_or_default(),
        window_sizes,
        monte_carlo_runs,
    }
}

/// Checks `[evaluation]`: at least one test trajectory, each defined.
fn check_evaluation(
    evaluation: file::EvaluationFile,
    sources: &[TrajectorySource],
    faults: &mut Faults,
) -> Vec<usize> {
    let file::EvaluationFile { trajectories } = evaluation;
    if trajectories.is_empty() {
        faults.add(
            "evaluation.trajectories",
            "is empty: name at least one test trajectory",
        );
    }
    trajectories
        .iter()
        .enumerate()
        .filter_map(|(i, wanted)| {
            let key = format!("evaluation.trajectories[{i}]");
            if trajectories[..i].contains(wanted) {
                faults.add(key, format!("{wanted:?} is listed twice"));
                return None;
            }
            lookup(sources, &key, wanted, faults)
        })
        .collect()
}

/// Checks `[estimators]`: kinds and error models known, each listed once.
fn check_estimators(
    estimators: file::EstimatorsFile,
    faults: &mut Faults,
) -> (Vec<EstimatorKind>, Vec<ErrorModel>) {
    let file::EstimatorsFile {
        kinds,
        error_models,
    } = estimators;
    let names = kinds;
    let mut kinds = parse_names("estimators.kinds", &names, faults);
    // Two kinds that a spec does not list: the tables always have them, or have them
    // whenever they apply.
    for (kind, why) in [
        (
            EstimatorKind::Bound,
            "the bound is no method to list: it is computed for every DVL",
        ),
        (
            EstimatorKind::DcnetEnsemble,
            "\"dcnet_ensemble\" is not listed: it runs beside \"dcnet\" when training.replicates is above 1",
        ),
    ] {
        if let Some(i) = names.iter().position(|name| *name == kind.to_string()) {
            faults.add(format!("estimators.kinds[{i}]"), why);
        }
    }
    kinds.retain(|k| !matches!(k, EstimatorKind::Bound | EstimatorKind::DcnetEnsemble));
    let error_models = parse_names("estimators.error_models", &error_models, faults);
    (kinds, error_models)
}

/// With DCNet among the estimators: every calibration window holds one DCNet window.
fn check_dcnet_windows(window: Window, window_sizes: &[usize], rate: f64, faults: &mut Faults) {
    let Some(samples) = window.samples else {
        return;
    };
    for (i, &size) in window_sizes.iter().enumerate() {
        if size < samples {
            faults.add(
                format!("calibration.window_sizes_s[{i}]"),
                format!(
                    "{} s is shorter than one DCNet window (dataset.window_s = {} s)",
                    size as f64 / rate,
                    window.seconds
                ),
            );
        }
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

/// Checks `[report]`: the published values read, a tolerance not negative, and none or
/// two defined trajectories to draw the velocity of; `resolved` gets the absolute path.
fn check_report(
    report: file::ReportFile,
    spec_dir: &Path,
    sources: &[TrajectorySource],
    resolved: &mut SpecFile,
    faults: &mut Faults,
) -> ReportSpec {
    let file::ReportFile {
        published,
        tolerance_pct,
        velocity_trajectories,
    } = report;
    let published = published.and_then(|file| {
        let path = spec_dir.join(file);
        resolved.report.published = Some(path.clone());
        Published::read(&path)
            .map_err(|errors| faults.add("report.published", errors.to_string()))
            .ok()
    });
    if !(tolerance_pct.is_finite() && tolerance_pct >= 0.0) {
        faults.add(
            "report.tolerance_pct",
            format!("{tolerance_pct} must be zero or positive"),
        );
    }
    if !matches!(velocity_trajectories.len(), 0 | 2) {
        faults.add(
            "report.velocity_trajectories",
            format!(
                "has {} names: give two (a training and a test trajectory), or none",
                velocity_trajectories.len()
            ),
        );
    }
    for (i, wanted) in velocity_trajectories.iter().enumerate() {
        lookup(
            sources,
            &format!("report.velocity_trajectories[{i}]"),
            wanted,
            faults,
        );
    }
    ReportSpec {
        published,
        tolerance_pct,
        velocity_trajectories,
    }
}

/// Whether `name` can name a results folder: letters, digits, '-', '_', '.', and for
/// the points of a sweep (`<name>/<point>`) '/', '=' and ','; no part empty, longer
/// than [`MAX_NAME_CHARS`] or starting with '.' (`.`, `..`, and the `.cache` beside the
/// results).
fn is_folder_name(name: &str) -> bool {
    name.split('/').all(|part| {
        !part.is_empty()
            && !part.starts_with('.')
            && part.len() <= MAX_NAME_CHARS
            && part
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_.=,".contains(c))
    })
}

/// `seconds × rate` as a whole number of samples, if it is one.
pub fn seconds_to_samples(seconds: f64, rate_hz: f64) -> Option<usize> {
    let samples = seconds * rate_hz;
    let rounded = samples.round();
    (samples.is_finite() && rounded >= 0.0 && (samples - rounded).abs() < 1e-6)
        .then_some(rounded as usize)
}

fn positive_samples(key: &str, seconds: f64, rate: f64, faults: &mut Faults) -> Option<usize> {
    match seconds_to_samples(seconds, rate) {
        Some(samples) if samples > 0 => Some(samples),
        _ => {
            faults.add(
                key,
                format!("{seconds} must be a positive whole number of samples at {rate} Hz"),
            );
            None
        }
    }
}

/// The three velocity columns of a `.csv` file: named, and each once.
fn check_columns(key: &str, columns: &[String; 3], faults: &mut Faults) {
    for (i, column) in columns.iter().enumerate() {
        if column.trim().is_empty() {
            faults.add(
                format!("{key}[{i}]"),
                "is empty: name a column of the header",
            );
        } else if columns[..i].contains(column) {
            faults.add(
                format!("{key}[{i}]"),
                format!("{column:?} is named twice: x, y and z need a column each"),
            );
        }
    }
}

/// A scale factor error: above -100 % (the DVL still measures) and within its range.
fn check_scale(key: &str, value: f64, faults: &mut Faults) {
    if !(value.is_finite() && value > -100.0) {
        faults.add(key, format!("{value} must be above -100 %"));
    }
    ranges::SCALE_PCT.check(key, value, faults);
}

/// A velocity noise: zero or positive and within its range.
fn check_noise(key: &str, value: f64, faults: &mut Faults) {
    non_negative(key, value, faults);
    ranges::VELOCITY_ERROR_CM_S.check(key, value, faults);
}

fn non_negative(key: &str, value: f64, faults: &mut Faults) {
    if !(value.is_finite() && value >= 0.0) {
        faults.add(key, format!("{value} must be zero or positive"));
    }
}

/// Checks `[model]`: sizes of at least 1 that fit the window, a known activation, a
/// dropout below 1.
fn check_model(model: file::ModelFile, window: Option<usize>, faults: &mut Faults) -> ModelSpec {
    let file::ModelFile {
        conv_channels,
        conv1d_kernel_size,
        fc_widths,
        activation,
        leaky_relu_slope,
        dropout,
    } = model;
    if conv_channels == 0 {
        faults.add("model.conv_channels", "0 must be at least 1");
    }
    ranges::CONV_CHANNELS.check("model.conv_channels", conv_channels as f64, faults);
    match window {
        Some(window) if conv1d_kernel_size == 0 || 2 * (conv1d_kernel_size - 1) >= window => faults.add(
            "model.conv1d_kernel_size",
            format!("{conv1d_kernel_size} must be at least 1 and leave the two Conv1d an output of a window of {window} samples"),
        ),
        Some(window) if window < 4 => faults.add("dataset.window_s", format!("{window} samples are too few for the 2D head (at least 4)")),
        _ => {}
    }
    for (i, width) in fc_widths.iter().enumerate() {
        if *width == 0 {
            faults.add(format!("model.fc_widths[{i}]"), "0 must be at least 1");
        }
        ranges::FC_WIDTH.check(&format!("model.fc_widths[{i}]"), *width as f64, faults);
    }
    let activation = activation.parse().unwrap_or_else(|message: String| {
        faults.add("model.activation", message);
        Activation::Tanh
    });
    non_negative("model.leaky_relu_slope", leaky_relu_slope, faults);
    if !(0.0..1.0).contains(&dropout) {
        faults.add(
            "model.dropout",
            format!("{dropout} must be at least 0 and below 1"),
        );
    }
    ModelSpec {
        conv_channels,
        conv1d_kernel_size,
        fc_widths,
        activation,
        leaky_relu_slope,
        dropout,
    }
}

/// Checks `[training]`: a known backend, counts of at least 1, RMSProp's settings in
/// range, and the learning rates and early stopping.
fn check_training(training: file::TrainingFile, faults: &mut Faults) -> TrainingSpec {
    let file::TrainingFile {
        backend,
        epochs,
        batch_size,
        learning_rate,
        rmsprop_alpha,
        rmsprop_epsilon,
        checkpoint_every_epochs,
        early_stopping,
        replicates,
    } = training;
    let backend = backend.parse().unwrap_or_else(|message: String| {
        faults.add("training.backend", message);
        Backend::Flex
    });
    for (key, value) in [
        ("training.epochs", epochs),
        ("training.batch_size", batch_size),
        ("training.checkpoint_every_epochs", checkpoint_every_epochs),
        ("training.replicates", replicates),
    ] {
        if value == 0 {
            faults.add(key, "0 must be at least 1");
        }
    }
    ranges::EPOCHS.check("training.epochs", epochs as f64, faults);
    ranges::BATCH_SIZE.check("training.batch_size", batch_size as f64, faults);
    ranges::REPLICATES.check("training.replicates", replicates as f64, faults);
    let learning_rates = check_learning_rates(learning_rate, faults);
    if !(rmsprop_alpha > 0.0 && rmsprop_alpha < 1.0) {
        faults.add(
            "training.rmsprop_alpha",
            format!("{rmsprop_alpha} must lie strictly between 0 and 1"),
        );
    }
    if !(rmsprop_epsilon.is_finite() && rmsprop_epsilon > 0.0) {
        faults.add(
            "training.rmsprop_epsilon",
            format!("{rmsprop_epsilon} must be a positive number"),
        );
    }
    let early_stopping = early_stopping.map(|file| check_early_stopping(file, faults));
    TrainingSpec {
        backend,
        epochs,
        batch_size,
        learning_rates,
        rmsprop_alpha,
        rmsprop_epsilon,
        checkpoint_every_epochs,
        early_stopping,
        replicates,
    }
}

/// Checks `training.learning_rate`: a positive number per error model, in
/// `ErrorModel` order.
fn check_learning_rates(learning_rate: file::LearningRatesFile, faults: &mut Faults) -> [f64; 5] {
    let file::LearningRatesFile {
        em1,
        em2,
        em3,
        em4,
        em5,
    } = learning_rate;
    let learning_rates = [em1, em2, em3, em4, em5];
    for (model, rate) in ErrorModel::ALL.iter().zip(learning_rates) {
        let key = format!("training.learning_rate.{model}");
        if !(rate.is_finite() && rate > 0.0) {
            faults.add(&key, format!("{rate} must be a positive number"));
        }
    }
    learning_rates
}

/// Checks `[training.early_stopping]`: a patience of at least 1 epoch, an improvement
/// not negative.
fn check_early_stopping(
    early_stopping: file::EarlyStoppingFile,
    faults: &mut Faults,
) -> EarlyStopping {
    let file::EarlyStoppingFile {
        patience_epochs,
        min_improvement,
    } = early_stopping;
    if patience_epochs == 0 {
        faults.add(
            "training.early_stopping.patience_epochs",
            "0 must be at least 1",
        );
    }
    if !(min_improvement.is_finite() && min_improvement >= 0.0) {
        faults.add(
            "training.early_stopping.min_improvement",
            format!("{min_improvement} must be 0 or more (cm/s)²"),
        );
    }
    EarlyStopping {
        patience: patience_epochs,
        min_improvement,
    }
}

/// Checks `[data.synthetic]`: ranges of positive numbers, amounts not negative, each
/// within what an AUV does.
fn check_synthetic(synthetic: &SyntheticFile, faults: &mut Faults) {
    let SyntheticFile {
        speed_m_s,
        leg_duration_s,
        turn_rate_deg_s,
        heave_amplitude_m_s,
        surface_s,
        recording_noise_cm_s,
    } = synthetic;
    for (key, [low, high]) in [
        ("data.synthetic.speed_m_s", speed_m_s),
        ("data.synthetic.leg_duration_s", leg_duration_s),
    ] {
        if !(low.is_finite() && high.is_finite() && *low > 0.0 && low <= high) {
            faults.add(
                key,
                format!("[{low}, {high}] must be a range of positive numbers, low first"),
            );
        }
    }
    for (key, value, limit) in [
        (
            "data.synthetic.speed_m_s[1]",
            speed_m_s[1],
            ranges::SPEED_M_S,
        ),
        (
            "data.synthetic.leg_duration_s[1]",
            leg_duration_s[1],
            ranges::TRAJECTORY_S,
        ),
        (
            "data.synthetic.turn_rate_deg_s",
            *turn_rate_deg_s,
            ranges::TURN_RATE_DEG_S,
        ),
        (
            "data.synthetic.heave_amplitude_m_s",
            *heave_amplitude_m_s,
            ranges::SPEED_M_S,
        ),
        ("data.synthetic.surface_s", *surface_s, ranges::TRAJECTORY_S),
        (
            "data.synthetic.recording_noise_cm_s",
            *recording_noise_cm_s,
            ranges::VELOCITY_ERROR_CM_S,
        ),
    ] {
        non_negative(key, value, faults);
        limit.check(key, value, faults);
    }
}

/// Expands `values` or `start`/`stop`/`step` into the list of grid values.
fn expand_axis(key: &str, axis: &AxisFile, faults: &mut Faults) -> Vec<f64> {
    let values = match axis {
        AxisFile {
            values: Some(values),
            start: None,
            stop: None,
            step: None,
        } => values.clone(),
        AxisFile {
            values: None,
            start: Some(start),
            stop: Some(stop),
            step: Some(step),
        } => {
            if !(start.is_finite()
                && stop.is_finite()
                && step.is_finite()
                && *step > 0.0
                && stop >= start)
            {
                faults.add(key, format!("start {start}, stop {stop}, step {step}: step must be positive and stop at least start"));
                return Vec::new();
            }
            let steps = (stop - start) / step;
            // A quotient that overflows to infinity is too many values too.
            let count = (steps.round() + 1.0).min(f64::MAX);
            if let Some(why) = ranges::GRID_AXIS_VALUES.exceeded(count) {
                faults.add(key, why);
                return Vec::new();
            }
            if (steps - steps.round()).abs() > 1e-6 {
                faults.add(
                    key,
                    format!("stop {stop} is not start {start} plus a whole number of steps {step}"),
                );
                return Vec::new();
            }
            // Rounded to 1e-9 so that 0.1 + 2 × 0.1 prints and compares as 0.3.
            (0..=steps.round() as usize)
                .map(|i| ((start + i as f64 * step) * 1e9).round() / 1e9)
                .collect()
        }
        _ => {
            faults.add(
                key,
                "give either values = [...] or all of start, stop and step",
            );
            return Vec::new();
        }
    };
    if values.is_empty() {
        faults.add(
            key,
            "is empty: the grid needs at least one value on every axis",
        );
    }
    if let Some(why) = ranges::GRID_AXIS_VALUES.exceeded(values.len() as f64) {
        faults.add(key, why);
        return Vec::new();
    }
    for (i, value) in values.iter().enumerate() {
        if !value.is_finite() {
            faults.add(
                format!("{key}.values[{i}]"),
                format!("{value} must be a finite number"),
            );
        } else if values[..i].contains(value) {
            faults.add(
                format!("{key}.values[{i}]"),
                format!(
                    "{value} is listed twice: every combination with it would be generated twice"
                ),
            );
        }
    }
    values
}

fn parse_names<T: std::str::FromStr<Err = String> + PartialEq>(
    key: &str,
    names: &[String],
    faults: &mut Faults,
) -> Vec<T> {
    if names.is_empty() {
        faults.add(key, "is empty");
    }
    let mut parsed = Vec::new();
    for (i, name) in names.iter().enumerate() {
        match name.parse::<T>() {
            Ok(value) if parsed.contains(&value) => {
                faults.add(format!("{key}[{i}]"), format!("{name:?} is listed twice"))
            }
            Ok(value) => parsed.push(value),
            Err(message) => faults.add(format!("{key}[{i}]"), message),
        }
    }
    parsed
}

/// experiments/quick.toml with `overrides`, for tests.
#[cfg(test)]
pub(crate) fn quick_spec(overrides: &[&str]) -> Spec {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quick.toml");
    let overrides: Vec<String> = overrides.iter().map(ToString::to_string).collect();
    load(&path, &overrides).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The faults `load` finds in quick.toml with `overrides`, one per line.
    fn faults(overrides: &[&str]) -> String {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quick.toml");
        let overrides: Vec<String> = overrides.iter().map(ToString::to_string).collect();
        load(&path, &overrides).unwrap_err().to_string()
    }

    #[test]
    fn lists_whose_repeats_make_no_sense_are_refused() {
        let error = faults(&["calibration.window_sizes_s=[20, 40, 20.0]"]);
        assert!(
            error.contains(
                "calibration.window_sizes_s[2]: 20 s is calibration.window_sizes_s[0] again"
            ),
            "{error}"
        );
        let error = faults(&["dataset.trajectories=[\"S1\", \"S2\", \"S1\"]"]);
        assert!(
            error.contains("dataset.trajectories[2]: \"S1\" is listed twice"),
            "{error}"
        );
        let error = faults(&["evaluation.trajectories=[\"S3\", \"S3\"]"]);
        assert!(
            error.contains("evaluation.trajectories[1]: \"S3\" is listed twice"),
            "{error}"
        );
        let error = faults(&["grid.scale_pct={values = [0.5, 1.0, 0.5]}"]);
        assert!(
            error.contains("grid.scale_pct.values[2]: 0.5 is listed twice"),
            "{error}"
        );
        let error = faults(&["estimators.kinds=[\"baseline\", \"baseline\"]"]);
        assert!(
            error.contains("estimators.kinds[1]: \"baseline\" is listed twice"),
            "{error}"
        );
    }

    #[test]
    fn values_beyond_their_physical_range_are_refused_at_their_key() {
        for (set, key, why) in [
            (
                "data.sample_rate_hz=5000",
                "data.sample_rate_hz",
                "faster than any DVL",
            ),
            (
                "data.ground_truth_window_samples=100000",
                "data.ground_truth_window_samples",
                "100000 samples at 1 Hz",
            ),
            (
                "data.trajectories[0].synthetic_duration_s=1e12",
                "data.trajectories[0].synthetic_duration_s",
                "30-day AUV mission",
            ),
            (
                "data.synthetic.speed_m_s=[1, 100]",
                "data.synthetic.speed_m_s[1]",
                "faster than an AUV travels",
            ),
            (
                "data.synthetic.turn_rate_deg_s=1000",
                "data.synthetic.turn_rate_deg_s",
                "faster than an AUV turns",
            ),
            (
                "sensors.gnss_noise_cm_s=500",
                "sensors.gnss_noise_cm_s",
                "more than 1 m/s",
            ),
            (
                "grid.bias_cm_s={values = [0.3, -150]}",
                "grid.bias_cm_s[1]",
                "more than 1 m/s",
            ),
            (
                "grid.scale_pct={values = [0.5, 250]}",
                "grid.scale_pct[1]",
                "above 100 %",
            ),
            (
                "grid.noise_cm_s={start = 0.0, stop = 100.0, step = 0.001}",
                "grid.noise_cm_s",
                "100001 values",
            ),
            (
                "grid.noise_cm_s={start = 0.0, stop = 1e308, step = 1e-308}",
                "grid.noise_cm_s",
                "values is above 10000",
            ),
            (
                "dvl[1].noise_cm_s=101",
                "dvl[1].noise_cm_s",
                "more than 1 m/s",
            ),
            (
                "dataset.window_s=1000",
                "dataset.window_s",
                "DCNet's windows",
            ),
            (
                "calibration.monte_carlo_runs=1000000000",
                "calibration.monte_carlo_runs",
                "the paper runs 200",
            ),
            (
                "model.conv_channels=1000000",
                "model.conv_channels",
                "the paper's convolutions",
            ),
            (
                "model.fc_widths=[100000000, 64, 32]",
                "model.fc_widths[0]",
                "the paper's widest layer",
            ),
            (
                "training.epochs=10000000",
                "training.epochs",
                "the paper trains for 100",
            ),
            (
                "training.batch_size=100000000",
                "training.batch_size",
                "hold 256",
            ),
        ] {
            let error = faults(&[set]);
            assert!(
                error.contains(&format!("--set {set}: {key}: ")),
                "{set}: {error}"
            );
            assert!(error.contains(why), "{set}: {error}");
            assert_eq!(
                error.lines().count(),
                1,
                "{set}: one fault, no echoes: {error}"
            );
        }
        let combinations = faults(&[
            "grid.scale_pct={start = 0.1, stop = 100.0, step = 0.1}",
            "grid.bias_cm_s={start = 0.1, stop = 10.0, step = 0.1}",
        ]);
        assert!(
            combinations.contains(": grid: 200000 combinations is above 100000"),
            "{combinations}"
        );
    }

    #[test]
    fn an_integer_beyond_toml_is_placed_at_its_line_and_key() {
        let folder = tempfile::tempdir().unwrap();
        let quick = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quick.toml");
        let text = std::fs::read_to_string(&quick).unwrap().replace(
            "fc_widths = [128, 64, 32]",
            "fc_widths = [128, 18446744073709551616, 32]",
        );
        let path = folder.path().join("huge.toml");
        std::fs::write(&path, &text).unwrap();
        let line = text
            .lines()
            .position(|l| l.starts_with("fc_widths"))
            .unwrap()
            + 1;
        let error = load(&path, &[]).unwrap_err().to_string();
        assert_eq!(
            error,
            format!(
                "{}:{line}: model.fc_widths[1]: 18446744073709551616 is larger than TOML's largest integer, 9223372036854775807",
                path.display()
            )
        );
        let error = faults(&["seed=18446744073709551615"]);
        assert!(
            error.starts_with(
                "--set seed=18446744073709551615: seed: 18446744073709551615 is larger"
            ),
            "{error}"
        );
    }

    #[test]
    fn windows_are_counted_as_they_are_cut() {
        for (len, window, stride) in [
            (0, 10, 9),
            (9, 10, 9),
            (10, 10, 9),
            (165, 10, 9),
            (1000, 7, 3),
        ] {
            let cut = window_starts(len, window, stride).count();
            assert_eq!(
                window_count(len, window, stride),
                cut,
                "{len} {window} {stride}"
            );
        }
        assert_eq!(window_count(usize::MAX, 10, 1), usize::MAX - 9);
    }

    #[test]
    fn training_needs_validation_and_training_windows() {
        let error = faults(&["dataset.validation_fraction=0.0"]);
        assert!(
            error.contains("dataset.validation_fraction: 0 must be above 0 and below 1"),
            "{error}"
        );
        // quick.toml's S1 and S2 give 165 windows per combination.
        let error = faults(&["dataset.validation_fraction=0.001"]);
        assert!(
            error.contains(
                "0.001 of 165 windows per combination leaves 0 for validation and 165 for training"
            ),
            "{error}"
        );
        let error = faults(&["dataset.validation_fraction=0.999"]);
        assert!(
            error.contains("leaves 165 for validation and 0 for training"),
            "{error}"
        );
        assert!(
            load(
                &Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quick.toml"),
                &["dataset.validation_fraction=0.01".to_string()]
            )
            .is_ok()
        );
    }
}
