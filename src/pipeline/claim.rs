//! Claims on tasks, so that processes sharing an OUT (two runs, two shards on one
//! machine, a run beside a `collect`) never compute the same task. A task is claimed
//! by an exclusive lock on `OUT/.cache/locks/<key>.lock`, which the system releases
//! when the claim is dropped or its process ends, however it ends; a lock file left
//! behind claims nothing. A process computes the tasks it can claim at once, then
//! waits for the others and computes only what their holder left undone.

use super::cache;
use std::fs::{File, TryLockError};
use std::io;
use std::path::{Path, PathBuf};

/// The locks folder of the cache under `out`.
pub fn folder(out: &Path) -> PathBuf {
    cache::root(out).join("locks")
}

/// A held claim on one task; dropping it releases the task.
#[derive(Debug)]
pub struct Claim {
    _lock: File,
}

/// A lock that could not be opened or taken, with the path of the lock file (or of
/// the folder that could not be made for it).
#[derive(Debug, thiserror::Error)]
#[error("locking {}", path.display())]
pub struct ClaimError {
    pub path: PathBuf,
    #[source]
    pub source: io::Error,
}

/// The lock file of the task with cache key `key`, and the file opened.
fn open(out: &Path, key: &str) -> Result<(PathBuf, File), ClaimError> {
    let folder = folder(out);
    crate::files::create_folder(&folder).map_err(|source| ClaimError {
        path: folder.clone(),
        source,
    })?;
    let path = folder.join(format!("{}.lock", &key[..key.len().min(16)]));
    let file = File::options()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path);
    match file {
        Ok(file) => Ok((path, file)),
        Err(source) => Err(ClaimError { path, source }),
    }
}

/// The claim on task `key`, when no other process holds it.
pub fn try_claim(out: &Path, key: &str) -> Result<Option<Claim>, ClaimError> {
    let (path, lock) = open(out, key)?;
    match lock.try_lock() {
        Ok(()) => Ok(Some(Claim { _lock: lock })),
        Err(TryLockError::WouldBlock) => Ok(None),
        Err(TryLockError::Error(source)) => Err(ClaimError { path, source }),
    }
}

/// The claim on task `key`, once the process that holds it lets it go.
pub fn claim(out: &Path, key: &str) -> Result<Claim, ClaimError> {
    let (path, lock) = open(out, key)?;
    lock.lock().map_err(|source| ClaimError { path, source })?;
    Ok(Claim { _lock: lock })
}

/// Tasks claimed, each with its claim, and tasks another process holds.
pub type Split<T> = (Vec<(T, Claim)>, Vec<T>);

/// Of `tasks`, those claimed now and those another process holds.
pub fn split<T: Copy>(
    out: &Path,
    tasks: &[T],
    key: impl Fn(T) -> String,
) -> Result<Split<T>, ClaimError> {
    let mut claimed = Vec::new();
    let mut busy = Vec::new();
    for &task in tasks {
        match try_claim(out, &key(task))? {
            Some(claim) => claimed.push((task, claim)),
            None => busy.push(task),
        }
    }
    Ok((claimed, busy))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_claim_is_held_until_dropped() {
        let out = tempfile::tempdir().unwrap();
        let key = "0123456789abcdef0123";
        let held = try_claim(out.path(), key).unwrap().expect("free");
        assert!(try_claim(out.path(), key).unwrap().is_none(), "held");
        assert!(try_claim(out.path(), "fedcba9876543210").unwrap().is_some());
        drop(held);
        assert!(try_claim(out.path(), key).unwrap().is_some(), "released");
        let (claimed, busy) = split(out.path(), &[1, 2], |i| format!("{i:016}")).unwrap();
        assert_eq!((claimed.len(), busy.len()), (2, 0));
        let (again, busy) = split(out.path(), &[2, 3], |i| format!("{i:016}")).unwrap();
        assert_eq!((again.len(), busy), (1, vec![2]));
    }
}
