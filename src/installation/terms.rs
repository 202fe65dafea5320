//! The terms of an installation: which are estimated ([`TermSet`], the paper's EM1 to
//! EM5 among them), their values ([`Installation`]), the DVL velocity they predict from
//! the reference, and the correction of a DVL record they give. Every sign and frame is
//! stated at the field that carries it.
//! In: a reference at t+τ, or a DVL sample. Out: a predicted or corrected velocity.

use crate::Vec3;
use crate::vocab::ErrorModel;

/// How a scale or a bias is estimated: not at all, one for all axes, or one per axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PerAxis {
    Off,
    Scalar,
    PerAxis,
}

/// The terms a calibration estimates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TermSet {
    pub scale: PerAxis,
    pub misalignment: bool,
    pub lever_arm: bool,
    pub time_offset: bool,
    pub bias: PerAxis,
}

impl TermSet {
    /// The paper's error model as a term set: scale and bias only.
    pub fn of_error_model(model: ErrorModel) -> Self {
        let _ = model;
        todo!("issue 26")
    }

    /// The estimated parameters' names, in the order of a parameter vector, such as
    /// `lever_arm_x_m` or `time_offset_s`.
    pub fn parameter_names(&self) -> Vec<&'static str> {
        todo!("issue 26")
    }
}

/// The values of every term (those not estimated are zero).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Installation {
    /// S: the DVL reads (1 + s) times the true velocity, per axis (0.01 for 1 %).
    pub scale: Vec3,
    /// δ: roll, pitch, yaw of the DVL's axes from the body's, radians; R(δ) takes a
    /// body-frame vector into the DVL's axes.
    pub misalignment_rad: Vec3,
    /// l: the DVL's position from the reference point, body frame, metres.
    pub lever_arm_m: Vec3,
    /// τ: the DVL sample stamped t measured the motion of the reference at t + τ, s.
    pub time_offset_s: f64,
    /// b: added to every DVL sample, per axis, m/s.
    pub bias_m_s: Vec3,
}
