//! `[calibration.kalman]` of an installation spec as written: which named term sets of
//! `[[calibration.models]]` the extended Kalman filter runs besides their fit, the
//! filter's prior standard deviation of each of the installation's five kinds of term
//! about zero, and the random walk a scale, a bias and the time offset (a drifting clock) may take. In: the TOML table.
//! Out: an [`StudyKalmanFile`], defaults filled in; its check is
//! `installation/spec/check/kalman.rs`.
//!
//! Not the paper's `[estimators.kalman]`
//! ([`ScaleBiasKalmanFile`](crate::spec::file::ScaleBiasKalmanFile)): that filter
//! estimates only the scale and bias of a simulated DVL's error model, its prior
//! 10 %; this one estimates a real installation's scale, misalignment, lever arm, time
//! offset and bias, its scale prior 5 % (a DVL's scale is within a few %).

/// `[calibration.kalman]` as written.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StudyKalmanFile {
    /// Names of `[[calibration.models]]` the filter runs too.
    pub models: Vec<String>,
    pub prior_scale_pct: f64,
    pub prior_misalignment_deg: f64,
    pub prior_lever_arm_m: f64,
    pub prior_time_offset_s: f64,
    pub prior_bias_cm_s: f64,
    pub scale_random_walk_pct_per_sqrt_s: f64,
    pub bias_random_walk_cm_s_per_sqrt_s: f64,
    /// A clock that drifts within a dive: the time offset's random walk, s per √s.
    pub time_offset_random_walk_s_per_sqrt_s: f64,
}

impl Default for StudyKalmanFile {
    /// Wide priors: a DVL whose scale is within a few %, mounted within a few degrees
    /// and metres of the reference, its stamps within a second; constant terms.
    fn default() -> Self {
        StudyKalmanFile {
            models: Vec::new(),
            prior_scale_pct: 5.0,
            prior_misalignment_deg: 5.0,
            prior_lever_arm_m: 2.0,
            prior_time_offset_s: 1.0,
            prior_bias_cm_s: 10.0,
            scale_random_walk_pct_per_sqrt_s: 0.0,
            bias_random_walk_cm_s_per_sqrt_s: 0.0,
            time_offset_random_walk_s_per_sqrt_s: 0.0,
        }
    }
}
