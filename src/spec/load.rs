//! Reads a spec file, applies `--set KEY=VALUE` overrides, deserializes and checks it.
//! Every fault, from a TOML syntax error to a failed check, comes back as a
//! [`SpecError`] that names the file and line (or the `--set` it came from) and the key.

use super::{Spec, SpecFile};
use std::fmt;
use std::path::{Path, PathBuf};
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

/// Reads, overrides, deserializes and checks the spec at `path`.
pub fn load(path: &Path, overrides: &[String]) -> Result<Spec, SpecErrors> {
    let shown = path.display().to_string();
    let fail = |message: String| {
        SpecErrors(vec![SpecError {
            location: shown.clone(),
            key: String::new(),
            message,
        }])
    };
    let text =
        std::fs::read_to_string(path).map_err(|e| fail(format!("cannot read the spec: {e}")))?;
    let spans = DeTable::parse(&text).map_err(|e| {
        let location = match e.span() {
            Some(span) => format!("{shown}:{}", line_of(&text, span.start)),
            None => shown.clone(),
        };
        SpecErrors(vec![SpecError {
            location,
            key: String::new(),
            message: e.message().trim().to_string(),
        }])
    })?;
    let mut table: toml::Table =
        toml::from_str(&text).map_err(|e| fail(e.message().to_string()))?;

    let mut applied = Vec::new();
    let mut errors = Vec::new();
    for assignment in overrides {
        match apply_override(&mut table, assignment) {
            Ok(key) => applied.push((key, assignment.clone())),
            Err(message) => errors.push(SpecError {
                location: format!("--set {assignment}"),
                key: String::new(),
                message,
            }),
        }
    }
    if !errors.is_empty() {
        return Err(SpecErrors(errors));
    }
    let locate = |key: String, message: String| {
        let overridden = applied.iter().rev().find(|(set, _)| {
            key == *set
                || key.starts_with(&format!("{set}."))
                || key.starts_with(&format!("{set}["))
        });
        let location = match overridden {
            Some((_, assignment)) => format!("--set {assignment}"),
            None => format!("{shown}:{}", line_of(&text, span_of(&spans, &key))),
        };
        SpecError {
            location,
            key,
            message,
        }
    };

    let file: SpecFile =
        serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
            let key = e.path().to_string();
            let key = if key == "." { String::new() } else { key };
            SpecErrors(vec![locate(key, e.into_inner().message().to_string())])
        })?;
    let spec_dir = path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    let spec_dir = if spec_dir.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        spec_dir
    };
    let spec_dir = std::path::absolute(&spec_dir).unwrap_or(spec_dir);
    file.check(&spec_dir).map_err(|faults| {
        SpecErrors(
            faults
                .into_iter()
                .map(|(key, message)| locate(key, message))
                .collect(),
        )
    })
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

fn fault_at(shown: &str, text: &str, key: &str, message: &dyn fmt::Display) -> SpecError {
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
enum Step<'a> {
    Key(&'a str),
    Index(usize),
}

/// Splits `data.trajectories[2].samples` (or `data.trajectories.2.samples`) into steps.
fn steps(key: &str) -> Result<Vec<Step<'_>>, String> {
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

/// Applies `key=value` to `table`; the value is read as TOML, or as a string when it
/// is not valid TOML. Returns the key in the form errors are reported with.
fn apply_override(table: &mut toml::Table, assignment: &str) -> Result<String, String> {
    let (key, raw) = assignment
        .split_once('=')
        .ok_or("expected KEY=VALUE, such as calibration.monte_carlo_runs=50")?;
    let key = key.trim();
    let path = steps(key)?;
    let value = toml::from_str::<toml::Table>(&format!("value = {raw}"))
        .ok()
        .and_then(|mut t| t.remove("value"))
        .unwrap_or_else(|| toml::Value::String(raw.to_string()));
    let mut root = toml::Value::Table(std::mem::take(table));
    let result = set_at(&mut root, &path, value);
    if let toml::Value::Table(t) = root {
        *table = t;
    }
    result.map(|()| {
        let mut canonical = String::new();
        for step in &path {
            match step {
                Step::Key(k) if canonical.is_empty() => canonical.push_str(k),
                Step::Key(k) => canonical.push_str(&format!(".{k}")),
                Step::Index(i) => canonical.push_str(&format!("[{i}]")),
            }
        }
        canonical
    })
}

/// Puts `new` at `path` below `value`, creating missing tables on the way.
fn set_at(value: &mut toml::Value, path: &[Step<'_>], new: toml::Value) -> Result<(), String> {
    let Some((first, rest)) = path.split_first() else {
        *value = new;
        return Ok(());
    };
    let child = match (first, value) {
        (Step::Key(k), toml::Value::Table(t)) => t
            .entry(k.to_string())
            .or_insert_with(|| toml::Value::Table(Default::default())),
        (Step::Index(i), toml::Value::Array(a)) => {
            let len = a.len();
            a.get_mut(*i)
                .ok_or_else(|| format!("index [{i}] is out of range: there are {len} entries"))?
        }
        (Step::Key(k), _) => {
            return Err(format!("cannot set key {k:?}: its parent is not a table"));
        }
        (Step::Index(i), _) => {
            return Err(format!(
                "cannot set index [{i}]: its parent is not an array"
            ));
        }
    };
    set_at(child, rest, new)
}

/// Byte offset where `key` (or its deepest existing parent) is written in the spec.
fn span_of(root: &Spanned<DeTable<'_>>, key: &str) -> usize {
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

fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_paths_split_into_steps() {
        assert_eq!(
            steps("dvl[1].noise_cm_s").unwrap(),
            vec![Step::Key("dvl"), Step::Index(1), Step::Key("noise_cm_s")]
        );
        assert_eq!(
            steps("dvl.1.noise_cm_s").unwrap(),
            steps("dvl[1].noise_cm_s").unwrap()
        );
    }

    #[test]
    fn overrides_read_toml_values_and_fall_back_to_strings() {
        let mut table: toml::Table = toml::from_str("[a]\nb = 1\n[[c]]\nd = 2\n").unwrap();
        assert_eq!(apply_override(&mut table, "a.b=[3, 4]").unwrap(), "a.b");
        assert_eq!(apply_override(&mut table, "c.0.d=hello").unwrap(), "c[0].d");
        assert_eq!(
            table["a"]["b"],
            toml::Value::Array(vec![3.into(), 4.into()])
        );
        assert_eq!(table["c"][0]["d"], toml::Value::String("hello".into()));
        assert!(apply_override(&mut table, "c[5].d=1").is_err());
        assert!(apply_override(&mut table, "novalue").is_err());
    }

    #[test]
    fn keys_are_found_on_their_lines() {
        let text = "name = \"x\"\n\n[calibration]\nruns = 3\nwindow_sizes_s = [1, 2]\n\n[[dvl]]\nname = \"a\"\n[[dvl]]\nname = \"b\"\nnoise = 1\n";
        let spans = DeTable::parse(text).unwrap();
        assert_eq!(
            line_of(text, span_of(&spans, "calibration.window_sizes_s")),
            5
        );
        assert_eq!(line_of(text, span_of(&spans, "dvl[1].noise")), 11);
        // A missing key points at its deepest parent that exists.
        assert_eq!(line_of(text, span_of(&spans, "calibration.missing")), 3);
    }
}
