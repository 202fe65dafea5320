//! Simulated installations: the DVL that an installation's terms would make read beside
//! a real reference, over a grid of installations, cut into the windows a network
//! trains on. The reference's own motion (its body velocity and rate at the DVL's
//! stamps) is real; only the DVL is simulated, by the model of [`terms`](crate::installation::terms)
//! plus white noise per axis.
//! In: [`Recording`]s, a [`SimulationGrid`], the DVL noise, a seed. Out: [`InstallationWindows`]:
//! per window `[9, time]` inputs (DVL, reference body velocity, body rate) and `[6,
//! time + 6]` targets (reference body velocity and body rate, with three samples either
//! side so that the loss can read them at t + τ), f32, SI units.
//!
//! Each (trajectory, installation) draws its noise from its own generator, seeded by the
//! seed, the trajectory's name and the installation's index, and the windows are
//! generated in parallel and put in that order, so the bytes do not depend on the thread
//! count.

use crate::Vec3;
use crate::data::paired::sample_interval;
use crate::installation::frames::ReferenceAt;
use crate::installation::learned::spec::SimulationGrid;
use crate::installation::study::Recording;
use crate::installation::terms::Installation;
use crate::rng::task_rng;
use rand::Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;

/// Rows of an input window: DVL x, y, z; reference body velocity x, y, z; body rate p,
/// q, r.
pub const INPUT_ROWS: usize = 9;
/// Rows of a target window: reference body velocity x, y, z and body rate p, q, r.
pub const TARGET_ROWS: usize = 6;
/// Samples of the reference a target window holds either side of its window, so that
/// the reference can be read at t + τ for |τ| up to this many sample intervals.
pub const REFERENCE_MARGIN: usize = 3;
/// How far an interval between two stamps of a window may be from the recording's median
/// interval, as a fraction of it: windows across a gap are not cut.
const STEP_TOLERANCE: f64 = 0.01;

/// The DVL that `installation` makes read on `recording`'s stamps, with white noise of
/// `noise_m_s` per axis from `rng`: `predict(reference at t + τ) + n`, `None` where t + τ
/// falls outside the reference.
pub fn simulate_dvl(
    recording: &Recording,
    installation: &Installation,
    noise_m_s: f64,
    rng: &mut impl Rng,
) -> Vec<Option<Vec3>> {
    simulate_dvl_correlated(recording, installation, (noise_m_s, 0.0), rng)
}

/// [`simulate_dvl`] with noise correlated in time: per axis a stationary first-order
/// autoregression of standard deviation `noise_m_s` whose correlation between samples
/// one second apart is `correlation_at_1_s` (between samples Δt apart, its power Δt);
/// at 0, white noise of the same draws as [`simulate_dvl`]'s.
pub fn simulate_dvl_correlated(
    recording: &Recording,
    installation: &Installation,
    (noise_m_s, correlation_at_1_s): (f64, f64),
    rng: &mut impl Rng,
) -> Vec<Option<Vec3>> {
    let noise = Normal::new(0.0, noise_m_s).expect("a finite, non-negative noise");
    let time_s = &recording.recording.time_s;
    let mut last: Option<(f64, Vec3)> = None;
    time_s
        .iter()
        .map(|&t| {
            let at = recording.reference.at(t + installation.time_offset_s)?;
            let clean = installation.predict(at);
            let drawn = [0, 1, 2].map(|_| noise.sample(rng));
            let n = match last {
                Some((before, previous)) if correlation_at_1_s != 0.0 => {
                    let rho = correlation_at_1_s.powf(t - before);
                    let fresh = (1.0 - rho * rho).sqrt();
                    [0, 1, 2].map(|k| rho * previous[k] + fresh * drawn[k])
                }
                _ => drawn,
            };
            last = Some((t, n));
            Some([0, 1, 2].map(|k| clean[k] + n[k]))
        })
        .collect()
}

/// Windows of a network that learns an installation, in the layout of the module's
/// rows, with where each came from.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct InstallationWindows {
    /// Samples per window.
    pub window: usize,
    /// The interval between two samples, s.
    pub step_s: f64,
    /// `[count, INPUT_ROWS, window]`, row-major.
    pub inputs: Vec<f32>,
    /// `[count, TARGET_ROWS, window + 2 · REFERENCE_MARGIN]`, row-major.
    pub targets: Vec<f32>,
    /// Each window's trajectory, by its name.
    pub trajectory: Vec<String>,
    /// Each window's installation, an index into the grid's (0 for a real DVL).
    pub installation: Vec<usize>,
    /// Whether each window is kept for validation.
    pub validation: Vec<bool>,
}

impl InstallationWindows {
    pub fn len(&self) -> usize {
        self.trajectory.len()
    }

    pub fn is_empty(&self) -> bool {
        self.trajectory.is_empty()
    }

    pub fn extend(&mut self, other: InstallationWindows) {
        self.window = other.window;
        self.step_s = other.step_s;
        self.inputs.extend(other.inputs);
        self.targets.extend(other.targets);
        self.trajectory.extend(other.trajectory);
        self.installation.extend(other.installation);
        self.validation.extend(other.validation);
    }

    /// Keeps the last `fraction` (rounded) of the windows of each trajectory and
    /// installation for validation, as the paper splits each grid combination's.
    pub fn with_validation(mut self, fraction: f64) -> Self {
        let mut start = 0;
        while start < self.len() {
            let same = |i: usize| {
                self.trajectory[i] == self.trajectory[start]
                    && self.installation[i] == self.installation[start]
            };
            let end = (start..self.len())
                .find(|&i| !same(i))
                .unwrap_or(self.len());
            let kept = ((end - start) as f64 * fraction).round() as usize;
            for i in start..end {
                self.validation[i] = i >= end - kept;
            }
            start = end;
        }
        self
    }
}

/// The windows of `window` samples, every `stride` samples, of `recording` with the DVL
/// `dvl` on its stamps; a window is kept where every sample has a DVL value, the reference
/// is there on every stamp from [`REFERENCE_MARGIN`] samples before it to as many after,
/// and those stamps are evenly spaced.
pub fn windows_of(
    recording: &Recording,
    dvl: &[Option<Vec3>],
    window: usize,
    stride: usize,
    installation: usize,
) -> InstallationWindows {
    let time_s = &recording.recording.time_s;
    let step_s = sample_interval(time_s);
    let reference: Vec<Option<ReferenceAt>> =
        time_s.iter().map(|&t| recording.reference.at(t)).collect();
    let mut out = InstallationWindows {
        window,
        step_s,
        ..Default::default()
    };
    let margin = REFERENCE_MARGIN;
    let span = window + 2 * margin;
    for first in (0..time_s.len().saturating_sub(span - 1)).step_by(stride.max(1)) {
        let stamps = first..first + span;
        let inside = first + margin..first + margin + window;
        let even = time_s[stamps.clone()]
            .windows(2)
            .all(|pair| ((pair[1] - pair[0]) - step_s).abs() <= STEP_TOLERANCE * step_s);
        let (Some(dvl), Some(at)) = (
            dvl[inside.clone()]
                .iter()
                .copied()
                .collect::<Option<Vec<Vec3>>>(),
            reference[stamps]
                .iter()
                .copied()
                .collect::<Option<Vec<ReferenceAt>>>(),
        ) else {
            continue;
        };
        if !even {
            continue;
        }
        let inner = &at[margin..margin + window];
        let row = |out: &mut Vec<f32>, values: &mut dyn Iterator<Item = f64>| {
            out.extend(values.map(|v| v as f32));
        };
        for k in 0..3 {
            row(&mut out.inputs, &mut dvl.iter().map(|v| v[k]));
        }
        for k in 0..3 {
            row(
                &mut out.inputs,
                &mut inner.iter().map(|a| a.velocity_body_m_s[k]),
            );
        }
        for k in 0..3 {
            row(&mut out.inputs, &mut inner.iter().map(|a| a.rate_rad_s[k]));
        }
        for k in 0..3 {
            row(
                &mut out.targets,
                &mut at.iter().map(|a| a.velocity_body_m_s[k]),
            );
        }
        for k in 0..3 {
            row(&mut out.targets, &mut at.iter().map(|a| a.rate_rad_s[k]));
        }
        out.trajectory.push(recording.name.clone());
        out.installation.push(installation);
        out.validation.push(false);
    }
    out
}

/// The simulated training windows of every installation of `grid` on every recording of
/// `recordings`: trajectory by trajectory, installation by installation within it.
pub fn simulated_windows(
    recordings: &[&Recording],
    grid: &SimulationGrid,
    noise_m_s: f64,
    window: usize,
    stride: usize,
    seed: u64,
) -> InstallationWindows {
    let installations = grid.installations();
    let tasks: Vec<(usize, usize)> = (0..recordings.len())
        .flat_map(|s| (0..installations.len()).map(move |i| (s, i)))
        .collect();
    let parts: Vec<InstallationWindows> = tasks
        .par_iter()
        .map(|&(s, i)| {
            let recording = recordings[s];
            let mut rng = task_rng(seed, &[&"installation-dvl", &recording.name, &i]);
            let dvl = simulate_dvl(recording, &installations[i], noise_m_s, &mut rng);
            windows_of(recording, &dvl, window, stride, i)
        })
        .collect();
    let mut all = InstallationWindows {
        window,
        step_s: recordings
            .first()
            .map_or(1.0, |s| sample_interval(&s.recording.time_s)),
        ..Default::default()
    };
    for part in parts {
        all.extend(part);
    }
    all
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::data::paired::PairedRecording;
    use crate::installation::estimate::fit::fit;
    use crate::installation::terms::TermSet;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// A vehicle weaving at up to about 11°/s with a changing speed, 1 Hz, its DVL
    /// column empty.
    pub(crate) fn weaving(name: &str, seconds: usize, phase: f64) -> Recording {
        let time_s: Vec<f64> = (0..seconds).map(|t| t as f64).collect();
        let yaw = |t: f64| 1.5 * (t / 8.0 + phase).sin() + 0.3 * (t / 3.0).cos();
        let speed = |t: f64| 2.0 + 0.3 * (t / 11.0 + phase).sin();
        let recording = PairedRecording {
            dvl_m_s: vec![[0.0; 3]; time_s.len()],
            left_out: Vec::new(),
            reference_time_s: time_s.clone(),
            velocity_ned_m_s: time_s
                .iter()
                .map(|&t| {
                    [
                        speed(t) * yaw(t).cos(),
                        speed(t) * yaw(t).sin(),
                        0.1 * (t / 5.0).sin(),
                    ]
                })
                .collect(),
            attitude_rad: time_s
                .iter()
                .map(|&t| [0.02 * (t / 4.0).sin(), 0.05 * (t / 7.0).cos(), yaw(t)])
                .collect(),
            time_s,
            rate_rad_s: None,
            position_ne_m: None,
            gap_limit_s: 3.0,
            reference_read: None,
        };
        Recording::new(name.to_string(), recording)
    }

    fn grid() -> SimulationGrid {
        SimulationGrid {
            lever_arm_x_m: vec![-2.0, 0.0],
            lever_arm_y_m: vec![0.0],
            lever_arm_z_m: vec![0.5],
            time_offset_s: vec![0.0, 1.4],
            misalignment_z_deg: vec![1.0],
            scale_pct: vec![-1.0],
            bias_cm_s: vec![0.5],
        }
    }

    #[test]
    fn the_grid_holds_every_combination_in_spec_units() {
        let all = grid().installations();
        assert_eq!(all.len(), 4);
        assert_eq!(all[3].lever_arm_m, [0.0, 0.0, 0.5]);
        assert_eq!(all[3].time_offset_s, 1.4);
        assert_eq!(all[1].misalignment_rad, [0.0, 0.0, 1f64.to_radians()]);
        assert_eq!(all[0].scale, [-0.01; 3]);
        assert_eq!(all[0].bias_m_s, [0.005; 3]);
    }

    /// Without noise, the correction with the true terms gives back the reference at
    /// t + τ, and the installation model's fit finds the terms that simulated the DVL.
    #[test]
    fn a_noise_free_simulation_is_undone_by_its_terms_and_fitted_back() {
        let recording = weaving("W", 300, 0.0);
        let truth = Installation {
            scale: [0.01, -0.005, 0.002],
            misalignment_rad: [0.0, 0.0, 2f64.to_radians()],
            lever_arm_m: [-1.9, 0.1, 0.6],
            time_offset_s: 1.4,
            bias_m_s: [0.006, -0.002, 0.001],
        };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let dvl = simulate_dvl(&recording, &truth, 0.0, &mut rng);
        let time_s = &recording.recording.time_s;
        for (&t, dvl) in time_s.iter().zip(&dvl) {
            let Some(dvl) = dvl else { continue };
            let at = recording.reference.at(t + truth.time_offset_s).unwrap();
            let corrected = truth.correct(*dvl, at.rate_rad_s);
            for k in 0..3 {
                assert!((corrected[k] - at.velocity_body_m_s[k]).abs() < 1e-12);
            }
        }
        assert!(
            dvl.iter().rev().take(1).all(Option::is_none),
            "t + τ past the end"
        );
        let kept: Vec<usize> = (0..dvl.len()).filter(|&i| dvl[i].is_some()).collect();
        let fitted = fit(
            &kept.iter().map(|&i| time_s[i]).collect::<Vec<_>>(),
            &kept.iter().map(|&i| dvl[i].unwrap()).collect::<Vec<_>>(),
            &recording.reference,
            TermSet::EVERY,
        )
        .unwrap();
        let truth_parameters = truth.to_parameters(&TermSet::EVERY);
        for (found, expected) in fitted.parameters.iter().zip(&truth_parameters) {
            assert!((found - expected).abs() < 1e-6, "{fitted:?}");
        }
    }

    #[test]
    fn windows_hold_the_rows_in_order_and_skip_samples_without_a_dvl() {
        let recording = weaving("W", 40, 0.0);
        let truth = grid().installations()[3];
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let mut dvl = simulate_dvl(&recording, &truth, 0.01, &mut rng);
        dvl[20] = None;
        let windows = windows_of(&recording, &dvl, 10, 5, 3);
        // Samples 0 to 37 have a DVL but for 20 (38 and 39 none: t + 1.4 s is past the
        // reference's end), and 3 samples of reference either side: windows start at 3
        // to 27, by 5 from the first sample at 0 that can lead a window's margin: 3, 8,
        // 13, 18 and 23, of which 13 and 18 hold sample 20.
        let starts = [3usize, 8, 23];
        assert_eq!(windows.len(), starts.len(), "{:?}", windows.trajectory);
        assert_eq!(windows.step_s, 1.0);
        let span = 10 + 2 * REFERENCE_MARGIN;
        for (w, &start) in starts.iter().enumerate() {
            let input = |row: usize, t: usize| windows.inputs[(w * INPUT_ROWS + row) * 10 + t];
            let target = |row: usize, t: usize| windows.targets[(w * TARGET_ROWS + row) * span + t];
            let at = |i: usize| {
                recording
                    .reference
                    .at(recording.recording.time_s[i])
                    .unwrap()
            };
            assert_eq!(input(1, 3), dvl[start + 3].unwrap()[1] as f32);
            assert_eq!(input(4, 3), at(start + 3).velocity_body_m_s[1] as f32);
            assert_eq!(input(8, 3), at(start + 3).rate_rad_s[2] as f32);
            assert_eq!(target(0, 3 + REFERENCE_MARGIN), input(3, 3));
            assert_eq!(
                target(0, 0),
                at(start - REFERENCE_MARGIN).velocity_body_m_s[0] as f32
            );
            assert_eq!(target(5, span - 1), at(start + 12).rate_rad_s[2] as f32);
        }
        assert!(windows.installation.iter().all(|&i| i == 3));
    }

    #[test]
    fn the_last_windows_of_each_trajectory_and_installation_are_kept_for_validation() {
        let recordings = [weaving("A", 60, 0.0), weaving("B", 60, 1.0)];
        let recordings: Vec<&Recording> = recordings.iter().collect();
        let windows = simulated_windows(&recordings, &grid(), 0.0, 10, 5, 7).with_validation(0.25);
        // Each of the 2 × 4 groups holds 8 windows (starts 0, 5, …, 35, all inside the
        // reference but those whose DVL at t + 1.4 s runs past its end): count per group.
        let mut groups: Vec<(String, usize, usize, usize)> = Vec::new();
        for i in 0..windows.len() {
            let key = (windows.trajectory[i].clone(), windows.installation[i]);
            match groups.last_mut() {
                Some(g) if (g.0.clone(), g.1) == key => {
                    g.2 += 1;
                    g.3 += usize::from(windows.validation[i]);
                }
                _ => groups.push((key.0, key.1, 1, usize::from(windows.validation[i]))),
            }
        }
        assert_eq!(groups.len(), 8);
        for (_, _, count, validation) in &groups {
            assert_eq!(
                *validation,
                ((*count as f64) * 0.25).round() as usize,
                "{groups:?}"
            );
        }
        // The validation windows are each group's last.
        for i in 1..windows.len() {
            let same_group = windows.trajectory[i] == windows.trajectory[i - 1]
                && windows.installation[i] == windows.installation[i - 1];
            if same_group && windows.validation[i - 1] {
                assert!(windows.validation[i]);
            }
        }
    }

    #[test]
    fn simulated_windows_are_the_same_bytes_on_one_thread_or_two() {
        let recordings = [weaving("A", 60, 0.0), weaving("B", 60, 1.0)];
        let recordings: Vec<&Recording> = recordings.iter().collect();
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| simulated_windows(&recordings, &grid(), 0.02, 10, 3, 7))
        };
        let (one, two) = (on(1), on(2));
        assert_eq!(one, two);
        assert_eq!(one.trajectory[0], "A");
        assert_eq!(one.trajectory.last().unwrap(), "B");
        // A different seed draws other noise.
        let other = simulated_windows(&recordings, &grid(), 0.02, 10, 3, 8);
        assert_ne!(one.inputs, other.inputs);
        assert_eq!(one.targets, other.targets);
    }
}
