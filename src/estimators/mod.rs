//! Calibration methods behind one trait. An [`Estimator`] takes a calibration window of
//! DVL and GNSS-RTK velocity and returns a [`Correction`] in the form of the measurement
//! model `v_dvl = (1 + k)·v + b`; every error model (EM1–EM5, PAPER-NOTES) is that form
//! with some terms fixed or tied. The protocol runs the list [`lineup`] builds.

mod baseline;
mod dcnet;
mod floor;
mod least_squares;

pub use baseline::Baseline;
pub use dcnet::DcnetEstimator;
pub use floor::Floor;
pub use least_squares::LeastSquares;

use crate::Vec3;
use crate::model::Settings;
use crate::noise::BeamGeometry;
use crate::spec::{Dvl, Spec};
use crate::train::Trained;
use std::fmt;
use std::str::FromStr;

/// Estimated error terms; `apply` undoes them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Correction {
    /// Scale factor per axis, `k` (0.01 for 1 %).
    pub scale: Vec3,
    /// Bias per axis, m/s.
    pub bias_m_s: Vec3,
}

impl Correction {
    pub const NONE: Correction = Correction {
        scale: [0.0; 3],
        bias_m_s: [0.0; 3],
    };

    /// `(v − b) ⊘ (1 + k)`.
    pub fn apply(&self, v: Vec3) -> Vec3 {
        std::array::from_fn(|axis| (v[axis] - self.bias_m_s[axis]) / (1.0 + self.scale[axis]))
    }
}

pub trait Estimator: Send + Sync {
    /// Estimates the terms from matching DVL and GNSS-RTK samples of one window.
    fn estimate(&self, dvl: &[Vec3], gnss: &[Vec3]) -> Correction;
}

/// The structure of the terms being estimated (PAPER-NOTES, "Error models"). Stored
/// by name, "EM1" to "EM5".
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(try_from = "String", into = "String")]
pub enum ErrorModel {
    /// Scalar scale.
    Em1,
    /// Vector scale.
    Em2,
    /// Scalar bias.
    Em3,
    /// Vector bias.
    Em4,
    /// Vector scale and vector bias.
    Em5,
}

impl ErrorModel {
    pub const ALL: [ErrorModel; 5] = [Self::Em1, Self::Em2, Self::Em3, Self::Em4, Self::Em5];

    /// Number of terms the model estimates: 1, 3, 1, 3, 6.
    pub fn term_count(self) -> usize {
        match self {
            Self::Em1 | Self::Em3 => 1,
            Self::Em2 | Self::Em4 => 3,
            Self::Em5 => 6,
        }
    }
}

impl fmt::Display for ErrorModel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "EM{}", *self as usize + 1)
    }
}

impl TryFrom<String> for ErrorModel {
    type Error = String;
    fn try_from(name: String) -> Result<Self, String> {
        name.parse()
    }
}

impl From<ErrorModel> for String {
    fn from(model: ErrorModel) -> String {
        model.to_string()
    }
}

impl FromStr for ErrorModel {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        parse_by_name(&Self::ALL, "error model", s)
    }
}

/// A calibration method. The floor is no method but a bound: it corrects with the
/// true terms, which shows what no calibration can beat.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum EstimatorKind {
    Baseline,
    LeastSquares,
    Dcnet,
    Floor,
}

impl EstimatorKind {
    pub const ALL: [EstimatorKind; 4] =
        [Self::Baseline, Self::LeastSquares, Self::Dcnet, Self::Floor];

    /// Whether the method is run once per error model.
    pub fn takes_error_model(self) -> bool {
        matches!(self, Self::LeastSquares | Self::Dcnet)
    }

    /// How the method is labelled in tables.
    pub fn label(self) -> &'static str {
        match self {
            Self::Baseline => "baseline",
            Self::LeastSquares => "least squares",
            Self::Dcnet => "DCNet",
            Self::Floor => "floor (bound)",
        }
    }
}

impl fmt::Display for EstimatorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Baseline => "baseline",
            Self::LeastSquares => "least_squares",
            Self::Dcnet => "dcnet",
            Self::Floor => "floor",
        })
    }
}

impl FromStr for EstimatorKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        parse_by_name(&Self::ALL, "estimator", s)
    }
}

/// The value of `all` whose name (its `Display`) is `name`.
fn parse_by_name<T: Copy + fmt::Display>(all: &[T], what: &str, name: &str) -> Result<T, String> {
    all.iter()
        .copied()
        .find(|value| value.to_string() == name)
        .ok_or_else(|| {
            let names: Vec<String> = all.iter().map(ToString::to_string).collect();
            format!(
                "unknown {what} {name:?}; expected one of {}",
                names.join(", ")
            )
        })
}

/// A method as the protocol runs it on one DVL.
pub struct Entry {
    pub kind: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    pub estimator: Box<dyn Estimator>,
}

/// Every (estimator kind, error model) the spec asks for, in table order: the kinds as
/// listed, each with every error model when it takes one.
pub fn series(spec: &Spec) -> Vec<(EstimatorKind, Option<ErrorModel>)> {
    let mut series = Vec::new();
    for &kind in &spec.kinds {
        if kind.takes_error_model() {
            series.extend(spec.error_models.iter().map(|&m| (kind, Some(m))));
        } else {
            series.push((kind, None));
        }
    }
    series
}

/// Every (estimator kind, error model) of [`series`], set up for `dvl`. DCNet runs for
/// the error models in `dcnets`, the models that trained.
pub fn lineup(spec: &Spec, dvl: &Dvl, dcnets: &[Trained]) -> Vec<Entry> {
    let geometry = BeamGeometry::janus_x(spec.beam_pitch_deg);
    let mut entries = Vec::new();
    for (kind, error_model) in series(spec) {
        let estimator: Box<dyn Estimator> = match (kind, error_model) {
            (EstimatorKind::Baseline, _) => Box::new(Baseline),
            (EstimatorKind::LeastSquares, Some(model)) => Box::new(LeastSquares(model)),
            (EstimatorKind::Dcnet, Some(model)) => {
                let Some(trained) = dcnets.iter().find(|t| t.error_model == model) else {
                    continue;
                };
                Box::new(DcnetEstimator {
                    model: trained.model.clone(),
                    error_model: model,
                    window: spec.dataset.window,
                    settings: Settings::from(&spec.model),
                    device: spec.training.backend.device(),
                })
            }
            (EstimatorKind::LeastSquares | EstimatorKind::Dcnet, None) => {
                unreachable!("{kind} always has an error model")
            }
            (EstimatorKind::Floor, _) => Box::new(Floor::new(&dvl.errors, &geometry)),
        };
        entries.push(Entry {
            kind,
            error_model,
            estimator,
        });
    }
    entries
}
