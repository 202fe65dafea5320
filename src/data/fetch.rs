//! `dcnet-exp data fetch`: downloads a [`Dataset`] of the catalogue
//! ([`crate::data::catalogue`]: the Snapir or the A-KIT recordings), streaming each
//! body to a temporary file beside its place while hashing it, and renames it there once its size and SHA-256 are the published
//! ones. A file already present with the right hash is kept. A body longer than the
//! file's known size is cut off at the first chunk past it, so memory stays bounded
//! whatever the server sends. A server that does not answer, stalls, or is not done
//! within a deadline per try times out; a failed download is tried again a few times,
//! waiting longer each time, before the fetch gives up naming the URL
//! ([`Patience::DEFAULT`] states the worst case).

use super::catalogue::Dataset;
use crate::files::sha256_hex;
use crate::progress::Progress;
use crate::spec::recordings::RemoteFile;
use sha2::{Digest, Sha256};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// How much of a body is read at a time: the most read past a file's known size before
/// the fetch stops.
const CHUNK_BYTES: usize = 1 << 16;

/// How long to wait for a server, and how often to try.
#[derive(Debug, Clone, Copy)]
pub struct Patience {
    /// For the connection to open.
    pub connect: Duration,
    /// For the response to begin, and for each read of the body.
    pub read: Duration,
    /// For one try as a whole, from the connection to the body's last byte.
    pub deadline: Duration,
    /// Tries per file, the first included.
    pub attempts: u32,
    /// The wait before the second try; it doubles before each later one.
    pub backoff: Duration,
}

impl Patience {
    /// 15 s to connect, 30 s for each read, 60 s for a try as a whole (at least
    /// 5.5 kB/s for the 333 kB of `V.npy`), four tries with waits of 2, 4 and 8 s: a
    /// file is given up on after at most 4 × 60 + 14 = 254 s, both after 508 s.
    pub const DEFAULT: Patience = Patience {
        connect: Duration::from_secs(15),
        read: Duration::from_secs(30),
        deadline: Duration::from_secs(60),
        attempts: 4,
        backoff: Duration::from_secs(2),
    };

    /// The longest a file can take before it is given up on: every try until its
    /// deadline, and the waits between them.
    pub fn worst_case(&self) -> Duration {
        let waits: Duration = (0..self.attempts.saturating_sub(1))
            .map(|k| self.backoff * 2u32.pow(k))
            .sum();
        self.deadline * self.attempts + waits
    }
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
    #[error(
        "downloading {url}: gave up after {attempts} tries, none done within the deadline of {deadline:?} per try"
    )]
    Deadline {
        url: String,
        attempts: u32,
        deadline: Duration,
    },
    #[error(
        "{url}: the server sent more than the {expected} bytes of the file; stopped there, nothing written"
    )]
    TooLong { url: String, expected: u64 },
    #[error(
        "{url}: the server declares {declared} bytes (Content-Length), the file has {expected}; nothing read"
    )]
    Length {
        url: String,
        declared: u64,
        expected: u64,
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

/// Downloads the files of `dataset` from `base_url` into `dest`.
pub fn fetch(dataset: Dataset, base_url: &str, dest: &Path) -> Result<Vec<Fetched>, FetchError> {
    fetch_files(dataset.files(), base_url, dest, Patience::DEFAULT)
}

/// Downloads `files` from `base_url` into `dest` (each to its name there, folders
/// made as needed), keeping those already there with the right hash; a download with
/// another hash or size is refused and nothing of it is written.
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
        .timeout_global(Some(patience.deadline))
        .build()
        .into();
    let mut fetched = Vec::new();
    for file in files {
        let path = dest.join(file.name);
        let present = std::fs::metadata(&path).is_ok_and(|meta| meta.len() == file.size_bytes)
            && std::fs::read(&path).is_ok_and(|bytes| sha256_hex(&bytes) == file.sha256);
        if present {
            fetched.push(Fetched::AlreadyPresent(path));
            continue;
        }
        if let Some(folder) = path.parent() {
            std::fs::create_dir_all(folder).map_err(|source| FetchError::Write {
                path: folder.to_path_buf(),
                source,
            })?;
        }
        let url = format!("{}/{}", base_url, file.remote_path);
        download_with_retries(&agent, &url, file, &path, patience)?;
        fetched.push(Fetched::Downloaded(path));
    }
    Ok(fetched)
}

/// Why one try failed.
enum Failure {
    /// The server or the network; another try may pass (see [`may_pass`]).
    Http(ureq::Error),
    /// The try was not done within [`Patience::deadline`].
    Deadline,
    /// Another try would get the same answer.
    Final(FetchError),
}

/// Downloads `url` to `path`, tried up to `patience.attempts` times while the failure
/// may pass (no answer, a stall, the deadline, a server error); a client error such as
/// 404, a wrong size or a wrong hash is final.
fn download_with_retries(
    agent: &ureq::Agent,
    url: &str,
    file: &RemoteFile,
    path: &Path,
    patience: Patience,
) -> Result<(), FetchError> {
    let mut wait = patience.backoff;
    let mut attempt = 1;
    loop {
        let failure = match download(agent, url, file, path, patience.deadline) {
            Ok(()) => return Ok(()),
            Err(failure) => failure,
        };
        let retry = attempt < patience.attempts;
        match failure {
            Failure::Http(error) if retry && may_pass(&error) => {
                eprintln!("downloading {url}: {error}; trying again in {wait:?}");
            }
            Failure::Deadline if retry => eprintln!(
                "downloading {url}: not done within {:?}; trying again in {wait:?}",
                patience.deadline
            ),
            Failure::Http(error) => {
                return Err(FetchError::Http {
                    url: url.to_string(),
                    attempts: attempt,
                    source: Box::new(error),
                });
            }
            Failure::Deadline => {
                return Err(FetchError::Deadline {
                    url: url.to_string(),
                    attempts: attempt,
                    deadline: patience.deadline,
                });
            }
            Failure::Final(error) => return Err(error),
        }
        std::thread::sleep(wait);
        wait *= 2;
        attempt += 1;
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

/// One try at `url`: its body streamed to a temporary file beside `path` (never more
/// than `file.size_bytes` and one chunk read), checked against the file's size and
/// SHA-256, then renamed to `path`; with a progress bar on a terminal.
fn download(
    agent: &ureq::Agent,
    url: &str,
    file: &RemoteFile,
    path: &Path,
    deadline: Duration,
) -> Result<(), Failure> {
    let started = Instant::now();
    let timed = |error: ureq::Error| match error {
        ureq::Error::Timeout(ureq::Timeout::Global) => Failure::Deadline,
        _ if started.elapsed() >= deadline => Failure::Deadline,
        error => Failure::Http(error),
    };
    let mut response = agent.get(url).call().map_err(timed)?;
    let body = response.body_mut();
    if let Some(declared) = body.content_length()
        && declared != file.size_bytes
    {
        return Err(Failure::Final(FetchError::Length {
            url: url.to_string(),
            declared,
            expected: file.size_bytes,
        }));
    }
    let write = |source| {
        Failure::Final(FetchError::Write {
            path: path.to_path_buf(),
            source,
        })
    };
    let mut partial = crate::files::partial_beside(path).map_err(write)?;
    let progress = Progress::new(file.name.to_string(), file.size_bytes as usize, "bytes");
    let reader = body.with_config().limit(u64::MAX).reader();
    let copied = copy_at_most(reader, &mut partial, file.size_bytes, |read| {
        progress.inc(read)
    });
    progress.finish();
    let actual = match copied {
        Ok(actual) => actual,
        Err(Copy::TooLong) => {
            return Err(Failure::Final(FetchError::TooLong {
                url: url.to_string(),
                expected: file.size_bytes,
            }));
        }
        Err(Copy::Read(error)) => return Err(timed(ureq::Error::Io(error))),
        Err(Copy::Write(error)) => return Err(write(error)),
    };
    if actual != file.sha256 {
        return Err(Failure::Final(FetchError::Checksum {
            url: url.to_string(),
            actual,
            expected: file.sha256.to_string(),
        }));
    }
    crate::files::persist_partial(partial, path).map_err(write)
}

/// Why [`copy_at_most`] stopped.
#[derive(Debug)]
enum Copy {
    TooLong,
    Read(std::io::Error),
    Write(std::io::Error),
}

/// Copies `reader` to `writer` a chunk at a time, stopping as soon as more than
/// `size_bytes` have come, telling `copied` the size of each chunk; returns the SHA-256
/// of what was copied, in hex.
fn copy_at_most(
    mut reader: impl Read,
    mut writer: impl Write,
    size_bytes: u64,
    mut copied: impl FnMut(usize),
) -> Result<String, Copy> {
    let mut hasher = Sha256::new();
    let mut chunk = vec![0u8; CHUNK_BYTES];
    let mut total = 0u64;
    loop {
        let read = match reader.read(&mut chunk) {
            Ok(0) => break,
            Ok(read) => read,
            Err(error) if error.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(error) => return Err(Copy::Read(error)),
        };
        total += read as u64;
        if total > size_bytes {
            return Err(Copy::TooLong);
        }
        hasher.update(&chunk[..read]);
        writer.write_all(&chunk[..read]).map_err(Copy::Write)?;
        copied(read);
    }
    Ok(hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect())
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
                size_bytes: bytes.len() as u64,
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
    fn files_named_in_folders_go_to_those_folders_below_the_destination() {
        let (mut files, served) = generated();
        files[0].name = "Trajectory1/DVL_trajectory1.csv";
        files[1].name = "Trajectory1/GT_trajectory1.csv";
        let dir = tempfile::tempdir().unwrap();
        let dest = dir.path().join("data/akit");
        let (url, server) = serve(served.clone(), 2);
        let fetched = fetch_files(&files, &url, &dest, Patience::DEFAULT).unwrap();
        server.join().unwrap();
        let folder = dest.join("Trajectory1");
        assert_eq!(
            fetched,
            vec![
                Fetched::Downloaded(folder.join("DVL_trajectory1.csv")),
                Fetched::Downloaded(folder.join("GT_trajectory1.csv"))
            ]
        );
        assert_eq!(
            std::fs::read(folder.join("GT_trajectory1.csv")).unwrap(),
            served[1].1
        );
        assert_eq!(std::fs::read_dir(&folder).unwrap().count(), 2);
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

    /// Patience short enough for a test: half a second per read, two seconds a try, two
    /// tries.
    const IMPATIENT: Patience = Patience {
        connect: Duration::from_millis(500),
        read: Duration::from_millis(500),
        deadline: Duration::from_secs(2),
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
    /// A reader of endless bytes that counts how many it handed out.
    struct Counting {
        handed_out: u64,
    }

    impl Read for Counting {
        fn read(&mut self, buffer: &mut [u8]) -> std::io::Result<usize> {
            buffer.fill(b'x');
            self.handed_out += buffer.len() as u64;
            Ok(buffer.len())
        }
    }

    #[test]
    fn an_endless_body_is_read_no_further_than_one_chunk_past_the_size() {
        let mut endless = Counting { handed_out: 0 };
        let mut written = Vec::new();
        let copied = copy_at_most(&mut endless, &mut written, 333_392, |_| {});
        assert!(matches!(copied, Err(Copy::TooLong)), "{copied:?}");
        assert!(endless.handed_out <= 333_392 + CHUNK_BYTES as u64);
        assert!(written.len() <= 333_392);
    }

    /// Answers one request on 127.0.0.1 with `response`, then stops.
    fn answer_once(
        response: tiny_http::Response<Box<dyn Read + Send>>,
    ) -> (String, std::thread::JoinHandle<()>) {
        let server = tiny_http::Server::http("127.0.0.1:0").unwrap();
        let url = format!("http://{}", server.server_addr().to_ip().unwrap());
        let handle = std::thread::spawn(move || {
            if let Ok(Some(request)) = server.recv_timeout(Duration::from_secs(10)) {
                let _ = request.respond(response);
            }
        });
        (url, handle)
    }

    #[test]
    fn a_body_longer_than_the_file_is_cut_off_and_nothing_written() {
        let (files, _) = generated();
        // 10 MB without a declared length (chunked), for a file of 50,000 bytes.
        let body: Box<dyn Read + Send> = Box::new(std::io::repeat(b'x').take(10_000_000));
        let (url, server) = answer_once(tiny_http::Response::new(
            200.into(),
            Vec::new(),
            body,
            None,
            None,
        ));
        let dir = tempfile::tempdir().unwrap();
        let error = fetch_files(&files, &url, dir.path(), IMPATIENT).unwrap_err();
        server.join().unwrap();
        assert_eq!(
            error.to_string(),
            format!(
                "{url}/one/a.npy: the server sent more than the 50000 bytes of the file; stopped there, nothing written"
            )
        );
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn a_declared_length_other_than_the_file_size_is_refused_before_reading() {
        let (files, served) = generated();
        let mut bytes = served[0].1.clone();
        bytes.push(0);
        let length = bytes.len();
        let body: Box<dyn Read + Send> = Box::new(std::io::Cursor::new(bytes));
        let (url, server) = answer_once(
            tiny_http::Response::new(200.into(), Vec::new(), body, Some(length), None)
                .with_chunked_threshold(usize::MAX),
        );
        let dir = tempfile::tempdir().unwrap();
        let error = fetch_files(&files, &url, dir.path(), IMPATIENT).unwrap_err();
        server.join().unwrap();
        assert_eq!(
            error.to_string(),
            format!(
                "{url}/one/a.npy: the server declares 50001 bytes (Content-Length), the file has 50000; nothing read"
            )
        );
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn a_server_that_trickles_is_given_up_on_at_the_deadline_and_named() {
        use std::io::Write;
        let (files, _) = generated();
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let url = format!("http://{}", listener.local_addr().unwrap());
        // One byte every 100 ms, each read well within the 500 ms per read, for each of
        // the two tries; each connection is given up after 5 s at most.
        let server = std::thread::spawn(move || {
            for stream in listener.incoming().take(IMPATIENT.attempts as usize) {
                let mut stream = stream.unwrap();
                let _ = stream.write_all(b"HTTP/1.1 200 OK\r\nContent-Length: 50000\r\n\r\n");
                let clock = Instant::now();
                while clock.elapsed() < Duration::from_secs(5)
                    && stream.write_all(b"x").and_then(|()| stream.flush()).is_ok()
                {
                    std::thread::sleep(Duration::from_millis(100));
                }
            }
        });
        let dir = tempfile::tempdir().unwrap();
        let error = fetch_files(&files, &url, dir.path(), IMPATIENT).unwrap_err();
        assert_eq!(
            error.to_string(),
            format!(
                "downloading {url}/one/a.npy: gave up after 2 tries, none done within the deadline of 2s per try"
            )
        );
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        server.join().unwrap();
    }

    #[test]
    fn the_default_worst_case_is_the_one_the_docs_state() {
        assert_eq!(Patience::DEFAULT.worst_case(), Duration::from_secs(254));
    }
}
