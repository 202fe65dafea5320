//! `[calibration.kalman]` of an installation spec: which named term sets of
//! `[[calibration.models]]` the extended Kalman filter runs besides their fit, the
//! filter's prior standard deviation of each kind of term about zero, and the random
//! walk a scale and a bias may take. In: the table as written and the models' names.
//! Out: the filter's settings, or every fault at its key.

use super::filter::FilterSettings;
use super::terms::PerKind;

/// `[calibration.kalman]` as written.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct KalmanFile {
    /// Names of `[[calibration.models]]` the filter runs too.
    pub models: Vec<String>,
    pub prior_scale_pct: f64,
    pub prior_misalignment_deg: f64,
    pub prior_lever_arm_m: f64,
    pub prior_time_offset_s: f64,
    pub prior_bias_cm_s: f64,
    pub scale_random_walk_pct_per_sqrt_s: f64,
    pub bias_random_walk_cm_s_per_sqrt_s: f64,
}

impl Default for KalmanFile {
    /// Wide priors: a DVL whose scale is within a few %, mounted within a few degrees
    /// and metres of the reference, its stamps within a second; constant terms.
    fn default() -> Self {
        KalmanFile {
            models: Vec::new(),
            prior_scale_pct: 5.0,
            prior_misalignment_deg: 5.0,
            prior_lever_arm_m: 2.0,
            prior_time_offset_s: 1.0,
            prior_bias_cm_s: 10.0,
            scale_random_walk_pct_per_sqrt_s: 0.0,
            bias_random_walk_cm_s_per_sqrt_s: 0.0,
        }
    }
}

/// Checks `[calibration.kalman]` against the models defined (`model_names`): the models
/// it names, a positive prior and a random walk not below zero, in stored units.
pub fn check_kalman(
    kalman: &KalmanFile,
    model_names: &[&str],
    fault: &mut dyn FnMut(String, String),
) -> FilterSettings {
    for (i, name) in kalman.models.iter().enumerate() {
        if !model_names.contains(&name.as_str()) {
            fault(
                format!("calibration.kalman.models[{i}]"),
                format!(
                    "{name:?} is not a model of [[calibration.models]]; defined: {}",
                    model_names.join(", ")
                ),
            );
        } else if kalman.models[..i].contains(name) {
            fault(
                format!("calibration.kalman.models[{i}]"),
                format!("{name:?} is listed twice"),
            );
        }
    }
    let mut value = |key: &str, value: f64, zero_allowed: bool| {
        if !value.is_finite() || value < 0.0 || (value == 0.0 && !zero_allowed) {
            let rule = if zero_allowed {
                "zero or more"
            } else {
                "above zero"
            };
            fault(
                format!("calibration.kalman.{key}"),
                format!("{value} must be finite and {rule}"),
            );
        }
        value
    };
    let prior = PerKind {
        scale: value("prior_scale_pct", kalman.prior_scale_pct, false) / 100.0,
        misalignment_rad: value(
            "prior_misalignment_deg",
            kalman.prior_misalignment_deg,
            false,
        )
        .to_radians(),
        lever_arm_m: value("prior_lever_arm_m", kalman.prior_lever_arm_m, false),
        time_offset_s: value("prior_time_offset_s", kalman.prior_time_offset_s, false),
        bias_m_s: value("prior_bias_cm_s", kalman.prior_bias_cm_s, false) / 100.0,
    };
    let random_walk = PerKind {
        scale: value(
            "scale_random_walk_pct_per_sqrt_s",
            kalman.scale_random_walk_pct_per_sqrt_s,
            true,
        ) / 100.0,
        misalignment_rad: 0.0,
        lever_arm_m: 0.0,
        time_offset_s: 0.0,
        bias_m_s: value(
            "bias_random_walk_cm_s_per_sqrt_s",
            kalman.bias_random_walk_cm_s_per_sqrt_s,
            true,
        ) / 100.0,
    };
    FilterSettings { prior, random_walk }
}
