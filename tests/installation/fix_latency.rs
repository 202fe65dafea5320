//! The fixes' latency (`calibrate --fix-latency`): fixes stamped a second after the
//! positions they give are fitted with their latency beside the DVL's clock, the two
//! and their sum printed with their intervals, the latency saved beside the
//! installation rather than among its terms (it is the fixes', not the DVL's) and
//! carried by `correct --fixes`; a latency beyond the search, and the flag without
//! fixes, refused by name. A latency known (`--fix-latency-s`) reads each fix
//! that long before its stamp, in `calibrate` and in `correct`.

use crate::common::{self, installed};
use crate::fixes::{FIX_TRUTH, number_after, positions, refused_naming};
use std::path::{Path, PathBuf};

/// A dive written by `common::installed` under [`FIX_TRUTH`], its positions every 5 s
/// as fixes stamped each of `lates` seconds after them, and the columns that read them.
struct LateFixDive {
    folder: PathBuf,
    dvl: String,
    attitude: String,
    /// One file per latency of `lates`, in their order.
    fixes: Vec<String>,
}

impl LateFixDive {
    fn written(folder: &Path, lates: &[f64]) -> LateFixDive {
        installed::write_installed(folder, 1, &[], FIX_TRUTH, 1);
        let files = dcnet_exp::data::paired::PairedFiles::akit(folder, 1);
        let segment = &crate::coverage::segments(std::slice::from_ref(&files))[0];
        let positions = positions(segment);
        let text = |p: &Path| p.to_str().unwrap().to_string();
        let fixes = (lates.iter())
            .map(|late_s| {
                let mut rows = String::from("t,n,e\n");
                for (i, p) in positions.iter().enumerate().step_by(5) {
                    let t = segment.recording.reference_time_s[i] + late_s;
                    rows.push_str(&format!("{t},{},{}\n", p[0], p[1]));
                }
                let path = folder.join(format!("fixes-{late_s}.csv"));
                std::fs::write(&path, rows).unwrap();
                text(&path)
            })
            .collect();
        std::fs::write(
            folder.join("columns.toml"),
            "[fix_columns]\ntime = \"t\"\nnorth_east = [\"n\", \"e\"]\n",
        )
        .unwrap();
        LateFixDive {
            folder: folder.to_path_buf(),
            dvl: text(&files.dvl),
            attitude: text(&files.reference),
            fixes,
        }
    }

    /// `command` (calibrate or correct) on the DVL against `fixes`, at 0.5 m of noise,
    /// with the arguments `extra`.
    fn run(&self, command: &str, fixes: &str, extra: &[&str]) -> std::process::Output {
        let mut args = vec![
            command,
            &self.dvl,
            "--fixes",
            fixes,
            "--attitude",
            &self.attitude,
            "--columns",
            "columns.toml",
            "--fix-noise-m",
            "0.5",
        ];
        args.extend(extra);
        common::dcnet(&self.folder, &args)
    }
}

/// The estimate and 95 % half-width of the term `row` names in the printed table.
fn estimate(text: &str, row: &str) -> (f64, f64) {
    let line = (text.lines())
        .find(|l| l.starts_with(&format!("| {row} ")))
        .unwrap_or_else(|| panic!("{row} in {text}"));
    (number_after(line, " | "), number_after(line, "± "))
}

#[test]
fn fixes_stamped_late_give_their_latency_beside_the_clock_and_the_sum() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let dive = LateFixDive::written(d, &[1.0, 5.0]);
    let [late, five] = [&dive.fixes[0], &dive.fixes[1]];
    let output = dive.run("calibrate", late, &["--fix-latency", "--save", "late.toml"]);
    let text = String::from_utf8_lossy(&output.stdout).to_string();
    assert!(output.status.success(), "{}", common::stderr(&output));
    println!("{text}");
    // Noise-free fixes on this dive's 1 Hz turns, whose dead reckoning is itself off
    // by decimetres (tests/installation/fixes.rs: FIX_TRUTH): within a tenth or so of
    // a second, the intervals' own coverage is tests/installation/fix_coverage.rs's.
    let (latency, latency_95) = estimate(&text, "fix latency");
    let (clock, clock_95) = estimate(&text, "time offset");
    assert!((latency - 1.0).abs() < 0.15, "{latency} ± {latency_95}");
    assert!(
        (clock - FIX_TRUTH.time_offset_s).abs() < 0.15,
        "{clock} ± {clock_95}"
    );
    let sum = number_after(&text, "the shift of the whole track against the fixes, ");
    assert!((sum - latency - clock).abs() < 1e-3, "{sum}");
    assert!((sum - 2.0).abs() < 0.05, "{sum}");
    // The latency is the fixes': saved beside the DVL's terms, not among them.
    let saved =
        dcnet_exp::operator::installation_file::SavedInstallation::read(&d.join("late.toml"))
            .unwrap();
    assert!(saved.terms.iter().all(|t| !t.name.contains("latency")));
    let carried = saved.fix_latency.as_ref().expect("the latency saved");
    assert!((carried.value - latency).abs() < 1e-3, "{carried:?}");
    // `correct --fixes` on the same late fixes reads them by the latency carried, and
    // finds the clock again where the calibration put it; given, another stands.
    let correct = |extra: &[&str], out: &str| {
        let mut args = vec!["--installation", "late.toml", "--out", out];
        args.extend(extra);
        let output = dive.run("correct", late, &args);
        assert!(output.status.success(), "{}", common::stderr(&output));
        String::from_utf8_lossy(&output.stdout).to_string()
    };
    let text = correct(&[], "carried");
    assert!(
        text.contains("s before its stamp, the latency carried with the installation"),
        "{text}"
    );
    let found = number_after(&text, "the time offset at ");
    assert!(
        (found - clock).abs() < 0.05,
        "{found} against {clock}: {text}"
    );
    let text = correct(&["--fix-latency-s", "0.5"], "given");
    assert!(
        text.contains("(each read 0.5 s before its stamp, the latency given)"),
        "{text}"
    );
    // Fixes 5 s late: a latency beyond the search is refused, not fitted at its edge.
    let output = dive.run("calibrate", five, &["--fix-latency"]);
    refused_naming(&output, "the fixes' latency that fits them best", &[]);
    // The flag goes with fixes.
    let output = common::dcnet(
        d,
        &[
            "calibrate",
            &dive.dvl,
            "--reference",
            &dive.attitude,
            "--fix-latency",
        ],
    );
    refused_naming(&output, "--fix-latency: goes with position fixes", &[]);
}

/// The saved terms of `file` in `dir`: each name and value.
fn saved_terms(dir: &Path, file: &str) -> Vec<(String, f64)> {
    let saved =
        dcnet_exp::operator::installation_file::SavedInstallation::read(&dir.join(file)).unwrap();
    saved
        .terms
        .iter()
        .map(|t| (t.name.clone(), t.value))
        .collect()
}

#[test]
fn a_latency_given_reads_each_fix_before_its_stamp_in_calibrate_and_correct() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let dive = LateFixDive::written(d, &[0.0, 1.0]);
    let run = |command: &str, fixes: &str, extra: &[&str]| dive.run(command, fixes, extra);
    let [on_time, late] = [&dive.fixes[0], &dive.fixes[1]];
    let output = run("calibrate", &on_time, &["--save", "on-time.toml"]);
    assert!(output.status.success(), "{}", common::stderr(&output));
    let output = run(
        "calibrate",
        &late,
        &[
            "--fix-latency-s",
            "1",
            "--save",
            "late.toml",
            "--out",
            "late",
        ],
    );
    assert!(output.status.success(), "{}", common::stderr(&output));
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(
        text.contains("(each read 1 s before its stamp, the latency given)"),
        "{text}"
    );
    // The same fixes as on time, but for the rounding of t + 1 − 1.
    let (on_time_terms, late_terms) = (saved_terms(d, "on-time.toml"), saved_terms(d, "late.toml"));
    assert_eq!(on_time_terms.len(), late_terms.len());
    for ((name, a), (_, b)) in on_time_terms.iter().zip(&late_terms) {
        assert!((a - b).abs() < 1e-6, "{name}: {a} against {b}");
    }
    // `correct` reads the next dive's fixes by the same latency: the clock it finds
    // again is the one the fixes on time give. Unshifted, the installation fits the
    // late fixes worse than no terms, and the dive is refused.
    let correct = |fixes: &str, extra: &[&str], out: &str| {
        let mut args = vec!["--installation", "late.toml", "--out", out];
        args.extend(extra);
        let output = run("correct", fixes, &args);
        assert!(output.status.success(), "{}", common::stderr(&output));
        String::from_utf8_lossy(&output.stdout).to_string()
    };
    let shifted = correct(&late, &["--fix-latency-s", "1"], "shifted");
    assert!(
        shifted.contains("each read 1 s before its stamp"),
        "{shifted}"
    );
    let on_time = correct(&on_time, &[], "on-time");
    // The value column of correct's table (it has no interval's).
    let clock = |text: &str| {
        let line = (text.lines())
            .find(|l| l.starts_with("| time offset "))
            .unwrap_or_else(|| panic!("{text}"));
        number_after(line, " | ")
    };
    assert!(
        (clock(&shifted) - clock(&on_time)).abs() < 1e-3,
        "{shifted}\n{on_time}"
    );
    let unshifted = ["--installation", "late.toml", "--out", "unshifted"];
    refused_naming(
        &run("correct", &late, &unshifted),
        "further from the dead reckoning than no terms do",
        &unshifted,
    );
    for bad in ["nan", "120", "inf"] {
        let output = run("calibrate", &late, &["--fix-latency-s", bad]);
        refused_naming(&output, "--fix-latency-s: ", &[bad]);
    }
    let both = ["--fix-latency-s", "1", "--fix-latency"];
    refused_naming(
        &run("calibrate", &late, &both),
        "--fix-latency: estimates",
        &both,
    );
}
