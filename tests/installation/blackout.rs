//! `calibrate --fixes --blackout-s START:LENGTH`: the fixes inside the window withheld
//! from the fit and the dead reckoning carried through it, its error at the window's
//! end a share of the distance travelled in it. Known answer on a synthetic dive whose
//! DVL reads 1 % fast and has no other error: with no terms, the dead reckoning placed
//! on the fixes before the window is off, on the fixes after it, by 1 % of the chord
//! between the two, a share of the path the calibrated dead reckoning travels; with the
//! scale fitted without the window's fixes, by far less. `--accept` holds the blackout's drift; `--report` draws
//! the plan view and the fixes' residual, each caption the printed numbers, and so does
//! `correct --fixes --report` of the installation carried to the next dive.

use crate::common::installed::Installed;
use crate::common::{dcnet, stderr, stdout};
use crate::fixes::{fix_dive_every, number_after, refused_naming};

/// A DVL reading 1 % fast, on time, at the reference point, its noise 0.2 cm/s (a
/// walk of about 2 cm across the blackout, against an error of about a metre).
const FAST: Installed = Installed {
    scale: 0.01,
    lever_arm_m: [0.0; 3],
    time_offset_s: 0.0,
    bias_m_s: [0.0; 3],
    noise_m_s: 0.002,
};

/// The rows (time, north, east) of a CSV file of that header.
fn rows(path: &str) -> Vec<[f64; 3]> {
    let text = std::fs::read_to_string(path).unwrap();
    (text.lines().skip(1))
        .map(|line| {
            let cells: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
            [cells[0], cells[1], cells[2]]
        })
        .collect()
}

/// The first stamp of the DVL's CSV file.
fn first_stamp(path: &str) -> f64 {
    let text = std::fs::read_to_string(path).unwrap();
    let line = text.lines().nth(1).unwrap();
    line.split(',').next().unwrap().parse().unwrap()
}

/// The expected drift, % of the distance, of a DVL reading 1 % fast across the window
/// `(from, to)`: each end placed on the mean of the fixes within 10 s outside it, the
/// error 1 % of the chord between those means, the distance the fixes' path between
/// them (the calibrated dead reckoning's). And the number of fixes strictly inside the
/// window.
fn expected(fixes: &[[f64; 3]], (from, to): (f64, f64)) -> (f64, usize) {
    let mean = |range: std::ops::RangeInclusive<f64>| {
        let inside: Vec<&[f64; 3]> = fixes.iter().filter(|f| range.contains(&f[0])).collect();
        let n = inside.len() as f64;
        [0, 1, 2].map(|k| inside.iter().map(|f| f[k]).sum::<f64>() / n)
    };
    let (start, end) = (mean(from - 10.0..=from), mean(to..=to + 10.0));
    let chord = (end[1] - start[1]).hypot(end[2] - start[2]);
    let mut path: Vec<&[f64; 3]> = (fixes.iter())
        .filter(|f| start[0] < f[0] && f[0] < end[0])
        .collect();
    let (first, last) = ([start[0], start[1], start[2]], [end[0], end[1], end[2]]);
    path.insert(0, &first);
    path.push(&last);
    let length: f64 = (path.windows(2))
        .map(|p| (p[1][1] - p[0][1]).hypot(p[1][2] - p[0][2]))
        .sum();
    let withheld = fixes.iter().filter(|f| from < f[0] && f[0] < to).count();
    (100.0 * 0.01 * chord / length, withheld)
}

#[test]
fn a_blackout_is_carried_through_by_the_dead_reckoning_and_scored_at_its_end() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Fixes every second, so that the path between them is the vehicle's.
    let [dvl, attitude, fixes] = fix_dive_every(d, FAST, 3, 1);
    std::fs::write(
        d.join("columns.toml"),
        "[fix_columns]\ntime = \"t\"\nnorth_east = [\"n\", \"e\"]\n",
    )
    .unwrap();
    let run = |extra: &[&str]| {
        let args = [
            "calibrate",
            &dvl,
            "--fixes",
            &fixes,
            "--attitude",
            &attitude,
            "--columns",
            "columns.toml",
            "--fix-noise-m",
            "0.1",
        ];
        dcnet(d, &[&args[..], extra].concat())
    };
    let output = run(&[
        "--blackout-s",
        "150:100",
        "--accept",
        "--report=report",
        "--save",
        "fast.toml",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    let start = first_stamp(&dvl);
    let (pct, withheld) = expected(&rows(&fixes), (start + 150.0, start + 250.0));
    assert!(
        text.contains(&format!(
            "blackout from 150 s to 250 s after the DVL's first sample: its {withheld} fixes withheld from the fit"
        )),
        "{text}"
    );
    let blackout = &text[text.find("blackout from").unwrap()..];
    let none = number_after(blackout, "at its end ");
    let terms = number_after(blackout, "with no terms, ");
    assert!((none - pct).abs() < 0.03 * pct, "{none} % against {pct} %");
    assert!(
        terms < 0.1 * none,
        "{terms} % against {none} % with no terms"
    );
    // The acceptance holds the blackout's drift as printed.
    let row = (text.lines())
        .find(|l| l.starts_with("| dead-reckoning drift at the blackout's end"))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(row.contains(&format!("| {terms:.3} %")), "{row}");
    // The report: each caption the printed numbers.
    let markdown = std::fs::read_to_string(d.join("report/report.md")).unwrap();
    assert!(
        markdown.contains(&format!(
            "{none:.3} % of the {:.1} m travelled in it with no terms, {terms:.3} % with the terms (red)",
            number_after(blackout, "over the ")
        )),
        "{markdown}"
    );
    let rms = &text[text.find("fixes' horizontal residual RMS: ").unwrap()..];
    let before = number_after(rms, "RMS: ");
    let after = number_after(
        rms,
        "with no terms (the start positions alone, to the same fixes), ",
    );
    assert!(
        markdown.contains(&format!(
            "RMS {before:.2} m with no terms, {after:.2} m with the terms applied"
        )),
        "{markdown}"
    );
    for figure in ["track", "fix_residual"] {
        assert!(d.join(format!("report/{figure}.png")).exists(), "{figure}");
    }
    assert!(d.join("report/report.html").exists());

    // The installation carried to the next dive, its report's residual the printed one.
    let [dvl, attitude, fixes] = fix_dive_every(&d.join("next"), FAST, 4, 1);
    let args = [
        "correct",
        &dvl,
        "--installation",
        "fast.toml",
        "--fixes",
        &fixes,
        "--attitude",
        &attitude,
        "--columns",
        "columns.toml",
        "--fix-noise-m",
        "0.1",
        "--report=next-report",
        "--accept",
    ];
    let output = dcnet(d, &args);
    assert!(output.status.success(), "{}", stderr(&output));
    let printed = stdout(&output);
    // --accept holds the carried installation's drift on the dive as printed.
    let dive_drift = number_after(&printed, "% of the distance with no terms, ");
    let check = (printed.lines())
        .find(|l| {
            l.starts_with("| dead-reckoning drift at the dive's end, the installation carried")
        })
        .unwrap_or_else(|| panic!("{printed}"));
    assert!(check.contains(&format!("| {dive_drift:.3} %")), "{check}");
    let line = &printed[printed.find("fixes' horizontal residual RMS").unwrap()..];
    let (before, after) = (
        number_after(line, "travelled: "),
        number_after(line, "of the distance) with no terms, "),
    );
    let markdown = std::fs::read_to_string(d.join("next-report/report.md")).unwrap();
    assert!(
        markdown.contains(&format!(
            "RMS {before:.2} m with no terms, {after:.2} m with the installation applied"
        )),
        "{printed}\n{markdown}"
    );
    assert!(d.join("next-report/track.png").exists());

    // A blackout past the record, or without fixes, is refused by name.
    let past = ["--blackout-s", "350:100"];
    refused_naming(&run(&past), "--blackout-s 350:100: ends 450.0 s", &past);
    let velocity = dcnet(
        d,
        &[
            "calibrate",
            &dvl,
            "--reference",
            &attitude,
            "--blackout-s",
            "1:2",
        ],
    );
    refused_naming(&velocity, "--blackout-s: goes with position fixes", &[]);
}

/// The rows of the CSV file `path` (a header, then numbers; an empty cell NaN).
fn numbers(path: &std::path::Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    (text.lines().skip(1))
        .map(|line| {
            (line.split(','))
                .map(|c| c.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect()
}

/// `ys` at `x`, linearly between the samples at `xs` (increasing).
fn between(xs: &[f64], ys: &[f64], x: f64) -> f64 {
    let k = xs.partition_point(|&t| t <= x).clamp(1, xs.len() - 1);
    let w = (x - xs[k - 1]) / (xs[k] - xs[k - 1]);
    ys[k - 1] + w * (ys[k] - ys[k - 1])
}

/// A-KIT's T1, its reference's positions as fixes beside its attitude, a 300-s blackout
/// 50 s in: the blackout's drift printed with the terms is within 5 % of an independent
/// dead reckoning's of the corrected recording the command wrote: each corrected
/// velocity turned into north and east by the reference's roll, pitch and yaw
/// (interpolated) at its valid time, summed by the trapezoidal rule, placed on the
/// positions of the 10 s before the blackout and scored on those of the 10 s after it,
/// latitude and longitude carried to metres on the WGS-84 ellipsoid's radii at the
/// first. (Measured: 0.229 % against 0.233 %.)
#[test]
#[ignore = "needs the A-KIT recordings: dcnet-exp data fetch akit"]
fn an_akit_blackouts_drift_is_an_independent_dead_reckonings() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let segment = crate::common::akit().join("Trajectory1");
    let (dvl, reference) = (
        segment.join("DVL_trajectory1.csv"),
        segment.join("GT_trajectory1.csv"),
    );
    let reference_path = reference.to_str().unwrap();
    let args = [
        "calibrate",
        dvl.to_str().unwrap(),
        "--fixes",
        reference_path,
        "--attitude",
        reference_path,
        "--fix-noise-m",
        "0.5",
        "--blackout-s",
        "50:300",
        "--accept",
        "--out",
        "t1",
    ];
    let output = dcnet(d, &args);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    let blackout = &text[text.find("blackout from 50 s to 350 s").expect(&text)..];
    let printed = number_after(blackout, "with no terms, ");

    // The reference: time, longitude, latitude (rad), ..., roll, pitch, yaw (rad).
    let rows = numbers(&reference);
    let column = |k: usize| -> Vec<f64> { rows.iter().map(|r| r[k]).collect() };
    let (time_s, longitude, latitude) = (column(0), column(1), column(2));
    let (roll, pitch, mut yaw) = (column(7), column(8), column(9));
    for k in 1..yaw.len() {
        let turn = ((yaw[k] - yaw[k - 1]) / std::f64::consts::TAU).round();
        yaw[k] -= turn * std::f64::consts::TAU;
    }
    let (a, e2, lat0) = (6_378_137.0, 6.694_379_990_14e-3, latitude[0]);
    let s2 = lat0.sin().powi(2);
    let (r_meridian, r_normal) = (
        a * (1.0 - e2) / (1.0 - e2 * s2).powf(1.5),
        a / (1.0 - e2 * s2).sqrt(),
    );
    let north: Vec<f64> = latitude.iter().map(|l| (l - lat0) * r_meridian).collect();
    let east: Vec<f64> = (longitude.iter())
        .map(|l| (l - longitude[0]) * r_normal * lat0.cos())
        .collect();
    // The corrected recording: time, valid at, vx, vy, vz (m/s, body axes).
    let corrected = numbers(&d.join("t1/DVL_trajectory1-corrected.csv"));
    let valid_s: Vec<f64> = corrected.iter().map(|r| r[1]).collect();
    let ned: Vec<[f64; 2]> = (corrected.iter())
        .map(|r| {
            let at = |angles: &[f64]| between(&time_s, angles, r[1]);
            let (phi, theta, psi) = (at(&roll), at(&pitch), at(&yaw));
            let (v, (sf, cf), (st, ct), (sp, cp)) = (
                [r[2], r[3], r[4]],
                phi.sin_cos(),
                theta.sin_cos(),
                psi.sin_cos(),
            );
            [
                cp * ct * v[0] + (cp * st * sf - sp * cf) * v[1] + (cp * st * cf + sp * sf) * v[2],
                sp * ct * v[0] + (sp * st * sf + cp * cf) * v[1] + (sp * st * cf - cp * sf) * v[2],
            ]
        })
        .collect();
    let mut track = vec![[0.0; 2]];
    for k in 1..ned.len() {
        let dt = valid_s[k] - valid_s[k - 1];
        let last = track[k - 1];
        track.push([0, 1].map(|j| last[j] + 0.5 * dt * (ned[k][j] + ned[k - 1][j])));
    }
    let on_track = |t: f64, j: usize| {
        let values: Vec<f64> = track.iter().map(|p| p[j]).collect();
        between(&valid_s, &values, t)
    };
    // Each end: the mean time and offset (position less track) of the positions there.
    let anchor = |low: f64, high: f64| {
        let inside: Vec<usize> = (0..time_s.len())
            .filter(|&k| (low..=high).contains(&time_s[k]))
            .filter(|&k| (valid_s[0]..=valid_s[valid_s.len() - 1]).contains(&time_s[k]))
            .collect();
        let n = inside.len() as f64;
        let mean = |f: &dyn Fn(usize) -> f64| inside.iter().map(|&k| f(k)).sum::<f64>() / n;
        (
            mean(&|k| time_s[k]),
            mean(&|k| north[k] - on_track(time_s[k], 0)),
            mean(&|k| east[k] - on_track(time_s[k], 1)),
        )
    };
    let first = corrected[0][0];
    let (from, to) = (first + 50.0, first + 350.0);
    let (start_s, start_n, start_e) = anchor(from - 10.0, from);
    let (end_s, end_n, end_e) = anchor(to, to + 10.0);
    let error_m = (start_n - end_n).hypot(start_e - end_e);
    let mut times = vec![start_s];
    times.extend(valid_s.iter().filter(|&&t| start_s < t && t < end_s));
    times.push(end_s);
    let distance_m: f64 = (times.windows(2))
        .map(|t| {
            let step = |j| on_track(t[1], j) - on_track(t[0], j);
            step(0).hypot(step(1))
        })
        .sum();
    let independent = 100.0 * error_m / distance_m;
    assert!(
        (printed - independent).abs() <= 0.05 * independent,
        "printed {printed} % against an independent {independent} %"
    );
}
