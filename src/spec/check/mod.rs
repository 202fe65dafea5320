//! The checks of a spec, one file per section. In: a section of the [`SpecFile`] as
//! read from TOML, and what earlier sections gave (the trajectories, the sample rate,
//! DCNet's window). Out: the section's checked type, and every fault as its key path
//! and message in `Faults`. [`SpecFile::check`] calls them in the order of the file.
//!
//! This file holds what the sections share: `Faults`, a trajectory looked up by name,
//! seconds as a positive number of samples, the rules of an error term and of a
//! results folder's name, and `Limit::check`, which adds a fault for a value beyond
//! its [`Limit`]. A new key's rule goes in its section's file, beside its tests. The
//! installation spec's checks, one file a section in `installation/spec/check/`,
//! collect their faults in the same `Faults` and check `[learned.model]` and
//! `[learned.training]` with `check_model_and_training`.
//!
//! [`SpecFile`]: crate::spec::SpecFile
//! [`SpecFile::check`]: crate::spec::SpecFile::check

pub mod data;
pub mod sensors;
pub mod grid;
pub mod dataset;
pub mod calibration;
pub mod evaluation;
pub mod estimators;
pub mod model;
pub mod training;
pub mod report;

use crate::spec::ranges::{self, Limit};
use crate::spec::{MAX_NAME_CHARS, TrajectorySource, seconds_to_samples};
use std::collections::HashMap;

/// A key path such as `data.trajectories[2].samples`, and what is wrong there.
pub(crate) type Fault = (String, String);

/// Collects faults while checking, keyed by their path in the spec; the installation
/// spec's checks collect theirs in it too.
#[derive(Default)]
pub(crate) struct Faults(pub(crate) Vec<Fault>);

impl Faults {
    pub(crate) fn add(&mut self, key: impl Into<String>, message: impl Into<String>) {
        self.0.push((key.into(), message.into()));
    }
}

impl Limit {
    /// Adds a fault at `key` when `value` is above the limit.
    pub(super) fn check(&self, key: &str, value: f64, faults: &mut Faults) {
        if let Some(message) = self.exceeded(value) {
            faults.add(key, message);
        }
    }
}

/// Checks a `[model]` and a `[training]` table that another kind of spec holds under
/// `prefix` (`"learned."` for `[learned.model]`), for windows of `window` samples: the
/// checked settings, and the faults at their keys under the prefix.
pub(crate) fn check_model_and_training(
    model: crate::spec::file::ModelFile,
    training: crate::spec::file::TrainingFile,
    window: usize,
    prefix: &str,
) -> (
    crate::spec::ModelSpec,
    crate::spec::TrainingSpec,
    Vec<Fault>,
) {
    let mut faults = Faults(Vec::new());
    let model = model::check_model(model, Some(window), &mut faults);
    let training = training::check_training(training, &mut faults);
    let faults = faults
        .0
        .into_iter()
        .map(|(key, message)| (format!("{prefix}{key}"), message))
        .collect();
    (model, training, faults)
}

/// Whether `name` can name a results folder: letters, digits, '-', '_', '.', and for
/// the points of a sweep (`<name>/<point>`) '/', '=' and ','; no part empty, longer
/// than [`MAX_NAME_CHARS`] or starting with '.' (`.`, `..`, and the `.cache` beside the
/// results).
pub(crate) fn is_folder_name(name: &str) -> bool {
    name.split('/').all(|part| {
        !part.is_empty()
            && !part.starts_with('.')
            && part.len() <= MAX_NAME_CHARS
            && part
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_.=,".contains(c))
    })
}

/// The trajectories `[data]` defines, indexed by name: each lookup takes the same
/// time however many there are, so a spec listing many names is checked in linear time.
pub(in crate::spec) struct Defined<'a> {
    sources: &'a [TrajectorySource],
    by_name: HashMap<&'a str, usize>,
}

/// The most defined names a fault lists; the rest are counted.
const LISTED_NAMES: usize = 10;

impl<'a> Defined<'a> {
    pub(in crate::spec) fn new(sources: &'a [TrajectorySource]) -> Self {
        let mut by_name = HashMap::with_capacity(sources.len());
        for (i, source) in sources.iter().enumerate() {
            by_name.entry(source.name.as_str()).or_insert(i);
        }
        Defined { sources, by_name }
    }

    /// The index of the trajectory named `wanted`; a fault at `key` when none is.
    pub(super) fn lookup(&self, key: &str, wanted: &str, faults: &mut Faults) -> Option<usize> {
        let found = self.by_name.get(wanted).copied();
        if found.is_none() {
            let mut known: Vec<&str> = self
                .sources
                .iter()
                .take(LISTED_NAMES)
                .map(|s| s.name.as_str())
                .collect();
            let more = self.sources.len().saturating_sub(LISTED_NAMES);
            let all = format!("… ({} in all)", self.sources.len());
            if more > 0 {
                known.push(&all);
            }
            let known = if known.is_empty() {
                "none".to_string()
            } else {
                known.join(", ")
            };
            faults.add(
                key,
                format!("unknown trajectory {wanted:?}; data.trajectories defines {known}"),
            );
        }
        found
    }
}

impl std::ops::Index<usize> for Defined<'_> {
    type Output = TrajectorySource;

    fn index(&self, i: usize) -> &TrajectorySource {
        &self.sources[i]
    }
}

pub(super) fn positive_samples(
    key: &str,
    seconds: f64,
    rate: f64,
    faults: &mut Faults,
) -> Option<usize> {
    match seconds_to_samples(seconds, rate) {
        Some(samples) if samples > 0 => Some(samples),
        _ => {
            faults.add(
                key,
                format!("{seconds} must be a positive whole number of samples at {rate} Hz"),
            );
            None
        }
    }
}

/// A scale factor error: above -100 % (the DVL still measures) and within its range.
pub(super) fn check_scale(key: &str, value: f64, faults: &mut Faults) {
    if !(value.is_finite() && value > -100.0) {
        faults.add(key, format!("{value} must be above -100 %"));
    }
    ranges::SCALE_PCT.check(key, value, faults);
}

/// A velocity noise: zero or positive and within its range.
pub(super) fn check_noise(key: &str, value: f64, faults: &mut Faults) {
    non_negative(key, value, faults);
    ranges::VELOCITY_ERROR_CM_S.check(key, value, faults);
}

pub(super) fn non_negative(key: &str, value: f64, faults: &mut Faults) {
    if !(value.is_finite() && value >= 0.0) {
        faults.add(key, format!("{value} must be zero or positive"));
    }
}

#[cfg(test)]
mod tests {
    use crate::spec::fixture::quick_faults;

    #[test]
    fn lists_whose_repeats_make_no_sense_are_refused() {
        let error = quick_faults(&["calibration.window_sizes_s=[20, 40, 20.0]"]);
        assert!(
            error.contains(
                "calibration.window_sizes_s[2]: 20 s is calibration.window_sizes_s[0] again"
            ),
            "{error}"
        );
        let error = quick_faults(&["dataset.trajectories=[\"S1\", \"S2\", \"S1\"]"]);
        assert!(
            error.contains("dataset.trajectories[2]: \"S1\" is listed twice"),
            "{error}"
        );
        let error = quick_faults(&["evaluation.trajectories=[\"S3\", \"S3\"]"]);
        assert!(
            error.contains("evaluation.trajectories[1]: \"S3\" is listed twice"),
            "{error}"
        );
        let error = quick_faults(&["grid.scale_pct={values = [0.5, 1.0, 0.5]}"]);
        assert!(
            error.contains("grid.scale_pct.values[2]: 0.5 is listed twice"),
            "{error}"
        );
        let error = quick_faults(&["estimators.kinds=[\"baseline\", \"baseline\"]"]);
        assert!(
            error.contains("estimators.kinds[1]: \"baseline\" is listed twice"),
            "{error}"
        );
    }
}
