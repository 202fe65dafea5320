//! The terms of an installation: which are estimated ([`TermSet`], the paper's EM1 to
//! EM5 among them), their values ([`Installation`]), the DVL velocity they predict from
//! the reference, the correction of a DVL record they give, and the score of a
//! correction against the reference. Every sign and frame is stated at the field that
//! carries it.
//! In: a reference at t+τ, or a DVL sample. Out: a predicted or corrected velocity.
//!
//! The model, for a DVL sample stamped t:
//! `v_dvl(t) = (I + S) · R(δ) · [v_b(t+τ) + ω_b(t+τ) × l] + b`, with v_b = C_n^b · v_n
//! the reference point's velocity in body axes and ω_b the body rate (see
//! [`frames`](crate::installation::frames)). Its inverse, the correction of a DVL sample, is
//! `v_corr = R(δ)ᵀ · (I + S)⁻¹ · (v_dvl − b) − ω_b(t+τ) × l`, an estimate of v_b at
//! t + τ.

mod bias;
pub mod kind;
mod lever_arm;
mod misalignment;
pub mod names;
mod scale;
mod time_offset;

pub use kind::{KindOfTerm, ShownUnit, TermKind};

use crate::Vec3;
use crate::installation::frames::{Mat3, Reference, ReferenceAt, apply, body_to_ned, cross};
use crate::vocab::ErrorModel;
use misalignment::misalignment_matrix;

/// How a scale or a bias is estimated: not at all, one for all axes, or one per axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PerAxis {
    Off,
    Scalar,
    PerAxis,
}

impl TermKind {
    /// The kind's row.
    pub fn table(self) -> &'static KindOfTerm {
        match self {
            TermKind::Scale => &scale::TERM,
            TermKind::Misalignment => &misalignment::TERM,
            TermKind::LeverArm => &lever_arm::TERM,
            TermKind::TimeOffset => &time_offset::TERM,
            TermKind::Bias => &bias::TERM,
        }
    }
}

/// A value for each kind of term, in its stored unit: a tolerance, a prior's standard
/// deviation, a random walk's per √s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PerKind {
    /// A fraction (0.005 for 0.5 %).
    pub scale: f64,
    pub misalignment_rad: f64,
    pub lever_arm_m: f64,
    pub time_offset_s: f64,
    pub bias_m_s: f64,
}

impl PerKind {
    /// The value of each kind, from `value`.
    pub fn from_fn(value: impl Fn(TermKind) -> f64) -> Self {
        PerKind {
            scale: value(TermKind::Scale),
            misalignment_rad: value(TermKind::Misalignment),
            lever_arm_m: value(TermKind::LeverArm),
            time_offset_s: value(TermKind::TimeOffset),
            bias_m_s: value(TermKind::Bias),
        }
    }

    /// The value for a term of this kind.
    pub fn of(&self, kind: TermKind) -> f64 {
        match kind {
            TermKind::Scale => self.scale,
            TermKind::Misalignment => self.misalignment_rad,
            TermKind::LeverArm => self.lever_arm_m,
            TermKind::TimeOffset => self.time_offset_s,
            TermKind::Bias => self.bias_m_s,
        }
    }
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
    /// Nothing estimated: the baseline, the DVL taken as it reads.
    pub const NONE: TermSet = TermSet {
        scale: PerAxis::Off,
        misalignment: false,
        lever_arm: false,
        time_offset: false,
        bias: PerAxis::Off,
    };

    /// Every term, scale and bias per axis: thirteen parameters.
    pub const EVERY: TermSet = TermSet {
        scale: PerAxis::PerAxis,
        misalignment: true,
        lever_arm: true,
        time_offset: true,
        bias: PerAxis::PerAxis,
    };

    /// The paper's error model as a term set: scale and bias only. EM1 a scalar scale,
    /// EM2 a scale per axis, EM3 a scalar bias (the same on every axis), EM4 a bias per
    /// axis, EM5 a scale and a bias per axis.
    pub fn of_error_model(model: ErrorModel) -> Self {
        let (scale, bias) = match model {
            ErrorModel::Em1 => (PerAxis::Scalar, PerAxis::Off),
            ErrorModel::Em2 => (PerAxis::PerAxis, PerAxis::Off),
            ErrorModel::Em3 => (PerAxis::Off, PerAxis::Scalar),
            ErrorModel::Em4 => (PerAxis::Off, PerAxis::PerAxis),
            ErrorModel::Em5 => (PerAxis::PerAxis, PerAxis::PerAxis),
        };
        TermSet {
            scale,
            bias,
            ..Self::NONE
        }
    }

    /// How many parameters the set estimates.
    pub fn parameter_count(&self) -> usize {
        self.parameter_kinds().len()
    }

    /// How many parameters of `kind` the set estimates: none, one for all axes, or
    /// one per axis (a misalignment and a lever arm are per axis, a time offset one).
    pub fn of(&self, kind: TermKind) -> PerAxis {
        let on = |estimated: bool, form: PerAxis| if estimated { form } else { PerAxis::Off };
        match kind {
            TermKind::Scale => self.scale,
            TermKind::Misalignment => on(self.misalignment, PerAxis::PerAxis),
            TermKind::LeverArm => on(self.lever_arm, PerAxis::PerAxis),
            TermKind::TimeOffset => on(self.time_offset, PerAxis::Scalar),
            TermKind::Bias => self.bias,
        }
    }

    /// The estimated parameters, in the order of a parameter vector (the order of
    /// [`TermKind::ALL`]): each one's kind and axis (`None` for one value on all axes).
    fn parameters(&self) -> impl Iterator<Item = (&'static KindOfTerm, Option<usize>)> + '_ {
        TermKind::ALL.into_iter().flat_map(|kind| {
            let axes: &[Option<usize>] = match self.of(kind) {
                PerAxis::Off => &[],
                PerAxis::Scalar => &[None],
                PerAxis::PerAxis => &[Some(0), Some(1), Some(2)],
            };
            axes.iter().map(move |&axis| (kind.table(), axis))
        })
    }

    /// The estimated parameters' names, in the order of a parameter vector: scale,
    /// misalignment, lever arm, time offset, bias; such as `lever_arm_x_m` or
    /// `time_offset_s`. A scalar scale or bias has no axis in its name.
    pub fn parameter_names(&self) -> Vec<&'static str> {
        self.parameters()
            .map(|(term, axis)| match axis {
                None => term
                    .one_name
                    .expect("a kind estimated once has a name for it"),
                Some(axis) => term.axis_names.expect("a kind per axis names its axes")[axis],
            })
            .collect()
    }

    /// The kind of each estimated parameter, in the order of [`Self::parameter_names`].
    pub fn parameter_kinds(&self) -> Vec<TermKind> {
        self.parameters().map(|(term, _)| term.kind).collect()
    }
}

/// The values of every term (those not estimated are zero).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Installation {
    /// S: the DVL reads (1 + s) times the true velocity, per axis, in the DVL's axes
    /// (0.01 for 1 %).
    pub scale: Vec3,
    /// δ: roll, pitch, yaw of the DVL's axes from the body's, radians;
    /// R(δ) = (Rz(δ_z) · Ry(δ_y) · Rx(δ_x))ᵀ takes a body-frame vector into the DVL's
    /// axes (the same ZYX form as C_n^b).
    pub misalignment_rad: Vec3,
    /// l: the DVL's position from the reference point, body frame (x forward, y
    /// starboard, z down), metres; the DVL moves at v_b + ω_b × l.
    pub lever_arm_m: Vec3,
    /// τ: the DVL sample stamped t measured the motion of the reference at t + τ, s
    /// (τ > 0: the DVL's stamps lead the reference's).
    pub time_offset_s: f64,
    /// b: added to every DVL sample, per axis, in the DVL's axes, m/s.
    pub bias_m_s: Vec3,
}

impl Installation {
    /// The installation with the parameters of `terms` from `parameters` (in the
    /// order of [`TermSet::parameter_names`]) and every other term zero.
    ///
    /// # Panics
    /// When `parameters` has not `terms.parameter_count()` values.
    pub fn from_parameters(terms: &TermSet, parameters: &[f64]) -> Self {
        Self::default().with_parameters(terms, parameters)
    }

    /// This installation with the parameters of `terms` replaced by `parameters`; the
    /// other terms keep their values.
    ///
    /// # Panics
    /// When `parameters` has not `terms.parameter_count()` values.
    pub fn with_parameters(mut self, terms: &TermSet, parameters: &[f64]) -> Self {
        assert_eq!(parameters.len(), terms.parameter_count(), "parameter count");
        let mut next = parameters.iter().copied();
        for kind in TermKind::ALL {
            let term = kind.table();
            let mut take = || next.next().unwrap_or(0.0);
            match terms.of(kind) {
                PerAxis::Off => {}
                PerAxis::Scalar => (term.set)(&mut self, [take(); 3]),
                PerAxis::PerAxis => (term.set)(&mut self, [take(), take(), take()]),
            }
        }
        self
    }

    /// The parameters of `terms`, in the order of [`TermSet::parameter_names`]; a scalar
    /// scale or bias is read from the x axis.
    pub fn to_parameters(&self, terms: &TermSet) -> Vec<f64> {
        terms
            .parameters()
            .map(|(term, axis)| (term.values)(self)[axis.unwrap_or(0)])
            .collect()
    }

    /// The DVL velocity predicted from the reference at t + τ (the caller reads the
    /// reference at the DVL's stamp plus [`Self::time_offset_s`]):
    /// `(I + S) · R(δ) · [v_b + ω_b × l] + b`, m/s in the DVL's axes.
    pub fn predict(&self, at: ReferenceAt) -> Vec3 {
        let rotated = apply(
            &misalignment_matrix(self.misalignment_rad),
            self.dvl_point_velocity(at),
        );
        [0, 1, 2].map(|k| (1.0 + self.scale[k]) * rotated[k] + self.bias_m_s[k])
    }

    /// v_b + ω_b × l: the velocity of the DVL's position, body axes, m/s.
    fn dvl_point_velocity(&self, at: ReferenceAt) -> Vec3 {
        let turning = cross(at.rate_rad_s, self.lever_arm_m);
        [0, 1, 2].map(|k| at.velocity_body_m_s[k] + turning[k])
    }

    /// ∂[`Self::predict`]/∂θ for each parameter θ of `terms`, in their order: one
    /// column (a velocity, m/s per unit of the parameter) each. `slope` is the time
    /// derivative of the reference at the same time (for τ).
    pub fn predict_jacobian(
        &self,
        terms: &TermSet,
        at: ReferenceAt,
        slope: ReferenceAt,
    ) -> Vec<Vec3> {
        let rotation = misalignment_matrix(self.misalignment_rad);
        let point = self.dvl_point_velocity(at);
        let linearisation = Linearisation {
            installation: self,
            at,
            slope,
            rotation,
            point,
            rotated: apply(&rotation, point),
        };
        terms
            .parameters()
            .map(|(term, axis)| (term.column)(&linearisation, axis))
            .collect()
    }

    /// The DVL sample corrected: `R(δ)ᵀ · (I + S)⁻¹ · (v_dvl − b) − ω_b × l`, the
    /// reference point's velocity in body axes at t + τ, where t is the sample's stamp
    /// and `rate_at_t_plus_tau_rad_s` is ω_b at t + τ (on a vehicle, from its gyro).
    pub fn correct(&self, dvl_m_s: Vec3, rate_at_t_plus_tau_rad_s: Vec3) -> Vec3 {
        let unscaled = [0, 1, 2].map(|k| (dvl_m_s[k] - self.bias_m_s[k]) / (1.0 + self.scale[k]));
        let body = apply(&body_to_ned(self.misalignment_rad), unscaled);
        let turning = cross(rate_at_t_plus_tau_rad_s, self.lever_arm_m);
        [0, 1, 2].map(|k| body[k] - turning[k])
    }
}

/// The prediction at one sample, in the parts every kind's Jacobian column is built
/// from.
struct Linearisation<'a> {
    installation: &'a Installation,
    /// The reference at t + τ.
    at: ReferenceAt,
    /// Its time derivative.
    slope: ReferenceAt,
    /// R(δ).
    rotation: Mat3,
    /// v_b + ω_b × l, body axes.
    point: Vec3,
    /// R(δ) · (v_b + ω_b × l), the DVL's axes.
    rotated: Vec3,
}

impl Linearisation<'_> {
    /// (I + S) · v.
    fn scaled(&self, v: Vec3) -> Vec3 {
        [0, 1, 2].map(|k| (1.0 + self.installation.scale[k]) * v[k])
    }
}

/// Root mean square errors per body axis and in total, m/s, over `sample_count`
/// samples; total = √(x² + y² + z²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisRmse {
    pub x_m_s: f64,
    pub y_m_s: f64,
    pub z_m_s: f64,
    pub total_m_s: f64,
    pub sample_count: usize,
}

impl AxisRmse {
    /// The RMSE of the errors given, per axis; `None` when there are none.
    pub fn of_errors(errors: impl IntoIterator<Item = Vec3>) -> Option<Self> {
        let mut sum = [0.0; 3];
        let mut count = 0usize;
        for error in errors {
            for k in 0..3 {
                sum[k] += error[k] * error[k];
            }
            count += 1;
        }
        if count == 0 {
            return None;
        }
        let [x_m_s, y_m_s, z_m_s] = sum.map(|s| (s / count as f64).sqrt());
        Some(AxisRmse {
            x_m_s,
            y_m_s,
            z_m_s,
            total_m_s: (x_m_s * x_m_s + y_m_s * y_m_s + z_m_s * z_m_s).sqrt(),
            sample_count: count,
        })
    }
}

/// The score of an installation on a record: the RMSE, per body axis and in total, of
/// the corrected DVL against the reference at the corrected stamps,
/// `installation.correct(dvl_i, ω_b(t_i+τ)) − v_b(t_i+τ)`, over the samples i in
/// `samples` whose t_i + τ lies inside the reference. Only the DVL record is
/// corrected; the reference is read, never resampled. `None` when no sample is scored.
pub fn score(
    installation: &Installation,
    time_s: &[f64],
    dvl_m_s: &[Vec3],
    reference: &Reference,
    samples: impl IntoIterator<Item = usize>,
) -> Option<AxisRmse> {
    AxisRmse::of_errors(
        (samples.into_iter())
            .filter_map(|i| corrected_error(installation, (time_s, dvl_m_s), reference, i)),
    )
}

/// What [`score`] scores of sample `i` of the record (`time_s`, `dvl_m_s`): the
/// corrected DVL less the reference at t_i + τ, m/s per body axis; `None` where t_i + τ
/// lies outside the reference.
pub fn corrected_error(
    installation: &Installation,
    (time_s, dvl_m_s): (&[f64], &[Vec3]),
    reference: &Reference,
    i: usize,
) -> Option<Vec3> {
    let at = reference.at(time_s[i] + installation.time_offset_s)?;
    let corrected = installation.correct(dvl_m_s[i], at.rate_rad_s);
    Some([0, 1, 2].map(|k| corrected[k] - at.velocity_body_m_s[k]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn installation() -> Installation {
        Installation {
            scale: [0.01, -0.02, 0.03],
            misalignment_rad: [0.02, -0.01, 0.03],
            lever_arm_m: [-1.9, 0.05, 0.4],
            time_offset_s: 0.6,
            bias_m_s: [0.01, -0.005, 0.002],
        }
    }

    #[test]
    fn the_error_models_are_the_papers() {
        let count = |model| TermSet::of_error_model(model).parameter_count();
        for model in ErrorModel::ALL {
            assert_eq!(count(model), model.term_count(), "{model}");
        }
        assert_eq!(
            TermSet::of_error_model(ErrorModel::Em3).parameter_names(),
            ["bias_m_s"]
        );
        assert_eq!(
            TermSet::of_error_model(ErrorModel::Em5).parameter_names(),
            [
                "scale_x",
                "scale_y",
                "scale_z",
                "bias_x_m_s",
                "bias_y_m_s",
                "bias_z_m_s"
            ]
        );
        assert_eq!(TermSet::NONE.parameter_count(), 0);
    }

    #[test]
    fn parameters_go_in_and_out_in_the_order_of_their_names() {
        let terms = TermSet::EVERY;
        let names = terms.parameter_names();
        assert_eq!(names.len(), 13);
        assert_eq!(names[9], "time_offset_s");
        let parameters = installation().to_parameters(&terms);
        assert_eq!(parameters[6], -1.9);
        assert_eq!(
            Installation::from_parameters(&terms, &parameters),
            installation()
        );
        let scalar = TermSet {
            scale: PerAxis::Scalar,
            bias: PerAxis::Scalar,
            ..TermSet::NONE
        };
        let tied = Installation::from_parameters(&scalar, &[0.02, -0.1]);
        assert_eq!(tied.scale, [0.02; 3]);
        assert_eq!(tied.bias_m_s, [-0.1; 3]);
    }

    #[test]
    fn a_yaw_misalignment_turns_forward_motion_to_port_in_the_dvls_axes() {
        // The DVL turned +90° in yaw (its x axis to starboard): the body's forward
        // motion is along the DVL's −y.
        let turned = Installation {
            misalignment_rad: [0.0, 0.0, std::f64::consts::FRAC_PI_2],
            ..Installation::default()
        };
        let at = ReferenceAt {
            velocity_body_m_s: [2.0, 0.0, 0.0],
            rate_rad_s: [0.0; 3],
        };
        let predicted = turned.predict(at);
        assert!((predicted[1] + 2.0).abs() < 1e-15 && predicted[0].abs() < 1e-15);
    }

    #[test]
    fn a_lever_arm_aft_reads_a_starboard_turn_as_motion_to_port() {
        // The DVL 2 m aft (l_x = −2), turning to starboard at r = 0.1 rad/s: the stern
        // swings to port, ω × l = (0, −0.2, 0).
        let aft = Installation {
            lever_arm_m: [-2.0, 0.0, 0.0],
            ..Installation::default()
        };
        let at = ReferenceAt {
            velocity_body_m_s: [2.0, 0.0, 0.0],
            rate_rad_s: [0.0, 0.0, 0.1],
        };
        assert_eq!(aft.predict(at), [2.0, -0.2, 0.0]);
    }

    #[test]
    fn the_correction_inverts_the_prediction() {
        let at = ReferenceAt {
            velocity_body_m_s: [1.9, -0.1, 0.05],
            rate_rad_s: [0.01, -0.02, 0.2],
        };
        let installation = installation();
        let corrected = installation.correct(installation.predict(at), at.rate_rad_s);
        for k in 0..3 {
            assert!((corrected[k] - at.velocity_body_m_s[k]).abs() < 1e-14);
        }
    }

    #[test]
    fn the_jacobian_is_the_predictions_derivative() {
        let terms = TermSet::EVERY;
        let at = ReferenceAt {
            velocity_body_m_s: [1.9, -0.1, 0.05],
            rate_rad_s: [0.01, -0.02, 0.2],
        };
        let slope = ReferenceAt {
            velocity_body_m_s: [0.1, 0.3, -0.02],
            rate_rad_s: [0.002, 0.001, -0.05],
        };
        let base = installation();
        let parameters = base.to_parameters(&terms);
        let columns = base.predict_jacobian(&terms, at, slope);
        let step = 1e-6;
        for (index, column) in columns.iter().enumerate() {
            let nudged = |sign: f64| {
                let mut p = parameters.clone();
                p[index] += sign * step;
                let moved = Installation::from_parameters(&terms, &p);
                // τ moves the time at which the reference is read: to first order,
                // the reference plus its slope times the change.
                let shift = p[9] - base.time_offset_s;
                let at = ReferenceAt {
                    velocity_body_m_s: [0, 1, 2]
                        .map(|k| at.velocity_body_m_s[k] + shift * slope.velocity_body_m_s[k]),
                    rate_rad_s: [0, 1, 2].map(|k| at.rate_rad_s[k] + shift * slope.rate_rad_s[k]),
                };
                moved.predict(at)
            };
            let (up, down) = (nudged(1.0), nudged(-1.0));
            for k in 0..3 {
                let numeric = (up[k] - down[k]) / (2.0 * step);
                assert!(
                    (numeric - column[k]).abs() < 1e-8,
                    "{}: {numeric} {}",
                    terms.parameter_names()[index],
                    column[k]
                );
            }
        }
    }

    #[test]
    fn the_score_of_the_true_installation_on_its_own_prediction_is_zero_and_of_none_is_the_error() {
        use crate::data::paired::PairedRecording;
        let time_s: Vec<f64> = (0..50).map(f64::from).collect();
        let recording = PairedRecording {
            dvl_m_s: vec![[0.0; 3]; 50],
            time_s: time_s.clone(),
            left_out: Vec::new(),
            reference_time_s: time_s.clone(),
            velocity_ned_m_s: time_s
                .iter()
                .map(|t| [2.0 * (0.1 * t).cos(), 2.0 * (0.1 * t).sin(), 0.0])
                .collect(),
            attitude_rad: time_s.iter().map(|t| [0.0, 0.0, 0.1 * t]).collect(),
            rate_rad_s: None,
            position_ne_m: None,
            gap_limit_s: 3.0,
            reference_read: None,
        };
        let reference = Reference::new(&recording);
        let truth = Installation {
            time_offset_s: 1.0,
            ..installation()
        };
        let dvl: Vec<Vec3> = time_s
            .iter()
            .map(|t| truth.predict(reference.at(t + 1.0).unwrap_or(reference.at(*t).unwrap())))
            .collect();
        let scored = score(&truth, &time_s, &dvl, &reference, 0..50).unwrap();
        // The last sample's t + τ is outside the reference: not scored.
        assert_eq!(scored.sample_count, 49);
        assert!(scored.total_m_s < 1e-12);
        let none = score(&Installation::default(), &time_s, &dvl, &reference, 5..45).unwrap();
        assert!(none.total_m_s > 0.05 && none.sample_count == 40);
    }
}
