//! What the operator's commands share about their inputs: the columns a `--columns`
//! file names (A-KIT's without one), and the check that no file a command writes is one
//! it reads.
//! In: the paths given on the command line. Out: the columns, or the file at fault.

use crate::data::paired::PairedColumns;
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

/// The columns of `path`'s `[columns]` table, or A-KIT's, with the DVL's validity
/// column `valid` where the command line names one (`--valid-column`).
pub fn columns(path: Option<&Path>, valid: Option<&str>) -> Result<PairedColumns, SpecError> {
    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct ColumnsFile {
        columns: PairedColumns,
    }
    let Some(path) = path else {
        let mut columns = PairedColumns::akit();
        columns.valid = valid.map(String::from);
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
    if let Some((key, why)) = file.value.columns.named_twice() {
        let fault = file.fault(&format!("columns.{key}"), why);
        return Err(fault);
    }
    Ok(file.value.columns)
}
