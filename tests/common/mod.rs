//! Helpers for the integration tests: run the built binary in a temporary folder, read
//! the Parquet results and the printed plan back, list and hash the files below a
//! folder (`tree`, `snapshot`, `sha256`), store an error message whole as an insta
//! snapshot (`assert_error_snapshot!`), and find the Snapir and A-KIT recordings
//! where a user keeps them.
//!
//! Tests that need the recordings carry
//! `#[ignore = "needs the Snapir recordings: dcnet-exp data fetch"]`, so a fresh clone
//! reports them as ignored; `cargo test --release -- --ignored` runs them (only them),
//! and then a missing recording fails the test with the places searched.

#![allow(dead_code)]

pub mod fix_dives;
pub mod pd0;
pub mod installed;

use arrow_array::{Array, BooleanArray, Float64Array, Int64Array, RecordBatch, StringArray};
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::SystemTime;

pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The places searched for the Snapir recordings, in order: `DCNET_SNAPIR_DIR`, then
/// `data/snapir/` in the repository (where `dcnet-exp data fetch` puts them), then
/// `../shared/data/snapir`.
pub fn snapir_candidates() -> Vec<PathBuf> {
    let mut candidates: Vec<PathBuf> = std::env::var_os("DCNET_SNAPIR_DIR")
        .map(PathBuf::from)
        .into_iter()
        .collect();
    candidates.push(repo().join("data/snapir"));
    candidates.push(repo().join("../shared/data/snapir"));
    candidates
}

/// The first folder of [`snapir_candidates`] that holds both recordings; a test that
/// needs them fails here, naming every place searched, when none does.
pub fn snapir() -> PathBuf {
    let candidates = snapir_candidates();
    candidates
        .iter()
        .find(|dir| dir.join("V.npy").is_file() && dir.join("V_test.npy").is_file())
        .cloned()
        .unwrap_or_else(|| {
            let searched: Vec<String> =
                candidates.iter().map(|d| d.display().to_string()).collect();
            panic!(
                "the Snapir recordings (V.npy, V_test.npy) are in none of: {}; \
                 run `cargo run --release -- data fetch` or set DCNET_SNAPIR_DIR",
                searched.join(", ")
            )
        })
}

/// The places searched for the A-KIT recordings, in order: `DCNET_AKIT_DIR`, then
/// `data/akit/` in the repository (where `dcnet-exp data fetch akit` puts them), then
/// `../shared/data/akit`. Tests that need them carry
/// `#[ignore = "needs the A-KIT recordings: dcnet-exp data fetch akit"]`.
pub fn akit_candidates() -> Vec<PathBuf> {
    let mut candidates: Vec<PathBuf> = std::env::var_os("DCNET_AKIT_DIR")
        .map(PathBuf::from)
        .into_iter()
        .collect();
    candidates.push(repo().join("data/akit"));
    candidates.push(repo().join("../shared/data/akit"));
    candidates
}

/// The columns of an A-KIT segment with its reference's positions (latitude and
/// longitude), as `--columns` reads them.
pub const AKIT_COLUMNS_WITH_POSITIONS: &str = "[columns]\ntime = \"Time [s]\"\ndvl = [\"DVL X [m/s]\", \"DVL Y [m/s]\", \"DVL Z [m/s]\"]\nvelocity_ned = [\"V North [m/s]\", \"V East [m/s]\", \"V Down [m/s]\"]\nattitude = [\"Roll [rad]\", \"Pitch [rad]\", \"Yaw [rad]\"]\nlatitude_longitude = [\"Latitude [rad]\", \"Longitude [rad]\"]\n";

/// A-KIT's segment `k`: its DVL file and its reference file.
pub fn akit_segment(k: usize) -> [String; 2] {
    let segment = akit().join(format!("Trajectory{k}"));
    [
        format!("DVL_trajectory{k}.csv"),
        format!("GT_trajectory{k}.csv"),
    ]
    .map(|file| segment.join(file).display().to_string())
}

/// The first folder of [`akit_candidates`] that holds the 13 segments; a test that
/// needs them fails here, naming every place searched, when none does.
pub fn akit() -> PathBuf {
    let candidates = akit_candidates();
    let complete = |dir: &PathBuf| {
        (1..=13).all(|n| {
            let segment = dir.join(format!("Trajectory{n}"));
            segment.join(format!("DVL_trajectory{n}.csv")).is_file()
                && segment.join(format!("GT_trajectory{n}.csv")).is_file()
        })
    };
    candidates
        .iter()
        .find(|dir| complete(dir))
        .cloned()
        .unwrap_or_else(|| {
            let searched: Vec<String> =
                candidates.iter().map(|d| d.display().to_string()).collect();
            panic!(
                "the A-KIT recordings (Trajectory1/ to Trajectory13/) are in none of: {}; \
                 run `cargo run --release -- data fetch akit` or set DCNET_AKIT_DIR",
                searched.join(", ")
            )
        })
}

/// Runs `dcnet-exp ARGS` in `cwd`.
pub fn dcnet(cwd: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dcnet-exp"))
        .current_dir(cwd)
        .args(args)
        .env_remove("DCNET_LOG_EVERY")
        .output()
        .expect("the binary runs")
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// A temporary project: `experiments/` with the repository's specs, `data/snapir`
/// linked to the shared recordings when `with_data`.
pub fn project(with_data: bool) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("experiments")).unwrap();
    std::fs::create_dir(dir.path().join("experiments/published")).unwrap();
    for spec in ["paper.toml", "quick.toml", "published/dcnet-paper.toml"] {
        std::fs::copy(
            repo().join("experiments").join(spec),
            dir.path().join("experiments").join(spec),
        )
        .unwrap();
    }
    if with_data {
        std::fs::create_dir(dir.path().join("data")).unwrap();
        std::os::unix::fs::symlink(snapir(), dir.path().join("data/snapir")).unwrap();
    }
    dir
}

/// `run experiments/quick.toml` with `extra` arguments, which must succeed.
pub fn quick_run(dir: &Path, extra: &[&str]) -> Output {
    let args = [&["run", "experiments/quick.toml"], extra].concat();
    let output = dcnet(dir, &args);
    assert!(output.status.success(), "{}", stderr(&output));
    output
}

/// Writes `experiments/sweep.toml` in `dir`: quick.toml named "quick-sweep", with the
/// `[sweep.values]` table whose lines are `values`.
pub fn write_quick_sweep(dir: &Path, values: &str) {
    let quick = std::fs::read_to_string(dir.join("experiments/quick.toml")).unwrap();
    let text = quick.replacen("name = \"quick\"", "name = \"quick-sweep\"", 1)
        + "\n[sweep.values]\n"
        + values;
    std::fs::write(dir.join("experiments/sweep.toml"), text).unwrap();
}

/// A small quick run: 3 Monte Carlo runs, 2 epochs.
pub fn small_quick_run(dir: &Path, extra: &[&str]) {
    let small = [
        "--set",
        "calibration.monte_carlo_runs=3",
        "--set",
        "training.epochs=2",
    ];
    quick_run(dir, &[&small, extra].concat());
}

/// Runs the studies `experiments/{csv}.toml` and `experiments/{other}.toml` in `dir`
/// (`--no-plots`) and checks that they score alike: the same methods, each held-out
/// RMSE within 1e-6 cm/s of the other's.
pub fn studies_score_alike(dir: &Path, csv: &str, other: &str) {
    for name in [csv, other] {
        let output = dcnet(
            dir,
            &["run", &format!("experiments/{name}.toml"), "--no-plots"],
        );
        assert!(output.status.success(), "{name}: {}", stderr(&output));
    }
    let scores = |name: &str| {
        let batch = read_parquet(&dir.join(format!("results/{name}/summary.parquet")));
        (strings(&batch, "method"), floats(&batch, "rmse_cm_s"))
    };
    let (csv, other) = (scores(csv), scores(other));
    assert_eq!(csv.0, other.0);
    assert!(!csv.1.is_empty());
    for (a, b) in csv.1.iter().zip(&other.1) {
        assert!(
            (a.unwrap() - b.unwrap()).abs() < 1e-6,
            "{a:?} against {b:?}"
        );
    }
}

pub fn read_parquet(path: &Path) -> RecordBatch {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let reader = ParquetRecordBatchReaderBuilder::try_new(file)
        .unwrap()
        .with_batch_size(1 << 24)
        .build()
        .unwrap();
    let mut batches: Vec<RecordBatch> = reader.map(Result::unwrap).collect();
    assert_eq!(
        batches.len(),
        1,
        "the tool writes each table as one row group"
    );
    batches.remove(0)
}

pub fn strings(batch: &RecordBatch, column: &str) -> Vec<Option<String>> {
    let array = batch
        .column_by_name(column)
        .unwrap_or_else(|| panic!("no column {column}"));
    let array = array.as_any().downcast_ref::<StringArray>().unwrap();
    (0..array.len())
        .map(|i| array.is_valid(i).then(|| array.value(i).to_string()))
        .collect()
}

pub fn floats(batch: &RecordBatch, column: &str) -> Vec<Option<f64>> {
    let array = batch
        .column_by_name(column)
        .unwrap_or_else(|| panic!("no column {column}"));
    let array = array.as_any().downcast_ref::<Float64Array>().unwrap();
    (0..array.len())
        .map(|i| array.is_valid(i).then(|| array.value(i)))
        .collect()
}

pub fn integers(batch: &RecordBatch, column: &str) -> Vec<Option<i64>> {
    let array = batch
        .column_by_name(column)
        .unwrap_or_else(|| panic!("no column {column}"));
    let array = array.as_any().downcast_ref::<Int64Array>().unwrap();
    (0..array.len())
        .map(|i| array.is_valid(i).then(|| array.value(i)))
        .collect()
}

pub fn bools(batch: &RecordBatch, column: &str) -> Vec<bool> {
    let array = batch
        .column_by_name(column)
        .unwrap()
        .as_any()
        .downcast_ref::<BooleanArray>()
        .unwrap();
    (0..array.len()).map(|i| array.value(i)).collect()
}

/// One row of a results table, as the tests look rows up.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub dvl: String,
    pub estimator: String,
    pub error_model: Option<String>,
    /// `window_s` (calibration) or `trajectory` (evaluation).
    pub at: String,
    pub rmse_cm_s: f64,
    pub rmse_std_cm_s: f64,
    /// `is_t_conv` (calibration) or always true (evaluation).
    pub selected: bool,
    pub t_conv_s: Option<f64>,
    pub improvement_pct: Option<f64>,
}

/// The selected row of `rows` (at T_conv, for calibration rows) of the DVL, estimator
/// and error model, at `at` (a window or trajectory) when given.
pub fn find_row<'a>(
    rows: &'a [Row],
    dvl: &str,
    estimator: &str,
    model: Option<&str>,
    at: Option<&str>,
) -> &'a Row {
    rows.iter()
        .find(|r| {
            r.selected
                && r.dvl == dvl
                && r.estimator == estimator
                && r.error_model.as_deref() == model
                && at.is_none_or(|at| r.at == at)
        })
        .unwrap_or_else(|| panic!("no row {dvl} {estimator} {model:?} {at:?}"))
}

pub fn calibration_rows(results: &Path) -> Vec<Row> {
    let batch = read_parquet(&results.join("calibration.parquet"));
    let (dvl, estimator, model) = (
        strings(&batch, "dvl"),
        strings(&batch, "estimator"),
        strings(&batch, "error_model"),
    );
    let (window, rmse, std, t_conv) = (
        floats(&batch, "window_s"),
        floats(&batch, "rmse_cm_s"),
        floats(&batch, "rmse_std_cm_s"),
        bools(&batch, "is_t_conv"),
    );
    (0..batch.num_rows())
        .map(|i| Row {
            dvl: dvl[i].clone().unwrap(),
            estimator: estimator[i].clone().unwrap(),
            error_model: model[i].clone(),
            at: window[i].unwrap().to_string(),
            rmse_cm_s: rmse[i].unwrap(),
            rmse_std_cm_s: std[i].unwrap(),
            selected: t_conv[i],
            t_conv_s: None,
            improvement_pct: None,
        })
        .collect()
}

pub fn evaluation_rows(results: &Path) -> Vec<Row> {
    let batch = read_parquet(&results.join("evaluation.parquet"));
    let (dvl, estimator, model) = (
        strings(&batch, "dvl"),
        strings(&batch, "estimator"),
        strings(&batch, "error_model"),
    );
    let (trajectory, rmse, std) = (
        strings(&batch, "trajectory"),
        floats(&batch, "rmse_cm_s"),
        floats(&batch, "rmse_std_cm_s"),
    );
    let (t_conv, improvement) = (
        floats(&batch, "t_conv_s"),
        floats(&batch, "improvement_pct"),
    );
    (0..batch.num_rows())
        .map(|i| Row {
            dvl: dvl[i].clone().unwrap(),
            estimator: estimator[i].clone().unwrap(),
            error_model: model[i].clone(),
            at: trajectory[i].clone().unwrap(),
            rmse_cm_s: rmse[i].unwrap(),
            rmse_std_cm_s: std[i].unwrap(),
            selected: true,
            t_conv_s: t_conv[i],
            improvement_pct: improvement[i],
        })
        .collect()
}

/// Asserts that `path` is a PNG of `size` pixels with more than 1 % of them drawn on.
pub fn assert_png(path: &Path, size: (u32, u32)) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes))
        .read_info()
        .unwrap();
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut pixels).unwrap();
    assert_eq!((info.width, info.height), size, "{}", path.display());
    let channels = info.color_type.samples();
    let inked = pixels
        .chunks(channels)
        .filter(|p| p[..3].iter().any(|c| *c < 200))
        .count();
    let share = inked as f64 / (size.0 * size.1) as f64;
    assert!(
        share > 0.01,
        "{}: only {:.2} % of the pixels are drawn on",
        path.display(),
        100.0 * share
    );
}

/// Starts `dcnet-exp ARGS` in `cwd` with stderr piped.
pub fn spawn<S: AsRef<std::ffi::OsStr>>(cwd: &Path, args: &[S]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_dcnet-exp"))
        .current_dir(cwd)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Every file below `root`, hidden ones too, by its path relative to `root` (with `/`
/// between folders); a folder that cannot be read, or is gone, holds none.
pub fn tree(root: &Path) -> BTreeMap<String, PathBuf> {
    let mut files = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let rel = path.strip_prefix(root).unwrap().to_string_lossy();
                files.insert(rel.replace('\\', "/"), path);
            }
        }
    }
    files
}

/// The bytes and modification time of the file at `path`.
pub fn file_state(path: &Path) -> (Vec<u8>, SystemTime) {
    let modified = path.metadata().unwrap().modified().unwrap();
    (std::fs::read(path).unwrap(), modified)
}

/// Every file below the folder `folder`, by its path: its bytes and modification time.
pub fn snapshot(folder: &Path) -> BTreeMap<PathBuf, (Vec<u8>, SystemTime)> {
    assert!(folder.is_dir(), "{} is no folder", folder.display());
    tree(folder)
        .into_values()
        .map(|path| (path.clone(), file_state(&path)))
        .collect()
}

/// Replaces the sealed file `path` with `bytes` and writes its seal (`path.sha256`)
/// anew for them under the same key: a forged entry whose seal holds.
pub fn forge_sealed(path: &Path, bytes: &[u8]) {
    let mut seal_path = path.to_path_buf().into_os_string();
    seal_path.push(".sha256");
    let seal = std::fs::read_to_string(&seal_path).unwrap();
    let key = seal.split_whitespace().next().unwrap().to_string();
    std::fs::write(path, bytes).unwrap();
    std::fs::write(&seal_path, format!("{key} {}\n", sha256(bytes))).unwrap();
}

/// The SHA-256 of `bytes` in lowercase hex, as the tool's seals and manifests write it.
pub fn sha256(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The (task, status) rows of the table that `plan` prints (the first and third
/// columns), below its header and delimiter lines.
pub fn plan_rows(printed: &str) -> Vec<(String, String)> {
    printed
        .lines()
        .skip(2)
        .filter(|l| l.starts_with('|'))
        .map(|l| {
            let cells: Vec<&str> = l.split('|').map(str::trim).collect();
            (cells[1].to_string(), cells[3].to_string())
        })
        .collect()
}

/// `text` as an error snapshot stores it, the same on every machine: the temporary
/// folder `dir` (as given and as its canonical path) written `[TEMP]`, and the sizes in
/// a memory estimate (they depend on how many threads train at once and on this
/// machine's memory) written `[MEMORY]`.
pub fn redact(text: &str, dir: &Path) -> String {
    let mut text = text.to_string();
    let canonical = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
    for dir in [canonical, dir.to_path_buf()] {
        text = text.replace(&dir.display().to_string(), "[TEMP]");
    }
    for (start, end) in [
        ("needs about ", " of memory"),
        ("this machine has ", ";"),
        ("most of it, ", ","),
    ] {
        text = replace_between(&text, start, end, "[MEMORY]");
    }
    text
}

/// `text` with what stands between `start` and the next `end` on the same line written
/// `token`, wherever `start` is.
fn replace_between(text: &str, start: &str, end: &str, token: &str) -> String {
    let mut replaced = String::new();
    let mut rest = text;
    while let Some(at) = rest.find(start) {
        let (before, after) = rest.split_at(at + start.len());
        replaced.push_str(before);
        let line = &after[..after.find('\n').unwrap_or(after.len())];
        if let Some(n) = line.find(end) {
            replaced.push_str(token);
            rest = &after[n..];
        } else {
            rest = after;
        }
    }
    replaced.push_str(rest);
    replaced
}

/// A name for a snapshot made of `text`: its letters and digits, lowercase, each run of
/// other characters one `_` (`dvl[0].bias_cm_s=-500` gives `dvl_0_bias_cm_s_500`).
pub fn snapshot_name(text: &str) -> String {
    let mut name = String::new();
    for c in text.chars() {
        if c.is_ascii_alphanumeric() {
            name.push(c.to_ascii_lowercase());
        } else if !name.ends_with('_') {
            name.push('_');
        }
    }
    name.trim_matches('_').to_string()
}

/// Stores `error`, the stderr of `command` run in the temporary folder `dir`, whole as
/// the insta snapshot `name` of the calling test module (`snapshots/<test
/// binary>__<module>__<name>.snap` beside its file), [`redact`]ed, with `command` as
/// its description. Where CI is set, insta writes nothing and a message that differs
/// from its snapshot fails.
#[allow(unused_macros)]
macro_rules! assert_error_snapshot {
    ($name:expr, $command:expr, $error:expr, $dir:expr $(,)?) => {{
        let mut settings = insta::Settings::clone_current();
        settings.set_description($command);
        settings.set_omit_expression(true);
        let name: &str = $name;
        let redacted = crate::common::redact($error, $dir);
        settings.bind(|| insta::assert_snapshot!(name, redacted));
    }};
}
#[allow(unused_imports)]
pub(crate) use assert_error_snapshot;

/// Serves `files` (URL path → bytes) on 127.0.0.1 until the returned server is unblocked: the
/// fetch tests' server.
pub fn serve(
    files: Vec<(String, Vec<u8>)>,
) -> (
    String,
    std::thread::JoinHandle<()>,
    std::sync::Arc<tiny_http::Server>,
) {
    let server = std::sync::Arc::new(tiny_http::Server::http("127.0.0.1:0").unwrap());
    let url = format!("http://{}", server.server_addr().to_ip().unwrap());
    let worker = server.clone();
    let handle = std::thread::spawn(move || {
        for request in worker.incoming_requests() {
            let response = match files.iter().find(|(path, _)| *path == request.url()) {
                Some((_, bytes)) => tiny_http::Response::from_data(bytes.clone()),
                None => tiny_http::Response::from_data(b"not found".to_vec()).with_status_code(404),
            };
            let _ = request.respond(response);
        }
    });
    (url, handle, server)
}
