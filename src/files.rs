//! Files written so that nothing is lost: a file is written whole or not at all
//! ([`write_atomic`]: a temporary file beside it, synced, then renamed), the
//! temporaries of writers killed mid-write are cleaned up, and contents are named by
//! their SHA-256. A cache entry is sealed ([`write_sealed`]): a `.sha256` file beside it
//! names its key and the SHA-256 of its bytes, so that a damaged, truncated or swapped
//! entry is found when read ([`check_seal`]) and set aside ([`set_aside`]) rather than
//! trusted. In: paths and bytes. Out: files on disk, hex digests. Every stage that
//! stores something writes through here.

use sha2::{Digest, Sha256};
use std::io::Write;
use std::path::{Path, PathBuf};

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
        if let Some(pid) = writer
            && !processes.join(pid.to_string()).exists()
        {
            std::fs::remove_file(&path)?;
            removed += 1;
        }
    }
    Ok(removed)
}

/// Makes the folder `path` and its parents, like `create_dir_all`, but where a file
/// stands in the place of one of them the error names that file.
pub fn create_folder(path: &Path) -> std::io::Result<()> {
    if let Err(file) = deepest_folder(path) {
        return Err(std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            format!(
                "{} is a file, where a folder is needed; move or remove it",
                file.display()
            ),
        ));
    }
    std::fs::create_dir_all(path)
}

/// The deepest of `path` and its parents that exists (`.` where no part of a relative
/// path does), where the rest would be made; `Err` with it where it is not a folder,
/// so that nothing can be made below it.
pub fn deepest_folder(path: &Path) -> Result<&Path, &Path> {
    let deepest = (path.ancestors())
        .find(|a| !a.as_os_str().is_empty() && a.exists())
        .unwrap_or(Path::new("."));
    match deepest.is_dir() {
        true => Ok(deepest),
        false => Err(deepest),
    }
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut file = partial_beside(path)?;
    file.write_all(bytes)?;
    persist_partial(file, path)
}

/// A temporary file in `path`'s folder, removed when dropped unless
/// [`persist_partial`] renames it to `path`; for a file written piece by piece.
pub fn partial_beside(path: &Path) -> std::io::Result<tempfile::NamedTempFile> {
    let folder = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    tempfile::Builder::new()
        .prefix(&format!("{PARTIAL}{}-", std::process::id()))
        .tempfile_in(folder)
}

/// Syncs the temporary `file` of [`partial_beside`] and renames it to `path`.
pub fn persist_partial(file: tempfile::NamedTempFile, path: &Path) -> std::io::Result<()> {
    let mut permissions = file.as_file().metadata()?.permissions();
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

/// A file something was read from, and the SHA-256 of its bytes as read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SourceFile {
    pub path: PathBuf,
    pub sha256: String,
}

/// Reads the file at `path` a line at a time, hashing its bytes as it reads: each line,
/// numbered from 1, with its ending, goes to `visit`; gives the file's SHA-256 (as 64
/// lowercase hex digits). `io` turns a failure to read into the caller's error.
pub fn read_lines<E>(
    path: &Path,
    io: impl Fn(std::io::Error) -> E,
    mut visit: impl FnMut(u64, &[u8]) -> Result<(), E>,
) -> Result<String, E> {
    use std::io::BufRead;
    let mut reader = std::io::BufReader::new(std::fs::File::open(path).map_err(&io)?);
    let (mut hasher, mut text, mut line) = (Sha256::new(), Vec::new(), 0);
    loop {
        text.clear();
        if reader.read_until(b'\n', &mut text).map_err(&io)? == 0 {
            break;
        }
        hasher.update(&text);
        line += 1;
        visit(line, &text)?;
    }
    Ok(format!("{:x}", hasher.finalize()))
}

/// What a sealed file's seal says of it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Seal {
    /// Neither the file nor its seal is there.
    Absent,
    /// The file has the bytes its seal names, for the key asked for.
    Intact,
    /// Why the file cannot be trusted.
    Damaged(String),
}

/// The seal of `path`: `path` with `.sha256` appended.
pub fn seal_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".sha256");
    PathBuf::from(name)
}

/// Writes `bytes` to `path`, then its seal naming `key` and the bytes' SHA-256, each
/// atomically: a writer killed between the two leaves a file without a seal, which
/// [`check_seal`] reports as damaged.
pub fn write_sealed(path: &Path, bytes: &[u8], key: &str) -> std::io::Result<()> {
    write_atomic(path, bytes)?;
    let digest = sha256_hex(bytes);
    write_atomic(&seal_path(path), format!("{key} {digest}\n").as_bytes())
}

/// `body` with its seal as its first line, for a file that must be whole and
/// trustworthy on its own, written in one atomic step: no kill can separate the two.
pub fn inline_sealed(body: &[u8], key: &str) -> Vec<u8> {
    let mut bytes = format!("{key} {}\n", sha256_hex(body)).into_bytes();
    bytes.extend_from_slice(body);
    bytes
}

/// The body of [`inline_sealed`] bytes, if their seal holds for `key`, or why not.
pub fn open_inline_sealed<'a>(bytes: &'a [u8], key: &str) -> Result<&'a [u8], String> {
    let newline = bytes.iter().position(|&b| b == b'\n');
    let (seal, body) = match newline {
        Some(at) => (String::from_utf8_lossy(&bytes[..at]), &bytes[at + 1..]),
        None => return Err("it has no seal line".into()),
    };
    match seal.split_once(' ') {
        Some((sealed_key, _)) if sealed_key != key => {
            Err(format!("it is sealed for another key, {sealed_key}"))
        }
        Some((_, digest)) if digest == sha256_hex(body) => Ok(body),
        Some(_) => Err("its bytes do not match the SHA-256 of its seal".into()),
        None => Err("its seal is unreadable".into()),
    }
}

/// Whether the file at `path` is the one sealed for `key`.
pub fn check_seal(path: &Path, key: &str) -> Seal {
    let seal = seal_path(path);
    let (bytes, sealed) = (std::fs::read(path), std::fs::read_to_string(&seal));
    let (bytes, sealed) = match (bytes, sealed) {
        (Err(_), Err(_)) => return Seal::Absent,
        (Err(_), Ok(_)) => return Seal::Damaged("it is missing beside its seal".into()),
        (Ok(_), Err(_)) => {
            return Seal::Damaged(
                "it has no seal (a write that was interrupted, or a cache from before seals)"
                    .into(),
            );
        }
        (Ok(bytes), Ok(sealed)) => (bytes, sealed),
    };
    match sealed.trim().split_once(' ') {
        Some((sealed_key, _)) if sealed_key != key => {
            Seal::Damaged(format!("it is sealed for another key, {sealed_key}"))
        }
        Some((_, digest)) if digest == sha256_hex(&bytes) => Seal::Intact,
        Some(_) => Seal::Damaged("its bytes do not match the SHA-256 of its seal".into()),
        None => Seal::Damaged("its seal is unreadable".into()),
    }
}

/// Moves the sealed file at `path` and its seal into `damaged` (see [`set_aside`]) when
/// the seal says it is damaged for `key`; returns what was wrong with the `what` and
/// where it went, or `None` when it is intact or absent.
pub fn set_aside_if_damaged(
    path: &Path,
    key: &str,
    damaged: &Path,
    what: &str,
) -> std::io::Result<Option<String>> {
    let Seal::Damaged(why) = check_seal(path, key) else {
        return Ok(None);
    };
    set_aside(path, damaged)?;
    Ok(Some(format!(
        "damaged {what} {}: {why}; moved to {} and computed again",
        path.display(),
        damaged.display()
    )))
}

/// Moves `path` and its seal, where they exist, into `folder`, each name followed by
/// the time in seconds (and a count, when an earlier copy of that second is there), and
/// returns where the file went.
pub fn set_aside(path: &Path, folder: &Path) -> std::io::Result<PathBuf> {
    std::fs::create_dir_all(folder)?;
    let seconds = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let mut moved = folder.to_path_buf();
    for file in [path.to_path_buf(), seal_path(path)] {
        let Some(name) = file.file_name() else {
            continue;
        };
        if !file.exists() {
            continue;
        }
        // The time names the copy; a count after it keeps copies of one second apart.
        let destination = (0..)
            .map(|n| match n {
                0 => format!("{}.{seconds}", name.to_string_lossy()),
                n => format!("{}.{seconds}-{n}", name.to_string_lossy()),
            })
            .map(|name| folder.join(name))
            .find(|destination| !destination.exists())
            .expect("a free name");
        std::fs::rename(&file, &destination)?;
        if file == path {
            moved = destination;
        }
    }
    Ok(moved)
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

    #[test]
    fn a_seal_tells_intact_from_flipped_swapped_truncated_and_unsealed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("entry.bin");
        assert_eq!(check_seal(&path, "k1"), Seal::Absent);
        write_sealed(&path, b"the bytes", "k1").unwrap();
        assert_eq!(
            std::fs::read_to_string(seal_path(&path)).unwrap(),
            format!("k1 {}\n", sha256_hex(b"the bytes"))
        );
        assert_eq!(check_seal(&path, "k1"), Seal::Intact);
        let damaged = |seal: Seal| matches!(seal, Seal::Damaged(_));
        assert!(damaged(check_seal(&path, "k2")), "another key's entry");
        std::fs::write(&path, b"the bytez").unwrap();
        assert!(damaged(check_seal(&path, "k1")), "a flipped byte");
        std::fs::write(&path, b"the byte").unwrap();
        assert!(damaged(check_seal(&path, "k1")), "truncated");
        std::fs::remove_file(seal_path(&path)).unwrap();
        assert!(damaged(check_seal(&path, "k1")), "no seal");
        write_sealed(&path, b"the bytes", "k1").unwrap();
        std::fs::remove_file(&path).unwrap();
        assert!(damaged(check_seal(&path, "k1")), "a seal without its file");

        write_sealed(&path, b"the bytes", "k1").unwrap();
        let moved = set_aside(&path, &dir.path().join("damaged")).unwrap();
        assert_eq!(std::fs::read(&moved).unwrap(), b"the bytes");
        assert_eq!(
            std::fs::read_dir(dir.path().join("damaged"))
                .unwrap()
                .count(),
            2
        );
        assert_eq!(check_seal(&path, "k1"), Seal::Absent);
    }

    #[test]
    fn an_inline_seal_holds_only_for_its_key_and_its_bytes() {
        let sealed = inline_sealed(b"{\"epoch\": 2}", "k1");
        assert_eq!(
            open_inline_sealed(&sealed, "k1"),
            Ok(&b"{\"epoch\": 2}"[..])
        );
        assert!(
            open_inline_sealed(&sealed, "k2")
                .unwrap_err()
                .contains("another key")
        );
        let mut flipped = sealed.clone();
        *flipped.last_mut().unwrap() ^= 1;
        assert!(
            open_inline_sealed(&flipped, "k1")
                .unwrap_err()
                .contains("do not match")
        );
        assert!(open_inline_sealed(b"{}", "k1").is_err());
    }
}
