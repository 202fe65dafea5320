//! Several dives with position fixes calibrated as one vehicle: the vehicle's terms are
//! the dives' own weighed by their information in each (known answers: one dive twice
//! is that dive, its standard deviations over √2; a dive that does not apply a term
//! adds nothing to it; two dives that disagree give their weighed mean), the joint `calibrate` with fixes end to end (its table, the
//! installation saved with the spread between dives, each dive written corrected,
//! `correct --fixes` showing the next dive's band), and its refusals. The intervals'
//! coverage is in `fix_coverage`.

use crate::common::{self, fix_dives, installed};
use crate::fixes::{FIX_TRUTH, fix_dive, number_after, refused_naming};
use dcnet_exp::installation::estimate::fix_joint::fix_vehicle;
use dcnet_exp::operator::installation_file::SavedInstallation;

/// One dive fitted to fixes of 2 m (the coverage's generator, a weave).
fn one_fit() -> dcnet_exp::installation::estimate::fixes::FixFit {
    let case = fix_dives::Case {
        fix_m: 2.0,
        correlation: 0.0,
        clock_s: 0.6,
        latency_s: 0.0,
        noise_spread: 1.0,
        fits_latency: false,
    };
    let (fits, _) = fix_dives::fits(&case, 1);
    fits[0].clone().expect("the weave fitted")
}

/// One dive twice is that dive, known twice as well: each vehicle term its value, its
/// standard deviation over √2, its correlations its own; its clock is the dive's and
/// not the vehicle's. A copy that did not apply the yaw adds nothing to the yaw.
#[test]
fn the_vehicles_terms_are_the_dives_weighed_by_their_information() {
    let fit = one_fit();
    let vehicle = fix_vehicle(&[fit.clone(), fit.clone()], &["time_offset_s"]);
    assert_eq!(
        vehicle.names,
        [
            "scale",
            "misalignment_z_rad",
            "lever_arm_x_m",
            "lever_arm_y_m"
        ]
    );
    let at = |name: &str| fit.bound.names.iter().position(|n| *n == name).unwrap();
    for (i, name) in vehicle.names.iter().enumerate() {
        let k = at(name);
        assert!(vehicle.applied[i], "{name}");
        assert!(
            (vehicle.value[i] - fit.bound.value[k]).abs() <= 1e-9 * fit.bound.std[k],
            "{name}"
        );
        let std = fit.bound.std[k] / 2f64.sqrt();
        assert!((vehicle.std[i] / std - 1.0).abs() < 1e-9, "{name}");
        for (j, other) in vehicle.names.iter().enumerate() {
            let own = if i == j {
                1.0
            } else {
                fit.bound.correlation[k][at(other)]
            };
            assert!(
                (vehicle.correlation[i][j] - own).abs() < 1e-9,
                "{name}, {other}"
            );
        }
        assert_eq!(
            vehicle.own[1][i],
            Some((fit.bound.value[k], fit.bound.std[k]))
        );
    }
    // Two dives show no spread between dives: it takes three.
    assert!(vehicle.between.iter().all(Option::is_none));
    let yaw = at("misalignment_z_rad");
    let mut without_yaw = fit.clone();
    without_yaw.bound.applied[yaw] = false;
    without_yaw.bound.value[yaw] += 1.0;
    let vehicle = fix_vehicle(&[without_yaw, fit.clone()], &["time_offset_s"]);
    assert_eq!(vehicle.own[0][1], None);
    assert!((vehicle.value[1] - fit.bound.value[yaw]).abs() <= 1e-9 * fit.bound.std[yaw]);
    assert!((vehicle.std[1] / fit.bound.std[yaw] - 1.0).abs() < 1e-9);
    // Nor the other terms: weighed term by term, each lies within the dives' own.
    for (i, name) in vehicle.names.iter().enumerate() {
        let k = at(name);
        assert!(
            (vehicle.value[i] - fit.bound.value[k]).abs() <= 1e-9 * fit.bound.std[k],
            "{name}"
        );
    }
}

/// Two dives that disagree: each vehicle term lies between their own estimates,
/// weighed by their information in it (a dive known twice as well weighs four times).
#[test]
fn each_vehicle_term_lies_between_the_dives_own() {
    let fit = one_fit();
    let mut other = fit.clone();
    for k in 0..other.bound.names.len() {
        other.bound.value[k] += 3.0 * other.bound.std[k];
        other.bound.std[k] *= 0.5;
    }
    let vehicle = fix_vehicle(&[fit.clone(), other], &["time_offset_s"]);
    let at = |name: &str| fit.bound.names.iter().position(|n| *n == name).unwrap();
    for (i, name) in vehicle.names.iter().enumerate() {
        let k = at(name);
        // (1 · θ + 4 · (θ + 3 s)) / 5 = θ + 2.4 s; standard deviation s / √5.
        let expected = fit.bound.value[k] + 2.4 * fit.bound.std[k];
        assert!(
            (vehicle.value[i] - expected).abs() < 1e-9 * fit.bound.std[k],
            "{name}"
        );
        assert!(
            (vehicle.std[i] / (fit.bound.std[k] / 5f64.sqrt()) - 1.0).abs() < 1e-9,
            "{name}"
        );
    }
}

/// A dive that saw few headings applies a yaw that holds the attitude's heading error
/// at those headings: beside a dive that turned, it is set aside (shown, not weighed),
/// however tight; its other terms are weighed. Where no dive turned, its yaw is weighed.
#[test]
fn a_yaw_seen_over_few_headings_is_set_aside_beside_a_turning_dive() {
    use dcnet_exp::installation::estimate::bound::{Unseen, Why};
    let fit = one_fit();
    let at = |name: &str| fit.bound.names.iter().position(|n| *n == name).unwrap();
    let yaw = at("misalignment_z_rad");
    let mut straight = fit.clone();
    straight.bound.value[yaw] += 10.0 * fit.bound.std[yaw];
    straight.bound.std[yaw] *= 0.5;
    straight.bound.unseen.push(Unseen {
        term: "misalignment_z_rad",
        why: Why::FewHeadings { span_rad: 0.1 },
    });
    let vehicle = fix_vehicle(&[fit.clone(), straight.clone()], &["time_offset_s"]);
    let i = vehicle
        .names
        .iter()
        .position(|n| *n == "misalignment_z_rad")
        .unwrap();
    assert!(vehicle.set_aside[1][i] && !vehicle.set_aside[0][i]);
    assert_eq!(
        vehicle.own[1][i],
        Some((straight.bound.value[yaw], straight.bound.std[yaw]))
    );
    assert_eq!(vehicle.weighed(1, i), None);
    assert!((vehicle.value[i] - fit.bound.value[yaw]).abs() <= 1e-9 * fit.bound.std[yaw]);
    assert!((vehicle.std[i] / fit.bound.std[yaw] - 1.0).abs() < 1e-9);
    let scale = vehicle.names.iter().position(|n| *n == "scale").unwrap();
    assert!(!vehicle.set_aside[1][scale]);
    let std = fit.bound.std[at("scale")] / 2f64.sqrt();
    assert!((vehicle.std[scale] / std - 1.0).abs() < 1e-9);
    // Two dives that both saw few headings: both yaws weighed, (1 · θ + 4 · (θ + 10 s)) / 5.
    let mut first = fit.clone();
    first
        .bound
        .unseen
        .push(straight.bound.unseen.last().unwrap().clone());
    let vehicle = fix_vehicle(&[first, straight], &["time_offset_s"]);
    assert!(vehicle.set_aside.iter().flatten().all(|aside| !aside));
    let expected = fit.bound.value[yaw] + 8.0 * fit.bound.std[yaw];
    assert!((vehicle.value[i] - expected).abs() < 1e-9 * fit.bound.std[yaw]);
}

/// Three dives of one vehicle, their clocks 1.0, 1.3 and 0.8 s, calibrated jointly with
/// their fixes: the vehicle's terms near the truth, each dive's clock its own, the
/// installation saved with the three dives' spread, each dive written corrected (two
/// files of one name numbered by their place); `correct --fixes` on a fourth dive
/// prints the next dive's band. Fixes and attitudes not one per DVL file, and one dive
/// given twice, are refused by name.
#[test]
fn dives_with_fixes_calibrate_jointly_and_carry_their_spread_to_the_next() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("columns.toml"),
        "[fix_columns]\ntime = \"t\"\nnorth_east = [\"n\", \"e\"]\n",
    )
    .unwrap();
    let clocks = [1.0, 1.3, 0.8, 1.1];
    let dives: Vec<[String; 3]> = (clocks.iter().enumerate())
        .map(|(k, &time_offset_s)| {
            let truth = installed::Installed {
                time_offset_s,
                ..FIX_TRUTH
            };
            fix_dive(&d.join(format!("dive{k}")), truth, k as u64 + 1)
        })
        .collect();
    let joint = |dives: &[&[String; 3]], extra: &[&str]| {
        let mut args = vec!["calibrate".to_string()];
        args.extend(dives.iter().map(|[dvl, _, _]| dvl.clone()));
        for [_, attitude, fixes] in dives {
            args.extend(["--fixes".into(), fixes.clone()]);
            args.extend(["--attitude".into(), attitude.clone()]);
        }
        args.extend(["--columns", "columns.toml", "--fix-noise-m", "0.5"].map(String::from));
        args.extend(extra.iter().map(|s| s.to_string()));
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        common::dcnet(d, &refs)
    };
    let three: Vec<&[String; 3]> = dives[..3].iter().collect();
    let output = joint(&three, &["--save", "vehicle.toml", "--report"]);
    let stdout = String::from_utf8_lossy(&output.stdout).to_string();
    assert!(output.status.success(), "{}", common::stderr(&output));
    assert!(
        stdout.contains("calibrated jointly on 3 dives with position fixes"),
        "{stdout}"
    );
    // The report's forest plot gives the vehicle's lever arm as the table prints it.
    let lever: Vec<&str> = (stdout.lines())
        .find(|l| l.starts_with("| lever arm x"))
        .unwrap_or_else(|| panic!("{stdout}"))
        .split('|')
        .map(str::trim)
        .collect();
    let markdown = std::fs::read_to_string(d.join("calibrated/report.md")).unwrap();
    let said = format!(
        "lever arm x joint {}, standard deviation {}, vehicle {}, next dive {}",
        lever[2], lever[3], lever[5], lever[6]
    );
    assert!(markdown.contains(&said), "{said}\n{markdown}");
    assert!(d.join("calibrated/forest.png").is_file());
    for name in [
        "1-DVL_trajectory1",
        "2-DVL_trajectory1",
        "3-DVL_trajectory1",
    ] {
        let corrected = d.join(format!("calibrated/{name}-corrected.csv"));
        let rows = std::fs::read_to_string(&corrected).unwrap().lines().count();
        assert_eq!(rows, 401, "{}", corrected.display());
    }
    let saved = SavedInstallation::read(&d.join("vehicle.toml")).unwrap();
    assert_eq!(saved.dives, 3);
    // Fixes measure no velocity residual: the one saved is the noise given, and says so.
    assert!(!saved.residual_measured);
    let found = saved.installation();
    // Near the truth, as one dive's fit is (the 1 Hz dead reckoning's own error of a
    // few centimetres aside); the clock saved the dives' mean.
    assert!(
        (found.lever_arm_m[0] - FIX_TRUTH.lever_arm_m[0]).abs() < 0.1,
        "{found:?}"
    );
    assert!(
        (found.scale[0] - FIX_TRUTH.scale).abs() < 0.002,
        "{found:?}"
    );
    assert!((found.time_offset_s - 1.033).abs() < 0.15, "{found:?}");
    for term in [
        "scale",
        "misalignment_z_rad",
        "lever_arm_x_m",
        "lever_arm_y_m",
    ] {
        let spread = saved.spread_of(term).unwrap_or_else(|| panic!("{term}"));
        assert!(spread.next_dive[0] < spread.next_dive[1], "{term}");
    }
    // Each dive's clock with the vehicle's terms, its own.
    let row = |name: &str| {
        stdout
            .lines()
            .find(|l| l.starts_with(&format!("| {name}")))
            .unwrap()
    };
    let clock_of = |name: &str| {
        let cells: Vec<&str> = row(name).split('|').map(str::trim).collect();
        cells[cells.len() - 3]
            .split(' ')
            .next()
            .unwrap()
            .parse::<f64>()
            .unwrap()
    };
    for (k, clock) in clocks[..3].iter().enumerate() {
        let found = clock_of(&format!("{}-DVL_trajectory1", k + 1));
        assert!(
            (found - clock).abs() < 0.15,
            "dive {k}: {found} s against {clock} s"
        );
    }
    // The fourth dive corrected by the vehicle's terms: the next dive's band shown.
    let [dvl, attitude, fixes] = &dives[3];
    let correct = [
        "correct",
        dvl,
        "--installation",
        "vehicle.toml",
        "--fixes",
        fixes,
        "--attitude",
        attitude,
        "--columns",
        "columns.toml",
        "--fix-noise-m",
        "0.5",
        "--out",
        "next",
    ];
    let output = common::dcnet(d, &correct);
    let stdout = String::from_utf8_lossy(&output.stdout).to_string();
    assert!(output.status.success(), "{}", common::stderr(&output));
    assert!(stdout.contains("next dive, 95 %"), "{stdout}");
    let found = number_after(&stdout, "the time offset at ");
    assert!((found - 1.1).abs() < 0.15, "{stdout}");
    // Against the dive's velocity reference, the residual it leaves is not set beside
    // one the calibration never measured.
    let args = [
        "correct",
        dvl,
        "--installation",
        "vehicle.toml",
        "--reference",
        attitude,
    ];
    let output = common::dcnet(d, &[&args[..], &["--out", "against-velocity"]].concat());
    let stdout = String::from_utf8_lossy(&output.stdout).to_string();
    assert!(output.status.success(), "{}", common::stderr(&output));
    assert!(
        stdout.contains("the calibration, against fixes, measured no velocity residual"),
        "{stdout}"
    );
    // Refused: fixes or attitudes not one per DVL file, one dive twice.
    let [dvl0, attitude0, fixes0] = &dives[0];
    let [dvl1, _, fixes1] = &dives[1];
    let mut args = vec!["calibrate", dvl0, dvl1, "--fixes", fixes0];
    args.extend(["--attitude", attitude0, "--fix-noise-m", "0.5"]);
    refused_naming(
        &common::dcnet(d, &args),
        "--fixes: 1 file for 2 DVL files: give one --fixes per DVL file, in the same order",
        &[],
    );
    args.extend(["--fixes", fixes1]);
    refused_naming(
        &common::dcnet(d, &args),
        "--attitude: 1 file for 2 --fixes: give one --attitude per --fixes, in the same order",
        &[],
    );
    let twice = [&dives[0], &dives[0], &dives[1]];
    refused_naming(
        &joint(&twice, &["--out", "twice"]),
        "hold the same recording (the same SHA-256): a joint calibration counts each recording once",
        &[],
    );
}
