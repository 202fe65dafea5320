//! `cargo bench --bench dive`: the operator's two costs beside the recording's length.
//! `correct` of a dive at 10 Hz of a quarter, a half and a whole hour with an
//! installation saved from a 400-s calibration (its clock found again from the first
//! 60 s, the dive corrected and written, CSV and Parquet); and the joint calibration of
//! 10, 30 and 100 synthetic segments of 400 s at 1 Hz, each with its own clock (the
//! vehicle's lever arm, scale and bias shared). Prints the seconds of each, and per
//! 100,000 rows or per segment, which stay flat where the cost is linear. With
//! `-- --hour correct` or `-- --hour joint`, a case of its own instead: `correct` of an
//! hour's dive at 100 Hz (360,000 rows, its clock found again from the first 60 s), or
//! the joint `calibrate` of two such dives, with the process's peak resident memory.

#[allow(dead_code)]
#[path = "../tests/common/installed.rs"]
mod installed;

use dcnet_exp::data::paired::{PairedColumns, PairedFiles, read};
use dcnet_exp::installation::estimate::bound::{DEFAULT_TOLERANCES, Noise};
use dcnet_exp::installation::estimate::fit::fit;
use dcnet_exp::installation::estimate::joint::{JointRecording, joint_fit, starts_from};
use dcnet_exp::installation::frames::Reference;
use dcnet_exp::installation::terms::names::TermName;
use dcnet_exp::installation::terms::{PerAxis, TermSet};
use dcnet_exp::operator::calibrate::{CalibrateArgs, calibrate};
use dcnet_exp::operator::calibrate_joint::{JointArgs, calibrate_joint};
use dcnet_exp::operator::correct::{CorrectArgs, correct};
use dcnet_exp::operator::inputs::Reading;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(at) = args.iter().position(|a| a == "--hour") {
        return hour(args.get(at + 1).map(String::as_str));
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let saved = saved_installation(d);
    println!("| dive at 10 Hz | rows | correct s | s per 100,000 rows |");
    println!("|---|---|---|---|");
    for minutes in [15, 30, 60] {
        let rows = minutes * 600;
        let dive = d.join(format!("dive{minutes}"));
        let clocked = installed::Installed {
            time_offset_s: 7.3,
            ..installed::INSTALLED
        };
        installed::write_installed_sampled(&dive, 1, &[], clocked, 2, (rows, 0.1));
        let at = dive.join("Trajectory1");
        let (dvl, reference) = (
            at.join("DVL_trajectory1.csv"),
            at.join("GT_trajectory1.csv"),
        );
        let clock = Instant::now();
        let corrected = corrected((&dvl, &reference), &saved, &dive.join("out"));
        let seconds = clock.elapsed().as_secs_f64();
        let found = corrected.applied.time_offset_s;
        assert!((found - 7.3).abs() < 0.1, "the clock found again: {found}");
        println!(
            "| {minutes} min | {rows} | {seconds:.2} | {:.2} |",
            seconds / rows as f64 * 1e5
        );
    }
    println!();
    println!("| segments of 400 s at 1 Hz | joint fit s | s per segment |");
    println!("|---|---|---|");
    let noise = Noise {
        dvl_m_s: 0.02,
        reference_m_s: 0.005,
    };
    let set = TermSet {
        scale: PerAxis::Scalar,
        lever_arm: true,
        time_offset: true,
        bias: PerAxis::PerAxis,
        ..TermSet::NONE
    };
    let clock_only = TermSet {
        time_offset: true,
        ..TermSet::NONE
    };
    for count in [10, 30, 100] {
        let folder = d.join(format!("segments{count}"));
        let recordings: Vec<_> = (0..count)
            .map(|k| {
                let installed = installed::Installed {
                    time_offset_s: -2.0 + 4.0 * k as f64 / count as f64,
                    ..installed::INSTALLED
                };
                let at = folder.join(format!("s{k}"));
                installed::write_installed(&at, 1, &[], installed, 100 + k as u64);
                let recording = read(&PairedFiles::akit(&at, 1), &PairedColumns::akit()).unwrap();
                let reference = Reference::new(&recording);
                (recording, reference)
            })
            .collect();
        let joint: Vec<JointRecording> = recordings
            .iter()
            .map(|(r, reference)| JointRecording {
                time_s: &r.time_s,
                dvl_m_s: &r.dvl_m_s,
                reference,
            })
            .collect();
        let clock = Instant::now();
        let first = fit(joint[0].time_s, joint[0].dvl_m_s, joint[0].reference, set).unwrap();
        let starts = starts_from(&joint, first.installation, 30.0);
        let fitted = joint_fit(
            &joint,
            &starts,
            (set, clock_only),
            (noise, &DEFAULT_TOLERANCES),
        )
        .expect("the segments calibrate jointly");
        let seconds = clock.elapsed().as_secs_f64();
        assert_eq!(fitted.dives.len(), count);
        println!("| {count} | {seconds:.2} | {:.3} |", seconds / count as f64);
    }
}

/// The `--hour` case: `correct` (`which` = "correct") or the joint `calibrate` ("joint")
/// of dives of an hour at 100 Hz, each on its own clock.
fn hour(which: Option<&str>) {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rows = 360_000;
    // The first within the ±3 s a fit alone scans (a joint calibration starts from its
    // fit), the second's clock found by the search.
    let dives: Vec<_> = [1.3, 7.3]
        .iter()
        .enumerate()
        .map(|(k, &time_offset_s)| {
            let at = d.join(format!("dive{k}"));
            let clocked = installed::Installed {
                time_offset_s,
                ..installed::INSTALLED
            };
            installed::write_installed_sampled(&at, 1, &[], clocked, 3 + k as u64, (rows, 0.01));
            let at = at.join("Trajectory1");
            (
                at.join("DVL_trajectory1.csv"),
                at.join("GT_trajectory1.csv"),
            )
        })
        .collect();
    let terms = [TermName::LeverArm, TermName::TimeOffset, TermName::Bias];
    let clock = Instant::now();
    match which {
        Some("correct") => {
            let saved = saved_installation(d);
            let clock = Instant::now();
            let corrected = corrected((&dives[1].0, &dives[1].1), &saved, &d.join("out"));
            let found = corrected.applied.time_offset_s;
            assert!((found - 7.3).abs() < 0.1, "the clock found again: {found}");
            report("correct", clock.elapsed().as_secs_f64());
        }
        Some("joint") => {
            let (dvls, references): (Vec<_>, Vec<_>) = dives.into_iter().unzip();
            let joint = calibrate_joint(&JointArgs {
                dvls: &dvls,
                references: &references,
                columns: None,
                reading: Reading::default(),
                terms: &terms,
                dive_terms: &[TermName::TimeOffset],
                window_s: None,
                dvl_noise_cm_s: 2.0,
                reference_noise_cm_s: 0.5,
                tolerance_pct: 10.0,
                out: &d.join("joint"),
                save: None,
            })
            .expect("the dives calibrate jointly");
            let found = joint.joint.dives[1].time_offset_s;
            assert!((found - 7.3).abs() < 0.1, "the second clock: {found}");
            report("joint calibrate", clock.elapsed().as_secs_f64());
        }
        _ => panic!("--hour takes correct or joint"),
    }
}

/// Prints the `--hour` case's line.
fn report(what: &str, seconds: f64) {
    println!("| an hour at 100 Hz (360,000 rows) | s | peak resident memory |");
    println!("|---|---|---|");
    println!(
        "| {what} | {seconds:.1} | {} |",
        installed::peak_resident_memory()
    );
}

/// The installation `calibrate --save` finds on 400 s at 1 Hz (lever arm, time offset,
/// bias, scale), saved in `d`: its path.
fn saved_installation(d: &std::path::Path) -> std::path::PathBuf {
    installed::write_installed(&d.join("calibration"), 1, &[], installed::INSTALLED, 1);
    let at = d.join("calibration/Trajectory1");
    let saved = d.join("installation.toml");
    calibrate(&CalibrateArgs {
        dvl: &at.join("DVL_trajectory1.csv"),
        reference: Some(&at.join("GT_trajectory1.csv")),
        columns: None,
        reading: Reading::default(),
        terms: &[
            TermName::LeverArm,
            TermName::TimeOffset,
            TermName::Bias,
            TermName::Scale,
        ],
        window_s: None,
        dvl_noise_cm_s: 2.0,
        reference_noise_cm_s: 0.5,
        tolerance_pct: 10.0,
        out: &d.join("calibrated"),
        save: Some(&saved),
        dive_terms: &[TermName::TimeOffset],
    })
    .expect("the synthetic recording calibrates");
    saved
}

/// `correct` of the dive (`dvl`, `reference`) with the installation `saved`, its clock
/// found again from the first 60 s, into `out`.
fn corrected(
    (dvl, reference): (&std::path::Path, &std::path::Path),
    saved: &std::path::Path,
    out: &std::path::Path,
) -> dcnet_exp::operator::correct::Correction {
    correct(&CorrectArgs {
        dvl,
        reference: Some(reference),
        columns: None,
        reading: Reading::default(),
        installation: saved,
        window_s: 60.0,
        search_s: 30.0,
        time_offset_s: None,
        out,
    })
    .expect("the dive is corrected")
}
