//! Files written so that nothing is lost: a file is written whole or not at all
//! ([`write_atomic`]: a temporary file beside it, synced, then renamed), the
//! temporaries of writers killed mid-write are cleaned up, and contents are named by
//! their SHA-256. In: paths and bytes. Out: files on disk, hex digests. Every stage
//! that stores something writes through here.

use sha2::{Digest, Sha256};
use std::io::Write;
use std::path::Path;

/// How the temporary file of [`write_atomic`] starts; the writer's process id follows.
const PARTIAL: &str = ".partial-";

/// Removes the temporary files that writers killed mid-write left below `folder`:
/// those of processes no longer running on this machine. Where the process table
/// cannot be read (no `/proc`), nothing is removed.
pub fn remove_stale_partials(folder: &Path) -> std::io::Result<usize> {
    let processes = Path::new("/proc");
    if !processes.is_dir() {
        return Ok(0);
    }
    let mut removed = 0;
    let Ok(entries) = std::fs::read_dir(folder) else {
        return Ok(0);
    };
    for entry in entries {
        let entry = entry?;
        let path = entry.path();
        if entry.file_type()?.is_dir() {
            removed += remove_stale_partials(&path)?;
            continue;
        }
        let name = entry.file_name().to_string_lossy().into_owned();
        let writer = name
            .strip_prefix(PARTIAL)
            .and_then(|rest| rest.split('-').next())
            .and_then(|pid| pid.parse::<u32>().ok());
        if let Some(pid) = writer {
            if !processes.join(pid.to_string()).exists() {
                std::fs::remove_file(&path)?;
                removed += 1;
            }
        }
    }
    Ok(removed)
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let folder = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let mut file = tempfile::Builder::new()
        .prefix(&format!("{PARTIAL}{}-", std::process::id()))
        .tempfile_in(folder)?;
    let mut permissions = file.as_file().metadata()?.permissions();
    file.write_all(bytes)?;
    // Readable like any other output file, not the 0600 of a temporary file.
    #[cfg(unix)]
    std::os::unix::fs::PermissionsExt::set_mode(&mut permissions, 0o644);
    file.as_file().set_permissions(permissions)?;
    file.as_file().sync_all()?;
    file.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// The SHA-256 of `bytes`, as 64 lowercase hex digits.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_writes_replace_whole_files_and_leave_no_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.txt");
        write_atomic(&path, b"first").unwrap();
        write_atomic(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn partial_files_of_dead_writers_are_removed_and_live_ones_kept() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        // No process has the largest pid; this test's own process is alive.
        let dead = dir.path().join(format!("sub/{PARTIAL}{}-abc", u32::MAX));
        let live = dir
            .path()
            .join(format!("{PARTIAL}{}-abc", std::process::id()));
        let other = dir.path().join("sub/kept.parquet");
        for path in [&dead, &live, &other] {
            std::fs::write(path, b"x").unwrap();
        }
        assert_eq!(remove_stale_partials(dir.path()).unwrap(), 1);
        assert!(!dead.exists() && live.exists() && other.exists());
    }
}
