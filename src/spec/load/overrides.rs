//! `--set KEY=VALUE` overrides. In: the spec's TOML table and the assignments, each a
//! dotted key path (`dvl[1].noise_cm_s`) and a value read as TOML, or as a string when
//! it is not TOML. Out: the table with each value put at its path (missing tables
//! made on the way), and the keys assigned, so that a fault at one is placed on its
//! `--set`; or a fault per assignment that failed.

use super::source::Assigned;
use crate::spec::toml_file::{SpecError, SpecErrors, Step, shown_value, steps};

/// Applies every `--set KEY=VALUE` to `table`; the keys set, or a fault per assignment
/// that failed.
pub(super) fn apply_overrides(
    table: &mut toml::Table,
    overrides: &[String],
) -> Result<Assigned, SpecErrors> {
    let mut assigned = Assigned::default();
    let mut errors = Vec::new();
    for assignment in overrides {
        let location = match assignment.split_once('=') {
            Some((key, value)) => format!("--set {key}={}", shown_value(value)),
            None => format!("--set {}", shown_value(assignment)),
        };
        match apply_override(table, assignment) {
            Ok(key) => assigned.0.push((key, location)),
            Err(message) => errors.push(SpecError {
                location,
                key: assignment
                    .split_once('=')
                    .map(|(key, _)| key.trim().to_string())
                    .unwrap_or_default(),
                message,
            }),
        }
    }
    if !errors.is_empty() {
        return Err(SpecErrors(errors));
    }
    Ok(assigned)
}

/// Applies `key=value` to `table`; the value is read as TOML, or as a string when it
/// is not valid TOML. Returns the key in the form errors are reported with.
fn apply_override(table: &mut toml::Table, assignment: &str) -> Result<String, String> {
    let (key, raw) = assignment
        .split_once('=')
        .ok_or("expected KEY=VALUE, such as calibration.monte_carlo_runs=50")?;
    let key = key.trim();
    let path = steps(key)?;
    let value = match toml::from_str::<toml::Table>(&format!("value = {raw}")) {
        Ok(mut read) => read.remove("value"),
        Err(_) if raw.trim().replace('_', "").parse::<i128>().is_ok() => {
            return Err(format!(
                "{} is larger than TOML's largest integer, {}",
                raw.trim(),
                i64::MAX
            ));
        }
        Err(_) => None,
    }
    .unwrap_or_else(|| toml::Value::String(raw.to_string()));
    set_in(table, &path, value).map(|()| {
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

/// Puts `new` at `path` in `table`, creating missing tables on the way.
pub(super) fn set_in(
    table: &mut toml::Table,
    path: &[Step<'_>],
    new: toml::Value,
) -> Result<(), String> {
    let mut root = toml::Value::Table(std::mem::take(table));
    let result = set_at(&mut root, path, new);
    if let toml::Value::Table(t) = root {
        *table = t;
    }
    result
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
}
