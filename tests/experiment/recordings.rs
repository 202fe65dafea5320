//! A user's own recording as a CSV file: it runs to the same results as the same
//! samples in a `.npy` file, its hash and its column choice enter the cache keys, and a
//! bad row or header is refused with exit code 1, naming the file, line and column,
//! before anything is written.

use crate::common;

use common::*;
use std::path::Path;

/// AUV-like body-frame velocity, m/s: a cruise speed that changes slowly, sway and heave.
fn velocities(samples: usize) -> Vec<[f64; 3]> {
    (0..samples)
        .map(|i| {
            let t = i as f64;
            [
                1.2 + 0.4 * (t / 150.0).sin(),
                0.05 * (t / 37.0).sin(),
                0.05 * (std::f64::consts::TAU * t / 45.0).sin(),
            ]
        })
        .collect()
}

/// A CSV with the velocity columns out of order among others: `time_s, vz_m_s,
/// vx_m_s, vy_m_s, vx_copy_m_s` (a second copy of x).
fn csv_text(velocities: &[[f64; 3]]) -> String {
    let mut text = String::from("time_s,vz_m_s,vx_m_s,vy_m_s,vx_copy_m_s\n");
    for (i, [x, y, z]) in velocities.iter().enumerate() {
        text.push_str(&format!("{i},{z},{x},{y},{x}\n"));
    }
    text
}

fn write_npy(path: &Path, velocities: &[[f64; 3]]) {
    use npyz::WriterBuilder;
    let mut out = Vec::new();
    let mut writer = npyz::WriteOptions::new()
        .default_dtype()
        .shape(&[velocities.len() as u64, 3])
        .writer(&mut out)
        .begin_nd()
        .unwrap();
    writer.extend(velocities.iter().flatten().copied()).unwrap();
    writer.finish().unwrap();
    std::fs::write(path, out).unwrap();
}

/// A small spec on the recording `file`: training, calibration and test segments of
/// it, the baseline, least squares, DCNet EM5 (2 epochs) and the floor.
fn spec(file: &str, extra: &str) -> String {
    format!(
        r#"name = "own"
seed = 3

[[data.trajectories]]
name = "Train"
file = "{file}"
samples = [0, 400]{extra}

[[data.trajectories]]
name = "Cal"
file = "{file}"
samples = [400, 520]

[[data.trajectories]]
name = "Test"
file = "{file}"
samples = [520, 700]

[grid]
scale_pct = {{ values = [1.0] }}
bias_cm_s = {{ values = [0.5] }}
noise_cm_s = {{ values = [0.02] }}

[dataset]
trajectories = ["Train"]

[[dvl]]
name = "DVL"
scale_pct = 1.0
bias_cm_s = 0.7
noise_cm_s = 0.02

[calibration]
trajectory = "Cal"
window_sizes_s = [20.0, 60.0]
monte_carlo_runs = 3

[evaluation]
trajectories = ["Test"]

[estimators]
kinds = ["baseline", "least_squares", "beam_wls", "dcnet", "floor"]
error_models = ["EM5"]

[training]
epochs = 2
batch_size = 16
"#
    )
}

/// Runs `args` in `dir` and expects exit code 1 with exactly `expected` on stderr, and
/// no results written; the message is the snapshot `name`
/// (`tests/experiment/snapshots/experiment__recordings__<name>.snap`).
fn assert_refused(dir: &Path, name: &str, args: &[&str], expected: &str) {
    let output = dcnet(dir, args);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert_eq!(stderr(&output), format!("{expected}\n"));
    let command = format!("dcnet-exp {}", args.join(" "));
    assert_error_snapshot!(name, &command, &stderr(&output), dir);
    assert!(!dir.join("results").exists(), "a refused run wrote results");
}

#[test]
fn a_csv_recording_gives_the_results_of_the_same_samples_in_a_npy_file() {
    let project = tempfile::tempdir().unwrap();
    let dir = project.path();
    let samples = velocities(700);
    std::fs::write(dir.join("rec.csv"), csv_text(&samples)).unwrap();
    write_npy(&dir.join("rec.npy"), &samples);
    std::fs::write(dir.join("csv.toml"), spec("rec.csv", "")).unwrap();
    std::fs::write(dir.join("npy.toml"), spec("rec.npy", "")).unwrap();
    for (spec, out) in [("csv.toml", "from-csv"), ("npy.toml", "from-npy")] {
        let output = dcnet(dir, &["run", spec, "--no-plots", "--out", out]);
        assert!(output.status.success(), "{}", stderr(&output));
    }
    for table in [
        "calibration.parquet",
        "evaluation.parquet",
        "monte_carlo.parquet",
    ] {
        assert_eq!(
            std::fs::read(dir.join("from-csv/own").join(table)).unwrap(),
            std::fs::read(dir.join("from-npy/own").join(table)).unwrap(),
            "{table} differs between the CSV and the .npy recording"
        );
    }
    let rows = calibration_rows(&dir.join("from-csv/own"));
    assert_eq!(
        rows.len(),
        2 * 6,
        "two windows × five estimators and the bound: {rows:?}"
    );

    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("from-csv/own/manifest.json")).unwrap())
            .unwrap();
    let files = manifest["data_files"].as_array().unwrap();
    assert_eq!(files.len(), 1, "{files:?}");
    assert_eq!(
        files[0]["path"].as_str().unwrap(),
        dir.join("rec.csv").to_str().unwrap()
    );
    assert_eq!(
        files[0]["sha256"].as_str().unwrap(),
        sha256(&std::fs::read(dir.join("rec.csv")).unwrap())
    );
    // The resolved spec names the columns read.
    let resolved = std::fs::read_to_string(dir.join("from-csv/own/spec.toml")).unwrap();
    assert!(
        resolved.contains("columns = [\n    \"vx_m_s\",\n    \"vy_m_s\",\n    \"vz_m_s\",\n]"),
        "{resolved}"
    );

    // The plan: done; another column for x redoes what the Train segment feeds (its
    // dataset, DCNet and DCNet's block); a changed file redoes everything.
    let plan = |extra: &[&str]| {
        let mut args = vec!["plan", "csv.toml", "--out", "from-csv"];
        args.extend(extra);
        let output = dcnet(dir, &args);
        assert!(output.status.success(), "{}", stderr(&output));
        stdout(&output)
    };
    assert!(plan(&[]).contains("own: 8 tasks, 0 to do"), "{}", plan(&[]));
    let copy = [
        "--set",
        "data.trajectories[0].columns=[\"vx_copy_m_s\", \"vy_m_s\", \"vz_m_s\"]",
    ];
    let text = plan(&copy);
    assert!(text.contains("own: 8 tasks, 4 to do"), "{text}");
    assert!(
        text.lines()
            .any(|l| l.contains("train DCNet EM5") && l.contains("to do")),
        "{text}"
    );
    let mut changed = samples.clone();
    changed[450][0] += 0.01;
    std::fs::write(dir.join("rec.csv"), csv_text(&changed)).unwrap();
    let text = plan(&[]);
    assert!(text.contains("own: 8 tasks, 8 to do"), "{text}");
}

#[test]
fn a_bad_row_or_header_is_named_and_nothing_is_written() {
    let project = tempfile::tempdir().unwrap();
    let dir = project.path();
    let mut text = csv_text(&velocities(700));
    // Line 38 of the file (the header is line 1) is sample 36.
    let row = text.lines().nth(37).unwrap().to_string();
    let fields: Vec<&str> = row.split(',').collect();
    let bad = format!(
        "{},{},{},abc,{}",
        fields[0], fields[1], fields[2], fields[4]
    );
    text = text.replacen(&row, &bad, 1);
    std::fs::write(dir.join("bad.csv"), &text).unwrap();
    std::fs::write(dir.join("own.toml"), spec("bad.csv", "")).unwrap();
    let file = dir.join("bad.csv");
    assert_refused(
        dir,
        "csv_field_not_a_number",
        &["run", "own.toml"],
        &format!(
            "error: {}:38: vy_m_s: \"abc\" is not a number",
            file.display()
        ),
    );
    std::fs::write(
        dir.join("bad.csv"),
        text.replacen(
            &bad,
            &format!("{},{},{}", fields[0], fields[1], fields[2]),
            1,
        ),
    )
    .unwrap();
    assert_refused(
        dir,
        "csv_field_missing",
        &["run", "own.toml"],
        &format!(
            "error: {}:38: vy_m_s: missing: the row has 3 fields, the header 5",
            file.display()
        ),
    );

    std::fs::write(dir.join("rec.csv"), csv_text(&velocities(700))).unwrap();
    std::fs::write(dir.join("own.toml"), spec("rec.csv", "")).unwrap();
    assert_refused(
        dir,
        "csv_column_not_in_header",
        &[
            "run",
            "own.toml",
            "--set",
            "data.trajectories[0].columns=[\"u\", \"vy_m_s\", \"vz_m_s\"]",
        ],
        &format!(
            "error: {}:1: u: not in the header, which has time_s, vz_m_s, vx_m_s, vy_m_s, vx_copy_m_s",
            dir.join("rec.csv").display()
        ),
    );
}

#[test]
fn columns_are_for_csv_files_only_and_each_named_once() {
    let project = tempfile::tempdir().unwrap();
    let dir = project.path();
    let samples = velocities(700);
    write_npy(&dir.join("rec.npy"), &samples);
    std::fs::write(dir.join("rec.csv"), csv_text(&samples)).unwrap();
    std::fs::write(
        dir.join("own.toml"),
        spec("rec.npy", "\ncolumns = [\"a\", \"b\", \"c\"]"),
    )
    .unwrap();
    assert_refused(
        dir,
        "columns_for_npy",
        &["validate", "own.toml"],
        &format!(
            "error: own.toml:8: data.trajectories[0].columns: is for .csv files; {} is read as .npy",
            dir.join("rec.npy").display()
        ),
    );
    std::fs::write(
        dir.join("own.toml"),
        spec("rec.csv", "\ncolumns = [\"vx_m_s\", \"vx_m_s\", \"\"]"),
    )
    .unwrap();
    let output = dcnet(dir, &["validate", "own.toml"]);
    assert_eq!(output.status.code(), Some(1));
    assert_eq!(
        stderr(&output),
        "error: own.toml:8: data.trajectories[0].columns[1]: \"vx_m_s\" is named twice: x, y and z need a column each\n\
         error: own.toml:8: data.trajectories[0].columns[2]: is empty: name a column of the header\n"
    );
    assert_error_snapshot!(
        "columns_named_twice_and_empty",
        "dcnet-exp validate own.toml",
        &stderr(&output),
        dir
    );

    let project = common::project(false);
    let output = dcnet(
        project.path(),
        &[
            "validate",
            "experiments/quick.toml",
            "--set",
            "data.trajectories[0].columns=[\"a\", \"b\", \"c\"]",
        ],
    );
    assert_eq!(output.status.code(), Some(1));
    assert!(
        stderr(&output).contains(
            "data.trajectories[0].columns: is for .csv files; a synthetic trajectory has synthetic_duration_s only"
        ),
        "{}",
        stderr(&output)
    );
    assert_error_snapshot!(
        "set_columns_for_synthetic",
        "dcnet-exp validate experiments/quick.toml --set data.trajectories[0].columns=[\"a\", \"b\", \"c\"]",
        &stderr(&output),
        project.path()
    );
}

#[test]
fn the_example_spec_reads_its_recording() {
    let output = dcnet(&repo(), &["validate", "experiments/own-recording.toml"]);
    assert!(output.status.success(), "{}", stderr(&output));
    // Survey1 (1500 rows) and Survey2 (900) give 166 + 99 windows of 10 s every 9 s.
    let printed = stdout(&output);
    let mut lines = printed.lines();
    assert_eq!(
        lines.next(),
        Some(
            "experiments/own-recording.toml: ok (5 trajectories, 3180 training windows, 1 DVL, 20 Monte Carlo runs)"
        )
    );
    // Then the memory it needs and how long its training takes here.
    assert!(
        lines.next().unwrap().starts_with("  memory: about "),
        "{printed}"
    );
    assert!(
        lines
            .next()
            .unwrap()
            .starts_with("  training: 5 models, about "),
        "{printed}"
    );
}
