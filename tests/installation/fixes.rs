//! A DVL calibrated against position fixes: the fit's 95 % intervals cover the truth on
//! synthetic dives with multipath outliers (and without, in `fix_coverage`), a straight
//! dive shows no lever arm and no clock and applies neither (its yaw, seen poorly), `calibrate --fixes` refuses
//! bad input by name, and on A-KIT the fixes' installation carried to other turning
//! segments leaves less drift than none.

use crate::common::{self, installed};
use crate::coverage::{NOISE_M_S, simulated, synthetic_segments};
use dcnet_exp::data::fixes::{FixSimulation, Fixes, simulate_fixes};
use dcnet_exp::installation::estimate::bound::Why;
use dcnet_exp::installation::estimate::fix_joint::fix_vehicle;
use dcnet_exp::installation::estimate::fixes::{
    FixFit, FixFitError, FixNoise, default_fix_terms, fit_fixes,
};
use dcnet_exp::installation::frames::Attitude;
use dcnet_exp::installation::study::Recording;
use dcnet_exp::installation::terms::Installation;
use dcnet_exp::installation::terms::names::term_set;
use rand::SeedableRng;
use rayon::prelude::*;
use std::path::Path;

/// The installation the coverage dives are simulated with.
const TRUTH: Installation = Installation {
    scale: [0.008; 3],
    misalignment_rad: [0.0, 0.0, 0.012],
    lever_arm_m: [0.9, -0.4, 0.0],
    time_offset_s: 1.0,
    bias_m_s: [0.0; 3],
};

/// The fixes of the coverage dives: one every 5 s with 0.5 m of noise per axis (a
/// good USBL's, or a surface GNSS's). With 2 m the clock's standard deviation on these
/// 400 s dives reaches 0.3–0.8 s, the turns' own time scale, where the linearised
/// intervals of the yaw and the clock cover only 88–92 % (docs/installation.md).
const FIXES: FixSimulation = FixSimulation {
    interval_s: 5.0,
    noise_m: 0.5,
    outlier_share: 0.0,
    outlier_m: 10.0,
};

/// The fixes of the A-KIT check: one every 5 s with 2 m of noise per axis, a USBL's.
const USBL_FIXES: FixSimulation = FixSimulation {
    noise_m: 2.0,
    ..FIXES
};

/// The true positions of a segment's reference point: its NED velocity summed by the
/// trapezoidal rule from zero.
pub(crate) fn positions(segment: &Recording) -> Vec<[f64; 2]> {
    let r = &segment.recording;
    let mut position = [0.0; 2];
    let mut out = vec![position];
    for i in 1..r.reference_time_s.len() {
        let dt = r.reference_time_s[i] - r.reference_time_s[i - 1];
        for (k, p) in position.iter_mut().enumerate() {
            *p += 0.5 * dt * (r.velocity_ned_m_s[i][k] + r.velocity_ned_m_s[i - 1][k]);
        }
        out.push(position);
    }
    out
}

/// One synthetic dive of `segment`: its DVL simulated with [`TRUTH`] under noise of AR(1)
/// correlation `correlation_at_1_s`, fixes drawn by `fixes`, and the fit of every term.
fn dive(
    segment: &Recording,
    correlation_at_1_s: f64,
    fixes: &FixSimulation,
    seed: u64,
) -> (FixFit, Fixes) {
    fitted_dive(segment, correlation_at_1_s, fixes, seed)
        .unwrap_or_else(|e| panic!("seed {seed}: {e}"))
}

/// [`dive`], or the fit's refusal.
fn fitted_dive(
    segment: &Recording,
    correlation_at_1_s: f64,
    fixes: &FixSimulation,
    seed: u64,
) -> Result<(FixFit, Fixes), FixFitError> {
    fitted_dive_edited(segment, (correlation_at_1_s, fixes), seed, |_| {})
}

/// [`fitted_dive`] with the fixes drawn changed by `edit` before the fit.
fn fitted_dive_edited(
    segment: &Recording,
    (correlation_at_1_s, fixes): (f64, &FixSimulation),
    seed: u64,
    edit: impl FnOnce(&mut Fixes),
) -> Result<(FixFit, Fixes), FixFitError> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let (time_s, dvl) = simulated(segment, &TRUTH, correlation_at_1_s, &mut rng);
    let reference_time_s = &segment.recording.reference_time_s;
    let mut drawn = simulate_fixes((reference_time_s, &positions(segment)), fixes, &mut rng);
    edit(&mut drawn);
    let pieces = vec![0..time_s.len()];
    let noise = FixNoise {
        fix_m: fixes.noise_m,
        depth_m: fixes.noise_m,
        dvl_m_s: NOISE_M_S,
    };
    let attitude = Attitude::of(&segment.recording);
    let terms = term_set(&default_fix_terms());
    let fit = fit_fixes((&time_s, &dvl), &pieces, &attitude, &drawn, terms, noise)?;
    Ok((fit, drawn))
}

/// Of `seeds` dives on the segments in turn, per term estimated (scale, yaw, lever arm
/// x and y, time offset): the share of the dives that applied it whose 95 % interval
/// holds the truth, and how many applied it (the rest say the term is not seen, and do
/// not apply it); and how many dives the fit refused.
fn coverage(
    segments: &[Recording],
    correlation_at_1_s: f64,
    fixes: &FixSimulation,
    seeds: u64,
) -> (Vec<(&'static str, f64, usize)>, usize) {
    let truth = TRUTH.to_parameters(&term_set(&default_fix_terms()));
    let fitted: Vec<Option<Vec<(&'static str, Option<bool>)>>> = (0..seeds)
        .into_par_iter()
        .map(|seed| {
            let segment = &segments[seed as usize % segments.len()];
            let (fit, _) = fitted_dive(segment, correlation_at_1_s, fixes, seed).ok()?;
            let terms = (0..fit.bound.names.len())
                .filter(|&k| fit.estimated[k])
                .map(|k| {
                    let error = (fit.bound.value[k] - truth[k]).abs();
                    let applied = fit.bound.is_applied(fit.bound.names[k]);
                    (
                        fit.bound.names[k],
                        applied.then(|| error <= fit.bound.half_width_95(k)),
                    )
                })
                .collect();
            Some(terms)
        })
        .collect();
    let refused = fitted.iter().filter(|dive| dive.is_none()).count();
    let dives: Vec<Vec<(&'static str, Option<bool>)>> = fitted.into_iter().flatten().collect();
    let names: Vec<&'static str> = dives[0].iter().map(|(name, _)| *name).collect();
    let table = names
        .iter()
        .enumerate()
        .map(|(k, &name)| {
            let applied: Vec<bool> = dives.iter().filter_map(|dive| dive[k].1).collect();
            let covered = applied.iter().filter(|&&inside| inside).count();
            (
                name,
                covered as f64 / applied.len().max(1) as f64,
                applied.len(),
            )
        })
        .collect();
    (table, refused)
}

/// Prints each term's coverage and checks that, pooled over the terms applied, it lies
/// in 93–97 %, and for each term applied on most dives in 90–99 % (400 dives: a term's
/// share has a standard error of about 1.1 %).
fn check_coverage(case: &str, coverage: &[(&str, f64, usize)]) {
    println!("fixes, {case}: (term, coverage, dives that applied it) {coverage:?}");
    let applied: usize = coverage.iter().map(|c| c.2).sum();
    let pooled = coverage.iter().map(|c| c.1 * c.2 as f64).sum::<f64>() / applied as f64;
    assert!(
        (0.93..=0.97).contains(&pooled),
        "{case}: pooled coverage {pooled:.3}: {coverage:?}"
    );
    for (name, c, dives) in coverage.iter().filter(|c| c.2 >= 200) {
        assert!(
            (0.90..=0.99).contains(c),
            "{case}: {name} {c:.3} of {dives}: {coverage:?}"
        );
    }
}

/// 5 % of the fixes displaced 10 m (multipath): each is left out as an outlier, and the
/// intervals still cover.
#[test]
fn multipath_fixes_are_left_out_and_the_intervals_still_cover() {
    let (_dir, segments) = synthetic_segments();
    let multipath = FixSimulation {
        outlier_share: 0.05,
        ..FIXES
    };
    let (fit, fixes) = dive(&segments[0], 0.0, &multipath, 7);
    let (clean, _) = dive(&segments[0], 0.0, &FIXES, 7);
    assert!(
        !fit.outliers.is_empty(),
        "no outlier found among {} fixes",
        fixes.len()
    );
    assert_eq!(clean.outliers, Vec::<usize>::new());
    // One dive in 400 (seed 230) runs its clock to the scan's edge, and is refused
    // rather than answered there.
    let (table, refused) = coverage(&segments, 0.0, &multipath, 400);
    assert!(refused <= 4, "{refused} of 400 dives refused");
    check_coverage("5 % of fixes 10 m off", &table);
}

/// One fix 300 m off and one 10 m off among fixes of 0.5 m: both left out, and every
/// term as the fit without them gives it. (The 300-m fix, read with the others, made
/// the noise a walk under which most good fixes were outliers, and the fit was refused
/// as "more than a quarter are outliers"; the 10-m one, under the walk the good fixes
/// read, hid within it and moved the clock by several standard deviations.)
#[test]
fn a_fix_hundreds_of_metres_off_is_left_out_and_the_fit_is_the_clean_ones() {
    let (_dir, segments) = synthetic_segments();
    let (clean, _) = dive(&segments[0], 0.0, &FIXES, 7);
    let (fit, _) = fitted_dive_edited(&segments[0], (0.0, &FIXES), 7, |fixes| {
        fixes.north_east_m[40][0] += 300.0;
        fixes.north_east_m[50][1] += 10.0;
    })
    .unwrap();
    assert_eq!(clean.outliers, Vec::<usize>::new());
    assert_eq!(fit.outliers, vec![40, 50]);
    for k in (0..fit.bound.names.len()).filter(|&k| fit.estimated[k]) {
        assert!(
            (fit.bound.value[k] - clean.bound.value[k]).abs() < 0.25 * clean.bound.std[k],
            "{}: {} against {} ± {} without the two fixes",
            fit.bound.names[k],
            fit.bound.value[k],
            clean.bound.value[k],
            clean.bound.std[k]
        );
    }
}

/// A dive that never turns shows neither the lever arm nor the clock: neither is
/// applied and the flags say why. Its scale is applied, and so is its yaw, which the
/// track's direction shows at any heading: found within its 95 % interval of the truth,
/// and said to be seen poorly (at one heading it holds the attitude's heading error).
#[test]
fn a_straight_dive_applies_no_lever_arm_or_clock_and_its_yaw_seen_poorly() {
    let dir = tempfile::tempdir().unwrap();
    let straight = [installed::Shape::Straight];
    installed::write_shaped(
        dir.path(),
        &straight,
        installed::INSTALLED,
        1,
        (400, 1.0),
        1,
    );
    let files = [dcnet_exp::data::paired::PairedFiles::akit(dir.path(), 1)];
    let segment = &crate::coverage::segments(&files)[0];
    let (fit, _) = dive(segment, 0.0, &FIXES, 3);
    let why = |name: &str| {
        let found = fit.bound.unseen.iter().find(|u| u.term == name);
        found
            .unwrap_or_else(|| panic!("{name}: {:?}", fit.bound.unseen))
            .why
            .to_string()
    };
    for name in ["lever_arm_x_m", "lever_arm_y_m", "time_offset_s"] {
        assert!(
            !fit.bound.is_applied(name),
            "{name}: {:?}",
            fit.bound.unseen
        );
        assert!(why(name).contains("show only as it turns"), "{}", why(name));
    }
    assert!(fit.bound.is_applied("scale"), "{:?}", fit.bound.unseen);
    assert!(
        fit.bound.is_applied("misalignment_z_rad"),
        "{:?}",
        fit.bound.unseen
    );
    assert!(why("misalignment_z_rad").contains("heading error at these headings"));
    let k = fit
        .bound
        .names
        .iter()
        .position(|n| *n == "misalignment_z_rad")
        .unwrap();
    let half_width = fit.bound.half_width_95(k);
    let yaw_rad = fit.installation.misalignment_rad[2];
    assert!(
        (yaw_rad - TRUTH.misalignment_rad[2]).abs() <= half_width,
        "yaw {yaw_rad:.5} ± {half_width:.5} rad against {}",
        TRUTH.misalignment_rad[2]
    );
    let applied = fit.installation;
    assert_eq!(
        (applied.lever_arm_m, applied.time_offset_s),
        ([0.0; 3], 0.0)
    );
}

/// Fixes over only a stretch of a turning dive where its heading spans under 80° show
/// no lever arm or clock (and the yaw only poorly), however much the dive turns around them: the heading's
/// span is read over the fixes' own times (it was once read over the whole dive, and
/// fixes of A-KIT T2's first minute applied a clock 7σ from the dive's own); the
/// distance travelled is the fixes' span's.
#[test]
fn fixes_over_a_stretch_of_few_headings_apply_no_term_only_turns_show() {
    let dir = tempfile::tempdir().unwrap();
    installed::write_installed(dir.path(), 1, &[], installed::INSTALLED, 1);
    let files = [dcnet_exp::data::paired::PairedFiles::akit(dir.path(), 1)];
    let segment = &crate::coverage::segments(&files)[0];
    let (whole, drawn) = dive(segment, 0.0, &FIXES, 3);
    let turns_only = [
        "lever_arm_x_m",
        "lever_arm_y_m",
        "time_offset_s",
        "misalignment_z_rad",
    ];
    assert!(turns_only.iter().all(|name| whole.bound.is_applied(name)));
    // The longest stretch of the dive over which the heading spans under 80°.
    let attitude = Attitude::of(&segment.recording);
    let yaw = |t: f64| {
        let k = attitude
            .time_s
            .partition_point(|&s| s < t)
            .min(attitude.time_s.len() - 1);
        attitude.angles_rad[k][2]
    };
    let span = |from: usize, to: usize| {
        let yaws: Vec<f64> = (from..=to).map(|k| yaw(drawn.time_s[k])).collect();
        let low = yaws.iter().cloned().fold(f64::INFINITY, f64::min);
        yaws.iter().cloned().fold(f64::NEG_INFINITY, f64::max) - low
    };
    let (mut best, mut from) = ((0, 0), 0);
    for to in 0..drawn.len() {
        while span(from, to) >= 80f64.to_radians() {
            from += 1;
        }
        if to - from > best.1 - best.0 {
            best = (from, to);
        }
    }
    let window = drawn.time_s[best.0]..=drawn.time_s[best.1];
    let start = drawn.select(|k| window.contains(&drawn.time_s[k]));
    assert!(start.len() >= 6, "{} fixes over {window:?} s", start.len());
    let (time_s, dvl) = {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        simulated(segment, &TRUTH, 0.0, &mut rng)
    };
    let noise = FixNoise {
        fix_m: FIXES.noise_m,
        depth_m: FIXES.noise_m,
        dvl_m_s: NOISE_M_S,
    };
    let terms = term_set(&default_fix_terms());
    let pieces = [0..time_s.len()];
    let fit = fit_fixes((&time_s, &dvl), &pieces, &attitude, &start, terms, noise).unwrap();
    for name in &turns_only[..3] {
        assert!(
            !fit.bound.is_applied(name),
            "{name} applied over {window:?} s: {:?}",
            fit.bound.unseen
        );
    }
    let yaw_why = fit
        .bound
        .unseen
        .iter()
        .find(|u| u.term == "misalignment_z_rad");
    assert!(
        yaw_why.is_some_and(|u| matches!(u.why, Why::FewHeadings { .. })),
        "{:?}",
        fit.bound.unseen
    );
    assert!(
        fit.distance_m < 0.5 * whole.distance_m,
        "the distance over the fixes' span"
    );
}

/// The installation the dives of `calibrate --fixes` and `correct --fixes` are written
/// with: without its bias, which fixes do not calibrate, and its clock a whole sample
/// ahead (at 0.6 s the 1 Hz dead reckoning of these 1 Hz piecewise-linear turns is
/// itself 0.67 m off after 400 s at the true terms, and the noise-free fixes put the
/// clock at 0.43 ± 0.03 s: docs/installation.md); its lever arm's depth, which
/// horizontal fixes feel only through roll and pitch, zero.
pub(crate) const FIX_TRUTH: installed::Installed = installed::Installed {
    bias_m_s: [0.0; 3],
    time_offset_s: 1.0,
    lever_arm_m: [-1.9, 0.05, 0.0],
    ..installed::INSTALLED
};

/// The fixes the tests write: a time and north, east in metres, every 5 s of the
/// segment written by `common::installed` (its reference positions, no noise).
pub(crate) fn write_fixes(path: &Path, segment: &Recording, every: usize) {
    let positions = positions(segment);
    let mut text = String::from("t,n,e\n");
    for (i, p) in positions.iter().enumerate().step_by(every) {
        let t = segment.recording.reference_time_s[i];
        text.push_str(&format!("{t},{},{}\n", p[0], p[1]));
    }
    std::fs::write(path, text).unwrap();
}

/// `calibrate --fixes` on a written dive: its terms near the truth of the installed
/// recording, saved for `correct`; and every bad input refused with a message that names
/// what is wrong.
#[test]
fn calibrate_with_fixes_finds_the_installation_and_refuses_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let truth = FIX_TRUTH;
    installed::write_installed(d, 1, &[], truth, 1);
    let files = [dcnet_exp::data::paired::PairedFiles::akit(d, 1)];
    let segment = &crate::coverage::segments(&files)[0];
    write_fixes(&d.join("fixes.csv"), segment, 5);
    std::fs::write(
        d.join("columns.toml"),
        "[fix_columns]\ntime = \"t\"\nnorth_east = [\"n\", \"e\"]\n",
    )
    .unwrap();
    let dvl = files[0].dvl.to_str().unwrap().to_string();
    let attitude = files[0].reference.to_str().unwrap().to_string();
    let args = |extra: &[&str]| -> Vec<String> {
        let mut args: Vec<String> = [
            "calibrate",
            &dvl,
            "--fixes",
            "fixes.csv",
            "--attitude",
            &attitude,
            "--columns",
            "columns.toml",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        args.extend(extra.iter().map(|s| s.to_string()));
        args
    };
    let run = |extra: &[&str]| {
        let owned = args(extra);
        let refs: Vec<&str> = owned.iter().map(String::as_str).collect();
        common::dcnet(d, &refs)
    };
    let output = run(&["--fix-noise-m", "0.5", "--save", "fixes.toml"]);
    let stdout = String::from_utf8_lossy(&output.stdout).to_string();
    assert!(output.status.success(), "{}", common::stderr(&output));
    assert!(stdout.contains("| time offset"), "{stdout}");
    assert!(
        stdout.contains("fixes' horizontal residual RMS"),
        "{stdout}"
    );
    let saved =
        dcnet_exp::operator::installation_file::SavedInstallation::read(&d.join("fixes.toml"))
            .unwrap();
    let found = saved.installation();
    // Near the truth: the noise-free fixes leave the 1 Hz dead reckoning's own error
    // in these turns, a few centimetres, beyond the standard deviations of fixes this
    // clean (lever arm x −1.874 ± 0.007 m, the clock 0.93 ± 0.04 s).
    assert!(
        (found.time_offset_s - truth.time_offset_s).abs() < 0.15,
        "{found:?}"
    );
    assert!(
        (found.lever_arm_m[0] - truth.lever_arm_m[0]).abs() < 0.1,
        "{found:?}"
    );
    assert!((found.scale[0] - truth.scale).abs() < 0.002, "{found:?}");
    // The recording written corrected by what was found, a row per DVL sample.
    let corrected =
        std::fs::read_to_string(d.join("calibrated/DVL_trajectory1-corrected.csv")).unwrap();
    assert_eq!(corrected.lines().count(), 401, "{corrected}");
    // As `run`, on other fixes and columns files.
    let run_on = |fixes: &str, columns: &str, extra: &[&str]| {
        let mut owned = args(extra);
        owned[3] = fixes.to_string();
        owned[7] = columns.to_string();
        let refs: Vec<&str> = owned.iter().map(String::as_str).collect();
        common::dcnet(d, &refs)
    };
    let refused = |extra: &[&str], expected: &str| refused_naming(&run(extra), expected, extra);
    refused(
        &["--fix-noise-m", "0"],
        "--fix-noise-m 0: give a positive number of metres",
    );
    refused(
        &[],
        "--fixes: give the fixes' noise per horizontal axis with --fix-noise-m",
    );
    refused(
        &["--fix-noise-m", "1", "--terms", "bias"],
        "bias: fixes calibrate scale, misalignment, lever_arm, time_offset",
    );
    // A noise the residuals contradict by orders of magnitude: a unit or a digit wrong;
    // the residuals' size and the ratio to three figures.
    let contradicted = run(&["--fix-noise-m", "1e-9"]);
    refused_naming(
        &contradicted,
        "times the noise given, beyond a factor of 100 either way",
        &["--fix-noise-m", "1e-9"],
    );
    let digits = (common::stderr(&contradicted).split(|c: char| !c.is_ascii_digit()))
        .map(str::len)
        .max();
    assert!(digits < Some(10), "{}", common::stderr(&contradicted));
    refused(
        &["--fix-noise-m", "1e308"],
        "--fix-noise-m 1e308: give a positive number of metres, under 10,000 km",
    );
    refused(
        &["--fix-noise-m", "0.5", "--depth-noise-m", "0.3"],
        "--depth-noise-m: fixes.csv gives no depth",
    );
    for flag in [
        ["--tolerance-pct", "5"],
        ["--reference-noise-cm-s", "1"],
        ["--search-s", "60"],
    ] {
        let expected = format!("{}: does not apply to a calibration against fixes", flag[0]);
        refused(
            &[&["--fix-noise-m", "0.5"][..], &flag[..]].concat(),
            &expected,
        );
    }
    // The reference's latitude and longitude, in radians, read as degrees.
    std::fs::write(
        d.join("degrees.toml"),
        "[fix_columns]\ntime = \"Time [s]\"\nlatitude_longitude = [\"Latitude [rad]\", \"Longitude [rad]\"]\nangles_in_degrees = true\n",
    )
    .unwrap();
    let output = run_on(&attitude, "degrees.toml", &["--fix-noise-m", "0.5"]);
    let message = common::stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{message}");
    assert!(
        message
            .contains("latitude and longitude in radians, read as degrees, travel 57.3 times less"),
        "{message}"
    );
    // One fix's longitude of 500°: refused at its line, not its good neighbours
    // thrown out.
    std::fs::write(
        d.join("geo.toml"),
        "[fix_columns]\ntime = \"t\"\nlatitude_longitude = [\"lat\", \"lon\"]\nangles_in_degrees = true\n",
    )
    .unwrap();
    std::fs::write(
        d.join("geo.csv"),
        "t,lat,lon\n0,32.8,34.9\n5,32.8,500\n10,32.8,34.9\n",
    )
    .unwrap();
    let output = run_on("geo.csv", "geo.toml", &["--fix-noise-m", "0.5"]);
    let message = common::stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{message}");
    assert!(
        message.contains(
            "geo.csv:3: lon: a longitude of 500 deg, off the globe (beyond -180 to 360 deg)"
        ),
        "{message}"
    );
    // Two fixes in five moved 300 m: more than a quarter are outliers.
    let jumped: String = std::fs::read_to_string(d.join("fixes.csv"))
        .unwrap()
        .lines()
        .enumerate()
        .map(|(i, line)| match i % 5 {
            1 | 3 if i > 0 => {
                let (t, rest) = line.split_once(',').unwrap();
                let (n, e) = rest.split_once(',').unwrap();
                format!("{t},{},{e}\n", n.parse::<f64>().unwrap() + 300.0)
            }
            _ => format!("{line}\n"),
        })
        .collect();
    std::fs::write(d.join("jumped.csv"), jumped).unwrap();
    let output = run_on("jumped.csv", "columns.toml", &["--fix-noise-m", "0.5"]);
    let message = common::stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{message}");
    assert!(
        message.contains("more than a quarter are outliers"),
        "{message}"
    );
    // Fixes of another hour: none overlaps the DVL.
    let late: String = std::fs::read_to_string(d.join("fixes.csv"))
        .unwrap()
        .lines()
        .enumerate()
        .map(|(i, line)| match i {
            0 => format!("{line}\n"),
            _ => {
                let (t, rest) = line.split_once(',').unwrap();
                format!("{},{rest}\n", t.parse::<f64>().unwrap() + 3600.0)
            }
        })
        .collect();
    std::fs::write(d.join("late.csv"), late).unwrap();
    let mut late_args = args(&["--fix-noise-m", "1"]);
    late_args[3] = "late.csv".into();
    let refs: Vec<&str> = late_args.iter().map(String::as_str).collect();
    let output = common::dcnet(d, &refs);
    let message = common::stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{message}");
    assert!(
        message.contains("the fixes do not overlap the DVL"),
        "{message}"
    );
    // Three fixes: fewer residuals than terms and start positions.
    let few: String = std::fs::read_to_string(d.join("fixes.csv"))
        .unwrap()
        .lines()
        .take(4)
        .skip(0)
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(d.join("few.csv"), few).unwrap();
    let mut few_args = args(&["--fix-noise-m", "1"]);
    few_args[3] = "few.csv".into();
    let refs: Vec<&str> = few_args.iter().map(String::as_str).collect();
    let output = common::dcnet(d, &refs);
    let message = common::stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{message}");
    assert!(message.contains("a fit needs more"), "{message}");
    // A fix stamped before the one above it, placed at its line.
    std::fs::write(d.join("back.csv"), "t,n,e\n10,0,0\n5,1,1\n").unwrap();
    let mut back_args = args(&["--fix-noise-m", "1"]);
    back_args[3] = "back.csv".into();
    let refs: Vec<&str> = back_args.iter().map(String::as_str).collect();
    let output = common::dcnet(d, &refs);
    let message = common::stderr(&output);
    assert!(
        message.contains("back.csv:3: t: 5 s follows 10 s of line 2"),
        "{message}"
    );
}

/// A dive written by `common::installed` under `truth` into `folder`, with its
/// reference's positions every 5 s as fixes beside it: the DVL's, the attitude's and
/// the fixes' paths.
pub(crate) fn fix_dive(folder: &Path, truth: installed::Installed, seed: u64) -> [String; 3] {
    fix_dive_every(folder, truth, seed, 5)
}

/// [`fix_dive`] with a fix every `every` seconds.
pub(crate) fn fix_dive_every(
    folder: &Path,
    truth: installed::Installed,
    seed: u64,
    every: usize,
) -> [String; 3] {
    installed::write_installed(folder, 1, &[], truth, seed);
    let files = [dcnet_exp::data::paired::PairedFiles::akit(folder, 1)];
    let segment = &crate::coverage::segments(&files)[0];
    let fixes = folder.join("fixes.csv");
    write_fixes(&fixes, segment, every);
    [&files[0].dvl, &files[0].reference, &fixes].map(|p| p.to_str().unwrap().to_string())
}

/// `correct --fixes`: an installation calibrated on one dive's fixes carried to another
/// whose clock is 0.8 s later, the clock found again from the second dive's fixes (all
/// of them, or its first 200 s), the dive corrected and written, the fixes' residual
/// lower with the installation than without; a clock given is applied as given; what
/// does not apply refused by name.
#[test]
fn correct_with_fixes_finds_the_dives_clock_again_and_carries_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let truth = FIX_TRUTH;
    let [dvl, attitude, fixes] = fix_dive(&d.join("first"), truth, 1);
    std::fs::write(
        d.join("columns.toml"),
        "[fix_columns]\ntime = \"t\"\nnorth_east = [\"n\", \"e\"]\n",
    )
    .unwrap();
    let calibrate = [
        "calibrate",
        &dvl,
        "--fixes",
        &fixes,
        "--attitude",
        &attitude,
        "--columns",
        "columns.toml",
        "--fix-noise-m",
        "0.5",
        "--save",
        "fixes.toml",
    ];
    let output = common::dcnet(d, &calibrate);
    assert!(output.status.success(), "{}", common::stderr(&output));
    let saved =
        dcnet_exp::operator::installation_file::SavedInstallation::read(&d.join("fixes.toml"))
            .unwrap()
            .installation();
    let later = installed::Installed {
        time_offset_s: 1.8,
        ..truth
    };
    let [dvl, attitude, fixes] = fix_dive(&d.join("second"), later, 2);
    let correct_with = |attitude: &str, extra: &[&str]| {
        let mut args = vec![
            "correct",
            &dvl,
            "--installation",
            "fixes.toml",
            "--fixes",
            &fixes,
            "--attitude",
            attitude,
            "--columns",
            "columns.toml",
        ];
        args.extend(extra);
        common::dcnet(d, &args)
    };
    let correct = |extra: &[&str]| correct_with(&attitude, extra);
    let succeeded = |extra: &[&str]| {
        let output = correct(extra);
        let said = common::stderr(&output);
        assert!(output.status.success(), "{said}");
        assert!(
            said.contains("correct with fixes: "),
            "the cost stated: {said}"
        );
        String::from_utf8_lossy(&output.stdout).to_string()
    };
    let stdout = succeeded(&["--fix-noise-m", "0.5", "--out", "corrected"]);
    // The clock found again: the saved one moved by the dives' 0.8 s, the few
    // centimetres of the 1 Hz dead reckoning's own error aside.
    let found = number_after(&stdout, "the time offset at ");
    assert!(
        (found - saved.time_offset_s - 0.8).abs() < 0.1,
        "found {found} s, saved {} s: {stdout}",
        saved.time_offset_s
    );
    let before = number_after(&stdout, "over the ");
    assert!(before > 100.0, "{stdout}");
    let residual = |after: &str| number_after(&stdout, after);
    let (bare, applied) = (
        residual("m travelled: "),
        residual("% of the distance) with no terms, "),
    );
    assert!(applied < 0.2 * bare, "{stdout}");
    let corrected =
        std::fs::read_to_string(d.join("corrected/DVL_trajectory1-corrected.csv")).unwrap();
    assert_eq!(
        corrected.lines().count(),
        401,
        "a row per DVL sample and a header"
    );
    // The first 200 s' fixes alone.
    let stdout = succeeded(&[
        "--fix-noise-m",
        "0.5",
        "--window-s",
        "200",
        "--out",
        "window",
    ]);
    let used = number_after(&stdout, "clock found again from ");
    assert!((30.0..=41.0).contains(&used), "{stdout}");
    // A clock given: applied as given.
    let stdout = succeeded(&[
        "--fix-noise-m",
        "0.5",
        "--time-offset-s",
        "1.25",
        "--out",
        "given",
    ]);
    assert!(stdout.contains("| 1.2500 s "), "{stdout}");
    assert!(stdout.contains("given"), "{stdout}");
    assert!(
        stdout.contains("beside the attitude's 400 on its own stamps"),
        "{stdout}"
    );
    // A clock given 4.3 s wrong: the installation fits the fixes worse than none, and
    // nothing is written.
    refused_naming(
        &correct(&[
            "--fix-noise-m",
            "0.5",
            "--time-offset-s",
            "-2.5",
            "--out",
            "wrong",
        ]),
        "--time-offset-s -2.5: the installation at the clock given leaves the fixes further from the dead reckoning than no terms do",
        &["--time-offset-s", "-2.5"],
    );
    assert!(!d.join("wrong").exists());
    // An attitude of the dive's first 300 s: the samples beyond it are counted.
    let attitude_text = std::fs::read_to_string(&attitude).unwrap();
    let cut: Vec<&str> = attitude_text.lines().take(301).collect();
    std::fs::write(d.join("cut.csv"), cut.join("\n") + "\n").unwrap();
    let output = correct_with("cut.csv", &["--fix-noise-m", "0.5", "--out", "cut"]);
    let stdout = String::from_utf8_lossy(&output.stdout).to_string();
    assert!(output.status.success(), "{}", common::stderr(&output));
    let line = (stdout.lines())
        .find(|l| l.contains("of the dive's samples lie outside the attitude"))
        .unwrap_or_else(|| panic!("{stdout}"));
    let outside: usize = line.split_whitespace().next().unwrap().parse().unwrap();
    assert!((95..=105).contains(&outside), "{stdout}");
    let refused = |extra: &[&str], expected: &str| refused_naming(&correct(extra), expected, extra);
    refused(
        &[],
        "--fixes: give the fixes' noise per horizontal axis with --fix-noise-m",
    );
    refused(
        &["--fix-noise-m", "0.5", "--reference", &attitude],
        "--reference: does not apply to a correction against fixes",
    );
    refused(
        &["--fix-noise-m", "0.5", "--search-s", "10"],
        "--search-s: does not apply to a correction against fixes",
    );
    refused(
        &["--fix-noise-m", "0.5", "--window-s", "0"],
        "--window-s 0: give a positive number of seconds",
    );
    // A window of 5 s holds fixes, but none 3 s inside the DVL's start: the flag named.
    refused(
        &["--fix-noise-m", "0.5", "--window-s", "5"],
        "the first 5 s of the dive (--window-s) hold no fix the fit can read",
    );
    refused(
        &[
            "--fix-noise-m",
            "0.5",
            "--window-s",
            "100",
            "--time-offset-s",
            "1",
        ],
        "--window-s 100: with --time-offset-s there is no clock to find",
    );
    // A clock given 50 s off: the fixes fitted about it, the flag named.
    refused(
        &["--fix-noise-m", "0.5", "--time-offset-s", "50"],
        "--time-offset-s 50: the installation at the clock given does not fit the dive's fixes",
    );
    // Fixes 5 s late on the attitude's clock, beyond the search about the carried clock:
    // refused, the clocks named (it read the attitude beyond its end before).
    let late: String = (std::fs::read_to_string(&fixes).unwrap().lines())
        .enumerate()
        .map(|(i, line)| match i {
            0 => format!("{line}\n"),
            _ => {
                let (t, rest) = line.split_once(',').unwrap();
                format!("{},{rest}\n", t.parse::<f64>().unwrap() + 5.0)
            }
        })
        .collect();
    std::fs::write(d.join("late.csv"), late).unwrap();
    let mut late_args = vec!["correct", &dvl, "--installation", "fixes.toml"];
    late_args.extend(["--fixes", "late.csv", "--attitude", &attitude]);
    late_args.extend(["--columns", "columns.toml", "--fix-noise-m", "0.5"]);
    refused_naming(
        &common::dcnet(d, &late_args),
        "on another clock than the attitude's, more than the ±3 s a fit searches apart",
        &["fixes 5 s late"],
    );
    refused(
        &["--fix-noise-m", "-2"],
        "--fix-noise-m -2: give a positive number of metres",
    );
    let output = common::dcnet(
        d,
        &[
            "correct",
            &dvl,
            "--installation",
            "fixes.toml",
            "--attitude",
            &attitude,
        ],
    );
    assert_eq!(output.status.code(), Some(1));
    assert!(
        common::stderr(&output)
            .contains("--attitude: goes with position fixes: give them with --fixes"),
        "{}",
        common::stderr(&output)
    );
}

/// Checks that the command run with the arguments `extra` exited 1 saying `expected`.
pub(crate) fn refused_naming(output: &std::process::Output, expected: &str, extra: &[&str]) {
    let message = common::stderr(output);
    assert_eq!(output.status.code(), Some(1), "{extra:?}: {message}");
    assert!(message.contains(expected), "{extra:?}: {message}");
}

/// The number that follows `after` in `text`.
pub(crate) fn number_after(text: &str, after: &str) -> f64 {
    let at = text
        .find(after)
        .unwrap_or_else(|| panic!("{after:?} in {text}"))
        + after.len();
    let number: String = text[at..]
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.' || *c == '-' || *c == '+')
        .collect();
    number
        .parse()
        .unwrap_or_else(|_| panic!("a number after {after:?} in {text}"))
}

/// On A-KIT, fixes every 5 s with 2 m of noise simulated from the reference's positions
/// of a turning segment (T1, T4, T8) calibrate an installation that, carried to the other
/// turning segments T2, T3, T9 and T10, leaves at most 0.20 % of the distance travelled
/// in RMS drift (no calibration: about 0.56 %; measured 0.141 % in the mean); the three
/// calibrated jointly, at most 0.13 % (measured 0.090 % in the mean). The straight
/// T12's yaw (−0.25 ± 0.12° on the first draw, seen poorly) leaves T12 itself with
/// less drift than its yaw held at zero (measured 0.073 % against 0.192 %), and the
/// turning segments with at most 0.1 % more than no calibration (measured 0.61–0.63 %:
/// at one heading the yaw holds the attitude's heading error there). T13 (one turn of 228°) is printed,
/// not held to that: every term it shows is seen poorly, and applied at its estimate
/// they left 0.85 and 0.96 % on two of three draws (docs/findings.md).
#[test]
#[ignore = "needs the A-KIT recordings: dcnet-exp data fetch akit"]
fn fixes_from_a_turning_akit_segment_halve_the_drift_of_the_others() {
    use dcnet_exp::data::paired::{PairedColumns, PairedFiles, read};
    use dcnet_exp::installation::dead_reckoning::drift_of;
    let folder = common::akit();
    let segment = |k: usize| {
        read(
            &PairedFiles::akit(&folder, k),
            &PairedColumns::akit_with_positions(),
        )
        .unwrap()
    };
    let scored: Vec<_> = [2, 3, 9, 10].map(segment).into_iter().collect();
    let mean_drift = |installation: &Installation| {
        let drifts: Vec<f64> = (scored.iter())
            .map(|r| drift_of(installation, r).unwrap().rms_pct)
            .collect();
        drifts.iter().sum::<f64>() / drifts.len() as f64
    };
    let none = mean_drift(&Installation::default());
    let fitted = |k: usize, seed: u64| {
        let recording = segment(k);
        let mut rng = dcnet_exp::rng::task_rng(seed, &[&"fixes", &k]);
        let positions = recording.position_ne_m.as_ref().unwrap();
        let fixes = simulate_fixes(
            (&recording.reference_time_s, positions),
            &USBL_FIXES,
            &mut rng,
        );
        let noise = FixNoise {
            fix_m: 2.0,
            depth_m: 2.0,
            dvl_m_s: 0.02,
        };
        let dvl = (&recording.time_s[..], &recording.dvl_m_s[..]);
        let terms = term_set(&default_fix_terms());
        let attitude = Attitude::of(&recording);
        fit_fixes(dvl, &recording.pieces(), &attitude, &fixes, terms, noise).unwrap()
    };
    let turning: Vec<f64> = [1, 4, 8]
        .iter()
        .flat_map(|&k| (0..3).map(move |seed| (k, seed)))
        .map(|(k, seed)| mean_drift(&fitted(k, seed).installation))
        .collect();
    // T12's own drift with its installation, and with its yaw held at zero; the
    // others' drift with it.
    let t12 = segment(12);
    let straight: Vec<[f64; 3]> = (0..3)
        .map(|seed| {
            let installation = fitted(12, seed).installation;
            let mut yaw_held = installation;
            yaw_held.misalignment_rad[2] = 0.0;
            let own = |i: &Installation| drift_of(i, &t12).unwrap().rms_pct;
            [
                own(&installation),
                own(&yaw_held),
                mean_drift(&installation),
            ]
        })
        .collect();
    // T1, T4 and T8 of each draw calibrated jointly: the vehicle's terms, the clock the
    // three dives' mean.
    let joint: Vec<f64> = (0..3)
        .map(|seed| {
            let fits: Vec<FixFit> = [1, 4, 8].iter().map(|&k| fitted(k, seed)).collect();
            let vehicle = fix_vehicle(&fits, &["time_offset_s"]);
            let clock_s = fits
                .iter()
                .map(|f| f.installation.time_offset_s)
                .sum::<f64>()
                / 3.0;
            mean_drift(&vehicle.installation(&term_set(&default_fix_terms()), clock_s))
        })
        .collect();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    println!(
        "A-KIT drift on T2, T3, T9, T10: none {none:.3} %, from turning segments {turning:.3?} (mean {:.3} %), from T1, T4 and T8 jointly {joint:.3?} (mean {:.3} %), from the straight T12 [own, own with its yaw held, others] {straight:.3?}, from T13's one turn {:.3?}",
        mean(&turning),
        mean(&joint),
        (0..3)
            .map(|seed| mean_drift(&fitted(13, seed).installation))
            .collect::<Vec<_>>()
    );
    assert!((0.5..0.6).contains(&none), "no calibration: {none:.3} %");
    assert!(mean(&turning) <= 0.20, "{turning:?}");
    assert!(mean(&joint) <= 0.13, "jointly {joint:?}");
    for [own, own_yaw_held, others] in &straight {
        assert!(
            own < own_yaw_held,
            "T12's own drift {own:.3} % with its yaw, {own_yaw_held:.3} % without"
        );
        assert!(
            *others <= none + 0.1,
            "from a straight segment {others:.3} % against {none:.3} %"
        );
    }
}

/// On A-KIT's real attitude, the reference's own body velocity as the DVL against
/// fixes that are its NED velocity summed by the trapezoidal rule (so that velocity and
/// positions agree exactly) give every term back at zero on T2, T3, T8 and T10: the
/// dead reckoning's sum, its interpolation and its attitude read at t + τ add nothing
/// of their own. (Against the reference's recorded positions the clock comes out near
/// −0.5 s: those positions and velocities disagree by centimetres per second in turns,
/// which fixes read through a clock they see only in changes of speed and crab;
/// docs/findings.md.)
#[test]
#[ignore = "needs the A-KIT recordings: dcnet-exp data fetch akit"]
fn a_reference_against_its_own_summed_velocity_gives_every_term_zero_on_akit() {
    use dcnet_exp::data::paired::{PairedColumns, PairedFiles, read};
    use dcnet_exp::installation::frames::Reference;
    let folder = common::akit();
    for k in [2, 3, 8, 10] {
        let recording = read(
            &PairedFiles::akit(&folder, k),
            &PairedColumns::akit_with_positions(),
        )
        .unwrap();
        let time_s = &recording.reference_time_s;
        let dvl = Reference::new(&recording).velocity_body_m_s;
        let mut summed = vec![[0.0; 2]];
        for i in 1..time_s.len() {
            let (v, w, dt) = (
                recording.velocity_ned_m_s[i - 1],
                recording.velocity_ned_m_s[i],
                time_s[i] - time_s[i - 1],
            );
            let last = summed[i - 1];
            summed.push([0, 1].map(|a| last[a] + 0.5 * (v[a] + w[a]) * dt));
        }
        let chosen: Vec<usize> = (0..time_s.len()).step_by(5).collect();
        let fixes = Fixes {
            lines: (0..chosen.len() as u64).collect(),
            time_s: chosen.iter().map(|&i| time_s[i]).collect(),
            north_east_m: chosen.iter().map(|&i| summed[i]).collect(),
            depth_m: None,
            noise_m: None,
        };
        let noise = FixNoise {
            fix_m: 0.01,
            depth_m: 0.01,
            dvl_m_s: 0.02,
        };
        let attitude = Attitude::of(&recording);
        let pieces = vec![0..time_s.len()];
        let terms = term_set(&default_fix_terms());
        let fit = fit_fixes((time_s, &dvl), &pieces, &attitude, &fixes, terms, noise).unwrap();
        let found = fit.installation;
        println!("T{k}: {found:?}");
        // Zero to rounding (measured: 1e-14 or less in each unit).
        let terms = [
            found.time_offset_s,
            found.scale[0],
            found.misalignment_rad[2],
            found.lever_arm_m[0],
            found.lever_arm_m[1],
        ];
        assert!(terms.iter().all(|t| t.abs() < 1e-9), "T{k}: {found:?}");
    }
}
