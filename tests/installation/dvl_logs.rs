//! A DVL's own log as the recording's DVL: public PD0 files read ping for ping as dolfyn
//! reads them; logs the tests write (`common::pd0`, from the byte layout) turned from
//! beam, instrument and earth coordinates into the vehicle's velocity; bad bytes counted
//! or refused by name; and `calibrate` on a PD0 log beside its reference's CSV file
//! finding the terms the same recording finds as CSV; a public log against its own GNSS
//! calibrated as an independent least-squares fit calibrates it.

use crate::bags::{TERMS, calibrate, csv_args, terms, terms_agree};
use crate::common::installed::{INSTALLED, write_installed};
use crate::common::pd0::{Ping, Setup, beams_of, blocks, ensemble, framed, log, navigation};
use crate::common::{akit, dcnet, repo, stderr, stdout};
use dcnet_exp::data::paired::dvl_log::{self, LogFormat, Thresholds, pd0};
use dcnet_exp::data::paired::{self, LeftOutWhy, PairedColumns, PairedFiles, PairedRecording};
use std::path::{Path, PathBuf};

fn public(name: &str) -> PathBuf {
    repo().join("tests/data/pd0").join(name)
}

/// dolfyn's reading of a file: per ensemble, its clock, the four velocities as
/// recorded and the instrument-axes velocity (NaN where dolfyn does not turn the frame).
fn dolfyn(name: &str) -> Vec<(f64, [f64; 4], [f64; 3])> {
    let text = std::fs::read_to_string(public(name)).unwrap();
    (text.lines().skip(1))
        .map(|line| {
            let v: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
            (v[0], [v[1], v[2], v[3], v[4]], [v[5], v[6], v[7]])
        })
        .collect()
}

/// Public PD0 files (earth, ship and beam coordinates; WinRiver, RiverPro, a file cut
/// short) read as dolfyn reads them: the same ensembles and clocks (to 1 ms), the same
/// pings with bottom lock, and each velocity dolfyn turns into the instrument's axes
/// within 1 mm/s of this reader's (the vehicle's, in forward, starboard, down). dolfyn
/// leaves out the last ensemble of the WinRiver and the RiverPro file, whose checksums
/// hold: this reader reads it.
#[test]
fn public_pd0_logs_read_ping_for_ping_as_dolfyn_reads_them() {
    for (file, reference, frame, [ensembles, by_dolfyn], kept, turned) in [
        (
            "RDI_withBT.000",
            "RDI_withBT.dolfyn.csv",
            "earth",
            [1721, 1721],
            901,
            901,
        ),
        (
            "winriver02.PD0",
            "winriver02.dolfyn.csv",
            "ship",
            [75, 74],
            74,
            0,
        ),
        (
            "RiverPro_test01_first20.PD0",
            "RiverPro_test01_first20.dolfyn.csv",
            "beam",
            [20, 19],
            19,
            19,
        ),
    ] {
        let log = dvl_log::read(&public(file), LogFormat::Pd0, Thresholds::default()).unwrap();
        let dolfyn = dolfyn(reference);
        assert_eq!(log.time_s.len(), ensembles, "{file}");
        assert_eq!(dolfyn.len(), by_dolfyn, "{file}");
        assert!(
            log.summary.frames[0].starts_with(frame),
            "{file}: {:?}",
            log.summary.frames
        );
        // Bottom lock as dolfyn's numbers say it: no −32.768 on x, y or z (in beam
        // coordinates, on two beams or more).
        let locked = |raw: &[f64; 4]| match frame {
            "beam" => raw.iter().filter(|&&v| v == -32.768).count() < 2,
            _ => raw[..3].iter().all(|&v| v != -32.768),
        };
        assert_eq!(
            dolfyn.iter().filter(|(_, raw, _)| locked(raw)).count(),
            kept,
            "{file}"
        );
        let (mut kept_here, mut compared) = (0, 0);
        for (k, (time_s, raw, instrument)) in dolfyn.iter().enumerate() {
            assert!((log.time_s[k] - time_s).abs() < 1e-3, "{file} ensemble {k}");
            assert_eq!(log.stated[k].is_none(), locked(raw), "{file} ensemble {k}");
            kept_here += usize::from(log.stated[k].is_none());
            assert!(log.stated[k].is_some() || log.velocity_m_s[k].iter().all(|v| v.abs() < 5.0));
            if log.stated[k].is_none() && instrument[0].is_finite() {
                // The vehicle's velocity is the bottom's negative, y forward, x starboard,
                // z up (EA is 0 in these files).
                let [x, y, z] = *instrument;
                let expected = [-y, -x, z];
                for axis in 0..3 {
                    assert!(
                        (log.velocity_m_s[k][axis] - expected[axis]).abs() < 1e-3,
                        "{file} ensemble {k}: {:?} against dolfyn's {expected:?}",
                        log.velocity_m_s[k]
                    );
                }
                compared += 1;
            }
        }
        assert_eq!((kept_here, compared), (kept, turned), "{file}");
    }
}

/// `data info` on a public PD0 file says its span, pings kept and left out by reason,
/// the last ensemble cut short, the frame and the data types.
#[test]
fn data_info_says_what_a_pd0_log_holds() {
    let dir = tempfile::tempdir().unwrap();
    let path = public("RDI_withBT.000");
    let output = dcnet(dir.path(), &["data", "info", path.to_str().unwrap()]);
    assert!(output.status.success(), "{}", stderr(&output));
    let info = stdout(&output);
    for expected in [
        "a Teledyne RDI PD0 log, 1721 pings over 2580.00 s from 2017-05-24 11:50:13.400 UTC",
        "SHA-256 cdb9c80b6014c0a0eded27a318350d0362153789761cf48915a7fc34c16ddfe6",
        "pings: 901 with bottom lock kept (4 of them on three beams), 820 left out: 509 with the invalid marker -32.768 m/s, 311 with the DVL looking up",
        "the last ensemble, at byte 999901, is cut short by the file's end (99 of its 581 bytes): not read",
        "frame: earth coordinates, turned back by each ensemble's heading, pitch and roll",
        "0x0600 bottom track: 1721",
    ] {
        assert!(info.contains(expected), "{expected}\nnot in\n{info}");
    }
}

/// Vehicle velocities written as beam velocities (30° convex with EA 45°, 20° concave)
/// come back within the mm/s rounding; a ping with one beam lost is a three-beam
/// solution, kept, marked and exact; two lost leave it out with the marker's reason,
/// and a correlation threshold set leaves out the ping with two beams below it.
#[test]
fn a_written_pd0_log_in_beam_coordinates_gives_the_vehicles_velocity() {
    let dir = tempfile::tempdir().unwrap();
    let vehicle = [1.52, -0.31, 0.12];
    for (setup, name) in [
        (
            Setup {
                frame: 0,
                beam_angle_code: 2,
                convex: true,
                alignment_deg: 45.0,
            },
            "convex",
        ),
        (
            Setup {
                frame: 0,
                beam_angle_code: 1,
                convex: false,
                alignment_deg: 0.0,
            },
            "concave",
        ),
    ] {
        let beams = beams_of(vehicle, &setup).map(|v| (v * 1000.0).round() as i16);
        let mut pings: Vec<Ping> = (0..4)
            .map(|k| Ping::good(1.6e9 + f64::from(k), beams))
            .collect();
        pings[1].velocity_mm_s[2] = -32768;
        pings[2].velocity_mm_s[0] = -32768;
        pings[2].velocity_mm_s[3] = -32768;
        pings[3].correlation = [250, 90, 250, 80];
        let path = dir.path().join(format!("{name}.pd0"));
        std::fs::write(&path, log(&setup, &pings)).unwrap();
        let read = dvl_log::read(&path, LogFormat::Pd0, Thresholds::default()).unwrap();
        assert_eq!(
            read.stated,
            vec![None, None, Some(LeftOutWhy::Marker), None],
            "{name}"
        );
        assert_eq!(read.summary.three_beam, 1, "{name}");
        for k in [0, 1, 3] {
            for axis in 0..3 {
                assert!(
                    (read.velocity_m_s[k][axis] - vehicle[axis]).abs() < 2e-3,
                    "{name} ping {k}: {:?}",
                    read.velocity_m_s[k]
                );
            }
        }
        let strict = Thresholds {
            correlation_min: Some(100),
            percent_good_min: None,
        };
        let read = dvl_log::read(&path, LogFormat::Pd0, strict).unwrap();
        assert_eq!(read.stated[3], Some(LeftOutWhy::LowCorrelation), "{name}");
    }
}

/// Bottom track in earth coordinates is turned back by the ensemble's own heading,
/// pitch and roll: a vehicle heading 120° and rolled 5° reads its own velocity.
#[test]
fn a_pd0_log_in_earth_coordinates_is_turned_back_by_its_attitude() {
    let dir = tempfile::tempdir().unwrap();
    let setup = Setup {
        frame: 3,
        beam_angle_code: 1,
        convex: true,
        alignment_deg: 0.0,
    };
    let vehicle = [1.2, 0.2, -0.05];
    let attitude_deg = [120.0, 3.0, 5.0];
    // The bottom's velocity in the instrument's axes, turned to east, north, up by
    // RDI's matrix (the internal tilt sensor's pitch, as the writer states EZ).
    let instrument = [-vehicle[1], -vehicle[0], vehicle[2]];
    let [h, p, r] = attitude_deg.map(f64::to_radians);
    let gimbal = (p.tan() * r.cos()).atan();
    let m = dvl_log::instrument_to_earth([h, gimbal, r]);
    let earth: Vec<i16> = (0..3)
        .map(|i| ((0..3).map(|j| m[i][j] * instrument[j]).sum::<f64>() * 1000.0).round() as i16)
        .collect();
    let mut ping = Ping::good(1.6e9, [earth[0], earth[1], earth[2], 0]);
    ping.attitude_deg = attitude_deg;
    let path = dir.path().join("earth.pd0");
    std::fs::write(
        &path,
        log(
            &setup,
            &[
                ping,
                Ping {
                    time_s: 1.6e9 + 1.0,
                    ..ping
                },
            ],
        ),
    )
    .unwrap();
    let read = dvl_log::read(&path, LogFormat::Pd0, Thresholds::default()).unwrap();
    for axis in 0..3 {
        assert!(
            (read.velocity_m_s[0][axis] - vehicle[axis]).abs() < 2e-3,
            "{:?}",
            read.velocity_m_s[0]
        );
    }
    // The turn is no identity: heading alone moves the forward velocity off x.
    assert!(earth[0].abs() > 500, "{earth:?}");
}

/// A byte changed in one ensemble fails its checksum: counted, not read, the others
/// read; bytes before the first ensemble are counted; offsets that overlap are refused
/// naming the ensemble's byte; a file of no ensemble is refused.
#[test]
fn bad_bytes_in_a_pd0_log_are_counted_or_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let setup = Setup {
        frame: 1,
        beam_angle_code: 2,
        convex: true,
        alignment_deg: 0.0,
    };
    let pings: Vec<Ping> = (0..5)
        .map(|k| Ping::good(1.6e9 + f64::from(k), [100, -2000, 30, 0]))
        .collect();
    let mut bytes = b"garbage".to_vec();
    let one = ensemble(&setup, 1, &pings[0]).len();
    bytes.extend(log(&setup, &pings));
    bytes[7 + one + 100] ^= 0x55;
    let path = dir.path().join("damaged.pd0");
    std::fs::write(&path, &bytes).unwrap();
    let read = dvl_log::read(&path, LogFormat::Pd0, Thresholds::default()).unwrap();
    assert_eq!(read.summary.bad_checksums, vec![(7 + one) as u64]);
    assert_eq!(read.time_s.len(), 4);
    assert_eq!(read.summary.bytes_between, 7 + one as u64);
    assert_eq!(read.velocity_m_s[0], [2.0, -0.1, 0.03]);
    // Offsets that overlap: the variable leader placed inside the fixed leader.
    let mut overlapping = framed(&[vec![0u8; 59], {
        let mut v = vec![0u8; 65];
        v[0] = 0x80;
        v
    }]);
    overlapping[8..10].copy_from_slice(&20u16.to_le_bytes());
    let length = overlapping.len() - 2;
    let sum = overlapping[..length]
        .iter()
        .fold(0u16, |s, &b| s.wrapping_add(u16::from(b)));
    overlapping[length..].copy_from_slice(&sum.to_le_bytes());
    let path = dir.path().join("overlapping.pd0");
    std::fs::write(&path, &overlapping).unwrap();
    let error = dvl_log::read(&path, LogFormat::Pd0, Thresholds::default())
        .unwrap_err()
        .to_string();
    assert!(
        error.starts_with(&format!(
            "{}: the ensemble at byte 0: its fixed leader at offset 10 holds 10 bytes before the next data type",
            path.display()
        )),
        "{error}"
    );
    let path = dir.path().join("none.pd0");
    std::fs::write(&path, [0x7F, 0x7F, 0x10, 0x00, 1, 2]).unwrap();
    let error = dvl_log::read(&path, LogFormat::Pd0, Thresholds::default())
        .unwrap_err()
        .to_string();
    assert!(error.contains("no PD0 ensemble"), "{error}");
    // A ping of the DVL looking up (system configuration bit 7) is left out as such.
    let mut up = ensemble(&setup, 1, &pings[0]);
    let fixed_at = usize::from(u16::from_le_bytes([up[6], up[7]]));
    up[fixed_at + 4] |= 0x80;
    let length = up.len() - 2;
    let sum = up[..length]
        .iter()
        .fold(0u16, |s, &b| s.wrapping_add(u16::from(b)));
    up[length..].copy_from_slice(&sum.to_le_bytes());
    up.extend(ensemble(&setup, 2, &pings[1]));
    let path = dir.path().join("up.pd0");
    std::fs::write(&path, &up).unwrap();
    let read = dvl_log::read(&path, LogFormat::Pd0, Thresholds::default()).unwrap();
    assert_eq!(read.stated, vec![Some(LeftOutWhy::LookingUp), None]);
    // A stray 0x7F before a header, and a false start whose length runs past the
    // file's end, lose no ensemble after them.
    let clean = log(&setup, &pings);
    for stray in [&[0x7F][..], &[0x7F, 0x7F, 0xFF, 0xFF, 0, 2, 10, 0][..]] {
        let mut bytes = clean[..3 * one].to_vec();
        bytes.extend_from_slice(stray);
        bytes.extend_from_slice(&clean[3 * one..]);
        let path = dir.path().join("stray.pd0");
        std::fs::write(&path, &bytes).unwrap();
        let read = dvl_log::read(&path, LogFormat::Pd0, Thresholds::default()).unwrap();
        assert_eq!(read.time_s.len(), 5, "{stray:?}");
        assert_eq!(read.summary.cut_short, None, "{stray:?}");
        assert_eq!(read.summary.bytes_between, stray.len() as u64, "{stray:?}");
    }
    let survey = pd0::read(&public("RiverPro_test01_first20.PD0"), &mut |_| {}).unwrap();
    assert_eq!(
        (
            survey.ensembles,
            survey.bad_checksums.len(),
            survey.cut_short
        ),
        (20, 0, None)
    );
}

/// `recording`'s DVL as a PD0 log in instrument coordinates, its clock from 1970-01-01
/// UTC as the CSV's seconds.
fn as_pd0(recording: &PairedRecording, path: &Path) {
    let setup = Setup {
        frame: 1,
        beam_angle_code: 2,
        convex: true,
        alignment_deg: 0.0,
    };
    let pings: Vec<Ping> = (recording.time_s.iter().zip(&recording.dvl_m_s))
        .map(|(&time_s, v)| {
            let mm = |x: f64| (x * 1000.0).round() as i16;
            Ping::good(time_s, [mm(-v[1]), mm(-v[0]), mm(v[2]), 0])
        })
        .collect();
    std::fs::write(path, log(&setup, &pings)).unwrap();
}

/// `calibrate` reads a PD0 log (and Water Linked reports) beside its reference's CSV
/// file, found by its content, and finds every term within one standard deviation of
/// the same recording as CSV; a log without --reference, or with --valid-column, is
/// refused by the flag (before the cost line); `correct` finds the log's clock again as it finds the CSV's.
#[test]
fn calibrate_reads_a_pd0_log_beside_its_reference_csv() {
    let dir = tempfile::tempdir().unwrap();
    write_installed(dir.path(), 1, &[], INSTALLED, 7);
    let files = PairedFiles {
        dvl: dir.path().join("Trajectory1/DVL_trajectory1.csv"),
        reference: dir.path().join("Trajectory1/GT_trajectory1.csv"),
    };
    calibrates_as_its_csv(dir.path(), &files);
    let pd0 = dir.path().join("dvl.pd0");
    let output = dcnet(dir.path(), &["calibrate", pd0.to_str().unwrap()]);
    assert_eq!(output.status.code(), Some(1));
    // Refused before its cost is stated: nothing is read of a log it cannot calibrate.
    assert!(
        stderr(&output).starts_with("error: --reference: "),
        "{}",
        stderr(&output)
    );
    let reference = files.reference.to_str().unwrap();
    let args = [
        "calibrate",
        pd0.to_str().unwrap(),
        "--reference",
        reference,
        "--valid-column",
        "ok",
    ];
    let output = dcnet(dir.path(), &args);
    assert!(
        stderr(&output).contains("--valid-column: "),
        "{}",
        stderr(&output)
    );
    // `correct` reads the log as it reads the CSV: the clock found again within a
    // tenth of its standard deviation (the log's velocities are whole mm/s).
    let csv = files.dvl.to_str().unwrap();
    let save = ["--save", "installation.toml", "--out", "saved"];
    calibrate(
        dir.path(),
        &[&[csv, "--reference", reference, TERMS][..], &save].concat(),
    );
    let corrected = |dvl: &str, out: &str| {
        let args = ["correct", dvl, "--installation", "installation.toml"];
        let output = dcnet(
            dir.path(),
            &[&args[..], &["--reference", reference, "--out", out]].concat(),
        );
        assert!(output.status.success(), "{}", stderr(&output));
        stdout(&output)
    };
    let (from_csv, from_pd0) = (
        corrected(csv, "from-csv"),
        corrected(pd0.to_str().unwrap(), "from-pd0"),
    );
    assert!(from_pd0.contains("clock found again"), "{from_pd0}");
    terms_agree(&from_csv, &from_pd0, 0.1);
}

/// Writes `files`' DVL as `dvl.pd0` and as Water Linked reports in `dir`, and checks
/// each one's calibration against the CSV's: every term within one standard deviation.
fn calibrates_as_its_csv(dir: &Path, files: &PairedFiles) {
    let recording = paired::read(files, &PairedColumns::akit()).unwrap();
    let (pd0, json) = (dir.join("dvl.pd0"), dir.join("dvl.json"));
    as_pd0(&recording, &pd0);
    as_water_linked(&recording, &json);
    let csv_args = csv_args(files);
    let csv_args: Vec<&str> = csv_args.iter().map(String::as_str).collect();
    let csv = terms(&calibrate(
        dir,
        &[&csv_args[..], &[TERMS, "--out", "csv"]].concat(),
    ));
    let reference = files.reference.to_str().unwrap();
    for (log, out) in [(&pd0, "out-pd0"), (&json, "out-json")] {
        let args = [
            log.to_str().unwrap(),
            "--reference",
            reference,
            TERMS,
            "--out",
            out,
        ];
        let text = calibrate(dir, &args);
        let found = terms(&text);
        assert_eq!(found.len(), csv.len(), "{text}");
        for ((term, log, _), (_, csv, std)) in found.iter().zip(&csv) {
            assert!(
                (log - csv).abs() <= *std,
                "{out}: {term}: {log} against {csv} ± {std}"
            );
        }
    }
}

/// An A-KIT segment's DVL written as PD0 and as Water Linked reports calibrates as its
/// CSV does, each term within one standard deviation.
#[test]
#[ignore = "needs the A-KIT recordings: dcnet-exp data fetch akit"]
fn an_akit_segment_as_pd0_calibrates_to_the_csv_terms() {
    let akit = akit();
    let dir = tempfile::tempdir().unwrap();
    let files = PairedFiles {
        dvl: akit.join("Trajectory1/DVL_trajectory1.csv"),
        reference: akit.join("Trajectory1/GT_trajectory1.csv"),
    };
    calibrates_as_its_csv(dir.path(), &files);
}

/// The navigation blocks (ID 0x2000) of a public VmDAS log read as dolfyn reads them:
/// each ensemble's last GNSS fix before its ping, its UTC time to 0.1 ms, its latitude
/// and longitude within a unit in the last place of dolfyn's float32 (dolfyn leaves out
/// the file's last ensemble, whose checksum holds). As fixes, each new time is one
/// (none repeats here: the GNSS and the pings are both at 1 Hz), placed on the log's
/// clock, which runs 7 h 1 min behind UTC (the recorder on local time, and its drift).
#[test]
fn vmdas_navigation_blocks_read_as_dolfyn_reads_them() {
    let log = dvl_log::read(
        &public("vmdas01_wh_first200.ENX"),
        LogFormat::Pd0,
        Thresholds::default(),
    )
    .unwrap();
    let reference = std::fs::read_to_string(public("vmdas01_wh_first200.dolfyn_nav.csv")).unwrap();
    let rows: Vec<Vec<f64>> = (reference.lines().skip(1))
        .map(|line| line.split(',').map(|c| c.parse().unwrap()).collect())
        .collect();
    assert_eq!((log.navigation.len(), rows.len()), (200, 199));
    let ulp = |v: f64| {
        let single = v as f32;
        f64::from(f32::from_bits(single.to_bits() + 1) - single).abs()
    };
    for ((stamp_s, _, fix), row) in log.navigation.iter().zip(&rows) {
        assert!((stamp_s - row[0]).abs() < 1e-3, "{stamp_s} against {row:?}");
        let time_s = fix.time_s.unwrap();
        assert!((time_s - row[1]).abs() < 1e-4, "{time_s} against {row:?}");
        assert!(
            (fix.latitude_deg - row[2]).abs() <= ulp(row[2]),
            "{fix:?} against {row:?}"
        );
        assert!(
            (fix.longitude_deg - row[3]).abs() <= ulp(row[3]),
            "{fix:?} against {row:?}"
        );
        assert!(fix.position_valid && fix.time_valid, "{fix:?}");
    }
    let fixes = dvl_log::navigation_fixes(&log).unwrap();
    assert_eq!((fixes.fixes.len(), fixes.left_out.len()), (200, 0));
    assert!(
        (fixes.recorder_behind_s - 25_268.79).abs() < 0.01,
        "{}",
        fixes.recorder_behind_s
    );
}

/// `calibrate --fixes` on a public WinRiver PD0 log: its own heading, pitch and roll as
/// the attitude, its GGA sentences as the fixes, placed on the log's clock (4 h and
/// 26.3 s behind the GNSS's: the recorder ran on local time), the fixes outside the
/// DVL's pieces left out. Its scale and yaw are those an independent least-squares fit
/// of the same model finds (`tests/data/pd0/gnss_fit.py`: numpy over dolfyn's decode,
/// 1.0266 and −25.73°), each within the tool's 95 % interval; the heading spans 52°, so
/// the yaw is said to be seen poorly. An attitude named from another file is that
/// file's, not the log's: one too short is refused naming it.
#[test]
fn a_pd0_log_is_fitted_to_its_own_gnss_fixes_on_its_own_clock() {
    let dir = tempfile::tempdir().unwrap();
    let log = public("winriver02.PD0");
    let log = log.to_str().unwrap();
    let fit = |attitude: &str| {
        let args = ["calibrate", log, "--fixes", log, "--attitude", attitude];
        let more = ["--fix-noise-m", "10", "--terms", "scale,misalignment"];
        dcnet(dir.path(), &[&args[..], &more, &["--out", "out"]].concat())
    };
    let output = fit(log);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    for expected in [
        "Read from the Teledyne RDI PD0 log: ship coordinates",
        "50 of them without a checksum, so unchecked",
        "placed on the log's clock, which runs 14426.30 s behind the GNSS's",
        "the DVL's 75 samples, 69 kept (6 left out: 6 beside a gap in the reference)",
        "50 fixes, 38 fitted (12 outside the DVL's pieces",
        "seen poorly, applied: misalignment z: the vehicle's heading spans 52° only",
    ] {
        assert!(text.contains(expected), "{expected}\nnot in\n{text}");
    }
    let independent = std::fs::read_to_string(public("winriver02.gnss_fit.csv")).unwrap();
    let row: Vec<f64> = (independent.lines().nth(1).unwrap().split(','))
        .map(|c| c.parse().unwrap())
        .collect();
    // v_dvl = (1 + s) R(δ) v_b, R(δ) taking the body's axes into the DVL's: the GNSS's
    // distance over the DVL's is 1 / (1 + s), and the GNSS's track lies δ_z clockwise of
    // the DVL's.
    let expected = [
        ("scale", 100.0 * (1.0 / row[3] - 1.0)),
        ("misalignment z", row[4]),
    ];
    for (term, independent) in expected {
        let (estimate, half_width) = table_row(&text, term);
        assert!(
            half_width.is_finite() && (estimate - independent).abs() <= half_width,
            "{term}: {estimate} ± {half_width} against the independent fit's {independent}\n{text}"
        );
    }
    let other = dir.path().join("attitude.csv");
    std::fs::write(
        &other,
        "Time [s],Roll [rad],Pitch [rad],Yaw [rad]\n0,0,0,0\n",
    )
    .unwrap();
    let output = fit(other.to_str().unwrap());
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("attitude.csv: 1 samples below the header"),
        "{}",
        stderr(&output)
    );
}

/// The estimate and the 95 % half-width of `term` in the terms table `calibrate` prints
/// (in the unit it prints them in).
fn table_row(text: &str, term: &str) -> (f64, f64) {
    let line = (text.lines())
        .find(|line| line.starts_with(&format!("| {term} ")))
        .unwrap_or_else(|| panic!("no row for {term} in\n{text}"));
    let cells: Vec<&str> = line.split('|').map(str::trim).collect();
    let number = |cell: &str| -> f64 {
        let digits = cell.trim_start_matches("± ").split(' ').next().unwrap();
        digits
            .parse()
            .unwrap_or_else(|_| panic!("{cell} in {line}"))
    };
    (number(cells[2]), number(cells[cells.len() - 2]))
}

/// A velocity report as a Water Linked DVL sends it, `time_of_validity` in µs since 1970.
fn water_linked_report(
    time_s: f64,
    velocity_m_s: [f64; 3],
    valid: bool,
    beams: usize,
    kind: &str,
) -> String {
    let transducers: Vec<String> = (0..4)
        .map(|id| format!(r#"{{"id":{id},"velocity":0.1,"distance":1.2,"rssi":-30.0,"nsd":-90.0,"beam_valid":{}}}"#, id < beams))
        .collect();
    format!(
        r#"{{"time":10.0,"vx":{},"vy":{},"vz":{},"fom":0.002,"altitude":1.2,"transducers":[{}],"velocity_valid":{valid},"status":0,"format":"json_v3.3","type":"{kind}","time_of_validity":{},"time_of_transmission":{}}}"#,
        velocity_m_s[0],
        velocity_m_s[1],
        velocity_m_s[2],
        transducers.join(","),
        (time_s * 1e6).round() as u64,
        (time_s * 1e6).round() as u64 + 150_000,
    )
}

/// The public Water Linked report reads as its numbers; a log of velocity reports,
/// one without lock, one tracking the water, one on three beams, a dead-reckoning
/// report and a last line cut short reads each ping with its reason; an unknown format
/// is refused naming its line.
#[test]
fn water_linked_reports_read_each_ping_with_its_validity() {
    let read = dvl_log::read(
        &repo().join("tests/data/water_linked/velocity_report.json"),
        LogFormat::WaterLinked,
        Thresholds::default(),
    )
    .unwrap();
    assert_eq!(read.time_s, vec![1_638_191_471.563_017]);
    assert_eq!(
        read.velocity_m_s,
        vec![[
            -3.713480691658333e-05,
            5.703703573090024e-05,
            2.4990416932269e-05
        ]]
    );
    assert_eq!(read.stated, vec![None]);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("dvl.json");
    let lines = [
        water_linked_report(1.7e9, [1.0, 0.1, 0.0], true, 4, "velocity"),
        water_linked_report(1.7e9 + 0.2, [0.0, 0.0, 0.0], false, 0, "velocity"),
        r#"{"ts":49056.8,"x":1.0,"y":2.0,"z":3.0,"std":0.01,"roll":0.6,"pitch":0.6,"yaw":0.6,"type":"position_local","status":0,"format":"json_v3.3"}"#.to_string(),
        water_linked_report(1.7e9 + 0.4, [0.9, 0.1, 0.0], true, 4, "velocity_water"),
        water_linked_report(1.7e9 + 0.6, [1.1, 0.0, 0.05], true, 3, "velocity"),
        r#"{"time":10.0,"vx":1.0,"#.to_string(),
    ];
    std::fs::write(&path, lines.join("\n")).unwrap();
    assert_eq!(dvl_log::format_of(&path), Some(LogFormat::WaterLinked));
    let read = dvl_log::read(&path, LogFormat::WaterLinked, Thresholds::default()).unwrap();
    assert_eq!(
        read.stated,
        vec![
            None,
            Some(LeftOutWhy::Flagged),
            Some(LeftOutWhy::WaterTrack),
            None
        ]
    );
    assert_eq!(read.number, vec![1, 2, 4, 5]);
    assert_eq!(read.velocity_m_s[3], [1.1, 0.0, 0.05]);
    assert_eq!(
        (read.summary.three_beam, read.summary.cut_short_line),
        (1, Some(6))
    );
    let output = dcnet(dir.path(), &["data", "info", path.to_str().unwrap()]);
    let info = stdout(&output);
    for expected in [
        "a Water Linked JSON log, 4 pings over 0.60 s",
        "pings: 2 with bottom lock kept (1 of them on three beams), 2 left out: 1 flagged invalid, 1 tracking the water, not the bottom",
        "the last line, 6, is cut short by the file's end (no JSON report): not read",
        "\"position_local\" reports: 1",
    ] {
        assert!(
            info.contains(expected),
            "{expected}\nnot in\n{info}\n{}",
            stderr(&output)
        );
    }
    let unknown = lines[0].replace("json_v3.3", "json_v4");
    std::fs::write(&path, format!("{}\n{unknown}\n", lines[4])).unwrap();
    let error = dvl_log::read(&path, LogFormat::WaterLinked, Thresholds::default())
        .unwrap_err()
        .to_string();
    assert_eq!(
        error,
        format!(
            "{}:2: format \"json_v4\": the reports read are json_v3, json_v3.1, json_v3.2, json_v3.3",
            path.display()
        )
    );
}

/// `recording`'s DVL as Water Linked velocity reports, stamped as the CSV's seconds.
fn as_water_linked(recording: &PairedRecording, path: &Path) {
    let lines: Vec<String> = (recording.time_s.iter().zip(&recording.dvl_m_s))
        .map(|(&time_s, &v)| water_linked_report(time_s, v, true, 4, "velocity"))
        .collect();
    std::fs::write(path, lines.join("\n") + "\n").unwrap();
}

/// A latitude or longitude (radians) as NMEA's degrees and minutes, and its hemisphere.
fn nmea_angle(rad: f64, degree_digits: usize, hemispheres: [char; 2]) -> String {
    let degrees = rad.to_degrees();
    let (whole, minutes) = (degrees.abs().trunc(), (degrees.abs().fract()) * 60.0);
    let hemisphere = if degrees < 0.0 {
        hemispheres[1]
    } else {
        hemispheres[0]
    };
    format!(
        "{:0degree_digits$}{minutes:09.6},{hemisphere}",
        whole as u32
    )
}

/// `body` (between `$` and `*`) as a sentence with its checksum.
fn sentence(body: &str) -> String {
    let sum = body.bytes().fold(0u8, |sum, b| sum ^ b);
    format!("${body}*{sum:02X}")
}

/// Synthetic segment 1 in `d`, and its reference's positions as GGA fixes every fifth
/// sample, in `fixes.nmea` (dated by a ZDA, the reference's seconds from 1970-01-01
/// UTC, after one GGA before any date; one with a bad checksum) and in `fixes.csv`
/// (the sentences' fixes as they round them), with `columns.toml` naming its columns.
fn gga_fixture(d: &Path) -> PairedFiles {
    write_installed(d, 1, &[], INSTALLED, 3);
    let files = PairedFiles::akit(d, 1);
    let segment = &crate::coverage::segments(std::slice::from_ref(&files))[0];
    let positions = crate::fixes::positions(segment);
    let (mut nmea, mut csv) = (Vec::new(), vec!["t,lat,lon".to_string()]);
    let gga = |t: f64, lat: f64, lon: f64| {
        let (h, m, s) = (
            (t / 3600.0).floor(),
            ((t % 3600.0) / 60.0).floor(),
            t % 60.0,
        );
        sentence(&format!(
            "GPGGA,{h:02}{m:02}{s:05.2},{},{},2,9,0.9,1.0,M,0.0,M,,",
            nmea_angle(lat, 2, ['N', 'S']),
            nmea_angle(lon, 3, ['E', 'W'])
        ))
    };
    // North and east turned into latitude and longitude about 44° N, 67° W.
    let (lat0, lon0, earth_m) = (44f64.to_radians(), -67f64.to_radians(), 6_378_137.0);
    for (k, p) in positions.iter().enumerate().step_by(5) {
        let t = segment.recording.reference_time_s[k];
        let (lat, lon) = (lat0 + p[0] / earth_m, lon0 + p[1] / (earth_m * lat0.cos()));
        if k == 0 {
            nmea.push(gga(t, lat, lon));
            nmea.push(sentence("GPZDA,000000.00,01,01,1970,00,00"));
            continue;
        }
        let mut fix = gga(t, lat, lon);
        if k == 50 {
            fix.truncate(fix.len() - 2);
            fix.push_str("00");
        } else {
            // The CSV file's fix is the sentence's, rounded as the sentence rounds it.
            let read = dcnet_exp::data::nmea::gga_fixes(&[(t, 0, fix.clone())]).unwrap();
            let origin = read.origin_deg.map(f64::to_radians);
            csv.push(format!("{t},{},{}", origin[0], origin[1]));
        }
        nmea.push(fix);
    }
    std::fs::write(d.join("fixes.nmea"), nmea.join("\r\n") + "\r\n").unwrap();
    std::fs::write(d.join("fixes.csv"), csv.join("\n") + "\n").unwrap();
    std::fs::write(
        d.join("columns.toml"),
        "[fix_columns]\ntime = \"t\"\nlatitude_longitude = [\"lat\", \"lon\"]\n",
    )
    .unwrap();
    files
}

/// An NMEA file of GGA fixes (dated by a ZDA, the reference's seconds from 1970-01-01
/// UTC) gives the calibration the same fixes as a CSV file gives, every term within a
/// tenth of its standard deviation; a GGA before any date is counted, one with a bad
/// checksum left out and counted.
#[test]
fn nmea_gga_fixes_calibrate_as_the_same_fixes_in_csv() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let files = gga_fixture(d);
    let (dvl, attitude) = (
        files.dvl.to_str().unwrap(),
        files.reference.to_str().unwrap(),
    );
    let fit = |fixes: &str, out: &str| {
        let args = [
            "calibrate",
            dvl,
            "--attitude",
            attitude,
            "--fixes",
            fixes,
            "--columns",
            "columns.toml",
        ];
        let output = dcnet(
            d,
            &[&args[..], &["--fix-noise-m", "0.5", "--out", out]].concat(),
        );
        assert!(output.status.success(), "{}", stderr(&output));
        stdout(&output)
    };
    let (from_csv, from_nmea) = (fit("fixes.csv", "out-csv"), fit("fixes.nmea", "out-nmea"));
    assert!(from_nmea.contains("from the NMEA file"), "{from_nmea}");
    assert!(
        from_nmea.contains("(1 more left out: a GGA before any RMC or ZDA gave the date)"),
        "{from_nmea}"
    );
    assert!(
        from_nmea.contains("78 fixes (1 more left out: a GGA whose checksum fails"),
        "{from_nmea}"
    );
    terms_agree(&from_csv, &from_nmea, 0.1);
}

/// A DVL's own log fitted to fixes beside another file's attitude and fixes (the
/// reference's CSV, an NMEA file), and a Water Linked log beside its own attitude (its
/// dead-reckoning reports), calibrate as the same recording's CSV: every term within
/// one standard deviation (PD0's velocities are whole mm/s). A Water Linked log with
/// no dead-reckoning report, named as its own attitude, is refused naming the file.
#[test]
fn dvl_logs_fit_fixes_beside_their_own_or_another_files_attitude() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let files = gga_fixture(d);
    let recording = paired::read(&files, &PairedColumns::akit()).unwrap();
    as_pd0(&recording, &d.join("dvl.pd0"));
    as_water_linked(&recording, &d.join("bare.json"));
    let mut lines = std::fs::read_to_string(d.join("bare.json")).unwrap();
    for (&t, rpy) in recording
        .reference_time_s
        .iter()
        .zip(&recording.attitude_rad)
    {
        let [roll, pitch, yaw] = rpy.map(f64::to_degrees);
        lines.push_str(&format!(
            r#"{{"ts":{t},"x":0.0,"y":0.0,"z":0.0,"std":0.01,"roll":{roll},"pitch":{pitch},"yaw":{yaw},"type":"position_local","status":0,"format":"json_v3.3"}}"#
        ));
        lines.push('\n');
    }
    std::fs::write(d.join("own.json"), lines).unwrap();
    let fit = |dvl: &str, attitude: &str, out: &str| {
        let args = [
            "calibrate",
            dvl,
            "--attitude",
            attitude,
            "--fixes",
            "fixes.nmea",
        ];
        dcnet(
            d,
            &[&args[..], &["--fix-noise-m", "0.5", "--out", out]].concat(),
        )
    };
    let reference = files.reference.to_str().unwrap();
    let from_csv = fit(files.dvl.to_str().unwrap(), reference, "out-csv");
    assert!(from_csv.status.success(), "{}", stderr(&from_csv));
    for (dvl, attitude, expected) in [
        ("dvl.pd0", reference, "the attitude from "),
        (
            "own.json",
            "own.json",
            "the roll, pitch and yaw of its dead-reckoning reports",
        ),
    ] {
        let output = fit(dvl, attitude, &format!("out-{dvl}"));
        assert!(output.status.success(), "{dvl}: {}", stderr(&output));
        let text = stdout(&output);
        assert!(text.contains(expected), "{expected}\nnot in\n{text}");
        assert!(text.contains("the fixes from the NMEA file"), "{text}");
        terms_agree(&stdout(&from_csv), &text, 1.0);
    }
    let output = fit("bare.json", "bare.json", "out-bare");
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("bare.json: this Water Linked JSON log records no attitude"),
        "{}",
        stderr(&output)
    );
}

/// A PD0 log whose recorder wrote VmDAS navigation blocks (each ping's last fix before
/// it, from the GGA fixes' positions; before the first fix, the position flagged
/// invalid) is fitted to them beside the reference's attitude as the CSV DVL is fitted
/// to the same fixes in CSV: every term within one standard deviation; each block
/// repeating the fix before is read once and counted, each flagged invalid left out
/// and counted (the log's velocities are whole mm/s, and the fixes are placed on its
/// clock by the median of their age at each ping).
#[test]
fn a_pd0_logs_vmdas_navigation_blocks_are_its_fixes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let files = gga_fixture(d);
    let recording = paired::read(&files, &PairedColumns::akit()).unwrap();
    let fixes: Vec<(f64, [f64; 2])> = (std::fs::read_to_string(d.join("fixes.csv")).unwrap())
        .lines()
        .skip(1)
        .map(|line| {
            let row: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
            (row[0], [row[1].to_degrees(), row[2].to_degrees()])
        })
        .collect();
    let setup = Setup {
        frame: 1,
        beam_angle_code: 2,
        convex: true,
        alignment_deg: 0.0,
    };
    let (mut bytes, mut before_any) = (Vec::new(), 0);
    for (k, (&time_s, v)) in recording.time_s.iter().zip(&recording.dvl_m_s).enumerate() {
        let mm = |x: f64| (x * 1000.0).round() as i16;
        let ping = Ping::good(time_s, [mm(-v[1]), mm(-v[0]), mm(v[2]), 0]);
        let mut blocks = blocks(&setup, k as u32 + 1, &ping).to_vec();
        // Before the first fix, VmDAS writes its block with the position flagged invalid.
        match fixes.iter().rev().find(|(t, _)| *t <= time_s) {
            Some(&(fix_s, position_deg)) => blocks.push(navigation(fix_s, position_deg, true)),
            None => {
                blocks.push(navigation(time_s, [0.0; 2], false));
                before_any += 1;
            }
        }
        bytes.extend(framed(&blocks));
    }
    std::fs::write(d.join("nav.pd0"), bytes).unwrap();
    let reference = files.reference.to_str().unwrap();
    let fit = |dvl: &str, fixes: &str, out: &str| {
        let args = ["calibrate", dvl, "--attitude", reference, "--fixes", fixes];
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
    let from_csv = fit(files.dvl.to_str().unwrap(), "fixes.csv", "out-csv");
    let from_log = fit("nav.pd0", "nav.pd0", "out-log");
    let repeats = recording.time_s.len() - before_any - fixes.len();
    for expected in [
        format!(
            "the fixes from its VmDAS navigation blocks (each ping's last fix before it; {repeats} blocks repeating the fix before, read once;"
        ),
        format!(
            "{} fixes ({before_any} more left out: a VmDAS navigation block whose position is flagged invalid)",
            fixes.len()
        ),
    ] {
        assert!(
            from_log.contains(&expected),
            "{expected}\nnot in\n{from_log}"
        );
    }
    assert!(before_any > 0 && repeats > 0, "{before_any} {repeats}");
    terms_agree(&from_csv, &from_log, 1.0);
}

/// A study whose recordings' DVLs are Water Linked logs (the same velocities, written
/// whole) scores as the same study over the CSV files, to 1e-6 cm/s; a log's format
/// named wrongly, or a log without its reference, is refused at its key.
#[test]
fn a_study_of_dvl_logs_scores_as_the_study_of_their_csv_files() {
    use crate::common::installed::write_study_spec;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_installed(&d.join("data/syn"), 3, &[], INSTALLED, 5);
    write_study_spec(d, "csv", "syn", 3, "");
    std::fs::create_dir_all(d.join("data/logs")).unwrap();
    let mut spec = std::fs::read_to_string(d.join("experiments/csv.toml"))
        .unwrap()
        .replace("name = \"csv\"", "name = \"logs\"");
    for n in 1..=3 {
        let files = PairedFiles::akit(&d.join("data/syn"), n);
        let recording = paired::read(&files, &PairedColumns::akit()).unwrap();
        as_water_linked(&recording, &d.join(format!("data/logs/S{n}.json")));
        spec = spec.replace(
            &format!("dvl = \"../data/syn/Trajectory{n}/DVL_trajectory{n}.csv\""),
            &format!("dvl = \"../data/logs/S{n}.json\""),
        );
    }
    std::fs::write(d.join("experiments/logs.toml"), &spec).unwrap();
    crate::common::studies_score_alike(d, "csv", "logs");
    let wrong = spec
        .replace("dvl = \"../data/logs/S1.json\"", "dvl = \"../data/logs/S1.json\"\ndvl_format = \"nortek\"")
        .replace(
            "dvl = \"../data/logs/S2.json\"\nreference = \"../data/syn/Trajectory2/GT_trajectory2.csv\"",
            "dvl = \"../data/logs/S2.json\"",
        )
        .replace("name = \"logs\"", "name = \"wrong\"");
    std::fs::write(d.join("experiments/wrong.toml"), wrong).unwrap();
    let output = dcnet(d, &["validate", "experiments/wrong.toml"]);
    assert!(!output.status.success());
    let error = stderr(&output);
    assert!(error.contains("recordings.trajectories[0].dvl_format: \"nortek\": a DVL log's format is one of pd0, water-linked"), "{error}");
    assert!(
        error.contains("recordings.trajectories[1].reference: "),
        "{error}"
    );
}
