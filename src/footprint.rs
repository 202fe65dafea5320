//! What a spec asks of this machine, known before anything is allocated: the memory of
//! its trajectories, its training set, the models that train side by side with their
//! batches, and its Monte Carlo rows, each part with the spec key that drives it; and
//! the time its trainings take, from one training batch timed on this machine.
//! `validate` shows both; `validate` and `run` refuse a spec whose memory is beyond
//! this machine's, naming the key of its largest part, and `run` says how long a long
//! training will take. In: a checked spec and its trajectories' lengths. Out: a
//! [`Footprint`].

use crate::dataset::{DatasetSize, TrainingSet};
use crate::evaluate::RunRow;
use crate::evaluate::calibration_time::curve_lengths;
use crate::installation::study::spec::StudySpec;
use crate::model::layer_shapes;
use crate::spec::{Origin, Spec};
use crate::vocab::{ErrorModel, EstimatorKind};
use std::fmt;

/// Bytes a stored float of the network takes.
const FLOAT_BYTES: f64 = 4.0;
/// Copies of a model's weights while it trains: the weights, their gradients, RMSProp's
/// running mean square and the best epoch's weights.
const MODEL_COPIES: f64 = 4.0;
/// A forward pass keeps each layer's input and output for the backward pass, which
/// makes a gradient of each: three floats per value.
const BATCH_COPIES: f64 = 3.0;
/// The validation loss is taken over chunks of at least this many windows.
const VALIDATION_CHUNK: usize = 1024;
/// Copies of the Monte Carlo rows at the end of a run: the rows, their gathered
/// copy and their Arrow columns.
const ROW_COPIES: f64 = 3.0;
/// Heap bytes of a row beyond its own size: its DVL and trajectory names.
const ROW_NAME_BYTES: f64 = 64.0;

/// One part of a spec's memory.
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    pub what: &'static str,
    pub bytes: f64,
    /// The spec key the part grows with.
    pub key: String,
}

/// The memory a spec needs at its peak: every part, as if all were held at once.
#[derive(Debug, Clone, PartialEq)]
pub struct Footprint {
    pub parts: Vec<Part>,
}

impl Footprint {
    /// The parts of `spec` whose trajectories are `lengths` samples long, with
    /// `threads` threads training a model each.
    pub fn of(spec: &Spec, lengths: &[usize], threads: usize) -> Self {
        let mut parts = vec![trajectories(spec, lengths), training_set(spec, lengths)];
        if !spec.trained_models().is_empty() {
            parts.extend(training(spec, threads));
        }
        parts.push(monte_carlo_rows(spec));
        Self { parts }
    }

    pub fn bytes(&self) -> f64 {
        self.parts.iter().map(|p| p.bytes).sum()
    }

    /// The part that needs the most memory.
    pub fn largest(&self) -> &Part {
        self.parts
            .iter()
            .max_by(|a, b| a.bytes.total_cmp(&b.bytes))
            .expect("a footprint has parts")
    }

    /// Why the spec cannot run on a machine of `memory` bytes, when it cannot: the
    /// key to change and the message.
    pub fn refusal(&self, memory: u64) -> Option<(String, String)> {
        if self.bytes() <= memory as f64 {
            return None;
        }
        let largest = self.largest();
        Some((
            largest.key.clone(),
            format!(
                "needs about {} of memory and this machine has {}; most of it, {}, is the {}, which grows with this key",
                Bytes(self.bytes()),
                Bytes(memory as f64),
                Bytes(largest.bytes),
                largest.what
            ),
        ))
    }
}

/// The memory this process may use: the machine's, or its control group's limit when
/// that is lower; under an address-space limit (`ulimit -v`) what that limit leaves once
/// the process's fixed needs are met ([`address_space_left`]) when that is lower.
pub fn machine_memory() -> u64 {
    let mut system = sysinfo::System::new();
    system.refresh_memory();
    let total = system.total_memory();
    let grouped = system
        .cgroup_limits()
        .map_or(total, |limits| total.min(limits.total_memory));
    match crate::memory::address_space_limit() {
        Some(limit) => grouped.min(address_space_left(limit)),
        None => grouped,
    }
}

/// The address space a thread the process has yet to start takes, bytes: its stack
/// (2 MiB, Rust's default) and its guard page, and the allocator's first segment for
/// it (32 MiB, mimalloc's).
const THREAD_ADDRESS_SPACE: u64 = (2 << 20) + 4096 + (32 << 20);

/// The address space the process's own growth takes beyond what its data need, bytes:
/// a new allocator segment where the last is full, mapped aligned (32 MiB, from a
/// mapping of twice that where the system's first does not come back aligned).
const GROWTH_ADDRESS_SPACE: u64 = 2 * (32 << 20);

/// The threads a command may start beyond those it holds when it states its cost: the
/// pool of the matrix products (matrixmultiply's, started at their first large one),
/// which by its own rule takes none on one core, one on two or three, and three on
/// four or more (`MATMUL_NUM_THREADS` where set and not empty, the machine's physical
/// cores otherwise, whatever this process's CPU quota or affinity; the larger of those
/// and the cores this process may use is counted, so the count never errs low).
fn threads_to_start() -> u64 {
    let asked = (std::env::var("MATMUL_NUM_THREADS").ok())
        .filter(|v| !v.is_empty())
        .map(|v| v.parse::<usize>().unwrap_or(1));
    let usable = std::thread::available_parallelism().map_or(1, |n| n.get());
    let cores = asked.unwrap_or_else(|| num_cpus::get_physical().max(usable));
    match cores {
        0 | 1 => 0,
        2 | 3 => 1,
        _ => 3,
    }
}

/// What the address-space `limit` leaves to a command's data, bytes: the limit less
/// the address space the process holds now (its code and libraries, its stacks, the
/// rayon pool started, the allocator's segments), the threads it may yet start and its
/// allocator's growth. The allocator reserves no arena ahead under a limit
/// ([`crate::memory::reserve_no_arena_under_an_address_limit`]), so what is held is
/// what is used. Reading it starts rayon's pool, so that its threads are counted held.
fn address_space_left(limit: u64) -> u64 {
    let _ = rayon::current_num_threads();
    limit
        .saturating_sub(address_space_held())
        .saturating_sub(threads_to_start() * THREAD_ADDRESS_SPACE + GROWTH_ADDRESS_SPACE)
}

/// The address space this process holds, bytes (the first field of Linux's
/// `/proc/self/statm`, in pages); 0 where it cannot be read.
fn address_space_held() -> u64 {
    let pages = std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|statm| statm.split_whitespace().next()?.parse::<u64>().ok());
    // SAFETY: sysconf only reads a configuration value.
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
    pages.map_or(0, |pages| pages * page.max(0) as u64)
}

/// The memory of an installation study's `[learned]` training at its peak, for
/// trajectories of `lengths` samples with `threads` models training side by side: the
/// installations of its simulated grid, and the windows of the sets that train together
/// (each counted as every trajectory's windows under every installation, an upper bound
/// since a fold's set leaves its own trajectories out, and twice, while a set is put
/// together from its parts). `None` without `[learned]`.
pub fn learned(spec: &StudySpec, lengths: &[usize], threads: usize) -> Option<Footprint> {
    use crate::installation::learned::simulate::{INPUT_ROWS, REFERENCE_MARGIN, TARGET_ROWS};
    use crate::installation::learned::spec::TrainingSource;
    let learned = spec.learned.as_ref()?;
    let grid = &learned.simulation;
    let lists = [
        ("lever_arm_x_m", grid.lever_arm_x_m.len()),
        ("lever_arm_y_m", grid.lever_arm_y_m.len()),
        ("lever_arm_z_m", grid.lever_arm_z_m.len()),
        ("time_offset_s", grid.time_offset_s.len()),
        ("misalignment_z_deg", grid.misalignment_z_deg.len()),
        ("scale_pct", grid.scale_pct.len()),
        ("bias_cm_s", grid.bias_cm_s.len()),
    ];
    let installations: f64 = lists.iter().map(|&(_, n)| n as f64).product();
    let longest_list = lists.iter().max_by_key(|&&(_, n)| n).expect("lists").0;
    let key = format!("learned.simulation.{longest_list}");
    let (window, stride) = (learned.window_samples, learned.stride_samples.max(1));
    let span = window + 2 * REFERENCE_MARGIN;
    let windows: f64 = lengths
        .iter()
        .map(|&len| {
            if len < span {
                0.0
            } else {
                ((len - span) / stride + 1) as f64
            }
        })
        .sum();
    let window_bytes = FLOAT_BYTES * (INPUT_ROWS * window + TARGET_ROWS * span) as f64
        + (std::mem::size_of::<String>() + std::mem::size_of::<usize>() + 1) as f64
        + ROW_NAME_BYTES;
    let simulated = learned.sources.contains(&TrainingSource::Simulated);
    let per_set = if simulated { installations } else { 1.0 };
    let replicates = learned.training.replicates.max(1);
    let sets_together = threads.div_ceil(replicates).clamp(1, learned.folds.max(1)) as f64;
    let mut parts = vec![Part {
        what: "training windows of the sets that train together",
        bytes: 2.0 * sets_together * per_set * windows * window_bytes,
        key: if simulated {
            key.clone()
        } else {
            "learned.stride_samples".into()
        },
    }];
    if simulated {
        parts.push(Part {
            what: "simulated installations",
            bytes: installations
                * std::mem::size_of::<crate::installation::terms::Installation>() as f64,
            key,
        });
    }
    Some(Footprint { parts })
}

/// The recorded velocities and their ground truth, for every trajectory.
fn trajectories(spec: &Spec, lengths: &[usize]) -> Part {
    let samples: f64 = lengths.iter().map(|&len| len as f64).sum();
    let longest = (0..lengths.len()).max_by_key(|&i| lengths[i]).unwrap_or(0);
    let key = match spec.trajectories.get(longest).map(|t| &t.origin) {
        Some(Origin::File { .. }) => format!("data.trajectories[{longest}].file"),
        _ => format!("data.trajectories[{longest}].synthetic_duration_s"),
    };
    Part {
        what: "trajectories",
        bytes: samples * 2.0 * std::mem::size_of::<crate::Vec3>() as f64,
        key,
    }
}

/// Every window of every grid combination, as [`TrainingSet`] holds them.
fn training_set(spec: &Spec, lengths: &[usize]) -> Part {
    let size = DatasetSize::from_lengths(spec, lengths);
    let windows = size.combinations as f64 * size.per_combination as f64;
    Part {
        what: "training set",
        bytes: TrainingSet::size_bytes(windows, spec.dataset.window_samples as f64),
        key: "grid".into(),
    }
}

/// The models of every error model and replicate, which train side by side, and the batches that
/// `threads` of them run at once.
fn training(spec: &Spec, threads: usize) -> [Part; 2] {
    let window = spec.dataset.window_samples;
    let shapes = layer_shapes(&spec.model, ErrorModel::Em5, window);
    let parameters: f64 = shapes.iter().map(|s| s.parameters() as f64).sum();
    let per_window: f64 = shapes
        .iter()
        .map(|s| (s.inputs + s.outputs) as f64 * s.positions as f64)
        .sum();
    let models = spec.model_count() as f64;
    let biggest = (0..shapes.len())
        .max_by_key(|&i| shapes[i].parameters())
        .unwrap_or(0);
    let widths = spec.model.fc_widths;
    let width_key = match biggest {
        // The first dense layer reads the convolutions' flattened output.
        5 if widths[0] < spec.model.conv_channels => "model.conv_channels".to_string(),
        5 => "model.fc_widths[0]".to_string(),
        6 | 7 => {
            let (a, b) = (biggest - 6, biggest - 5);
            format!(
                "model.fc_widths[{}]",
                if widths[a] >= widths[b] { a } else { b }
            )
        }
        8 => "model.fc_widths[2]".to_string(),
        _ => "model.conv_channels".to_string(),
    };
    let running = threads.clamp(1, spec.model_count()) as f64;
    let batch = spec.training.batch_size.max(VALIDATION_CHUNK) as f64;
    [
        Part {
            what: "models in training",
            bytes: models * parameters * MODEL_COPIES * FLOAT_BYTES,
            key: width_key,
        },
        Part {
            what: "training batches",
            bytes: running * batch * per_window * BATCH_COPIES * FLOAT_BYTES,
            key: "training.batch_size".into(),
        },
    ]
}

/// One row per run, DVL, estimator and calibration window, test trajectory or length of
/// its held-out curve.
fn monte_carlo_rows(spec: &Spec) -> Part {
    let windows = &spec.calibration.window_sizes;
    let rows_per_run: usize = spec
        .kinds
        .iter()
        .map(|&kind| {
            let entries = match kind {
                // Each replicate, and their ensemble when there are several.
                EstimatorKind::Dcnet if spec.training.replicates > 1 => {
                    spec.error_models.len() * (spec.training.replicates + 1)
                }
                kind if kind.takes_error_model() => spec.error_models.len(),
                _ => 1,
            };
            let places = windows.len() + spec.evaluation.len() + curve_lengths(kind, windows).len();
            entries * places
        })
        .sum();
    let rows =
        spec.calibration.monte_carlo_runs as f64 * spec.dvls.len() as f64 * rows_per_run as f64;
    let row_bytes = std::mem::size_of::<RunRow>() as f64 + ROW_NAME_BYTES;
    Part {
        what: "Monte Carlo rows",
        bytes: rows * row_bytes * ROW_COPIES,
        key: "calibration.monte_carlo_runs".into(),
    }
}

/// The seconds `trainings` trainings of `spec` take on `threads` threads, each model
/// on a thread of its own, at `seconds_per_batch`: every epoch's training batches, and
/// its validation windows at a third of a batch's time (forward only).
pub fn training_seconds(
    spec: &Spec,
    lengths: &[usize],
    trainings: usize,
    threads: usize,
    seconds_per_batch: f64,
) -> f64 {
    let size = DatasetSize::from_lengths(spec, lengths);
    let batch = spec.training.batch_size as f64;
    let validation = size.validation() as f64;
    let batches = ((size.windows() as f64 - validation) / batch).ceil() + validation / batch / 3.0;
    let parallel = threads.clamp(1, trainings.max(1)) as f64;
    trainings as f64 * spec.training.epochs as f64 * batches * seconds_per_batch / parallel
}

/// A byte count as a person reads it: `1.5 GiB`.
pub struct Bytes(pub f64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const UNITS: [&str; 7] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
        let mut value = self.0;
        let mut unit = 0;
        while value >= 1024.0 && unit + 1 < UNITS.len() {
            value /= 1024.0;
            unit += 1;
        }
        if unit == 0 {
            write!(f, "{value:.0} B")
        } else {
            write!(f, "{value:.1} {}", UNITS[unit])
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::quick_spec;

    fn lengths(spec: &Spec) -> Vec<usize> {
        spec.trajectories
            .iter()
            .map(|t| t.known_len().unwrap())
            .collect()
    }

    #[test]
    fn the_training_set_part_is_the_set_the_dataset_generates() {
        let spec = quick_spec(&[]);
        let trajectories = crate::data::load_trajectories(&spec).unwrap();
        let set =
            crate::dataset::generate(&spec, &trajectories, &crate::progress::Progress::hidden());
        let footprint = Footprint::of(&spec, &lengths(&spec), 2);
        let part = footprint
            .parts
            .iter()
            .find(|p| p.what == "training set")
            .unwrap();
        let held = (set.inputs.len() + set.targets.len()) * 4 + set.is_validation.len();
        assert_eq!(part.bytes, held as f64);
    }

    #[test]
    fn the_models_part_counts_the_weights_of_every_error_model_and_replicate() {
        let spec = quick_spec(&[]);
        let footprint = Footprint::of(&spec, &lengths(&spec), 2);
        let part = footprint
            .parts
            .iter()
            .find(|p| p.what == "models in training")
            .unwrap();
        let model = crate::model::Dcnet::new(
            &spec.model,
            ErrorModel::Em5,
            spec.dataset.window_samples,
            &spec.training.backend.device(),
            &mut crate::rng::task_rng(0, &[&"test"]),
        );
        use burn::module::Module;
        let weights = model.num_params() as f64 * FLOAT_BYTES * MODEL_COPIES;
        assert_eq!(part.bytes, weights * spec.error_models.len() as f64);
        let three = quick_spec(&["training.replicates=3"]);
        let footprint = Footprint::of(&three, &lengths(&three), 2);
        let part = footprint
            .parts
            .iter()
            .find(|p| p.what == "models in training")
            .unwrap();
        assert_eq!(part.bytes, 3.0 * weights * spec.error_models.len() as f64);
    }

    #[test]
    fn a_spec_beyond_the_machine_is_refused_with_the_key_of_its_largest_part() {
        let spec = quick_spec(&["calibration.monte_carlo_runs=100000"]);
        let footprint = Footprint::of(&spec, &lengths(&spec), 2);
        assert_eq!(footprint.refusal(u64::MAX), None);
        let (key, message) = footprint.refusal(1 << 20).unwrap();
        assert_eq!(key, "calibration.monte_carlo_runs");
        assert!(message.contains("this machine has 1.0 MiB"), "{message}");
        assert!(message.contains("Monte Carlo rows"), "{message}");
        for (widths, key) in [
            ("[64,65536,65536]", "model.fc_widths[1]"),
            ("[65536,65536,64]", "model.fc_widths[0]"),
        ] {
            let wide = quick_spec(&[&format!("model.fc_widths={widths}")]);
            let footprint = Footprint::of(&wide, &lengths(&wide), 2);
            assert_eq!(footprint.refusal(1 << 20).unwrap().0, key, "{widths}");
        }
    }

    /// The quick spec's rows, as `tests/experiment/cli.rs` counts them in `monte_carlo.parquet`.
    #[test]
    fn the_monte_carlo_rows_are_those_a_run_writes() {
        let spec = quick_spec(&["calibration.monte_carlo_runs=3"]);
        let part = monte_carlo_rows(&spec);
        let row_bytes = std::mem::size_of::<RunRow>() as f64 + ROW_NAME_BYTES;
        let rows = part.bytes / (row_bytes * ROW_COPIES);
        assert_eq!(rows, (3 * 2 * (19 * (5 + 2) + 13 * 100 + 5 * 5)) as f64);
    }

    #[test]
    fn bytes_read_in_binary_units() {
        assert_eq!(Bytes(512.0).to_string(), "512 B");
        assert_eq!(Bytes(1536.0).to_string(), "1.5 KiB");
        assert_eq!(Bytes(15.8 * 1024f64.powi(4)).to_string(), "15.8 TiB");
    }
}
