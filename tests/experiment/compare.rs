//! `compare`: two folders of one spec differ in no key and no cell; a changed DVL2 noise
//! lists exactly the changed keys and marks exactly the DVL2 cells it must and no DVL1
//! cell; what is printed is what is written, to `compare.md` by default; a folder that
//! is not a results folder, or a sweep folder, is refused with exit code 1, naming it.

use crate::common;

use common::*;

/// The rows of the Markdown table under `## {section}`, each cell trimmed.
fn section_rows(markdown: &str, section: &str) -> Vec<Vec<String>> {
    let start = markdown
        .find(&format!("## {section}\n"))
        .unwrap_or_else(|| panic!("no section {section} in\n{markdown}"));
    markdown[start..]
        .lines()
        .skip(1)
        .take_while(|line| !line.starts_with("## "))
        .filter(|line| line.starts_with('|'))
        .skip(2) // header and delimiter
        .map(|line| {
            line.trim_matches('|')
                .split('|')
                .map(|cell| cell.trim().to_string())
                .collect()
        })
        .collect()
}

/// The cells of a calibration or evaluation table marked ⚠, as "DVL estimator EM at",
/// `at` the window or the trajectory.
fn marked(rows: &[Vec<String>], mark_column: usize) -> Vec<String> {
    rows.iter()
        .filter(|row| row[mark_column] == "⚠")
        .map(|row| row[..4].join(" "))
        .collect()
}

#[test]
fn two_folders_of_one_spec_differ_in_no_key_and_no_cell_and_the_file_is_what_is_printed() {
    let project = project(false);
    small_quick_run(project.path(), &["--no-plots"]);
    small_quick_run(project.path(), &["--no-plots", "--out", "again"]);
    let output = dcnet(
        project.path(),
        &[
            "compare",
            "results/quick",
            "again/quick",
            "--out",
            "reports/quick.md",
        ],
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let markdown = stdout(&output);
    assert_eq!(
        std::fs::read_to_string(project.path().join("reports/quick.md")).unwrap(),
        markdown
    );
    assert!(!project.path().join("compare.md").exists());
    assert!(
        markdown.contains("## Spec\n\nThe resolved specs are the same.\n"),
        "{markdown}"
    );
    // 2 DVLs × (baseline, beam-model WLS, its Kalman filter, floor, bound, least
    // squares, Kalman filter and DCNet with EM1-EM5) = 40 series, at 5 windows and on
    // 2 test trajectories.
    let calibration = section_rows(&markdown, "Calibration");
    let evaluation = section_rows(&markdown, "Evaluation");
    assert_eq!((calibration.len(), evaluation.len()), (200, 80));
    for row in calibration.iter().chain(&evaluation) {
        let at = if row.len() == 9 { 6 } else { 8 };
        assert_eq!(row[at], "+0.0000", "{row:?}");
        assert_eq!(row[at + 1], "+0.0", "{row:?}");
    }
    assert!(marked(&calibration, 8).is_empty() && marked(&evaluation, 10).is_empty());
    // The calibration times side by side, the same in both: per DVL every series but
    // the floor, which does not calibrate (18), and the bound.
    let times = section_rows(&markdown, "Calibration time");
    assert_eq!(times.len(), 2 * 19);
    assert!(
        times.iter().all(|row| row[3] == row[4] && row[5] == row[6]),
        "{times:?}"
    );
    let training = section_rows(&markdown, "DCNet training");
    assert_eq!(
        training
            .iter()
            .map(|row| format!("{} {} {}", row[0], row[1], row[2]))
            .collect::<Vec<_>>(),
        ["EM1 2 2", "EM2 2 2", "EM3 2 2", "EM4 2 2", "EM5 2 2"]
    );
    assert_eq!(
        markdown.lines().last().unwrap(),
        "0 of 280 cells differ beyond 2 combined standard errors"
    );
}

/// The model-based estimators: their rows do not depend on any training.
const MODEL_BASED: &str = "estimators.kinds=[\"baseline\", \"least_squares\", \"floor\"]";

#[test]
fn a_changed_dvl2_noise_marks_its_dvl2_cells_and_no_dvl1_cell() {
    let project = project(false);
    small_quick_run(project.path(), &["--no-plots", "--set", MODEL_BASED]);
    small_quick_run(
        project.path(),
        &[
            "--no-plots",
            "--set",
            MODEL_BASED,
            "--set",
            "name=quick-noise",
            "--set",
            "dvl[1].noise_cm_s=0.05",
        ],
    );
    let output = dcnet(
        project.path(),
        &["compare", "results/quick", "results/quick-noise"],
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let markdown = stdout(&output);
    assert_eq!(
        std::fs::read_to_string(project.path().join("compare.md")).unwrap(),
        markdown,
        "compare.md in the current folder is the default"
    );
    assert_eq!(
        section_rows(&markdown, "Spec"),
        [
            ["`name`", "\"quick\"", "\"quick-noise\""],
            ["`dvl[1].noise_cm_s`", "0.02", "0.05"]
        ]
    );
    let calibration = section_rows(&markdown, "Calibration");
    let evaluation = section_rows(&markdown, "Evaluation");
    // 2 DVLs × (baseline, floor, bound, least squares EM1-EM5) = 16 series, at 5
    // windows and on 2 test trajectories.
    assert_eq!((calibration.len(), evaluation.len()), (80, 32));
    // DVL1's blocks are seeded by (seed, DVL1, run, trajectory): the same bytes, so a
    // difference of exactly 0 and the same T_conv.
    for row in calibration.iter().filter(|row| row[0] == "DVL1") {
        assert_eq!(
            (row[6].as_str(), row[8].as_str()),
            ("+0.0000", ""),
            "{row:?}"
        );
    }
    for row in evaluation.iter().filter(|row| row[0] == "DVL1") {
        assert_eq!(row[4], row[5], "{row:?}");
        assert_eq!(
            (row[8].as_str(), row[10].as_str()),
            ("+0.0000", ""),
            "{row:?}"
        );
    }
    // DVL2 draws the same standard normals with 2.5 times the beam noise. The floor
    // leaves nothing but that noise, so its RMSE is 2.5 times A's in every run: marked
    // at every window and on every trajectory, far beyond 2 standard errors. Every other
    // estimator keeps its 0.7 cm/s of uncorrected error, to which the noise adds about
    // √(0.74² + (2.97·0.05)²) − √(0.74² + (2.97·0.02)²) = 0.012 cm/s: more in every
    // cell, marked only where 3 runs spread less than that.
    let value = |cell: &str| cell.parse::<f64>().unwrap();
    for (rows, a) in [(&calibration, 4), (&evaluation, 6)] {
        for row in rows.iter().filter(|row| row[0] == "DVL2") {
            assert!(value(&row[a + 2]) > 0.0, "{row:?}");
            if row[1] == "floor (true terms)" {
                assert!(
                    (value(&row[a + 1]) - 2.5 * value(&row[a])).abs() < 3e-4,
                    "{row:?}"
                );
                assert_eq!(row[a + 4], "⚠", "{row:?}");
            }
        }
    }
    let mut expected_calibration: Vec<String> = [
        "DVL2 baseline - 100",
        "DVL2 least squares EM1 40",
        "DVL2 least squares EM1 60",
        "DVL2 least squares EM1 80",
        "DVL2 least squares EM1 100",
        "DVL2 least squares EM2 60",
        "DVL2 least squares EM2 100",
    ]
    .map(String::from)
    .into();
    for window in ["20", "40", "60", "80", "100"] {
        expected_calibration.push(format!("DVL2 floor (true terms) - {window}"));
    }
    // The bound rises with the noise too; at 20 s its spread over runs is wider than
    // the change.
    for window in ["40", "60", "80", "100"] {
        expected_calibration.push(format!("DVL2 information bound - {window}"));
    }
    let expected_evaluation = [
        "DVL2 least squares EM1 S3",
        "DVL2 least squares EM1 S4",
        "DVL2 floor (true terms) - S3",
        "DVL2 floor (true terms) - S4",
        "DVL2 information bound - S3",
        "DVL2 information bound - S4",
    ];
    assert_eq!(marked(&calibration, 8), expected_calibration, "{markdown}");
    assert_eq!(marked(&evaluation, 10), expected_evaluation, "{markdown}");
    // Those are the cells whose difference exceeds 2 √((std_A² + std_B²) / 3), computed
    // here from the Parquet tables.
    for (a, b, rows, column) in [
        (
            calibration_rows(&project.path().join("results/quick")),
            calibration_rows(&project.path().join("results/quick-noise")),
            &calibration,
            8,
        ),
        (
            evaluation_rows(&project.path().join("results/quick")),
            evaluation_rows(&project.path().join("results/quick-noise")),
            &evaluation,
            10,
        ),
    ] {
        assert_eq!(a.len(), rows.len());
        for ((a, b), row) in a.iter().zip(&b).zip(rows) {
            assert_eq!((&a.dvl, &a.at), (&row[0], &row[3]));
            let threshold =
                2.0 * ((a.rmse_std_cm_s.powi(2) + b.rmse_std_cm_s.powi(2)) / 3.0).sqrt();
            let beyond = (b.rmse_cm_s - a.rmse_cm_s).abs() > threshold;
            assert_eq!(row[column] == "⚠", beyond, "{row:?}");
        }
    }
    assert_eq!(
        markdown.lines().last().unwrap(),
        "22 of 112 cells differ beyond 2 combined standard errors"
    );
}

#[test]
fn a_folder_that_holds_no_results_is_refused_naming_its_file() {
    let project = project(false);
    small_quick_run(
        project.path(),
        &[
            "--no-plots",
            "--set",
            "estimators.kinds=[\"baseline\", \"floor\"]",
        ],
    );
    let refused = |a: &str, b: &str, message: &str| {
        let output = dcnet(project.path(), &["compare", a, b]);
        assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
        assert!(stderr(&output).contains(message), "{}", stderr(&output));
        assert!(stdout(&output).is_empty());
        assert!(!project.path().join("compare.md").exists());
    };
    std::fs::create_dir(project.path().join("empty")).unwrap();
    refused(
        "results/quick",
        "empty",
        "error: empty/spec.toml: missing; a results folder written by `dcnet-exp run` holds it",
    );
    // A table of another schema: the evaluation table where the calibration one belongs.
    let broken = project.path().join("broken");
    std::fs::create_dir(&broken).unwrap();
    for file in std::fs::read_dir(project.path().join("results/quick")).unwrap() {
        let file = file.unwrap().path();
        std::fs::copy(&file, broken.join(file.file_name().unwrap())).unwrap();
    }
    std::fs::copy(
        broken.join("evaluation.parquet"),
        broken.join("calibration.parquet"),
    )
    .unwrap();
    refused(
        "broken",
        "results/quick",
        "error: broken/calibration.parquet: column `window_s` is missing",
    );
    std::fs::write(broken.join("manifest.json"), "{").unwrap();
    refused("results/quick", "broken", "error: broken/manifest.json: ");
    // A sweep folder names its points.
    let sweep = project.path().join("sweep");
    std::fs::create_dir(&sweep).unwrap();
    std::fs::write(
        sweep.join("sweep.json"),
        r#"{"name": "sweep", "swept": ["seed"], "points": ["seed=1", "seed=2"], "results_keys": ["", ""]}"#,
    )
    .unwrap();
    refused(
        "sweep",
        "results/quick",
        "error: sweep: a sweep folder, not a results folder; compare two of its points: sweep/seed=1, sweep/seed=2",
    );
    // A folder as the file to write: refused before anything is printed, said once.
    let output = dcnet(
        project.path(),
        &[
            "compare",
            "results/quick",
            "results/quick",
            "--out",
            "empty",
        ],
    );
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert_eq!(
        stderr(&output),
        "error: --out empty: is a folder; name the file to write the comparison to\n"
    );
    assert!(stdout(&output).is_empty());
    // A file that cannot be written: a failure, its cause printed once after the path.
    std::fs::write(project.path().join("a-file"), "").unwrap();
    let output = dcnet(
        project.path(),
        &[
            "compare",
            "results/quick",
            "results/quick",
            "--out",
            "a-file/compare.md",
        ],
    );
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    let error = stderr(&output);
    let cause = error
        .strip_prefix("error: writing a-file/compare.md: ")
        .unwrap_or_else(|| panic!("{error}"));
    assert_eq!(cause.lines().count(), 1, "{error}");
    assert_eq!(error.matches("(os error").count(), 1, "{error}");
}
