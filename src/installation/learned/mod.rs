//! What `[learned]` trains and how its models calibrate: for each fold and source, the
//! training windows of the trajectories outside the fold (simulated installations over
//! their reference, or their real DVL), and the terms a trained model reads from a
//! calibration window of a trajectory inside it (the mean of its outputs over the
//! window's consecutive network windows, as the paper's DCNet calibrates).
//! In: the study's spec and recordings. Out: [`InstallationWindows`] to train on, and an
//! [`Installation`] per calibration window.
//!
//! No trajectory that a fold's model is scored on is seen in its training, as
//! simulation or as reality: both sources read only the trajectories outside the fold.

pub mod spec;
pub mod simulate;
pub mod network;

use crate::installation::learned::network::{batch_of, closed_loop_loss, installation_of};
use crate::installation::learned::simulate::{InstallationWindows, simulated_windows, windows_of};
use crate::installation::learned::spec::{LearnedSpec, TrainingSource};
use crate::installation::study::Recording;
use crate::installation::study::spec::StudySpec;
use crate::installation::terms::names::term_set;
use crate::installation::terms::{Installation, TermSet};
use crate::model::{Dcnet, Settings};
use crate::train::Windowed;
use burn::tensor::{Device, Tensor};
use rand_chacha::ChaCha8Rng;
use std::ops::Range;

/// What `[learned]` asks that the recordings (each trajectory's name and time stamps)
/// cannot give, as `(key, message)`: a simulated time offset beyond the reach of the
/// loss (it reads the reference at t + τ within the window's margin), or a window, with
/// its margins, longer than a trajectory. `validate` and `run` refuse it alike.
pub fn beyond_the_recordings(
    learned: &LearnedSpec,
    recordings: &[(&str, &[f64])],
) -> Option<(String, String)> {
    use crate::data::paired::sample_interval;
    use crate::installation::learned::simulate::REFERENCE_MARGIN;
    let span = learned.window_samples + 2 * REFERENCE_MARGIN;
    if let Some((name, time_s)) = recordings.iter().find(|(_, time_s)| time_s.len() < span) {
        return Some((
            "learned.window_samples".into(),
            format!(
                "{} samples, with the {REFERENCE_MARGIN} of margin each side, are longer than trajectory {name:?}'s {}: give a shorter window",
                learned.window_samples,
                time_s.len()
            ),
        ));
    }
    let step_s = recordings
        .iter()
        .map(|(_, time_s)| sample_interval(time_s))
        .fold(f64::INFINITY, f64::min);
    let reach_s = REFERENCE_MARGIN as f64 * step_s;
    let tau = learned
        .simulation
        .time_offset_s
        .iter()
        .find(|t| t.abs() > reach_s)?;
    learned.sources.contains(&TrainingSource::Simulated).then(|| {
        (
            "learned.simulation.time_offset_s".into(),
            format!(
                "{tau} s is beyond the {reach_s} s at which the loss can read the reference ({REFERENCE_MARGIN} samples of {step_s} s): simulate time offsets within it"
            ),
        )
    })
}

/// The indices of the recordings that train the model of `fold`: those outside it.
pub fn training_recordings(learned: &LearnedSpec, count: usize, fold: usize) -> Vec<usize> {
    (0..count).filter(|&i| learned.fold_of(i) != fold).collect()
}

/// The windows the model of `fold` trains on, from `source`, with their validation
/// share marked.
pub fn training_windows(
    spec: &StudySpec,
    learned: &LearnedSpec,
    recordings: &[&Recording],
    fold: usize,
    source: TrainingSource,
) -> InstallationWindows {
    let outside: Vec<&Recording> = training_recordings(learned, recordings.len(), fold)
        .into_iter()
        .map(|i| recordings[i])
        .collect();
    let (window, stride) = (learned.window_samples, learned.stride_samples);
    let windows = match source {
        TrainingSource::Simulated => simulated_windows(
            &outside,
            &learned.simulation,
            spec.dvl_noise_m_s,
            window,
            stride,
            learned.seed,
        ),
        TrainingSource::Vehicle => {
            let mut all = InstallationWindows::default();
            for recording in outside {
                let dvl: Vec<_> = recording
                    .recording
                    .dvl_m_s
                    .iter()
                    .copied()
                    .map(Some)
                    .collect();
                all.extend(windows_of(recording, &dvl, window, stride, 0));
            }
            all
        }
    };
    windows.with_validation(learned.validation_fraction)
}

/// Training windows with the terms the network outputs: what [`crate::train`] trains on.
pub struct LearnedWindows {
    pub windows: InstallationWindows,
    pub terms: TermSet,
}

impl Windowed for LearnedWindows {
    fn len(&self) -> usize {
        self.windows.len()
    }

    fn is_validation(&self, window: usize) -> bool {
        self.windows.validation[window]
    }

    fn loss(
        &self,
        model: &Dcnet,
        indices: &[usize],
        settings: &Settings,
        device: &Device,
        dropout_rng: Option<&mut ChaCha8Rng>,
    ) -> Tensor<1> {
        let batch = batch_of(&self.windows, indices, settings.kernel, device);
        let outputs = model.forward(&batch.windows, settings, dropout_rng);
        closed_loop_loss(outputs, &self.terms, &batch)
    }
}

/// The terms `model` reads from samples `range` of `recording` with its real DVL: the mean
/// of its outputs over the range's consecutive network windows; `None` where the range
/// holds none (a window needs the reference a few samples either side).
pub fn estimate(
    model: &Dcnet,
    learned: &LearnedSpec,
    recording: &Recording,
    range: Range<usize>,
    device: &Device,
) -> Option<Installation> {
    let dvl: Vec<_> = (0..recording.recording.dvl_m_s.len())
        .map(|i| range.contains(&i).then_some(recording.recording.dvl_m_s[i]))
        .collect();
    let window = learned.window_samples;
    let windows = windows_of(recording, &dvl, window, window, 0);
    if windows.is_empty() {
        return None;
    }
    let settings = Settings::from(&learned.model);
    let indices: Vec<usize> = (0..windows.len()).collect();
    let batch = batch_of(&windows, &indices, settings.kernel, device);
    let outputs = model.forward(&batch.windows, &settings, None);
    let mean: Vec<f32> = outputs
        .mean_dim(0)
        .into_data()
        .try_to_vec()
        .expect("f32 outputs");
    Some(installation_of(&term_set(&learned.terms), &mean))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::installation::learned::simulate::tests::weaving;

    /// A learned spec of `folds` folds over the test recordings.
    pub(crate) fn learned(folds: usize) -> LearnedSpec {
        let file: crate::installation::learned::spec::LearnedFile = toml::from_str(
            r#"
            terms = ["lever_arm", "time_offset"]
            folds = 2
            window_samples = 10
            stride_samples = 5
            [simulation]
            lever_arm_x_m = [-2.0, -1.0]
            lever_arm_y_m = [0.0]
            lever_arm_z_m = [0.5]
            time_offset_s = [0.0, 1.0]
            misalignment_z_deg = [0.0]
            scale_pct = [0.0]
            bias_cm_s = [0.0]
            "#,
        )
        .unwrap();
        let (model, training, faults) = crate::spec::check::check_model_and_training(
            file.model.clone(),
            file.training.clone(),
            10,
            "learned.",
        );
        assert!(faults.is_empty(), "{faults:?}");
        LearnedSpec {
            terms: file.terms,
            folds,
            sources: vec![TrainingSource::Simulated, TrainingSource::Vehicle],
            window_samples: 10,
            stride_samples: 5,
            validation_fraction: 0.2,
            seed: 1,
            simulation: file.simulation,
            model,
            training,
        }
    }

    /// No window a fold's model trains on comes from a trajectory inside the fold, from
    /// either source; every trajectory outside it gives some.
    #[test]
    fn a_folds_training_reads_only_the_trajectories_outside_it() {
        let recordings: Vec<Recording> = (0..5)
            .map(|i| {
                let mut recording = weaving(&format!("T{i}"), 80, i as f64);
                // Its own DVL, so that the vehicle source has one to read.
                recording.recording.dvl_m_s = recording.reference.velocity_body_m_s.clone();
                recording
            })
            .collect();
        let refs: Vec<&Recording> = recordings.iter().collect();
        let learned = learned(2);
        let spec = crate::installation::study::spec::tests::spec_with(learned.clone());
        for fold in 0..2 {
            let inside: Vec<String> = (0..5)
                .filter(|&i| learned.fold_of(i) == fold)
                .map(|i| format!("T{i}"))
                .collect();
            for source in [TrainingSource::Simulated, TrainingSource::Vehicle] {
                let windows = training_windows(&spec, &learned, &refs, fold, source);
                assert!(!windows.is_empty());
                for name in &windows.trajectory {
                    assert!(
                        !inside.contains(name),
                        "fold {fold} {source:?} trains on {name}"
                    );
                }
                for i in training_recordings(&learned, 5, fold) {
                    assert!(windows.trajectory.contains(&format!("T{i}")));
                }
            }
        }
    }
}
