//! Whose a results folder is: the spec file its manifest records, by its path from the
//! output folder (so a project moved or copied whole, results and specs together,
//! keeps its owners; a folder copied away from its spec file, where that path leads
//! to no file, belongs to anyone). A run replaces a folder written from its own spec file (an
//! edited spec, other `--set` values), but never, without `--force`, one that another
//! spec file with the same `name` wrote; a single run, a sweep and an installation
//! study never write into a folder that holds another of them. In: a plan and one of its points. Out:
//! nothing, or an [`OwnerError`] naming both.

use super::{Plan, cache};
use crate::results::{self, Manifest, sweep};
use std::path::{Component, Path, PathBuf};

/// A results folder that belongs to another spec.
#[derive(Debug, thiserror::Error)]
pub enum OwnerError {
    #[error(
        "{}: holds the results of {} ({their_name}, spec SHA-256 {their_hash}); this run's spec is {} ({our_name}, spec SHA-256 {our_hash}), whose `name` is the same: give it another `name`, or --force replaces those results",
        folder.display(), theirs.display(), ours.display()
    )]
    AnotherSpec {
        folder: PathBuf,
        theirs: PathBuf,
        their_name: String,
        their_hash: String,
        ours: PathBuf,
        our_name: String,
        our_hash: String,
    },
    #[error(
        "{}: is a file, where the results folder goes; move or remove it",
        folder.display()
    )]
    NotAFolder { folder: PathBuf },
    #[error(
        "{}: holds {theirs}, and this run of {} ({name}) is {ours}: one folder cannot hold both; give the spec another `name`, or move the folder away",
        folder.display(), spec.display()
    )]
    OtherKind {
        folder: PathBuf,
        theirs: &'static str,
        ours: &'static str,
        spec: PathBuf,
        name: String,
    },
}

/// The claim key of point `p`'s results folder, the same for every spec that writes
/// it: processes writing one folder take turns.
pub fn folder_key(plan: &Plan, p: usize) -> String {
    cache::hash(&("results folder", &plan.spec(p).name))
}

/// `spec_file` as a manifest records it: its path from the output folder `out`.
pub fn recorded(spec_file: &Path, out: &Path) -> Option<String> {
    let spec_file = std::fs::canonicalize(spec_file).ok()?;
    let out = std::fs::canonicalize(out)
        .or_else(|_| std::path::absolute(out))
        .ok()?;
    let relative = pathdiff::diff_paths(&spec_file, &out)?;
    Some(relative.to_string_lossy().into_owned())
}

/// The spec file that `recorded` (a path from `out`) names, for a message.
fn resolved(out: &Path, recorded: &str) -> PathBuf {
    let out = std::path::absolute(out).unwrap_or_else(|_| out.to_path_buf());
    let mut path = PathBuf::new();
    for component in out.join(recorded).components() {
        match component {
            Component::ParentDir => {
                path.pop();
            }
            Component::CurDir => {}
            other => path.push(other),
        }
    }
    path
}

/// Refuses to write point `p`'s folder, unless `force`, when another spec wrote it.
pub fn check(plan: &Plan, p: usize, force: bool) -> Result<(), OwnerError> {
    let folder = &plan.points[p].folder;
    if folder.exists() && !folder.is_dir() {
        return Err(OwnerError::NotAFolder {
            folder: folder.clone(),
        });
    }
    let spec = plan.spec(p);
    let ours = plan.spec_file.clone().unwrap_or_default();
    check_kind(plan, folder, &resolved(&plan.out, &ours), &spec.name)?;
    if force {
        return Ok(());
    }
    let our_hash = crate::files::sha256_hex(spec.resolved_toml().as_bytes());
    another_spec(folder, &plan.out, &ours, &spec.name, &our_hash)
}

/// Refuses, unless `force`, to write an installation study named `name` from the spec
/// file `ours` (as [`recorded`] gives it) into `folder` when another spec file's study
/// is there; and, `force` or not, when a paper run or a sweep is.
pub fn check_installation(
    folder: &Path,
    out: &Path,
    ours: &str,
    name: &str,
    spec_sha256: &str,
    force: bool,
) -> Result<(), OwnerError> {
    if folder.exists() && !folder.is_dir() {
        return Err(OwnerError::NotAFolder {
            folder: folder.to_path_buf(),
        });
    }
    let held = Held::of(folder);
    if held != Held::Nothing && held != Held::InstallationResults {
        return Err(OwnerError::OtherKind {
            folder: folder.to_path_buf(),
            theirs: held.words(),
            ours: Held::InstallationResults.words(),
            spec: resolved(out, ours),
            name: name.to_string(),
        });
    }
    if force {
        return Ok(());
    }
    another_spec(folder, out, ours, name, spec_sha256)
}

/// Refuses to write the points of a study sweep named `name` into `folder` when it
/// holds a paper run, a paper sweep or a single study.
pub fn check_installation_sweep(
    folder: &Path,
    out: &Path,
    ours: &str,
    name: &str,
) -> Result<(), OwnerError> {
    if folder.exists() && !folder.is_dir() {
        return Err(OwnerError::NotAFolder {
            folder: folder.to_path_buf(),
        });
    }
    let held = Held::of(folder);
    if held != Held::Nothing && held != Held::InstallationSweep {
        return Err(OwnerError::OtherKind {
            folder: folder.to_path_buf(),
            theirs: held.words(),
            ours: Held::InstallationSweep.words(),
            spec: resolved(out, ours),
            name: name.to_string(),
        });
    }
    Ok(())
}

/// Refuses a folder whose manifest records a spec file other than `ours` that still
/// exists (a folder from before manifests named their spec file, a run that named
/// none, or a folder copied away from its spec file belongs to anyone).
fn another_spec(
    folder: &Path,
    out: &Path,
    ours: &str,
    our_name: &str,
    our_hash: &str,
) -> Result<(), OwnerError> {
    let Some(manifest) = read_manifest(folder) else {
        return Ok(());
    };
    let theirs = resolved(out, &manifest.spec_file);
    let our_path = resolved(out, ours);
    if manifest.spec_file.is_empty()
        || ours.is_empty()
        || manifest.spec_file == ours
        || !theirs.is_file()
        || same_file(&theirs, &our_path)
    {
        return Ok(());
    }
    Err(OwnerError::AnotherSpec {
        folder: folder.to_path_buf(),
        theirs,
        their_name: manifest.name,
        their_hash: short(&manifest.spec_sha256),
        ours: our_path,
        our_name: our_name.to_string(),
        our_hash: short(our_hash),
    })
}

/// What a results folder holds.
#[derive(PartialEq)]
enum Held {
    Nothing,
    Single,
    Sweep,
    InstallationResults,
    InstallationSweep,
}

impl Held {
    fn of(folder: &Path) -> Held {
        if folder.join(crate::results::installation::HELDOUT).is_file() {
            Held::InstallationResults
        } else if folder.join(sweep::INDEX).is_file() {
            match sweep::read_index(folder) {
                Ok(index) if index.kind == crate::installation::spec::KIND => {
                    Held::InstallationSweep
                }
                _ => Held::Sweep,
            }
        } else if folder.join(results::MANIFEST).is_file() {
            Held::Single
        } else {
            Held::Nothing
        }
    }

    fn words(&self) -> &'static str {
        match self {
            Held::Nothing => "nothing",
            Held::Single => "the results of a single run",
            Held::Sweep => "the points of a sweep",
            Held::InstallationResults => "the results of an installation study",
            Held::InstallationSweep => "the points of a sweep of installation studies",
        }
    }
}

/// Refuses a single run's results in a sweep's or a study's folder, and a sweep's
/// points in a single run's or a study's folder.
fn check_kind(plan: &Plan, folder: &Path, spec: &Path, name: &str) -> Result<(), OwnerError> {
    let (holder, ours) = if plan.experiment.is_sweep() {
        (folder.parent().unwrap_or(folder), Held::Sweep)
    } else {
        (folder, Held::Single)
    };
    let held = Held::of(holder);
    if held == Held::Nothing || held == ours {
        return Ok(());
    }
    Err(OwnerError::OtherKind {
        folder: holder.to_path_buf(),
        theirs: held.words(),
        ours: ours.words(),
        spec: spec.to_path_buf(),
        name: name.to_string(),
    })
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

fn read_manifest(folder: &Path) -> Option<Manifest> {
    let bytes = std::fs::read(folder.join(results::MANIFEST)).ok()?;
    serde_json::from_slice(&bytes).ok()
}

/// The first 16 hex digits of a SHA-256, as `plan` shows keys.
fn short(digest: &str) -> String {
    digest[..digest.len().min(16)].to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_recorded_path_resolves_against_the_output_folder() {
        assert_eq!(
            resolved(Path::new("/p/results"), "../experiments/quick.toml"),
            PathBuf::from("/p/experiments/quick.toml")
        );
        assert_eq!(
            resolved(Path::new("/p/results"), "./a.toml"),
            PathBuf::from("/p/results/a.toml")
        );
    }

    #[test]
    fn a_spec_file_is_recorded_by_its_path_from_the_output_folder() {
        let project = tempfile::tempdir().unwrap();
        let spec = project.path().join("experiments/quick.toml");
        std::fs::create_dir_all(spec.parent().unwrap()).unwrap();
        std::fs::write(&spec, "").unwrap();
        let out = project.path().join("results");
        assert_eq!(
            recorded(&spec, &out).as_deref(),
            Some("../experiments/quick.toml")
        );
        std::fs::create_dir_all(&out).unwrap();
        assert_eq!(
            recorded(&spec, &out).as_deref(),
            Some("../experiments/quick.toml")
        );
    }
}
