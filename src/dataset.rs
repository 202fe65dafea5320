//! The training dataset: every combination of the error-term grid, applied to every
//! training trajectory, cut into windows. In: the checked spec and the trajectories.
//! Out: a [`TrainingSet`] in a compact f32 layout, `[window, 6, time]` inputs (DVL x, y,
//! z, then GNSS-RTK x, y, z) and `[window, 3, time]` ground-truth targets, with each
//! combination's windows split 80:20 (or as the spec says) into training and validation.
//! Combinations are generated in parallel, each from its own generator seeded by
//! (seed, combination index), so the bytes do not depend on the thread count.

use crate::data::Trajectory;
use crate::noise::{BeamGeometry, measure_trajectory};
use crate::progress::Progress;
use crate::rng::task_rng;
use crate::spec::{Grid, Spec, window_starts};
use crate::vocab::SensorErrors;
use rayon::prelude::*;

/// Rows of one input window: DVL x, y, z and GNSS-RTK x, y, z.
pub const INPUT_ROWS: usize = 6;
/// Rows of one target window: ground-truth x, y, z.
pub const TARGET_ROWS: usize = 3;

/// One combination of the training grid, in the spec's units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridPoint {
    pub scale_pct: f64,
    pub bias_cm_s: f64,
    pub noise_cm_s: f64,
}

impl Grid {
    /// Every combination, scale outermost and noise innermost.
    pub fn points(&self) -> Vec<GridPoint> {
        let mut points =
            Vec::with_capacity(self.scale_pct.len() * self.bias_cm_s.len() * self.noise_cm_s.len());
        for &scale_pct in &self.scale_pct {
            for &bias_cm_s in &self.bias_cm_s {
                for &noise_cm_s in &self.noise_cm_s {
                    points.push(GridPoint {
                        scale_pct,
                        bias_cm_s,
                        noise_cm_s,
                    });
                }
            }
        }
        points
    }
}

/// How many windows a spec's training set has, known before any is generated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DatasetSize {
    /// Combinations of the error-term grid.
    pub combinations: usize,
    /// Windows that one combination yields from the training trajectories.
    pub per_combination: usize,
    /// Of those, the validation windows.
    pub validation_per_combination: usize,
}

impl DatasetSize {
    pub fn of(spec: &Spec, trajectories: &[Trajectory]) -> Self {
        let lengths: Vec<usize> = trajectories.iter().map(|t| t.ground_truth.len()).collect();
        Self::from_lengths(spec, &lengths)
    }

    /// The size from the lengths in samples of the spec's trajectories, before any is
    /// loaded.
    pub fn from_lengths(spec: &Spec, lengths: &[usize]) -> Self {
        let d = &spec.dataset;
        let per_combination = d.windows_per_combination(d.trajectories.iter().map(|&t| lengths[t]));
        Self {
            combinations: spec.grid.points().len(),
            per_combination,
            validation_per_combination: d.validation_windows(per_combination),
        }
    }

    /// Every window of the set.
    pub fn windows(&self) -> usize {
        self.combinations * self.per_combination
    }

    /// The validation windows of the set.
    pub fn validation(&self) -> usize {
        self.combinations * self.validation_per_combination
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct TrainingSet {
    pub points: Vec<GridPoint>,
    /// Samples per window.
    pub window: usize,
    pub windows_per_combination: usize,
    /// `[window, INPUT_ROWS, time]`, row-major.
    pub inputs: Vec<f32>,
    /// `[window, TARGET_ROWS, time]`, row-major.
    pub targets: Vec<f32>,
    /// One flag per window.
    pub is_validation: Vec<bool>,
}

impl TrainingSet {
    pub fn len(&self) -> usize {
        self.is_validation.len()
    }

    pub fn is_empty(&self) -> bool {
        self.is_validation.is_empty()
    }

    pub fn validation_len(&self) -> usize {
        self.is_validation.iter().filter(|&&v| v).count()
    }

    /// The windows an epoch trains on.
    pub fn training_len(&self) -> usize {
        self.len() - self.validation_len()
    }

    /// Bytes of the window data a set of `windows` windows of `window` samples holds
    /// (in floating point, so that no size overflows).
    pub fn size_bytes(windows: f64, window: f64) -> f64 {
        windows * (INPUT_ROWS + TARGET_ROWS) as f64 * window * std::mem::size_of::<f32>() as f64
            + windows * std::mem::size_of::<bool>() as f64
    }
}

/// Generates the whole training set; `progress` advances once per combination.
pub fn generate(spec: &Spec, trajectories: &[Trajectory], progress: &Progress) -> TrainingSet {
    let geometry = BeamGeometry::janus_x(spec.beam_pitch_deg);
    let points = spec.grid.points();
    let window = spec.dataset.window_samples;
    let size = DatasetSize::of(spec, trajectories);
    let (per_combination, total) = (size.per_combination, size.windows());
    let mut inputs = vec![0f32; total * INPUT_ROWS * window];
    let mut targets = vec![0f32; total * TARGET_ROWS * window];
    crate::memory::prefer_huge_pages(&mut inputs);
    crate::memory::prefer_huge_pages(&mut targets);
    let mut is_validation = vec![false; total];
    let validation_count = size.validation_per_combination;

    inputs
        .par_chunks_mut(per_combination * INPUT_ROWS * window)
        .zip(targets.par_chunks_mut(per_combination * TARGET_ROWS * window))
        .zip(is_validation.par_chunks_mut(per_combination))
        .enumerate()
        .for_each(|(combination, ((inputs, targets), is_validation))| {
            let point = points[combination];
            let errors =
                SensorErrors::from_spec_units(point.scale_pct, point.bias_cm_s, point.noise_cm_s);
            let mut rng = task_rng(spec.seed, &[&"dataset", &combination]);
            let mut next = 0;
            for &t in &spec.dataset.trajectories {
                let truth = &trajectories[t].ground_truth;
                let measured =
                    measure_trajectory(&geometry, truth, &errors, spec.gnss_noise_m_s, &mut rng);
                for start in window_starts(truth.len(), window, spec.dataset.stride_samples) {
                    let input = &mut inputs[next * INPUT_ROWS * window..][..INPUT_ROWS * window];
                    let target =
                        &mut targets[next * TARGET_ROWS * window..][..TARGET_ROWS * window];
                    for time in 0..window {
                        for axis in 0..3 {
                            input[axis * window + time] = measured.dvl[start + time][axis] as f32;
                            input[(3 + axis) * window + time] =
                                measured.gnss[start + time][axis] as f32;
                            target[axis * window + time] = truth[start + time][axis] as f32;
                        }
                    }
                    next += 1;
                }
            }
            let mut split_rng = task_rng(spec.seed, &[&"split", &combination]);
            for index in rand::seq::index::sample(&mut split_rng, per_combination, validation_count)
            {
                is_validation[index] = true;
            }
            progress.inc(1);
        });
    TrainingSet {
        points,
        window,
        windows_per_combination: per_combination,
        inputs,
        targets,
        is_validation,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::load_trajectories;
    use crate::spec::quick_spec;

    #[test]
    fn one_and_two_threads_generate_identical_data() {
        let spec = quick_spec(&[]);
        let trajectories = load_trajectories(&spec).unwrap();
        let with_threads = |n| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap();
            pool.install(|| generate(&spec, &trajectories, &Progress::hidden()))
        };
        let one = with_threads(1);
        assert_eq!(one, with_threads(2));
        assert_eq!(one.len(), 12 * 165);
        assert_eq!(one.validation_len(), 12 * 33);
    }

    #[test]
    fn windows_hold_the_measurements_and_the_ground_truth() {
        // Without any error or noise, the DVL and GNSS rows equal the targets.
        let spec = quick_spec(&[
            "grid.scale_pct.values=[0.0, 1.0]",
            "grid.bias_cm_s.values=[0.0]",
            "grid.noise_cm_s.values=[0.0]",
            "sensors.gnss_noise_cm_s=0.0",
        ]);
        let trajectories = load_trajectories(&spec).unwrap();
        let set = generate(&spec, &trajectories, &Progress::hidden());
        let w = set.window;
        let second = set.windows_per_combination - 1; // the last window of S2
        let truth = &trajectories[1].ground_truth;
        let start = 9 * (window_starts(truth.len(), w, 9).count() - 1);
        for (combination, scale) in [(0, 1.0), (1, 1.01)] {
            let index = combination * set.windows_per_combination + second;
            let input = &set.inputs[index * INPUT_ROWS * w..][..INPUT_ROWS * w];
            let target = &set.targets[index * TARGET_ROWS * w..][..TARGET_ROWS * w];
            for time in 0..w {
                for axis in 0..3 {
                    let gt = truth[start + time][axis];
                    assert_eq!(target[axis * w + time], gt as f32);
                    assert!(
                        (input[axis * w + time] - (scale * gt) as f32).abs() < 1e-6,
                        "DVL row"
                    );
                    assert!(
                        (input[(3 + axis) * w + time] - gt as f32).abs() < 1e-6,
                        "GNSS row"
                    );
                }
            }
        }
    }

    #[test]
    fn windows_of_10_s_every_9_s() {
        assert_eq!(window_starts(28, 10, 9).collect::<Vec<_>>(), vec![0, 9, 18]);
        assert_eq!(window_starts(27, 10, 9).count(), 2);
        assert_eq!(window_starts(9, 10, 9).count(), 0);
        // T1 of the Snapir split: 1339 samples.
        assert_eq!(window_starts(1339, 10, 9).count(), 148);
    }

    #[test]
    fn the_paper_grid_has_1134_combinations() {
        let axis = |start: f64, step: f64, n: usize| {
            (0..n).map(|i| start + i as f64 * step).collect::<Vec<_>>()
        };
        let grid = Grid {
            scale_pct: axis(0.2, 0.1, 14),
            bias_cm_s: axis(0.1, 0.1, 9),
            noise_cm_s: axis(0.01, 0.01, 9),
        };
        let points = grid.points();
        assert_eq!(points.len(), 1134);
        assert_eq!(
            points[1],
            GridPoint {
                scale_pct: 0.2,
                bias_cm_s: 0.1,
                noise_cm_s: 0.02
            }
        );
    }
}
