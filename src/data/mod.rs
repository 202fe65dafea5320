//! Trajectories: the recorded velocities named in the spec, read from `.npy` or `.csv`
//! files or generated, each with its ground truth (a forward moving average, docs/paper.md);
//! and [`paired`]: a DVL recorded beside a reference with attitude. [`catalogue`] lists
//! the published recordings (Snapir, A-KIT) and [`fetch`] downloads them.
//! In: a checked [`Spec`]. Out: one [`Trajectory`] per `data.trajectories` entry, in
//! spec order.

pub mod catalogue;
pub mod csv;
pub mod fetch;
pub mod fixes;
pub mod interpolate;
pub mod local_plane;
pub mod nmea;
pub mod npy;
pub mod paired;
pub mod position_fixes;
pub mod synthetic;

use crate::Vec3;
use crate::spec::{FileFormat, Origin, Spec, ranges};
use std::collections::BTreeMap;
use std::collections::btree_map::Entry;
use std::path::{Path, PathBuf};

/// A recorded trajectory and its ground truth, body-frame velocity in m/s.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    pub name: String,
    pub ground_truth: Vec<Vec3>,
}

impl Trajectory {
    pub fn mean_speed_m_s(&self) -> f64 {
        let total: f64 = self.ground_truth.iter().map(|v| norm(*v)).sum();
        total / self.ground_truth.len().max(1) as f64
    }
}

#[derive(Debug, thiserror::Error)]
pub enum DataError {
    #[error(transparent)]
    Npy(#[from] npy::NpyError),
    #[error(transparent)]
    Csv(#[from] csv::CsvError),
    #[error("{path}: sample {sample}, axis {axis} is {value} m/s: {why}", path = path.display(), why = ranges::SPEED_M_S.why)]
    Implausible {
        path: PathBuf,
        sample: usize,
        axis: usize,
        value: f64,
    },
    #[error("{path}: trajectory {trajectory} asks for samples [{start}, {end}) but the file has {len}", path = path.display())]
    OutOfRange {
        trajectory: String,
        path: PathBuf,
        start: usize,
        end: usize,
        len: usize,
    },
}

/// The length in samples of every trajectory of the spec, known without loading any:
/// from the spec, a `.npy` file's header, or a `.csv` file's rows.
pub fn lengths(spec: &Spec) -> Result<Vec<usize>, DataError> {
    spec.trajectories
        .iter()
        .map(|source| match (&source.origin, source.known_len()) {
            (_, Some(len)) => Ok(len),
            (Origin::File { path, format, .. }, None) => Ok(match format {
                FileFormat::Npy => npy::sample_count(path)?,
                FileFormat::Csv { .. } => csv::row_count(path)?,
            }),
            (Origin::Synthetic { samples }, None) => Ok(*samples),
        })
        .collect()
}

/// Loads every trajectory of the spec; each file is read once (a `.csv` once per choice
/// of columns).
pub fn load_trajectories(spec: &Spec) -> Result<Vec<Trajectory>, DataError> {
    let mut files: BTreeMap<(&PathBuf, &FileFormat), Vec<Vec3>> = BTreeMap::new();
    let mut trajectories = Vec::with_capacity(spec.trajectories.len());
    for source in &spec.trajectories {
        let recorded = match &source.origin {
            Origin::File {
                path,
                format,
                samples,
            } => {
                let all = match files.entry((path, format)) {
                    Entry::Occupied(read) => read.into_mut(),
                    Entry::Vacant(unread) => unread.insert(plausible(
                        path,
                        match format {
                            FileFormat::Npy => npy::read_velocities(path)?,
                            FileFormat::Csv { columns } => csv::read_velocities(path, columns)?,
                        },
                    )?),
                };
                let [start, end] = samples.unwrap_or([0, all.len()]);
                if end > all.len() {
                    return Err(DataError::OutOfRange {
                        trajectory: source.name.clone(),
                        path: path.clone(),
                        start,
                        end,
                        len: all.len(),
                    });
                }
                all[start..end].to_vec()
            }
            Origin::Synthetic { samples } => synthetic::generate(&source.name, *samples, spec),
        };
        trajectories.push(Trajectory {
            name: source.name.clone(),
            ground_truth: ground_truth(&recorded, spec.ground_truth_window_samples),
        });
    }
    Ok(trajectories)
}

/// `recorded`, when every velocity in it is one an AUV can have: at most
/// [`ranges::SPEED_M_S`] on each axis.
fn plausible(path: &Path, recorded: Vec<Vec3>) -> Result<Vec<Vec3>, DataError> {
    for (sample, velocity) in recorded.iter().enumerate() {
        for (axis, &value) in velocity.iter().enumerate() {
            if value.abs() > ranges::SPEED_M_S.max {
                return Err(DataError::Implausible {
                    path: path.to_path_buf(),
                    sample,
                    axis,
                    value,
                });
            }
        }
    }
    Ok(recorded)
}

/// Forward moving average: `out[i] = mean(x[i .. i + window])`, shrinking at the end.
pub fn ground_truth(recorded: &[Vec3], window: usize) -> Vec<Vec3> {
    (0..recorded.len())
        .map(|i| {
            let span = &recorded[i..(i + window).min(recorded.len())];
            let n = span.len() as f64;
            std::array::from_fn(|axis| span.iter().map(|v| v[axis]).sum::<f64>() / n)
        })
        .collect()
}

pub fn norm(v: Vec3) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ground_truth_is_a_forward_moving_average_that_shrinks_at_the_end() {
        let recorded: Vec<Vec3> = (0..7).map(|i| [i as f64, 2.0 * i as f64, 1.0]).collect();
        let gt = ground_truth(&recorded, 5);
        assert_eq!(gt[0], [2.0, 4.0, 1.0]); // mean of 0..=4
        assert_eq!(gt[2], [4.0, 8.0, 1.0]); // mean of 2..=6
        assert_eq!(gt[5], [5.5, 11.0, 1.0]); // mean of 5, 6
        assert_eq!(gt[6], [6.0, 12.0, 1.0]);
    }
}
