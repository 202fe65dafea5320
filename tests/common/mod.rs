//! Helpers for the integration tests: run the built binary in a temporary folder, read
//! the Parquet results back, and find the Snapir recordings where a user keeps them.
//!
//! Tests that need the recordings carry
//! `#[ignore = "needs the Snapir recordings: dcnet-exp data fetch"]`, so a fresh clone
//! reports them as ignored; `cargo test --release -- --include-ignored` runs them, and
//! then a missing recording fails the test with the places searched.

#![allow(dead_code)]

use arrow_array::{Array, BooleanArray, Float64Array, Int64Array, RecordBatch, StringArray};
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
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

pub fn read_parquet(path: &Path) -> RecordBatch {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let reader = ParquetRecordBatchReaderBuilder::try_new(file)
        .unwrap()
        .build()
        .unwrap();
    let mut batches: Vec<RecordBatch> = reader.map(Result::unwrap).collect();
    assert_eq!(batches.len(), 1, "the tool writes each table as one batch");
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

/// Every file below `folder`: its bytes and modification time.
pub fn snapshot(folder: &Path) -> BTreeMap<PathBuf, (Vec<u8>, SystemTime)> {
    let mut files = BTreeMap::new();
    let mut stack = vec![folder.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let modified = path.metadata().unwrap().modified().unwrap();
                files.insert(path.clone(), (std::fs::read(&path).unwrap(), modified));
            }
        }
    }
    files
}
