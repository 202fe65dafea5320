//! Checks `[estimators]`. In: the kinds of estimator and the error models by name, and
//! the Kalman filters' prior and random walk. Out: each parsed, known and listed once;
//! the bound and the DCNet ensemble, which a spec does not list, refused with the
//! reason; the prior positive and the random walk not negative, as fractions and m/s.

use super::Faults;
use crate::spec::{KalmanSpec, TermSettings, file};
use crate::vocab::{ErrorModel, EstimatorKind};

/// Checks `[estimators]`: kinds and error models known, each listed once, and the
/// Kalman filters' settings.
pub(in crate::spec) fn check_estimators(
    estimators: file::EstimatorsFile,
    faults: &mut Faults,
) -> (Vec<EstimatorKind>, Vec<ErrorModel>, KalmanSpec) {
    let file::EstimatorsFile {
        kinds,
        error_models,
        kalman,
    } = estimators;
    let names = kinds;
    let mut kinds = parse_names("estimators.kinds", &names, faults);
    // Two kinds that a spec does not list: the tables always have them, or have them
    // whenever they apply.
    for (kind, why) in [
        (
            EstimatorKind::Bound,
            "the bound is no method to list: it is computed for every DVL",
        ),
        (
            EstimatorKind::DcnetEnsemble,
            "\"dcnet_ensemble\" is not listed: it runs beside \"dcnet\" when training.replicates is above 1",
        ),
    ] {
        if let Some(i) = names.iter().position(|name| *name == kind.to_string()) {
            faults.add(format!("estimators.kinds[{i}]"), why);
        }
    }
    kinds.retain(|k| !matches!(k, EstimatorKind::Bound | EstimatorKind::DcnetEnsemble));
    let error_models = parse_names("estimators.error_models", &error_models, faults);
    (kinds, error_models, check_kalman(kalman, faults))
}

/// Checks `[estimators.kalman]`: a positive finite prior, a finite random walk not
/// below zero.
fn check_kalman(kalman: file::ScaleBiasKalmanFile, faults: &mut Faults) -> KalmanSpec {
    let file::ScaleBiasKalmanFile {
        prior_scale_pct,
        prior_bias_cm_s,
        scale_random_walk_pct_per_sqrt_s,
        bias_random_walk_cm_s_per_sqrt_s,
    } = kalman;
    let mut value = |name: &str, value: f64, zero_allowed: bool| {
        let key = format!("estimators.kalman.{name}");
        if !value.is_finite() || value < 0.0 || (value == 0.0 && !zero_allowed) {
            let rule = if zero_allowed {
                "zero or more"
            } else {
                "above zero"
            };
            faults.add(key, format!("{value} must be finite and {rule}"));
        }
        value / 100.0
    };
    KalmanSpec {
        prior: TermSettings {
            scale: value("prior_scale_pct", prior_scale_pct, false),
            bias_m_s: value("prior_bias_cm_s", prior_bias_cm_s, false),
        },
        random_walk: TermSettings {
            scale: value(
                "scale_random_walk_pct_per_sqrt_s",
                scale_random_walk_pct_per_sqrt_s,
                true,
            ),
            bias_m_s: value(
                "bias_random_walk_cm_s_per_sqrt_s",
                bias_random_walk_cm_s_per_sqrt_s,
                true,
            ),
        },
    }
}

fn parse_names<T: std::str::FromStr<Err = String> + PartialEq>(
    key: &str,
    names: &[String],
    faults: &mut Faults,
) -> Vec<T> {
    if names.is_empty() {
        faults.add(key, "is empty");
    }
    let mut parsed = Vec::new();
    for (i, name) in names.iter().enumerate() {
        match name.parse::<T>() {
            Ok(value) if parsed.contains(&value) => {
                faults.add(format!("{key}[{i}]"), format!("{name:?} is listed twice"))
            }
            Ok(value) => parsed.push(value),
            Err(message) => faults.add(format!("{key}[{i}]"), message),
        }
    }
    parsed
}

#[cfg(test)]
mod tests {
    use crate::spec::fixture::quick_faults;

    #[test]
    fn a_kalman_prior_must_be_positive_and_a_random_walk_not_negative() {
        let faults = quick_faults(&[
            "estimators.kalman.prior_scale_pct=0",
            "estimators.kalman.bias_random_walk_cm_s_per_sqrt_s=-1",
        ]);
        assert!(
            faults.contains("estimators.kalman.prior_scale_pct: 0 must be finite and above zero"),
            "{faults}"
        );
        assert!(
            faults.contains(
                "estimators.kalman.bias_random_walk_cm_s_per_sqrt_s: -1 must be finite and zero or more"
            ),
            "{faults}"
        );
    }

    #[test]
    fn the_bound_is_not_listed() {
        let set = "estimators.kinds=[\"baseline\", \"bound\"]";
        assert_eq!(
            quick_faults(&[set]),
            format!(
                "--set {set}: estimators.kinds[1]: the bound is no method to list: it is computed for every DVL"
            )
        );
    }
}
