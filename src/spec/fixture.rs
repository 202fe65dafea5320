//! The spec that tests across the crate start from. In: `--set` overrides. Out:
//! experiments/quick.toml loaded with them, as a checked [`Spec`], or its faults as
//! the text a user reads; or quick.toml with lines appended, written to a temporary
//! folder. Compiled for tests only.

use super::{Spec, load};
use std::path::{Path, PathBuf};

/// experiments/quick.toml with `overrides`, for tests.
pub(crate) fn quick_spec(overrides: &[&str]) -> Spec {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quick.toml");
    let overrides: Vec<String> = overrides.iter().map(ToString::to_string).collect();
    load(&path, &overrides).unwrap()
}

/// The faults `load` finds in quick.toml with `overrides`, one per line.
pub(crate) fn quick_faults(overrides: &[&str]) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/quick.toml");
    let overrides: Vec<String> = overrides.iter().map(ToString::to_string).collect();
    load(&path, &overrides).unwrap_err().to_string()
}

/// quick.toml with `extra` appended, in a temporary folder beside its trajectories.
pub(crate) fn quick_plus(extra: &str) -> (tempfile::TempDir, PathBuf) {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(repo.join("experiments/quick.toml")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("spec.toml");
    std::fs::write(&path, format!("{text}\n{extra}")).unwrap();
    (dir, path)
}
