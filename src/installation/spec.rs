//! The spec of an installation study (`kind = "installation"`): the paired recordings,
//! the DVL and reference noise the bound assumes, the calibration windows, the methods
//! (the paper's baseline and least squares, named term sets of the installation model,
//! DCNet models of a paper spec), and the tolerances past which a term counts as not
//! seen. In: a TOML file and `--set` overrides. Out: an [`InstallationSpec`], or every
//! fault placed on its line.

use super::terms::Installation;
use crate::data::paired::{PairedColumns, PairedFiles};
use crate::spec::{Document, Experiment, SpecErrors, load_documents};
use crate::vocab::ErrorModel;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// The value of `kind` that makes a spec an installation study.
pub const KIND: &str = "installation";

/// One term of the installation model, as a spec names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TermName {
    /// One scale for all axes.
    Scale,
    ScalePerAxis,
    Misalignment,
    LeverArm,
    TimeOffset,
    /// One bias per axis.
    Bias,
    /// One bias for all axes.
    BiasScalar,
}

impl TermName {
    pub const ALL: [TermName; 7] = [
        TermName::Scale,
        TermName::ScalePerAxis,
        TermName::Misalignment,
        TermName::LeverArm,
        TermName::TimeOffset,
        TermName::Bias,
        TermName::BiasScalar,
    ];

    /// The term's name in a spec and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            TermName::Scale => "scale",
            TermName::ScalePerAxis => "scale_per_axis",
            TermName::Misalignment => "misalignment",
            TermName::LeverArm => "lever_arm",
            TermName::TimeOffset => "time_offset",
            TermName::Bias => "bias",
            TermName::BiasScalar => "bias_scalar",
        }
    }
}

impl std::str::FromStr for TermName {
    type Err = String;

    fn from_str(name: &str) -> Result<Self, String> {
        TermName::ALL
            .into_iter()
            .find(|term| term.name() == name)
            .ok_or_else(|| {
                let names: Vec<&str> = TermName::ALL.iter().map(|term| term.name()).collect();
                format!("{name:?} is not a term: give {}", names.join(", "))
            })
    }
}

/// What is wrong with a list of terms, each with the index it is at (`None` for the
/// list): empty, a term listed twice, or a term with its per-axis form.
pub fn term_list_faults(terms: &[TermName]) -> Vec<(Option<usize>, String)> {
    let mut faults = Vec::new();
    if terms.is_empty() {
        faults.push((None, "is empty: name at least one term (scale, scale_per_axis, misalignment, lever_arm, time_offset, bias, bias_scalar)".to_string()));
    }
    let has = |term| terms.contains(&term);
    if has(TermName::Scale) && has(TermName::ScalePerAxis) {
        faults.push((None, "lists scale and scale_per_axis: give one".to_string()));
    }
    if has(TermName::Bias) && has(TermName::BiasScalar) {
        faults.push((None, "lists bias and bias_scalar: give one".to_string()));
    }
    let mut seen = HashSet::new();
    for (j, term) in terms.iter().enumerate() {
        if !seen.insert(term) {
            faults.push((Some(j), format!("{:?} is listed twice", term.name())));
        }
    }
    faults
}

/// The file as written.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InstallationFile {
    pub name: String,
    pub kind: String,
    pub recordings: RecordingsFile,
    pub noise: NoiseFile,
    pub calibration: StudyCalibrationFile,
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
pub struct StudyCalibrationFile {
    /// Calibration windows: the first w seconds of the calibration trajectory; a w at
    /// least its length takes all of it.
    pub window_s: Vec<f64>,
    /// The paper's methods: "baseline", "EM1" to "EM5" (least squares), "dcnet".
    pub methods: Vec<String>,
    /// Named term sets of the installation model, fitted by nonlinear least squares.
    #[serde(default)]
    pub models: Vec<TermSetFile>,
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
    /// [`Tolerances::default`](super::bound::Tolerances) in the file's units.
    fn default() -> Self {
        ObservabilityFile::from(super::bound::Tolerances::default())
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

/// `[learned]`: DCNets that learn the installation's terms, trained fold by fold on the
/// trajectories outside the fold (simulated installations over their reference, or
/// their real DVL), and scored on the trajectories inside it.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LearnedFile {
    /// The terms the network outputs.
    pub terms: Vec<TermName>,
    /// Folds over the trajectories, round robin in spec order.
    pub folds: usize,
    /// What the models train on: "simulated" installations, the "vehicle"'s own DVL.
    #[serde(default = "LearnedFile::default_sources")]
    pub sources: Vec<String>,
    /// Samples per network window.
    #[serde(default = "LearnedFile::default_window")]
    pub window_samples: usize,
    /// A training window starts every this many samples.
    #[serde(default = "LearnedFile::default_stride")]
    pub stride_samples: usize,
    /// The share of each trajectory's (and installation's) windows, its last ones, kept
    /// for validation.
    #[serde(default = "LearnedFile::default_validation")]
    pub validation_fraction: f64,
    #[serde(default = "LearnedFile::default_seed")]
    pub seed: u64,
    pub simulation: SimulationGrid,
    #[serde(default)]
    pub model: crate::spec::file::ModelFile,
    #[serde(default)]
    pub training: crate::spec::file::TrainingFile,
}

impl LearnedFile {
    fn default_sources() -> Vec<String> {
        vec!["simulated".into(), "vehicle".into()]
    }
    fn default_window() -> usize {
        10
    }
    fn default_stride() -> usize {
        5
    }
    fn default_validation() -> f64 {
        0.2
    }
    fn default_seed() -> u64 {
        2024
    }
}

/// The installations a model trains on: every combination of the lists, in the spec's
/// units (lever arm in m, time offset in s, misalignment in degrees, scale in %, bias in
/// cm/s, one value for the three axes of a scale or a bias).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationGrid {
    pub lever_arm_x_m: Vec<f64>,
    pub lever_arm_y_m: Vec<f64>,
    pub lever_arm_z_m: Vec<f64>,
    pub time_offset_s: Vec<f64>,
    pub misalignment_z_deg: Vec<f64>,
    pub scale_pct: Vec<f64>,
    pub bias_cm_s: Vec<f64>,
}

impl SimulationGrid {
    /// Every combination, the lever arm's x outermost and the bias innermost.
    pub fn installations(&self) -> Vec<Installation> {
        let mut all = Vec::new();
        for &x in &self.lever_arm_x_m {
            for &y in &self.lever_arm_y_m {
                for &z in &self.lever_arm_z_m {
                    for &time_offset_s in &self.time_offset_s {
                        for &yaw_deg in &self.misalignment_z_deg {
                            for &scale_pct in &self.scale_pct {
                                for &bias_cm_s in &self.bias_cm_s {
                                    all.push(Installation {
                                        scale: [scale_pct / 100.0; 3],
                                        misalignment_rad: [0.0, 0.0, yaw_deg.to_radians()],
                                        lever_arm_m: [x, y, z],
                                        time_offset_s,
                                        bias_m_s: [bias_cm_s / 100.0; 3],
                                    });
                                }
                            }
                        }
                    }
                }
            }
        }
        all
    }
}

/// How the labels of `[learned]`'s methods begin.
pub const LEARNED_LABEL: &str = "DCNet trained on ";

/// What a learned model trains on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    /// Simulated installations over the reference of the trajectories outside the fold.
    Simulated,
    /// The real DVL and reference of the trajectories outside the fold.
    Vehicle,
}

impl Source {
    pub fn name(self) -> &'static str {
        match self {
            Source::Simulated => "simulated",
            Source::Vehicle => "vehicle",
        }
    }
}

/// `[learned]`, checked.
#[derive(Debug, Clone)]
pub struct LearnedSpec {
    pub terms: Vec<TermName>,
    pub folds: usize,
    pub sources: Vec<Source>,
    pub window_samples: usize,
    pub stride_samples: usize,
    pub validation_fraction: f64,
    pub seed: u64,
    pub simulation: SimulationGrid,
    pub model: crate::spec::ModelSpec,
    pub training: crate::spec::TrainingSpec,
}

impl LearnedSpec {
    /// The fold of the trajectory at `index`: round robin in spec order.
    pub fn fold_of(&self, index: usize) -> usize {
        index % self.folds
    }
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
    /// The paper spec's DCNet for an error model.
    Dcnet(ErrorModel),
    /// `[learned]`'s DCNet trained on a source, replicate `replicate` (of
    /// `learned.training.replicates`), the model of the calibration trajectory's fold.
    Learned { source: Source, replicate: usize },
}

impl Method {
    /// How the method is labelled in tables and figures.
    pub fn label(&self) -> String {
        match self {
            Method::Baseline => "baseline".into(),
            Method::LeastSquares(model) => format!("least squares {model}"),
            Method::Installation { name, .. } => format!("installation {name}"),
            Method::Dcnet(model) => format!("DCNet {model}"),
            Method::Learned { source, replicate } => {
                let on = match source {
                    Source::Simulated => "simulation",
                    Source::Vehicle => "the vehicle",
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
        check_learned(
            learned,
            file.recordings.trajectories.len(),
            &mut methods,
            &mut fault,
        )
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
        observability: o.clone(),
        dcnet_spec,
        learned,
        resolved_toml: document.resolved_toml.clone(),
    }
}

/// Checks `[learned]` for a study of `trajectories` trajectories; its methods are added
/// to `methods`.
fn check_learned(
    learned: &LearnedFile,
    trajectories: usize,
    methods: &mut Vec<Method>,
    fault: &mut dyn FnMut(String, String),
) -> LearnedSpec {
    for (at, message) in term_list_faults(&learned.terms) {
        let key = match at {
            Some(j) => format!("learned.terms[{j}]"),
            None => "learned.terms".to_string(),
        };
        fault(key, message);
    }
    if learned.folds < 2 || 2 * learned.folds > trajectories {
        fault(
            "learned.folds".into(),
            format!(
                "{} must be at least 2, and leave at least two trajectories in every fold (one to calibrate on, another to score on): at most {} for {trajectories} trajectories",
                learned.folds,
                trajectories / 2
            ),
        );
    }
    let mut sources = Vec::new();
    for (i, name) in learned.sources.iter().enumerate() {
        let key = format!("learned.sources[{i}]");
        match name.as_str() {
            "simulated" if !sources.contains(&Source::Simulated) => sources.push(Source::Simulated),
            "vehicle" if !sources.contains(&Source::Vehicle) => sources.push(Source::Vehicle),
            "simulated" | "vehicle" => fault(key, format!("{name:?} is listed twice")),
            other => fault(
                key,
                format!("{other:?} is not a source: give \"simulated\" or \"vehicle\""),
            ),
        }
    }
    if learned.sources.is_empty() {
        fault(
            "learned.sources".into(),
            "is empty: give \"simulated\", \"vehicle\" or both".into(),
        );
    }
    if learned.window_samples < 4 {
        fault(
            "learned.window_samples".into(),
            format!(
                "{} must be at least 4 (the 2D head's three convolutions)",
                learned.window_samples
            ),
        );
    }
    if learned.stride_samples == 0 {
        fault(
            "learned.stride_samples".into(),
            "0 must be at least 1".into(),
        );
    }
    let v = learned.validation_fraction;
    if !(0.0..1.0).contains(&v) {
        fault(
            "learned.validation_fraction".into(),
            format!("{v} must lie in [0, 1)"),
        );
    }
    let grid = &learned.simulation;
    for (key, values) in [
        ("lever_arm_x_m", &grid.lever_arm_x_m),
        ("lever_arm_y_m", &grid.lever_arm_y_m),
        ("lever_arm_z_m", &grid.lever_arm_z_m),
        ("time_offset_s", &grid.time_offset_s),
        ("misalignment_z_deg", &grid.misalignment_z_deg),
        ("scale_pct", &grid.scale_pct),
        ("bias_cm_s", &grid.bias_cm_s),
    ] {
        if values.is_empty() {
            fault(
                format!("learned.simulation.{key}"),
                "is empty: give at least one value".into(),
            );
        }
        for (i, value) in values.iter().enumerate() {
            if !value.is_finite() {
                fault(
                    format!("learned.simulation.{key}[{i}]"),
                    format!("{value} must be a finite number"),
                );
            }
        }
    }
    let (model, training, model_faults) = crate::spec::check::check_model_and_training(
        learned.model.clone(),
        learned.training.clone(),
        learned.window_samples.max(4),
        "learned.",
    );
    for (key, message) in model_faults {
        fault(key, message);
    }
    if training
        .learning_rates
        .iter()
        .any(|&rate| rate != training.learning_rates[0])
    {
        fault(
            "learned.training.learning_rate".into(),
            "is a table of error models: give one number, the learned model's".into(),
        );
    }
    for &source in &sources {
        methods.extend(
            (0..training.replicates.max(1)).map(|replicate| Method::Learned { source, replicate }),
        );
    }
    LearnedSpec {
        terms: learned.terms.clone(),
        folds: learned.folds.max(1),
        sources,
        window_samples: learned.window_samples,
        stride_samples: learned.stride_samples.max(1),
        validation_fraction: v,
        seed: learned.seed,
        simulation: grid.clone(),
        model,
        training,
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::installation::bound::Tolerances;

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
        assert_eq!(file.tolerances(), Tolerances::default());
    }
}
