//! Whose a results folder is: the spec file its manifest records. A run replaces a
//! folder written from its own spec file (an edited spec, other `--set` values), but
//! never, without `--force`, one that another spec file with the same `name` wrote, nor
//! a point of a sweep from a run that is not that sweep. In: a plan and one of its
//! points. Out: nothing, or an [`OwnerError`] naming both specs.

use super::{Plan, cache};
use crate::results::{self, Manifest, sweep};
use std::path::PathBuf;

/// A results folder that belongs to another spec.
#[derive(Debug, thiserror::Error)]
pub enum OwnerError {
    #[error(
        "{}: holds the results of {theirs} ({their_name}, spec SHA-256 {their_hash}); this run's spec is {ours} ({our_name}, spec SHA-256 {our_hash}), whose `name` is the same: give it another `name`, or --force replaces those results",
        folder.display()
    )]
    AnotherSpec {
        folder: PathBuf,
        theirs: String,
        their_name: String,
        their_hash: String,
        ours: String,
        our_name: String,
        our_hash: String,
    },
    #[error(
        "{}: is a file, where the results folder goes; move or remove it",
        folder.display()
    )]
    NotAFolder { folder: PathBuf },
    #[error(
        "{}: is a point of the sweep in {}; this run of {ours} ({our_name}) is not that sweep: give it another `name`, or --force replaces the point",
        folder.display(),
        sweep.display()
    )]
    SweepPoint {
        folder: PathBuf,
        sweep: PathBuf,
        ours: String,
        our_name: String,
    },
}

/// The claim key of point `p`'s results folder, the same for every spec that writes
/// it: processes writing one folder take turns.
pub fn folder_key(plan: &Plan, p: usize) -> String {
    cache::hash(&("results folder", &plan.spec(p).name))
}

/// Refuses to write point `p`'s folder, unless `force`, when another spec wrote it.
pub fn check(plan: &Plan, p: usize, force: bool) -> Result<(), OwnerError> {
    let folder = &plan.points[p].folder;
    if folder.exists() && !folder.is_dir() {
        return Err(OwnerError::NotAFolder {
            folder: folder.clone(),
        });
    }
    if force {
        return Ok(());
    }
    let spec = plan.spec(p);
    let ours = plan
        .spec_file
        .as_ref()
        .map_or_else(String::new, |path| path.display().to_string());
    let our_hash = crate::files::sha256_hex(spec.resolved_toml().as_bytes());
    if !plan.experiment.is_sweep()
        && let Some(parent) = folder.parent()
        && parent.join(sweep::INDEX).is_file()
    {
        return Err(OwnerError::SweepPoint {
            folder: folder.clone(),
            sweep: parent.to_path_buf(),
            ours: shown(&ours),
            our_name: spec.name.clone(),
        });
    }
    let Some(manifest) = read_manifest(folder) else {
        return Ok(());
    };
    // A folder from before manifests named their spec file, or a run that named none,
    // belongs to anyone.
    if manifest.spec_file.is_empty() || ours.is_empty() || manifest.spec_file == ours {
        return Ok(());
    }
    Err(OwnerError::AnotherSpec {
        folder: folder.clone(),
        theirs: manifest.spec_file,
        their_name: manifest.name,
        their_hash: short(&manifest.spec_sha256),
        ours,
        our_name: spec.name.clone(),
        our_hash: short(&our_hash),
    })
}

fn read_manifest(folder: &std::path::Path) -> Option<Manifest> {
    let bytes = std::fs::read(folder.join(results::MANIFEST)).ok()?;
    serde_json::from_slice(&bytes).ok()
}

fn shown(file: &str) -> String {
    if file.is_empty() {
        "this spec".into()
    } else {
        file.into()
    }
}

/// The first 16 hex digits of a SHA-256, as `plan` shows keys.
fn short(digest: &str) -> String {
    digest[..digest.len().min(16)].to_string()
}
