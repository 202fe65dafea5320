//! An adversarial suite for issue 13: nothing a run has computed is ever lost or trusted
//! when it should not be. Every kind of file a run keeps (a model's weights, history
//! and seal, a checkpoint's `state.json`, epoch files and their seals, a Monte Carlo
//! block and its seal, the results folder's tables, manifest, spec and reports, a
//! figure, a sweep's table) is truncated to half, has one byte flipped, is swapped with
//! another file of its kind, emptied and deleted, each in a copy of one small reference
//! run; `plan` must show a damaged cache entry as `to do (damaged)`, and `run` must exit
//! with 0, name a damaged entry once, move it into `.cache/damaged/`, recompute only
//! it, and end with every file as the reference has it (the Parquet tables and figures
//! byte for byte). Runs are then killed with SIGKILL at pseudo-random moments (a fixed
//! seed, anchored on the stages the log announces: dataset, training, Monte Carlo,
//! results, figures, reports): every file visible after the kill must be whole, and the
//! resumed run must keep what was stored and end with the reference's bytes. Last, as
//! root, OUT is a small tmpfs that fills up at each stage: exit 2 naming the file and
//! "No space left", nothing half-written, and a resume elsewhere to the reference.
//! `cargo test --release --test experiment adversarial:: -- --nocapture` prints the
//! count of cases tried and held per category.

use crate::common;
use arrow_array::RecordBatch;
use common::*;
use parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder;
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::mpsc;
use std::time::{Duration, Instant, SystemTime};

const SPEC: &str = "experiments/quick.toml";

/// The small quick run every case starts from: two DCNets, two epochs, three runs.
const SMALL: [&str; 6] = [
    "--set",
    "calibration.monte_carlo_runs=3",
    "--set",
    "training.epochs=2",
    "--set",
    "estimators.error_models=[\"EM1\", \"EM3\"]",
];

/// A checkpoint after every epoch; not part of any key, so the results are the same.
const EVERY_EPOCH: [&str; 2] = ["--set", "training.checkpoint_every_epochs=1"];

/// The sweep of two points that share their models, for `sweep.parquet`.
const SWEEP: [&str; 4] = [
    "--set",
    "name=quick-sweep",
    "--set",
    "sweep.values={\"calibration.monte_carlo_runs\" = [2, 3]}",
];

/// A second results folder beside `quick` in the reference, from the same cache: its
/// files are the swap partners of `quick`'s manifest, spec and reports.
const SECOND: [&str; 2] = ["--set", "name=quick2"];

const REFERENCE: &str = "reference";

// ---------------------------------------------------------------- running the binary

/// `run SPEC --out OUT --plots OUT/plots`, small, with `extra`.
fn run_args(out: &str, extra: &[&str]) -> Vec<String> {
    let plots = format!("{out}/plots");
    let mut args: Vec<String> = ["run", SPEC, "--out", out, "--plots", &plots]
        .iter()
        .map(|s| s.to_string())
        .collect();
    args.extend(SMALL.iter().chain(extra).map(|s| s.to_string()));
    args
}

fn plan_args(out: &str, extra: &[&str]) -> Vec<String> {
    let mut args: Vec<String> = ["plan", SPEC, "--out", out]
        .iter()
        .map(|s| s.to_string())
        .collect();
    args.extend(SMALL.iter().chain(extra).map(|s| s.to_string()));
    args
}

fn exe(cwd: &Path, args: &[String]) -> Output {
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    dcnet(cwd, &args)
}

/// Returns early from a function giving `Result<_, String>` when `cond` fails.
macro_rules! ensure {
    ($cond:expr, $($why:tt)+) => {
        if !$cond {
            return Err(format!($($why)+));
        }
    };
}

// ---------------------------------------------------------------- files

fn copy_tree(from: &Path, to: &Path) {
    for (rel, path) in tree(from) {
        let destination = to.join(&rel);
        std::fs::create_dir_all(destination.parent().unwrap()).unwrap();
        std::fs::copy(&path, &destination).unwrap();
    }
}

fn file_name(rel: &str) -> &str {
    rel.rsplit('/').next().unwrap()
}

/// The temporary files of writers below `root` (`.partial-<pid>-*`).
fn partials(root: &Path) -> Vec<String> {
    tree(root)
        .into_keys()
        .filter(|rel| file_name(rel).starts_with(".partial-"))
        .collect()
}

/// Every file below `root` but the set-aside ones and the claims' lock files (made as
/// tasks are claimed), by its path relative to `root`: its bytes and modification time.
fn kept_snapshot(root: &Path) -> BTreeMap<String, (Vec<u8>, SystemTime)> {
    tree(root)
        .into_iter()
        .filter(|(rel, _)| !rel.starts_with(".cache/damaged/") && !rel.starts_with(".cache/locks/"))
        .map(|(rel, path)| (rel, file_state(&path)))
        .collect()
}

/// The one file of `dir` whose name starts with `prefix` and ends with `suffix`.
fn find(dir: &Path, prefix: &str, suffix: &str) -> PathBuf {
    let mut found: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| {
            let name = p.file_name().unwrap().to_string_lossy();
            name.starts_with(prefix) && name.ends_with(suffix)
        })
        .collect();
    found.sort();
    assert!(
        !found.is_empty(),
        "no {prefix}*{suffix} in {}",
        dir.display()
    );
    found.remove(0)
}

fn model_file(out: &Path, em: &str, extension: &str) -> PathBuf {
    let dir = out.join(".cache/models");
    let prefix = format!("{em}-");
    let path = find(&dir, &prefix, extension);
    assert_eq!(
        path.file_name().unwrap().len(),
        prefix.len() + 16 + extension.len(),
        "{}",
        path.display()
    );
    path
}

fn checkpoint_file(out: &Path, em: &str, name: &str) -> PathBuf {
    find(&out.join(".cache/models"), &format!("{em}-"), ".checkpoint").join(name)
}

/// The `index`-th Monte Carlo block (by name), or its seal.
fn block(out: &Path, index: usize, seal: bool) -> PathBuf {
    let mut blocks: Vec<PathBuf> = tree(&out.join(".cache/monte_carlo"))
        .into_values()
        .filter(|p| p.extension().is_some_and(|e| e == "parquet"))
        .collect();
    blocks.sort();
    let path = blocks.swap_remove(index);
    if seal {
        PathBuf::from(format!("{}.sha256", path.display()))
    } else {
        path
    }
}

// ---------------------------------------------------------------- the reference

/// A project with the reference run in `reference/`, its figures in
/// `reference/plots/`; `quick2`, the second folder, beside `quick` when asked for.
struct Reference {
    project: tempfile::TempDir,
    /// Wall seconds of the uninterrupted run.
    seconds: f64,
}

impl Reference {
    fn build(second_folder: bool, extra: &[&str]) -> Self {
        let project = project(false);
        let started = Instant::now();
        let output = exe(project.path(), &run_args(REFERENCE, extra));
        assert!(output.status.success(), "{}", stderr(&output));
        let seconds = started.elapsed().as_secs_f64();
        if second_folder {
            let output = exe(project.path(), &run_args(REFERENCE, &SECOND));
            assert!(output.status.success(), "{}", stderr(&output));
        }
        Reference { project, seconds }
    }

    fn dir(&self) -> &Path {
        self.project.path()
    }

    fn out(&self) -> PathBuf {
        self.dir().join(REFERENCE)
    }
}

/// A copy of OUT after a run killed once both trainings have written the checkpoint
/// of their first epoch, with nothing else damaged: `plan` shows both trainings as
/// `to do (resumes after epoch 1)`. The kill may cut a write short and leave its
/// temporary file; one of a writer no longer running is always planted, so every run
/// from the copy meets one and must remove it.
fn checkpointed(dir: &Path, name: &str) -> PathBuf {
    let out = dir.join(name);
    let checkpoints = || {
        std::fs::read_dir(out.join(".cache/models")).map_or(0, |entries| {
            entries
                .flatten()
                .filter(|e| e.path().join("state.json").is_file())
                .count()
        })
    };
    for _ in 0..30 {
        let _ = std::fs::remove_dir_all(&out);
        let mut child = spawn(dir, &run_args(name, &EVERY_EPOCH));
        let started = Instant::now();
        while checkpoints() < 2
            && child.try_wait().unwrap().is_none()
            && started.elapsed() < Duration::from_secs(60)
        {
            std::thread::sleep(Duration::from_millis(1));
        }
        let _ = child.kill();
        child.wait().unwrap();
        let plan = stdout(&exe(dir, &plan_args(name, &[])));
        if plan.matches("to do (resumes after epoch 1)").count() == 2 && !plan.contains("damaged") {
            // No process has the largest pid.
            let stale = out.join(format!(".cache/models/.partial-{}-killed", u32::MAX));
            std::fs::write(stale, b"half a file").unwrap();
            return out;
        }
    }
    panic!("no run was caught with both checkpoints written and nothing else damaged");
}

// ---------------------------------------------------------------- comparing with it

/// What `out` holds that an uninterrupted run would not have written, file by file:
/// every file visible there must be whole (the reference's bytes where those are
/// reproducible, otherwise readable and consistent with its seal or manifest). With
/// `complete`, every file of the reference must be there too and no checkpoint left.
/// Set-aside entries, lock files, temporary files and the second folder are not
/// compared.
fn differences(out: &Path, reference: &Path, complete: bool) -> Vec<String> {
    let skip = |rel: &str| {
        rel.starts_with(".cache/damaged/")
            || rel.starts_with(".cache/locks/")
            || rel.starts_with("quick2/")
            || rel.starts_with("plots/quick2/")
            || file_name(rel).starts_with(".partial-")
    };
    let ours = tree(out);
    let theirs = tree(reference);
    let mut found = Vec::new();
    for (rel, path) in &ours {
        if skip(rel) {
            continue;
        }
        if let Some((stem, _)) = rel.split_once(".checkpoint/") {
            // A checkpoint beside its stored model is one a kill cut off while it was
            // being removed: whatever is left of it is never read.
            if ours.contains_key(&format!("{stem}.bin")) {
                if complete {
                    found.push(format!("{rel}: {LEFTOVER}"));
                }
                continue;
            }
            if complete {
                found.push(format!("{rel}: a checkpoint is left after the run ended"));
            }
        }
        if let Err(why) = whole(rel, path, theirs.get(rel)) {
            found.push(format!("{rel}: {why}"));
        }
    }
    if complete {
        for rel in theirs.keys() {
            if !skip(rel) && !ours.contains_key(rel) {
                found.push(format!("{rel}: missing"));
            }
        }
    }
    found
}

/// How [`differences`] names a checkpoint left beside its stored model.
const LEFTOVER: &str = "a checkpoint is left beside its stored model";

/// Whether the file at `rel` is whole; `reference` is the same file of the reference.
fn whole(rel: &str, path: &Path, reference: Option<&PathBuf>) -> Result<(), String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    let name = file_name(rel);
    if rel.contains(".checkpoint/") {
        return checkpoint_file_whole(path, name, &bytes);
    }
    let history = rel.starts_with(".cache/models/") && name.contains(".json");
    if history {
        // A model's history holds its wall times: sealed for its own bytes, under the
        // reference's key.
        return match name.strip_suffix(".sha256") {
            Some(data) => {
                let sealed = std::fs::read(path.with_file_name(data))
                    .map_err(|_| "a seal without its file".to_string())?;
                let key = reference
                    .and_then(|r| std::fs::read_to_string(r).ok())
                    .and_then(|s| s.split(' ').next().map(str::to_string))
                    .ok_or("not in the reference run")?;
                ensure!(
                    String::from_utf8_lossy(&bytes) == format!("{key} {}\n", sha256(&sealed)),
                    "does not seal its file"
                );
                Ok(())
            }
            None => {
                let value: serde_json::Value =
                    serde_json::from_slice(&bytes).map_err(|e| format!("not JSON: {e}"))?;
                let expected: serde_json::Value = reference
                    .and_then(|r| std::fs::read(r).ok())
                    .and_then(|b| serde_json::from_slice(&b).ok())
                    .ok_or("not in the reference run")?;
                for field in ["key", "best_epoch", "stop"] {
                    ensure!(value[field] == expected[field], "its {field} differs");
                }
                Ok(())
            }
        };
    }
    let reference = reference.ok_or("not in the reference run")?;
    let expected = std::fs::read(reference).unwrap();
    match name {
        "manifest.json" => manifest_matches(path, &bytes, &expected),
        "report.md" => {
            ensure!(
                normalized(&bytes) == normalized(&expected),
                "differs from the reference's beyond times and dates"
            );
            Ok(())
        }
        "report.sha256" => {
            // It holds the manifest's hash, and so its times: checked against the
            // files beside it.
            let folder = path.parent().unwrap();
            for line in String::from_utf8_lossy(&bytes).lines() {
                let (digest, file) = line.split_once("  ").ok_or("a line without its path")?;
                let sealed =
                    std::fs::read(folder.join(file)).map_err(|e| format!("{file}: {e}"))?;
                ensure!(
                    sha256(&sealed) == digest,
                    "{file} does not have its line's SHA-256"
                );
            }
            Ok(())
        }
        "training.parquet" => {
            ensure!(
                losses(path)? == losses(reference)?,
                "its losses differ from the reference's"
            );
            Ok(())
        }
        _ => {
            ensure!(
                bytes == expected,
                "{} bytes, not the reference's {} bytes",
                bytes.len(),
                expected.len()
            );
            Ok(())
        }
    }
}

/// A checkpoint's files: `state.json` holds its inline seal, a seal names its file's
/// SHA-256; an epoch file is checked through its seal.
fn checkpoint_file_whole(path: &Path, name: &str, bytes: &[u8]) -> Result<(), String> {
    if name == "state.json" {
        let at = bytes
            .iter()
            .position(|&b| b == b'\n')
            .ok_or("no seal line")?;
        let seal = String::from_utf8_lossy(&bytes[..at]);
        let digest = seal.split(' ').nth(1).ok_or("an unreadable seal line")?;
        ensure!(
            digest == sha256(&bytes[at + 1..]),
            "its body does not match its seal"
        );
        serde_json::from_slice::<serde_json::Value>(&bytes[at + 1..])
            .map_err(|e| format!("not JSON: {e}"))?;
    } else if let Some(data) = name.strip_suffix(".sha256") {
        let sealed =
            std::fs::read(path.with_file_name(data)).map_err(|_| "a seal without its file")?;
        let text = String::from_utf8_lossy(bytes);
        ensure!(
            text.trim().split(' ').nth(1) == Some(sha256(&sealed).as_str()),
            "does not seal its file"
        );
    }
    Ok(())
}

/// A manifest names the reference's results key and files, each with the SHA-256 the
/// reference's has (`training.parquet`, which holds wall times, the one beside it).
fn manifest_matches(path: &Path, bytes: &[u8], expected: &[u8]) -> Result<(), String> {
    let ours: serde_json::Value =
        serde_json::from_slice(bytes).map_err(|e| format!("not JSON: {e}"))?;
    let theirs: serde_json::Value = serde_json::from_slice(expected).unwrap();
    ensure!(
        ours["results_key"] == theirs["results_key"],
        "another results key"
    );
    let (Some(files), Some(expected)) = (
        ours["files_sha256"].as_object(),
        theirs["files_sha256"].as_object(),
    ) else {
        return Err("no files_sha256".into());
    };
    ensure!(
        files.keys().eq(expected.keys()),
        "names other files: {:?}",
        files.keys().collect::<Vec<_>>()
    );
    for (file, digest) in files {
        let wanted = if file == "training.parquet" {
            let beside = std::fs::read(path.with_file_name(file)).unwrap_or_default();
            serde_json::Value::String(sha256(&beside))
        } else {
            expected[file].clone()
        };
        ensure!(*digest == wanted, "another SHA-256 for {file}");
    }
    Ok(())
}

/// A report without its times and dates: every run of digits and dots one `#`, every
/// run of spaces or dashes one.
fn normalized(bytes: &[u8]) -> String {
    let mut text = String::new();
    for c in String::from_utf8_lossy(bytes).chars() {
        let c = if c.is_ascii_digit() || c == '.' {
            '#'
        } else {
            c
        };
        if matches!(c, '#' | ' ' | '-') && text.ends_with(c) {
            continue;
        }
        text.push(c);
    }
    text
}

fn try_read_parquet(path: &Path) -> Result<RecordBatch, String> {
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let reader = ParquetRecordBatchReaderBuilder::try_new(file)
        .and_then(|b| b.build())
        .map_err(|e| format!("not Parquet: {e}"))?;
    let mut batches = reader
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| format!("not Parquet: {e}"))?;
    ensure!(batches.len() == 1, "{} batches", batches.len());
    Ok(batches.remove(0))
}

type Losses = (Vec<Option<String>>, Vec<Option<f64>>, Vec<Option<f64>>);

fn losses(path: &Path) -> Result<Losses, String> {
    let batch = try_read_parquet(path)?;
    Ok((
        strings(&batch, "error_model"),
        floats(&batch, "train_loss"),
        floats(&batch, "validation_loss"),
    ))
}

// ---------------------------------------------------------------- case bookkeeping

/// Cases tried and held in one category.
#[derive(Default)]
struct Tally {
    rows: Vec<(String, [usize; 2])>,
    failures: Vec<String>,
}

impl Tally {
    /// Records a case's outcome; a failure is kept for the test to report.
    fn record(&mut self, category: &str, case: &str, outcome: Result<(), String>) {
        if self.rows.last().is_none_or(|(c, _)| c != category) {
            self.rows.push((category.to_string(), [0; 2]));
        }
        let row = &mut self.rows.last_mut().unwrap().1;
        row[0] += 1;
        match outcome {
            Ok(()) => row[1] += 1,
            Err(e) => self.failures.push(format!("{case}: {e}")),
        }
    }

    /// Prints the table; fails the test on any failure.
    fn finish(self, title: &str) {
        println!("\n{title}\n| category | tried | held |\n|---|---|---|");
        let mut total = [0; 2];
        for (category, row) in &self.rows {
            println!("| {category} | {} | {} |", row[0], row[1]);
            for (t, r) in total.iter_mut().zip(row) {
                *t += r;
            }
        }
        println!("| all | {} | {} |", total[0], total[1]);
        assert!(
            self.failures.is_empty(),
            "{} cases failed:\n{}",
            self.failures.len(),
            self.failures.join("\n\n")
        );
    }
}

/// "1 task", "2 tasks", as the run's log counts them.
fn tasks(count: usize) -> String {
    match count {
        1 => "1 task".to_string(),
        n => format!("{n} tasks"),
    }
}

// ---------------------------------------------------------------- (a) damaged files

#[derive(Debug, Clone, Copy, PartialEq)]
enum Damage {
    Truncate,
    Flip,
    Swap,
    Empty,
    Delete,
}

const DAMAGES: [Damage; 5] = [
    Damage::Truncate,
    Damage::Flip,
    Damage::Swap,
    Damage::Empty,
    Damage::Delete,
];

impl Damage {
    /// Damages `target` (swapping it with `partner`): the files damaged, with their
    /// bytes now (none when deleted).
    fn apply(
        self,
        target: &Path,
        partner: &Path,
        flip_after: Option<&str>,
    ) -> Vec<(PathBuf, Option<Vec<u8>>)> {
        let bytes = std::fs::read(target).unwrap();
        let damaged = match self {
            Damage::Truncate => bytes[..bytes.len() / 2].to_vec(),
            Damage::Flip => {
                let at = match flip_after {
                    Some(text) => {
                        let text = text.as_bytes();
                        bytes.windows(text.len()).position(|w| w == text).unwrap() + text.len()
                    }
                    None => bytes.len() / 2,
                };
                let mut flipped = bytes;
                flipped[at] ^= 1;
                flipped
            }
            Damage::Swap => {
                let other = std::fs::read(partner).unwrap();
                assert_ne!(
                    other,
                    bytes,
                    "{} is a copy of its partner",
                    target.display()
                );
                std::fs::write(partner, &bytes).unwrap();
                std::fs::write(target, &other).unwrap();
                return vec![
                    (target.to_path_buf(), Some(other)),
                    (partner.to_path_buf(), Some(bytes)),
                ];
            }
            Damage::Empty => Vec::new(),
            Damage::Delete => {
                std::fs::remove_file(target).unwrap();
                return vec![(target.to_path_buf(), None)];
            }
        };
        std::fs::write(target, &damaged).unwrap();
        vec![(target.to_path_buf(), Some(damaged))]
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Fixture {
    /// A copy of the finished reference run.
    Complete,
    /// A copy of a run killed with both trainings checkpointed.
    Checkpointed,
    /// A copy of a finished sweep of two points.
    Sweep,
}

/// A kind of file, found in a case's OUT, with another of its kind to swap it with.
#[derive(Clone, Copy)]
struct Kind {
    name: &'static str,
    fixture: Fixture,
    /// Whether the file belongs to the cache (else to a results or figures folder).
    cache: bool,
    target: fn(&Path) -> PathBuf,
    partner: fn(&Path) -> PathBuf,
    /// A flipped byte is the one after this text, instead of the middle one.
    flip_after: Option<&'static str>,
    damages: &'static [Damage],
}

fn kind(
    name: &'static str,
    fixture: Fixture,
    cache: bool,
    target: fn(&Path) -> PathBuf,
    partner: fn(&Path) -> PathBuf,
) -> Kind {
    Kind {
        name,
        fixture,
        cache,
        target,
        partner,
        flip_after: None,
        damages: &DAMAGES,
    }
}

fn kinds() -> Vec<Kind> {
    use Fixture::*;
    vec![
        kind(
            "model weights (.bin)",
            Complete,
            true,
            |o| model_file(o, "EM1", ".bin"),
            |o| model_file(o, "EM3", ".bin"),
        ),
        kind(
            "model history (.json)",
            Complete,
            true,
            |o| model_file(o, "EM1", ".json"),
            |o| model_file(o, "EM3", ".json"),
        ),
        kind(
            "model seal (.bin.sha256)",
            Complete,
            true,
            |o| model_file(o, "EM1", ".bin.sha256"),
            |o| model_file(o, "EM3", ".bin.sha256"),
        ),
        kind(
            "Monte Carlo block (.parquet)",
            Complete,
            true,
            |o| block(o, 0, false),
            |o| block(o, 1, false),
        ),
        kind(
            "block seal (.parquet.sha256)",
            Complete,
            true,
            |o| block(o, 0, true),
            |o| block(o, 1, true),
        ),
        kind(
            "checkpoint state.json",
            Checkpointed,
            true,
            |o| checkpoint_file(o, "EM1", "state.json"),
            |o| checkpoint_file(o, "EM3", "state.json"),
        ),
        kind(
            "checkpoint epoch file (epoch-1.optimizer)",
            Checkpointed,
            true,
            |o| checkpoint_file(o, "EM1", "epoch-1.optimizer"),
            |o| checkpoint_file(o, "EM3", "epoch-1.optimizer"),
        ),
        kind(
            "checkpoint epoch seal (epoch-1.model.sha256)",
            Checkpointed,
            true,
            |o| checkpoint_file(o, "EM1", "epoch-1.model.sha256"),
            |o| checkpoint_file(o, "EM3", "epoch-1.model.sha256"),
        ),
        kind(
            "calibration.parquet",
            Complete,
            false,
            |o| o.join("quick/calibration.parquet"),
            |o| o.join("quick/evaluation.parquet"),
        ),
        kind(
            "evaluation.parquet",
            Complete,
            false,
            |o| o.join("quick/evaluation.parquet"),
            |o| o.join("quick/calibration.parquet"),
        ),
        kind(
            "manifest.json",
            Complete,
            false,
            |o| o.join("quick/manifest.json"),
            |o| o.join("quick2/manifest.json"),
        ),
        Kind {
            flip_after: Some("\"started_at\": \""),
            damages: &[Damage::Flip],
            ..kind(
                "manifest.json, a provenance byte",
                Complete,
                false,
                |o| o.join("quick/manifest.json"),
                |o| o.join("quick2/manifest.json"),
            )
        },
        kind(
            "spec.toml",
            Complete,
            false,
            |o| o.join("quick/spec.toml"),
            |o| o.join("quick2/spec.toml"),
        ),
        kind(
            "report.md",
            Complete,
            false,
            |o| o.join("quick/report.md"),
            |o| o.join("quick2/report.md"),
        ),
        kind(
            "report.tex",
            Complete,
            false,
            |o| o.join("quick/report.tex"),
            |o| o.join("quick2/report.tex"),
        ),
        kind(
            "figure (calibration.png)",
            Complete,
            false,
            |o| o.join("plots/quick/calibration.png"),
            |o| o.join("plots/quick/velocity.png"),
        ),
        kind(
            "sweep.parquet",
            Sweep,
            false,
            |o| o.join("quick-sweep/sweep.parquet"),
            |o| o.join("quick-sweep/monte_carlo_runs=2/evaluation.parquet"),
        ),
    ]
}

/// What a log names a damaged cache file by: the file its seal belongs to, with its
/// checkpoint folder where it has one.
fn named(path: &Path) -> String {
    let text = path.to_string_lossy();
    let data = Path::new(text.strip_suffix(".sha256").unwrap_or(&text));
    let name = data.file_name().unwrap().to_string_lossy();
    let parent = data
        .parent()
        .unwrap()
        .file_name()
        .unwrap()
        .to_string_lossy();
    if parent.ends_with(".checkpoint") {
        format!("{parent}/{name}")
    } else {
        name.into_owned()
    }
}

/// The files set aside with a deleted one: its seal, the file of a deleted seal, or
/// the epoch files of a checkpoint's `state.json`.
fn companions(path: &Path) -> Vec<PathBuf> {
    let text = path.to_string_lossy();
    if let Some(data) = text.strip_suffix(".sha256") {
        return vec![PathBuf::from(data)];
    }
    if path.file_name().unwrap() == "state.json" {
        return vec![path.with_file_name("epoch-1.model")];
    }
    vec![PathBuf::from(format!("{text}.sha256"))]
}

/// The entry a cache file belongs to, as a prefix of its files' paths: a model's
/// `<EM>-<key>.`, a block's `<key>.parquet`.
fn entry_prefix(rel: &str) -> String {
    let (dir, name) = rel.rsplit_once('/').unwrap();
    let stem = name.split('.').next().unwrap();
    format!("{dir}/{stem}.")
}

/// The folders of one test: the project, the reference and the fixtures it asks for.
struct Bench {
    reference: Reference,
    checkpointed: Option<PathBuf>,
    sweep: Option<PathBuf>,
    cases: usize,
}

impl Bench {
    fn new(kinds: &[Kind]) -> Self {
        let reference = Reference::build(true, &[]);
        let dir = reference.dir().to_path_buf();
        let needs = |fixture| kinds.iter().any(|k| k.fixture == fixture);
        let checkpointed = needs(Fixture::Checkpointed).then(|| checkpointed(&dir, "checkpointed"));
        let sweep = needs(Fixture::Sweep).then(|| {
            let output = exe(&dir, &run_args("sweep-reference", &SWEEP));
            assert!(output.status.success(), "{}", stderr(&output));
            dir.join("sweep-reference")
        });
        Bench {
            reference,
            checkpointed,
            sweep,
            cases: 0,
        }
    }

    /// Runs every damage of `kinds` and records each in `tally`.
    fn run_all(&mut self, kinds: &[Kind], tally: &mut Tally) {
        for kind in kinds {
            for &damage in kind.damages {
                let outcome = self.case(kind, damage);
                let case = format!("{} / {damage:?}", kind.name);
                tally.record(kind.name, &case, outcome);
            }
        }
    }

    /// Damages a copy of the fixture of `kind`, runs `plan` and `run` on it and checks
    /// what issue 13 asks.
    fn case(&mut self, kind: &Kind, damage: Damage) -> Result<(), String> {
        self.cases += 1;
        let dir = self.reference.dir().to_path_buf();
        let name = format!("case-{}", self.cases);
        let out = dir.join(&name);
        let (fixture, reference, extra): (PathBuf, PathBuf, &[&str]) = match kind.fixture {
            Fixture::Complete => (self.reference.out(), self.reference.out(), &[]),
            Fixture::Checkpointed => (
                self.checkpointed.clone().unwrap(),
                self.reference.out(),
                &[],
            ),
            Fixture::Sweep => (
                self.sweep.clone().unwrap(),
                self.sweep.clone().unwrap(),
                &SWEEP,
            ),
        };
        copy_tree(&fixture, &out);
        let target = (kind.target)(&out);
        let partner = (kind.partner)(&out);
        let cache_entry = kind.cache;
        let kept: Vec<(PathBuf, Vec<u8>)> = companions(&target)
            .into_iter()
            .filter_map(|p| std::fs::read(&p).ok().map(|b| (p, b)))
            .collect();
        let damaged = damage.apply(&target, &partner, kind.flip_after);
        let entries = if cache_entry { damaged.len() } else { 0 };

        let plan = exe(&dir, &plan_args(&name, extra));
        ensure!(plan.status.success(), "plan failed: {}", stderr(&plan));
        let listed = stdout(&plan);
        let shown = listed.matches("to do (damaged)").count();
        ensure!(
            shown == entries,
            "plan shows {shown} tasks `to do (damaged)`, not {entries}:\n{listed}"
        );
        // A sweep table's partner is a table of one of its points: swapped, both
        // folders are to do.
        let to_do = match (kind.name, damage) {
            ("sweep.parquet", Damage::Swap) => 2,
            _ => 1,
        };
        if !cache_entry {
            ensure!(
                listed.contains(&format!("{to_do} to do;")),
                "plan does not show the {to_do} damaged results as to do:\n{listed}"
            );
        }
        ensure!(
            !out.join(".cache/damaged").exists(),
            "plan set something aside"
        );

        let before = kept_snapshot(&out);
        let output = exe(&dir, &run_args(&name, extra));
        let log = stderr(&output);
        ensure!(
            output.status.code() == Some(0),
            "run exited with {:?}:\n{log}",
            output.status.code()
        );
        let reports = log.lines().filter(|l| l.contains("damaged")).count();
        ensure!(
            reports == entries,
            "{reports} lines report damage, not {entries}:\n{log}"
        );
        if cache_entry {
            let aside: Vec<Vec<u8>> = tree(&out.join(".cache/damaged"))
                .values()
                .map(|p| std::fs::read(p).unwrap())
                .collect();
            for (path, bytes) in &damaged {
                let named = named(path);
                let count = log.matches(named.as_str()).count();
                ensure!(
                    count == 1,
                    "the log names {named} {count} times, not once:\n{log}"
                );
                match bytes {
                    Some(bytes) => ensure!(
                        aside.contains(bytes),
                        "the damaged {named} is not in .cache/damaged/"
                    ),
                    None => {
                        for (companion, bytes) in &kept {
                            ensure!(
                                aside.contains(bytes),
                                "{} (beside the deleted {named}) is not in .cache/damaged/",
                                companion.display()
                            );
                        }
                    }
                }
            }
        } else {
            ensure!(
                log.contains(&format!("{} to do", tasks(to_do))),
                "not {to_do} to do:\n{log}"
            );
        }
        // Nothing already computed is lost: every entry the damage did not touch is
        // the same file as before, and a damaged checkpoint leaves the other to resume.
        // A killed writer's temporary file (the checkpointed fixture always holds one)
        // is not computed work: the next run removes it.
        let affected: Vec<String> = damaged
            .iter()
            .map(|(p, _)| entry_prefix(&p.strip_prefix(&out).unwrap().to_string_lossy()))
            .collect();
        let after = kept_snapshot(&out);
        for (rel, (bytes, modified)) in &before {
            let untouched = rel.starts_with(".cache/")
                && !(cache_entry && affected.iter().any(|a| rel.starts_with(a.as_str())))
                && !rel.contains(".checkpoint/")
                && !file_name(rel).starts_with(".partial-");
            if untouched {
                ensure!(
                    after.get(rel) == Some(&(bytes.clone(), *modified)),
                    "{rel}, untouched by the damage, was rewritten or removed:\n{log}"
                );
            }
        }
        if kind.fixture == Fixture::Checkpointed && damage != Damage::Swap {
            ensure!(
                log.contains("resumed from the checkpoint of epoch 1"),
                "the undamaged checkpoint was not resumed:\n{log}"
            );
        }
        let found = differences(&out, &reference, true);
        ensure!(
            found.is_empty(),
            "after the run, {name} differs from the reference: {found:#?}\n{log}"
        );
        let left = partials(&out);
        ensure!(left.is_empty(), "temporary files left: {left:?}");
        let again = exe(&dir, &run_args(&name, extra));
        ensure!(
            again.status.success() && stderr(&again).contains("nothing to do"),
            "a second run is not `nothing to do`:\n{}",
            stderr(&again)
        );
        std::fs::remove_dir_all(&out).unwrap();
        Ok(())
    }
}

#[test]
fn damaged_cache_entries_are_reported_once_set_aside_and_computed_again() {
    let kinds: Vec<Kind> = kinds().into_iter().filter(|k| k.cache).collect();
    let mut bench = Bench::new(&kinds);
    let mut tally = Tally::default();
    bench.run_all(&kinds, &mut tally);
    tally.finish("damaged cache entries");
}

#[test]
fn damaged_results_files_make_their_folder_written_again() {
    let kinds: Vec<Kind> = kinds().into_iter().filter(|k| !k.cache).collect();
    let mut bench = Bench::new(&kinds);
    let mut tally = Tally::default();
    bench.run_all(&kinds, &mut tally);
    tally.finish("damaged results files");
}

/// Damages the file at `path` by flipping the byte at `at`.
fn flip(path: &Path, at: usize) {
    let mut bytes = std::fs::read(path).unwrap();
    bytes[at] ^= 1;
    std::fs::write(path, bytes).unwrap();
}

/// Waits for the start of a wall-clock second, so that what follows shares one.
fn at_a_second_start() {
    let sub = SystemTime::now()
        .duration_since(SystemTime::UNIX_EPOCH)
        .unwrap()
        .subsec_millis();
    std::thread::sleep(Duration::from_millis(u64::from(1000 - sub) + 5));
}

#[test]
fn an_entry_damaged_twice_within_a_second_keeps_both_damaged_copies() {
    let reference = Reference::build(false, &[]);
    let dir = reference.dir();
    let out = reference.out();
    let weights = model_file(&out, "EM1", ".bin");
    at_a_second_start();
    flip(&weights, 1000);
    let first = exe(dir, &run_args(REFERENCE, &[]));
    assert!(first.status.success(), "{}", stderr(&first));
    flip(&weights, 2000);
    let second = exe(dir, &run_args(REFERENCE, &[]));
    assert!(second.status.success(), "{}", stderr(&second));
    let aside: Vec<String> = tree(&out.join(".cache/damaged"))
        .into_keys()
        .filter(|rel| rel.contains(".bin.") && !rel.contains(".sha256"))
        .collect();
    assert_eq!(aside.len(), 2, "both damaged weights are kept: {aside:?}");
}

#[test]
fn a_checkpoint_damaged_twice_within_a_second_is_set_aside_again() {
    let reference = Reference::build(false, &[]);
    let dir = reference.dir();
    let fixture = checkpointed(dir, "checkpointed");
    let name = "twice";
    let out = dir.join(name);
    copy_tree(&fixture, &out);
    let checkpoint = checkpoint_file(&out, "EM1", "");
    let state = checkpoint.join("state.json");
    at_a_second_start();
    std::fs::write(&state, b"").unwrap();
    let first = exe(dir, &run_args(name, &["--no-plots"]));
    assert!(first.status.success(), "{}", stderr(&first));
    // The same checkpoint again, damaged again, with its model to train again.
    for (rel, path) in tree(&fixture) {
        if rel.contains(".checkpoint/") {
            let to = out.join(&rel);
            std::fs::create_dir_all(to.parent().unwrap()).unwrap();
            std::fs::copy(path, to).unwrap();
        }
    }
    for extension in [".bin", ".bin.sha256", ".json", ".json.sha256"] {
        std::fs::remove_file(model_file(&out, "EM1", extension)).unwrap();
    }
    std::fs::write(&state, b"").unwrap();
    let second = exe(dir, &run_args(name, &["--no-plots"]));
    assert_eq!(second.status.code(), Some(0), "{}", stderr(&second));
    let aside = tree(&out.join(".cache/damaged"));
    assert_eq!(
        aside
            .keys()
            .filter(|rel| rel.ends_with("state.json"))
            .count(),
        2,
        "{aside:?}"
    );
}

// ---------------------------------------------------------------- (b) kills

/// SplitMix64: the pseudo-random delays, the same on every run.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The stage a run was in when its log ended with `lines`.
fn stage(lines: &[String], ended: bool) -> &'static str {
    if ended {
        return "after the end";
    }
    let trained = lines.iter().filter(|l| l.starts_with("DCNet ")).count();
    match lines.last().map(String::as_str) {
        None => "loading",
        Some(l) if l.starts_with("quick: ") => "dataset",
        Some(l) if l.starts_with("dataset ") => "training",
        Some(l) if l.starts_with("DCNet ") && trained < 2 => "training",
        Some(l) if l.starts_with("DCNet ") => "monte carlo",
        Some(l) if l.starts_with("monte carlo quick DVL1") => "monte carlo",
        Some(l) if l.starts_with("monte carlo") => "results tables",
        Some(l) if l.starts_with("results written") => "figures",
        Some(l) if l.starts_with("figure") => "reports",
        Some(_) => "after the end",
    }
}

/// Starts a run into `name` and kills it (SIGKILL) `offset` after its log shows a
/// line starting with `anchor` (at once when `anchor` is empty): the stage it was in.
fn kill_run(dir: &Path, name: &str, anchor: &str, offset: Duration) -> &'static str {
    let mut child = spawn(dir, &run_args(name, &EVERY_EPOCH));
    let pipe = child.stderr.take().unwrap();
    let (sender, receiver) = mpsc::channel();
    let reader = std::thread::spawn(move || {
        for line in BufReader::new(pipe).lines() {
            let Ok(line) = line else { break };
            if sender.send(line).is_err() {
                break;
            }
        }
    });
    let mut lines = Vec::new();
    if !anchor.is_empty() {
        while let Ok(line) = receiver.recv_timeout(Duration::from_secs(60)) {
            let found = line.starts_with(anchor);
            lines.push(line);
            if found {
                break;
            }
        }
    }
    std::thread::sleep(offset);
    let ended = child.try_wait().unwrap().is_some();
    let _ = child.kill();
    child.wait().unwrap();
    reader.join().unwrap();
    lines.extend(receiver.try_iter());
    stage(&lines, ended)
}

/// Whether `path` has the bytes its seal names.
fn sealed(path: &Path) -> bool {
    let seal = std::fs::read_to_string(format!("{}.sha256", path.display()));
    seal.is_ok_and(|seal| {
        std::fs::read(path)
            .is_ok_and(|bytes| seal.trim().split(' ').nth(1) == Some(sha256(&bytes).as_str()))
    })
}

/// The entries stored whole in `out`'s cache (a model's weights with its history, a
/// block), with the time of their main file.
fn stored(out: &Path) -> BTreeMap<String, SystemTime> {
    tree(&out.join(".cache"))
        .into_iter()
        .filter(|(rel, path)| {
            !rel.starts_with("damaged/")
                && !rel.contains(".checkpoint/")
                && (rel.ends_with(".parquet")
                    || (rel.ends_with(".bin") && sealed(&path.with_extension("json"))))
                && sealed(path)
        })
        .map(|(rel, path)| (rel, path.metadata().unwrap().modified().unwrap()))
        .collect()
}

/// After a kill: every visible file whole. Then a resumed run that keeps what was
/// stored, resumes a checkpoint, and ends with the reference's files and no
/// temporaries anywhere.
fn check_kill_and_resume(reference: &Reference, name: &str, resume: bool) -> Result<(), String> {
    let dir = reference.dir();
    let out = dir.join(name);
    let found = differences(&out, &reference.out(), false);
    ensure!(
        found.is_empty(),
        "after the kill, a visible file is not whole: {found:#?}"
    );
    if !resume {
        return Ok(());
    }
    let kept = stored(&out);
    let plan = stdout(&exe(dir, &plan_args(name, &[])));
    let output = exe(dir, &run_args(name, &EVERY_EPOCH));
    let log = stderr(&output);
    ensure!(
        output.status.code() == Some(0),
        "the resumed run exited with {:?}:\n{log}",
        output.status.code()
    );
    if plan.contains("to do (resumes after epoch") {
        ensure!(
            log.contains("resumed from the checkpoint of epoch"),
            "a checkpoint was not resumed:\n{plan}\n{log}"
        );
    }
    let now = stored(&out);
    for (rel, modified) in &kept {
        ensure!(
            now.get(rel) == Some(modified),
            "{rel}, stored before the resume, was computed again:\n{log}"
        );
    }
    let found = differences(&out, &reference.out(), true);
    ensure!(
        found.is_empty(),
        "the resumed run differs from the reference: {found:#?}\n{log}"
    );
    let left = partials(&out);
    ensure!(
        left.is_empty(),
        "temporary files left after the resume: {left:?}"
    );
    Ok(())
}

#[test]
fn kills_at_pseudo_random_moments_leave_whole_files_and_resume_to_the_same_bytes() {
    // The killed runs checkpoint every epoch, which their resolved spec.toml records.
    let reference = Reference::build(false, &EVERY_EPOCH);
    let dir = reference.dir();
    let total = reference.seconds;
    let mut random = SplitMix(13);
    // (anchor, kills, the share of the reference run's time the delay is drawn from)
    let anchors: [(&str, usize, f64); 7] = [
        ("", 1, 0.01),
        ("quick: ", 2, 0.002),
        ("dataset ", 4, 0.4),
        ("DCNet ", 2, 0.15),
        ("monte carlo quick DVL1", 3, 0.02),
        ("results written", 3, 0.4),
        ("figure training_loss", 1, 0.01),
    ];
    let mut tally = Tally::default();
    let mut stages: BTreeMap<&str, usize> = BTreeMap::new();
    let mut kill = 0;
    for (anchor, count, share) in anchors {
        for _ in 0..count {
            kill += 1;
            let name = format!("killed-{kill}");
            let offset = Duration::from_secs_f64(random.unit() * share * total);
            let stage = kill_run(dir, &name, anchor, offset);
            *stages.entry(stage).or_default() += 1;
            let outcome = check_kill_and_resume(&reference, &name, true);
            let case = format!("kill {kill}, {offset:?} after `{anchor}`, during {stage}");
            tally.record("single kill, then resume", &case, outcome);
            let _ = std::fs::remove_dir_all(dir.join(&name));
        }
    }
    // One folder, killed again and again at any moment, then finished.
    let name = "killed-again";
    for round in 1..=6 {
        let offset = Duration::from_secs_f64(random.unit() * 0.3 * total);
        let stage = kill_run(dir, name, "", offset);
        *stages.entry(stage).or_default() += 1;
        let outcome = check_kill_and_resume(&reference, name, false);
        let case = format!("chained kill {round}, {offset:?} after the start, during {stage}");
        tally.record("kills in a row", &case, outcome);
    }
    let outcome = check_kill_and_resume(&reference, name, true);
    tally.record("kills in a row", "resume after 6 kills", outcome);
    println!("\nkills by the stage they cut (reference run {total:.2} s): {stages:?}");
    for wanted in ["training", "monte carlo", "figures"] {
        assert!(
            stages.contains_key(wanted),
            "no kill cut the {wanted}: {stages:?}"
        );
    }
    tally.finish("kills");
}

#[test]
fn a_killed_figure_writers_temporary_file_is_removed_by_the_next_run() {
    let reference = Reference::build(false, &[]);
    let dir = reference.dir();
    let out = reference.out();
    // What a figure writer killed mid-write leaves (no process has the largest pid),
    // in a run killed before its reports.
    let stale = out.join(format!("plots/quick/.partial-{}-abcdef", u32::MAX));
    std::fs::write(&stale, b"half a figure").unwrap();
    std::fs::remove_file(out.join("quick/report.md")).unwrap();
    let output = exe(dir, &run_args(REFERENCE, &[]));
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        !stale.exists(),
        "{} is left after the next run",
        stale.display()
    );
}

#[test]
fn a_checkpoint_left_beside_its_stored_model_is_removed() {
    let reference = Reference::build(false, &[]);
    let dir = reference.dir();
    let fixture = checkpointed(dir, "checkpointed");
    // What a run killed right after storing EM1, before removing its checkpoint,
    // leaves.
    let out = reference.out();
    for (rel, path) in tree(&fixture) {
        if rel.contains("EM1-") && rel.contains(".checkpoint/") {
            let to = out.join(&rel);
            std::fs::create_dir_all(to.parent().unwrap()).unwrap();
            std::fs::copy(path, to).unwrap();
        }
    }
    let output = exe(dir, &run_args(REFERENCE, &[]));
    assert!(output.status.success(), "{}", stderr(&output));
    let left: Vec<String> = tree(&out)
        .into_keys()
        .filter(|rel| rel.contains(".checkpoint/"))
        .collect();
    assert!(left.is_empty(), "left after the next run: {left:?}");
}

// ---------------------------------------------------------------- (c) a full disk

/// Why this process cannot mount a tmpfs, if it cannot.
fn cannot_mount() -> Option<String> {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let uid = status
        .lines()
        .find_map(|l| l.strip_prefix("Uid:"))
        .and_then(|l| l.split_whitespace().next().map(str::to_string));
    if uid.as_deref() != Some("0") {
        return Some(format!("not root (uid {uid:?})"));
    }
    None
}

/// A tmpfs mounted at a folder, unmounted when dropped.
struct Tmpfs(PathBuf);

impl Tmpfs {
    fn mount(at: &Path, bytes: u64) -> Result<Self, String> {
        std::fs::create_dir_all(at).unwrap();
        let output = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={bytes}"), "tmpfs"])
            .arg(at)
            .output()
            .map_err(|e| format!("mount: {e}"))?;
        if !output.status.success() {
            return Err(format!(
                "mount -t tmpfs failed: {}",
                String::from_utf8_lossy(&output.stderr).trim()
            ));
        }
        Ok(Tmpfs(at.to_path_buf()))
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let unmounted = Command::new("umount")
            .arg(&self.0)
            .status()
            .is_ok_and(|s| s.success());
        if !unmounted {
            let _ = Command::new("umount").arg("-l").arg(&self.0).status();
        }
    }
}

/// The bytes the reference's files take on a filesystem of 4 KiB pages.
fn footprint(out: &Path) -> u64 {
    tree(out)
        .values()
        .map(|p| p.metadata().unwrap().len().div_ceil(4096) * 4096)
        .sum()
}

/// Where a run that ran out of space was, by the file it names.
fn disk_stage(log: &str) -> &'static str {
    let line = log
        .lines()
        .find(|l| l.contains("No space left"))
        .unwrap_or("");
    if line.contains(".checkpoint/") {
        "checkpoint"
    } else if line.contains(".cache/models/") {
        "model"
    } else if line.contains(".cache/monte_carlo/") {
        "monte carlo block"
    } else if line.contains("/plots/") {
        "figures"
    } else if line.contains("report.") {
        "reports"
    } else {
        "results tables"
    }
}

/// A run into a tmpfs of `bytes` that fills up: exit 2 naming the file and "No space
/// left", every visible file whole and no temporaries; then the folder, copied where
/// there is room, resumes to the reference. Returns the stage that ran out of space.
/// `checkpointing` is the reference run with `extra`, which the files visible after
/// the failure are compared with.
fn full_disk_case(
    reference: &Reference,
    checkpointing: &Reference,
    index: usize,
    bytes: u64,
    extra: &[&str],
) -> Result<&'static str, String> {
    let dir = reference.dir();
    let disk = format!("disk-{index}");
    let out = format!("{disk}/out");
    let stage;
    {
        let _tmpfs = Tmpfs::mount(&dir.join(&disk), bytes)?;
        let output = exe(dir, &run_args(&out, extra));
        let log = stderr(&output);
        if output.status.success() {
            stage = "none (it fitted)";
        } else {
            ensure!(
                output.status.code() == Some(2),
                "exit {:?}, not 2:\n{log}",
                output.status.code()
            );
            ensure!(
                log.contains("No space left on device"),
                "no `No space left on device`:\n{log}"
            );
            let error = log
                .lines()
                .find(|l| l.starts_with("error: "))
                .unwrap_or_default();
            ensure!(
                error.contains(&format!("{out}/")),
                "the error names no file of {out}:\n{log}"
            );
            stage = disk_stage(&log);
        }
        let like = if extra.is_empty() {
            reference
        } else {
            checkpointing
        };
        let found = differences(&dir.join(&out), &like.out(), false);
        ensure!(
            found.is_empty(),
            "a visible file is not whole: {found:#?}\n{log}"
        );
        let left = partials(&dir.join(&out));
        ensure!(left.is_empty(), "temporary files left: {left:?}");
        copy_tree(&dir.join(&out), &dir.join(format!("{disk}-roomy")));
    }
    // Resumed as the reference ran: how often a checkpoint is written changes no
    // result, only the resolved spec.toml.
    let roomy = format!("{disk}-roomy");
    let output = exe(dir, &run_args(&roomy, &[]));
    ensure!(
        output.status.success(),
        "the resumed run failed:\n{}",
        stderr(&output)
    );
    let found = differences(&dir.join(&roomy), &reference.out(), true);
    ensure!(
        found.is_empty(),
        "the resumed run differs from the reference: {found:#?}\n{}",
        stderr(&output)
    );
    let _ = std::fs::remove_dir_all(dir.join(&roomy));
    Ok(stage)
}

/// A finished folder on a full disk rewritten for a report setting: the tables fit
/// but a figure does not. Once there is room again, the next run must draw every
/// figure and write the reports.
fn full_disk_while_drawing(reference: &Reference, bytes: u64) -> Result<(), String> {
    let dir = reference.dir();
    let disk = dir.join("disk-figures");
    let _tmpfs = Tmpfs::mount(&disk, bytes)?;
    let out = "disk-figures/out";
    let first = exe(dir, &run_args(out, &[]));
    ensure!(first.status.success(), "{}", stderr(&first));
    for path in tree(&dir.join(out).join("plots")).values() {
        std::fs::remove_file(path).unwrap();
    }
    // Leave 300 KiB: every table fits beside its old self, not every figure.
    let filler = disk.join("filler");
    {
        let mut file = std::fs::File::create(&filler).unwrap();
        let chunk = vec![0u8; 64 << 10];
        while file.write_all(&chunk).is_ok() {}
        let _ = file.flush();
        let length = std::fs::metadata(&filler).unwrap().len();
        file.set_len(length.saturating_sub(300 << 10)).unwrap();
    }
    let tolerance = ["--set", "report.tolerance_pct=5"];
    let full = exe(dir, &run_args(out, &tolerance));
    let log = stderr(&full);
    ensure!(
        full.status.code() == Some(2) && log.contains("No space left") && log.contains("/plots/"),
        "the figures did not run out of space (exit {:?}):\n{log}",
        full.status.code()
    );
    std::fs::remove_file(&filler).unwrap();
    let again = exe(dir, &run_args(out, &tolerance));
    ensure!(again.status.success(), "{}", stderr(&again));
    for rel in tree(&reference.out().join("plots/quick")).keys() {
        ensure!(
            dir.join(out).join("plots/quick").join(rel).is_file(),
            "plots/quick/{rel} is not drawn again once there is room:\n{}",
            stderr(&again)
        );
    }
    Ok(())
}

#[test]
fn a_full_disk_fails_with_exit_2_naming_the_file_and_resumes_to_the_same_bytes() {
    if let Some(reason) = cannot_mount() {
        println!("skipped: {reason}");
        return;
    }
    let reference = Reference::build(false, &[]);
    // Its resolved spec.toml records how often a checkpoint is written.
    let checkpointing = Reference::build(false, &EVERY_EPOCH);
    let size = footprint(&reference.out());
    // Shares of the reference's footprint; with a checkpoint every epoch, training
    // needs more room than the finished run.
    let cases: [(f64, &[&str]); 11] = [
        (0.04, &[]),
        (0.15, &[]),
        (0.26, &[]),
        (0.3, &[]),
        (0.36, &[]),
        (0.45, &[]),
        (0.7, &[]),
        (0.9, &[]),
        (0.05, &EVERY_EPOCH),
        (0.1, &EVERY_EPOCH),
        (0.2, &EVERY_EPOCH),
    ];
    let mut tally = Tally::default();
    let mut stages: BTreeMap<&str, usize> = BTreeMap::new();
    for (index, (share, extra)) in cases.into_iter().enumerate() {
        let bytes = ((size as f64 * share) as u64).div_ceil(4096) * 4096;
        let outcome = full_disk_case(&reference, &checkpointing, index, bytes, extra);
        if let Err(why) = &outcome
            && why.starts_with("mount")
        {
            println!("skipped: {why}");
            return;
        }
        let stage = outcome.as_ref().map_or("failed", |s| *s);
        *stages.entry(stage).or_default() += 1;
        let case = format!(
            "tmpfs of {} KiB {extra:?}, out of space at {stage}",
            bytes >> 10
        );
        tally.record("full disk, then resume", &case, outcome.map(|_| ()));
    }
    let outcome = full_disk_while_drawing(&reference, 2 * size);
    tally.record(
        "full disk while redrawing a finished folder",
        "figures out of space",
        outcome,
    );
    println!(
        "\nfull disks by the stage that ran out of space (footprint {} KiB): {stages:?}",
        size >> 10
    );
    // Every stage that writes must have been reached by some size.
    for wanted in [
        "model",
        "monte carlo block",
        "results tables",
        "figures",
        "checkpoint",
    ] {
        assert!(
            stages.contains_key(wanted),
            "no case ran out of space at {wanted}: {stages:?}"
        );
    }
    tally.finish("full disk");
}

// ---------------------------------------------------------------- whose folder

/// What makes the other spec file's spec another one: a report setting.
const OTHER: [&str; 2] = ["--set", "report.tolerance_pct=5"];

/// `run` with the spec file `spec` in place of the quick one.
fn run_of(spec: &str, out: &str, extra: &[&str]) -> Vec<String> {
    let mut args = run_args(out, extra);
    args[1] = spec.to_string();
    args
}

/// A results folder is never replaced by a run of another spec file with the same
/// `name` unless `--force`: the error names the folder and both specs, and the folder
/// is left as it was. A single run and a sweep never share a folder.
#[test]
fn a_results_folder_of_another_spec_is_refused_unless_forced() {
    let project = project(false);
    let d = project.path();
    std::fs::copy(d.join(SPEC), d.join("experiments/other.toml")).unwrap();
    let output = exe(d, &run_args("out", &[]));
    assert!(output.status.success(), "{}", stderr(&output));
    let manifest = d.join("out/quick/manifest.json");
    let before = std::fs::read(&manifest).unwrap();

    let other = run_of("experiments/other.toml", "out", &OTHER);
    let refused = exe(d, &other);
    let message = stderr(&refused);
    assert_eq!(refused.status.code(), Some(1), "{message}");
    for part in [
        "out/quick",
        "experiments/quick.toml",
        "experiments/other.toml",
    ] {
        assert!(message.contains(part), "{part}: {message}");
    }
    assert!(message.contains("--force"), "{message}");
    assert!(!message.contains("results written"), "{message}");
    assert!(
        std::fs::read(&manifest).unwrap() == before,
        "the folder changed"
    );

    let forced = exe(d, &[other, vec!["--force".into()]].concat());
    assert!(forced.status.success(), "{}", stderr(&forced));
    let after = std::fs::read_to_string(&manifest).unwrap();
    assert!(after.contains("experiments/other.toml"), "{after}");

    // A single run named like a sweep, and a sweep named like a single run: one
    // folder cannot hold both, --force or not.
    let output = exe(d, &run_args("out", &SWEEP));
    assert!(output.status.success(), "{}", stderr(&output));
    let index = d.join("out/quick-sweep/sweep.json");
    let before = std::fs::read(&index).unwrap();
    for force in [false, true] {
        let mut plain = run_args("out", &["--set", "name=quick-sweep"]);
        let mut sweep = run_args("out", &[&SWEEP[2..], &["--set", "name=quick"]].concat());
        if force {
            plain.push("--force".into());
            sweep.push("--force".into());
        }
        for (args, expected) in [
            (plain, "out/quick-sweep: holds the points of a sweep"),
            (sweep, "out/quick: holds the results of a single run"),
        ] {
            let refused = exe(d, &args);
            let message = stderr(&refused);
            assert_eq!(refused.status.code(), Some(1), "{message}");
            assert!(message.contains(expected), "{expected}: {message}");
            assert!(message.contains("experiments/quick.toml"), "{message}");
        }
    }
    assert!(
        std::fs::read(&index).unwrap() == before,
        "the sweep changed"
    );
    assert!(!d.join("out/quick-sweep/manifest.json").exists());
    assert!(!d.join("out/quick/monte_carlo_runs=2").exists());
}

/// A project copied whole, its specs and results together, keeps its folders' owners:
/// the manifest records the spec file by its path from the output folder, so the
/// copy's run of the same spec, edited, replaces its folder.
#[test]
fn a_project_copied_whole_keeps_its_folders_owners() {
    let project = project(false);
    let d = project.path();
    let output = exe(d, &run_args("out", &[]));
    assert!(output.status.success(), "{}", stderr(&output));
    let manifest = std::fs::read_to_string(d.join("out/quick/manifest.json")).unwrap();
    assert!(
        manifest.contains(r#""spec_file": "../experiments/quick.toml""#),
        "{manifest}"
    );
    let copy = tempfile::tempdir().unwrap();
    let status = Command::new("cp")
        .args(["-a", &format!("{}/.", d.display())])
        .arg(copy.path())
        .status()
        .unwrap();
    assert!(status.success());
    let edited = exe(copy.path(), &run_args("out", &OTHER));
    assert!(edited.status.success(), "{}", stderr(&edited));
    assert!(
        stderr(&edited).contains("results written"),
        "{}",
        stderr(&edited)
    );
}

/// Two runs of different spec files with one `name`, started together: one writes the
/// folder, the other is refused with both specs named, whichever comes first.
#[test]
fn two_specs_with_one_name_at_once_write_one_folder_and_refuse_the_other() {
    let project = project(false);
    let d = project.path();
    std::fs::copy(d.join(SPEC), d.join("experiments/other.toml")).unwrap();
    let both = [
        spawn(d, &run_args("out", &[])),
        spawn(d, &run_of("experiments/other.toml", "out", &OTHER)),
    ]
    .map(|child| child.wait_with_output().unwrap());
    let ok: Vec<&Output> = both.iter().filter(|o| o.status.success()).collect();
    let refused: Vec<&Output> = both.iter().filter(|o| !o.status.success()).collect();
    assert_eq!(
        (ok.len(), refused.len()),
        (1, 1),
        "{}\n{}",
        stderr(&both[0]),
        stderr(&both[1])
    );
    let message = stderr(refused[0]);
    for part in [
        "out/quick",
        "experiments/quick.toml",
        "experiments/other.toml",
    ] {
        assert!(message.contains(part), "{part}: {message}");
    }
    assert!(!message.contains("results written"), "{message}");
}

// ---------------------------------------------------------------- tables edited by hand

/// `table` of `folder` rewritten, a valid Parquet file of the same schema, with every
/// value of `column` set to `value`.
fn edit_table(folder: &Path, table: &str, column: &str, value: f64) {
    use arrow_array::{ArrayRef, Float64Array};
    let path = folder.join(table);
    let batch = read_parquet(&path);
    let columns: Vec<ArrayRef> = batch
        .schema()
        .fields()
        .iter()
        .zip(batch.columns())
        .map(|(field, array)| match field.name() == column {
            true => std::sync::Arc::new(Float64Array::from(vec![value; array.len()])) as ArrayRef,
            false => array.clone(),
        })
        .collect();
    let edited = RecordBatch::try_new(batch.schema(), columns).unwrap();
    let mut bytes = Vec::new();
    let mut writer =
        parquet::arrow::ArrowWriter::try_new(&mut bytes, edited.schema(), None).unwrap();
    writer.write(&edited).unwrap();
    writer.close().unwrap();
    std::fs::write(&path, bytes).unwrap();
}

/// `plot` of a folder whose table was edited (to NaN, to infinity) after the run is
/// refused with exit code 1, naming the table: the manifest holds each table's SHA-256.
#[test]
fn plot_refuses_a_table_whose_digest_is_not_the_manifests() {
    let project = project(false);
    let d = project.path();
    let output = exe(d, &run_args("out", &[]));
    assert!(output.status.success(), "{}", stderr(&output));
    let folder = d.join("out/quick");
    let saved = std::fs::read(folder.join("calibration.parquet")).unwrap();
    let plot = ["plot", "out/quick", "--out", "figures"];
    assert!(dcnet(d, &plot).status.success());
    for value in [f64::NAN, f64::INFINITY] {
        edit_table(&folder, "calibration.parquet", "rmse_cm_s", value);
        let refused = dcnet(d, &plot);
        let message = stderr(&refused);
        assert_eq!(refused.status.code(), Some(1), "{value}: {message}");
        assert!(
            message.contains("out/quick/calibration.parquet: its SHA-256 is"),
            "{message}"
        );
        assert!(message.contains("manifest.json"), "{message}");
    }
    std::fs::write(folder.join("calibration.parquet"), saved).unwrap();
    edit_table(
        &folder,
        "evaluation.parquet",
        "rmse_cm_s",
        f64::NEG_INFINITY,
    );
    let message = stderr(&dcnet(d, &plot));
    assert!(
        message.contains("out/quick/evaluation.parquet"),
        "{message}"
    );
}

// ---------------------------------------------------------------- what stands in the way

/// A file where the results folder or the cache goes, and a folder where a lock file
/// goes, are refused with the path that is in the way, never "File exists"; the
/// results folder is checked before anything is computed.
#[test]
fn a_file_or_folder_in_the_way_is_named() {
    let project = project(false);
    let d = project.path();
    std::fs::create_dir(d.join("out")).unwrap();
    std::fs::write(d.join("out/quick"), "").unwrap();
    let refused = exe(d, &run_args("out", &[]));
    let message = stderr(&refused);
    assert_eq!(refused.status.code(), Some(1), "{message}");
    assert!(
        message.contains("out/quick: is a file, where the results folder goes"),
        "{message}"
    );
    assert!(!message.contains("trained"), "{message}");
    assert!(!message.contains("os error 17"), "{message}");
    std::fs::remove_file(d.join("out/quick")).unwrap();

    std::fs::write(d.join("out/.cache"), "").unwrap();
    let message = stderr(&exe(d, &run_args("out", &[])));
    assert!(
        message.contains("out/.cache is a file, where a folder is needed"),
        "{message}"
    );
    std::fs::remove_file(d.join("out/.cache")).unwrap();

    // The first lock a run takes is its first training's, named by its key.
    let plan = stdout(&exe(d, &plan_args("out", &[])));
    let key = plan
        .lines()
        .find(|l| l.starts_with("| train DCNet"))
        .map(|l| l.split('|').nth(2).unwrap().trim().to_string())
        .expect(&plan);
    let lock = format!("out/.cache/locks/{key}.lock");
    std::fs::create_dir_all(d.join(&lock)).unwrap();
    let message = stderr(&exe(d, &run_args("out", &[])));
    assert!(message.contains(&lock), "{message}");
}

/// `DCNET_LOG_EVERY` that is not a number is refused naming the variable, not the
/// `--log-every` flag the user never typed.
#[test]
fn a_bad_log_every_variable_is_named() {
    let project = project(false);
    let output = Command::new(env!("CARGO_BIN_EXE_dcnet-exp"))
        .current_dir(project.path())
        .args(["validate", SPEC])
        .env("DCNET_LOG_EVERY", "abc")
        .output()
        .unwrap();
    let message = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{message}");
    assert!(message.contains("DCNET_LOG_EVERY=abc"), "{message}");
    assert!(!message.contains("'--log-every"), "{message}");
}

/// `RAYON_NUM_THREADS` that is not a count of threads is refused naming the variable,
/// where rayon would ignore it and use every core; a typed `--threads` wins; 0, every
/// core, is said.
#[test]
fn a_bad_thread_count_variable_is_named() {
    let project = project(false);
    let with_threads = |value: &str, args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_dcnet-exp"))
            .current_dir(project.path())
            .args(args)
            .env("RAYON_NUM_THREADS", value)
            .output()
            .unwrap()
    };
    let validate = |args: &[&str]| with_threads("abc", args);
    let every_core = with_threads("0", &["validate", SPEC]);
    assert!(every_core.status.success(), "{}", stderr(&every_core));
    assert!(
        stderr(&every_core).contains("RAYON_NUM_THREADS=0: every core, "),
        "{}",
        stderr(&every_core)
    );
    let output = validate(&["validate", SPEC]);
    let message = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{message}");
    assert!(
        message.contains("RAYON_NUM_THREADS=abc: not a number of threads"),
        "{message}"
    );
    let typed = validate(&["--threads", "1", "validate", SPEC]);
    assert!(typed.status.success(), "{}", stderr(&typed));
}

/// A `--plots` folder that cannot be written (under a file, or read-only) is refused
/// before the run, exit 1, naming the flag; the run once found it only after computing
/// everything.
#[test]
fn an_unwritable_plots_folder_is_refused_before_the_run() {
    let project = project(false);
    let d = project.path();
    std::fs::write(d.join("a-file"), "").unwrap();
    let mut args: Vec<String> = ["run", SPEC, "--out", "results", "--plots", "a-file/plots"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    args.extend(SMALL.iter().map(|s| s.to_string()));
    let under_a_file = exe(d, &args);
    let message = stderr(&under_a_file);
    assert_eq!(under_a_file.status.code(), Some(1), "{message}");
    assert!(
        message.contains("--plots a-file/plots: a-file is not a folder; give a folder that can be written, or --no-plots"),
        "{message}"
    );
    assert!(!d.join("results").exists(), "{message}");
}
