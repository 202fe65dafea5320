//! TOML files that report their faults where a user can find them: `path:line: key:
//! message`. [`TomlFile`] reads a file into a type and places any later fault on its
//! key's line; the spec, its `--set` overrides and the published values all locate
//! keys here. In: a path or a TOML text. Out: the value, or [`SpecError`]s.

use std::fmt;
use std::path::Path;
use toml::Spanned;
use toml::de::{DeTable, DeValue};

/// One fault in a spec, placed where a user can find it.
#[derive(Debug, Clone, PartialEq)]
pub struct SpecError {
    /// `path/to/spec.toml:14`, or `--set key=value`.
    pub location: String,
    /// Dotted key path such as `data.trajectories[2].samples`; empty for syntax errors.
    pub key: String,
    pub message: String,
}

impl fmt::Display for SpecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.key.is_empty() {
            write!(f, "{}: {}", self.location, self.message)
        } else {
            write!(f, "{}: {}: {}", self.location, self.key, self.message)
        }
    }
}

/// Every fault found in a spec, one per line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct SpecErrors(pub Vec<SpecError>);

impl fmt::Display for SpecErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let lines: Vec<String> = self.0.iter().map(ToString::to_string).collect();
        f.write_str(&lines.join("\n"))
    }
}

/// A TOML data file read into `T`, kept with its text so that later checks can name
/// the line of a key.
pub struct TomlFile<T> {
    pub value: T,
    shown: String,
    text: String,
}

impl<T: serde::de::DeserializeOwned> TomlFile<T> {
    /// Reads `path`; a fault reads `path:line: key: message`.
    pub fn read(path: &Path) -> Result<Self, SpecError> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SpecError {
            location: shown.clone(),
            key: String::new(),
            message: format!("cannot read it: {e}"),
        })?;
        if let Err(e) = DeTable::parse(&text) {
            let location = match e.span() {
                Some(span) => format!("{shown}:{}", line_of(&text, span.start)),
                None => shown.clone(),
            };
            return Err(SpecError {
                location,
                key: String::new(),
                message: e.message().trim().to_string(),
            });
        }
        let fault = |key: &str, message: &dyn fmt::Display| fault_at(&shown, &text, key, message);
        let table: toml::Table = toml::from_str(&text).map_err(|e| fault("", &e.message()))?;
        let value = serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
            let key = e.path().to_string();
            let key = if key == "." { String::new() } else { key };
            fault(&key, &e.into_inner().message())
        })?;
        Ok(TomlFile { value, shown, text })
    }
}

impl<T> TomlFile<T> {
    /// A fault at `key`, placed on the key's line.
    pub fn fault(&self, key: &str, message: impl fmt::Display) -> SpecError {
        fault_at(&self.shown, &self.text, key, &message)
    }
}

pub(super) fn fault_at(
    shown: &str,
    text: &str,
    key: &str,
    message: &dyn fmt::Display,
) -> SpecError {
    let line = DeTable::parse(text)
        .map(|spans| line_of(text, span_of(&spans, key)))
        .unwrap_or(1);
    SpecError {
        location: format!("{shown}:{line}"),
        key: key.to_string(),
        message: message.to_string(),
    }
}

/// One step of a key path.
#[derive(Debug, PartialEq)]
pub(super) enum Step<'a> {
    Key(&'a str),
    Index(usize),
}

/// Splits `data.trajectories[2].samples` (or `data.trajectories.2.samples`) into steps.
pub(super) fn steps(key: &str) -> Result<Vec<Step<'_>>, String> {
    let mut steps = Vec::new();
    for part in key.split('.') {
        let (name, indices) = part
            .split_once('[')
            .map_or((part, ""), |(name, rest)| (name, rest));
        if let Ok(index) = name.parse::<usize>() {
            steps.push(Step::Index(index));
        } else if !name.is_empty() {
            steps.push(Step::Key(name));
        } else if indices.is_empty() {
            return Err(format!("{key:?} has an empty key segment"));
        }
        for index in indices.split('[').filter(|s| !s.is_empty()) {
            let index = index
                .strip_suffix(']')
                .and_then(|i| i.parse().ok())
                .ok_or_else(|| format!("{key:?}: bad index [{index}"))?;
            steps.push(Step::Index(index));
        }
    }
    Ok(steps)
}

/// Byte offset where `key` (or its deepest existing parent) is written in the spec.
pub(super) fn span_of(root: &Spanned<DeTable<'_>>, key: &str) -> usize {
    let mut best = 0;
    let Ok(path) = steps(key) else { return best };
    let mut table = Some(root.get_ref());
    let mut array: Option<&[Spanned<DeValue<'_>>]> = None;
    for step in path {
        let found = match (step, table, array) {
            (Step::Key(k), Some(t), _) => t
                .iter()
                .find(|(name, _)| name.get_ref() == k)
                .map(|(name, value)| (name.span().start, value)),
            (Step::Index(i), _, Some(a)) => a.get(i).map(|value| (value.span().start, value)),
            _ => None,
        };
        let Some((start, value)) = found else { break };
        best = start;
        (table, array) = match value.get_ref() {
            DeValue::Table(t) => (Some(t), None),
            DeValue::Array(a) => (None, Some(&a[..])),
            _ => (None, None),
        };
    }
    best
}

pub(super) fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}
