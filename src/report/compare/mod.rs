//! `dcnet-exp compare A B`: what changed between two results folders, two runs or two
//! points of a sweep. In: the two folders, read back and schema-checked as
//! [`StoredRun`]s. Out: one Markdown text, printed and written to a file: the keys of
//! the resolved `spec.toml` that differ, every calibration cell (DVL, estimator, error
//! model, window) and evaluation cell (DVL, estimator, error model, trajectory) with
//! A, B and B − A, each RMSE difference marked when it exceeds twice the combined Monte
//! Carlo standard error, each method's calibration time ([`calibration_time`]), then
//! the DCNet training times and the wall time per stage side
//! by side, and a count of the marked cells.
//!
//! This module reads the two folders and writes the text; [`difference`] holds the
//! test of two means, [`spec_keys`] the spec's keys that differ, [`pairs`] pairs the
//! rows of A and B, and [`markdown`] sets it all as Markdown. Two installation studies
//! (folders holding `heldout.parquet`) are compared by [`study`] instead;
//! [`folders`] is the one entry, which reads the kind of the two folders and
//! dispatches.

pub mod calibration_time;
pub mod difference;
pub mod study;
pub mod markdown;
pub mod pairs;
pub mod spec_keys;

pub use difference::{Difference, FLOAT_NOISE, Mean, STANDARD_ERRORS};
pub use markdown::render;
pub use spec_keys::{KeyDifference, flatten, spec_differences};

use crate::files::write_atomic;
use crate::results::held::Held;
use crate::results::read::{ReadError, StoredRun};
use crate::results::sweep;
use std::path::{Path, PathBuf};

/// Where the comparison is written unless `--out` says otherwise: the current folder.
pub const DEFAULT_FILE: &str = "compare.md";

#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    #[error(transparent)]
    Read(#[from] ReadError),
    #[error(
        "{}: a sweep folder, not a results folder; compare two of its points: {}",
        path.display(),
        points.join(", ")
    )]
    Sweep { path: PathBuf, points: Vec<String> },
    #[error("{}", path.display())]
    SpecToml {
        path: PathBuf,
        #[source]
        source: Box<toml::de::Error>,
    },
    #[error(
        "{} is an installation study (it holds heldout.parquet) and {} a run of the paper: compare two studies or two runs",
        study.display(),
        run.display()
    )]
    InstallationAndRun { study: PathBuf, run: PathBuf },
    #[error("writing {}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Reads the results folder `folder`; a sweep folder is refused with its points listed.
pub fn read(folder: &Path) -> Result<StoredRun, CompareError> {
    refuse_sweep(folder)?;
    Ok(StoredRun::read(folder)?)
}

/// Refuses a sweep's folder (of runs or of studies), naming its points.
pub fn refuse_sweep(folder: &Path) -> Result<(), CompareError> {
    if !folder.join(sweep::INDEX).is_file() {
        return Ok(());
    }
    let index = sweep::read_index(folder)?;
    Err(CompareError::Sweep {
        path: folder.to_path_buf(),
        points: index
            .points
            .iter()
            .map(|point| folder.join(point).display().to_string())
            .collect(),
    })
}

/// The comparison of two results folders as Markdown, by their kind: two runs of the
/// paper ([`render`]) or two installation studies ([`study::render`]); a sweep's
/// folder, or one folder of each kind, is refused.
pub fn folders(first: &Path, second: &Path) -> Result<String, CompareError> {
    for folder in [first, second] {
        refuse_sweep(folder)?;
    }
    match (
        Held::of(first) == Held::Study,
        Held::of(second) == Held::Study,
    ) {
        (true, true) => Ok(study::render(&study::read(first)?, &study::read(second)?)),
        (true, false) => Err(CompareError::InstallationAndRun {
            study: first.to_path_buf(),
            run: second.to_path_buf(),
        }),
        (false, true) => Err(CompareError::InstallationAndRun {
            study: second.to_path_buf(),
            run: first.to_path_buf(),
        }),
        (false, false) => Ok(render(&read(first)?, &read(second)?)),
    }
}

/// Writes the comparison to `path`, atomically, making its folder if need be.
pub fn write(path: &Path, markdown: &str) -> Result<(), CompareError> {
    let failed = |source| CompareError::Write {
        path: path.to_path_buf(),
        source,
    };
    if let Some(folder) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(folder).map_err(failed)?;
    }
    write_atomic(path, markdown.as_bytes()).map_err(failed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_write_keeps_its_cause_for_the_chain_to_print_once() {
        let folder = tempfile::tempdir().unwrap();
        let file = folder.path().join("a-file");
        std::fs::write(&file, "").unwrap();
        let error = write(&file.join("compare.md"), "# text").unwrap_err();
        let cause = std::error::Error::source(&error).expect("the I/O error as its source");
        assert!(cause.downcast_ref::<std::io::Error>().is_some());
        assert_eq!(
            error.to_string(),
            format!("writing {}", file.join("compare.md").display())
        );
    }
}
