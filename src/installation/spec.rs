//! The spec of an installation study (`kind = "installation"`): the paired recordings,
//! the DVL and reference noise the bound assumes, the calibration windows, the methods
//! (the paper's baseline and least squares, named term sets of the installation model,
//! DCNet models of a paper spec), and the tolerances past which a term counts as not
//! seen. In: a TOML file and `--set` overrides. Out: an [`InstallationSpec`], or every
//! fault placed on its line.

use super::filter::FilterSettings;
use super::filter_spec::{KalmanFile, check_kalman};
use super::learned_spec::{LEARNED_LABEL, LearnedFile, LearnedSpec, TrainingSource, check_learned};
use super::term_names::{TermName, term_list_faults};
use crate::data::paired::{PairedColumns, PairedFiles};
use crate::spec::{Document, Experiment, SpecErrors, load_documents};
use crate::vocab::ErrorModel;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// The value of `kind` that makes a spec an installation study.
pub const KIND: &str = "installation";

/// The file as written.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InstallationFile {
    pub name: String,
    pub kind: String,
    pub recordings: RecordingsFile,
    pub noise: NoiseFile,
    pub calibration: InstallationCalibrationFile,
    #[serde(default)]
    pub observability: ObservabilityFile,
    pub dcnet: Option<DcnetModelsFile>,
    pub learned: Option<LearnedFile>,
}

#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordingsFile {
    /// The column names, when they are not A-KIT's.
    pub columns: Option<PairedColumns>,
    pub trajectories: Vec<PairedTrajectoryFile>,
}

#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairedTrajectoryFile {
    pub name: String,
    /// The DVL's CSV file, relative to the spec.
    pub dvl: PathBuf,
    /// The reference's CSV file; the DVL's when it holds both.
    pub reference: Option<PathBuf>,
}

#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseFile {
    /// The DVL's white noise per axis, cm/s.
    pub dvl_cm_s: f64,
    /// The reference velocity's white noise per axis, cm/s.
    pub reference_cm_s: f64,
}

#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InstallationCalibrationFile {
    /// Calibration windows: the first w seconds of the calibration trajectory; a w at
    /// least its length takes all of it.
    pub window_s: Vec<f64>,
    /// The paper's methods: "baseline", "EM1" to "EM5" (least squares), "dcnet".
    pub methods: Vec<String>,
    /// Named term sets of the installation model, fitted by nonlinear least squares.
    #[serde(default)]
    pub models: Vec<TermSetFile>,
    /// The models the extended Kalman filter runs too, and its prior.
    #[serde(default)]
    pub kalman: KalmanFile,
    /// A method's calibration time is the shortest window after which its held-out
    /// RMSE stays within this of its value at the longest window, %.
    #[serde(default = "InstallationCalibrationFile::default_time_tolerance_pct")]
    pub time_tolerance_pct: f64,
}

impl InstallationCalibrationFile {
    fn default_time_tolerance_pct() -> f64 {
        10.0
    }
}

#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TermSetFile {
    pub name: String,
    pub terms: Vec<TermName>,
}

/// The standard deviation past which a term counts as not seen (a pair correlated
/// beyond [`CORRELATION_LIMIT`](super::bound::CORRELATION_LIMIT) is not seen either).
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ObservabilityFile {
    pub scale_pct: f64,
    pub misalignment_deg: f64,
    pub lever_arm_m: f64,
    pub time_offset_s: f64,
    pub bias_cm_s: f64,
}

impl Default for ObservabilityFile {
    /// [`DEFAULT_TOLERANCES`](super::bound::DEFAULT_TOLERANCES) in the file's units.
    fn default() -> Self {
        ObservabilityFile::from(super::bound::DEFAULT_TOLERANCES)
    }
}

impl From<super::bound::Tolerances> for ObservabilityFile {
    /// The tolerances in the file's units: the inverse of
    /// [`ObservabilityFile::tolerances`].
    fn from(tolerances: super::bound::Tolerances) -> Self {
        ObservabilityFile {
            scale_pct: tolerances.scale * 100.0,
            misalignment_deg: tolerances.misalignment_rad.to_degrees(),
            lever_arm_m: tolerances.lever_arm_m,
            time_offset_s: tolerances.time_offset_s,
            bias_cm_s: tolerances.bias_m_s * 100.0,
        }
    }
}

impl ObservabilityFile {
    /// The tolerances in the bound's units.
    pub fn tolerances(&self) -> super::bound::Tolerances {
        super::bound::Tolerances {
            scale: self.scale_pct / 100.0,
            misalignment_rad: self.misalignment_deg.to_radians(),
            lever_arm_m: self.lever_arm_m,
            time_offset_s: self.time_offset_s,
            bias_m_s: self.bias_cm_s / 100.0,
        }
    }
}

/// The DCNet models a paper spec trained, applied to these recordings.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DcnetModelsFile {
    /// The paper spec whose models are used, relative to this spec.
    pub spec: PathBuf,
}

/// A method of the study: how the terms of a calibration window are estimated.
#[derive(Debug, Clone, PartialEq)]
pub enum Method {
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
    /// `[learned]`'s DCNet trained on a source, replicate `replicate` (of
    /// `learned.training.replicates`), the model of the calibration trajectory's fold.
    Learned {
        source: TrainingSource,
        replicate: usize,
    },
}

impl Method {
    /// How the method is labelled in tables and figures.
    pub fn label(&self) -> String {
        match self {
            Method::Baseline => "baseline".into(),
            Method::LeastSquares(model) => format!("least squares {model}"),
            Method::Installation { name, .. } => format!("installation {name}"),
            Method::Filter { name, .. } => format!("Kalman filter {name}"),
            Method::Dcnet(model) => format!("DCNet {model}"),
            Method::Learned { source, replicate } => {
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

/// The checked spec.
#[derive(Debug, Clone)]
pub struct InstallationSpec {
    pub name: String,
    /// Each trajectory's name and files.
    pub trajectories: Vec<(String, PairedFiles)>,
    pub columns: PairedColumns,
    pub dvl_noise_m_s: f64,
    pub reference_noise_m_s: f64,
    /// In increasing order.
    pub windows_s: Vec<f64>,
    pub methods: Vec<Method>,
    /// The extended Kalman filter's prior and random walk.
    pub filter: FilterSettings,
    /// The calibration time's tolerance, a fraction (0.1 for 10 %).
    pub time_tolerance: f64,
    pub observability: ObservabilityFile,
    /// The paper spec whose DCNet models are used, when `dcnet` is a method.
    pub dcnet_spec: Option<PathBuf>,
    /// `[learned]`, when the spec has it.
    pub learned: Option<LearnedSpec>,
    /// The spec with its overrides, as TOML.
    pub resolved_toml: String,
}

/// Reads and checks the installation spec at `path`, and each point of its `[sweep]`.
pub fn load_experiment(
    path: &Path,
    overrides: &[String],
) -> Result<Experiment<InstallationSpec>, SpecErrors> {
    load_documents(path, overrides, |document: Document<InstallationFile>| {
        let mut faults = Vec::new();
        let spec = check(&document, &mut faults);
        if faults.is_empty() {
            Ok(spec)
        } else {
            Err(document.faults(faults))
        }
    })
}

/// Reads and checks the installation spec at `path`; the first point of a sweep.
pub fn load(path: &Path, overrides: &[String]) -> Result<InstallationSpec, SpecErrors> {
    let mut experiment = load_experiment(path, overrides)?;
    Ok(experiment.points.swap_remove(0).spec)
}

fn check(
    document: &Document<InstallationFile>,
    faults: &mut Vec<(String, String)>,
) -> InstallationSpec {
    let file = &document.value;
    let mut fault = |key: String, message: String| faults.push((key, message));
    if file.kind != KIND {
        fault(
            "kind".into(),
            format!("{:?} must be {KIND:?} here", file.kind),
        );
    }
    // The results folder's rule ('/', '=' and ',' only in a sweep point's name, which
    // the loader gives it).
    if !crate::spec::check::is_folder_name(&file.name) {
        fault(
            "name".into(),
            format!(
                "{:?} must be non-empty, at most {} characters, use only letters, digits, '-', '_' and '.', and not start with '.' (it names the results folder)",
                file.name,
                crate::spec::MAX_NAME_CHARS
            ),
        );
    }

    let mut names = HashSet::new();
    let mut trajectories = Vec::new();
    for (i, trajectory) in file.recordings.trajectories.iter().enumerate() {
        if !names.insert(trajectory.name.as_str()) {
            fault(
                format!("recordings.trajectories[{i}].name"),
                format!("{:?} is defined twice", trajectory.name),
            );
        }
        let dvl = document.folder.join(&trajectory.dvl);
        let reference = trajectory
            .reference
            .as_ref()
            .map_or_else(|| dvl.clone(), |r| document.folder.join(r));
        trajectories.push((trajectory.name.clone(), PairedFiles { dvl, reference }));
    }
    if trajectories.len() < 2 {
        fault(
            "recordings.trajectories".into(),
            format!(
                "has {} trajectories: held-out scores need at least two (one to calibrate on, another to score on)",
                trajectories.len()
            ),
        );
    }

    let noise = &file.noise;
    if !(noise.dvl_cm_s.is_finite() && noise.dvl_cm_s > 0.0) {
        fault(
            "noise.dvl_cm_s".into(),
            format!(
                "{} must be a finite positive number: the bound divides by it",
                noise.dvl_cm_s
            ),
        );
    }
    if !(noise.reference_cm_s.is_finite() && noise.reference_cm_s >= 0.0) {
        fault(
            "noise.reference_cm_s".into(),
            format!(
                "{} must be zero or a finite positive number",
                noise.reference_cm_s
            ),
        );
    }

    let calibration = &file.calibration;
    if calibration.window_s.is_empty() {
        fault("calibration.window_s".into(), "is empty: give at least one window, in seconds (one at least a trajectory's length takes all of it)".into());
    }
    let mut windows_s = Vec::new();
    for (i, &w) in calibration.window_s.iter().enumerate() {
        if !(w.is_finite() && w > 0.0) {
            fault(
                format!("calibration.window_s[{i}]"),
                format!("{w} must be a finite positive number of seconds"),
            );
        } else if windows_s.contains(&w) {
            fault(
                format!("calibration.window_s[{i}]"),
                format!("{w} is listed twice"),
            );
        } else {
            windows_s.push(w);
        }
    }
    windows_s.sort_by(f64::total_cmp);

    let mut methods = Vec::new();
    let mut listed = HashSet::new();
    let mut wants_dcnet = false;
    for (i, method) in calibration.methods.iter().enumerate() {
        let key = format!("calibration.methods[{i}]");
        if !listed.insert(method.as_str()) {
            fault(key, format!("{method:?} is listed twice"));
            continue;
        }
        match method.as_str() {
            "baseline" => methods.push(Method::Baseline),
            "dcnet" => wants_dcnet = true,
            other => match other.parse::<ErrorModel>() {
                Ok(model) => methods.push(Method::LeastSquares(model)),
                Err(_) => fault(
                    key,
                    format!(
                        "{other:?} is not a method: give \"baseline\", \"EM1\" to \"EM5\" (the paper's least squares) or \"dcnet\"; term sets of the installation model go in [[calibration.models]]"
                    ),
                ),
            },
        }
    }
    let mut model_names = HashSet::new();
    for (i, model) in calibration.models.iter().enumerate() {
        let key = format!("calibration.models[{i}]");
        if !model_names.insert(model.name.as_str()) {
            fault(
                format!("{key}.name"),
                format!("{:?} is defined twice", model.name),
            );
        }
        for (at, message) in term_list_faults(&model.terms) {
            let key = match at {
                Some(j) => format!("{key}.terms[{j}]"),
                None => format!("{key}.terms"),
            };
            fault(key, message);
        }
        methods.push(Method::Installation {
            name: model.name.clone(),
            terms: model.terms.clone(),
        });
    }
    let names: Vec<&str> = calibration.models.iter().map(|m| m.name.as_str()).collect();
    let filter = check_kalman(&calibration.kalman, &names, &mut fault);
    for name in &calibration.kalman.models {
        if let Some(model) = calibration.models.iter().find(|m| &m.name == name) {
            methods.push(Method::Filter {
                name: model.name.clone(),
                terms: model.terms.clone(),
            });
        }
    }
    let tolerance_pct = calibration.time_tolerance_pct;
    if !(tolerance_pct.is_finite() && tolerance_pct > 0.0) {
        fault(
            "calibration.time_tolerance_pct".into(),
            format!("{tolerance_pct} must be a finite number above zero"),
        );
    }
    let dcnet_spec = match (&file.dcnet, wants_dcnet) {
        (Some(dcnet), true) => {
            methods.extend(ErrorModel::ALL.map(Method::Dcnet));
            Some(document.folder.join(&dcnet.spec))
        }
        (None, true) => {
            fault("dcnet".into(), "is missing: the method \"dcnet\" needs [dcnet] spec = \"<paper spec>\", whose trained models it applies".into());
            None
        }
        (_, false) => None,
    };

    let learned = file.learned.as_ref().map(|learned| {
        let learned = check_learned(learned, file.recordings.trajectories.len(), &mut fault);
        for &source in &learned.sources {
            methods.extend(
                (0..learned.training.replicates.max(1))
                    .map(|replicate| Method::Learned { source, replicate }),
            );
        }
        learned
    });

    let o = &file.observability;
    for (key, value) in [
        ("scale_pct", o.scale_pct),
        ("misalignment_deg", o.misalignment_deg),
        ("lever_arm_m", o.lever_arm_m),
        ("time_offset_s", o.time_offset_s),
        ("bias_cm_s", o.bias_cm_s),
    ] {
        if !(value.is_finite() && value > 0.0) {
            fault(
                format!("observability.{key}"),
                format!(
                    "{value} must be a finite positive number: a term whose standard deviation is beyond it counts as not seen"
                ),
            );
        }
    }

    InstallationSpec {
        name: file.name.clone(),
        trajectories,
        columns: file
            .recordings
            .columns
            .clone()
            .unwrap_or_else(PairedColumns::akit),
        dvl_noise_m_s: noise.dvl_cm_s / 100.0,
        reference_noise_m_s: noise.reference_cm_s / 100.0,
        windows_s,
        methods,
        filter,
        time_tolerance: tolerance_pct / 100.0,
        observability: o.clone(),
        dcnet_spec,
        learned,
        resolved_toml: document.resolved_toml.clone(),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::installation::bound::DEFAULT_TOLERANCES;

    /// A study of no recordings with `learned`, its noise 2 cm/s: what code that reads
    /// only the spec's settings needs.
    pub(crate) fn spec_with(learned: LearnedSpec) -> InstallationSpec {
        InstallationSpec {
            name: "test".into(),
            trajectories: Vec::new(),
            columns: PairedColumns::akit(),
            dvl_noise_m_s: 0.02,
            reference_noise_m_s: 0.0,
            windows_s: vec![100.0],
            filter: check_kalman(&KalmanFile::default(), &[], &mut |_, _| {}),
            time_tolerance: 0.1,
            methods: learned
                .sources
                .iter()
                .map(|&source| Method::Learned {
                    source,
                    replicate: 0,
                })
                .collect(),
            observability: ObservabilityFile::default(),
            dcnet_spec: None,
            learned: Some(learned),
            resolved_toml: String::new(),
        }
    }

    /// The default `[observability]` is the bound's default tolerances in the file's
    /// units, exactly: the numbers a spec without the table resolves to, and back.
    #[test]
    fn default_observability_is_the_bounds_default_in_file_units() {
        let file = ObservabilityFile::default();
        let in_file_units = [
            file.scale_pct,
            file.misalignment_deg,
            file.lever_arm_m,
            file.time_offset_s,
            file.bias_cm_s,
        ];
        assert_eq!(in_file_units, [0.5, 0.5, 0.1, 0.05, 1.0]);
        assert_eq!(file.tolerances(), DEFAULT_TOLERANCES);
    }
}
