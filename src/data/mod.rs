//! Trajectories: the recorded velocities named in the spec, read from `.npy` or `.csv`
//! files or generated, each with its ground truth (a forward moving average, PAPER-NOTES).
//! In: a checked [`Spec`]. Out: one [`Trajectory`] per `data.trajectories` entry, in
//! spec order.

pub mod csv;
pub mod fetch;
pub mod npy;
pub mod synthetic;

use crate::Vec3;
use crate::spec::{FileFormat, Origin, Spec};
use std::collections::BTreeMap;
use std::collections::btree_map::Entry;
use std::path::PathBuf;

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
    #[error("{path}: trajectory {trajectory} asks for samples [{start}, {end}) but the file has {len}", path = path.display())]
    OutOfRange {
        trajectory: String,
        path: PathBuf,
        start: usize,
        end: usize,
        len: usize,
    },
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
                    Entry::Vacant(unread) => unread.insert(match format {
                        FileFormat::Npy => npy::read_velocities(path)?,
                        FileFormat::Csv { columns } => csv::read_velocities(path, columns)?,
                    }),
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
