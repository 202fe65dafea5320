//! The A-KIT recordings as `data::paired` reads them (all 13 segments, 400 samples each,
//! the same time stamps in both files, yaw within ±π and wrapping there), and
//! `dcnet-exp data fetch akit` against a local server: the files land where the reader
//! looks for them, byte for byte, and bytes with another hash are refused.

use crate::common;
use common::*;
use dcnet_exp::data::catalogue::{AKIT_FILES, AKIT_SEGMENTS};
use dcnet_exp::data::paired::{PairedColumns, PairedFiles, PairedRecording, read};
use std::f64::consts::PI;
use std::path::Path;

/// Every A-KIT segment, read.
fn segments(folder: &Path) -> Vec<PairedRecording> {
    (1..=AKIT_SEGMENTS)
        .map(|segment| {
            read(&PairedFiles::akit(folder, segment), &PairedColumns::akit())
                .unwrap_or_else(|e| panic!("segment {segment}: {e}"))
        })
        .collect()
}

#[test]
#[ignore = "needs the A-KIT recordings: dcnet-exp data fetch akit"]
fn all_13_segments_read_with_400_samples_on_shared_time_stamps() {
    let folder = akit();
    let recordings = segments(&folder);
    assert_eq!(recordings.len(), 13);
    for (segment, recording) in (1..).zip(&recordings) {
        assert_eq!(recording.len(), 400, "segment {segment}");
        assert_eq!(recording.dvl_m_s.len(), 400);
        assert_eq!(recording.velocity_ned_m_s.len(), 400);
        assert_eq!(recording.attitude_rad.len(), 400);
        assert_eq!(recording.rate_rad_s, None);
        // The reference file's time stamps are the DVL file's, exactly: read them
        // again with the DVL's columns pointed at the reference file's.
        let files = PairedFiles::akit(&folder, segment);
        let reference_time = read(
            &PairedFiles {
                dvl: files.reference.clone(),
                reference: files.reference,
            },
            &PairedColumns {
                dvl: PairedColumns::akit().velocity_ned,
                ..PairedColumns::akit()
            },
        )
        .unwrap()
        .time_s;
        assert_eq!(recording.time_s, reference_time, "segment {segment}");
        // About 1.0025 s apart, from 0.
        assert_eq!(recording.time_s[0], 0.0);
        let step_s = recording.duration_s() / 399.0;
        assert!(
            (step_s - 1.0025).abs() < 1e-3,
            "segment {segment}: {step_s}"
        );
    }
    // The first DVL sample of segment 1, as its file has it.
    assert_eq!(
        recordings[0].dvl_m_s[0],
        [
            2.0635318058026133,
            0.30927571440863166,
            -0.012977275639956064
        ]
    );
    assert_eq!(recordings[0].attitude_rad[0][2], -2.938959909979959);
}

#[test]
#[ignore = "needs the A-KIT recordings: dcnet-exp data fetch akit"]
fn yaw_lies_within_pi_and_wraps_on_every_segment_with_turns() {
    let recordings = segments(&akit());
    let mut wrapping = Vec::new();
    for (segment, recording) in (1..).zip(&recordings) {
        let yaw: Vec<f64> = recording.attitude_rad.iter().map(|a| a[2]).collect();
        assert!(
            yaw.iter().all(|y| (-PI..=PI).contains(y)),
            "segment {segment}"
        );
        let jumps = yaw
            .windows(2)
            .filter(|pair| (pair[1] - pair[0]).abs() > PI)
            .count();
        if jumps > 0 {
            wrapping.push(segment);
        }
        // Roll and pitch of a level AUV: within 0.5 rad.
        assert!(
            recording
                .attitude_rad
                .iter()
                .all(|a| a[0].abs() < 0.5 && a[1].abs() < 0.5),
            "segment {segment}"
        );
    }
    // The straight segments T12 and T13 never cross ±π; every other one does.
    assert_eq!(wrapping, (1..=11).collect::<Vec<_>>());
}

#[test]
#[ignore = "needs the A-KIT recordings: dcnet-exp data fetch akit"]
fn data_fetch_akit_downloads_the_layout_the_reader_reads() {
    let folder = akit();
    let served: Vec<(String, Vec<u8>)> = AKIT_FILES
        .iter()
        .map(|file| {
            (
                format!("/{}", file.remote_path),
                std::fs::read(folder.join(file.name)).unwrap(),
            )
        })
        .collect();
    let (url, handle, server) = serve(served);
    let dir = tempfile::tempdir().unwrap();
    let output = dcnet(dir.path(), &["data", "fetch", "akit", "--base-url", &url]);
    assert!(output.status.success(), "{}", stderr(&output));
    let fetched = dir.path().join("data/akit");
    assert_eq!(tree(&fetched).len(), 26);
    for file in &AKIT_FILES {
        assert_eq!(
            std::fs::read(fetched.join(file.name)).unwrap(),
            std::fs::read(folder.join(file.name)).unwrap(),
            "{}",
            file.name
        );
    }
    assert_eq!(segments(&fetched), segments(&folder));
    // Fetched again, every file is kept; no Snapir file was asked for.
    let again = dcnet(dir.path(), &["data", "fetch", "akit", "--base-url", &url]);
    assert!(again.status.success(), "{}", stderr(&again));
    assert_eq!(
        stderr(&again)
            .matches("is already there (sha256 checked)")
            .count(),
        26,
        "{}",
        stderr(&again)
    );
    assert!(!dir.path().join("data/snapir").exists());
    server.unblock();
    handle.join().unwrap();
}

#[test]
fn data_fetch_akit_refuses_bytes_that_are_not_the_recording() {
    // The size of Trajectory1/DVL_trajectory1.csv, so that it is the hash that
    // refuses them.
    let first = &AKIT_FILES[0];
    let size = first.size_bytes as usize;
    let (url, handle, server) = serve(vec![(
        format!("/{}", first.remote_path),
        b"not the recording,".repeat(size / 18 + 1)[..size].to_vec(),
    )]);
    let dir = tempfile::tempdir().unwrap();
    let output = dcnet(
        dir.path(),
        &[
            "data",
            "fetch",
            "akit",
            "--base-url",
            &url,
            "--dest",
            "elsewhere",
        ],
    );
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    let message = stderr(&output);
    assert!(
        message.contains(&format!("{url}/Trajectory1/DVL_trajectory1.csv: sha256 ")),
        "{message}"
    );
    assert!(
        message.contains(&format!(
            ", expected {}: the download is not the published file",
            first.sha256
        )),
        "{message}"
    );
    assert!(tree(&dir.path().join("elsewhere")).is_empty());
    server.unblock();
    handle.join().unwrap();
}

#[test]
fn data_fetch_names_both_datasets_in_its_help_and_keeps_snapir_the_default() {
    let output = dcnet(Path::new("."), &["data", "fetch", "--help"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let help = stdout(&output);
    for expected in [
        "[DATASET]",
        "snapir",
        "akit",
        "the A-KIT recordings",
        "[default: snapir]",
    ] {
        assert!(help.contains(expected), "{expected:?} not in:\n{help}");
    }
    // A bad URL is refused (exit 1) before anything is made, for either dataset.
    let dir = tempfile::tempdir().unwrap();
    for dataset in ["snapir", "akit"] {
        let output = dcnet(
            dir.path(),
            &["data", "fetch", dataset, "--base-url", "localhost:1"],
        );
        assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
        assert_eq!(
            stderr(&output),
            "error: --base-url localhost:1: not an http:// or https:// address with a host\n"
        );
    }
    assert!(!dir.path().join("data").exists());
    let output = dcnet(dir.path(), &["data", "fetch", "beamsnet"]);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("invalid value 'beamsnet' for '[DATASET]'"),
        "{}",
        stderr(&output)
    );
}
