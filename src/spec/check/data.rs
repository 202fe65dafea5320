//! Checks `[data]`. In: [`DataSectionFile`]: the sample rate, the ground truth's
//! window, the synthetic generator's settings and the trajectories, and the folder
//! relative paths start from. Out: the rate the other sections count seconds with, and
//! each trajectory's origin (a sample range of a `.npy` or `.csv` file, or a synthetic
//! length), its path made absolute in the resolved spec.
//!
//! [`DataSectionFile`]: crate::spec::file::DataSectionFile

use super::{Faults, non_negative};
use crate::spec::file::{self, SyntheticFile};
use crate::spec::{FileFormat, Origin, TrajectorySource, ranges, recordings, seconds_to_samples};
use std::path::{Path, PathBuf};

/// The `[data]` section, checked.
pub(in crate::spec) struct Data {
    pub(in crate::spec) sample_rate_hz: f64,
    /// The rate seconds are counted in samples with: 1 Hz when `sample_rate_hz` is
    /// outside its range, so that the other checks still run.
    pub(in crate::spec) rate: f64,
    pub(in crate::spec) ground_truth_window_samples: usize,
    pub(in crate::spec) synthetic: SyntheticFile,
    pub(in crate::spec) trajectories: Vec<TrajectorySource>,
}

/// Checks `[data]`: the sample rate, the ground truth's window, the synthetic
/// generator and every trajectory; `resolved` gets the trajectories' absolute paths.
pub(in crate::spec) fn check_data(
    data: file::DataSectionFile,
    spec_dir: &Path,
    resolved: &mut [file::TrajectoryFile],
    faults: &mut Faults,
) -> Data {
    let file::DataSectionFile {
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
    let mut names = std::collections::HashSet::new();
    if trajectories.is_empty() {
        faults.add("data.trajectories", "no trajectory is defined");
    }
    for (i, trajectory) in trajectories.iter().enumerate() {
        let key = format!("data.trajectories[{i}]");
        let name = &trajectory.name;
        if !names.insert(name) {
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

/// Whether `path` is a symbolic link whose chain of targets comes back to a link it
/// passed (or goes on past 40 links, where the system gives up).
fn is_symlink_loop(path: &Path) -> bool {
    let mut passed = Vec::new();
    let mut link = path.to_path_buf();
    while std::fs::symlink_metadata(&link).is_ok_and(|meta| meta.file_type().is_symlink()) {
        if passed.contains(&link) || passed.len() > 40 {
            return true;
        }
        let Ok(target) = std::fs::read_link(&link) else {
            return false;
        };
        let next = link.parent().unwrap_or(Path::new("")).join(target);
        passed.push(std::mem::replace(&mut link, next));
    }
    false
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
    } else if is_symlink_loop(&path) {
        faults.add(
            format!("{key}.file"),
            format!(
                "{} is a loop of symbolic links that leads back to itself: name the recording file",
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

#[cfg(test)]
mod tests {
    use crate::spec::Origin;
    use crate::spec::fixture::{quick_faults, quick_spec};

    #[test]
    fn a_synthetic_trajectory_is_counted_in_samples_at_the_rate() {
        let origin = |spec: &crate::spec::Spec| spec.trajectories[0].origin.clone();
        assert_eq!(origin(&quick_spec(&[])), Origin::Synthetic { samples: 900 });
        assert_eq!(
            origin(&quick_spec(&["data.sample_rate_hz=2"])),
            Origin::Synthetic { samples: 1800 }
        );
        let set = "data.trajectories[0].synthetic_duration_s=0.5";
        assert_eq!(
            quick_faults(&[set]),
            format!(
                "--set {set}: data.trajectories[0].synthetic_duration_s: 0.5 must be a positive whole number of samples"
            )
        );
    }

    #[test]
    fn a_rate_at_fault_is_its_only_fault() {
        // The other sections count their seconds at 1 Hz instead.
        let set = "data.sample_rate_hz=0";
        assert_eq!(
            quick_faults(&[set]),
            format!("--set {set}: data.sample_rate_hz: 0 must be a positive number")
        );
    }
}
