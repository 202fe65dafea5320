//! Reads a spec file, applies `--set KEY=VALUE` overrides, deserializes and checks it;
//! a spec with a `[sweep]` becomes an [`Experiment`] of points, each checked the same
//! way. Every fault, from a TOML syntax error to a failed check, comes back as a
//! [`SpecError`] that names the file and line (or the `--set` or sweep value it came
//! from) and the key.
//!
//! - this file reads the spec and hands it on: [`load_experiment`] and [`load`];
//! - [`source`] keeps the spec's text and where each key's value was assigned, places a
//!   fault there, and checks a table with its faults so placed;
//! - [`overrides`] applies `--set` assignments to the spec's table;
//! - [`sweep`] expands `[sweep.values]` into its points, draws a sample of them, and
//!   names each point's results folder by its values.

pub mod source;
pub mod overrides;
pub mod sweep;

use super::Spec;
use super::toml_file::{SpecError, SpecErrors, TomlText, shown_value};
use overrides::apply_overrides;
use source::{Assigned, SpecSource};
use std::path::{Path, PathBuf};
use sweep::load_sweep;

/// A spec's points: the spec itself, or one per point of its `[sweep]`. `S` is the
/// checked spec of its kind: the paper's [`Spec`], or another kind's (an installation
/// study's).
#[derive(Debug, Clone)]
pub struct Experiment<S = Spec> {
    pub name: String,
    /// The swept keys in the order `[sweep.values]` lists them; empty without a sweep.
    pub swept: Vec<String>,
    pub points: Vec<Point<S>>,
    /// Where the spec's keys are written or were set, to place later faults.
    source: SpecSource,
    assigned: Assigned,
}

#[derive(Debug, Clone)]
pub struct Point<S = Spec> {
    /// One value per swept key.
    pub values: Vec<toml::Value>,
    /// The point's spec; a sweep point is named `<name>/<point>`, its results folder.
    pub spec: S,
}

impl<S> Experiment<S> {
    pub fn is_sweep(&self) -> bool {
        !self.swept.is_empty()
    }

    /// A fault at `key` found after loading, such as the memory a point needs, placed
    /// where the key is written or was set.
    pub fn fault(&self, key: &str, message: impl Into<String>) -> SpecError {
        self.source
            .locate(&self.assigned, key.to_string(), message.into())
    }
}

impl Experiment {
    /// What the spec asks that runs but says little, each placed like a fault: a test
    /// trajectory that is the calibration trajectory (its error is measured on the
    /// samples the calibration saw), and a training trajectory that is the calibration
    /// trajectory or a test one (the networks have learnt the samples they are then
    /// given).
    pub fn warnings(&self) -> Vec<SpecError> {
        let mut warnings: Vec<SpecError> = Vec::new();
        for point in &self.points {
            let spec = &point.spec;
            let calibration = spec.calibration.trajectory;
            let name = |t: usize| &spec.trajectories[t].name;
            let mut found = Vec::new();
            for (i, &t) in spec.evaluation.iter().enumerate() {
                if t == calibration {
                    found.push((
                        format!("evaluation.trajectories[{i}]"),
                        format!(
                            "{:?} is also calibration.trajectory: it is evaluated on the trajectory it was calibrated on, so its RMSE says little of another dive",
                            name(t)
                        ),
                    ));
                }
            }
            for (i, &t) in spec.dataset.trajectories.iter().enumerate() {
                let also = if t == calibration {
                    "calibration.trajectory: the networks have trained on the trajectory they calibrate"
                } else if spec.evaluation.contains(&t) {
                    "an evaluation trajectory: the networks have trained on the trajectory they are tested on, so its RMSE is not held out"
                } else {
                    continue;
                };
                found.push((
                    format!("dataset.trajectories[{i}]"),
                    format!("{:?} is also {also}", name(t)),
                ));
            }
            for (key, message) in found {
                let warning = self.fault(&key, message);
                if !warnings.contains(&warning) {
                    warnings.push(warning);
                }
            }
        }
        warnings
    }
}

/// Reads the spec at `path` with its overrides; the first point of a sweep.
pub fn load(path: &Path, overrides: &[String]) -> Result<Spec, SpecErrors> {
    let mut experiment = load_experiment(path, overrides)?;
    Ok(experiment.points.swap_remove(0).spec)
}

/// Reads, overrides, deserializes and checks the spec at `path`, and every point of
/// its `[sweep]`.
pub fn load_experiment(path: &Path, overrides: &[String]) -> Result<Experiment, SpecErrors> {
    load_points(path, overrides, |source, table, assigned| {
        source.check(table, assigned)
    })
}

/// Reads the spec at `path` with its overrides, and checks it with `check` (each point
/// of its `[sweep]` when it has one, named `<name>/<point>`).
fn load_points<S>(
    path: &Path,
    overrides: &[String],
    check: impl Fn(&SpecSource, toml::Table, &Assigned) -> Result<S, SpecErrors>,
) -> Result<Experiment<S>, SpecErrors> {
    let text = TomlText::read(path, "cannot read the spec")?;
    let mut table = text.table()?;
    let assigned = apply_overrides(&mut table, overrides)?;
    let source = SpecSource {
        text,
        folder: spec_folder(path),
    };
    let name = table
        .get("name")
        .and_then(toml::Value::as_str)
        .unwrap_or_default()
        .to_string();
    // '/', '=' and ',' name a sweep's points (`<name>/<point>`): a spec's own name with
    // them would write into a sweep's folder, or below another results folder.
    if name.contains(['/', '=', ',']) {
        return Err(source
            .locate(&assigned, "name".into(), format!("{:?} must use only letters, digits, '-', '_' and '.' (it names the results folder; '/', '=' and ',' name the points of a sweep)", shown_value(&name)))
            .into());
    }
    match table.remove("sweep") {
        None => {
            let spec = check(&source, table, &assigned)?;
            Ok(Experiment {
                name,
                swept: Vec::new(),
                points: vec![Point {
                    values: Vec::new(),
                    spec,
                }],
                source,
                assigned,
            })
        }
        Some(sweep) => load_sweep(source, table, sweep, assigned, check),
    }
}

/// The folder the relative paths of the spec at `path` start from, absolute if it can be.
/// The `kind` a spec file declares at its top: `None` for the paper's experiments (the
/// default), `Some("installation")` for a study of a real installation. Read before the
/// spec is checked, to choose its checks.
pub fn declared_kind(path: &Path) -> Result<Option<String>, SpecErrors> {
    let text = TomlText::read(path, "cannot read the spec")?;
    let table = text.table()?;
    match table.get("kind") {
        None => Ok(None),
        Some(toml::Value::String(kind)) => Ok(Some(kind.clone())),
        Some(other) => Err(text
            .fault(
                "kind",
                format!("{other} must be a string such as \"installation\""),
            )
            .into()),
    }
}

/// A TOML document of another kind than the paper's experiments (a study of a real
/// installation), read with the same `--set` overrides and the same placing of faults:
/// its value, the folder its relative paths start from, and where each key came from.
pub struct Document<T> {
    pub value: T,
    pub folder: PathBuf,
    /// The document with its overrides, as TOML: stored beside its results.
    pub resolved_toml: String,
    source: SpecSource,
    assigned: Assigned,
}

impl<T> Document<T> {
    /// A fault at `key`, placed where its value came from.
    pub fn fault(&self, key: &str, message: impl Into<String>) -> SpecError {
        self.source
            .locate(&self.assigned, key.to_string(), message.into())
    }

    /// Every fault of `faults` (key, message), each placed where its value came from.
    pub fn faults(&self, faults: Vec<(String, String)>) -> SpecErrors {
        SpecErrors(
            faults
                .into_iter()
                .map(|(key, message)| self.fault(&key, message))
                .collect(),
        )
    }
}

/// Reads `path` with `overrides` into `T` and checks it with `check`, each point of its
/// `[sweep]` when it has one; a value that does not fit is a fault placed on its line,
/// its `--set` or its sweep value.
pub fn load_documents<T: serde::de::DeserializeOwned, S>(
    path: &Path,
    overrides: &[String],
    check: impl Fn(Document<T>) -> Result<S, SpecErrors>,
) -> Result<Experiment<S>, SpecErrors> {
    load_points(path, overrides, |source, table, assigned| {
        let resolved_toml = toml::to_string_pretty(&table).expect("a TOML table serializes");
        let value = super::toml_file::deserialize(toml::Value::Table(table))
            .map_err(|(key, message)| source.locate(assigned, key, message))?;
        check(Document {
            value,
            folder: source.folder.clone(),
            resolved_toml,
            source: source.clone(),
            assigned: assigned.clone(),
        })
    })
}

fn spec_folder(path: &Path) -> PathBuf {
    let folder = path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    let folder = if folder.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        folder
    };
    std::path::absolute(&folder).unwrap_or(folder)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::fixture::{quick_faults, quick_plus};

    #[test]
    fn a_learning_rate_is_one_number_for_all_models_or_one_per_model() {
        let quick = |set: &[&str]| {
            let (_dir, path) = quick_plus("");
            let set: Vec<String> = set.iter().map(ToString::to_string).collect();
            load(&path, &set).map(|s| s.training.learning_rates)
        };
        assert_eq!(quick(&["training.learning_rate=1e-3"]).unwrap(), [1e-3; 5]);
        assert_eq!(quick(&["training.learning_rate=1"]).unwrap(), [1.0; 5]);
        assert_eq!(
            quick(&["training.learning_rate={EM2 = 2e-3}"]).unwrap(),
            [5e-5, 2e-3, 5e-5, 5e-5, 5e-4],
            "unlisted models keep their defaults"
        );
        let error = quick(&["training.learning_rate={EM6 = 1.0}"])
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("training.learning_rate.EM6: unknown field `EM6`"),
            "{error}"
        );
    }

    #[test]
    fn an_integer_beyond_toml_is_placed_at_its_line_and_key() {
        let folder = tempfile::tempdir().unwrap();
        let quick = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quick.toml");
        let text = std::fs::read_to_string(&quick).unwrap().replace(
            "fc_widths = [128, 64, 32]",
            "fc_widths = [128, 18446744073709551616, 32]",
        );
        let path = folder.path().join("huge.toml");
        std::fs::write(&path, &text).unwrap();
        let line = text
            .lines()
            .position(|l| l.starts_with("fc_widths"))
            .unwrap()
            + 1;
        let error = load(&path, &[]).unwrap_err().to_string();
        assert_eq!(
            error,
            format!(
                "{}:{line}: model.fc_widths[1]: 18446744073709551616 is larger than TOML's largest integer, 9223372036854775807",
                path.display()
            )
        );
        let error = quick_faults(&["seed=18446744073709551615"]);
        assert!(
            error.starts_with(
                "--set seed=18446744073709551615: seed: 18446744073709551615 is larger"
            ),
            "{error}"
        );
    }
}
