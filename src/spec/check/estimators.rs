//! Checks `[estimators]`. In: the kinds of estimator and the error models by name.
//! Out: each parsed, known and listed once; the bound and the DCNet ensemble, which a
//! spec does not list, refused with the reason.

use super::Faults;
use crate::spec::file;
use crate::vocab::{ErrorModel, EstimatorKind};

/// Checks `[estimators]`: kinds and error models known, each listed once.
pub(in crate::spec) fn check_estimators(
    estimators: file::EstimatorsFile,
    faults: &mut Faults,
) -> (Vec<EstimatorKind>, Vec<ErrorModel>) {
    let file::EstimatorsFile {
        kinds,
        error_models,
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
    (kinds, error_models)
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
