//! Where a spec's values came from, so that a fault lands where a user can fix it. In:
//! the spec's text, the folder its relative paths start from, and the keys that `--set`
//! or a sweep point assigned. Out: a [`SpecError`] placed on the `--set` or sweep value
//! that assigned its key (or one below it), or on the key's line; and a table
//! deserialized and checked into a [`Spec`], every fault so placed.

use crate::spec::toml_file::{Placer, SpecError, SpecErrors, TomlText, deserialize};
use crate::spec::{Spec, SpecFile};
use std::path::PathBuf;

/// Keys whose value does not come from the spec's own line, each with where it came
/// from (`--set KEY=VALUE`, or a sweep value's line and point), latest last.
#[derive(Debug, Clone, Default)]
pub(super) struct Assigned(pub(super) Vec<(String, String)>);

impl Assigned {
    /// Where the value at `key` came from, when it or a table above it was assigned.
    pub(super) fn origin(&self, key: &str) -> Option<&str> {
        self.0
            .iter()
            .rev()
            .find(|(set, _)| {
                key == *set
                    || key.starts_with(&format!("{set}."))
                    || key.starts_with(&format!("{set}["))
            })
            .map(|(_, location)| location.as_str())
    }

    /// Where a value below `key` came from, when one was assigned.
    fn below(&self, key: &str) -> Option<&str> {
        self.0
            .iter()
            .rev()
            .find(|(set, _)| {
                set.starts_with(&format!("{key}.")) || set.starts_with(&format!("{key}["))
            })
            .map(|(_, location)| location.as_str())
    }
}

/// The spec's text and the folder its relative paths start from.
#[derive(Debug, Clone)]
pub(super) struct SpecSource {
    pub(super) text: TomlText,
    pub(super) folder: PathBuf,
}

impl SpecSource {
    /// A fault at `key`, placed where its value came from: the `--set` or sweep value
    /// that assigned it (or, for a key the file does not write, one below it, such as
    /// an unknown table), or its line.
    pub(super) fn locate(&self, assigned: &Assigned, key: String, message: String) -> SpecError {
        Self::place(&self.text.placer(), assigned, key, message)
    }

    /// [`SpecSource::locate`] with the text parsed once, for many faults.
    fn place(placer: &Placer<'_>, assigned: &Assigned, key: String, message: String) -> SpecError {
        let origin = assigned.origin(&key).or_else(|| {
            // The key, or the deepest table above it that the file does not write
            // either (a missing key of a table that only `--set` gives).
            let mut unwritten = Some(key.as_str()).filter(|k| !placer.writes(k));
            while let Some(k) = unwritten {
                if let Some(origin) = assigned.below(k) {
                    return Some(origin);
                }
                unwritten = k
                    .rsplit_once(['.', '['])
                    .map(|(parent, _)| parent)
                    .filter(|parent| !placer.writes(parent));
            }
            None
        });
        match origin {
            Some(location) => SpecError {
                location: location.to_string(),
                key,
                message,
            },
            None => placer.fault(&key, message),
        }
    }

    /// Deserializes and checks `table`, each fault placed where its value came from.
    pub(super) fn check(
        &self,
        table: toml::Table,
        assigned: &Assigned,
    ) -> Result<Spec, SpecErrors> {
        let file: SpecFile = deserialize(toml::Value::Table(table))
            .map_err(|(key, message)| self.locate(assigned, key, message))?;
        file.check(&self.folder).map_err(|faults| {
            let placer = self.text.placer();
            SpecErrors(
                faults
                    .into_iter()
                    .map(|(key, message)| Self::place(&placer, assigned, key, message))
                    .collect(),
            )
        })
    }
}
