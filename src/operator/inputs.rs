//! What the operator's commands share about their inputs: the columns a `--columns`
//! file names (A-KIT's without one), and the check that no file a command writes is one
//! it reads.
//! In: the paths given on the command line. Out: the columns, or the file at fault.

use crate::data::paired::{GapLimit, PairedColumns};
use crate::spec::{SpecError, TomlFile};
use std::path::{Path, PathBuf};

/// The first of `outputs` that would replace one of `inputs`, and that input.
pub fn not_over_an_input(
    inputs: &[Option<&Path>],
    outputs: &[&Path],
) -> Option<(PathBuf, PathBuf)> {
    // A file's identity: its path with the folder's links resolved.
    let identity = |path: &Path| -> Option<PathBuf> {
        let folder = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        Some(std::fs::canonicalize(folder).ok()?.join(path.file_name()?))
    };
    for output in outputs {
        let same = |input: &&&Path| {
            identity(input).is_some_and(|i| identity(output).is_some_and(|o| o == i))
                || std::fs::canonicalize(input)
                    .ok()
                    .is_some_and(|i| std::fs::canonicalize(output).is_ok_and(|o| o == i))
        };
        if let Some(input) = inputs.iter().flatten().find(same) {
            return Some((output.to_path_buf(), input.to_path_buf()));
        }
    }
    None
}

/// What the command line says of how to read a recording, beyond its columns: each
/// as the `[columns]` table's key of the same name, and over it.
#[derive(Debug, Clone, Copy, Default)]
pub struct Reading<'a> {
    /// The DVL's validity column (`--valid-column`, the table's `valid`).
    pub valid_column: Option<&'a str>,
    /// The gap limit, s (`--gap-limit-s`, the table's `gap_limit_s`).
    pub gap_limit_s: Option<f64>,
}

/// The columns of `path`'s `[columns]` table, or A-KIT's, with what the command line
/// says of the `reading` over them.
pub fn columns(path: Option<&Path>, reading: Reading) -> Result<PairedColumns, SpecError> {
    let Reading {
        valid_column: valid,
        gap_limit_s,
    } = reading;
    let gap_limit_s = gap_limit_s.map(GapLimit);
    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct ColumnsFile {
        columns: PairedColumns,
    }
    let Some(path) = path else {
        let mut columns = PairedColumns::akit();
        columns.valid = valid.map(String::from);
        columns.gap_limit_s = gap_limit_s;
        return match columns.named_twice() {
            Some((_, why)) => Err(SpecError {
                location: "--valid-column".into(),
                key: String::new(),
                message: why,
            }),
            None => Ok(columns),
        };
    };
    let mut file = TomlFile::<ColumnsFile>::read(path)?;
    if let Some(valid) = valid {
        file.value.columns.valid = Some(valid.to_string());
    }
    if gap_limit_s.is_some() {
        file.value.columns.gap_limit_s = gap_limit_s;
    }
    if let Some((key, why)) = file.value.columns.named_twice() {
        let fault = file.fault(&format!("columns.{key}"), why);
        return Err(fault);
    }
    Ok(file.value.columns)
}
