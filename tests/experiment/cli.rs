//! The command line as a user meets it: quick runs, thread-count independence,
//! overrides, bad specs, and `data fetch` against a local server.

use crate::common;
use common::*;
use std::path::Path;

const TABLES: [&str; 3] = [
    "monte_carlo.parquet",
    "calibration.parquet",
    "evaluation.parquet",
];

#[test]
fn one_and_two_threads_write_identical_results() {
    let project = project(false);
    for threads in ["1", "2"] {
        let out = format!("out{threads}");
        let output = dcnet(
            project.path(),
            &[
                "--threads",
                threads,
                "run",
                "experiments/quick.toml",
                "--out",
                &out,
            ],
        );
        assert!(output.status.success(), "{}", stderr(&output));
    }
    let models: Vec<String> = std::fs::read_dir(project.path().join("out1/.cache/models"))
        .unwrap()
        .map(|e| format!(".cache/models/{}", e.unwrap().file_name().to_string_lossy()))
        .filter(|name| name.ends_with(".bin"))
        .collect();
    assert_eq!(models.len(), 5, "{models:?}");
    let tables = TABLES.iter().map(|t| format!("quick/{t}"));
    for file in tables.chain(models) {
        let one = std::fs::read(project.path().join("out1").join(&file)).unwrap();
        let two = std::fs::read(project.path().join("out2").join(&file)).unwrap();
        assert!(one == two, "{file} differs between 1 and 2 threads");
    }
    // training.parquet also holds wall times; its losses must agree.
    let losses = |out: &str| {
        let batch = read_parquet(&project.path().join(out).join("quick/training.parquet"));
        (
            floats(&batch, "train_loss"),
            floats(&batch, "validation_loss"),
        )
    };
    assert_eq!(losses("out1"), losses("out2"));
    let spec_one = std::fs::read_to_string(project.path().join("out1/quick/spec.toml")).unwrap();
    assert!(spec_one.contains("monte_carlo_runs = 20"));
}

#[test]
fn quick_run_prints_and_stores_both_tables() {
    let project = project(false);
    let output = dcnet(
        project.path(),
        &[
            "run",
            "experiments/quick.toml",
            "--set",
            "calibration.monte_carlo_runs=3",
        ],
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    assert!(
        text.contains("Calibration on SCal: RMSE in cm/s at T_conv, mean ± std over 3 runs"),
        "{text}"
    );
    assert!(text.contains("| DVL2 | floor (true terms)  "), "{text}");
    let results = project.path().join("results/quick");
    let runs = read_parquet(&results.join("monte_carlo.parquet"));
    // 3 runs × 2 DVLs × 19 estimators (baseline, 5 least squares, beam-model WLS, 5
    // Kalman filters, the beam-model one, 5 DCNet, floor) × (5 windows + 2 test
    // trajectories), and the held-out curves: every second up to 100 s for the 13
    // closed-form methods and filters, the 5 windows for each DCNet, none for the
    // floor; the bound is computed.
    assert_eq!(runs.num_rows(), 3 * 2 * (19 * (5 + 2) + 13 * 100 + 5 * 5));
    // The tables add the bound's row to the 19 estimators' rows.
    let calibration = calibration_rows(&results);
    assert_eq!(calibration.len(), 2 * 20 * 5);
    assert_eq!(calibration.iter().filter(|r| r.selected).count(), 2 * 20);
    let evaluation = evaluation_rows(&results);
    assert_eq!(evaluation.len(), 2 * 20 * 2);
    // DCNet EM5 clearly beats the baseline on the low-noise DVL.
    for trajectory in ["S3", "S4"] {
        let em5 = evaluation
            .iter()
            .find(|r| {
                r.dvl == "DVL2"
                    && r.estimator == "dcnet"
                    && r.error_model.as_deref() == Some("EM5")
                    && r.at == trajectory
            })
            .unwrap();
        assert!(
            em5.improvement_pct.unwrap() > 40.0,
            "DCNet EM5 on {trajectory}: {em5:?}"
        );
    }
    let training = read_parquet(&results.join("training.parquet"));
    assert_eq!(training.num_rows(), 5 * 20, "5 models × 20 epochs");
    assert_eq!(
        bools(&training, "is_best").iter().filter(|b| **b).count(),
        5
    );
    // The improvement column is computed against the baseline row of the same cell.
    for row in &evaluation {
        let baseline = evaluation
            .iter()
            .find(|b| b.estimator == "baseline" && b.dvl == row.dvl && b.at == row.at)
            .unwrap();
        let expected = 100.0 * (baseline.rmse_cm_s - row.rmse_cm_s) / baseline.rmse_cm_s;
        assert!((row.improvement_pct.unwrap() - expected).abs() < 1e-9);
    }
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(results.join("manifest.json")).unwrap())
            .unwrap();
    assert_eq!(manifest["name"], "quick");
    assert_eq!(manifest["spec_sha256"].as_str().unwrap().len(), 64);
    assert!(manifest["threads"].as_u64().unwrap() >= 1);
    assert_eq!(manifest["backend"], "flex");
    let leftovers: Vec<_> = std::fs::read_dir(&results)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .filter(|n| n.to_string_lossy().starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

/// The lines of a run's stderr that say how each DCNet came to be, without its key, in
/// the order of the error models (trainings end in any order).
fn provenance(output: &std::process::Output) -> Vec<String> {
    let mut lines: Vec<String> = stderr(output)
        .lines()
        .filter(|l| l.starts_with("DCNet EM"))
        .map(|l| {
            let (model, rest) = l.split_once(':').unwrap();
            let model = model.split(' ').take(2).collect::<Vec<_>>().join(" ");
            format!("{model}:{}", rest.split(';').next().unwrap())
        })
        .collect();
    lines.sort();
    lines
}

/// Where stderr is not a terminal (a cluster job's log), each task logs a plain line
/// at most every `--log-every` seconds, with what it is doing, how far it is, its rate
/// and its ETA, and one line when it ends. By default (30 s) a run of seconds logs only
/// the ends.
#[test]
fn a_run_logged_to_a_file_says_how_far_each_task_is_and_when_it_ends() {
    let project = project(false);
    let small = [
        "--set",
        "training.epochs=3",
        "--set",
        "calibration.monte_carlo_runs=3",
    ];
    let by_default = stderr(&quick_run(project.path(), &small));
    assert!(!by_default.contains("/s, ETA"), "{by_default}");
    std::fs::remove_dir_all(project.path().join("results")).unwrap();

    let log = stderr(&quick_run(
        project.path(),
        &[&small[..], &["--log-every", "0"]].concat(),
    ));
    let lines: Vec<&str> = log.lines().collect();
    // "DCNet EM1 0123456789abcdef: epoch 2/3, batch loss 0.4321 (cm/s)², 3200/4752 samples,
    // 31000 samples/s, ETA 1s"
    for model in ["EM1", "EM2", "EM3", "EM4", "EM5"] {
        let task = format!("DCNet {model} ");
        let progress: Vec<usize> = (0..lines.len())
            .filter(|&i| lines[i].starts_with(&task) && lines[i].contains(" samples/s, ETA "))
            .collect();
        assert!(!progress.is_empty(), "no progress line of {model}:\n{log}");
        for &i in &progress {
            let (name, rest) = lines[i].split_once(": ").unwrap();
            assert_eq!(name.len(), task.len() + 16, "{}", lines[i]);
            assert!(rest.starts_with("epoch "), "{}", lines[i]);
            assert!(rest.contains("/3, batch loss "), "{}", lines[i]);
            assert!(rest.contains(" (cm/s)², "), "{}", lines[i]);
        }
        let last = lines[*progress.last().unwrap()];
        let done = last.split(", ").nth(2).unwrap();
        let (position, len) = done.trim_end_matches(" samples").split_once('/').unwrap();
        assert_eq!(position, len, "the last line is not at the end: {last}");
        assert!(last.contains("epoch 3/3"), "{last}");
        assert!(last.ends_with("ETA 0s"), "{last}");
        let ended = lines
            .iter()
            .position(|l| l.starts_with(&task) && l.contains(": trained; best validation loss"))
            .unwrap_or_else(|| panic!("no end line for {model}:\n{log}"));
        assert!(ended > *progress.last().unwrap(), "{log}");
    }
    for (task, doing, unit) in [
        ("dataset ", "", "12/12 combinations"),
        (
            "monte carlo quick DVL1: ",
            "calibration on SCal, ",
            "1/6 passes",
        ),
        (
            "monte carlo quick DVL2: ",
            "evaluation at T_conv, ",
            "6/6 passes",
        ),
    ] {
        assert!(
            lines
                .iter()
                .any(|l| l.starts_with(task) && l.contains(&format!("{doing}{unit}, "))),
            "no line of {task}{doing}{unit}:\n{log}"
        );
    }
    let ends = [
        "dataset ",
        "monte carlo quick DVL1: ",
        "monte carlo quick DVL2: ",
    ];
    for task in ends {
        let last = lines.iter().rposition(|l| l.starts_with(task)).unwrap();
        assert!(!lines[last].contains("ETA"), "{task} logs no end: {log}");
    }
}

#[test]
fn trained_models_are_reused_until_a_training_setting_changes() {
    let project = project(false);
    let run = |extra: &[&str]| {
        provenance(&quick_run(
            project.path(),
            &[&["--set", "training.epochs=3"], extra].concat(),
        ))
    };
    let models = ["EM1", "EM2", "EM3", "EM4", "EM5"];
    assert_eq!(run(&[]), models.map(|m| format!("DCNet {m}: trained")));
    // Stored models are not even loaded for training: no DCNet trains.
    assert!(run(&["--set", "calibration.monte_carlo_runs=4"]).is_empty());
    assert_eq!(
        run(&["--set", "training.learning_rate.EM5=2e-4"]),
        ["DCNet EM5: trained"]
    );
    assert_eq!(
        run(&["--set", "training.learning_rate.EM5=2e-4", "--force"]),
        models.map(|m| format!("DCNet {m}: trained"))
    );
}

#[test]
fn early_stopping_ends_training_records_why_and_keys_the_model() {
    let project = project(false);
    let run = |extra: &[&str]| {
        quick_run(
            project.path(),
            &[&["--set", "training.epochs=40"], extra].concat(),
        )
    };
    let patience = ["--set", "training.early_stopping.patience_epochs=2"];
    let output = run(&patience);
    assert!(
        stderr(&output).contains("stopped early"),
        "{}",
        stderr(&output)
    );
    let batch = read_parquet(&project.path().join("results/quick/training.parquet"));
    let models = strings(&batch, "error_model");
    let reasons = strings(&batch, "stop_reason");
    let validation = floats(&batch, "validation_loss");
    for model in ["EM1", "EM2", "EM3", "EM4", "EM5"] {
        let rows: Vec<usize> = (0..models.len())
            .filter(|&i| models[i].as_deref() == Some(model))
            .collect();
        let epochs = rows.len();
        assert!(epochs < 40, "{model} trained all {epochs} epochs");
        assert!(
            rows.iter()
                .all(|&i| reasons[i].as_deref() == Some("early stopping"))
        );
        // The last two epochs did not beat the best before them.
        let loss = |k: usize| validation[rows[k]].unwrap();
        let best_before = (0..epochs - 2).map(loss).fold(f64::INFINITY, f64::min);
        assert!(loss(epochs - 1) >= best_before && loss(epochs - 2) >= best_before);
    }
    let report = std::fs::read_to_string(project.path().join("results/quick/report.md")).unwrap();
    assert!(report.contains("| early stopping |"), "{report}");
    // The same spec without early stopping is another model: all five train, to the end.
    let output = run(&[]);
    assert_eq!(provenance(&output).len(), 5, "{}", stderr(&output));
    let batch = read_parquet(&project.path().join("results/quick/training.parquet"));
    assert_eq!(batch.num_rows(), 5 * 40);
    assert!(
        strings(&batch, "stop_reason")
            .iter()
            .all(|r| r.as_deref() == Some("all epochs"))
    );
    // And with early stopping again, every model comes from the cache.
    assert!(provenance(&run(&patience)).is_empty());
}

#[test]
fn a_model_trained_alone_is_the_model_trained_beside_others() {
    let project = project(false);
    for (out, models) in [
        ("alone", r#"["EM5"]"#),
        ("beside", r#"["EM1","EM2","EM3","EM4","EM5"]"#),
    ] {
        let set = format!("estimators.error_models={models}");
        quick_run(project.path(), &["--out", out, "--set", &set]);
    }
    let em5 = |out: &str| -> Vec<u8> {
        let folder = project.path().join(out).join(".cache/models");
        let file = std::fs::read_dir(&folder)
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| {
                let name = p.file_name().unwrap().to_string_lossy().into_owned();
                name.starts_with("EM5-") && name.ends_with(".bin")
            })
            .expect("EM5 is stored");
        std::fs::read(file).unwrap()
    };
    assert!(
        em5("alone") == em5("beside"),
        "EM5 depends on the models beside it"
    );
}

#[test]
fn bench_refuses_a_pytorch_peer_it_cannot_run_before_timing_anything() {
    let project = project(false);
    let output = dcnet(
        project.path(),
        &[
            "bench",
            "experiments/quick.toml",
            "--pytorch",
            "nowhere/torch_dcnet.py",
        ],
    );
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(stderr(&output).contains("--pytorch: nowhere/torch_dcnet.py is not a file"));
    assert!(stdout(&output).is_empty(), "{}", stdout(&output));
}

#[test]
fn bench_times_the_models_of_a_run_on_the_cores_they_do_not_fill_one_per_core() {
    let project = project(false);
    let bench_with = |key: &str, value: &str| {
        let set = format!("estimators.{key}={value}");
        let args = [
            "--threads",
            "3",
            "bench",
            "experiments/quick.toml",
            "--set",
            &set,
            "--repeat",
            "2",
            "--training-batches",
            "2",
        ];
        let output = dcnet(project.path(), &args);
        assert!(output.status.success(), "{}", stderr(&output));
        stdout(&output)
    };
    let bench = |error_models: &str| bench_with("error_models", error_models);
    let run_line = |out: &str| {
        out.lines()
            .find(|l| l.starts_with("training as `run` trains"))
            .map(str::to_string)
    };
    // Two models on three cores: one model per core, then one of them over two.
    let two = bench(r#"["EM1", "EM5"]"#);
    let line = run_line(&two).expect("a line for the run's models");
    assert!(
        line.contains("the spec's 2 models at once")
            && line.contains("on 2 cores, one model each")
            && line.contains("on all 3 cores, on 2, 1 threads")
            && line.contains("(median of 2 paired runs"),
        "{line}"
    );
    // Three models fill the three cores one per core, and a spec without DCNet trains
    // none: nothing more to time.
    assert_eq!(run_line(&bench(r#"["EM1", "EM3", "EM5"]"#)), None);
    assert_eq!(run_line(&bench_with("kinds", r#"["baseline"]"#)), None);
}

#[test]
fn more_threads_than_cores_are_run_with_a_warning() {
    let project = project(false);
    let cores = std::thread::available_parallelism().unwrap().get();
    let threads = (cores + 1).to_string();
    let output = dcnet(
        project.path(),
        &["--threads", &threads, "plan", "experiments/quick.toml"],
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let warning = format!("warning: --threads {threads} is more than the {cores} cores");
    assert!(stderr(&output).contains(&warning), "{}", stderr(&output));
    let output = dcnet(
        project.path(),
        &[
            "--threads",
            &cores.to_string(),
            "plan",
            "experiments/quick.toml",
        ],
    );
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        !stderr(&output).contains("warning: --threads"),
        "{}",
        stderr(&output)
    );
}

#[test]
fn output_piped_into_a_reader_that_stopped_ends_the_command_quietly() {
    use std::os::unix::process::ExitStatusExt;
    let project = project(false);
    // The pipe's reader is closed before the command starts, so its first line finds no
    // one whatever the machine's load (a reader dropped after the start raced the plan).
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_dcnet-exp"))
        .current_dir(project.path())
        .args(["plan", "experiments/quick.toml"])
        .stdout(writer)
        .stderr(std::process::Stdio::piped())
        .output()
        .unwrap();
    assert!(!stderr(&output).contains("panicked"), "{}", stderr(&output));
    assert_eq!(
        output.status.signal(),
        Some(libc::SIGPIPE),
        "{:?}",
        output.status
    );
}

#[test]
fn a_diverging_model_is_reported_and_the_others_are_kept() {
    let project = project(false);
    let dir = project.path();
    let diverging = [
        "experiments/quick.toml",
        "--set",
        "training.learning_rate.EM3=1e30",
        "--set",
        "training.epochs=3",
        "--no-plots",
    ];
    let run = |extra: &[&str]| dcnet(dir, &[&["run"], &diverging[..], extra].concat());
    let dcnet_models = |folder: &str| -> Vec<String> {
        evaluation_rows(&dir.join(folder))
            .iter()
            .filter(|r| r.estimator == "dcnet" && r.dvl == "DVL1" && r.at == "S3")
            .map(|r| r.error_model.clone().unwrap())
            .collect()
    };
    let reported = |output: &std::process::Output| {
        assert_eq!(output.status.code(), Some(2), "{}", stderr(output));
        let message = stderr(output);
        assert!(
            message.contains("error: DCNet EM3: the training loss became"),
            "{message}"
        );
        assert!(message.contains("at epoch 1, batch"), "{message}");
        assert!(message.contains("--force trains them again"), "{message}");
    };

    let output = run(&[]);
    reported(&output);
    assert_eq!(dcnet_models("results/quick"), ["EM1", "EM2", "EM4", "EM5"]);

    // The failure is recorded: a second run trains nothing and says why again.
    let again = run(&[]);
    reported(&again);
    assert!(
        stderr(&again).contains("nothing to do"),
        "{}",
        stderr(&again)
    );
    let plan = dcnet(dir, &[&["plan"], &diverging[..5]].concat());
    assert!(
        stdout(&plan).contains("failed (--force tries again)"),
        "{}",
        stdout(&plan)
    );

    // Shards record it too, and collect writes the results without it.
    for shard in ["0/2", "1/2"] {
        let _ = run(&["--out", "sharded", "--shard", shard]);
    }
    let collected = dcnet(
        dir,
        &[&["collect"], &diverging[..], &["--out", "sharded"]].concat(),
    );
    reported(&collected);
    assert_eq!(dcnet_models("sharded/quick"), ["EM1", "EM2", "EM4", "EM5"]);
}

/// Writes quick.toml with `from` replaced by `to` and returns the 1-based line of `to`.
fn quick_with(dir: &Path, from: &str, to: &str) -> usize {
    let text = std::fs::read_to_string(repo().join("experiments/quick.toml")).unwrap();
    assert!(text.contains(from), "quick.toml has no {from:?}");
    let changed = text.replacen(from, to, 1);
    std::fs::write(dir.join("spec.toml"), &changed).unwrap();
    changed[..changed.find(to).unwrap()].matches('\n').count() + 1
}

/// Runs `run spec.toml` and checks exit code 1, the message, and an untouched `results/`;
/// the whole message is the snapshot `name` (`tests/experiment/snapshots/experiment__cli__<name>.snap`).
fn assert_rejected(dir: &Path, name: &str, extra: &[&str], expected: &str) {
    let mut args = vec!["run", "spec.toml"];
    args.extend(extra);
    let output = dcnet(dir, &args);
    let message = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{message}");
    assert!(
        message.contains(expected),
        "expected {expected:?} in:\n{message}"
    );
    let command = format!("dcnet-exp {}", args.join(" "));
    assert_error_snapshot!(name, &command, &message, dir);
    assert!(
        !dir.join("results").exists(),
        "a rejected spec must not create results/"
    );
}

#[test]
fn bad_specs_are_rejected_with_file_line_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let line = quick_with(d, "noise_cm_s = 0.02\n", "noise_cm_s = -0.02\n");
    assert_rejected(
        d,
        "file_dvl_noise_negative",
        &[],
        &format!("error: spec.toml:{line}: dvl[1].noise_cm_s: -0.02 must be zero or positive"),
    );

    let line = quick_with(
        d,
        "bias_cm_s = { values = [0.3, 0.7] }",
        "bias_cm_s = { values = [] }",
    );
    assert_rejected(
        d,
        "file_grid_axis_empty",
        &[],
        &format!(
            "error: spec.toml:{line}: grid.bias_cm_s: is empty: the grid needs at least one value on every axis"
        ),
    );

    let line = quick_with(d, "stride_s = 9.0", "stride_s = 0.0");
    assert_rejected(
        d,
        "file_stride_zero",
        &[],
        &format!(
            "error: spec.toml:{line}: dataset.stride_s: 0 must be a positive whole number of samples at 1 Hz"
        ),
    );

    let line = quick_with(
        d,
        "window_sizes_s = [20.0, 40.0, 60.0, 80.0, 100.0]",
        "window_sizes_s = [20.0, 250.0]",
    );
    assert_rejected(
        d,
        "file_window_longer_than_scal",
        &[],
        &format!(
            "error: spec.toml:{line}: calibration.window_sizes_s[1]: 250 s is not shorter than SCal (200 s): no samples would be left to evaluate on"
        ),
    );

    let line = quick_with(
        d,
        "trajectories = [\"S3\", \"S4\"]",
        "trajectories = [\"S3\", \"S9\"]",
    );
    assert_rejected(
        d,
        "file_unknown_trajectory",
        &[],
        &format!(
            "error: spec.toml:{line}: evaluation.trajectories[1]: unknown trajectory \"S9\"; data.trajectories defines S1, S2, S3, S4, SCal"
        ),
    );

    let line = quick_with(
        d,
        "checkpoint_every_epochs = 5",
        "checkpoint_every_epochs = 5\nearly_stopping = { patience_epochs = 0 }",
    ) + 1;
    assert_rejected(
        d,
        "file_patience_zero",
        &[],
        &format!(
            "error: spec.toml:{line}: training.early_stopping.patience_epochs: 0 must be at least 1"
        ),
    );

    let line = quick_with(
        d,
        "monte_carlo_runs = 20",
        "monte_carlo_runs = 20\ncolour = \"red\"",
    ) + 1;
    assert_rejected(
        d,
        "file_unknown_key",
        &[],
        &format!(
            "error: spec.toml:{line}: calibration.colour: unknown field `colour`, expected one of `trajectory`, `window_sizes_s`, `monte_carlo_runs`"
        ),
    );

    let line = quick_with(
        d,
        "name = \"SCal\"\nsynthetic_duration_s = 200",
        "name = \"SCal\"\nfile = \"nowhere/V_test.npy\"\nsamples = [0, 200]",
    ) + 1;
    let missing = d.join("nowhere/V_test.npy");
    assert_rejected(
        d,
        "file_missing_recording",
        &[],
        &format!(
            "error: spec.toml:{line}: data.trajectories[4].file: {} does not exist; run `dcnet-exp data fetch --dest {}`",
            missing.display(),
            d.join("nowhere").display()
        ),
    );

    let line = quick_with(d, "seed = 7", "seed = 7\n[broken") + 1;
    assert_rejected(
        d,
        "file_unclosed_table",
        &[],
        &format!("error: spec.toml:{line}: unclosed table, expected `]`"),
    );

    quick_with(d, "seed = 7", "seed = 7");
    assert_rejected(
        d,
        "set_monte_carlo_runs_negative",
        &["--set", "calibration.monte_carlo_runs=-3"],
        "error: --set calibration.monte_carlo_runs=-3: calibration.monte_carlo_runs: invalid value: integer `-3`, expected usize",
    );
    assert_rejected(
        d,
        "set_window_not_whole_samples",
        &["--set", "dataset.window_s=0.5"],
        "error: --set dataset.window_s=0.5: dataset.window_s: 0.5 must be a positive whole number of samples at 1 Hz",
    );
    assert_rejected(
        d,
        "set_index_out_of_range",
        &["--set", "dvl[7].noise_cm_s=1"],
        "error: --set dvl[7].noise_cm_s=1: dvl[7].noise_cm_s: index [7] is out of range: there are 2 entries",
    );
    assert_rejected(
        d,
        "backend_cuda",
        &["--backend", "cuda"],
        "error: --backend cuda: unknown backend \"cuda\"; expected flex or ndarray",
    );
}

#[test]
fn bad_arguments_and_names_are_bad_input_before_anything_runs() {
    let dir = project(false);
    let d = dir.path();
    std::fs::write(d.join("a-file"), "").unwrap();
    let cases: [(&[&str], &str); 7] = [
        (
            &["--threads", "10000", "plan", "experiments/quick.toml"],
            "error: --threads 10000: give 1 to 1024",
        ),
        (
            &["run", "experiments/quick.toml", "--out", "a-file"],
            "error: --out a-file: is a file; results go into a folder",
        ),
        (
            &["--log-every", "1e6", "plan", "experiments/quick.toml"],
            "error: --log-every 1000000 (or DCNET_LOG_EVERY): give 0 to 86400 seconds",
        ),
        (
            &["bench", "experiments/quick.toml", "--repeat", "0"],
            "0 is not in 1..=1000",
        ),
        (
            &[
                "data",
                "fetch",
                "--base-url",
                "localhost:1",
                "--dest",
                "fetched",
            ],
            "error: --base-url localhost:1: not an http:// or https:// address with a host",
        ),
        (
            &["run", "experiments/quick.toml", "--set", "name=\".cache\""],
            "name: \".cache\" must be non-empty, at most 200 characters",
        ),
        (
            &[
                "validate",
                "experiments/quick.toml",
                "--set",
                "calibration.window_sizes_s=[20, 20]",
            ],
            "calibration.window_sizes_s[1]: 20 s is calibration.window_sizes_s[0] again",
        ),
    ];
    for (args, expected) in cases {
        let output = dcnet(d, args);
        let message = stderr(&output);
        assert_eq!(output.status.code(), Some(1), "{args:?}: {message}");
        assert!(
            message.contains(expected),
            "{args:?}: expected {expected:?} in:\n{message}"
        );
        let command = format!("dcnet-exp {}", args.join(" "));
        let name = format!("arguments_{}", snapshot_name(&args.join(" ")));
        assert_error_snapshot!(&name, &command, &message, d);
        for made in ["results", "fetched"] {
            assert!(!d.join(made).exists(), "{args:?} made {made}/");
        }
    }
}

/// Specs that cannot fit in this machine's memory (the test machines have far less
/// than a terabyte), refused before anything is allocated: by `validate`, `plan` and
/// `run`, at the key of the largest part, with the estimate.
#[test]
fn a_spec_beyond_this_machines_memory_is_refused_with_its_estimate_and_key() {
    let dir = project(false);
    let d = dir.path();
    let wide = "model.fc_widths=[65536, 65536, 64]";
    for command in ["validate", "plan", "run"] {
        let output = dcnet(d, &[command, "experiments/quick.toml", "--set", wide]);
        let message = stderr(&output);
        assert_eq!(output.status.code(), Some(1), "{command}: {message}");
        assert!(
            message.contains(&format!("--set {wide}: model.fc_widths[0]: needs about ")),
            "{command}: {message}"
        );
        assert!(
            message.contains("of memory and this machine has")
                && message.contains("is the models in training"),
            "{command}: {message}"
        );
        assert!(!d.join("results").exists(), "{command} made results/");
    }
    // The same in a sweep, placed at the point that needs it.
    let spec = std::fs::read_to_string(d.join("experiments/quick.toml")).unwrap()
        + "\n[sweep.values]\n\"model.fc_widths\" = [[128, 64, 32], [65536, 65536, 64]]\n";
    std::fs::write(d.join("experiments/sweep.toml"), spec).unwrap();
    let output = dcnet(d, &["validate", "experiments/sweep.toml"]);
    let message = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{message}");
    assert!(
        message.contains(
            "sweep.toml:80: model.fc_widths[0]: point quick/fc_widths=65536-65536-64: needs about"
        ),
        "{message}"
    );
}

#[test]
fn validate_accepts_a_good_spec_and_overrides_apply() {
    let project = project(false);
    let output = dcnet(
        project.path(),
        &[
            "validate",
            "experiments/quick.toml",
            "--set",
            "calibration.monte_carlo_runs=5",
        ],
    );
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stdout(&output)
            .contains("ok (5 trajectories, 1980 training windows, 2 DVLs, 5 Monte Carlo runs)"),
        "{}",
        stdout(&output)
    );
    assert!(!project.path().join("results").exists());

    // A key of [estimators] left out takes its default: all five error models.
    let dir = tempfile::tempdir().unwrap();
    quick_with(
        dir.path(),
        "error_models = [\"EM1\", \"EM2\", \"EM3\", \"EM4\", \"EM5\"]\n",
        "",
    );
    let output = dcnet(dir.path(), &["plan", "spec.toml"]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stdout(&output).contains("train DCNet EM5"),
        "{}",
        stdout(&output)
    );
}

#[test]
fn a_missing_recording_names_the_path_and_the_fetch_command() {
    let project = project(false);
    let output = dcnet(project.path(), &["validate", "experiments/paper.toml"]);
    assert_eq!(output.status.code(), Some(1));
    let message = stderr(&output);
    assert!(message.contains("data.trajectories[0].file:"), "{message}");
    assert!(
        message.contains("data/snapir/V.npy does not exist; run `dcnet-exp data fetch --dest"),
        "{message}"
    );
}

#[test]
fn a_recording_path_in_a_loop_of_symbolic_links_is_named_a_loop() {
    let project = project(false);
    let snapir = project.path().join("data/snapir");
    std::fs::create_dir_all(&snapir).unwrap();
    // V.npy -> loop.npy -> V.npy
    std::os::unix::fs::symlink("loop.npy", snapir.join("V.npy")).unwrap();
    std::os::unix::fs::symlink("V.npy", snapir.join("loop.npy")).unwrap();
    let output = dcnet(project.path(), &["validate", "experiments/paper.toml"]);
    assert_eq!(output.status.code(), Some(1));
    let message = stderr(&output);
    assert!(
        message.contains(&format!(
            "data.trajectories[0].file: {}/experiments/../data/snapir/V.npy is a loop of symbolic links that leads back to itself: name the recording file",
            project.path().display()
        )),
        "{message}"
    );
}

#[test]
#[ignore = "needs the Snapir recordings: dcnet-exp data fetch"]
fn data_fetch_downloads_and_checks_the_recordings() {
    let snapir = snapir();
    let files = vec![
        (
            "/dataset/TrainAndValidation/V.npy".to_string(),
            std::fs::read(snapir.join("V.npy")).unwrap(),
        ),
        (
            "/dataset/Test/V_test.npy".to_string(),
            std::fs::read(snapir.join("V_test.npy")).unwrap(),
        ),
    ];
    let (url, handle, server) = serve(files);
    let dir = tempfile::tempdir().unwrap();
    let output = dcnet(dir.path(), &["data", "fetch", "--base-url", &url]);
    assert!(output.status.success(), "{}", stderr(&output));
    for name in ["V.npy", "V_test.npy"] {
        assert_eq!(
            std::fs::read(dir.path().join("data/snapir").join(name)).unwrap(),
            std::fs::read(snapir.join(name)).unwrap()
        );
    }
    let again = dcnet(dir.path(), &["data", "fetch", "--base-url", &url]);
    assert!(
        stderr(&again).contains("is already there (sha256 checked)"),
        "{}",
        stderr(&again)
    );
    server.unblock();
    handle.join().unwrap();
}

#[test]
fn data_fetch_stops_a_body_longer_than_the_recording() {
    use std::io::Read;
    // One request, answered with 10 MB and no declared length, for the 333,392 bytes of
    // V.npy; the server gives up waiting after 10 s.
    let server = tiny_http::Server::http("127.0.0.1:0").unwrap();
    let url = format!("http://{}", server.server_addr().to_ip().unwrap());
    let handle = std::thread::spawn(move || {
        if let Ok(Some(request)) = server.recv_timeout(std::time::Duration::from_secs(10)) {
            let body = std::io::repeat(b'x').take(10_000_000);
            let _ = request.respond(tiny_http::Response::new(
                200.into(),
                Vec::new(),
                body,
                None,
                None,
            ));
        }
    });
    let dir = tempfile::tempdir().unwrap();
    let output = dcnet(dir.path(), &["data", "fetch", "--base-url", &url]);
    handle.join().unwrap();
    assert_eq!(output.status.code(), Some(2));
    assert!(
        stderr(&output).contains(&format!(
            "{url}/dataset/TrainAndValidation/V.npy: the server sent more than the 333392 bytes of the file; stopped there, nothing written"
        )),
        "{}",
        stderr(&output)
    );
    assert_eq!(
        std::fs::read_dir(dir.path().join("data/snapir"))
            .unwrap()
            .count(),
        0
    );
}

#[test]
fn data_fetch_refuses_bytes_that_are_not_the_recording() {
    // The size of V.npy, so that it is the hash that refuses them.
    let (url, handle, server) = serve(vec![(
        "/dataset/TrainAndValidation/V.npy".to_string(),
        b"not the recording".repeat(19_612)[..333_392].to_vec(),
    )]);
    let dir = tempfile::tempdir().unwrap();
    let output = dcnet(
        dir.path(),
        &["data", "fetch", "--base-url", &url, "--dest", "elsewhere"],
    );
    assert_eq!(output.status.code(), Some(2));
    assert!(
        stderr(&output).contains(&format!("{url}/dataset/TrainAndValidation/V.npy: sha256 ")),
        "{}",
        stderr(&output)
    );
    assert_eq!(
        std::fs::read_dir(dir.path().join("elsewhere"))
            .unwrap()
            .count(),
        0
    );
    server.unblock();
    handle.join().unwrap();
}
