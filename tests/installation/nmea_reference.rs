//! A reference written as NMEA-0183 sentences, as a surface vehicle's GNSS and AHRS
//! write them: RMC ground velocity beside PASHR attitude as `--reference`, and PASHR
//! attitude alone as the `--attitude` of a fit to fixes, each calibrating as the same
//! values in CSV; sentences that fail are left out and counted.

use crate::bags::{TERMS, calibrate, terms_agree};
use crate::common::installed::{INSTALLED, write_installed};
use crate::common::{dcnet, stderr, stdout};
use dcnet_exp::data::paired::{PairedColumns, PairedFiles, PairedRecording, read};
use std::path::Path;

/// A knot, m/s.
const KNOT_M_S: f64 = 1852.0 / 3600.0;

/// 2017-04-06 00:00 UTC, s since 1970: the day RMC's date gives (its two-digit year
/// read as 20yy below 83), and the written trajectory's stamps are moved to.
const DAY_S: f64 = 1_491_436_800.0;

/// `body` (between `$` and `*`) as a sentence with its checksum.
fn sentence(body: &str) -> String {
    let sum = body.bytes().fold(0u8, |sum, b| sum ^ b);
    format!("${body}*{sum:02X}")
}

/// A time of day as NMEA writes it, from seconds since 1970.
fn time_of_day(t: f64) -> String {
    let t = t.rem_euclid(86_400.0);
    let (h, m, s) = (
        (t / 3600.0).floor(),
        ((t % 3600.0) / 60.0).floor(),
        t % 60.0,
    );
    format!("{h:02}{m:02}{s:06.3}")
}

/// The PASHR of reference sample `k`: heading true, roll, pitch in degrees.
fn pashr(r: &PairedRecording, k: usize) -> String {
    let [roll, pitch, yaw] = r.attitude_rad[k].map(f64::to_degrees);
    sentence(&format!(
        "PASHR,{},{:.5},T,{roll:+.5},{pitch:+.5},+0.00,0.010,0.010,0.020,2,1",
        time_of_day(r.reference_time_s[k]),
        yaw.rem_euclid(360.0)
    ))
}

/// The RMC of reference sample `k`: its north and east velocity as speed over ground
/// (knots) and course true.
fn rmc(r: &PairedRecording, k: usize) -> String {
    let [north, east, _] = r.velocity_ned_m_s[k];
    sentence(&format!(
        "GPRMC,{},A,4400.000000,N,06700.000000,W,{:.6},{:.5},060417,,,D",
        time_of_day(r.reference_time_s[k]),
        north.hypot(east) / KNOT_M_S,
        east.atan2(north).to_degrees().rem_euclid(360.0)
    ))
}

/// A written trajectory and its recording as read, its stamps moved by `shift_s`.
fn trajectory(d: &Path, shift_s: f64) -> (PairedFiles, PairedRecording) {
    write_installed(d, 1, &[], INSTALLED, 3);
    let files = PairedFiles::akit(d, 1);
    for path in [&files.dvl, &files.reference] {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        let mut moved = vec![lines.next().unwrap().to_string()];
        moved.extend(lines.map(|line| {
            let (t, rest) = line.split_once(',').unwrap();
            format!("{},{rest}", t.parse::<f64>().unwrap() + shift_s)
        }));
        std::fs::write(path, moved.join("\n") + "\n").unwrap();
    }
    let recording = read(&files, &PairedColumns::akit()).unwrap();
    (files, recording)
}

/// The reference's CSV file without the rows `skipped`, its down velocity zero.
fn reference_csv(r: &PairedRecording, skipped: &[usize], path: &Path) {
    let mut text = String::from(
        "Time [s],V North [m/s],V East [m/s],V Down [m/s],Roll [rad],Pitch [rad],Yaw [rad]\n",
    );
    for k in (0..r.reference_time_s.len()).filter(|k| !skipped.contains(k)) {
        let ([north, east, _], [roll, pitch, yaw]) = (r.velocity_ned_m_s[k], r.attitude_rad[k]);
        let t = r.reference_time_s[k];
        text.push_str(&format!("{t},{north},{east},0,{roll},{pitch},{yaw}\n"));
    }
    std::fs::write(path, text).unwrap();
}

/// A surface vehicle's reference as NMEA (each second an RMC and a PASHR; one RMC
/// damaged, one PASHR with no true heading) calibrates as the same reference in CSV
/// with its down velocity zero, those two seconds left out of it: every term within a
/// tenth of its standard deviation. The printout counts the sentences left out.
#[test]
fn an_nmea_reference_calibrates_as_its_csv_with_the_down_velocity_zero() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (files, r) = trajectory(d, DAY_S);
    let mut nmea = Vec::new();
    for k in 0..r.reference_time_s.len() {
        let mut velocity = rmc(&r, k);
        if k == 100 {
            velocity.replace_range(8..9, "9");
        }
        let mut attitude = pashr(&r, k);
        if k == 200 {
            attitude = sentence(&attitude[1..attitude.len() - 3].replace(",T,", ",M,"));
        }
        nmea.extend([velocity, attitude]);
    }
    std::fs::write(d.join("gnss.nmea"), nmea.join("\r\n") + "\r\n").unwrap();
    reference_csv(&r, &[100, 200], &d.join("reference.csv"));
    let dvl = files.dvl.to_str().unwrap();
    let fit = |reference: &str, out: &str| {
        calibrate(d, &[dvl, "--reference", reference, TERMS, "--out", out])
    };
    let (from_csv, from_nmea) = (fit("reference.csv", "csv"), fit("gnss.nmea", "nmea"));
    for expected in [
        // 800 sentences: the RMC of sample 100 fails its checksum (its PASHR then serves
        // none), the PASHR of sample 200 has a magnetic heading (its RMC then has none).
        "the reference: 398 RMC ground velocities beside their PASHR attitude (the down velocity zero), read from NMEA sentences (398 more that dated them or gave their attitude, 1 PASHR no RMC took; 3 left out: 1 whose checksum fails or that do not parse, 1 PASHR with no true heading, roll or pitch, 1 RMC with no PASHR within 0.05 s; 0 without a checksum",
    ] {
        assert!(
            from_nmea.contains(expected),
            "{expected}\nnot in\n{from_nmea}"
        );
    }
    terms_agree(&from_csv, &from_nmea, 0.1);
    // Nothing but GGA: no reference, refused naming the file.
    std::fs::write(
        d.join("gga.nmea"),
        sentence("GPGGA,000001.00,4400.0,N,06700.0,W,1,8,1.0,0,M,0,M,,") + "\n",
    )
    .unwrap();
    let output = dcnet(
        d,
        &["calibrate", dvl, "--reference", "gga.nmea", "--out", "gga"],
    );
    assert_eq!(output.status.code(), Some(1), "{}", stdout(&output));
    assert!(
        stderr(&output)
            .contains("gga.nmea: no reference sample among its sentences: 0 RMC ground velocities"),
        "{}",
        stderr(&output)
    );
}

/// PASHR attitude as the `--attitude` of a fit to fixes gives the terms the same
/// attitude in CSV gives, each within a tenth of its standard deviation.
#[test]
fn a_pashr_attitude_beside_fixes_calibrates_as_its_csv() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (files, r) = trajectory(d, 0.0);
    let segment = &crate::coverage::segments(std::slice::from_ref(&files))[0];
    crate::fixes::write_fixes(&d.join("fixes.csv"), segment, 5);
    let mut nmea = vec![sentence("GPZDA,000000.00,01,01,1970,00,00")];
    nmea.extend((0..r.reference_time_s.len()).map(|k| pashr(&r, k)));
    std::fs::write(d.join("ahrs.nmea"), nmea.join("\n") + "\n").unwrap();
    std::fs::write(
        d.join("columns.toml"),
        "[fix_columns]\ntime = \"t\"\nnorth_east = [\"n\", \"e\"]\n",
    )
    .unwrap();
    let dvl = files.dvl.to_str().unwrap();
    let fit = |attitude: &str, out: &str| {
        let args = [
            "calibrate",
            dvl,
            "--attitude",
            attitude,
            "--fixes",
            "fixes.csv",
        ];
        let more = [
            "--columns",
            "columns.toml",
            "--fix-noise-m",
            "0.5",
            "--out",
            out,
        ];
        let output = dcnet(d, &[&args[..], &more].concat());
        assert!(output.status.success(), "{}", stderr(&output));
        stdout(&output)
    };
    let from_csv = fit(files.reference.to_str().unwrap(), "csv");
    let from_nmea = fit("ahrs.nmea", "nmea");
    let read = "the attitude: 400 PASHR attitudes, read from NMEA sentences (1 more that dated them or gave their attitude; 0 left out; 0 without a checksum, so unchecked; 0 other sentences passed over)";
    assert!(from_nmea.contains(read), "{from_nmea}");
    terms_agree(&from_csv, &from_nmea, 0.1);
    // `correct --fixes` reads the same file and says so on its own read line.
    let saved = [&["--save", "saved.toml"][..], &["--out", "saved"]].concat();
    let output = dcnet(
        d,
        &[
            &[
                "calibrate",
                dvl,
                "--attitude",
                "ahrs.nmea",
                "--fixes",
                "fixes.csv",
            ][..],
            &["--columns", "columns.toml", "--fix-noise-m", "0.5"],
            &saved,
        ]
        .concat(),
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let output = dcnet(
        d,
        &[
            &[
                "correct",
                dvl,
                "--installation",
                "saved.toml",
                "--fixes",
                "fixes.csv",
            ][..],
            &["--attitude", "ahrs.nmea", "--columns", "columns.toml"],
            &["--fix-noise-m", "0.5", "--out", "next"],
        ]
        .concat(),
    );
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(stdout(&output).contains(read), "{}", stdout(&output));
}
