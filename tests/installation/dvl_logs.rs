//! A DVL's own log as the recording's DVL: public PD0 files read ping for ping as dolfyn
//! reads them; logs the tests write (`common::pd0`, from the byte layout) turned from
//! beam, instrument and earth coordinates into the vehicle's velocity; bad bytes counted
//! or refused by name; and `calibrate` on a PD0 log beside its reference's CSV file
//! finding the terms the same recording finds as CSV.

use crate::bags::{TERMS, calibrate, csv_args, terms};
use crate::common::installed::{INSTALLED, write_installed};
use crate::common::pd0::{Ping, Setup, beams_of, ensemble, framed, log};
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
        "pings: 901 with bottom lock kept (4 of them on three beams), 820 left out: 820 with the invalid marker",
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

/// `calibrate` reads a PD0 log beside its reference's CSV file, found by its content,
/// and finds every term within one standard deviation of the same recording as CSV; a
/// log without --reference, or with --valid-column, is refused by the flag.
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
    assert!(
        stderr(&output).contains("--reference: "),
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
}

/// Writes `files`' DVL as `dvl.pd0` in `dir` and checks its calibration against the CSV's.
fn calibrates_as_its_csv(dir: &Path, files: &PairedFiles) {
    let recording = paired::read(files, &PairedColumns::akit()).unwrap();
    let pd0 = dir.join("dvl.pd0");
    as_pd0(&recording, &pd0);
    let csv_args = csv_args(files);
    let csv_args: Vec<&str> = csv_args.iter().map(String::as_str).collect();
    let csv = calibrate(dir, &[&csv_args[..], &[TERMS, "--out", "csv"]].concat());
    let reference = files.reference.to_str().unwrap();
    let text = calibrate(
        dir,
        &[
            pd0.to_str().unwrap(),
            "--reference",
            reference,
            TERMS,
            "--out",
            "pd0",
        ],
    );
    let (log, csv) = (terms(&text), terms(&csv));
    assert_eq!(log.len(), csv.len(), "{text}");
    for ((term, log, _), (_, csv, std)) in log.iter().zip(&csv) {
        assert!(
            (log - csv).abs() <= *std,
            "{term}: {log} against {csv} ± {std}"
        );
    }
}

/// An A-KIT segment's DVL written as PD0 calibrates as its CSV does, each term within
/// one standard deviation.
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
