//! Checks `[dataset]`. In: the training trajectories by name, the window, stride and
//! validation share, and the trajectories and rate `[data]` gave. Out: the
//! [`DatasetSpec`] in samples, and DCNet's input window (`Window`), which the
//! calibration and the model check against.
//!
//! [`DatasetSpec`]: crate::spec::DatasetSpec

use super::{Defined, Faults, positive_samples};
use crate::spec::{DatasetSpec, file, ranges};
use std::collections::HashSet;

/// DCNet's input window: as written, in seconds, and in samples when that is good.
#[derive(Clone, Copy)]
pub(in crate::spec) struct Window {
    pub(in crate::spec) seconds: f64,
    pub(in crate::spec) samples: Option<usize>,
}

/// Checks `[dataset]`: window, stride and validation share, and training trajectories
/// that each hold one window.
pub(in crate::spec) fn check_dataset(
    dataset: file::DatasetFile,
    sources: &Defined,
    rate: f64,
    faults: &mut Faults,
) -> (DatasetSpec, Window) {
    let file::DatasetFile {
        trajectories: names,
        window_s,
        stride_s,
        validation_fraction,
        published_windows,
    } = dataset;
    let window = match ranges::DCNET_WINDOW_S.exceeded(window_s) {
        Some(why) => {
            faults.add("dataset.window_s", why);
            None
        }
        None => positive_samples("dataset.window_s", window_s, rate, faults),
    };
    let stride = positive_samples("dataset.stride_s", stride_s, rate, faults);
    let trajectories = check_training_trajectories(&names, sources, window, window_s, faults);
    let valid_fraction = validation_fraction > 0.0 && validation_fraction < 1.0;
    if !valid_fraction {
        faults.add(
            "dataset.validation_fraction",
            format!(
                "{validation_fraction} must be above 0 and below 1: training keeps the epoch with the best validation loss"
            ),
        );
    }
    let dataset = DatasetSpec {
        trajectories,
        window_samples: window.unwrap_or_default(),
        stride_samples: stride.unwrap_or_default(),
        validation_fraction,
        published_windows,
    };
    if valid_fraction && window.is_some() && stride.is_some() {
        check_split(&dataset, sources, faults);
    }
    let window = Window {
        seconds: window_s,
        samples: window,
    };
    (dataset, window)
}

/// The training trajectories by index: each defined, listed once, and (where its
/// length is known) holding one window of `window` samples (`window_s` as written).
fn check_training_trajectories(
    names: &[String],
    sources: &Defined,
    window: Option<usize>,
    window_s: f64,
    faults: &mut Faults,
) -> Vec<usize> {
    if names.is_empty() {
        faults.add(
            "dataset.trajectories",
            "is empty: name at least one training trajectory",
        );
    }
    let mut trajectories = Vec::new();
    let mut listed = HashSet::new();
    for (i, wanted) in names.iter().enumerate() {
        let key = format!("dataset.trajectories[{i}]");
        if !listed.insert(wanted) {
            faults.add(key, format!("{wanted:?} is listed twice"));
            continue;
        }
        if let Some(index) = sources.lookup(&key, wanted, faults) {
            if let (Some(len), Some(window)) = (sources[index].known_len(), window)
                && len < window
            {
                faults.add(
                    key,
                    format!("{wanted} has {len} samples, fewer than one window of {window_s} s"),
                );
            }
            trajectories.push(index);
        }
    }
    trajectories
}

/// Where the training trajectories' lengths are known, checks that
/// `validation_fraction` leaves each grid combination at least one validation window
/// and at least one training window.
fn check_split(dataset: &DatasetSpec, sources: &Defined, faults: &mut Faults) {
    let lengths: Option<Vec<usize>> = dataset
        .trajectories
        .iter()
        .map(|&t| sources[t].known_len())
        .collect();
    let Some(lengths) = lengths else { return };
    let windows = dataset.windows_per_combination(lengths);
    let validation = dataset.validation_windows(windows);
    if windows > 0 && (validation == 0 || validation == windows) {
        faults.add(
            "dataset.validation_fraction",
            format!(
                "{} of {windows} windows per combination leaves {validation} for validation and {} for training: each needs at least one",
                dataset.validation_fraction,
                windows - validation
            ),
        );
    }
}

#[cfg(test)]
mod tests {
    use crate::spec::fixture::quick_faults;
    use crate::spec::load;
    use std::path::Path;

    #[test]
    fn training_needs_validation_and_training_windows() {
        let error = quick_faults(&["dataset.validation_fraction=0.0"]);
        assert!(
            error.contains("dataset.validation_fraction: 0 must be above 0 and below 1"),
            "{error}"
        );
        // quick.toml's S1 and S2 give 165 windows per combination.
        let error = quick_faults(&["dataset.validation_fraction=0.001"]);
        assert!(
            error.contains(
                "0.001 of 165 windows per combination leaves 0 for validation and 165 for training"
            ),
            "{error}"
        );
        let error = quick_faults(&["dataset.validation_fraction=0.999"]);
        assert!(
            error.contains("leaves 165 for validation and 0 for training"),
            "{error}"
        );
        assert!(
            load(
                &Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quick.toml"),
                &["dataset.validation_fraction=0.01".to_string()]
            )
            .is_ok()
        );
    }
}
