//! An installation study run as a user splits it: in shards that `collect` puts
//! together, resumed from the calibrations an earlier run stored (a damaged one
//! computed again), and swept over its settings, each point a study of its own beside
//! the sweep's table, index and figure. All on synthetic recordings with known terms.

use crate::common;

use common::installed::{INSTALLED, write_installed, write_study_spec};
use common::*;
use std::path::Path;

/// The tables and report of a study's folder, by their SHA-256.
fn digests(folder: &Path) -> Vec<String> {
    [
        "heldout.parquet",
        "terms.parquet",
        "summary.parquet",
        "trace.parquet",
        "failures.parquet",
        "report.md",
    ]
    .iter()
    .map(|f| sha256(&std::fs::read(folder.join(f)).unwrap()))
    .collect()
}

fn run(d: &Path, args: &[&str]) -> String {
    let output = dcnet(d, args);
    assert!(output.status.success(), "{args:?}: {}", stderr(&output));
    format!("{}{}", stdout(&output), stderr(&output))
}

#[test]
fn shards_collected_give_the_bytes_of_one_whole_run_and_collect_names_what_is_missing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 4, &[], INSTALLED, 7);
    write_study_spec(d, "syn", "syn", 4, "");
    let spec = "experiments/syn.toml";
    run(d, &["run", spec, "--out", "whole", "--no-plots"]);

    let planned = run(d, &["plan", spec, "--out", "split"]);
    assert!(
        planned.contains("syn: 4 calibrations, 4 to do"),
        "{planned}"
    );
    let shard = run(d, &["run", spec, "--out", "split", "--shard", "1/2"]);
    assert!(shard.contains("shard 1/2: 2 calibrations done"), "{shard}");
    assert!(!d.join("split/syn").exists(), "a shard writes no folder");
    let planned = run(d, &["plan", spec, "--out", "split"]);
    let rows = plan_rows(&planned);
    assert_eq!(
        rows,
        [
            ("S1".to_string(), "to do".to_string()),
            ("S2".into(), "done".into()),
            ("S3".into(), "to do".into()),
            ("S4".into(), "done".into()),
        ]
    );

    let early = dcnet(d, &["collect", spec, "--out", "split", "--no-plots"]);
    let message = stderr(&early);
    assert_eq!(early.status.code(), Some(1), "{message}");
    for part in [
        "2 of 4 calibrations are not in the cache",
        "S1; S3",
        "--shard K/N",
    ] {
        assert!(message.contains(part), "{part}: {message}");
    }
    assert!(!d.join("split/syn").exists());

    let again = run(d, &["run", spec, "--out", "split", "--shard", "1/2"]);
    assert!(again.contains("nothing to do"), "{again}");
    let empty = run(d, &["run", spec, "--out", "split", "--shard", "7/9"]);
    assert!(
        empty.contains("shard 7/9 has no calibrations (syn has 4 calibrations"),
        "{empty}"
    );
    run(d, &["run", spec, "--out", "split", "--shard", "0/2"]);
    let collected = run(d, &["collect", spec, "--out", "split", "--no-plots"]);
    assert!(collected.contains("held-out trajectories"), "{collected}");
    assert_eq!(digests(&d.join("whole/syn")), digests(&d.join("split/syn")));
    let current = run(d, &["collect", spec, "--out", "split", "--no-plots"]);
    assert!(current.contains("nothing to do"), "{current}");
}

#[test]
fn a_run_resumes_from_the_calibrations_stored_and_computes_a_damaged_one_again() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 3, &[], INSTALLED, 8);
    write_study_spec(d, "syn", "syn", 3, "");
    let spec = "experiments/syn.toml";
    run(d, &["run", spec, "--out", "whole", "--no-plots"]);
    // What a run cut short leaves: some calibrations stored, no folder.
    run(d, &["run", spec, "--out", "cut", "--shard", "0/3"]);
    let planned = run(d, &["plan", spec, "--out", "cut"]);
    assert!(planned.contains("3 calibrations, 2 to do"), "{planned}");
    run(d, &["run", spec, "--out", "cut", "--no-plots"]);
    assert_eq!(digests(&d.join("whole/syn")), digests(&d.join("cut/syn")));

    // A stored calibration with a flipped byte is set aside and computed again.
    let stored: Vec<_> = std::fs::read_dir(d.join("cut/.cache/installation"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "msgpack"))
        .collect();
    assert_eq!(stored.len(), 3);
    let mut bytes = std::fs::read(&stored[0]).unwrap();
    bytes[10] ^= 0x40;
    std::fs::write(&stored[0], bytes).unwrap();
    let planned = run(d, &["plan", spec, "--out", "cut"]);
    assert!(planned.contains("to do (damaged)"), "{planned}");
    std::fs::remove_dir_all(d.join("cut/syn")).unwrap();
    let rerun = run(d, &["run", spec, "--out", "cut", "--no-plots"]);
    assert!(
        rerun.contains("damaged calibration") && rerun.contains("computed again"),
        "{rerun}"
    );
    assert_eq!(digests(&d.join("whole/syn")), digests(&d.join("cut/syn")));

    // `--force` computes every calibration again, stored or not.
    let stored_at = |path: &Path| std::fs::metadata(path).unwrap().modified().unwrap();
    let before: Vec<_> = stored.iter().map(|p| stored_at(p)).collect();
    std::thread::sleep(std::time::Duration::from_millis(20));
    run(d, &["run", spec, "--out", "cut", "--no-plots", "--force"]);
    for (path, before) in stored.iter().zip(before) {
        assert!(
            stored_at(path) > before,
            "{} was not computed again",
            path.display()
        );
    }
    assert_eq!(digests(&d.join("whole/syn")), digests(&d.join("cut/syn")));
}

#[test]
fn a_point_without_a_fit_is_named_and_the_other_points_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 2, &[], INSTALLED, 11);
    write_study_spec(
        d,
        "syn",
        "syn",
        2,
        "\n[sweep.values]\n\"calibration.window_s\" = [[1.0], [400.0]]\n",
    );
    let output = dcnet(d, &["run", "experiments/syn.toml", "--no-plots"]);
    let message = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{message}");
    assert!(
        message.contains(
            "point syn/window_s=1.0: installation lever+offset+bias+scale could not be fitted"
        ),
        "{message}"
    );
    assert!(
        message.contains("1 other point written; the sweep's table is not"),
        "{message}"
    );
    assert!(d.join("results/syn/window_s=400.0/manifest.json").is_file());
    assert!(!d.join("results/syn/window_s=1.0").exists());
    assert!(!d.join("results/syn/sweep.json").exists());
}

#[test]
fn a_sweep_of_studies_writes_each_point_beside_its_table_index_and_figure() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 3, &[], INSTALLED, 9);
    write_study_spec(
        d,
        "syn",
        "syn",
        3,
        "\n[sweep.values]\n\"calibration.window_s\" = [[100.0], [400.0]]\n\"noise.dvl_cm_s\" = [1.0, 2.0]\n",
    );
    let spec = "experiments/syn.toml";
    let validated = run(d, &["validate", spec]);
    assert!(
        validated.contains("4 points of a sweep over calibration.window_s, noise.dvl_cm_s"),
        "{validated}"
    );
    let printed = run(d, &["run", spec, "--plots", "plots"]);
    let points = [
        "window_s=100.0,dvl_cm_s=1.0",
        "window_s=100.0,dvl_cm_s=2.0",
        "window_s=400.0,dvl_cm_s=1.0",
        "window_s=400.0,dvl_cm_s=2.0",
    ];
    for point in points {
        assert!(
            d.join("results/syn")
                .join(point)
                .join("manifest.json")
                .is_file(),
            "{point}"
        );
        assert!(printed.contains(point), "{printed}");
    }
    let index: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("results/syn/sweep.json")).unwrap()).unwrap();
    assert_eq!(index["kind"], "installation");
    assert_eq!(index["points"].as_array().unwrap().len(), 4);
    let table = read_parquet(&d.join("results/syn/sweep.parquet"));
    // Four points × (no calibration, baseline, EM5, the installation model) × one window.
    assert_eq!(table.num_rows(), 16);
    // A list is stored as its TOML text, a number as a number.
    let windows = strings(&table, "calibration.window_s");
    assert_eq!(windows[0].as_deref(), Some("[100.0]"), "{windows:?}");
    assert_eq!(floats(&table, "noise.dvl_cm_s")[..4], [Some(1.0); 4]);
    assert!(d.join("plots/syn/installation_sweep.svg").is_file());
    assert!(
        d.join("plots/syn")
            .join(points[3])
            .join("installation_residual.svg")
            .is_file()
    );

    // A point is the study a single run of its settings gives.
    write_study_spec(d, "single", "syn", 3, "");
    run(
        d,
        &[
            "run",
            "experiments/single.toml",
            "--out",
            "single",
            "--no-plots",
            "--set",
            "calibration.window_s=[400.0]",
            "--set",
            "noise.dvl_cm_s=2.0",
        ],
    );
    let sweep_point = d.join("results/syn").join(points[3]);
    let single = d.join("single/single");
    for file in [
        "heldout.parquet",
        "terms.parquet",
        "summary.parquet",
        "trace.parquet",
    ] {
        assert_eq!(
            sha256(&std::fs::read(sweep_point.join(file)).unwrap()),
            sha256(&std::fs::read(single.join(file)).unwrap()),
            "{file}"
        );
    }

    let again = run(d, &["run", spec, "--no-plots"]);
    assert!(again.contains("nothing to do"), "{again}");
    std::fs::remove_dir_all(d.join("plots")).unwrap();
    run(d, &["plot", "results/syn", "--out", "plots"]);
    assert!(d.join("plots/syn/installation_sweep.png").is_file());
    let compared = dcnet(
        d,
        &[
            "compare",
            "results/syn",
            "results/syn/window_s=100.0,dvl_cm_s=1.0",
        ],
    );
    let message = stderr(&compared);
    assert_eq!(compared.status.code(), Some(1), "{message}");
    assert!(message.contains("a sweep folder"), "{message}");
}

/// The sweep's printed table names a column for every cell of its rows: the header
/// and each row have as many columns, the calibrations among them.
#[test]
fn a_sweep_of_studies_prints_a_table_whose_header_has_a_column_per_cell() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 3, &[], INSTALLED, 12);
    write_study_spec(
        d,
        "syn",
        "syn",
        3,
        "\n[sweep.values]\n\"noise.dvl_cm_s\" = [1.0, 2.0]\n",
    );
    let output = dcnet(d, &["run", "experiments/syn.toml", "--no-plots"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let printed = stdout(&output);
    let table: Vec<&str> = printed
        .lines()
        .skip_while(|l| !l.starts_with("held-out trajectories, each point"))
        .skip(1)
        .take_while(|l| l.starts_with('|'))
        .collect();
    let columns = |line: &str| line.matches('|').count() - 1;
    let [header, rule, rows @ ..] = &table[..] else {
        panic!("no sweep table in\n{printed}");
    };
    assert_eq!(columns(header), 7, "{header}");
    assert!(header.contains("calibrations"), "{header}");
    assert_eq!(columns(rule), 7, "{rule}");
    assert!(rows.len() >= 2, "{printed}");
    for row in rows {
        assert_eq!(columns(row), columns(header), "{row}\n{printed}");
        let last = row
            .trim_end()
            .trim_end_matches('|')
            .rsplit('|')
            .next()
            .unwrap();
        assert_eq!(last.trim().parse::<usize>().ok(), Some(3), "{row}");
    }
    for point in ["dvl_cm_s=1.0", "dvl_cm_s=2.0"] {
        assert!(rows.iter().any(|r| r.contains(point)), "{point}: {printed}");
    }
}

#[test]
fn a_bad_sweep_value_is_placed_on_its_line_with_its_point() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 2, &[], INSTALLED, 10);
    write_study_spec(
        d,
        "syn",
        "syn",
        2,
        "\n[sweep.values]\n\"noise.dvl_cm_s\" = [2.0, -1.0]\n",
    );
    let spec_text = std::fs::read_to_string(d.join("experiments/syn.toml")).unwrap();
    let line = spec_text.lines().position(|l| l.contains("-1.0")).unwrap() + 1;
    let output = dcnet(d, &["run", "experiments/syn.toml", "--no-plots"]);
    let message = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{message}");
    assert!(
        message.contains(&format!(
            "experiments/syn.toml:{line} (sweep point dvl_cm_s=-1.0): noise.dvl_cm_s: -1 must be a finite positive number"
        )),
        "{message}"
    );
    assert!(!d.join("results").exists());
}
