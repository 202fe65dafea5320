//! Seed replicates (`training.replicates`) as a user meets them: one replicate is a run
//! without replicates byte for byte; N replicates plan N trainings per error model,
//! going from 2 to 3 trains only the third, and the tables name the replicates and
//! carry the confidence interval.

use crate::common;
use arrow_array::{Array, UInt32Array};
use common::*;
use std::path::Path;

/// The quick spec, small enough to train in a few seconds.
const SMALL: [&str; 6] = [
    "--set",
    "training.epochs=3",
    "--set",
    "calibration.monte_carlo_runs=3",
    "--set",
    "dataset.trajectories=[\"S1\"]",
];

fn run(dir: &Path, extra: &[&str]) -> String {
    let args = [
        &["run", "experiments/quick.toml", "--no-plots"],
        &SMALL[..],
        extra,
    ]
    .concat();
    let output = dcnet(dir, &args);
    assert!(output.status.success(), "{args:?}: {}", stderr(&output));
    stderr(&output)
}

/// The plan's (task, status) rows.
fn plan(dir: &Path, extra: &[&str]) -> Vec<(String, String)> {
    let args = [&["plan", "experiments/quick.toml"], &SMALL[..], extra].concat();
    let output = dcnet(dir, &args);
    assert!(output.status.success(), "{}", stderr(&output));
    plan_rows(&stdout(&output))
}

fn replicates(batch: &arrow_array::RecordBatch) -> Vec<Option<u32>> {
    let column = batch
        .column_by_name("replicate")
        .expect("a replicate column");
    let column = column.as_any().downcast_ref::<UInt32Array>().unwrap();
    (0..column.len())
        .map(|i| column.is_valid(i).then(|| column.value(i)))
        .collect()
}

#[test]
fn one_replicate_is_a_run_without_replicates_byte_for_byte() {
    let plain = project(false);
    let one = project(false);
    run(plain.path(), &[]);
    run(one.path(), &["--set", "training.replicates=1"]);
    let folder = |dir: &Path| dir.join("results/quick");
    for file in [
        "monte_carlo.parquet",
        "calibration.parquet",
        "evaluation.parquet",
        "trajectories.parquet",
        "spec.toml",
        "report.tex",
    ] {
        let a = std::fs::read(folder(plain.path()).join(file)).unwrap();
        let b = std::fs::read(folder(one.path()).join(file)).unwrap();
        assert!(a == b, "{file} differs");
    }
    // training.parquet: the same columns and values but the wall-clock ones.
    let training = |dir: &Path| {
        let batch = read_parquet(&folder(dir).join("training.parquet"));
        let names: Vec<String> = batch
            .schema()
            .fields()
            .iter()
            .map(|f| f.name().clone())
            .collect();
        (
            names,
            strings(&batch, "error_model"),
            floats(&batch, "train_loss"),
            floats(&batch, "validation_loss"),
            bools(&batch, "is_best"),
            strings(&batch, "stop_reason"),
        )
    };
    assert_eq!(training(plain.path()), training(one.path()));
    let spec = std::fs::read_to_string(folder(one.path()).join("spec.toml")).unwrap();
    assert!(!spec.contains("replicates"), "{spec}");
    let runs = read_parquet(&folder(one.path()).join("monte_carlo.parquet"));
    assert!(runs.column_by_name("replicate").is_none());
    let calibration = read_parquet(&folder(one.path()).join("calibration.parquet"));
    assert!(calibration.column_by_name("rmse_ci_cm_s").is_none());
}

#[test]
fn each_replicate_is_a_training_and_a_third_trains_only_the_third() {
    let project = project(false);
    let dir = project.path();
    let only_em = ["--set", "estimators.error_models=[\"EM1\", \"EM5\"]"];
    let two = [&only_em[..], &["--set", "training.replicates=2"]].concat();
    let three = [&only_em[..], &["--set", "training.replicates=3"]].concat();

    let rows = plan(dir, &three);
    let trainings: Vec<&str> = rows
        .iter()
        .map(|(label, _)| label.as_str())
        .filter(|label| label.starts_with("train DCNet"))
        .collect();
    assert_eq!(
        trainings,
        [
            "train DCNet EM1 replicate 1/3",
            "train DCNet EM1 replicate 2/3",
            "train DCNet EM1 replicate 3/3",
            "train DCNet EM5 replicate 1/3",
            "train DCNet EM5 replicate 2/3",
            "train DCNet EM5 replicate 3/3",
        ]
    );

    run(dir, &two);
    let rows = plan(dir, &three);
    let to_do: Vec<&str> = rows
        .iter()
        .filter(|(label, status)| label.starts_with("train DCNet") && status == "to do")
        .map(|(label, _)| label.as_str())
        .collect();
    assert_eq!(
        to_do,
        [
            "train DCNet EM1 replicate 3/3",
            "train DCNet EM5 replicate 3/3"
        ]
    );
    run(dir, &three);
    let models = std::fs::read_dir(dir.join("results/.cache/models"))
        .unwrap()
        .filter(|e| {
            let path = e.as_ref().unwrap().path();
            path.extension().is_some_and(|x| x == "bin")
        })
        .count();
    assert_eq!(models, 6, "each replicate trained once");

    // Replicate 0 is the model of a run without replicates: nothing to train.
    let rows = plan(dir, &only_em);
    assert!(
        rows.iter()
            .filter(|(label, _)| label.starts_with("train DCNet"))
            .all(|(_, status)| status == "done"),
        "{rows:?}"
    );

    let folder = dir.join("results/quick");
    let runs = read_parquet(&folder.join("monte_carlo.parquet"));
    let estimators = strings(&runs, "estimator");
    let replicate = replicates(&runs);
    let mut seen: Vec<u32> = estimators
        .iter()
        .zip(&replicate)
        .filter(|(e, _)| e.as_deref() == Some("dcnet"))
        .map(|(_, r)| r.expect("every DCNet row names its replicate"))
        .collect();
    seen.sort();
    seen.dedup();
    assert_eq!(seen, [0, 1, 2]);
    assert!(
        estimators
            .iter()
            .zip(&replicate)
            .all(|(e, r)| (e.as_deref() == Some("dcnet")) == r.is_some()),
        "only DCNet rows name a replicate"
    );
    assert!(
        estimators
            .iter()
            .any(|e| e.as_deref() == Some("dcnet_ensemble"))
    );

    // One calibration row per DCNet window, with an interval; none for the others.
    let calibration = read_parquet(&folder.join("calibration.parquet"));
    let estimators = strings(&calibration, "estimator");
    let ci = floats(&calibration, "rmse_ci_cm_s");
    let windows = 5;
    let dcnet_rows = estimators
        .iter()
        .filter(|e| e.as_deref() == Some("dcnet"))
        .count();
    assert_eq!(dcnet_rows, 2 * 2 * windows, "2 DVLs × 2 error models");
    for (estimator, ci) in estimators.iter().zip(&ci) {
        assert_eq!(estimator.as_deref() == Some("dcnet"), ci.is_some());
    }
    let report = std::fs::read_to_string(folder.join("report.md")).unwrap();
    assert!(report.contains(" ± "), "{report}");
    assert!(report.contains("mean over 3 replicates"), "{report}");
}

#[test]
fn a_sweep_with_replicates_tabulates_dcnet_intervals() {
    let project = project(false);
    let dir = project.path();
    write_quick_sweep(dir, "\"calibration.monte_carlo_runs\" = [3, 4]\n");
    let args = [
        "run",
        "experiments/sweep.toml",
        "--no-plots",
        "--set",
        "training.epochs=2",
        "--set",
        "dataset.trajectories=[\"S1\"]",
        "--set",
        "estimators.error_models=[\"EM5\"]",
        "--set",
        "training.replicates=2",
    ];
    let output = dcnet(dir, &args);
    assert!(output.status.success(), "{}", stderr(&output));
    let table = read_parquet(&dir.join("results/quick-sweep/sweep.parquet"));
    let estimators = strings(&table, "estimator");
    for column in ["calibration_rmse_ci_cm_s", "evaluation_rmse_ci_cm_s"] {
        let ci = floats(&table, column);
        for (estimator, ci) in estimators.iter().zip(&ci) {
            let dcnet = estimator.as_deref() == Some("dcnet");
            assert_eq!(dcnet, ci.is_some(), "{column} of {estimator:?}");
            assert!(ci.is_none_or(|ci| ci.is_finite() && ci >= 0.0));
        }
    }
    assert_eq!(
        estimators
            .iter()
            .filter(|e| e.as_deref() == Some("dcnet"))
            .count(),
        2 * 2,
        "2 points × 2 DVLs"
    );
}

#[test]
fn a_shard_holds_every_replicate_of_its_models_and_their_ensemble() {
    let project = project(false);
    let dir = project.path();
    let mut seen = Vec::new();
    for k in 0..3 {
        let shard = format!("{k}/3");
        let rows = plan(
            dir,
            &["--set", "training.replicates=2", "--shard", shard.as_str()],
        );
        let labels: Vec<&str> = rows
            .iter()
            .map(|(label, _)| label.as_str())
            .filter(|l| l.starts_with("train DCNet") || l.starts_with("monte carlo"))
            .collect();
        for model in ["EM1", "EM2", "EM3", "EM4", "EM5"] {
            let has = |label: String| labels.contains(&label.as_str());
            let trains = has(format!("train DCNet {model} replicate 1/2"));
            assert_eq!(trains, has(format!("train DCNet {model} replicate 2/2")));
            for dvl in ["DVL1", "DVL2"] {
                assert_eq!(
                    trains,
                    has(format!("monte carlo {dvl} dcnet_ensemble {model}")),
                    "shard {shard}: {labels:?}"
                );
            }
        }
        seen.extend(labels.iter().map(|l| l.to_string()));
    }
    let count = seen.len();
    seen.sort();
    seen.dedup();
    assert_eq!(seen.len(), count, "a task in two shards");
    // 10 trainings; per DVL the baseline, least squares and the Kalman filter per
    // model, DCNet's 2 replicates and ensemble per model, the beam-model WLS and its
    // Kalman filter, and the floor.
    assert_eq!(
        count,
        10 + 2 * (1 + 5 + 5 + 5 * 3 + 3),
        "every task in a shard"
    );
}

#[test]
fn a_sweep_over_replicates_shares_replicate_zero_with_the_point_without() {
    let project = project(false);
    let dir = project.path();
    write_quick_sweep(dir, "\"training.replicates\" = [1, 2]\n");
    let args = [
        "run",
        "experiments/sweep.toml",
        "--no-plots",
        "--set",
        "training.epochs=2",
        "--set",
        "calibration.monte_carlo_runs=3",
        "--set",
        "dataset.trajectories=[\"S1\"]",
        "--set",
        "estimators.error_models=[\"EM5\"]",
    ];
    let output = dcnet(dir, &args);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stderr(&output);
    assert_eq!(text.matches(": trained;").count(), 2, "two models: {text}");
    let sweep = dir.join("results/quick-sweep");
    let folders: Vec<_> = std::fs::read_dir(&sweep)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    assert_eq!(folders.len(), 2);
    for folder in folders {
        let two = folder.to_string_lossy().ends_with('2');
        let runs = read_parquet(&folder.join("monte_carlo.parquet"));
        assert_eq!(
            runs.column_by_name("replicate").is_some(),
            two,
            "{folder:?}"
        );
        if two {
            let estimators = strings(&runs, "estimator");
            let dcnet: Vec<Option<u32>> = replicates(&runs)
                .into_iter()
                .zip(&estimators)
                .filter(|(_, e)| e.as_deref() == Some("dcnet"))
                .map(|(r, _)| r)
                .collect();
            assert!(dcnet.contains(&Some(0)) && dcnet.contains(&Some(1)));
            assert!(dcnet.iter().all(Option::is_some));
        }
    }
}
