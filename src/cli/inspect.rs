//! `validate`, `data info` and `data fetch`: a spec and its data checked and
//! described without running anything (or a ROS 2 bag's topics listed), and the Snapir
//! or A-KIT recordings downloaded.

use super::{CliError, about, failure, footprints, input, load_spec, training_seconds};
use crate::data::paired::dvl_log;
use crate::data::{fetch, load_trajectories};
use crate::dataset::{DatasetSize, TrainingSet};
use crate::footprint::{self, Bytes};
use crate::spec::{Origin, load_experiment, window_starts};
use std::path::Path;

pub(super) fn validate(spec_path: &Path, set: &[String]) -> Result<(), CliError> {
    let experiment = load_experiment(spec_path, set).map_err(input)?;
    let memory = Bytes(footprint::machine_memory() as f64);
    for (point, (footprint, lengths)) in experiment.points.iter().zip(footprints(&experiment)?) {
        let spec = &point.spec;
        let trajectories = load_trajectories(spec).map_err(input)?;
        let windows = DatasetSize::of(spec, &trajectories).windows();
        println!(
            "{}: ok ({} trajectories, {}, {}, {})",
            if experiment.is_sweep() {
                format!("{} point {}", spec_path.display(), spec.name)
            } else {
                spec_path.display().to_string()
            },
            trajectories.len(),
            crate::count(windows, "training window"),
            crate::count(spec.dvls.len(), "DVL"),
            crate::count(spec.calibration.monte_carlo_runs, "Monte Carlo run")
        );
        let largest = footprint.largest();
        println!(
            "  memory: about {} of this machine's {memory}, most of it the {} ({})",
            Bytes(footprint.bytes()),
            largest.what,
            Bytes(largest.bytes)
        );
        let trainings: Vec<_> = (0..spec.model_count())
            .map(|_| (spec, lengths.clone()))
            .collect();
        if !trainings.is_empty() {
            println!(
                "  training: {}, about {} on {} (from one batch timed here; cached models take none)",
                crate::count(trainings.len(), "model"),
                about(training_seconds(&trainings)?),
                crate::count(rayon::current_num_threads(), "thread")
            );
        }
    }
    Ok(())
}

pub(super) fn info(spec_path: &Path, set: &[String]) -> Result<(), CliError> {
    let spec = load_spec(spec_path, set)?;
    let trajectories = load_trajectories(&spec).map_err(input)?;
    let mut table = comfy_table::Table::new();
    table.load_preset(comfy_table::presets::ASCII_MARKDOWN);
    table.set_header([
        "trajectory",
        "role",
        "source",
        "samples",
        "duration min",
        "mean speed m/s",
        "windows",
    ]);
    for (index, (source, trajectory)) in spec.trajectories.iter().zip(&trajectories).enumerate() {
        let roles = spec.roles(index);
        let origin = match &source.origin {
            Origin::File {
                path,
                samples: Some([start, end]),
                ..
            } => format!("{} [{start}, {end})", file_name(path)),
            Origin::File {
                path,
                samples: None,
                ..
            } => file_name(path),
            Origin::Synthetic { .. } => "synthetic".to_string(),
        };
        let len = trajectory.ground_truth.len();
        let windows = if roles.contains(&"train") {
            window_starts(
                len,
                spec.dataset.window_samples,
                spec.dataset.stride_samples,
            )
            .count()
            .to_string()
        } else {
            String::new()
        };
        table.add_row(vec![
            trajectory.name.clone(),
            roles.join(", "),
            origin,
            len.to_string(),
            format!("{:.1}", len as f64 / spec.sample_rate_hz / 60.0),
            format!("{:.2}", trajectory.mean_speed_m_s()),
            windows,
        ]);
    }
    println!("{table}");
    let size = DatasetSize::of(&spec, &trajectories);
    let (combinations, per_combination) = (size.combinations, size.per_combination);
    let (windows, validation) = (size.windows(), size.validation());
    println!(
        "grid: {} scale × {} bias × {} noise = {combinations} combinations",
        spec.grid.scale_pct.len(),
        spec.grid.bias_cm_s.len(),
        spec.grid.noise_cm_s.len()
    );
    println!(
        "windows: {per_combination} per combination × {combinations} = {windows} ({} train, {validation} validation), {} s long every {} s",
        windows - validation,
        spec.dataset.window_samples as f64 / spec.sample_rate_hz,
        spec.dataset.stride_samples as f64 / spec.sample_rate_hz
    );
    if let Some(published) = spec.dataset.published_windows {
        println!(
            "published: {published} windows; this spec makes {:.3} of that",
            windows as f64 / published as f64
        );
    }
    println!(
        "dataset size: {} bytes (f32 inputs and targets, one split flag per window)",
        TrainingSet::size_bytes(windows as f64, spec.dataset.window_samples as f64)
    );
    Ok(())
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

pub(super) fn fetch_data(
    dataset: crate::data::catalogue::Dataset,
    dest: &Path,
    base_url: &str,
) -> Result<(), CliError> {
    let fetched = fetch::fetch(dataset, base_url, dest).map_err(|error| match error {
        fetch::FetchError::BadUrl { .. } => input(error),
        _ => failure(error),
    })?;
    for file in fetched {
        match file {
            fetch::Fetched::Downloaded(path) => {
                eprintln!("downloaded {} (sha256 checked)", path.display())
            }
            fetch::Fetched::AlreadyPresent(path) => {
                eprintln!("{} is already there (sha256 checked)", path.display())
            }
        }
    }
    Ok(())
}

/// `data info` of a DVL's own log: its span, pings, frames, data types and validity.
pub(super) fn log_info(path: &Path, format: dvl_log::LogFormat) -> Result<(), CliError> {
    let log = dvl_log::read(path, format, dvl_log::Thresholds::default()).map_err(input)?;
    println!("{}", log.describe());
    Ok(())
}

/// `data info BAG`: its files, storage and time span, and each topic with its type,
/// message count, rate, and whether this tool reads it.
pub(super) fn bag_info(path: &Path) -> Result<(), CliError> {
    use crate::data::paired::bag::{Bag, topic_lines};
    let bag = Bag::open(path).map_err(input)?;
    let survey = bag.survey().map_err(input)?;
    let first = survey.topics.iter().filter_map(|t| t.first_ns).min();
    let last = survey.topics.iter().filter_map(|t| t.last_ns).max();
    println!(
        "{}: a {} bag, {}, {} messages{}",
        path.display(),
        match bag.storage {
            crate::data::paired::bag::Storage::Mcap => "MCAP",
            crate::data::paired::bag::Storage::Sqlite => "sqlite3",
        },
        crate::count(bag.files.len(), "file"),
        survey.topics.iter().map(|t| t.count).sum::<u64>(),
        match (first, last) {
            (Some(first), Some(last)) => format!(
                ", recorded over {:.3} s (from {:.3} s after the epoch)",
                (last - first) as f64 * 1e-9,
                first as f64 * 1e-9
            ),
            _ => String::new(),
        }
    );
    println!("{}", topic_lines(&survey));
    Ok(())
}
