//! Whose a results folder is: the spec file its manifest records, by its path from the
//! output folder (so a project moved or copied whole, results and specs together,
//! keeps its owners; a folder copied away from its spec file, where that path leads
//! to no file, belongs to anyone). A run replaces a folder written from its own spec file (an
//! edited spec, other `--set` values), but never, without `--force`, one that another
//! spec file with the same `name` wrote; a single run, a sweep and an installation
//! study never write into a folder that holds another of them. One check serves every
//! kind of run. In: a [`Writer`]: the folder, the output folder, the recorded spec
//! file, the spec's name and hash, the kind of run writing and `--force`. Out:
//! nothing, or an [`OwnerError`] naming both.

use super::{Plan, cache};
use crate::results::held::Held;
use crate::results::{self, Manifest};
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

/// The kind of run that writes a folder, which a folder holding another kind refuses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Writing {
    /// A paper run's results folder.
    Single,
    /// A point of a paper sweep: the sweep's folder, the point's parent, is the one
    /// that must hold nothing of another kind.
    SweepPoint,
    /// An installation study's folder, alone or a point of a sweep.
    Study,
    /// The folder of a sweep of installation studies: its points' folders are checked
    /// each, so only the kind is checked here.
    StudySweep,
}

impl Writing {
    fn held(self) -> Held {
        match self {
            Writing::Single => Held::Single,
            Writing::SweepPoint => Held::Sweep,
            Writing::Study => Held::Study,
            Writing::StudySweep => Held::StudySweep,
        }
    }
}

/// What the owner check needs to know of a folder about to be written.
#[derive(Debug, Clone)]
pub struct Writer<'a> {
    pub folder: &'a Path,
    /// The output folder the spec file is recorded from.
    pub out: &'a Path,
    /// The spec file as [`recorded`] gives it (empty when the run names none).
    pub spec_file: &'a str,
    /// The spec's `name`.
    pub name: &'a str,
    /// The SHA-256 of the resolved spec, in hex.
    pub spec_sha256: String,
    pub writing: Writing,
    /// Replace another spec file's results (never another kind's).
    pub force: bool,
}

impl<'a> Writer<'a> {
    /// The writer of paper point `p`'s folder.
    pub fn point(plan: &'a Plan, p: usize, force: bool) -> Writer<'a> {
        let spec = plan.spec(p);
        Writer {
            folder: &plan.points[p].folder,
            out: &plan.out,
            spec_file: plan.spec_file.as_deref().unwrap_or_default(),
            name: &spec.name,
            spec_sha256: crate::files::sha256_hex(spec.resolved_toml().as_bytes()),
            writing: if plan.experiment.is_sweep() {
                Writing::SweepPoint
            } else {
                Writing::Single
            },
            force,
        }
    }
}

/// Refuses to write `writer.folder` when it is a file, or (`force` or not) when it,
/// or a sweep point's sweep folder, holds another kind of run; and, unless `force`,
/// when another spec file wrote it.
pub fn check(writer: &Writer) -> Result<(), OwnerError> {
    let folder = writer.folder;
    if folder.exists() && !folder.is_dir() {
        return Err(OwnerError::NotAFolder {
            folder: folder.to_path_buf(),
        });
    }
    let holder = match writer.writing {
        Writing::SweepPoint => folder.parent().unwrap_or(folder),
        _ => folder,
    };
    let held = Held::of(holder);
    let ours = writer.writing.held();
    if held != Held::Nothing && held != ours {
        return Err(OwnerError::OtherKind {
            folder: holder.to_path_buf(),
            theirs: held.words(),
            ours: ours.words(),
            spec: resolved(writer.out, writer.spec_file),
            name: writer.name.to_string(),
        });
    }
    if writer.force || writer.writing == Writing::StudySweep {
        return Ok(());
    }
    another_spec(writer)
}

/// Refuses a folder whose manifest records a spec file other than the writer's that
/// still exists (a folder from before manifests named their spec file, a run that
/// named none, or a folder copied away from its spec file belongs to anyone).
fn another_spec(writer: &Writer) -> Result<(), OwnerError> {
    let Some(manifest) = read_manifest(writer.folder) else {
        return Ok(());
    };
    let ours = writer.spec_file;
    let theirs = resolved(writer.out, &manifest.spec_file);
    let our_path = resolved(writer.out, ours);
    if manifest.spec_file.is_empty()
        || ours.is_empty()
        || manifest.spec_file == ours
        || !theirs.is_file()
        || same_file(&theirs, &our_path)
    {
        return Ok(());
    }
    Err(OwnerError::AnotherSpec {
        folder: writer.folder.to_path_buf(),
        theirs,
        their_name: manifest.name,
        their_hash: short(&manifest.spec_sha256),
        ours: our_path,
        our_name: writer.name.to_string(),
        our_hash: short(&writer.spec_sha256),
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

    /// A writer of `writing` into `folder`, under the output folder `/p/results`.
    fn writer(folder: &Path, writing: Writing, force: bool) -> Writer<'_> {
        Writer {
            folder,
            out: Path::new("/p/results"),
            spec_file: "../experiments/a.toml",
            name: "a",
            spec_sha256: "0".repeat(64),
            writing,
            force,
        }
    }

    #[test]
    fn one_check_refuses_every_kind_in_a_folder_of_another_even_with_force() {
        let out = tempfile::tempdir().unwrap();
        let study = out.path().join("study");
        std::fs::create_dir_all(&study).unwrap();
        std::fs::write(study.join(results::study::HELDOUT), "").unwrap();
        let refused = |folder: &Path, writing| match check(&writer(folder, writing, true)) {
            Err(OwnerError::OtherKind {
                folder,
                theirs,
                ours,
                ..
            }) => Some((folder, theirs, ours)),
            _ => None,
        };
        let study_words = "the results of an installation study";
        assert_eq!(
            refused(&study, Writing::Single),
            Some((study.clone(), study_words, "the results of a single run"))
        );
        // A sweep point is refused at its sweep's folder, its parent.
        assert_eq!(
            refused(&study.join("lr=1"), Writing::SweepPoint),
            Some((study.clone(), study_words, "the points of a sweep"))
        );
        assert_eq!(refused(&study, Writing::Study), None);
        let sweep = "the points of a sweep of installation studies";
        assert_eq!(
            refused(&study, Writing::StudySweep),
            Some((study.clone(), study_words, sweep))
        );
        let file = out.path().join("file");
        std::fs::write(&file, "").unwrap();
        assert!(matches!(
            check(&writer(&file, Writing::Study, true)),
            Err(OwnerError::NotAFolder { .. })
        ));
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
