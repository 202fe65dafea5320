//! How long to calibrate, as a user meets it: the Kalman filters and the calibration
//! time of a quick run (stored, reported, drawn), a sweep over the tolerance that
//! re-runs no Monte Carlo, the installation study's extended Kalman filter on
//! synthetic recordings of a known installation, and bad `[estimators.kalman]` and
//! `[calibration.kalman]` keys refused at their line.

use crate::common;

use common::installed::{INSTALLED, write_installed, write_study_spec};
use common::*;
use std::path::Path;

/// `calibration_time.parquet` of `folder` as (DVL, estimator, error model,
/// calibration time, RMSE at the longest window).
fn times(folder: &Path) -> Vec<(String, String, Option<String>, Option<f64>, f64)> {
    let batch = read_parquet(&folder.join("calibration_time.parquet"));
    let text = |c| strings(&batch, c);
    let (dvl, estimator, model) = (text("dvl"), text("estimator"), text("error_model"));
    let time = floats(&batch, "calibration_time_s");
    let long = floats(&batch, "long_window_rmse_cm_s");
    (0..batch.num_rows())
        .map(|i| {
            (
                dvl[i].clone().unwrap(),
                estimator[i].clone().unwrap(),
                model[i].clone(),
                time[i],
                long[i].unwrap(),
            )
        })
        .collect()
}

/// The held-out curve of one method: (length s, RMSE).
fn curve(folder: &Path, dvl: &str, estimator: &str, model: Option<&str>) -> Vec<(f64, f64)> {
    let batch = read_parquet(&folder.join("held_out.parquet"));
    let (dvls, estimators, models) = (
        strings(&batch, "dvl"),
        strings(&batch, "estimator"),
        strings(&batch, "error_model"),
    );
    let (lengths, rmse) = (floats(&batch, "length_s"), floats(&batch, "rmse_cm_s"));
    (0..batch.num_rows())
        .filter(|&i| {
            dvls[i].as_deref() == Some(dvl)
                && estimators[i].as_deref() == Some(estimator)
                && models[i].as_deref() == model
        })
        .map(|i| (lengths[i].unwrap(), rmse[i].unwrap()))
        .collect()
}

/// Every method of the quick run has a calibration time that its own stored curve
/// gives by the definition: read at the windows, the shortest length after which it
/// stays within 10 % of what it changes (from its first window's value down to the
/// bound's at the longest) of its own value there, above or below, for a method that
/// ends within 10 % of the bound's own drop over the windows above the bound (none
/// otherwise: on DVL1's floor of 5.9 cm/s, 10 % of the whole RMSE let every method
/// through); the filters' curves are taken after every sample, DCNet's at the
/// windows; the report and the figure have them.
#[test]
fn every_method_has_the_calibration_time_its_held_out_curve_gives() {
    let dir = project(false);
    let d = dir.path();
    small_quick_run(d, &[]);
    let folder = d.join("results/quick");
    let rows = times(&folder);
    let estimators: Vec<&str> = rows.iter().map(|r| r.1.as_str()).collect();
    for kind in ["kalman", "kalman_beam", "least_squares", "dcnet", "bound"] {
        assert!(
            estimators.contains(&kind),
            "{kind} missing from {estimators:?}"
        );
    }
    let windows = [20.0, 40.0, 60.0, 80.0, 100.0];
    let mut never = 0;
    for (dvl, estimator, model, time, long) in &rows {
        let curve = curve(&folder, dvl, estimator, model.as_deref());
        let last = curve.last().unwrap();
        assert_eq!(last.1, *long, "{dvl} {estimator} {model:?}");
        let at: Vec<(f64, f64)> = curve
            .iter()
            .copied()
            .filter(|(length, _)| windows.contains(length))
            .collect();
        let bound_curve = self::curve(&folder, dvl, "bound", None);
        let bound = bound_curve.last().unwrap().1;
        let bound_first = bound_curve
            .iter()
            .rfind(|(length, _)| *length <= windows[0])
            .unwrap()
            .1;
        let stays = |within: &dyn Fn(f64) -> bool| {
            (0..at.len())
                .find(|&i| at[i..].iter().all(|&(_, rmse)| within(rmse)))
                .map(|i| at[i].0)
        };
        let band = 0.1 * (at[0].1.max(*long) - bound.min(*long));
        let reaches_the_bound = *long <= bound + 0.1 * (bound_first - bound);
        let expected = stays(&|rmse| (rmse - long).abs() <= band).filter(|_| reaches_the_bound);
        assert_eq!(*time, expected, "{dvl} {estimator} {model:?}");
        never += usize::from(time.is_none());
        let lengths = curve.len();
        match estimator.as_str() {
            "dcnet" => assert_eq!(lengths, 5, "DCNet at the quick spec's windows"),
            _ => assert_eq!(lengths, 100, "{estimator} after every sample up to 100 s"),
        }
    }
    // DVL2's scale-and-bias methods settle on values far above the bound: never.
    assert!(never > 0, "{rows:?}");
    let report = std::fs::read_to_string(folder.join("report.md")).unwrap();
    assert!(
        report.contains("### How long to calibrate DVL2"),
        "{report}"
    );
    assert!(report.contains("### The paper's claim: an 80 % shorter calibration"));
    let tex = std::fs::read_to_string(folder.join("report.tex")).unwrap();
    assert!(
        tex.contains("\\label{tab:quick-calibration-time-3}"),
        "{tex}"
    );
    assert_png(&d.join("plots/quick/kalman_terms.png"), (2160, 1320));
    let batch = read_parquet(&folder.join("terms_in_time.parquet"));
    // Two DVLs × 200 samples of SCal × (EM1 1 + EM2 3 + EM3 1 + EM4 3 + EM5 6 + beam 2).
    assert_eq!(batch.num_rows(), 2 * 200 * 16);

    // A folder written before the calibration time still plots, without its section.
    let manifest_path = folder.join("manifest.json");
    let mut manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&manifest_path).unwrap()).unwrap();
    for table in [
        "held_out.parquet",
        "calibration_time.parquet",
        "terms_in_time.parquet",
    ] {
        std::fs::remove_file(folder.join(table)).unwrap();
        manifest["files_sha256"]
            .as_object_mut()
            .unwrap()
            .remove(table);
    }
    std::fs::write(&manifest_path, manifest.to_string()).unwrap();
    let output = dcnet(d, &["plot", "results/quick"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let report = std::fs::read_to_string(folder.join("report.md")).unwrap();
    assert!(!report.contains("How long to calibrate"), "{report}");
}

/// A sweep over the tolerance and the filters' random walk: the tolerance changes the
/// calibration times and computes no Monte Carlo block again; the random walk runs the
/// filters' blocks only.
#[test]
fn a_sweep_over_the_tolerance_reuses_every_block_and_the_random_walk_only_the_filters() {
    let dir = project(false);
    let d = dir.path();
    write_quick_sweep(
        d,
        "\"calibration.time_tolerance_pct\" = [10.0, 1.0]\n\"estimators.kalman.bias_random_walk_cm_s_per_sqrt_s\" = [0.0, 0.01]\n",
    );
    let small = [
        "--set",
        "calibration.monte_carlo_runs=3",
        "--set",
        "training.epochs=2",
    ];
    let output = dcnet(
        d,
        &[&["run", "experiments/sweep.toml"][..], &small].concat(),
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let blocks = std::fs::read_dir(d.join("results/.cache/monte_carlo"))
        .unwrap()
        .filter(|entry| entry.as_ref().unwrap().path().extension() == Some("parquet".as_ref()))
        .count();
    // 2 DVLs × (baseline, 5 least squares, beam WLS, 5 + 1 filters, 5 DCNets, floor) =
    // 38 blocks at the first walk, and the 12 filter blocks again at the second.
    assert_eq!(blocks, 38 + 12);
    let point = |name: &str| d.join("results/quick-sweep").join(name);
    let wide = times(&point(
        "time_tolerance_pct=10.0,kalman.bias_random_walk_cm_s_per_sqrt_s=0.0",
    ));
    let tight = times(&point(
        "time_tolerance_pct=1.0,kalman.bias_random_walk_cm_s_per_sqrt_s=0.0",
    ));
    let mut longer = 0;
    for (w, t) in wide.iter().zip(&tight) {
        assert_eq!((&w.0, &w.1, &w.2, w.4), (&t.0, &t.1, &t.2, t.4));
        if let (Some(w), Some(t)) = (w.3, t.3) {
            assert!(t >= w, "a tighter tolerance cannot take less time");
            longer += usize::from(t > w);
        }
    }
    assert!(longer > 0, "1 % takes longer than 10 % somewhere");
}

/// The installation study's Kalman filter on four synthetic recordings of a known
/// installation: its terms after 400 s are within four of their standard deviations of
/// the truth on the turning segments, its rows stand beside the fit's in every table,
/// the terms against time and the calibration times are stored, and the figure drawn;
/// with a shorter longest window the filter runs up to it only.
#[test]
fn the_installation_filter_recovers_a_known_installation_and_reports_its_calibration_time() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 4, &[4], INSTALLED, 11);
    write_study_spec(
        d,
        "syn",
        "syn",
        4,
        "\n[calibration.kalman]\nmodels = [\"lever+offset+bias+scale\"]\n",
    );
    let output = dcnet(d, &["run", "experiments/syn.toml"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let folder = d.join("results/syn");
    let batch = read_parquet(&folder.join("terms.parquet"));
    let method = strings(&batch, "method");
    let (calibration, term) = (strings(&batch, "calibration"), strings(&batch, "term"));
    let (window, value, std) = (
        floats(&batch, "window_s"),
        floats(&batch, "value"),
        floats(&batch, "std"),
    );
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
    let mut checked = 0;
    for i in 0..batch.num_rows() {
        let filtered = method[i].as_deref() == Some("Kalman filter lever+offset+bias+scale");
        if !filtered || window[i] != Some(400.0) || calibration[i].as_deref() == Some("S4") {
            continue;
        }
        let term = term[i].clone().unwrap();
        let z = (value[i].unwrap() - truth(&term)) / std[i].unwrap();
        assert!(z.abs() < 4.0, "{:?} {term}: z = {z}", calibration[i]);
        checked += 1;
    }
    assert_eq!(checked, 3 * 8, "three turning segments × eight terms");
    let summary = read_parquet(&folder.join("summary.parquet"));
    assert!(
        strings(&summary, "method")
            .iter()
            .any(|m| m.as_deref() == Some("Kalman filter lever+offset+bias+scale"))
    );
    let filtered = read_parquet(&folder.join("terms_in_time.parquet"));
    // Four segments × 394 samples inside the 3-s margin at each end × eight terms.
    assert_eq!(filtered.num_rows(), 4 * 394 * 8);
    let timing = read_parquet(&folder.join("calibration_time.parquet"));
    assert!(timing.num_rows() > 0);
    let report = std::fs::read_to_string(folder.join("report.md")).unwrap();
    assert!(report.contains("### How long to calibrate"), "{report}");
    assert!(d.join("plots/syn/installation_kalman_terms.png").is_file());

    // Calibrated on the first 100 s only, the filter stops there: samples 3 to 99 of
    // each segment (inside the 3-s margin), and nothing after.
    let output = dcnet(
        d,
        &[
            "run",
            "experiments/syn.toml",
            "--set",
            "calibration.window_s=[100.0]",
            "--out",
            "short",
            "--no-plots",
        ],
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let filtered = read_parquet(&d.join("short/syn/terms_in_time.parquet"));
    assert_eq!(filtered.num_rows(), 4 * 97 * 8);
    let last = floats(&filtered, "time_s")
        .into_iter()
        .flatten()
        .fold(0.0, f64::max);
    assert!(last < 100.0, "{last}");
}

#[test]
fn bad_kalman_keys_are_refused_at_their_line() {
    let dir = project(false);
    let d = dir.path();
    let output = dcnet(
        d,
        &[
            "run",
            "experiments/quick.toml",
            "--set",
            "estimators.kalman.prior_bias_cm_s=-1",
            "--set",
            "calibration.time_tolerance_pct=0",
        ],
    );
    assert_eq!(output.status.code(), Some(1));
    let text = stderr(&output);
    assert!(
        text.contains("estimators.kalman.prior_bias_cm_s: -1 must be finite and above zero"),
        "{text}"
    );
    assert!(
        text.contains("calibration.time_tolerance_pct: 0 must be a finite number above zero"),
        "{text}"
    );
    write_installed(&d.join("data/syn"), 2, &[], INSTALLED, 3);
    write_study_spec(
        d,
        "syn",
        "syn",
        2,
        "\n[calibration.kalman]\nmodels = [\"lever\"]\nprior_time_offset_s = 0.0\n",
    );
    let output = dcnet(d, &["run", "experiments/syn.toml"]);
    assert_eq!(output.status.code(), Some(1));
    let text = stderr(&output);
    assert!(
        text.contains("calibration.kalman.models[0]: \"lever\" is not a model of [[calibration.models]]; defined: lever+offset+bias+scale"),
        "{text}"
    );
    assert!(
        text.contains("calibration.kalman.prior_time_offset_s: 0 must be finite and above zero"),
        "{text}"
    );
}
