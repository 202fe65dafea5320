//! The words every stage shares: a DVL's error terms, the error models, the
//! calibration methods and the corrections they return, the network's activation, burn's backend, why a training
//! ended, and the two phases of the protocol. In: nothing of the crate. Out: plain
//! types that the spec names and every later stage reads, each with the one spelling
//! it has in a spec, a Parquet column and a table.

use crate::Vec3;
use burn::tensor::Device;
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

impl Correction {
    /// The mean of `corrections`' terms, term by term: what an ensemble of models
    /// estimates.
    pub fn mean(corrections: &[Correction]) -> Correction {
        let n = corrections.len() as f64;
        let mean = |term: fn(&Correction) -> Vec3| -> Vec3 {
            std::array::from_fn(|axis| corrections.iter().map(|c| term(c)[axis]).sum::<f64>() / n)
        };
        Correction {
            scale: mean(|c| c.scale),
            bias_m_s: mean(|c| c.bias_m_s),
        }
    }
}

/// The structure of the terms being estimated (docs/paper.md, "Error models"). Stored
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

/// A calibration method, or one of the two limits set beside them. The floor corrects
/// with the true terms: no calibration beats it. The bound is the mean RMSE of an
/// efficient estimator of the terms from the calibration window (the Cramér–Rao
/// bound): no unbiased calibration from that much data beats it. The bound is
/// computed, not run, for every DVL; a spec does not list it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum EstimatorKind {
    Baseline,
    LeastSquares,
    BeamWls,
    /// A Kalman filter of an error model's terms, sample by sample.
    Kalman,
    /// A Kalman filter of the beam model's scale and bias.
    KalmanBeam,
    Dcnet,
    /// The mean of the terms of `training.replicates` DCNets; it runs beside DCNet when
    /// there are several, and a spec does not list it.
    DcnetEnsemble,
    Floor,
    Bound,
}

impl EstimatorKind {
    pub const ALL: [EstimatorKind; 9] = [
        Self::Baseline,
        Self::LeastSquares,
        Self::BeamWls,
        Self::Kalman,
        Self::KalmanBeam,
        Self::Dcnet,
        Self::DcnetEnsemble,
        Self::Floor,
        Self::Bound,
    ];

    /// The kinds a spec lists in `estimators.kinds`: not the ensemble, which runs
    /// whenever DCNet has replicates, nor the bound, which is computed for every DVL.
    pub const LISTED: [EstimatorKind; 7] = [
        Self::Baseline,
        Self::LeastSquares,
        Self::BeamWls,
        Self::Kalman,
        Self::KalmanBeam,
        Self::Dcnet,
        Self::Floor,
    ];

    /// Whether the method is run once per error model.
    pub fn takes_error_model(self) -> bool {
        matches!(
            self,
            Self::LeastSquares | Self::Kalman | Self::Dcnet | Self::DcnetEnsemble
        )
    }

    /// The label of this method with `error_model`: "DCNet EM5", or "baseline".
    pub fn label_with(self, error_model: Option<ErrorModel>) -> String {
        match error_model {
            Some(model) => format!("{} {model}", self.label()),
            None => self.label().to_string(),
        }
    }

    /// How the method is labelled in tables.
    pub fn label(self) -> &'static str {
        match self {
            Self::Baseline => "baseline",
            Self::LeastSquares => "least squares",
            Self::BeamWls => "beam-model WLS",
            Self::Kalman => "Kalman filter",
            Self::KalmanBeam => "beam-model Kalman filter",
            Self::Dcnet => "DCNet",
            Self::DcnetEnsemble => "DCNet ensemble",
            Self::Floor => "floor (true terms)",
            Self::Bound => "information bound",
        }
    }
}

impl fmt::Display for EstimatorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Baseline => "baseline",
            Self::LeastSquares => "least_squares",
            Self::BeamWls => "beam_wls",
            Self::Kalman => "kalman",
            Self::KalmanBeam => "kalman_beam",
            Self::Dcnet => "dcnet",
            Self::DcnetEnsemble => "dcnet_ensemble",
            Self::Floor => "floor",
            Self::Bound => "bound",
        })
    }
}

impl FromStr for EstimatorKind {
    type Err = String;
    /// Any kind a table names; an unknown name is told the kinds a spec may list.
    fn from_str(s: &str) -> Result<Self, String> {
        parse_by_name(&Self::ALL, "estimator", s).map_err(|_| {
            parse_by_name(&Self::LISTED, "estimator", s).expect_err("not among all kinds")
        })
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

/// The activation of the FC batch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Activation {
    Tanh,
    LeakyRelu,
}

impl fmt::Display for Activation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Tanh => "tanh",
            Self::LeakyRelu => "leaky_relu",
        })
    }
}

impl FromStr for Activation {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "tanh" => Ok(Self::Tanh),
            "leaky_relu" => Ok(Self::LeakyRelu),
            _ => Err(format!(
                "unknown activation {s:?}; expected tanh or leaky_relu"
            )),
        }
    }
}

/// burn's CPU backends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    /// burn-flex, the default: several times faster than ndarray on this model.
    Flex,
    /// burn-ndarray, deprecated by burn 0.22 but kept for comparison.
    NdArray,
}

impl Backend {
    pub fn device(self) -> Device {
        match self {
            Self::Flex => Device::flex(),
            #[allow(deprecated)]
            Self::NdArray => Device::ndarray(),
        }
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Flex => "flex",
            Self::NdArray => "ndarray",
        })
    }
}

impl FromStr for Backend {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "flex" => Ok(Self::Flex),
            "ndarray" => Ok(Self::NdArray),
            _ => Err(format!("unknown backend {s:?}; expected flex or ndarray")),
        }
    }
}

/// Why a training ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum StopReason {
    /// It ran `training.epochs`.
    #[serde(rename = "all epochs")]
    AllEpochs,
    /// `training.early_stopping` ended it: its patience ran out.
    #[serde(rename = "early stopping")]
    EarlyStopping,
}

impl fmt::Display for StopReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::AllEpochs => "all epochs",
            Self::EarlyStopping => "early stopping",
        })
    }
}

impl FromStr for StopReason {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "all epochs" => Ok(Self::AllEpochs),
            "early stopping" => Ok(Self::EarlyStopping),
            _ => Err(format!("unknown stop reason {s:?}")),
        }
    }
}

/// The trajectory name of a [`Phase::HeldOut`] row: the test trajectories pooled.
pub const HELD_OUT: &str = "test trajectories";

/// Which phase a Monte Carlo row belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    Calibration,
    Evaluation,
    /// The test trajectories pooled, scored with terms from every calibration length.
    HeldOut,
}

impl Phase {
    pub fn as_str(self) -> &'static str {
        match self {
            Phase::Calibration => "calibration",
            Phase::Evaluation => "evaluation",
            Phase::HeldOut => "held_out",
        }
    }
}

impl std::str::FromStr for Phase {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        [Phase::Calibration, Phase::Evaluation, Phase::HeldOut]
            .into_iter()
            .find(|p| p.as_str() == s)
            .ok_or_else(|| {
                format!("unknown phase {s:?}: expected calibration, evaluation or held_out")
            })
    }
}

/// Error terms of one DVL, in the units the pipeline computes in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorErrors {
    /// Beam scale factor `s` (0.01 for 1 %).
    pub scale: f64,
    /// Beam bias `b` in m/s.
    pub bias_m_s: f64,
    /// Standard deviation of the beam noise in m/s.
    pub noise_m_s: f64,
}

impl SensorErrors {
    /// From the spec's units: scale in %, bias and noise in cm/s.
    pub fn from_spec_units(scale_pct: f64, bias_cm_s: f64, noise_cm_s: f64) -> Self {
        Self {
            scale: scale_pct / 100.0,
            bias_m_s: bias_cm_s / 100.0,
            noise_m_s: noise_cm_s / 100.0,
        }
    }
}
