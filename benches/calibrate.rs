//! `cargo bench --bench calibrate`: `calibrate` (fit, bound, Kalman filter, settling
//! curve, corrected files) on synthetic recordings at 100 Hz of 36,000 and 360,000 rows,
//! and with `-- --long` 3,600,000 (ten hours); beside it, the installation study
//! (`run --no-plots` of two such recordings, each calibrated and scored on the other,
//! its least squares and Kalman filter) on the same lengths. Prints the seconds of each
//! and the seconds per 100,000 rows, which stays flat where the cost is linear in the
//! recording's length. With `-- --rates`, a case of its own instead: a ten-hour dive
//! with the DVL at 10 Hz (360,000 samples) beside a reference at 100 Hz (3,600,000
//! rows) in two files, `calibrate` alone, with the process's peak resident memory
//! (Linux's VmHWM, which counts the synthetic files' writing too). With `-- --report`,
//! the report of a ten-hour recording at 10 Hz (360,000 samples), its reference with
//! positions: `calibrate`, then its figures drawn (residual, filter's terms, plan view)
//! and `report.md` and `report.html` written, each timed; with `--
//! --fix-report`, the same recording calibrated against its positions at 1 Hz as fixes
//! (36,000) with a 300-s blackout, then its report (plan view, fixes' residual).

#[allow(dead_code)]
#[path = "../tests/common/installed.rs"]
mod installed;

use dcnet_exp::installation::terms::names::TermName;
use dcnet_exp::operator::calibrate::{CalibrateArgs, Calibration, calibrate};
use dcnet_exp::operator::inputs::Reading;
use dcnet_exp::report::operator::calibrate::calibration_text;
use dcnet_exp::report::operator::figures::calibration_figures;
use dcnet_exp::report::operator::page::write_report;
use std::time::Instant;

fn main() {
    if std::env::args().any(|a| a == "--rates") {
        return rates();
    }
    if std::env::args().any(|a| a == "--report") {
        return report();
    }
    if std::env::args().any(|a| a == "--fix-report") {
        return fix_report();
    }
    let long = std::env::args().any(|a| a == "--long");
    let mut rows = vec![36_000, 360_000];
    if long {
        rows.push(3_600_000);
    }
    println!(
        "| rows (100 Hz) | hours | calibrate s | s per 100,000 rows | study of two such recordings s | s per 100,000 rows |"
    );
    println!("|---|---|---|---|---|---|");
    for rows in rows {
        let dir = tempfile::tempdir().unwrap();
        installed::write_installed_sampled(
            &dir.path().join("data/long"),
            2,
            &[],
            installed::INSTALLED,
            7,
            (rows, 0.01),
        );
        let segment = dir.path().join("data/long/Trajectory1");
        let dvl = segment.join("DVL_trajectory1.csv");
        let reference = segment.join("GT_trajectory1.csv");
        let (seconds, recorded) = calibrate_seconds(&dvl, &reference, &dir.path().join("out"));
        assert_eq!(recorded, rows);
        let study = study_seconds(dir.path());
        let per = |s: f64| s / rows as f64 * 100_000.0;
        println!(
            "| {rows} | {:.1} | {seconds:.1} | {:.2} | {study:.1} | {:.2} |",
            rows as f64 / 360_000.0,
            per(seconds),
            per(study)
        );
    }
}

/// The terms calibrated: lever arm, time offset, bias and scale.
const TERMS: [TermName; 4] = [
    TermName::LeverArm,
    TermName::TimeOffset,
    TermName::Bias,
    TermName::Scale,
];

/// Seconds of `calibrate` of the DVL file `dvl` beside `reference` into `out`, and the
/// DVL samples it read.
fn calibrate_seconds(
    dvl: &std::path::Path,
    reference: &std::path::Path,
    out: &std::path::Path,
) -> (f64, usize) {
    let (seconds, calibration) = timed_calibration(dvl, (reference, None), out);
    (seconds, calibration.recorded)
}

/// `calibrate` of the DVL file `dvl` beside `reference` (its columns named by `columns`
/// where given) into `out`, and its seconds.
fn timed_calibration(
    dvl: &std::path::Path,
    (reference, columns): (&std::path::Path, Option<&std::path::Path>),
    out: &std::path::Path,
) -> (f64, Calibration) {
    let args = CalibrateArgs {
        dvl,
        reference: Some(reference),
        columns,
        reading: Reading::default(),
        terms: &TERMS,
        window_s: None,
        dvl_noise_cm_s: 2.0,
        reference_noise_cm_s: 0.5,
        tolerance_pct: 10.0,
        out,
        save: None,
        dive_terms: &[TermName::TimeOffset],
        search_s: None,
    };
    let clock = Instant::now();
    let calibration = calibrate(&args).expect("the synthetic recording calibrates");
    (clock.elapsed().as_secs_f64(), calibration)
}

/// The `--report` case: ten hours at 10 Hz calibrated against a reference with
/// positions, then its report drawn (residual, filter's terms, plan view) and written.
fn report() {
    let dir = tempfile::tempdir().unwrap();
    let rows = 360_000;
    installed::write_installed_sampled(
        &dir.path().join("data/report"),
        1,
        &[],
        installed::INSTALLED,
        7,
        (rows, 0.1),
    );
    let segment = dir.path().join("data/report/Trajectory1");
    let (dvl, reference) = (
        segment.join("DVL_trajectory1.csv"),
        segment.join("GT_trajectory1.csv"),
    );
    installed::add_positions(&reference);
    let columns = dir.path().join("columns.toml");
    std::fs::write(&columns, installed::COLUMNS_WITH_POSITIONS).unwrap();
    let out = dir.path().join("out");
    let (calibrated_s, calibration) = timed_calibration(&dvl, (&reference, Some(&columns)), &out);
    let printed = calibration_text(&calibration);
    let (drawn_s, written_s, written, bytes) = timed_report(&out, &printed, || {
        calibration_figures(&calibration, "report")
    });
    println!(
        "| hours | samples (10 Hz) | calibrate s | figures drawn s | report written s (PNG, SVG, Markdown, HTML) | files | MiB written |"
    );
    println!("|---|---|---|---|---|---|---|");
    println!(
        "| 10 | {} | {calibrated_s:.1} | {drawn_s:.2} | {written_s:.2} | {} | {:.1} |",
        calibration.recorded,
        written.len(),
        bytes as f64 / (1 << 20) as f64
    );
    for path in &written {
        let size = std::fs::metadata(path).map_or(0, |m| m.len());
        println!(
            "{}: {:.2} MiB",
            path.file_name().unwrap().to_string_lossy(),
            size as f64 / (1 << 20) as f64
        );
    }
}

/// The figures `draw` draws, then the report of them and of what was `printed` written
/// into `out`: the seconds of each, the files written and their bytes.
fn timed_report(
    out: &std::path::Path,
    printed: &str,
    draw: impl FnOnce() -> dcnet_exp::report::kit::plots::draw::PlotResult<
        Vec<(String, dcnet_exp::report::kit::plots::canvas::Outcome)>,
    >,
) -> (f64, f64, Vec<std::path::PathBuf>, u64) {
    let clock = Instant::now();
    let drawn = draw().expect("the figures draw");
    let drawn_s = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let written =
        write_report(out, "A ten-hour recording", printed, drawn).expect("the report is written");
    let written_s = clock.elapsed().as_secs_f64();
    let bytes: u64 = (written.iter())
        .map(|p| std::fs::metadata(p).map_or(0, |m| m.len()))
        .sum();
    (drawn_s, written_s, written, bytes)
}

/// The `--fix-report` case: ten hours at 10 Hz calibrated against its positions each
/// second as fixes, a 300-s blackout five hours in, then its report drawn and written.
fn fix_report() {
    use dcnet_exp::installation::estimate::fixes::default_fix_terms;
    use dcnet_exp::operator::calibrate_fixes::{FixArgs, FixFiles, calibrate_fixes};
    use dcnet_exp::operator::fix_drifts::BlackoutAsked;
    use dcnet_exp::report::operator::fix_figures::fix_calibration_figures;
    use dcnet_exp::report::operator::fixes::fixes_text;
    let dir = tempfile::tempdir().unwrap();
    installed::write_installed_sampled(
        &dir.path().join("data/report"),
        1,
        &[],
        installed::INSTALLED,
        7,
        (360_000, 0.1),
    );
    let segment = dir.path().join("data/report/Trajectory1");
    let (dvl, reference) = (
        segment.join("DVL_trajectory1.csv"),
        segment.join("GT_trajectory1.csv"),
    );
    // The reference's positions each second.
    let mut fixes = String::from("t,n,e\n");
    for (t, position) in installed::add_positions(&reference).iter().step_by(10) {
        fixes.push_str(&format!("{t},{},{}\n", position[0], position[1]));
    }
    let fixes_path = dir.path().join("fixes.csv");
    std::fs::write(&fixes_path, fixes).unwrap();
    let columns = dir.path().join("columns.toml");
    std::fs::write(
        &columns,
        "[fix_columns]\ntime = \"t\"\nnorth_east = [\"n\", \"e\"]\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let args = FixArgs {
        files: FixFiles {
            dvl: &dvl,
            attitude: &reference,
            fixes: &fixes_path,
            fix_topic: None,
            columns: Some(&columns),
            reading: Reading::default(),
            fix_latency_s: None,
        },
        terms: &default_fix_terms(),
        dive_terms: &[TermName::TimeOffset],
        fix_noise_m: Some(0.5),
        depth_noise_m: None,
        fix_latency: false,
        dvl_noise_cm_s: 2.0,
        save: None,
        out: &out,
        blackout: Some(BlackoutAsked {
            start_s: 18_000.0,
            length_s: 300.0,
        }),
    };
    let clock = Instant::now();
    let calibration = calibrate_fixes(&args).expect("the synthetic recording calibrates");
    let calibrated_s = clock.elapsed().as_secs_f64();
    let printed = fixes_text(&calibration);
    let (drawn_s, written_s, _, bytes) = timed_report(&out, &printed, || {
        fix_calibration_figures(&calibration, "report")
    });
    println!(
        "| hours | samples kept (10 Hz) | fixes (1 Hz) | calibrate --fixes s | figures drawn s | report written s | MiB written |"
    );
    println!("|---|---|---|---|---|---|---|");
    println!(
        "| 10 | {} | {} | {calibrated_s:.1} | {drawn_s:.2} | {written_s:.2} | {:.1} |",
        calibration.read.kept,
        calibration.fixes,
        bytes as f64 / (1 << 20) as f64
    );
}

/// The `--rates` case: ten hours, the DVL at 10 Hz beside the reference at 100 Hz.
fn rates() {
    let dir = tempfile::tempdir().unwrap();
    let (rows, dvl_every) = (3_600_000, 10);
    installed::write_installed_at_rates(
        &dir.path().join("data/rates"),
        1,
        &[],
        installed::INSTALLED,
        7,
        (rows, 0.01),
        dvl_every,
    );
    let segment = dir.path().join("data/rates/Trajectory1");
    let (seconds, recorded) = calibrate_seconds(
        &segment.join("DVL_trajectory1.csv"),
        &segment.join("GT_trajectory1.csv"),
        &dir.path().join("out"),
    );
    assert_eq!(recorded, rows / dvl_every);
    let peak = installed::peak_resident_memory();
    println!(
        "| hours | DVL samples (10 Hz) | reference rows (100 Hz) | calibrate s | peak resident memory |"
    );
    println!("|---|---|---|---|---|");
    println!("| 10 | {recorded} | {rows} | {seconds:.1} | {peak} |");
}

/// Seconds of `dcnet-exp run --no-plots` of a study over the two recordings in
/// `dir/data/long`: calibrated on the first 100 s and on all of each, its Kalman filter
/// beside its least squares, each scored on the other.
fn study_seconds(dir: &std::path::Path) -> f64 {
    installed::write_study_spec(
        dir,
        "long",
        "long",
        2,
        "\n[calibration.kalman]\nmodels = [\"lever+offset+bias+scale\"]\n",
    );
    let clock = Instant::now();
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_dcnet-exp"))
        .args(["run", "experiments/long.toml", "--no-plots"])
        .current_dir(dir)
        .output()
        .expect("dcnet-exp runs");
    let seconds = clock.elapsed().as_secs_f64();
    let log = String::from_utf8_lossy(&output.stderr);
    assert!(
        output.status.success(),
        "the study of the synthetic recordings failed: {}",
        log.lines().last().unwrap_or_default()
    );
    seconds
}
