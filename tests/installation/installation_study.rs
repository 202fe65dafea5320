//! The installation study end to end, as a user runs it: `run` of a spec with
//! `kind = "installation"` on synthetic recordings with known terms (any clone) and on
//! the A-KIT recordings (ignored without them), `calibrate` of one recording, `plot`
//! of a stored study, and bad input refused with the file, line and column named.

use crate::common;

use common::installed::{INSTALLED, write_installed, write_study_spec as write_spec};
use common::*;
use std::path::Path;

/// The rows of `terms.parquet` for `method` at `window_s`: (calibration, term, value,
/// std, why unseen).
fn term_rows(
    folder: &Path,
    method: &str,
    window_s: f64,
) -> Vec<(String, String, f64, f64, String)> {
    let batch = read_parquet(&folder.join("terms.parquet"));
    let text = |column| strings(&batch, column).into_iter().map(Option::unwrap);
    let number = |column| floats(&batch, column).into_iter().map(Option::unwrap);
    text("method")
        .zip(number("window_s"))
        .zip(text("calibration"))
        .zip(text("term"))
        .zip(number("value"))
        .zip(number("std"))
        .zip(text("unseen"))
        .filter(|((((((m, w), _), _), _), _), _)| m == method && *w == window_s)
        .map(|((((((_, _), c), t), v), s), u)| (c, t, v, s, u))
        .collect()
}

/// Each method's mean held-out RMSE and ratio to no calibration at `window_s`.
fn summary(folder: &Path, window_s: f64) -> Vec<(String, f64, f64)> {
    let batch = read_parquet(&folder.join("summary.parquet"));
    let methods = strings(&batch, "method");
    let windows = floats(&batch, "window_s");
    let means = floats(&batch, "rmse_cm_s");
    let ratios = floats(&batch, "ratio");
    (0..batch.num_rows())
        .filter(|&i| windows[i] == Some(window_s))
        .map(|i| {
            (
                methods[i].clone().unwrap(),
                means[i].unwrap(),
                ratios[i].unwrap(),
            )
        })
        .collect()
}

#[test]
fn a_synthetic_installation_is_recovered_within_its_bound_and_a_straight_segment_cannot_show_the_lever_arm()
 {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 4, &[4], INSTALLED, 11);
    write_spec(d, "syn", "syn", 4, "");
    let output = dcnet(d, &["run", "experiments/syn.toml"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let folder = d.join("results/syn");
    let method = "installation lever+offset+bias+scale";
    let rows = term_rows(&folder, method, 400.0);
    let truth = |term: &str| match term {
        "scale" => INSTALLED.scale,
        "lever_arm_x_m" => INSTALLED.lever_arm_m[0],
        "lever_arm_y_m" => INSTALLED.lever_arm_m[1],
        "lever_arm_z_m" => INSTALLED.lever_arm_m[2],
        "time_offset_s" => INSTALLED.time_offset_s,
        "bias_x_m_s" => INSTALLED.bias_m_s[0],
        "bias_y_m_s" => INSTALLED.bias_m_s[1],
        "bias_z_m_s" => INSTALLED.bias_m_s[2],
        other => panic!("unexpected term {other}"),
    };
    for (calibration, term, value, std, unseen) in &rows {
        if calibration == "S4" {
            continue;
        }
        let z = (value - truth(term)) / std;
        assert!(
            z.abs() < 3.0,
            "{calibration} {term}: {value} ± {std}, truth {}",
            truth(term)
        );
        // The vertical lever arm shows only through roll and pitch rates, which
        // these trajectories barely have; the horizontal one through the turns.
        if term == "lever_arm_x_m" || term == "lever_arm_y_m" {
            assert!(unseen.is_empty(), "{calibration} {term}: {unseen}");
        }
    }
    let straight: Vec<_> = rows
        .iter()
        .filter(|(c, t, ..)| c == "S4" && t.starts_with("lever_arm_x"))
        .collect();
    assert_eq!(straight.len(), 1);
    assert!(
        !straight[0].4.is_empty(),
        "the straight S4 shows the lever arm: {straight:?}"
    );

    // Held out: the installation model leaves the DVL's own noise (√3 · 2 cm/s in
    // total), the paper's models most of the error.
    let means = summary(&folder, 400.0);
    let of = |m: &str| {
        means
            .iter()
            .find(|(method, ..)| method == m)
            .unwrap()
            .clone()
    };
    let noise_floor = 3f64.sqrt() * 100.0 * INSTALLED.noise_m_s;
    assert!(of(method).1 < 1.1 * noise_floor, "{means:?}");
    assert!(of(method).2 < 0.3, "{means:?}");
    assert!(of("least squares EM5").2 > 0.5, "{means:?}");

    let again = dcnet(d, &["run", "experiments/syn.toml"]);
    assert!(
        stderr(&again).contains("nothing to do"),
        "{}",
        stderr(&again)
    );
    let report = std::fs::read(folder.join("report.md")).unwrap();
    std::fs::remove_file(folder.join("report.md")).unwrap();
    let plotted = dcnet(d, &["plot", "results/syn", "--out", "redrawn"]);
    assert_eq!(
        std::fs::read(folder.join("report.md")).unwrap(),
        report,
        "plot writes the report again to the same bytes"
    );
    assert!(plotted.status.success(), "{}", stderr(&plotted));
    assert_png(
        &d.join("redrawn/syn/installation_residual.png"),
        (3280, 1800),
    );
    for file in [
        "heldout.parquet",
        "terms.parquet",
        "summary.parquet",
        "trace.parquet",
        "report.md",
        "report.tex",
        "manifest.json",
        "spec.toml",
    ] {
        assert!(folder.join(file).is_file(), "{file}");
    }

    // `plot` of altered or missing tables refuses them, naming the file, and writes no
    // report of them (it once rewrote the report with NaN, or said "unknown field").
    let report = std::fs::read(folder.join("report.md")).unwrap();
    let summary = std::fs::read(folder.join("summary.parquet")).unwrap();
    std::fs::write(
        folder.join("summary.parquet"),
        &summary[..summary.len() / 2],
    )
    .unwrap();
    let altered = dcnet(d, &["plot", "results/syn", "--out", "redrawn"]);
    assert_eq!(altered.status.code(), Some(1), "{}", stderr(&altered));
    assert!(
        stderr(&altered).contains("summary.parquet"),
        "{}",
        stderr(&altered)
    );
    std::fs::write(folder.join("summary.parquet"), &summary).unwrap();
    std::fs::remove_file(folder.join("heldout.parquet")).unwrap();
    let missing = dcnet(d, &["plot", "results/syn", "--out", "redrawn"]);
    assert_eq!(missing.status.code(), Some(1), "{}", stderr(&missing));
    assert!(
        stderr(&missing).contains("heldout.parquet"),
        "{}",
        stderr(&missing)
    );
    assert_eq!(std::fs::read(folder.join("report.md")).unwrap(), report);
}

#[test]
fn a_study_gives_the_same_bytes_whatever_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 3, &[], INSTALLED, 5);
    write_spec(d, "syn", "syn", 3, "");
    let mut digests = Vec::new();
    for threads in ["1", "2"] {
        let out = format!("out{threads}");
        let output = dcnet(
            d,
            &[
                "run",
                "experiments/syn.toml",
                "--out",
                &out,
                "--no-plots",
                "--threads",
                threads,
            ],
        );
        assert!(output.status.success(), "{}", stderr(&output));
        let tables: Vec<String> = [
            "heldout.parquet",
            "terms.parquet",
            "summary.parquet",
            "trace.parquet",
            "report.md",
            "report.tex",
        ]
        .iter()
        .map(|f| sha256(&std::fs::read(d.join(&out).join("syn").join(f)).unwrap()))
        .collect();
        digests.push(tables);
    }
    assert_eq!(digests[0], digests[1]);
}

#[test]
fn calibrate_prints_the_terms_and_writes_the_recording_corrected() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 1, &[], INSTALLED, 3);
    let output = dcnet(
        d,
        &[
            "calibrate",
            "data/syn/Trajectory1/DVL_trajectory1.csv",
            "--reference",
            "data/syn/Trajectory1/GT_trajectory1.csv",
            "--terms",
            "lever_arm,time_offset,bias,scale",
            "--reference-noise-cm-s",
            "0",
            "--out",
            "fixed",
        ],
    );
    let printed = stdout(&output);
    assert!(output.status.success(), "{}", stderr(&output));
    for term in ["lever arm x", "time offset", "bias x", "scale"] {
        assert!(printed.contains(&format!("| {term} ")), "{term}: {printed}");
    }
    let value = fitted_lever_x_m(&printed);
    assert!((value - INSTALLED.lever_arm_m[0]).abs() < 0.05, "{printed}");
    check_the_filter(
        &printed,
        &d.join("fixed/DVL_trajectory1-terms-in-time.parquet"),
    );
    let csv = d.join("fixed/DVL_trajectory1-corrected.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(
        text.starts_with("time_s,valid_at_s,vx_m_s,vy_m_s,vz_m_s,left_out\n"),
        "{text}"
    );
    assert!(d.join("fixed/DVL_trajectory1-corrected.parquet").is_file());
    // Each corrected sample is valid at its stamp plus the time offset.
    let second: Vec<f64> = text
        .lines()
        .nth(2)
        .unwrap()
        .split(',')
        .take(5)
        .map(|f| f.parse().unwrap())
        .collect();
    assert!(
        (second[1] - second[0] - INSTALLED.time_offset_s).abs() < 0.05,
        "{second:?}"
    );
}

/// The lever arm's x that `calibrate` printed for its fit, m.
fn fitted_lever_x_m(printed: &str) -> f64 {
    printed
        .lines()
        .find(|l| l.starts_with("| lever arm x "))
        .and_then(|l| l.split('|').nth(2))
        .unwrap()
        .trim()
        .trim_end_matches(" m")
        .parse()
        .unwrap()
}

/// What `calibrate` says of its Kalman filter, against its fit: with every sample the
/// filter leaves the RMSE the fit leaves (within 2 %); the length the recording needed
/// lies inside it; the terms after every sample are stored in `terms_in_time`, and the
/// lever arm's x after the last is the fit's within 2 cm. Returns the length needed, s.
fn check_the_filter(printed: &str, terms_in_time: &Path) -> f64 {
    let fitted_lever_x_m = fitted_lever_x_m(printed);
    let fitted_rmse: f64 = printed
        .lines()
        .find(|l| l.starts_with("RMSE against the reference"))
        .and_then(|l| l.rsplit("before, ").next())
        .and_then(|after| after.split(" cm/s").next())
        .unwrap()
        .parse()
        .unwrap();
    let filtered = printed
        .lines()
        .find(|l| l.starts_with("| RMSE on the recording (cm/s) "))
        .unwrap();
    let last: f64 = filtered
        .trim_end_matches('|')
        .rsplit('|')
        .next()
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    assert!(
        (last - fitted_rmse).abs() <= 0.02 * fitted_rmse,
        "{printed}"
    );
    let needed: f64 = printed
        .lines()
        .find_map(|l| l.strip_prefix("after "))
        .and_then(|rest| rest.split_once(" s the filter's terms leave"))
        .map(|(seconds, _)| seconds)
        .unwrap()
        .parse()
        .unwrap();
    let batch = read_parquet(terms_in_time);
    let times = floats(&batch, "time_s");
    let end = times.iter().map(|t| t.unwrap()).fold(0.0, f64::max);
    assert!(
        needed > 1.0 && needed < end,
        "needed {needed} s of {end}: {printed}"
    );
    let lever_x: Vec<(f64, f64)> = strings(&batch, "term")
        .into_iter()
        .zip(times)
        .zip(floats(&batch, "value"))
        .filter(|((term, _), _)| term.as_deref() == Some("lever_arm_x_m"))
        .map(|((_, t), v)| (t.unwrap(), v.unwrap()))
        .collect();
    assert!(lever_x.len() > 100, "{}", lever_x.len());
    let (_, at_end) = lever_x.last().unwrap();
    assert!(
        (at_end - fitted_lever_x_m).abs() < 0.02,
        "{at_end} against the fit's {fitted_lever_x_m}"
    );
    needed
}

/// `calibrate` on the turning A-KIT T1: the filter reaches the fit, and says how long
/// the segment needed.
#[test]
#[ignore = "needs the A-KIT recordings: dcnet-exp data fetch akit"]
fn calibrate_on_a_real_segment_says_how_long_it_needed() {
    let dir = tempfile::tempdir().unwrap();
    let segment = akit().join("Trajectory1");
    let calibrate = |extra: &[&str]| {
        let dvl = segment.join("DVL_trajectory1.csv");
        let reference = segment.join("GT_trajectory1.csv");
        let args = [
            &[
                "calibrate",
                dvl.to_str().unwrap(),
                "--reference",
                reference.to_str().unwrap(),
            ][..],
            extra,
        ]
        .concat();
        let output = dcnet(dir.path(), &args);
        assert!(output.status.success(), "{}", stderr(&output));
        stdout(&output)
    };
    let printed = calibrate(&[]);
    let needed = check_the_filter(
        &printed,
        &dir.path()
            .join("calibrated/DVL_trajectory1-terms-in-time.parquet"),
    );
    // 43 s when measured (69 s with the band of the RMSE after all of it); the turning
    // T1 shows its terms within the first two minutes.
    assert!((40.0..=120.0).contains(&needed), "{printed}");
    // On a window, the last column and the sentence name the window, not the recording.
    let printed = calibrate(&["--window-s", "100", "--tolerance-pct", "7"]);
    assert!(printed.contains(" s (window) |"), "{printed}");
    assert!(
        printed.contains(" of the window (7 % of what calibration changes here: "),
        "{printed}"
    );
    assert!(
        printed.contains(" after the fit of all of it), and stay there,"),
        "{printed}"
    );
}

#[test]
fn bad_recordings_and_specs_are_refused_naming_the_file_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 2, &[], INSTALLED, 1);
    write_spec(d, "syn", "syn", 2, "");
    // A time stamp that goes back.
    let gt = d.join("data/syn/Trajectory2/GT_trajectory2.csv");
    let text = std::fs::read_to_string(&gt).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[5] = lines[5].replacen("4,", "2.5,", 1);
    std::fs::write(&gt, lines.join("\n") + "\n").unwrap();
    let output = dcnet(d, &["run", "experiments/syn.toml"]);
    let message = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{message}");
    assert!(
        message.contains("GT_trajectory2.csv:6: Time [s]: 2.5 s follows 3 s of line 5"),
        "{message}"
    );
    assert!(!d.join("results/syn").exists());

    // A missing file, a kind that is none, a term that is none.
    std::fs::remove_file(d.join("data/syn/Trajectory1/DVL_trajectory1.csv")).unwrap();
    let message = stderr(&dcnet(d, &["run", "experiments/syn.toml"]));
    assert!(
        message.contains("DVL_trajectory1.csv: file not found"),
        "{message}"
    );
    let message = stderr(&dcnet(
        d,
        &[
            "validate",
            "experiments/syn.toml",
            "--set",
            "kind=\"instalation\"",
        ],
    ));
    assert!(
        message.contains("kind: \"instalation\" must be \"installation\" here"),
        "{message}"
    );
    let spec = std::fs::read_to_string(d.join("experiments/syn.toml")).unwrap();
    std::fs::write(
        d.join("experiments/typo.toml"),
        spec.replace("kind = \"installation\"", "kind = \"instalation\""),
    )
    .unwrap();
    let message = stderr(&dcnet(d, &["run", "experiments/typo.toml"]));
    assert!(
        message.contains("experiments/typo.toml: kind: \"instalation\" is not a kind of spec"),
        "{message}"
    );
    let message = stderr(&dcnet(
        d,
        &[
            "validate",
            "experiments/syn.toml",
            "--set",
            "calibration.models[0].terms=[\"lever\"]",
        ],
    ));
    assert!(
        message.contains("calibration.models[0].terms[0]: unknown variant `lever`"),
        "{message}"
    );
    let message = stderr(&dcnet(d, &["bench", "experiments/syn.toml"]));
    assert!(
        message.contains(
            "an installation study has no training data to inspect nor training to bench"
        ),
        "{message}"
    );
    assert!(!d.join("results/syn").exists());
}

/// The A-KIT run: from a trajectory with turns the installation model's held-out RMSE
/// is at most a third of no calibration's, and the fixes' installation at most 0.30 %
/// of the distance in dead-reckoning drift (none: over 0.5 %); from the straight T12
/// (its yaw applied, seen poorly) at most 0.1 % more than none on the others; the
/// straight T12 cannot show the lever arm, the turning T1 can.
#[test]
#[ignore = "needs the A-KIT recordings: dcnet-exp data fetch akit"]
fn the_akit_study_removes_two_thirds_of_the_error_from_a_turning_segment() {
    let dir = project(false);
    let d = dir.path();
    std::fs::copy(
        repo().join("experiments/akit.toml"),
        d.join("experiments/akit.toml"),
    )
    .unwrap();
    std::fs::create_dir_all(d.join("data")).unwrap();
    std::os::unix::fs::symlink(akit(), d.join("data/akit")).unwrap();
    let output = dcnet(d, &["run", "experiments/akit.toml", "--no-plots"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let folder = d.join("results/akit");
    let batch = read_parquet(&folder.join("heldout.parquet"));
    let methods = strings(&batch, "method");
    let calibrations = strings(&batch, "calibration");
    let windows = floats(&batch, "window_s");
    let totals = floats(&batch, "rmse_cm_s");
    let mean = |method: &str, calibration: &str| {
        let values: Vec<f64> = (0..batch.num_rows())
            .filter(|&i| {
                methods[i].as_deref() == Some(method)
                    && calibrations[i].as_deref() == Some(calibration)
                    && windows[i] == Some(400.0)
            })
            .map(|i| totals[i].unwrap())
            .collect();
        assert_eq!(values.len(), 12, "{method} from {calibration}");
        values.iter().sum::<f64>() / 12.0
    };
    let none = mean("no calibration", "T1");
    let best = mean("installation lever+offset+bias", "T1");
    // Dead-reckoning drift: the fixes' installation (fixes every 5 s, 2 m) from a turning
    // segment halves it on the other turning ones; from a straight one it adds a little.
    let scored = strings(&batch, "scored");
    let drifts = floats(&batch, "drift_rms_pct");
    let drift = |method: &str, from: &[&str], on: &[&str]| {
        let values: Vec<f64> = (0..batch.num_rows())
            .filter(|&i| {
                methods[i].as_deref() == Some(method)
                    && from.contains(&calibrations[i].as_deref().unwrap_or(""))
                    && on.contains(&scored[i].as_deref().unwrap_or(""))
                    && windows[i] == Some(400.0)
            })
            .map(|i| drifts[i].unwrap())
            .collect();
        assert!(!values.is_empty(), "{method}");
        values.iter().sum::<f64>() / values.len() as f64
    };
    let turning_scored = ["T2", "T3", "T9", "T10"];
    let from_fixes = drift(
        "installation from fixes",
        &["T1", "T4", "T8"],
        &turning_scored,
    );
    let uncalibrated = drift("no calibration", &["T1", "T4", "T8"], &turning_scored);
    assert!(
        from_fixes <= 0.30 && uncalibrated > 0.5,
        "drift from fixes {from_fixes:.3} %, no calibration {uncalibrated:.3} %"
    );
    let all = [
        "T1", "T2", "T3", "T4", "T5", "T6", "T7", "T8", "T9", "T10", "T11", "T12", "T13",
    ];
    // T12 is straight (its heading within 2.3°): its yaw, seen poorly, is applied, and
    // carried to the other segments it adds a little drift, the attitude's heading
    // error at T12's heading not theirs (measured 0.499 % against none's 0.468 %;
    // docs/findings.md).
    let fixed = drift("installation from fixes", &["T12"], &all);
    let unfixed = drift("no calibration", &["T12"], &all);
    assert!(
        fixed <= unfixed + 0.1,
        "from T12: {fixed:.3} % against {unfixed:.3} %"
    );
    assert!(
        best <= none / 3.0,
        "from T1: {best:.2} cm/s against {none:.2} uncalibrated"
    );
    let seen = |calibration: &str| {
        term_rows(&folder, "installation lever+offset+bias", 400.0)
            .into_iter()
            .filter(|(c, t, ..)| c == calibration && t.starts_with("lever_arm_x"))
            .map(|(.., why)| why)
            .next()
            .unwrap()
    };
    assert!(seen("T1").is_empty(), "{}", seen("T1"));
    // T12's residuals (0.3–0.6 cm/s) let its small rate changes show the longitudinal
    // lever arm; T13's do not.
    assert!(!seen("T13").is_empty(), "T13 shows the lever arm");
    // The terms left out that the residuals still follow: the time offset, where only
    // the lever arm is fitted; a scale on the straight T12, where lever arm, time
    // offset and bias are.
    let report = std::fs::read_to_string(folder.join("report.md")).unwrap();
    assert!(
        report.contains("- T1, the residuals still follow a term left out (score test, p < 0.001): time_offset χ² "),
        "{report}"
    );
    assert!(
        report.contains("- T12, the residuals still follow a term left out (score test, p < 0.001): scale χ² 79.4;"),
        "{report}"
    );
}

/// DCNet as the paper would use it: the models a paper spec trained (here the quick
/// spec's) estimate each calibration window's scale and bias, scored like every other
/// method; before they are trained, the study says which command trains them.
#[test]
fn the_dcnet_models_of_a_paper_spec_are_scored_beside_the_other_methods() {
    let dir = project(false);
    let d = dir.path();
    write_installed(&d.join("data/syn"), 3, &[], INSTALLED, 9);
    write_spec(d, "syn", "syn", 3, "\n[dcnet]\nspec = \"quick.toml\"\n");
    let set = [
        "--set",
        "calibration.methods=[\"baseline\", \"EM5\", \"dcnet\"]",
    ];
    let refused = dcnet(
        d,
        &[&["run", "experiments/syn.toml", "--no-plots"][..], &set].concat(),
    );
    let message = stderr(&refused);
    assert_eq!(refused.status.code(), Some(1), "{message}");
    assert!(
        message.contains("is not trained: run `dcnet-exp run ")
            && message.contains("quick.toml --out results` first"),
        "{message}"
    );
    assert!(!d.join("results/syn").exists());

    quick_run(d, &["--no-plots"]);
    let output = dcnet(
        d,
        &[&["run", "experiments/syn.toml", "--no-plots"][..], &set].concat(),
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let means = summary(&d.join("results/syn"), 400.0);
    for model in ["EM1", "EM2", "EM3", "EM4", "EM5"] {
        let label = format!("DCNet {model}");
        let row = means.iter().find(|(m, ..)| *m == label);
        assert!(
            row.is_some_and(|(_, mean, _)| mean.is_finite()),
            "{label}: {means:?}"
        );
    }
}

/// A study's folder belongs to its spec file, and a study, a single run and a sweep
/// never share a folder.
#[test]
fn a_study_never_replaces_another_specs_folder_nor_a_runs() {
    let dir = project(false);
    let d = dir.path();
    write_installed(&d.join("data/syn"), 2, &[], INSTALLED, 4);
    write_spec(d, "syn", "syn", 2, "");
    let first = dcnet(d, &["run", "experiments/syn.toml", "--no-plots"]);
    assert!(first.status.success(), "{}", stderr(&first));
    std::fs::copy(
        d.join("experiments/syn.toml"),
        d.join("experiments/other.toml"),
    )
    .unwrap();
    let refused = dcnet(
        d,
        &[
            "run",
            "experiments/other.toml",
            "--no-plots",
            "--set",
            "noise.dvl_cm_s=3.0",
        ],
    );
    let message = stderr(&refused);
    assert_eq!(refused.status.code(), Some(1), "{message}");
    for part in [
        "results/syn: holds the results of",
        "experiments/syn.toml",
        "experiments/other.toml",
        "--force",
    ] {
        assert!(message.contains(part), "{part}: {message}");
    }
    let forced = dcnet(
        d,
        &[
            "run",
            "experiments/other.toml",
            "--no-plots",
            "--set",
            "noise.dvl_cm_s=3.0",
            "--force",
        ],
    );
    assert!(forced.status.success(), "{}", stderr(&forced));

    // A study named like a paper run's folder, and a paper run named like a study's.
    quick_run(d, &["--no-plots"]);
    let message = stderr(&dcnet(
        d,
        &[
            "run",
            "experiments/syn.toml",
            "--no-plots",
            "--set",
            "name=\"quick\"",
        ],
    ));
    assert!(
        message.contains("results/quick: holds the results of a single run, and this run of"),
        "{message}"
    );
    assert!(
        message.contains("is the results of an installation study"),
        "{message}"
    );
    let message = stderr(&dcnet(
        d,
        &[
            "run",
            "experiments/quick.toml",
            "--no-plots",
            "--set",
            "name=\"syn\"",
        ],
    ));
    assert!(
        message.contains("results/syn: holds the results of an installation study"),
        "{message}"
    );
}

/// What a reviewer found accepted: `validate` passing recordings `run` refuses, a DVL's
/// velocity beyond any vehicle's read as data, and `calibrate` taking term lists and noise the
/// spec refuses.
#[test]
fn validate_reads_the_recordings_and_calibrate_refuses_what_the_spec_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 2, &[], INSTALLED, 6);
    write_spec(d, "syn", "syn", 2, "");
    let dvl = d.join("data/syn/Trajectory1/DVL_trajectory1.csv");
    let text = std::fs::read_to_string(&dvl).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    // Teledyne RDI's invalid marker is a sample the DVL did not measure, left out;
    // another value beyond a vehicle's speed is refused at its line.
    let fields: Vec<&str> = lines[10].split(',').collect();
    lines[10] = format!("{},-32.768,{},{}", fields[0], fields[2], fields[3]);
    std::fs::write(&dvl, lines.join("\n") + "\n").unwrap();
    let output = dcnet(d, &["validate", "experiments/syn.toml"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let fields: Vec<&str> = lines[11].split(',').collect();
    lines[11] = format!("{},-25.0,{},{}", fields[0], fields[2], fields[3]);
    std::fs::write(&dvl, lines.join("\n") + "\n").unwrap();
    for command in ["validate", "run"] {
        let output = dcnet(d, &[command, "experiments/syn.toml"]);
        let message = stderr(&output);
        assert_eq!(output.status.code(), Some(1), "{command}: {message}");
        assert!(
            message.contains("DVL_trajectory1.csv:12: DVL X [m/s]: -25 m/s is beyond 20 m/s"),
            "{command}: {message}"
        );
    }
    let calibrate = |extra: &[&str]| {
        let args = [
            &[
                "calibrate",
                "data/syn/Trajectory2/DVL_trajectory2.csv",
                "--reference",
                "data/syn/Trajectory2/GT_trajectory2.csv",
            ][..],
            extra,
        ]
        .concat();
        let output = dcnet(d, &args);
        assert_eq!(
            output.status.code(),
            Some(1),
            "{extra:?}: {}",
            stderr(&output)
        );
        assert!(!d.join("calibrated").exists());
        stderr(&output)
    };
    assert!(
        calibrate(&["--terms", "scale,scale_per_axis"])
            .contains("--terms: lists scale and scale_per_axis: give one")
    );
    assert!(
        calibrate(&["--terms", "lever_arm,lever_arm"])
            .contains("--terms: \"lever_arm\" is listed twice")
    );
    assert!(
        calibrate(&["--dvl-noise-cm-s", "0"])
            .contains("--dvl-noise-cm-s 0: give a positive number")
    );
    assert!(
        calibrate(&["--window-s", "-5"])
            .contains("--window-s -5: give a positive number of seconds")
    );
    assert!(
        calibrate(&["--tolerance-pct", "0"])
            .contains("--tolerance-pct 0: give a positive percentage")
    );
}

/// `calibrate` never writes over a file it reads, nor over another recording's results
/// in the same `--out`: refused before anything is computed, naming both files, the
/// input untouched. The same recording again writes its files again.
#[test]
fn calibrate_never_writes_over_an_input_or_another_recordings_results() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 2, &[], INSTALLED, 3);
    let trajectory =
        |n: usize, file: &str| d.join(format!("data/syn/Trajectory{n}/{file}_trajectory{n}.csv"));
    std::fs::copy(trajectory(1, "DVL"), d.join("dvl.csv")).unwrap();
    std::fs::copy(trajectory(1, "GT"), d.join("dvl-corrected.csv")).unwrap();
    let reference = std::fs::read(d.join("dvl-corrected.csv")).unwrap();
    let refused = dcnet(
        d,
        &[
            "calibrate",
            "dvl.csv",
            "--reference",
            "dvl-corrected.csv",
            "--out",
            ".",
        ],
    );
    assert_eq!(refused.status.code(), Some(1), "{}", stderr(&refused));
    assert!(
        stderr(&refused).contains("dvl-corrected.csv: calibrate would write over its input"),
        "{}",
        stderr(&refused)
    );
    assert_eq!(
        std::fs::read(d.join("dvl-corrected.csv")).unwrap(),
        reference
    );
    // A columns file where the terms against time would go.
    std::fs::copy(trajectory(1, "GT"), d.join("gt.csv")).unwrap();
    std::fs::write(d.join("dvl-terms-in-time.parquet"), "[columns]\n").unwrap();
    let refused = dcnet(
        d,
        &[
            "calibrate",
            "dvl.csv",
            "--reference",
            "gt.csv",
            "--columns",
            "dvl-terms-in-time.parquet",
            "--out",
            ".",
        ],
    );
    assert_eq!(refused.status.code(), Some(1), "{}", stderr(&refused));
    assert!(
        stderr(&refused)
            .contains("dvl-terms-in-time.parquet: calibrate would write over its input"),
        "{}",
        stderr(&refused)
    );

    // Two dives whose DVL files share a name, into one folder.
    for (dive, n) in [("dive1", 1), ("dive2", 2)] {
        std::fs::create_dir_all(d.join(dive)).unwrap();
        std::fs::copy(trajectory(n, "DVL"), d.join(dive).join("dvl.csv")).unwrap();
        std::fs::copy(trajectory(n, "GT"), d.join(dive).join("gt.csv")).unwrap();
    }
    let calibrate = |dive: &str| {
        let dvl = format!("{dive}/dvl.csv");
        let gt = format!("{dive}/gt.csv");
        dcnet(d, &["calibrate", &dvl, "--reference", &gt, "--out", "both"])
    };
    let first = calibrate("dive1");
    assert!(first.status.success(), "{}", stderr(&first));
    let written = std::fs::read(d.join("both/dvl-corrected.csv")).unwrap();
    let second = calibrate("dive2");
    assert_eq!(second.status.code(), Some(1), "{}", stderr(&second));
    assert!(
        stderr(&second)
            .contains("both/dvl-corrected.parquet: holds the results of another recording")
            && stderr(&second).contains("which dive2/dvl.csv would replace"),
        "{}",
        stderr(&second)
    );
    assert_eq!(
        std::fs::read(d.join("both/dvl-corrected.csv")).unwrap(),
        written
    );
    let again = calibrate("dive1");
    assert!(again.status.success(), "{}", stderr(&again));
    assert_eq!(
        std::fs::read(d.join("both/dvl-corrected.csv")).unwrap(),
        written
    );

    // `correct` keeps to the same rule, and a `--save` over an input is named as such.
    let save = |to: &str| {
        let dvl = ["dive1/dvl.csv", "--reference", "dive1/gt.csv"];
        dcnet(
            d,
            &[&["calibrate"], &dvl[..], &["--out", "saving", "--save", to]].concat(),
        )
    };
    let saved = save("dive1/gt.csv");
    assert_eq!(saved.status.code(), Some(1), "{}", stderr(&saved));
    assert!(
        stderr(&saved).contains("give another --save, or rename the file"),
        "{}",
        stderr(&saved)
    );
    let saved = save("installation.toml");
    assert!(saved.status.success(), "{}", stderr(&saved));
    let correct = dcnet(
        d,
        &[
            "correct",
            "dive2/dvl.csv",
            "--reference",
            "dive2/gt.csv",
            "--installation",
            "installation.toml",
            "--out",
            "both",
        ],
    );
    assert_eq!(correct.status.code(), Some(1), "{}", stderr(&correct));
    assert!(
        stderr(&correct)
            .contains("both/dvl-corrected.parquet: holds the results of another recording")
            && stderr(&correct).contains("which dive2/dvl.csv would replace"),
        "{}",
        stderr(&correct)
    );
    assert_eq!(
        std::fs::read(d.join("both/dvl-corrected.csv")).unwrap(),
        written
    );
}

/// A DVL that reads no motion fits a scale of −100 %, whose correction divides by
/// zero: refused, exit 1, nothing written, where it once wrote NaN rows with exit 0.
#[test]
fn calibrate_refuses_a_dvl_that_reads_no_motion() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 1, &[], INSTALLED, 3);
    let dvl = d.join("data/syn/Trajectory1/DVL_trajectory1.csv");
    let text = std::fs::read_to_string(&dvl).unwrap();
    let zeros: String = text
        .lines()
        .enumerate()
        .map(|(i, line)| match (i, line.split_once(',')) {
            (0, _) | (_, None) => format!("{line}\n"),
            (_, Some((time, _))) => format!("{time},0,0,0\n"),
        })
        .collect();
    std::fs::write(d.join("zeros.csv"), zeros).unwrap();
    let output = dcnet(
        d,
        &[
            "calibrate",
            "zeros.csv",
            "--reference",
            "data/syn/Trajectory1/GT_trajectory1.csv",
            "--terms",
            "scale",
            "--out",
            "zeros",
        ],
    );
    // 0, 0, 0 is what a DVL without bottom lock sends: every sample is left out.
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("zeros.csv: 0 valid DVL samples, ")
            && stderr(&output).contains(" of exactly 0, 0, 0: a calibration needs at least 3"),
        "{}",
        stderr(&output)
    );
    // Said to be a reading (a vehicle that truly stops), it fits a scale of −100 %.
    std::fs::write(
        d.join("zero-is-valid.toml"),
        "[columns]\ntime = \"Time [s]\"\ndvl = [\"DVL X [m/s]\", \"DVL Y [m/s]\", \"DVL Z [m/s]\"]\nvelocity_ned = [\"V North [m/s]\", \"V East [m/s]\", \"V Down [m/s]\"]\nattitude = [\"Roll [rad]\", \"Pitch [rad]\", \"Yaw [rad]\"]\nzero_is_valid = true\n",
    )
    .unwrap();
    let output = dcnet(
        d,
        &[
            "calibrate",
            "zeros.csv",
            "--reference",
            "data/syn/Trajectory1/GT_trajectory1.csv",
            "--columns",
            "zero-is-valid.toml",
            "--terms",
            "scale",
            "--out",
            "zeros",
        ],
    );
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("the fitted scale x is -")
            && stderr(&output).contains(" %, beyond the ±50 % any installation is off by"),
        "{}",
        stderr(&output)
    );
    assert!(!d.join("zeros").exists());
}

/// Input that once ran to a poor answer: a column named for two quantities, one
/// recording listed twice, a device as a recording, a tolerance of 1e308 % and a
/// negative noise (which clap took for a flag). Each is refused, exit 1, naming its
/// key or flag.
#[test]
fn doubtful_input_is_refused_naming_its_key_or_flag() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 2, &[], INSTALLED, 6);
    let columns = "[recordings.columns]\ntime = \"Time [s]\"\ndvl = [\"DVL X [m/s]\", \"DVL Y [m/s]\", \"DVL Z [m/s]\"]\nvelocity_ned = [\"V North [m/s]\", \"V North [m/s]\", \"V Down [m/s]\"]\nattitude = [\"Roll [rad]\", \"Pitch [rad]\", \"Yaw [rad]\"]\n";
    write_spec(d, "syn", "syn", 2, columns);
    let output = dcnet(d, &["validate", "experiments/syn.toml"]);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("recordings.columns.velocity_ned[1]: \"V North [m/s]\" is named for another quantity too"),
        "{}",
        stderr(&output)
    );
    let spec = d.join("experiments/syn.toml");
    let text = std::fs::read_to_string(&spec).unwrap();
    std::fs::write(
        &spec,
        text.replace(columns, "")
            .replace("Trajectory2/DVL_trajectory2", "Trajectory1/DVL_trajectory1")
            .replace("Trajectory2/GT_trajectory2", "Trajectory1/GT_trajectory1"),
    )
    .unwrap();
    let output = dcnet(d, &["validate", "experiments/syn.toml"]);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("reads the same files as a trajectory before it"),
        "{}",
        stderr(&output)
    );

    let calibrate = |extra: &[&str]| {
        let mut args = vec![
            "calibrate",
            "data/syn/Trajectory1/DVL_trajectory1.csv",
            "--reference",
            "data/syn/Trajectory1/GT_trajectory1.csv",
        ];
        args.extend(extra);
        let output = dcnet(d, &args);
        assert_eq!(
            output.status.code(),
            Some(1),
            "{extra:?}: {}",
            stderr(&output)
        );
        stderr(&output)
    };
    assert!(
        calibrate(&["--tolerance-pct", "1e308"])
            .contains("--tolerance-pct 1e308: give a positive percentage, at most 100"),
    );
    assert!(
        calibrate(&["--dvl-noise-cm-s", "-1"])
            .contains("--dvl-noise-cm-s -1: give a positive number")
    );
    // A [dcnet] spec that names a study, not a paper spec.
    write_spec(
        d,
        "with-dcnet",
        "syn",
        2,
        "\n[dcnet]\nspec = \"syn.toml\"\n",
    );
    let spec = d.join("experiments/with-dcnet.toml");
    let text = std::fs::read_to_string(&spec).unwrap();
    std::fs::write(
        &spec,
        text.replace(
            "methods = [\"baseline\", \"EM5\"]",
            "methods = [\"baseline\", \"dcnet\"]",
        ),
    )
    .unwrap();
    let output = dcnet(d, &["validate", "experiments/with-dcnet.toml"]);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("dcnet.spec: ")
            && stderr(&output).contains("is a spec of kind \"installation\""),
        "{}",
        stderr(&output)
    );
    let device = dcnet(
        d,
        &[
            "calibrate",
            "/dev/zero",
            "--reference",
            "data/syn/Trajectory1/GT_trajectory1.csv",
        ],
    );
    assert_eq!(device.status.code(), Some(1), "{}", stderr(&device));
    assert!(
        stderr(&device).contains("/dev/zero: not a regular file"),
        "{}",
        stderr(&device)
    );
}

/// The same recordings at another path are the same calibrations: a study whose data
/// moved takes every calibration from the cache (the key holds the recordings' bytes,
/// not their paths), where it once computed them all again.
#[test]
fn recordings_moved_to_another_path_are_taken_from_the_cache() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 2, &[], INSTALLED, 8);
    write_spec(d, "syn", "syn", 2, "");
    let first = dcnet(d, &["run", "experiments/syn.toml", "--no-plots"]);
    assert!(first.status.success(), "{}", stderr(&first));
    std::fs::rename(d.join("data/syn"), d.join("data/moved")).unwrap();
    let spec = d.join("experiments/syn.toml");
    let text = std::fs::read_to_string(&spec).unwrap();
    std::fs::write(&spec, text.replace("/syn/", "/moved/")).unwrap();
    let planned = dcnet(d, &["plan", "experiments/syn.toml"]);
    assert!(planned.status.success(), "{}", stderr(&planned));
    assert!(
        stdout(&planned).contains("syn: 2 calibrations, 0 to do"),
        "{}",
        stdout(&planned)
    );
}

/// A study that cannot write its folder (here a table's place taken by a folder, as a
/// full disk would stop it) is a failure while running, exit 2, not bad input: its
/// calibrations stay in the cache and a run once the cause is gone resumes.
#[test]
fn a_study_that_cannot_write_is_a_failure_not_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 2, &[], INSTALLED, 9);
    write_spec(d, "syn", "syn", 2, "");
    let first = dcnet(d, &["run", "experiments/syn.toml", "--no-plots"]);
    assert!(first.status.success(), "{}", stderr(&first));
    let table = d.join("results/syn/heldout.parquet");
    std::fs::remove_file(&table).unwrap();
    std::fs::create_dir_all(table.join("in the way")).unwrap();
    let stopped = dcnet(d, &["run", "experiments/syn.toml", "--no-plots"]);
    assert_eq!(stopped.status.code(), Some(2), "{}", stderr(&stopped));
    assert!(
        stderr(&stopped).contains("heldout.parquet"),
        "{}",
        stderr(&stopped)
    );
    std::fs::remove_dir_all(&table).unwrap();
    let resumed = dcnet(d, &["run", "experiments/syn.toml", "--no-plots"]);
    assert!(resumed.status.success(), "{}", stderr(&resumed));
    assert!(table.is_file());
}

/// A DVL 5 s off its reference, beyond the ±3 s the fit scans: refused, exit 1, with a
/// message that names the scan's reach, where it once said only `Numerical("jacobian")`.
#[test]
fn a_time_offset_beyond_the_scan_is_refused_naming_the_scan() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let late = common::installed::Installed {
        time_offset_s: 5.0,
        ..INSTALLED
    };
    write_installed(&d.join("data/syn"), 1, &[], late, 4);
    let output = dcnet(
        d,
        &[
            "calibrate",
            "data/syn/Trajectory1/DVL_trajectory1.csv",
            "--reference",
            "data/syn/Trajectory1/GT_trajectory1.csv",
        ],
    );
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(stderr(&output).contains("±3 s"), "{}", stderr(&output));
}

/// A DVL's own validity column, named on the command line: the samples it flags are
/// left out and counted, the rest calibrated; a column named for two quantities is
/// refused.
#[test]
fn calibrate_leaves_out_what_the_dvls_validity_column_flags_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 1, &[], INSTALLED, 3);
    let dvl = d.join("data/syn/Trajectory1/DVL_trajectory1.csv");
    let text = std::fs::read_to_string(&dvl).unwrap();
    let flagged: String = text
        .lines()
        .enumerate()
        .map(|(i, line)| match i {
            0 => format!("{line},ok\n"),
            // Rows 101 to 110 flagged: a lost bottom lock whose velocity the DVL still
            // sent, garbage.
            101..=110 => {
                let time = line.split(',').next().unwrap();
                format!("{time},9,9,9,0\n")
            }
            _ => format!("{line},1\n"),
        })
        .collect();
    std::fs::write(d.join("flagged.csv"), flagged).unwrap();
    let calibrate = |extra: &[&str], out: &str| {
        let mut args = vec![
            "calibrate",
            "flagged.csv",
            "--reference",
            "data/syn/Trajectory1/GT_trajectory1.csv",
            "--out",
            out,
        ];
        args.extend(extra);
        dcnet(d, &args)
    };
    let output = calibrate(&["--valid-column", "ok"], "flagged");
    assert!(output.status.success(), "{}", stderr(&output));
    let printed = stdout(&output);
    assert!(
        printed.contains("read: the DVL's 400 samples, 390 kept (10 left out: 10 flagged invalid)"),
        "{printed}"
    );
    // The garbage rows left out, the fit is the clean one's: no outlier among the rest.
    assert!(printed.contains(", 0 of them outliers"), "{printed}");
    // The 11 s from 99 s to 110 s without a sample cut the recording in two.
    assert!(
        printed.contains(
            "on its own stamps; 2 pieces (gaps over 3.00 s cut it), the longest loss 11.00 s\n"
        ),
        "{printed}"
    );
    // The corrected recording keeps the flagged samples in their place, with no
    // velocity and why.
    let corrected = std::fs::read_to_string(d.join("flagged/flagged-corrected.csv")).unwrap();
    let rows: Vec<&str> = corrected.lines().collect();
    assert_eq!(rows.len(), 401);
    assert_eq!(rows[0], "time_s,valid_at_s,vx_m_s,vy_m_s,vz_m_s,left_out");
    for row in &rows[101..=110] {
        assert!(row.ends_with(",,,,flagged"), "{row}");
    }
    assert!(rows[100].ends_with(','), "{}", rows[100]);
    // A gap limit of the command line's: 20 s cuts nothing; zero is refused, and
    // nothing is written.
    let limited =
        |limit: &str, out: &str| calibrate(&["--valid-column", "ok", "--gap-limit-s", limit], out);
    let output = limited("20", "limited");
    assert!(
        stdout(&output)
            .contains("; one piece (gaps over 20.00 s cut it), the longest loss 11.00 s"),
        "{}",
        stdout(&output)
    );
    let output = limited("0", "zero");
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains(
            "flagged.csv: gap_limit_s = 0: a gap limit must be a positive number of seconds"
        ),
        "{}",
        stderr(&output)
    );
    assert!(!d.join("zero").exists());
    let output = calibrate(&["--valid-column", "DVL X [m/s]"], "twice");
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output)
            .contains("--valid-column: \"DVL X [m/s]\" is named for another quantity too"),
        "{}",
        stderr(&output)
    );
    assert!(!d.join("twice").exists());
}
