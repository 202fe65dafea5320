//! `dcnet-exp compare` of two installation studies, as a user runs it: two studies of
//! the same synthetic recordings whose specs differ in the DVL noise and in a
//! calibration window, compared; and a study beside a run refused, naming which is
//! which.

use crate::common;

use common::installed::{INSTALLED, write_installed};
use common::*;
use std::path::Path;

/// An installation spec `name` over `count` trajectories in `data/<folder>/` of `dir`,
/// with the DVL noise and calibration windows given.
fn write_spec(dir: &Path, name: &str, folder: &str, count: usize, dvl_cm_s: f64, windows: &str) {
    let mut text = format!("name = \"{name}\"\nkind = \"installation\"\n\n[recordings]\n");
    for n in 1..=count {
        text.push_str(&format!(
            "\n[[recordings.trajectories]]\nname = \"S{n}\"\ndvl = \"../data/{folder}/Trajectory{n}/DVL_trajectory{n}.csv\"\nreference = \"../data/{folder}/Trajectory{n}/GT_trajectory{n}.csv\"\n"
        ));
    }
    text.push_str(&format!(
        "\n[noise]\ndvl_cm_s = {dvl_cm_s:?}\nreference_cm_s = 0.0\n\n[calibration]\nwindow_s = {windows}\nmethods = [\"baseline\", \"EM5\"]\n\n[[calibration.models]]\nname = \"lever+offset+bias+scale\"\nterms = [\"lever_arm\", \"time_offset\", \"bias\", \"scale\"]\n",
    ));
    std::fs::create_dir_all(dir.join("experiments")).unwrap();
    std::fs::write(dir.join(format!("experiments/{name}.toml")), text).unwrap();
}

/// The cells of a Markdown table row, trimmed.
fn cells(line: &str) -> Vec<&str> {
    line.trim_matches('|').split('|').map(str::trim).collect()
}

#[test]
fn two_studies_differing_in_noise_and_a_window_are_compared_side_by_side() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 3, &[], INSTALLED, 5);
    write_spec(d, "syn", "syn", 3, 2.0, "[100.0, 400.0]");
    write_spec(d, "noisy", "syn", 3, 3.0, "[200.0, 400.0]");
    for name in ["syn", "noisy"] {
        let spec = format!("experiments/{name}.toml");
        let output = dcnet(d, &["run", &spec, "--no-plots"]);
        assert!(output.status.success(), "{}", stderr(&output));
    }
    let output = dcnet(
        d,
        &[
            "compare",
            "results/syn",
            "results/noisy",
            "--out",
            "compare.md",
        ],
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    assert_eq!(std::fs::read_to_string(d.join("compare.md")).unwrap(), text);
    let lines: Vec<&str> = text.lines().collect();
    let has = |line: &str| assert!(lines.contains(&line), "missing {line:?} in\n{text}");
    has("# Comparison of two installation studies");
    has("- A: `results/syn`");
    has("- B: `results/noisy`");
    has("| key                    | A              | B              |");
    has("| `name`                 | \"syn\"          | \"noisy\"        |");
    has("| `noise.dvl_cm_s`       | 2.0            | 3.0            |");
    has("| `calibration.window_s` | [100.0, 400.0] | [200.0, 400.0] |");
    has(
        "| method                               | window s | A cm/s       | B cm/s       | B − A cm/s |   |",
    );
    let methods = [
        "no calibration",
        "baseline",
        "least squares EM5",
        "installation lever+offset+bias+scale",
    ];
    // The same recordings and fits at 400 s: no difference; 100 s in A alone, 200 s in
    // B alone.
    let rows: Vec<Vec<&str>> = lines
        .iter()
        .filter(|line| methods.iter().any(|m| line.starts_with(&format!("| {m} "))))
        .map(|line| cells(line))
        .collect();
    assert_eq!(rows.len(), 3 * methods.len(), "{text}");
    for row in &rows {
        match row[1] {
            "400" => assert_eq!((row[4], row[5]), ("+0.00", ""), "{row:?}"),
            "100" => assert_eq!((row[3], row[4]), ("—", "—"), "{row:?}"),
            "200" => assert_eq!((row[2], row[4]), ("—", "—"), "{row:?}"),
            other => panic!("window {other} in {row:?}"),
        }
    }
    has("### installation lever+offset+bias+scale, window 400 s");
    // The same estimates and the same flags: a term is seen by the noise its residuals
    // show, which the specified noise does not change (it moves the bound only).
    has("| term            | A      | seen on | B      | seen on | B − A |");
    has("| lever arm x (m) | -1.89  | 3       | -1.89  | 3       | 0     |");
    has("| time offset (s) | 0.643  | 1       | 0.643  | 1       | 0     |");
    has("0 of 4 method and window pairs differ with 95 % intervals that do not overlap");
}

#[test]
fn a_study_beside_a_run_is_refused_naming_which_is_which() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir_all(d.join("study")).unwrap();
    std::fs::write(d.join("study/heldout.parquet"), "").unwrap();
    std::fs::create_dir_all(d.join("run")).unwrap();
    for (first, second) in [("study", "run"), ("run", "study")] {
        let output = dcnet(d, &["compare", first, second, "--out", "compare.md"]);
        assert!(!output.status.success());
        assert!(
            stderr(&output).contains(
                "study is an installation study (it holds heldout.parquet) and run a run of the paper: compare two studies or two runs"
            ),
            "{}",
            stderr(&output)
        );
        assert!(!d.join("compare.md").exists());
    }
}
