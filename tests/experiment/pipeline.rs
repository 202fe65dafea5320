//! Tasks, caching, resuming, sharding and sweeps, as a user meets them: `plan`, a run
//! that has nothing left to do, a changed Monte Carlo setting, runs killed with
//! SIGKILL mid-training and mid-Monte-Carlo, three shards and `collect`, and sweeps
//! over two keys and over one, with their figures. Each compares with an uninterrupted
//! single process byte for byte.

use crate::common;
use common::*;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The quick spec, small enough to train in a few seconds.
const SMALL: [&str; 4] = [
    "--set",
    "training.epochs=4",
    "--set",
    "training.checkpoint_every_epochs=1",
];

/// The tables whose bytes a run must reproduce (`training.parquet` also holds wall
/// times; its losses are compared apart).
const TABLES: [&str; 4] = [
    "monte_carlo.parquet",
    "calibration.parquet",
    "evaluation.parquet",
    "trajectories.parquet",
];

fn run_ok(cwd: &Path, args: &[&str]) -> String {
    let output = dcnet(cwd, args);
    assert!(output.status.success(), "{args:?}: {}", stderr(&output));
    stderr(&output)
}

fn args<'a>(first: &[&'a str], rest: &[&'a str]) -> Vec<&'a str> {
    [first, rest].concat()
}

/// Asserts that two results folders hold the same tables and training losses.
fn assert_same_results(a: &Path, b: &Path) {
    for table in TABLES {
        let one = std::fs::read(a.join(table)).unwrap();
        let two = std::fs::read(b.join(table)).unwrap();
        assert!(one == two, "{table} differs between {a:?} and {b:?}");
    }
    let losses = |folder: &Path| {
        let batch = read_parquet(&folder.join("training.parquet"));
        (
            strings(&batch, "error_model"),
            floats(&batch, "train_loss"),
            floats(&batch, "validation_loss"),
            bools(&batch, "is_best"),
        )
    };
    assert_eq!(losses(a), losses(b));
}

fn names_below(folder: &Path) -> Vec<String> {
    snapshot(folder)
        .keys()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect()
}

fn count_files(folder: &Path, extension: &str) -> usize {
    std::fs::read_dir(folder).map_or(0, |entries| {
        entries
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .path()
                    .extension()
                    .is_some_and(|x| x == extension)
            })
            .count()
    })
}

#[test]
fn plan_lists_every_task_and_changes_nothing() {
    let project = project(false);
    let dir = project.path();
    let plan = |extra: &[&str]| {
        let output = dcnet(
            dir,
            &args(
                &["plan", "experiments/quick.toml"],
                &[&SMALL[..], extra].concat(),
            ),
        );
        assert!(output.status.success(), "{}", stderr(&output));
        stdout(&output)
    };
    let text = plan(&[]);
    assert!(!dir.join("results").exists(), "plan wrote something");
    let rows = plan_rows(&text);
    let labels: Vec<&str> = rows.iter().map(|(label, _)| label.as_str()).collect();
    assert_eq!(labels.len(), 1 + 5 + 2 * 19 + 1, "{text}");
    assert_eq!(labels[0], "generate dataset");
    assert_eq!(
        labels[1..6],
        [
            "train DCNet EM1",
            "train DCNet EM2",
            "train DCNet EM3",
            "train DCNet EM4",
            "train DCNet EM5"
        ]
    );
    assert_eq!(labels[6], "monte carlo DVL1 baseline");
    assert_eq!(labels[7], "monte carlo DVL1 least_squares EM1");
    assert_eq!(labels[12], "monte carlo DVL1 beam_wls");
    assert_eq!(labels[13], "monte carlo DVL1 kalman EM1");
    assert_eq!(labels[18], "monte carlo DVL1 kalman_beam");
    assert_eq!(labels[43], "monte carlo DVL2 floor");
    assert_eq!(labels[44], "write results/quick");
    assert!(rows.iter().all(|(_, status)| status == "to do"), "{text}");
    assert!(text.contains("quick: 45 tasks, 45 to do"), "{text}");

    run_ok(
        dir,
        &args(&["run", "experiments/quick.toml", "--no-plots"], &SMALL),
    );
    let text = plan(&[]);
    assert!(text.contains("quick: 45 tasks, 0 to do"), "{text}");
    assert!(text.contains("| generate dataset "), "{text}");
    assert!(text.contains("not needed"), "{text}");

    // A Monte Carlo setting leaves the models done and the blocks to do.
    let text = plan(&["--set", "calibration.monte_carlo_runs=5"]);
    assert!(text.contains("quick: 45 tasks, 39 to do"), "{text}");
    assert_eq!(text.matches("| train DCNet").count(), 5);
    assert!(
        !text
            .lines()
            .any(|l| l.contains("train DCNet") && l.contains("to do")),
        "{text}"
    );

    // The shards split the trainings and blocks between them, each exactly once.
    let mut seen = Vec::new();
    for k in 0..3 {
        let text = plan(&["--shard", &format!("{k}/3")]);
        seen.extend(
            text.lines()
                .filter(|l| l.contains("train DCNet") || l.contains("monte carlo"))
                .map(|l| l.split('|').nth(1).unwrap().trim().to_string()),
        );
    }
    seen.sort();
    let mut all: Vec<String> = labels[1..44].iter().map(|l| l.to_string()).collect();
    all.sort();
    assert_eq!(seen, all);
}

#[test]
fn a_second_run_does_nothing_and_a_monte_carlo_change_trains_nothing() {
    let project = project(false);
    let dir = project.path();
    let run = |extra: &[&str]| {
        run_ok(
            dir,
            &args(
                &["run", "experiments/quick.toml", "--no-plots"],
                &[&SMALL[..], extra].concat(),
            ),
        )
    };
    run(&[]);
    let before = snapshot(&dir.join("results"));
    let second = run(&[]);
    assert!(
        second.contains("nothing to do: every task of quick is done"),
        "{second}"
    );
    assert!(
        !second.contains("DCNet") && !second.contains("monte carlo"),
        "{second}"
    );
    assert!(
        before == snapshot(&dir.join("results")),
        "the second run touched a file"
    );

    let models = snapshot(&dir.join("results/.cache/models"));
    let third = run(&["--set", "calibration.monte_carlo_runs=4"]);
    assert!(!third.contains("DCNet"), "{third}");
    assert!(!third.contains("dataset"), "{third}");
    assert!(
        third.contains("monte carlo quick DVL1: 19 estimators × 4 runs stored"),
        "{third}"
    );
    assert!(
        models == snapshot(&dir.join("results/.cache/models")),
        "a model was touched"
    );
    let runs = read_parquet(&dir.join("results/quick/monte_carlo.parquet"));
    // 4 runs × 2 DVLs × (19 estimators at 5 windows and on 2 test trajectories, and
    // the held-out curves: 13 methods at every second to 100 s, 5 DCNets at 5 windows).
    assert_eq!(runs.num_rows(), 4 * 2 * (19 * (5 + 2) + 13 * 100 + 5 * 5));

    // A report setting rewrites the results folder and computes nothing.
    let report = run(&[
        "--set",
        "calibration.monte_carlo_runs=4",
        "--set",
        "report.tolerance_pct=5",
    ]);
    assert!(
        report.contains("quick: 1 task to do (45 in the plan)"),
        "{report}"
    );
    assert!(
        !report.contains("DCNet") && !report.contains("monte carlo"),
        "{report}"
    );

    // Back to the first setting: everything comes from the cache, nothing is computed.
    let fourth = run(&[]);
    assert!(
        !fourth.contains("DCNet") && !fourth.contains("monte carlo"),
        "{fourth}"
    );
    for table in TABLES {
        let path = dir.join("results/quick").join(table);
        assert!(
            std::fs::read(&path).unwrap() == before[&path].0,
            "{table} differs"
        );
    }
}

fn no_partial_files(folder: &Path) {
    let partial: Vec<String> = names_below(folder)
        .into_iter()
        .filter(|n| n.starts_with(".partial-"))
        .collect();
    assert!(partial.is_empty(), "partial files left: {partial:?}");
}

#[test]
fn a_run_killed_mid_training_resumes_to_the_results_of_an_uninterrupted_one() {
    let project = project(false);
    let dir = project.path();
    let spec = ["experiments/quick.toml", "--no-plots"];
    run_ok(
        dir,
        &args(&["run", "--out", "whole"], &[&spec[..], &SMALL].concat()),
    );

    let killed = args(&["run", "--out", "killed"], &[&spec[..], &SMALL].concat());
    let mut child = spawn(dir, &killed);
    let models = dir.join("killed/.cache/models");
    let started = Instant::now();
    let checkpointed = || {
        std::fs::read_dir(&models).is_ok_and(|entries| {
            entries
                .flatten()
                .any(|e| e.path().join("state.json").is_file())
        })
    };
    while !checkpointed() {
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "no checkpoint appeared"
        );
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before a checkpoint"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    assert!(count_files(&models, "bin") < 5, "every model had finished");
    assert!(
        !dir.join("killed/quick").exists(),
        "results appeared before the run ended"
    );

    let resumed = run_ok(dir, &killed);
    assert!(
        resumed.contains("resumed from the checkpoint of epoch"),
        "{resumed}"
    );
    assert_same_results(&dir.join("whole/quick"), &dir.join("killed/quick"));
    no_partial_files(&dir.join("killed"));
}

#[test]
fn a_run_killed_mid_monte_carlo_resumes_to_the_results_of_an_uninterrupted_one() {
    let project = project(false);
    let dir = project.path();
    // No DCNet and many runs: the Monte Carlo stage lasts long enough to be cut.
    let spec = [
        "experiments/quick.toml",
        "--no-plots",
        "--set",
        "estimators.kinds=[\"baseline\", \"least_squares\", \"floor\"]",
        "--set",
        "calibration.monte_carlo_runs=3000",
    ];
    run_ok(dir, &args(&["run", "--out", "whole"], &spec));

    let killed = args(&["run", "--out", "killed"], &spec);
    let mut child = spawn(dir, &killed);
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let first = lines
        .find_map(|line| line.ok().filter(|l| l.starts_with("monte carlo quick")))
        .expect("the run reports its first DVL");
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    assert!(
        first.starts_with("monte carlo quick DVL1: 7 estimators"),
        "{first}"
    );
    let blocks = dir.join("killed/.cache/monte_carlo");
    assert_eq!(count_files(&blocks, "parquet"), 7, "DVL1's blocks only");
    assert!(!dir.join("killed/quick").exists());

    let resumed = run_ok(dir, &killed);
    assert!(!resumed.contains("monte carlo quick DVL1"), "{resumed}");
    assert!(
        resumed.contains("monte carlo quick DVL2: 7 estimators"),
        "{resumed}"
    );
    for table in TABLES {
        let one = std::fs::read(dir.join("whole/quick").join(table)).unwrap();
        let two = std::fs::read(dir.join("killed/quick").join(table)).unwrap();
        assert!(one == two, "{table} differs");
    }
    no_partial_files(&dir.join("killed"));
}

#[test]
fn three_shards_and_collect_write_what_one_process_writes() {
    let project = project(false);
    let dir = project.path();
    let spec = ["experiments/quick.toml", "--no-plots"];
    run_ok(
        dir,
        &args(&["run", "--out", "one"], &[&spec[..], &SMALL].concat()),
    );

    let shard = |k: usize, env: Option<(&str, &str)>| {
        let index = format!("{k}/3");
        let shard_arg = if env.is_some() { "3" } else { index.as_str() };
        let mut command = Command::new(env!("CARGO_BIN_EXE_dcnet-exp"));
        command
            .current_dir(dir)
            .args(args(
                &["run", "--out", "sharded", "--shard", shard_arg],
                &[&spec[..], &SMALL].concat(),
            ))
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        if let Some((variable, value)) = env {
            command.env(variable, value);
        }
        command.spawn().unwrap()
    };
    let collect = || {
        dcnet(
            dir,
            &args(
                &["collect", "--out", "sharded"],
                &[&spec[..], &SMALL].concat(),
            ),
        )
    };

    let first = shard(0, None).wait_with_output().unwrap();
    assert!(first.status.success(), "{}", stderr(&first));
    assert!(stderr(&first).contains("shard 0/3: "), "{}", stderr(&first));
    assert!(!dir.join("sharded/quick").exists(), "a shard wrote results");
    let early = collect();
    assert_eq!(early.status.code(), Some(2), "{}", stderr(&early));
    assert!(
        stderr(&early).contains("tasks are not done yet"),
        "{}",
        stderr(&early)
    );

    // The other two side by side, their indices from the schedulers' variables.
    let others = [
        shard(1, Some(("SLURM_ARRAY_TASK_ID", "1"))),
        shard(2, Some(("JOB_COMPLETION_INDEX", "2"))),
    ];
    for child in others {
        let output = child.wait_with_output().unwrap();
        assert!(output.status.success(), "{}", stderr(&output));
    }
    let collected = collect();
    assert!(collected.status.success(), "{}", stderr(&collected));
    assert_same_results(&dir.join("one/quick"), &dir.join("sharded/quick"));
    let again = collect();
    assert!(
        stderr(&again).contains("nothing to do"),
        "{}",
        stderr(&again)
    );
}

#[test]
fn a_sweep_over_two_keys_runs_every_point_and_tabulates_them() {
    let project = project(false);
    let dir = project.path();
    write_quick_sweep(
        dir,
        "\"training.learning_rate\" = [5e-4, 2e-3]\nmodel.conv_channels = [8, 16]\n",
    );
    let spec = ["experiments/sweep.toml", "--set", "training.epochs=2"];

    // Points that differ only in a Monte Carlo setting share their models.
    let shared = dcnet(
        dir,
        &args(
            &["plan"],
            &[
                &spec[..],
                &[
                    "--set",
                    "sweep.values={\"calibration.monte_carlo_runs\" = [3, 4]}",
                ],
            ]
            .concat(),
        ),
    );
    assert!(shared.status.success(), "{}", stderr(&shared));
    assert_eq!(
        stdout(&shared).matches("train DCNet").count(),
        5,
        "{}",
        stdout(&shared)
    );

    let output = run_ok(dir, &args(&["run"], &spec));
    let points = [
        "learning_rate=0.0005,conv_channels=8",
        "learning_rate=0.0005,conv_channels=16",
        "learning_rate=0.002,conv_channels=8",
        "learning_rate=0.002,conv_channels=16",
    ];
    assert_eq!(output.matches("DCNet EM1").count(), 4, "{output}");
    let folder = dir.join("results/quick-sweep");
    for point in points {
        assert!(
            folder.join(point).join("manifest.json").is_file(),
            "{point}"
        );
        assert!(
            dir.join("plots/quick-sweep")
                .join(point)
                .join("calibration.png")
                .is_file()
        );
    }
    for stem in ["sweep_training_learning_rate", "sweep_model_conv_channels"] {
        assert!(
            dir.join("plots/quick-sweep")
                .join(format!("{stem}.png"))
                .is_file(),
            "{stem}"
        );
    }
    // Two keys: also the parallel coordinates, a panel per DVL of three axes each.
    assert_png(
        &dir.join("plots/quick-sweep/sweep_parallel.png"),
        (2000, 1800),
    );
    let svg = std::fs::read_to_string(dir.join("plots/quick-sweep/sweep_parallel.svg")).unwrap();
    assert!(svg.contains("<path") && !svg.contains("<text"), "{svg}");

    let sweep = read_parquet(&folder.join("sweep.parquet"));
    // 4 points × 2 DVLs × (19 estimators and the bound).
    assert_eq!(sweep.num_rows(), 4 * 2 * 20);
    let point = strings(&sweep, "point");
    let rate = floats(&sweep, "training.learning_rate");
    let channels = integers(&sweep, "model.conv_channels");
    let (dvl, estimator, model) = (
        strings(&sweep, "dvl"),
        strings(&sweep, "estimator"),
        strings(&sweep, "error_model"),
    );
    let evaluation = floats(&sweep, "evaluation_rmse_cm_s");
    let training_s = floats(&sweep, "training_s");
    for (p, name) in points.iter().enumerate() {
        let rows: Vec<usize> = (0..sweep.num_rows())
            .filter(|&i| point[i].as_deref() == Some(name))
            .collect();
        assert_eq!(rows.len(), 40);
        let expected_rate = [5e-4, 5e-4, 2e-3, 2e-3][p];
        let expected_channels = [8, 16, 8, 16][p];
        assert!(
            rows.iter()
                .all(|&i| rate[i] == Some(expected_rate) && channels[i] == Some(expected_channels))
        );
        // Each row holds the point's own numbers: the mean over its test trajectories,
        // and its model's training time.
        let i = *rows
            .iter()
            .find(|&&i| {
                dvl[i].as_deref() == Some("DVL2")
                    && estimator[i].as_deref() == Some("dcnet")
                    && model[i].as_deref() == Some("EM5")
            })
            .unwrap();
        let own = evaluation_rows(&folder.join(name));
        let mean: Vec<f64> = own
            .iter()
            .filter(|r| {
                r.dvl == "DVL2" && r.estimator == "dcnet" && r.error_model.as_deref() == Some("EM5")
            })
            .map(|r| r.rmse_cm_s)
            .collect();
        assert_eq!(mean.len(), 2);
        assert!((evaluation[i].unwrap() - (mean[0] + mean[1]) / 2.0).abs() < 1e-12);
        let history = read_parquet(&folder.join(name).join("training.parquet"));
        let seconds: f64 = strings(&history, "error_model")
            .iter()
            .zip(floats(&history, "seconds"))
            .filter(|(m, _)| m.as_deref() == Some("EM5"))
            .map(|(_, s)| s.unwrap())
            .sum();
        assert!((training_s[i].unwrap() - seconds).abs() < 1e-9);
    }
    // The conv_channels = 8 and 16 models differ, so do their results.
    assert_ne!(evaluation[0..24], evaluation[24..48]);

    let plotted = dcnet(
        dir,
        &[
            "plot",
            "results/quick-sweep",
            "--out",
            "replot",
            "--metric",
            "training-time",
            "--format",
            "svg",
        ],
    );
    assert!(plotted.status.success(), "{}", stderr(&plotted));
    let svg =
        std::fs::read_to_string(dir.join("replot/quick-sweep/sweep_training_learning_rate.svg"))
            .unwrap();
    assert!(svg.contains("<path"), "the figure has no drawing");
    assert!(
        dir.join("replot/quick-sweep")
            .join(points[0])
            .join("calibration.svg")
            .is_file()
    );

    let again = run_ok(dir, &args(&["run"], &spec));
    assert!(again.contains("nothing to do"), "{again}");

    // A damaged table is written again, to the bytes it had.
    let table = folder.join("sweep.parquet");
    let good = std::fs::read(&table).unwrap();
    let mut flipped = good.clone();
    flipped[good.len() / 2] ^= 1;
    std::fs::write(&table, flipped).unwrap();
    let again = run_ok(dir, &args(&["run"], &spec));
    assert!(again.contains("1 task to do"), "{again}");
    assert_eq!(std::fs::read(&table).unwrap(), good);

    // An index naming a column the table lacks is bad input, named as such.
    let index = folder.join("sweep.json");
    let text = std::fs::read_to_string(&index).unwrap();
    std::fs::write(
        &index,
        text.replace("\"model.conv_channels\"", "\"model.dropout\""),
    )
    .unwrap();
    let broken = dcnet(dir, &["plot", "results/quick-sweep", "--out", "replot"]);
    assert_eq!(broken.status.code(), Some(1), "{}", stderr(&broken));
    assert!(
        stderr(&broken).contains(
            "sweep.parquet: column `model.dropout`, a swept key of sweep.json, is missing"
        ),
        "{}",
        stderr(&broken)
    );
}

#[test]
fn a_sweep_point_holds_what_a_plain_run_of_its_values_holds() {
    let project = project(false);
    let dir = project.path();
    let common = [
        "experiments/quick.toml",
        "--no-plots",
        "--set",
        "training.epochs=2",
    ];
    // Two grids: two datasets, each with its five models.
    let swept = run_ok(
        dir,
        &args(
            &["run", "--out", "swept"],
            &[
                &common[..],
                &[
                    "--set",
                    "name=grid",
                    "--set",
                    "sweep.values={\"grid.noise_cm_s.values\" = [[0.02], [0.05, 0.1]]}",
                ],
            ]
            .concat(),
        ),
    );
    let datasets = swept.lines().filter(|l| l.starts_with("dataset ")).count();
    assert_eq!(datasets, 2, "{swept}");
    run_ok(
        dir,
        &args(
            &["run", "--out", "plain"],
            &[
                &common[..],
                &["--set", "grid.noise_cm_s.values=[0.05, 0.1]"],
            ]
            .concat(),
        ),
    );
    assert_same_results(
        &dir.join("swept/grid/noise_cm_s.values=0.05-0.1"),
        &dir.join("plain/quick"),
    );
    // One key: its figure, and no parallel coordinates.
    run_ok(dir, &["plot", "swept/grid", "--out", "figures"]);
    assert!(
        dir.join("figures/grid/sweep_grid_noise_cm_s_values.png")
            .is_file()
    );
    assert!(!dir.join("figures/grid/sweep_parallel.png").exists());
    assert!(!dir.join("figures/grid/sweep_parallel.svg").exists());
}

/// The stored weights of the quick run's EM3 model in `cache`.
fn em3_weights(cache: &Path) -> PathBuf {
    files_with(&cache.join("models"), "bin")
        .into_iter()
        .find(|path| {
            path.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("EM3-")
        })
        .unwrap()
}

/// The files of `folder` whose extension is `extension`, sorted.
fn files_with(folder: &Path, extension: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(folder)
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == extension))
        .collect();
    files.sort();
    files
}

#[test]
fn a_damaged_cache_entry_is_set_aside_and_computed_again() {
    let dir = project(false);
    let d = dir.path();
    let run = args(&["run", "experiments/quick.toml", "--no-plots"], &SMALL);
    run_ok(d, &run);
    let cache = d.join("results/.cache");
    // One flipped byte in EM3's weights, and one Monte Carlo block copied over another.
    let weights = em3_weights(&cache);
    let good_weights = std::fs::read(&weights).unwrap();
    let mut flipped = good_weights.clone();
    let middle = flipped.len() / 2;
    flipped[middle] ^= 1;
    std::fs::write(&weights, flipped).unwrap();
    let blocks = files_with(&cache.join("monte_carlo"), "parquet");
    let good_block = std::fs::read(&blocks[1]).unwrap();
    std::fs::copy(&blocks[0], &blocks[1]).unwrap();

    let plan = dcnet(d, &args(&["plan", "experiments/quick.toml"], &SMALL));
    assert_eq!(
        stdout(&plan).matches("to do (damaged)").count(),
        2,
        "{}",
        stdout(&plan)
    );
    assert!(!cache.join("damaged").exists(), "plan changes nothing");

    let log = run_ok(d, &run);
    assert!(log.contains("DCNet EM3: damaged model "), "{log}");
    assert!(
        log.contains("its bytes do not match the SHA-256 of its seal"),
        "{log}"
    );
    assert!(log.contains("damaged Monte Carlo block "), "{log}");
    // Set aside, not deleted: the model (weights and history) and the block, each with
    // its seal.
    assert_eq!(std::fs::read_dir(cache.join("damaged")).unwrap().count(), 6);
    // Computed again, to the bytes they had before the damage.
    assert_eq!(std::fs::read(&weights).unwrap(), good_weights);
    assert_eq!(std::fs::read(&blocks[1]).unwrap(), good_block);
    assert!(run_ok(d, &run).contains("nothing to do"));

    // A damaged table, or a report lost to a kill, makes the folder not current.
    let folder = d.join("results/quick");
    let table = folder.join("calibration.parquet");
    let good_table = std::fs::read(&table).unwrap();
    let mut truncated = good_table.clone();
    truncated.truncate(good_table.len() - 1);
    std::fs::write(&table, truncated).unwrap();
    let log = run_ok(d, &run);
    assert!(log.contains("1 task to do"), "{log}");
    assert_eq!(std::fs::read(&table).unwrap(), good_table);
    std::fs::remove_file(folder.join("report.tex")).unwrap();
    let log = run_ok(d, &run);
    assert!(log.contains("1 task to do"), "{log}");
    assert!(folder.join("report.tex").is_file());
    assert!(run_ok(d, &run).contains("nothing to do"));
}

/// A stored model whose seals hold but whose weights are no model (forged, or another
/// build's) stopped every run that needed it: it is set aside, said so, and trained
/// again, to the bytes it had.
#[test]
fn a_sealed_model_that_is_no_model_is_set_aside_and_trained_again() {
    let dir = project(false);
    let d = dir.path();
    let run = args(&["run", "experiments/quick.toml", "--no-plots"], &SMALL);
    run_ok(d, &run);
    let cache = d.join("results/.cache");
    let weights = em3_weights(&cache);
    let good_weights = std::fs::read(&weights).unwrap();
    forge_sealed(&weights, b"not a model");
    // The blocks gone, so that the run needs the model.
    std::fs::remove_dir_all(cache.join("monte_carlo")).unwrap();

    let log = run_ok(d, &run);
    assert!(
        log.contains("DCNet EM3: sealed, but not a model of this version"),
        "{log}"
    );
    assert!(log.contains("and trained again"), "{log}");
    assert_eq!(std::fs::read(&weights).unwrap(), good_weights);
    assert!(run_ok(d, &run).contains("nothing to do"));
}

/// A results folder is done only with its report and every figure it links to: a run
/// whose figures cannot be written fails (exit 2) and leaves the folder to do, keeping
/// what it computed, and a figure lost later is drawn again.
#[test]
fn a_folder_whose_figures_are_missing_is_not_done() {
    let dir = project(false);
    let d = dir.path();
    let run = args(
        &["run", "experiments/quick.toml", "--plots", "figures"],
        &SMALL,
    );
    // A file where the figures' folder goes: it cannot be written, even by root.
    std::fs::create_dir(d.join("figures")).unwrap();
    std::fs::write(d.join("figures/quick"), "").unwrap();
    let failed = dcnet(d, &run);
    assert_eq!(failed.status.code(), Some(2), "{}", stderr(&failed));
    assert!(
        stderr(&failed).contains("figures/quick"),
        "{}",
        stderr(&failed)
    );
    let plan = stdout(&dcnet(
        d,
        &args(&["plan", "experiments/quick.toml"], &SMALL),
    ));
    let results_row = plan
        .lines()
        .find(|l| l.contains("write results/quick"))
        .unwrap();
    assert!(results_row.contains("to do"), "{plan}");
    // Nothing computed was lost: every other task is done.
    let to_do: Vec<&str> = plan
        .lines()
        .filter(|l| l.starts_with("| ") && l.contains("to do"))
        .collect();
    assert_eq!(to_do, [results_row], "{plan}");

    std::fs::remove_file(d.join("figures/quick")).unwrap();
    let log = run_ok(d, &run);
    assert!(
        log.contains("1 task to do"),
        "only the results are left: {log}"
    );
    let figure = d.join("figures/quick/calibration.png");
    assert!(figure.is_file(), "{log}");
    std::fs::remove_file(&figure).unwrap();
    let log = run_ok(d, &run);
    assert!(log.contains("1 task to do"), "{log}");
    assert!(figure.is_file());
    assert!(run_ok(d, &run).contains("nothing to do"));
}

/// `--force` on a current folder computes everything again and writes the folder anew,
/// saying so; it never claims another process wrote it.
#[test]
fn force_on_a_current_folder_writes_it_again() {
    let dir = project(false);
    let d = dir.path();
    let run = args(&["run", "experiments/quick.toml", "--no-plots"], &SMALL);
    run_ok(d, &run);
    let manifest_path = d.join("results/quick/manifest.json");
    let started_at = |manifest: &str| {
        let json: serde_json::Value = serde_json::from_str(manifest).unwrap();
        json["started_at"].as_str().unwrap().to_string()
    };
    let before = std::fs::read_to_string(&manifest_path).unwrap();
    // Seconds apart: the new manifest's start differs from the old one's.
    std::thread::sleep(Duration::from_millis(1100));

    let log = run_ok(d, &args(&run, &["--force"]));
    assert!(!log.contains("another process"), "{log}");
    assert!(log.contains("results written to"), "{log}");
    let after = std::fs::read_to_string(&manifest_path).unwrap();
    assert_ne!(started_at(&before), started_at(&after), "{after}");
    assert!(run_ok(d, &run).contains("nothing to do"));
}

/// The manifest and the report say on which vector instructions the matrix products
/// ran, since models trained on machines that differ there differ in their last bits.
#[test]
fn the_manifest_and_the_report_name_the_products_instruction_set() {
    let dir = project(false);
    let d = dir.path();
    run_ok(
        d,
        &args(&["run", "experiments/quick.toml", "--no-plots"], &SMALL),
    );
    let manifest = std::fs::read_to_string(d.join("results/quick/manifest.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&manifest).unwrap();
    let instruction_set = dcnet_exp::kernels::instruction_set();
    assert_eq!(json["instruction_set"], instruction_set, "{manifest}");
    let report = std::fs::read_to_string(d.join("results/quick/report.md")).unwrap();
    assert!(
        report.contains(&format!("matrix products on {instruction_set}")),
        "{report}"
    );
}

/// Two runs into one OUT at once share the work: each training and Monte Carlo block is
/// computed by one of them while the other waits for it, and both end with the results
/// of one run alone.
#[test]
fn two_concurrent_runs_compute_each_task_once() {
    let alone = project(false);
    let run = args(&["run", "experiments/quick.toml", "--no-plots"], &SMALL);
    run_ok(alone.path(), &run);

    let dir = project(false);
    let d = dir.path();
    let both = [spawn(d, &run), spawn(d, &run)].map(|child| child.wait_with_output().unwrap());
    let mut logs = String::new();
    for output in &both {
        assert!(output.status.success(), "{}", stderr(output));
        logs += &stderr(output);
    }
    let trained = logs.matches(": trained; best validation loss").count();
    let models = 5;
    assert_eq!(trained, models, "each model trained once:\n{logs}");
    // Each run stores its DVLs' blocks as "monte carlo quick DVL: N estimators × 3 runs".
    let stored: usize = logs
        .lines()
        .filter(|l| l.starts_with("monte carlo quick "))
        .map(|l| l.split(": ").nth(1).unwrap().split(' ').next().unwrap())
        .map(|n| n.parse::<usize>().unwrap())
        .sum();
    // Per DVL: the baseline, least squares, the Kalman filter and DCNet per model, the
    // beam-model WLS and its Kalman filter, and the floor.
    let blocks = 2 * (1 + 3 * models + 3);
    assert_eq!(stored, blocks, "each block computed once:\n{logs}");
    assert_same_results(
        &alone.path().join("results/quick"),
        &d.join("results/quick"),
    );
}
