//! `dcnet-exp data fetch`: downloads the Snapir recordings (`V.npy`, `V_test.npy`) from
//! the BeamsNet repository, checks their SHA-256 against the published ones, and writes them
//! atomically. A file already present with the right hash is kept. A server that does
//! not answer, or stalls mid-body, times out; a failed download is tried again a few
//! times, waiting longer each time, before the fetch gives up naming the URL.

use crate::files::sha256_hex;
use crate::progress::Progress;
use crate::spec::recordings::{FILES, RemoteFile};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Raw files of the BeamsNet repository (Cohen & Klein 2022) on its main branch.
pub const DEFAULT_BASE_URL: &str = "https://raw.githubusercontent.com/ansfl/BeamsNet/main";

/// Where `dcnet-exp data fetch` puts the files, relative to the working directory.
pub const DEFAULT_DEST: &str = "data/snapir";

/// How long to wait for a server, and how often to try.
#[derive(Debug, Clone, Copy)]
pub struct Patience {
    /// For the connection to open.
    pub connect: Duration,
    /// For the response to begin, and for each read of the body.
    pub read: Duration,
    /// Tries per file, the first included.
    pub attempts: u32,
    /// The wait before the second try; it doubles before each later one.
    pub backoff: Duration,
}

impl Patience {
    pub const DEFAULT: Patience = Patience {
        connect: Duration::from_secs(15),
        read: Duration::from_secs(30),
        attempts: 4,
        backoff: Duration::from_secs(2),
    };
}

#[derive(Debug, thiserror::Error)]
pub enum FetchError {
    #[error("--base-url {url}: not an http:// or https:// address with a host")]
    BadUrl { url: String },
    #[error("downloading {url}: gave up after {attempts} tries")]
    Http {
        url: String,
        attempts: u32,
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
    fetch_files(&FILES, base_url, dest, Patience::DEFAULT)
}

/// Downloads `files` from `base_url` into `dest`, keeping those already there with the
/// right hash; a download with another hash is refused and nothing of it is written.
pub fn fetch_files(
    files: &[RemoteFile],
    base_url: &str,
    dest: &Path,
    patience: Patience,
) -> Result<Vec<Fetched>, FetchError> {
    let base_url = base_url.trim_end_matches('/');
    let has_host = base_url.parse::<ureq::http::Uri>().is_ok_and(|uri| {
        matches!(uri.scheme_str(), Some("http" | "https")) && uri.host().is_some()
    });
    if !has_host {
        return Err(FetchError::BadUrl {
            url: base_url.to_string(),
        });
    }
    std::fs::create_dir_all(dest).map_err(|source| FetchError::Write {
        path: dest.to_path_buf(),
        source,
    })?;
    let agent: ureq::Agent = ureq::Agent::config_builder()
        .timeout_connect(Some(patience.connect))
        .timeout_recv_response(Some(patience.read))
        .timeout_per_read(Some(patience.read))
        .build()
        .into();
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
        let url = format!("{base_url}/{remote_path}");
        let bytes = download_with_retries(&agent, &url, name, patience)?;
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

/// `url`'s body, tried up to `patience.attempts` times while the failure may pass (no
/// answer, a stall, a server error); a client error such as 404 is final.
fn download_with_retries(
    agent: &ureq::Agent,
    url: &str,
    name: &str,
    patience: Patience,
) -> Result<Vec<u8>, FetchError> {
    let mut wait = patience.backoff;
    let mut attempt = 1;
    loop {
        match download(agent, url, name) {
            Ok(bytes) => return Ok(bytes),
            Err(error) if attempt < patience.attempts && may_pass(&error) => {
                eprintln!("downloading {url}: {error}; trying again in {wait:?}");
                std::thread::sleep(wait);
                wait *= 2;
                attempt += 1;
            }
            Err(error) => {
                return Err(FetchError::Http {
                    url: url.to_string(),
                    attempts: attempt,
                    source: Box::new(error),
                });
            }
        }
    }
}

/// Whether a failed download may succeed when tried again.
fn may_pass(error: &ureq::Error) -> bool {
    match error {
        ureq::Error::StatusCode(status) => *status >= 500 || *status == 429,
        ureq::Error::BadUri(_) | ureq::Error::InvalidProxyUrl => false,
        _ => true,
    }
}

/// One try at `url`'s body, with a progress bar on a terminal.
fn download(agent: &ureq::Agent, url: &str, name: &str) -> Result<Vec<u8>, ureq::Error> {
    let mut response = agent.get(url).call()?;
    let body = response.body_mut();
    let progress = Progress::new(
        name.to_string(),
        body.content_length().unwrap_or(0) as usize,
        "bytes",
    );
    let mut bytes = Vec::new();
    let mut reader = body.with_config().limit(u64::MAX).reader();
    let mut chunk = vec![0u8; 1 << 16];
    loop {
        let read = reader.read(&mut chunk).map_err(ureq::Error::Io)?;
        if read == 0 {
            break;
        }
        bytes.extend_from_slice(&chunk[..read]);
        progress.inc(read);
    }
    progress.finish();
    Ok(bytes)
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
        let fetched = fetch_files(&files, &url, &dest, Patience::DEFAULT).unwrap();
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
        let again = fetch_files(&files, "http://127.0.0.1:9", &dest, Patience::DEFAULT).unwrap();
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
        let error = fetch_files(&files, &url, dir.path(), Patience::DEFAULT).unwrap_err();
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

    /// Patience short enough for a test: half a second per read, two tries.
    const IMPATIENT: Patience = Patience {
        connect: Duration::from_millis(500),
        read: Duration::from_millis(500),
        attempts: 2,
        backoff: Duration::from_millis(10),
    };

    /// A server on 127.0.0.1 that answers every connection with `reply` (perhaps
    /// nothing) and then holds it open without a word more, for `connections`
    /// connections.
    fn stalling(reply: &'static [u8], connections: usize) -> (String, std::thread::JoinHandle<()>) {
        use std::io::Write;
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let url = format!("http://{}", listener.local_addr().unwrap());
        let handle = std::thread::spawn(move || {
            let mut held = Vec::new();
            for stream in listener.incoming().take(connections) {
                let mut stream = stream.unwrap();
                let _ = stream.write_all(reply);
                held.push(stream);
            }
            std::thread::sleep(Duration::from_secs(2));
        });
        (url, handle)
    }

    #[test]
    fn a_server_that_never_answers_or_stalls_mid_body_times_out_and_is_named() {
        let (files, _) = generated();
        let partial: &[u8] = b"HTTP/1.1 200 OK\r\nContent-Length: 50000\r\n\r\nfirst bytes";
        for reply in [&b""[..], partial] {
            let (url, server) = stalling(reply, 2);
            let dir = tempfile::tempdir().unwrap();
            let clock = std::time::Instant::now();
            let error = fetch_files(&files, &url, dir.path(), IMPATIENT).unwrap_err();
            assert!(
                clock.elapsed() < Duration::from_secs(10),
                "{:?}",
                clock.elapsed()
            );
            let shown = format!("{:#}", anyhow::Error::from(error));
            assert!(
                shown.starts_with(&format!(
                    "downloading {url}/one/a.npy: gave up after 2 tries: "
                )),
                "{shown}"
            );
            assert!(
                shown.contains("timeout") || shown.contains("timed out"),
                "{shown}"
            );
            assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
            server.join().unwrap();
        }
    }

    #[test]
    fn a_missing_file_is_not_asked_for_again_and_a_bad_url_is_refused() {
        let (files, _) = generated();
        let (url, server) = serve(Vec::new(), 1);
        let dir = tempfile::tempdir().unwrap();
        let error = fetch_files(&files, &url, dir.path(), IMPATIENT).unwrap_err();
        server.join().unwrap();
        assert!(
            matches!(error, FetchError::Http { attempts: 1, .. }),
            "{error:?}"
        );
        for url in ["localhost:8000", "ftp://example.org/x", "not a url"] {
            let error = fetch_files(&files, url, dir.path(), IMPATIENT).unwrap_err();
            assert!(
                matches!(error, FetchError::BadUrl { .. }),
                "{url}: {error:?}"
            );
        }
    }
}
