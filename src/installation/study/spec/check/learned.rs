//! Checks `[learned]`. In: the table as written ([`LearnedFile`]: the terms the network
//! outputs, its folds, sources, windows, seed, the simulated installations, and its
//! `[learned.model]` and `[learned.training]`, checked by the paper's rules under
//! `learned.`) and the count of trajectories. Out: the [`LearnedSpec`].

use crate::installation::learned::spec::{
    LearnedFile, LearnedSpec, SimulationGrid, TrainingSource,
};
use crate::installation::study::spec::check::check_terms;
use crate::spec::check::{Faults, check_model_and_training};
use crate::spec::file::{ModelFile, TrainingFile};
use crate::spec::{ModelSpec, TrainingSpec};

/// Checks `[learned]` for a study of `trajectories` trajectories, each fault at its key.
pub(in crate::installation::study::spec) fn check_learned(
    learned: LearnedFile,
    trajectories: usize,
    faults: &mut Faults,
) -> LearnedSpec {
    let LearnedFile {
        terms,
        folds,
        sources,
        window_samples,
        stride_samples,
        validation_fraction,
        seed,
        simulation,
        model,
        training,
    } = learned;
    check_terms("learned.terms", &terms, faults);
    if folds < 2 || 2 * folds > trajectories {
        faults.add(
            "learned.folds",
            format!(
                "{folds} must be at least 2, and leave at least two trajectories in every fold (one to calibrate on, another to score on): at most {} for {trajectories} trajectories",
                trajectories / 2
            ),
        );
    }
    let sources = check_sources(&sources, faults);
    check_windows(window_samples, stride_samples, validation_fraction, faults);
    let simulation = check_simulation(simulation, faults);
    let (model, training) = check_network(model, training, window_samples, faults);
    LearnedSpec {
        terms,
        folds: folds.max(1),
        sources,
        window_samples,
        stride_samples: stride_samples.max(1),
        validation_fraction,
        seed,
        simulation,
        model,
        training,
    }
}

/// `learned.sources`: "simulated", "vehicle" or both, each once.
fn check_sources(names: &[String], faults: &mut Faults) -> Vec<TrainingSource> {
    let mut sources = Vec::new();
    for (i, name) in names.iter().enumerate() {
        let key = format!("learned.sources[{i}]");
        match name.as_str() {
            "simulated" if !sources.contains(&TrainingSource::Simulated) => {
                sources.push(TrainingSource::Simulated)
            }
            "vehicle" if !sources.contains(&TrainingSource::Vehicle) => {
                sources.push(TrainingSource::Vehicle)
            }
            "simulated" | "vehicle" => faults.add(key, format!("{name:?} is listed twice")),
            other => faults.add(
                key,
                format!("{other:?} is not a source: give \"simulated\" or \"vehicle\""),
            ),
        }
    }
    if names.is_empty() {
        faults.add(
            "learned.sources",
            "is empty: give \"simulated\", \"vehicle\" or both",
        );
    }
    sources
}

/// The network's windows: at least 4 samples (the 2D head's three convolutions), a
/// stride of at least 1, a validation share in [0, 1).
fn check_windows(
    window_samples: usize,
    stride_samples: usize,
    validation_fraction: f64,
    faults: &mut Faults,
) {
    if window_samples < 4 {
        faults.add(
            "learned.window_samples",
            format!("{window_samples} must be at least 4 (the 2D head's three convolutions)"),
        );
    }
    if stride_samples == 0 {
        faults.add("learned.stride_samples", "0 must be at least 1");
    }
    if !(0.0..1.0).contains(&validation_fraction) {
        faults.add(
            "learned.validation_fraction",
            format!("{validation_fraction} must lie in [0, 1)"),
        );
    }
}

/// `[learned.simulation]`: every list of at least one finite value, none beyond what
/// an installation is off by (a lever arm of 1e300 m once ran to a failed training).
fn check_simulation(simulation: SimulationGrid, faults: &mut Faults) -> SimulationGrid {
    let SimulationGrid {
        lever_arm_x_m,
        lever_arm_y_m,
        lever_arm_z_m,
        time_offset_s,
        misalignment_z_deg,
        scale_pct,
        bias_cm_s,
    } = &simulation;
    use crate::data::paired::MAX_DVL_SPEED_M_S;
    use crate::installation::estimate::fit::{MAX_LEVER_ARM_M, MAX_SCALE};
    let lever = (MAX_LEVER_ARM_M, "m, the largest lever arm a fit may find");
    for (key, values, (most, what)) in [
        ("lever_arm_x_m", lever_arm_x_m, lever),
        ("lever_arm_y_m", lever_arm_y_m, lever),
        ("lever_arm_z_m", lever_arm_z_m, lever),
        // Checked against the recordings' reach (`beyond_the_recordings`).
        ("time_offset_s", time_offset_s, (f64::INFINITY, "s")),
        (
            "misalignment_z_deg",
            misalignment_z_deg,
            (180.0, "°, half a turn"),
        ),
        (
            "scale_pct",
            scale_pct,
            (100.0 * MAX_SCALE, "%, the largest scale error a DVL has"),
        ),
        (
            "bias_cm_s",
            bias_cm_s,
            (100.0 * MAX_DVL_SPEED_M_S, "cm/s, a vehicle's top speed"),
        ),
    ] {
        if values.is_empty() {
            faults.add(
                format!("learned.simulation.{key}"),
                "is empty: give at least one value",
            );
        }
        for (i, value) in values.iter().enumerate() {
            if !value.is_finite() {
                faults.add(
                    format!("learned.simulation.{key}[{i}]"),
                    format!("{value} must be a finite number"),
                );
            } else if value.abs() > most {
                faults.add(
                    format!("learned.simulation.{key}[{i}]"),
                    format!("{} is beyond ±{most} {what}", crate::Shown(*value)),
                );
            }
        }
    }
    simulation
}

/// `[learned.model]` and `[learned.training]` by the paper's rules, for windows of
/// `window_samples` (at least 4), and one learning rate, not a table of error models.
fn check_network(
    model: ModelFile,
    training: TrainingFile,
    window_samples: usize,
    faults: &mut Faults,
) -> (ModelSpec, TrainingSpec) {
    let (model, training, model_faults) =
        check_model_and_training(model, training, window_samples.max(4), "learned.");
    // The paper's rules check a learning rate per error model; the learned model has
    // one, so its fault is said once, at its own key.
    let rate = "learned.training.learning_rate";
    let mut rate_said = false;
    for (key, message) in model_faults {
        if key.starts_with(&format!("{rate}.")) {
            if !std::mem::replace(&mut rate_said, true) {
                faults.add(rate, message);
            }
        } else {
            faults.add(key, message);
        }
    }
    if training
        .learning_rates
        .iter()
        .any(|&rate| rate != training.learning_rates[0])
    {
        faults.add(
            "learned.training.learning_rate",
            "is a table of error models: give one number, the learned model's",
        );
    }
    (model, training)
}
