//! `[learned]` end to end on synthetic recordings of a known installation: DCNets trained
//! fold by fold on simulated installations and on the vehicle's own DVL, scored inside
//! their folds beside the model-based fit, stored in the cache, listed by `plan`,
//! resumed from their checkpoints after a kill, refused when the spec is wrong.

use crate::common;

use common::installed::{INSTALLED, write_installed, write_study_spec};
use common::{dcnet, floats, forge_sealed, read_parquet, spawn, stderr, stdout, strings, tree};
use std::path::Path;
use std::time::{Duration, Instant};

/// Four turning trajectories of [`INSTALLED`], a lever arm and time offset grid around
/// but not on it, two folds.
fn learned_spec(d: &Path, extra: &str) {
    write_installed(&d.join("data/syn"), 4, &[], INSTALLED, 21);
    let learned = format!(
        r#"
[[calibration.models]]
name = "lever+offset"
terms = ["lever_arm", "time_offset"]

[learned]
terms = ["lever_arm", "time_offset"]
folds = 2
window_samples = 10
stride_samples = 2
seed = 5

[learned.simulation]
lever_arm_x_m = [-2.5, -1.5, -0.5]
lever_arm_y_m = [0.0]
lever_arm_z_m = [0.4]
time_offset_s = [0.0, 1.0]
misalignment_z_deg = [0.0]
scale_pct = [1.0]
bias_cm_s = [0.0]

[learned.model]
conv_channels = 8
fc_widths = [32, 16, 8]

[learned.training]
epochs = 12
learning_rate = 0.002
{extra}"#
    );
    write_study_spec(d, "syn", "syn", 4, &learned);
}

/// Replaces each `(from, to)` in the spec `learned_spec` wrote; `from` must be there.
fn edit_spec(d: &Path, edits: &[(&str, &str)]) {
    let spec = d.join("experiments/syn.toml");
    let mut text = std::fs::read_to_string(&spec).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "the spec has no {from:?}");
        text = text.replace(from, to);
    }
    std::fs::write(&spec, text).unwrap();
}

fn fold_of(trajectory: &str) -> usize {
    // Round robin in spec order: S1, S3 | S2, S4.
    (trajectory[1..].parse::<usize>().unwrap() - 1) % 2
}

#[test]
fn learned_models_are_scored_inside_their_folds_and_come_back_from_the_cache() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    learned_spec(d, "replicates = 2\n");
    let output = dcnet(d, &["run", "experiments/syn.toml"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let log = stderr(&output);
    for source in ["simulated", "vehicle"] {
        for fold in [1, 2] {
            assert!(
                log.contains(&format!("DCNet installation {source} fold {fold}:")),
                "{log}"
            );
            assert!(
                log.contains(&format!(
                    "DCNet installation {source} fold {fold} replicate 2:"
                )),
                "{log}"
            );
        }
    }
    let folder = d.join("results/syn");
    assert!(
        d.join("plots/syn/installation_folds.png").is_file(),
        "{log}"
    );

    // No leak: a learned method is scored only on trajectories of its calibration's fold.
    let heldout = read_parquet(&folder.join("heldout.parquet"));
    let (methods, calibrations, scored) = (
        strings(&heldout, "method"),
        strings(&heldout, "calibration"),
        strings(&heldout, "scored"),
    );
    let mut learned_rows = 0;
    for i in 0..heldout.num_rows() {
        let method = methods[i].as_deref().unwrap();
        if method.starts_with("DCNet trained on ") {
            learned_rows += 1;
            let (c, s) = (
                calibrations[i].as_deref().unwrap(),
                scored[i].as_deref().unwrap(),
            );
            assert_eq!(
                fold_of(c),
                fold_of(s),
                "{method} calibrated on {c} scored on {s}"
            );
        }
    }
    // 2 sources × 2 replicates × 4 calibrations × 2 windows × 1 other trajectory in the
    // fold.
    assert_eq!(learned_rows, 32);

    // The fold table: every method on the same pairs, fold by fold and over all; the
    // simulation-trained model removes most of the installation's error.
    let folds = read_parquet(&folder.join("folds.parquet"));
    let (fold, method, window, rmse) = (
        strings(&folds, "fold"),
        strings(&folds, "method"),
        floats(&folds, "window_s"),
        floats(&folds, "rmse_cm_s"),
    );
    let cell = |f: &str, m: &str| {
        (0..folds.num_rows())
            .find(|&i| {
                fold[i].as_deref() == Some(f)
                    && method[i].as_deref() == Some(m)
                    && window[i] == Some(400.0)
            })
            .map(|i| rmse[i].unwrap())
            .unwrap_or_else(|| panic!("no row for fold {f}, {m}"))
    };
    for f in ["1", "2", "all"] {
        cell(f, "no calibration");
        cell(f, "installation lever+offset");
    }
    let (none, simulated) = (
        cell("all", "no calibration"),
        cell("all", "DCNet trained on simulation"),
    );
    // The second replicate is another model, from other seeds.
    assert_ne!(
        simulated,
        cell("all", "DCNet trained on simulation, replicate 2")
    );
    assert!(
        simulated < 0.5 * none,
        "trained on simulation {simulated:.2} cm/s against {none:.2} uncalibrated"
    );

    // Its lever arm lands near the installed one.
    let terms = read_parquet(&folder.join("terms.parquet"));
    let (term_method, term, value, term_window) = (
        strings(&terms, "method"),
        strings(&terms, "term"),
        floats(&terms, "value"),
        floats(&terms, "window_s"),
    );
    let lever_x: Vec<f64> = (0..terms.num_rows())
        .filter(|&i| {
            term_method[i].as_deref() == Some("DCNet trained on simulation")
                && term[i].as_deref() == Some("lever_arm_x_m")
                && term_window[i] == Some(400.0)
        })
        .map(|i| value[i].unwrap())
        .collect();
    assert_eq!(lever_x.len(), 4);
    for x in &lever_x {
        assert!(
            (x - INSTALLED.lever_arm_m[0]).abs() < 0.4,
            "lever arm x {x}, installed -1.9"
        );
    }
    let report = std::fs::read_to_string(folder.join("report.md")).unwrap();
    assert!(
        report.contains("Inside the folds: learned against model-based"),
        "{report}"
    );
    assert!(report.contains("Learned terms against the fit of every trajectory"));

    // `--force` computes every calibration again, but the models come from the cache:
    // nothing is trained and the tables are the same bytes.
    let first = std::fs::read(folder.join("folds.parquet")).unwrap();
    let again = dcnet(d, &["run", "experiments/syn.toml", "--no-plots", "--force"]);
    assert!(again.status.success(), "{}", stderr(&again));
    assert!(
        !stderr(&again).contains("DCNet installation"),
        "{}",
        stderr(&again)
    );
    assert_eq!(std::fs::read(folder.join("folds.parquet")).unwrap(), first);

    // A third replicate trains only its own models: the first two are the same
    // whatever the count.
    let third = dcnet(
        d,
        &[
            "run",
            "experiments/syn.toml",
            "--no-plots",
            "--set",
            "learned.training.replicates=3",
        ],
    );
    assert!(third.status.success(), "{}", stderr(&third));
    let log = stderr(&third);
    assert_eq!(log.matches("DCNet installation").count(), 4, "{log}");
    assert!(log.contains("simulated fold 1 replicate 3:"), "{log}");
}

/// With `[calibration.dive]`, the learned models' rows with the clock re-found are
/// scored inside their folds too, and the joint fits (calibrated on every other
/// trajectory, inside no fold) stay out of the fold table.
#[test]
fn the_clock_found_again_keeps_the_learned_rows_inside_their_folds() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    learned_spec(d, "\n[calibration.dive]\nwindow_s = [60.0]\n");
    let output = dcnet(d, &["run", "experiments/syn.toml", "--no-plots"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let folder = d.join("results/syn");
    let heldout = read_parquet(&folder.join("heldout.parquet"));
    let (methods, calibrations, scored) = (
        strings(&heldout, "method"),
        strings(&heldout, "calibration"),
        strings(&heldout, "scored"),
    );
    let (mut refound, mut joint) = (0, 0);
    for i in 0..heldout.num_rows() {
        let method = methods[i].as_deref().unwrap();
        let (c, s) = (
            calibrations[i].as_deref().unwrap(),
            scored[i].as_deref().unwrap(),
        );
        if method.starts_with("DCNet trained on ") && method.ends_with(", clock re-found in 60 s") {
            refound += 1;
            assert_eq!(
                fold_of(c),
                fold_of(s),
                "{method} calibrated on {c} scored on {s}"
            );
        }
        if method.contains(", joint") {
            joint += 1;
            assert_eq!(c, format!("all but {s}"), "{method}");
        }
    }
    // 2 sources × 4 calibrations × 2 windows × 1 other trajectory in the fold.
    assert_eq!(refound, 16);
    // The two models' joint fits, carried and re-found, × 4 left out × 2 windows.
    assert_eq!(joint, 32);
    let folds = read_parquet(&folder.join("folds.parquet"));
    assert!(
        strings(&folds, "method")
            .iter()
            .all(|m| !m.as_deref().unwrap().contains(", joint"))
    );
}

#[test]
fn a_wrong_learned_table_is_refused_naming_its_keys() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    learned_spec(d, "");
    edit_spec(
        d,
        &[
            ("folds = 2", "folds = 3\nsources = [\"simulated\", \"sky\"]"),
            ("lever_arm_y_m = [0.0]", "lever_arm_y_m = []"),
            ("lever_arm_z_m = [0.4]", "lever_arm_z_m = [1e300]"),
            ("epochs = 12", "epochs = 0"),
        ],
    );
    let output = dcnet(d, &["run", "experiments/syn.toml"]);
    assert!(!output.status.success(), "{}", stderr(&output));
    let message = stderr(&output);
    assert!(
        message.contains("learned.simulation.lever_arm_z_m[0]: 1e300 is beyond ±100 m"),
        "{message}"
    );
    // The learned model's one learning rate, refused once at its own key, where it was
    // refused once per error model of the paper.
    let rate = dcnet(
        d,
        &[
            "validate",
            "experiments/syn.toml",
            "--set",
            "learned.training.learning_rate=0",
        ],
    );
    let said = stderr(&rate);
    assert_eq!(said.matches("learning_rate").count(), 2, "{said}");
    assert!(
        said.contains("learned.training.learning_rate: 0 must be a positive number"),
        "{said}"
    );
    for key in [
        "learned.folds",
        "learned.sources[1]",
        "learned.simulation.lever_arm_y_m",
        "learned.training.epochs",
    ] {
        assert!(message.contains(key), "{key} not named: {message}");
    }
    assert!(!d.join("results").exists());
}

/// A sweep over the simulated grid: each point a study of its own with its fold table,
/// beside the sweep's table and index.
#[test]
fn a_sweep_over_the_simulated_grid_writes_each_points_fold_table() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    learned_spec(
        d,
        "\n[sweep.values]\n\"learned.simulation.time_offset_s\" = [[0.0, 1.0], [0.0, 0.5, 1.0]]\n",
    );
    let output = dcnet(d, &["run", "experiments/syn.toml", "--no-plots"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let folder = d.join("results/syn");
    assert!(folder.join("sweep.json").is_file());
    let table = read_parquet(&folder.join("sweep.parquet"));
    let methods = strings(&table, "method");
    assert!(
        methods
            .iter()
            .any(|m| m.as_deref() == Some("DCNet trained on simulation"))
    );
    let points: Vec<_> = std::fs::read_dir(&folder)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_dir())
        .collect();
    assert_eq!(points.len(), 2);
    for point in points {
        assert!(
            point.path().join("folds.parquet").is_file(),
            "{:?}",
            point.path()
        );
    }
}

/// Shards of a study with `[learned]`, then `collect`, give the tables of one whole run:
/// the models the first shard trains, the second loads.
#[test]
fn shards_of_a_learned_study_collect_to_the_bytes_of_one_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    learned_spec(d, "");
    let spec = "experiments/syn.toml";
    let run = |args: &[&str]| {
        let output = dcnet(d, args);
        assert!(output.status.success(), "{args:?}: {}", stderr(&output));
        stderr(&output)
    };
    run(&["run", spec, "--out", "whole", "--no-plots"]);
    let first = run(&["run", spec, "--out", "split", "--shard", "0/2"]);
    assert!(
        first.contains("DCNet installation simulated fold 2:"),
        "{first}"
    );
    let second = run(&["run", spec, "--out", "split", "--shard", "1/2"]);
    assert!(!second.contains("DCNet installation"), "{second}");
    run(&["collect", spec, "--out", "split", "--no-plots"]);
    for table in [
        "heldout.parquet",
        "terms.parquet",
        "folds.parquet",
        "report.md",
    ] {
        assert_eq!(
            std::fs::read(d.join("whole/syn").join(table)).unwrap(),
            std::fs::read(d.join("split/syn").join(table)).unwrap(),
            "{table}"
        );
    }
}

/// A simulated time offset beyond the window's margin of reference is refused, naming
/// the key, before any model is trained.
#[test]
fn a_simulated_time_offset_beyond_the_reference_margin_is_refused_before_training() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    learned_spec(d, "");
    edit_spec(
        d,
        &[("time_offset_s = [0.0, 1.0]", "time_offset_s = [0.0, 4.0]")],
    );
    let output = dcnet(d, &["run", "experiments/syn.toml", "--no-plots"]);
    let message = stderr(&output);
    assert!(!output.status.success(), "{message}");
    assert!(
        message.contains("learned.simulation.time_offset_s: 4 s is beyond"),
        "{message}"
    );
    assert!(!message.contains("DCNet installation"), "{message}");
    assert!(!d.join("results/syn").exists());
    // `validate` refuses it too, where it said ok.
    let validated = dcnet(d, &["validate", "experiments/syn.toml"]);
    assert_eq!(validated.status.code(), Some(1), "{}", stderr(&validated));
    assert!(
        stderr(&validated).contains("learned.simulation.time_offset_s: 4 s is beyond"),
        "{}",
        stderr(&validated)
    );
}

/// A window, with its margins, longer than a trajectory: `validate` and `run` refuse
/// it at `learned.window_samples`, naming the trajectory, where `run` blamed
/// `validation_fraction`.
#[test]
fn a_learned_window_longer_than_a_trajectory_is_refused_at_its_key() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    learned_spec(d, "");
    edit_spec(d, &[("window_samples = 10", "window_samples = 1000")]);
    for command in ["validate", "run"] {
        let output = dcnet(
            d,
            &[command, "experiments/syn.toml", "--no-plots"][..2 + usize::from(command == "run")],
        );
        let message = stderr(&output);
        assert_eq!(output.status.code(), Some(1), "{command}: {message}");
        assert!(
            message.contains("learned.window_samples: 1000 samples, with the 3 of margin each side, are longer than trajectory \"S1\"'s 400"),
            "{command}: {message}"
        );
    }
}

/// The weights of every stored `[learned]` model under `out`, by file name.
fn learned_weights(out: &Path) -> Vec<(String, Vec<u8>)> {
    tree(&out.join(".cache/learned"))
        .into_iter()
        .filter(|(rel, _)| rel.ends_with(".bin") && !rel.contains(".checkpoint/"))
        .map(|(rel, path)| (rel, std::fs::read(path).unwrap()))
        .collect()
}

/// A run killed with SIGKILL once a learned model has written a checkpoint resumes it
/// (`plan` lists it as resumable) and ends with the models and tables of a run never
/// interrupted, byte for byte; `plan` lists every model fold by fold, done.
#[test]
fn a_learned_training_killed_mid_way_resumes_to_the_bytes_of_an_uninterrupted_one() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    learned_spec(d, "checkpoint_every_epochs = 1\n");
    let spec = "experiments/syn.toml";
    let whole = dcnet(d, &["run", spec, "--out", "whole", "--no-plots"]);
    assert!(whole.status.success(), "{}", stderr(&whole));

    let killed = d.join("killed");
    let checkpointed = || {
        tree(&killed.join(".cache/learned"))
            .keys()
            .any(|rel| rel.ends_with(".checkpoint/state.json"))
    };
    let plan = || {
        let output = dcnet(d, &["plan", spec, "--out", "killed"]);
        assert!(output.status.success(), "{}", stderr(&output));
        stdout(&output)
    };
    let mut caught = None;
    for _ in 0..30 {
        let _ = std::fs::remove_dir_all(&killed);
        let mut child = spawn(d, &["run", spec, "--out", "killed", "--no-plots"]);
        let started = Instant::now();
        while !checkpointed()
            && child.try_wait().unwrap().is_none()
            && started.elapsed() < Duration::from_secs(60)
        {
            std::thread::sleep(Duration::from_millis(1));
        }
        let _ = child.kill();
        child.wait().unwrap();
        let planned = plan();
        if planned.contains("to do (resumes after epoch") && !planned.contains("damaged") {
            caught = Some(planned);
            break;
        }
    }
    let planned = caught.expect("no run was caught with a learned checkpoint written");
    assert!(!killed.join("syn").exists(), "{planned}");

    let resumed = dcnet(d, &["run", spec, "--out", "killed", "--no-plots"]);
    let log = stderr(&resumed);
    assert!(resumed.status.success(), "{log}");
    assert!(log.contains(", resumed after epoch "), "{log}");
    let (ours, theirs) = (learned_weights(&killed), learned_weights(&d.join("whole")));
    assert_eq!(ours.len(), 4, "{ours:?}");
    assert!(
        ours == theirs,
        "the resumed models differ from the uninterrupted ones"
    );
    for table in ["heldout.parquet", "terms.parquet", "folds.parquet"] {
        assert_eq!(
            std::fs::read(killed.join("syn").join(table)).unwrap(),
            std::fs::read(d.join("whole/syn").join(table)).unwrap(),
            "{table}"
        );
    }
    assert!(
        !tree(&killed.join(".cache/learned"))
            .keys()
            .any(|rel| rel.contains(".checkpoint/")),
        "a checkpoint is left after the run ended"
    );

    // `plan` lists each model fold by fold, done.
    let planned = plan();
    let models: Vec<&str> = planned
        .lines()
        .filter(|l| l.contains("train DCNet installation"))
        .collect();
    let labels: Vec<String> = models
        .iter()
        .map(|l| l.split('|').nth(1).unwrap().trim().to_string())
        .collect();
    assert_eq!(
        labels,
        [
            "train DCNet installation simulated fold 1",
            "train DCNet installation vehicle fold 1",
            "train DCNet installation simulated fold 2",
            "train DCNet installation vehicle fold 2",
        ],
        "{planned}"
    );
    assert!(models.iter().all(|l| l.contains("| done")), "{planned}");
    assert!(
        planned.contains("syn: 4 learned models, 0 to do; 4 calibrations, 0 to do"),
        "{planned}"
    );
}

/// A learned model is trained under its claim, as the paper's are: while another
/// process holds it (here the test, holding its lock file), a run waits for it, then,
/// the holder gone with the model untrained, trains it itself.
#[test]
fn a_learned_model_another_process_holds_is_waited_for_then_trained() {
    use std::io::{BufRead, BufReader};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    learned_spec(d, "");
    let spec = "experiments/syn.toml";
    let planned = dcnet(d, &["plan", spec]);
    assert!(planned.status.success(), "{}", stderr(&planned));
    let planned = stdout(&planned);
    // | train DCNet installation vehicle fold 2 | <key, 16 characters> | to do |
    let held = planned
        .lines()
        .find(|l| l.contains("train DCNet installation vehicle fold 2"))
        .and_then(|l| l.split('|').nth(2))
        .map(|key| key.trim().to_string())
        .unwrap_or_else(|| panic!("plan lists no vehicle fold 2 model: {planned}"));
    let locks = d.join("results/.cache/locks");
    std::fs::create_dir_all(&locks).unwrap();
    let lock = std::fs::File::create(locks.join(format!("{held}.lock"))).unwrap();
    lock.lock().unwrap();

    let mut child = spawn(d, &["run", spec, "--no-plots"]);
    let (lines, received) = std::sync::mpsc::channel();
    let stderr_pipe = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        for line in BufReader::new(stderr_pipe).lines().map_while(Result::ok) {
            let _ = lines.send(line);
        }
    });
    let mut log = Vec::new();
    let waited = loop {
        match received.recv_timeout(Duration::from_secs(300)) {
            Ok(line) => {
                let waiting = line.contains("waiting for another process");
                log.push(line);
                if waiting {
                    break true;
                }
            }
            Err(_) => break false,
        }
    };
    drop(lock);
    let status = child.wait().unwrap();
    reader.join().unwrap();
    log.extend(received.try_iter());
    let log = log.join("\n");
    assert!(waited, "the run did not wait for the held model: {log}");
    assert!(status.success(), "{log}");
    assert!(
        log.contains(
            "waiting for another process computing 1 of these tasks (DCNet installation vehicle fold 2)"
        ),
        "{log}"
    );
    assert!(
        log.contains("the other process did 0 of them; 1 left to do here"),
        "{log}"
    );
    assert!(
        log.contains("DCNet installation vehicle fold 2:"),
        "the run trained the model it waited for: {log}"
    );
    assert_eq!(learned_weights(&d.join("results")).len(), 4);
}

/// A simulated grid too large for memory aborted `run` with a failed allocation where
/// `validate` said ok: both refuse it at its key, saying how much it needs, and
/// `validate` says what a grid that fits needs.
#[test]
fn a_learned_grid_beyond_memory_is_refused_by_validate_and_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    learned_spec(d, "");
    let spec = "experiments/syn.toml";
    let fits = dcnet(d, &["validate", spec]);
    assert!(fits.status.success(), "{}", stderr(&fits));
    assert!(
        stdout(&fits).contains("[learned] training needs at most about "),
        "{}",
        stdout(&fits)
    );
    let values: Vec<String> = (0..40).map(|i| format!("{:.2}", 0.01 * i as f64)).collect();
    let list = format!("[{}]", values.join(", "));
    let keys = [
        "lever_arm_x_m",
        "lever_arm_y_m",
        "lever_arm_z_m",
        "time_offset_s",
        "misalignment_z_deg",
        "scale_pct",
        "bias_cm_s",
    ];
    let sets: Vec<String> = keys
        .iter()
        .map(|key| format!("learned.simulation.{key}={list}"))
        .collect();
    for command in ["validate", "run"] {
        let mut args = vec![command, spec];
        for set in &sets {
            args.extend(["--set", set.as_str()]);
        }
        let output = dcnet(d, &args);
        assert_eq!(
            output.status.code(),
            Some(1),
            "{command}: {}",
            stderr(&output)
        );
        let text = stderr(&output);
        assert!(
            text.contains("learned.simulation.") && text.contains("of memory and this machine has"),
            "{command}: {text}"
        );
    }
    assert!(!d.join("results/syn").exists());
}

/// With no validation windows the training loss chooses the best epoch, and the line
/// that reports a model says so, where it called it the validation loss.
#[test]
fn without_validation_windows_the_training_loss_is_named_as_such() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    learned_spec(d, "");
    edit_spec(
        d,
        &[
            ("seed = 5", "seed = 5\nvalidation_fraction = 0.0"),
            ("epochs = 12", "epochs = 2"),
        ],
    );
    let output = dcnet(d, &["run", "experiments/syn.toml", "--no-plots"]);
    let log = stderr(&output);
    assert!(output.status.success(), "{log}");
    let lines: Vec<&str> = log
        .lines()
        .filter(|l| l.starts_with("DCNet installation"))
        .collect();
    assert_eq!(lines.len(), 4, "{log}");
    assert!(
        lines
            .iter()
            .all(|l| l.contains("(training loss ") && !l.contains("validation loss")),
        "{log}"
    );
}

/// A stored learned model whose seals hold but whose history is no model's (forged, or
/// another build's) stopped every run, naming its path twice: it is set aside, said so,
/// and trained again, to the bytes of the model it replaced.
#[test]
fn a_sealed_model_that_is_no_model_is_set_aside_and_trained_again() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    learned_spec(d, "");
    edit_spec(d, &[("epochs = 12", "epochs = 2")]);
    let first = dcnet(d, &["run", "experiments/syn.toml", "--no-plots"]);
    assert!(first.status.success(), "{}", stderr(&first));
    let weights = learned_weights(&d.join("results"));
    let history = tree(&d.join("results/.cache/learned"))
        .into_iter()
        .map(|(_, path)| path)
        .find(|path| path.extension().is_some_and(|e| e == "json"))
        .expect("a stored history");
    forge_sealed(&history, b"{\"not\": \"a model\"}");
    let again = dcnet(d, &["run", "experiments/syn.toml", "--no-plots", "--force"]);
    let log = stderr(&again);
    assert!(again.status.success(), "{log}");
    assert!(
        log.contains("sealed, but not a model of this version"),
        "{log}"
    );
    assert!(log.contains("and trained again"), "{log}");
    assert_eq!(learned_weights(&d.join("results")), weights);
}
