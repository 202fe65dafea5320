//! Checks `[calibration.kalman]`. In: the table as written
//! ([`StudyKalmanFile`]) and the names of `[[calibration.models]]`. Out: the
//! extended Kalman filter's [`FilterSettings`] in stored units (fractions, radians,
//! m/s): the models it names defined and listed once, every prior above zero, every
//! random walk zero or more, and none beyond what an installation is off by.

use crate::data::paired::MAX_DVL_SPEED_M_S;
use crate::installation::estimate::filter::FilterSettings;
use crate::installation::estimate::fit::{MAX_LEVER_ARM_M, MAX_SCALE, TIME_OFFSET_MARGIN_S};
use crate::installation::study::spec::kalman::StudyKalmanFile;
use crate::installation::terms::PerKind;
use crate::spec::check::Faults;

/// Checks `[calibration.kalman]` against the models defined (`model_names`): the models
/// it names, a positive prior and a random walk not below zero, in stored units.
pub(in crate::installation::study::spec) fn check_kalman(
    kalman: StudyKalmanFile,
    model_names: &[&str],
    faults: &mut Faults,
) -> FilterSettings {
    let StudyKalmanFile {
        models,
        prior_scale_pct,
        prior_misalignment_deg,
        prior_lever_arm_m,
        prior_time_offset_s,
        prior_bias_cm_s,
        scale_random_walk_pct_per_sqrt_s,
        bias_random_walk_cm_s_per_sqrt_s,
        time_offset_random_walk_s_per_sqrt_s,
    } = kalman;
    check_models(&models, model_names, faults);
    let mut value = |key: &str, value: f64, zero_allowed: bool, most: (f64, &str)| {
        check_value(key, value, zero_allowed, most, faults)
    };
    let scale_pct = (100.0 * MAX_SCALE, "the largest scale error a DVL has");
    let bias_cm_s = (100.0 * MAX_DVL_SPEED_M_S, "a vehicle's top speed");
    let prior = PerKind {
        scale: value("prior_scale_pct", prior_scale_pct, false, scale_pct) / 100.0,
        misalignment_rad: value(
            "prior_misalignment_deg",
            prior_misalignment_deg,
            false,
            (180.0, "half a turn"),
        )
        .to_radians(),
        lever_arm_m: value(
            "prior_lever_arm_m",
            prior_lever_arm_m,
            false,
            (MAX_LEVER_ARM_M, "the largest lever arm a fit may find"),
        ),
        time_offset_s: value(
            "prior_time_offset_s",
            prior_time_offset_s,
            false,
            (TIME_OFFSET_MARGIN_S, "the time offsets a fit scans"),
        ),
        bias_m_s: value("prior_bias_cm_s", prior_bias_cm_s, false, bias_cm_s) / 100.0,
    };
    let random_walk = PerKind {
        scale: value(
            "scale_random_walk_pct_per_sqrt_s",
            scale_random_walk_pct_per_sqrt_s,
            true,
            scale_pct,
        ) / 100.0,
        misalignment_rad: 0.0,
        lever_arm_m: 0.0,
        time_offset_s: value(
            "time_offset_random_walk_s_per_sqrt_s",
            time_offset_random_walk_s_per_sqrt_s,
            true,
            (TIME_OFFSET_MARGIN_S, "the time offsets a fit scans"),
        ),
        bias_m_s: value(
            "bias_random_walk_cm_s_per_sqrt_s",
            bias_random_walk_cm_s_per_sqrt_s,
            true,
            bias_cm_s,
        ) / 100.0,
    };
    FilterSettings { prior, random_walk }
}

/// Each model `models` names defined in `model_names`, and listed once.
fn check_models(models: &[String], model_names: &[&str], faults: &mut Faults) {
    for (i, name) in models.iter().enumerate() {
        if !model_names.contains(&name.as_str()) {
            faults.add(
                format!("calibration.kalman.models[{i}]"),
                format!(
                    "{name:?} is not a model of [[calibration.models]]; defined: {}",
                    model_names.join(", ")
                ),
            );
        } else if models[..i].contains(name) {
            faults.add(
                format!("calibration.kalman.models[{i}]"),
                format!("{name:?} is listed twice"),
            );
        }
    }
}

/// `value` of `key` finite and above zero (or zero, where `zero_allowed`), and at most
/// `most`, `what` saying why: a prior or a random walk beyond what an installation is
/// off by says nothing the filter can use, and a huge one overflows its covariance.
fn check_value(
    key: &str,
    value: f64,
    zero_allowed: bool,
    (most, what): (f64, &str),
    faults: &mut Faults,
) -> f64 {
    if !value.is_finite() || value < 0.0 || (value == 0.0 && !zero_allowed) {
        let rule = if zero_allowed {
            "zero or more"
        } else {
            "above zero"
        };
        faults.add(
            format!("calibration.kalman.{key}"),
            format!("{} must be finite and {rule}", crate::Shown(value)),
        );
    } else if value > most {
        faults.add(
            format!("calibration.kalman.{key}"),
            format!(
                "{} is beyond {most}, {what}: the filter's covariance would overflow or say nothing",
                crate::Shown(value)
            ),
        );
    }
    value
}

/// The filter of a spec whose `[calibration.kalman]` is left out
/// ([`StudyKalmanFile::default`]): wide priors about zero, constant terms.
pub fn default_filter_settings() -> FilterSettings {
    let mut faults = Faults::default();
    let settings = check_kalman(StudyKalmanFile::default(), &[], &mut faults);
    assert!(
        faults.0.is_empty(),
        "the default [calibration.kalman] is refused: {:?}",
        faults.0
    );
    settings
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The defaults in stored units: 5 % of scale, 5° of misalignment, 2 m of lever
    /// arm, 1 s of time offset, 10 cm/s of bias, no random walk.
    #[test]
    fn the_default_filter_is_the_documented_priors_in_stored_units() {
        let settings = default_filter_settings();
        let prior = settings.prior;
        assert_eq!(prior.scale, 0.05);
        assert_eq!(prior.misalignment_rad, 5.0_f64.to_radians());
        assert_eq!(prior.lever_arm_m, 2.0);
        assert_eq!(prior.time_offset_s, 1.0);
        assert_eq!(prior.bias_m_s, 0.1);
        assert_eq!(settings.random_walk.scale, 0.0);
        assert_eq!(settings.random_walk.bias_m_s, 0.0);
    }

    /// A prior or a random walk of 1e300 overflowed the filter's covariance and every
    /// Kalman row then read as no calibration, exit 0: refused at its key.
    #[test]
    fn a_prior_or_random_walk_beyond_an_installation_is_refused() {
        let kalman = StudyKalmanFile {
            prior_lever_arm_m: 1e300,
            bias_random_walk_cm_s_per_sqrt_s: 1e300,
            ..StudyKalmanFile::default()
        };
        let mut faults = Faults::default();
        check_kalman(kalman, &[], &mut faults);
        let expected = [
            (
                "calibration.kalman.prior_lever_arm_m",
                "1e300 is beyond 100, the largest lever arm a fit may find: the filter's covariance would overflow or say nothing",
            ),
            (
                "calibration.kalman.bias_random_walk_cm_s_per_sqrt_s",
                "1e300 is beyond 2000, a vehicle's top speed: the filter's covariance would overflow or say nothing",
            ),
        ]
        .map(|(key, message)| (key.to_string(), message.to_string()));
        assert_eq!(faults.0, expected);
    }

    /// A model named twice, one not defined, a zero prior and a negative random walk:
    /// each fault at its key, in the table's order.
    #[test]
    fn each_fault_of_the_table_is_at_its_key() {
        let kalman = StudyKalmanFile {
            models: vec!["a".into(), "b".into(), "a".into()],
            prior_lever_arm_m: 0.0,
            bias_random_walk_cm_s_per_sqrt_s: -1.0,
            ..StudyKalmanFile::default()
        };
        let mut faults = Faults::default();
        check_kalman(kalman, &["a"], &mut faults);
        let expected = [
            (
                "calibration.kalman.models[1]",
                "\"b\" is not a model of [[calibration.models]]; defined: a",
            ),
            ("calibration.kalman.models[2]", "\"a\" is listed twice"),
            (
                "calibration.kalman.prior_lever_arm_m",
                "0 must be finite and above zero",
            ),
            (
                "calibration.kalman.bias_random_walk_cm_s_per_sqrt_s",
                "-1 must be finite and zero or more",
            ),
        ]
        .map(|(key, message)| (key.to_string(), message.to_string()));
        assert_eq!(faults.0, expected);
    }
}
