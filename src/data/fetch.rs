//! `dcnet-exp data fetch`: downloads the Snapir recordings (`V.npy`, `V_test.npy`) from
//! the BeamsNet repository, checks their SHA-256 against PAPER-NOTES, and writes them
//! atomically. A file already present with the right hash is kept.

use crate::files::sha256_hex;
use crate::spec::recordings::{FILES, RemoteFile};
use std::path::{Path, PathBuf};

/// Raw files of the BeamsNet repository (Cohen & Klein 2022) on its main branch.
pub const DEFAULT_BASE_URL: &str = "https://raw.githubusercontent.com/ansfl/BeamsNet/main";

/// Where `dcnet-exp data fetch` puts the files, relative to the working directory.
pub const DEFAULT_DEST: &str = "data/snapir";

#[derive(Debug, thiserror::Error)]
pub enum FetchError {
    #[error("downloading {url}")]
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
    #[error("writing {}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// What happened to one file.
#[derive(Debug, PartialEq)]
pub enum Fetched {
    Downloaded(PathBuf),
    AlreadyPresent(PathBuf),
}

/// Downloads the Snapir recordings ([`FILES`]) from `base_url` into `dest`.
pub fn fetch(base_url: &str, dest: &Path) -> Result<Vec<Fetched>, FetchError> {
    fetch_files(&FILES, base_url, dest)
}

/// Downloads `files` from `base_url` into `dest`, keeping those already there with the
/// right hash; a download with another hash is refused and nothing of it is written.
pub fn fetch_files(
    files: &[RemoteFile],
    base_url: &str,
    dest: &Path,
) -> Result<Vec<Fetched>, FetchError> {
    std::fs::create_dir_all(dest).map_err(|source| FetchError::Write {
        path: dest.to_path_buf(),
        source,
    })?;
    let mut fetched = Vec::new();
    for &RemoteFile {
        name,
        remote_path,
        sha256: expected,
    } in files
    {
        let path = dest.join(name);
        if std::fs::read(&path).is_ok_and(|bytes| sha256_hex(&bytes) == expected) {
            fetched.push(Fetched::AlreadyPresent(path));
            continue;
        }
        let url = format!("{}/{remote_path}", base_url.trim_end_matches('/'));
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
        crate::files::write_atomic(&path, &bytes).map_err(|source| FetchError::Write {
            path: path.clone(),
            source,
        })?;
        fetched.push(Fetched::Downloaded(path));
    }
    Ok(fetched)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Serves `files` (URL path → bytes) on 127.0.0.1 for `requests` requests, then stops.
    fn serve(
        files: Vec<(String, Vec<u8>)>,
        requests: usize,
    ) -> (String, std::thread::JoinHandle<()>) {
        let server = tiny_http::Server::http("127.0.0.1:0").unwrap();
        let url = format!("http://{}", server.server_addr().to_ip().unwrap());
        let handle = std::thread::spawn(move || {
            for request in server.incoming_requests().take(requests) {
                let response = match files.iter().find(|(path, _)| *path == request.url()) {
                    Some((_, bytes)) => tiny_http::Response::from_data(bytes.clone()),
                    None => {
                        tiny_http::Response::from_data(b"not found".to_vec()).with_status_code(404)
                    }
                };
                let _ = request.respond(response);
            }
        });
        (url, handle)
    }

    /// Two generated files, with the SHA-256 the fetch must find; leaked so that the
    /// file list has the `'static` names a [`RemoteFile`] holds.
    fn generated() -> (Vec<RemoteFile>, Vec<(String, Vec<u8>)>) {
        let contents: Vec<Vec<u8>> = (0..2u8)
            .map(|k| {
                (0..50_000u32)
                    .map(|i| (i * 7 + u32::from(k)) as u8)
                    .collect()
            })
            .collect();
        let files = [("a.npy", "one/a.npy"), ("b.npy", "two/b.npy")]
            .iter()
            .zip(&contents)
            .map(|(&(name, remote_path), bytes)| RemoteFile {
                name,
                remote_path,
                sha256: Box::leak(sha256_hex(bytes).into_boxed_str()),
            })
            .collect();
        let served = ["/one/a.npy", "/two/b.npy"]
            .iter()
            .map(|path| path.to_string())
            .zip(contents)
            .collect();
        (files, served)
    }

    #[test]
    fn downloads_checks_and_keeps_files_already_there() {
        let (files, served) = generated();
        let dir = tempfile::tempdir().unwrap();
        let dest = dir.path().join("data");
        let (url, server) = serve(served.clone(), 2);
        let fetched = fetch_files(&files, &url, &dest).unwrap();
        server.join().unwrap();
        assert_eq!(
            fetched,
            vec![
                Fetched::Downloaded(dest.join("a.npy")),
                Fetched::Downloaded(dest.join("b.npy"))
            ]
        );
        for ((_, bytes), file) in served.iter().zip(&files) {
            assert_eq!(&std::fs::read(dest.join(file.name)).unwrap(), bytes);
        }
        // No server now: both files are kept because their hashes match.
        let again = fetch_files(&files, "http://127.0.0.1:9", &dest).unwrap();
        assert_eq!(
            again,
            vec![
                Fetched::AlreadyPresent(dest.join("a.npy")),
                Fetched::AlreadyPresent(dest.join("b.npy"))
            ]
        );
    }

    #[test]
    fn a_download_with_another_hash_is_refused_and_not_written() {
        let (files, mut served) = generated();
        served[0].1[0] ^= 1;
        let dir = tempfile::tempdir().unwrap();
        let (url, server) = serve(served, 1);
        let error = fetch_files(&files, &url, dir.path()).unwrap_err();
        server.join().unwrap();
        assert!(
            error
                .to_string()
                .starts_with(&format!("{url}/one/a.npy: sha256 ")),
            "{error}"
        );
        assert!(error.to_string().ends_with(&format!(
            ", expected {}: the download is not the published file",
            files[0].sha256
        )));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
