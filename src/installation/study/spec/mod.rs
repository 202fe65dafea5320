//! The spec of an installation study (`kind = "installation"`): the paired recordings,
//! the DVL and reference noise the bound assumes, the calibration windows, the methods
//! (the paper's baseline and least squares, named term sets of the installation model,
//! DCNet models of a paper spec), and the tolerances past which a term counts as not
//! seen. In: a TOML file and `--set` overrides. Out: an [`StudySpec`], or every
//! fault placed on its line.
//!
//! The rooms, in the order a spec passes through them, as the paper's spec has them:
//! [`mod@file`] holds the serde types read from TOML (with `[calibration.kalman]` in
//! [`filter_spec`](crate::installation::study::spec::kalman) and `[learned]` in
//! [`learned_spec`](crate::installation::learned::spec)); this module holds the checked
//! types and `check`, which destructures the whole file and hands each section to its
//! check in [`mod@check`], one file a section.

pub mod file;
pub mod check;
pub mod kalman;

pub use check::kalman::default_filter_settings;
pub use file::{
    DcnetModelsFile, NoiseFile, ObservabilityFile, PairedTrajectoryFile, RecordingsFile,
    StudyCalibrationFile, StudyFile, TermSetFile,
};

use crate::data::fixes::FixSimulation;
use crate::data::paired::Source;
use crate::installation::estimate::bound::Noise;
use crate::installation::estimate::clock::ClockSearch;
use crate::installation::estimate::filter::FilterSettings;
use crate::installation::learned::spec::{LEARNED_LABEL, LearnedSpec, TrainingSource};
use crate::installation::terms::names::TermName;
use crate::spec::check::{Faults, is_folder_name};
use crate::spec::{Document, Experiment, MAX_NAME_CHARS, SpecErrors, load_documents};
use crate::vocab::ErrorModel;
use check::calibration::check_calibration;
use check::dcnet::check_dcnet;
use check::learned::check_learned;
use check::noise::check_noise;
use check::observability::check_observability;
use check::recordings::check_recordings;
use std::path::{Path, PathBuf};

/// The value of `kind` that makes a spec an installation study.
pub const KIND: &str = "installation";

/// The model of a method of the study: how the terms of a calibration window are
/// estimated. Its label is the model of the study's methods (`study::method`), which
/// add how it is calibrated (alone or jointly) and with which clock it is scored.
#[derive(Debug, Clone, PartialEq)]
pub enum Model {
    /// The paper's baseline: a scalar scale from speed ratios.
    Baseline,
    /// The paper's closed-form least squares of an error model.
    LeastSquares(ErrorModel),
    /// A named term set of the installation model, by nonlinear least squares.
    Installation { name: String, terms: Vec<TermName> },
    /// The same, by the extended Kalman filter.
    Filter { name: String, terms: Vec<TermName> },
    /// The paper spec's DCNet for an error model.
    Dcnet(ErrorModel),
    /// The installation fitted to fixes simulated from the calibration trajectory's
    /// positions (`[calibration.fixes]`), seeded by the trajectory's name and the seed.
    Fixes {
        simulation: FixSimulation,
        seed: u64,
    },
    /// `[learned]`'s DCNet trained on a source, replicate `replicate` (of
    /// `learned.training.replicates`), the model of the calibration trajectory's fold.
    Learned {
        source: TrainingSource,
        replicate: usize,
    },
}

impl Model {
    /// How the model is labelled in tables and figures, alone or before its variant.
    pub fn label(&self) -> String {
        match self {
            Model::Baseline => "baseline".into(),
            Model::LeastSquares(model) => format!("least squares {model}"),
            Model::Installation { name, .. } => format!("installation {name}"),
            Model::Filter { name, .. } => format!("Kalman filter {name}"),
            Model::Dcnet(model) => format!("DCNet {model}"),
            Model::Fixes { .. } => FIXES_LABEL.into(),
            Model::Learned { source, replicate } => {
                let on = match source {
                    TrainingSource::Simulated => "simulation",
                    TrainingSource::Vehicle => "the vehicle",
                };
                match replicate {
                    0 => format!("{LEARNED_LABEL}{on}"),
                    r => format!("{LEARNED_LABEL}{on}, replicate {}", r + 1),
                }
            }
        }
    }
}

/// The label of the method calibrated against fixes.
pub const FIXES_LABEL: &str = "installation from fixes";

/// `[calibration.dive]`, checked: the dive's terms and the search for its clock, and
/// the windows (the first w seconds of a scored trajectory, increasing) they are found
/// from.
#[derive(Debug, Clone, PartialEq)]
pub struct DiveSpec {
    pub search: ClockSearch,
    pub windows_s: Vec<f64>,
}

/// The checked spec.
#[derive(Debug, Clone)]
pub struct StudySpec {
    pub name: String,
    /// Each trajectory's name and where its recording is.
    pub trajectories: Vec<(String, Source)>,
    pub dvl_noise_m_s: f64,
    pub reference_noise_m_s: f64,
    /// In increasing order.
    pub windows_s: Vec<f64>,
    /// The model of each method, in the order of the tables.
    pub methods: Vec<Model>,
    /// The extended Kalman filter's prior and random walk.
    pub filter: FilterSettings,
    /// The calibration time's tolerance, a fraction (0.1 for 10 %).
    pub time_tolerance: f64,
    pub observability: ObservabilityFile,
    /// The paper spec whose DCNet models are used, when `dcnet` is a method.
    pub dcnet_spec: Option<PathBuf>,
    /// `[learned]`, when the spec has it.
    pub learned: Option<LearnedSpec>,
    /// `[calibration.dive]`, when the spec has it: every method's terms are also scored
    /// with the dive's terms found again on each scored trajectory.
    pub dive: Option<DiveSpec>,
    /// The spec with its overrides, as TOML.
    pub resolved_toml: String,
}

impl StudySpec {
    /// The noise the bound assumes on each velocity component: the DVL's and the
    /// reference's.
    pub fn noise(&self) -> Noise {
        Noise {
            dvl_m_s: self.dvl_noise_m_s,
            reference_m_s: self.reference_noise_m_s,
        }
    }
}

/// Reads and checks the installation spec at `path`, and each point of its `[sweep]`.
pub fn load_experiment(
    path: &Path,
    overrides: &[String],
) -> Result<Experiment<StudySpec>, SpecErrors> {
    load_documents(path, overrides, |document: Document<StudyFile>| {
        check(&document).map_err(|faults| document.faults(faults))
    })
}

/// Reads and checks the installation spec at `path`; the first point of a sweep.
pub fn load(path: &Path, overrides: &[String]) -> Result<StudySpec, SpecErrors> {
    let mut experiment = load_experiment(path, overrides)?;
    Ok(experiment.points.swap_remove(0).spec)
}

/// Checks every value of the document, section by section in the file's order; the
/// faults as (key path, message) pairs.
fn check(document: &Document<StudyFile>) -> Result<StudySpec, Vec<(String, String)>> {
    let mut faults = Faults::default();
    let StudyFile {
        name,
        kind,
        recordings,
        noise,
        calibration,
        observability,
        dcnet,
        learned,
    } = document.value.clone();
    if kind != KIND {
        faults.add("kind", format!("{kind:?} must be {KIND:?} here"));
    }
    // The results folder's rule ('/', '=' and ',' only in a sweep point's name, which
    // the loader gives it).
    if !is_folder_name(&name) {
        faults.add("name", format!("{name:?} must be non-empty, at most {MAX_NAME_CHARS} characters, use only letters, digits, '-', '_' and '.', and not start with '.' (it names the results folder)"));
    }
    let listed = recordings.trajectories.len();
    if calibration.fixes.is_some()
        && recordings
            .columns
            .as_ref()
            .is_none_or(|c| c.position().is_none())
    {
        faults.add(
            "calibration.fixes",
            "fixes are simulated from the recordings' positions: name them in [recordings.columns] (latitude_longitude, or north_east)",
        );
    }
    let trajectories = check_recordings(recordings, &document.folder, &mut faults);
    let (dvl_noise_m_s, reference_noise_m_s) = check_noise(noise, &mut faults);
    let calibration = check_calibration(calibration, &mut faults);
    let mut methods = calibration.methods;
    let dcnet_spec = check_dcnet(
        dcnet,
        calibration.wants_dcnet,
        &document.folder,
        &mut faults,
    );
    if dcnet_spec.is_some() {
        methods.extend(ErrorModel::ALL.map(Model::Dcnet));
    }
    let learned = learned.map(|learned| check_learned(learned, listed, &mut faults));
    if let Some(learned) = &learned {
        for &source in &learned.sources {
            methods.extend(
                (0..learned.training.replicates.max(1))
                    .map(|replicate| Model::Learned { source, replicate }),
            );
        }
    }
    let observability = check_observability(observability, &mut faults);
    if !faults.0.is_empty() {
        return Err(faults.0);
    }
    Ok(StudySpec {
        name,
        trajectories,
        dvl_noise_m_s,
        reference_noise_m_s,
        windows_s: calibration.windows_s,
        methods,
        filter: calibration.filter,
        time_tolerance: calibration.time_tolerance,
        observability,
        dcnet_spec,
        learned,
        dive: calibration.dive,
        resolved_toml: document.resolved_toml.clone(),
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A study of no recordings with `learned`, its noise 2 cm/s: what code that reads
    /// only the spec's settings needs.
    pub(crate) fn spec_with(learned: LearnedSpec) -> StudySpec {
        StudySpec {
            name: "test".into(),
            trajectories: Vec::new(),
            dvl_noise_m_s: 0.02,
            reference_noise_m_s: 0.0,
            windows_s: vec![100.0],
            filter: default_filter_settings(),
            time_tolerance: 0.1,
            methods: learned
                .sources
                .iter()
                .map(|&source| Model::Learned {
                    source,
                    replicate: 0,
                })
                .collect(),
            observability: ObservabilityFile::default(),
            dcnet_spec: None,
            learned: Some(learned),
            dive: None,
            resolved_toml: String::new(),
        }
    }
}
