//! `dcnet-exp data fetch`: downloads the Snapir recordings (`V.npy`, `V_test.npy`) from
//! the BeamsNet repository, checks their SHA-256 against PAPER-NOTES, and writes them
//! atomically. A file already present with the right hash is kept.

use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

/// Raw files of the BeamsNet repository (Cohen & Klein 2022) on its main branch.
pub const DEFAULT_BASE_URL: &str = "https://raw.githubusercontent.com/ansfl/BeamsNet/main";

/// Where `dcnet-exp data fetch` puts the files, relative to the working directory.
pub const DEFAULT_DEST: &str = "data/snapir";

/// File name, path under the base URL, SHA-256.
pub const FILES: [(&str, &str, &str); 2] = [
    (
        "V.npy",
        "dataset/TrainAndValidation/V.npy",
        "0c525b3f30e71f0d385af5c256930b0fc8bb9cc2e53581cda46943bb49308ed5",
    ),
    (
        "V_test.npy",
        "dataset/Test/V_test.npy",
        "ee517105d2a2856d5c5ee062c979d7a11e2fe929ae776bb341c8bf1ebe1014f7",
    ),
];

#[derive(Debug, thiserror::Error)]
pub enum FetchError {
    #[error("downloading {url}: {source}")]
    Http {
        url: String,
        source: Box<ureq::Error>,
    },
    #[error("{url}: sha256 {actual}, expected {expected}: the download is not the published file")]
    Checksum {
        url: String,
        actual: String,
        expected: String,
    },
    #[error("writing {}: {source}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// What happened to one file.
#[derive(Debug, PartialEq)]
pub enum Outcome {
    Downloaded(PathBuf),
    AlreadyPresent(PathBuf),
}

/// Downloads every file of [`FILES`] from `base_url` into `dest`.
pub fn fetch(base_url: &str, dest: &Path) -> Result<Vec<Outcome>, FetchError> {
    std::fs::create_dir_all(dest).map_err(|source| FetchError::Write {
        path: dest.to_path_buf(),
        source,
    })?;
    let mut outcomes = Vec::new();
    for (name, remote, expected) in FILES {
        let path = dest.join(name);
        if std::fs::read(&path).is_ok_and(|bytes| sha256_hex(&bytes) == expected) {
            outcomes.push(Outcome::AlreadyPresent(path));
            continue;
        }
        let url = format!("{}/{remote}", base_url.trim_end_matches('/'));
        let http = |source| FetchError::Http {
            url: url.clone(),
            source: Box::new(source),
        };
        let bytes = ureq::get(&url)
            .call()
            .map_err(http)?
            .body_mut()
            .read_to_vec()
            .map_err(http)?;
        let actual = sha256_hex(&bytes);
        if actual != expected {
            return Err(FetchError::Checksum {
                url,
                actual,
                expected: expected.to_string(),
            });
        }
        crate::results::write_atomic(&path, &bytes).map_err(|source| FetchError::Write {
            path: path.clone(),
            source,
        })?;
        outcomes.push(Outcome::Downloaded(path));
    }
    Ok(outcomes)
}

pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// A hint to append to a "file not found" message when the file is one we can fetch.
pub fn hint_for(path: &Path) -> String {
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or_default();
    if FILES.iter().any(|(file, _, _)| *file == name) {
        let folder = path
            .parent()
            .map(|p| p.display().to_string())
            .unwrap_or_default();
        format!(
            "; run `dcnet-exp data fetch --dest {folder}` to download the Snapir recordings there"
        )
    } else {
        String::new()
    }
}
