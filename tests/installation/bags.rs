//! ROS 2 bags as recordings: a recording written as a ROS 2 vehicle writes it (the DVL
//! as `marine_acoustic_msgs/msg/Dvl` in its own frame placed by `/tf_static`, the INS as
//! `nav_msgs/msg/Odometry` in ENU and forward-left-up), in each storage, calibrates to
//! the terms of the same recording as CSV; lost-lock pings are counted; frames turned
//! both ways; topics missing or ambiguous, and a bag cut short, refused by name.

use crate::common::installed::{INSTALLED, write_installed};
use crate::common::{akit, dcnet, stderr, stdout};
use dcnet_exp::data::paired::bag::write::{
    BagWriter, DvlStatus, Format, RosLayout, dvl_message, write_recording,
};
use dcnet_exp::data::paired::bag::{Bag, decode};
use dcnet_exp::data::paired::{self, PairedColumns, PairedFiles};
use std::path::{Path, PathBuf};

/// The synthetic trajectory 1 of a known installation, 1 Hz over 400 s, as CSV.
fn synthetic(dir: &Path) -> PairedFiles {
    write_installed(dir, 1, &[], INSTALLED, 7);
    PairedFiles {
        dvl: dir.join("Trajectory1/DVL_trajectory1.csv"),
        reference: dir.join("Trajectory1/GT_trajectory1.csv"),
    }
}

/// The rows of the first table `calibrate` prints: the terms as found.
fn term_rows(stdout: &str) -> Vec<String> {
    stdout
        .lines()
        .skip_while(|l| !l.starts_with("| term"))
        .take_while(|l| l.starts_with('|'))
        .skip(2)
        .map(String::from)
        .collect()
}

/// Each term's name, estimate and standard deviation from [`term_rows`].
pub(crate) fn terms(stdout: &str) -> Vec<(String, f64, f64)> {
    term_rows(stdout)
        .iter()
        .map(|row| {
            let cells: Vec<&str> = row.split('|').map(str::trim).collect();
            let number = |cell: &str| {
                cell.split_whitespace()
                    .next()
                    .unwrap()
                    .parse::<f64>()
                    .unwrap()
            };
            (cells[1].to_string(), number(cells[2]), number(cells[3]))
        })
        .collect()
}

/// Asserts that the terms `found` prints are those `expected` prints, each within
/// `share` of the standard deviation `expected` gives it.
pub(crate) fn terms_agree(expected: &str, found: &str, share: f64) {
    let (expected_terms, found_terms) = (terms(expected), terms(found));
    assert_eq!(expected_terms.len(), found_terms.len(), "{found}");
    for ((term, a, std), (_, b, _)) in expected_terms.iter().zip(&found_terms) {
        assert!(
            (a - b).abs() <= share * std,
            "{term}: {b} against {a} ± {std}\n{found}"
        );
    }
}

pub(crate) fn calibrate(dir: &Path, args: &[&str]) -> String {
    let output = dcnet(dir, &[&["calibrate"], args].concat());
    assert!(output.status.success(), "{}", stderr(&output));
    stdout(&output)
}

pub(crate) fn csv_args(files: &PairedFiles) -> Vec<String> {
    vec![
        files.dvl.display().to_string(),
        "--reference".into(),
        files.reference.display().to_string(),
    ]
}

pub(crate) const TERMS: &str = "--terms=lever_arm,time_offset,bias,scale";

/// The same recording as CSV and as bags of each storage (MCAP compressed and not,
/// sqlite3, and a rosbag2 folder) gives the same terms to the printed digits; the
/// bag's output says its frames and gives the terms in base_link's FLU axes, y and z
/// of the lever arm negated.
#[test]
fn a_bag_written_from_a_csv_recording_gives_the_csv_terms_in_every_storage() {
    let dir = tempfile::tempdir().unwrap();
    let files = synthetic(dir.path());
    let recording = paired::read(&files, &PairedColumns::akit()).unwrap();
    let csv = calibrate(
        dir.path(),
        &[
            csv_args(&files)
                .iter()
                .map(String::as_str)
                .collect::<Vec<_>>(),
            vec![TERMS, "--out", "csv"],
        ]
        .concat(),
    );
    let expected = term_rows(&csv);
    assert_eq!(expected.len(), 8, "{csv}");
    std::fs::create_dir(dir.path().join("folder")).unwrap();
    let bags: Vec<(PathBuf, Format)> = vec![
        (
            dir.path().join("zstd.mcap"),
            Format::Mcap { compressed: true },
        ),
        (
            dir.path().join("plain.mcap"),
            Format::Mcap { compressed: false },
        ),
        (dir.path().join("dive.db3"), Format::Sqlite),
        (
            dir.path().join("folder/folder_0.mcap"),
            Format::Mcap { compressed: true },
        ),
    ];
    for (path, format) in &bags {
        write_recording(&recording, path, *format, RosLayout::default()).unwrap();
    }
    std::fs::write(
        dir.path().join("folder/metadata.yaml"),
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  relative_file_paths:\n    - folder_0.mcap\n",
    )
    .unwrap();
    for bag in ["zstd.mcap", "plain.mcap", "dive.db3", "folder"] {
        let out = format!("out-{bag}");
        let text = calibrate(dir.path(), &[bag, TERMS, "--out", &out]);
        assert_eq!(term_rows(&text), expected, "{bag}:\n{text}");
        assert!(text.contains("the DVL from /dvl/data (marine_acoustic_msgs/msg/Dvl) in frame dvl_link, each ping's bottom lock read from its message, placed in base_link by /tf_static at (0.000, 0.000, 0.000) m, roll 180.0°"), "{text}");
        assert!(
            text.contains("world odom (ENU), body base_link (FLU: x forward, y left, z up)"),
            "{text}"
        );
    }
    // In FLU the lever arm's y and z read negated, its x the same.
    let text = calibrate(
        dir.path(),
        &["zstd.mcap", TERMS, "--out", "flu", "--save", "dvl.toml"],
    );
    let flu = text
        .split("The same terms in base_link's own axes (FLU")
        .nth(1)
        .unwrap();
    let frd = terms(&text);
    let lever = |axis: &str| {
        frd.iter()
            .find(|(n, _, _)| n == &format!("lever arm {axis}"))
            .unwrap()
            .1
    };
    for (axis, sign) in [("x", 1.0), ("y", -1.0), ("z", -1.0)] {
        let row = format!("| lever arm {axis}");
        let line = flu.lines().find(|l| l.starts_with(&row)).unwrap();
        let value: f64 = line
            .split('|')
            .nth(2)
            .unwrap()
            .split_whitespace()
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!((value - sign * lever(axis)).abs() < 1e-9, "{axis}: {line}");
    }
    // --save writes the joint and the static transform with that lever arm.
    let urdf = std::fs::read_to_string(dir.path().join("dvl.urdf")).unwrap();
    let xyz = format!(
        "xyz=\"{:.4} {:.4} {:.4}\"",
        lever("x"),
        -lever("y"),
        -lever("z")
    );
    assert!(urdf.contains(&xyz), "{urdf} lacks {xyz}");
    assert!(
        urdf.contains("<parent link=\"base_link\"/>")
            && urdf.contains("<child link=\"dvl_link\"/>"),
        "{urdf}"
    );
    let ros = std::fs::read_to_string(dir.path().join("dvl.ros.txt")).unwrap();
    assert!(
        ros.contains("static_transform_publisher --x")
            && ros.contains("--frame-id base_link --child-frame-id dvl_link"),
        "{ros}"
    );
    // `correct` carries it to another bag of the dive, finds its clock, and writes it.
    let output = dcnet(
        dir.path(),
        &[
            "correct",
            "plain.mcap",
            "--installation",
            "dvl.toml",
            "--out",
            "corrected",
        ],
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let corrected =
        std::fs::read_to_string(dir.path().join("corrected/plain-corrected.csv")).unwrap();
    assert!(
        stderr(&output).contains("399 of the dive's 400 samples written to"),
        "{}",
        stderr(&output)
    );
    // The corrected bag: one TwistWithCovarianceStamped a sample, in base_link's FLU
    // axes, stamped when it is valid, each the CSV's velocity with y and z negated.
    let bag = Bag::open(&dir.path().join("corrected/plain-corrected.mcap")).unwrap();
    let mut messages = Vec::new();
    let survey = bag
        .stream(&|_, _, _| true, &mut |topic, definitions, _, data| {
            messages.push(decode(data, &topic.type_name, definitions).unwrap());
            Ok(())
        })
        .unwrap();
    assert_eq!(survey.topics[0].name, "/dvl/data/corrected");
    assert_eq!(
        survey.topics[0].type_name,
        "geometry_msgs/msg/TwistWithCovarianceStamped"
    );
    assert_eq!(messages.len(), 399);
    for (line, message) in corrected
        .lines()
        .skip(1)
        .filter(|l| !l.contains(",,,"))
        .zip(&messages)
        .step_by(97)
    {
        let cells: Vec<f64> = line
            .split(',')
            .take(5)
            .map(|c| c.parse().unwrap())
            .collect();
        let number = |path: &[usize]| message.at(path).unwrap().number().unwrap();
        let stamp = number(&[0, 0, 0]) - 1_700_000_000.0 + number(&[0, 0, 1]) * 1e-9;
        assert!((stamp - cells[1]).abs() < 1e-6, "{line}: stamped {stamp}");
        assert_eq!(message.at(&[0, 1]).unwrap().text(), Some("base_link"));
        for (k, sign) in [(0, 1.0), (1, -1.0), (2, -1.0)] {
            assert!(
                (number(&[1, 0, 0, k]) - sign * cells[2 + k]).abs() < 1e-12,
                "{line}"
            );
        }
        let variance = number(&[1, 1, 0]);
        assert!(variance > 1e-5 && variance < 1e-2, "{variance}");
    }
    // The installation remembers the mount it was found on: a dive whose /tf_static
    // mounts the DVL otherwise is refused, not corrected with a turn from another.
    let saved = std::fs::read_to_string(dir.path().join("dvl.toml")).unwrap();
    assert!(
        saved.contains("[mount]") && saved.contains("dvl_frame = \"dvl_link\""),
        "{saved}"
    );
    let yawed = RosLayout {
        mount_yaw_deg: 10.0,
        ..RosLayout::default()
    };
    write_recording(
        &recording,
        &dir.path().join("yawed.mcap"),
        Format::Mcap { compressed: true },
        yawed,
    )
    .unwrap();
    let output = dcnet(
        dir.path(),
        &[
            "correct",
            "yawed.mcap",
            "--installation",
            "dvl.toml",
            "--out",
            "yawed",
        ],
    );
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("its /tf_static places dvl_link in base_link at roll, pitch, yaw 180.00, -0.00, 10.00 deg, but the installation dvl.toml was found with it at 180.00, -0.00, 0.00 deg"),
        "{}",
        stderr(&output)
    );
    // The mount is rolled 180°: the rotation found stays within a degree of it.
    let roll: f64 = ros
        .split("--roll ")
        .nth(1)
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        (roll.abs() - std::f64::consts::PI).abs() < 1f64.to_radians(),
        "{ros}"
    );
}

/// A DVL mounted rolled 180° and yawed 45° from base_link: its velocity in its own
/// axes is turned back by /tf_static, and the terms are the CSV's (the misalignment
/// found is the residual from the mount, near zero); lost-lock pings, flagged in the
/// message, are counted and left out, and the terms stay within two standard
/// deviations.
#[test]
fn a_yawed_mount_is_turned_back_and_lost_lock_pings_are_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let files = synthetic(dir.path());
    let recording = paired::read(&files, &PairedColumns::akit()).unwrap();
    let csv = calibrate(
        dir.path(),
        &[
            csv_args(&files)
                .iter()
                .map(String::as_str)
                .collect::<Vec<_>>(),
            vec![TERMS, "--out", "csv"],
        ]
        .concat(),
    );
    let yawed = RosLayout {
        mount_yaw_deg: 45.0,
        ..RosLayout::default()
    };
    write_recording(
        &recording,
        &dir.path().join("yawed.mcap"),
        Format::Mcap { compressed: true },
        yawed,
    )
    .unwrap();
    let text = calibrate(dir.path(), &["yawed.mcap", TERMS, "--out", "yawed"]);
    for ((name, bag, _), (_, csv, std)) in terms(&text).iter().zip(terms(&csv)) {
        assert!(
            (bag - csv).abs() <= 0.01 * std.max(1e-6) + 1e-4,
            "{name}: {bag} against {csv}"
        );
    }
    assert!(text.contains("yaw 45.0°"), "{text}");
    let lost = RosLayout {
        lost_lock_every: Some(10),
        ..RosLayout::default()
    };
    write_recording(
        &recording,
        &dir.path().join("lost.db3"),
        Format::Sqlite,
        lost,
    )
    .unwrap();
    let output = dcnet(
        dir.path(),
        &["calibrate", "lost.db3", TERMS, "--out", "lost"],
    );
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    assert!(text.contains("40 flagged invalid"), "{text}");
    for ((name, bag, std), (_, csv, _)) in terms(&text).iter().zip(terms(&csv)) {
        assert!(
            (bag - csv).abs() <= 2.0 * std,
            "{name}: {bag} against {csv} ± {std}"
        );
    }
}

/// A topic named that is not in the bag, two DVL topics and none named, a DVL frame
/// /tf_static does not join, a flag meant for CSV, and a bag cut short: each refused
/// with its cause, exit 1 or 2, never a panic; `data info` lists the topics.
#[test]
fn topics_missing_or_ambiguous_and_a_damaged_bag_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let files = synthetic(dir.path());
    let recording = paired::read(&files, &PairedColumns::akit()).unwrap();
    let bag = dir.path().join("dive.mcap");
    write_recording(
        &recording,
        &bag,
        Format::Mcap { compressed: true },
        RosLayout::default(),
    )
    .unwrap();
    let refused = |args: &[&str]| {
        let output = dcnet(dir.path(), &[&["calibrate"], args].concat());
        assert!(!output.status.success(), "{}", stdout(&output));
        assert!(
            matches!(output.status.code(), Some(1 | 2)),
            "{:?}",
            output.status
        );
        stderr(&output)
    };
    let error = refused(&["dive.mcap", "--dvl-topic", "/nope"]);
    assert!(
        error.contains("--dvl-topic: no topic /nope in the bag"),
        "{error}"
    );
    assert!(
        error.contains(
            "/dvl/data  marine_acoustic_msgs/msg/Dvl  400 messages, 1.00 Hz  (read as a DVL)"
        ),
        "{error}"
    );
    let error = refused(&["dive.mcap", "--reference-topic", "/dvl/data"]);
    assert!(error.contains("--reference-topic: /dvl/data is marine_acoustic_msgs/msg/Dvl with 400 messages, not a reference"), "{error}");
    let error = refused(&["dive.mcap", "--reference", "x.csv"]);
    assert!(
        error.contains("is a bag: it holds the reference too"),
        "{error}"
    );
    let error = refused(&[files.dvl.to_str().unwrap(), "--dvl-topic", "/dvl"]);
    assert!(error.contains("is not a bag"), "{error}");
    let error = refused(&[files.dvl.to_str().unwrap(), "--frame", "base_link"]);
    assert!(
        error.contains("--frame") && error.contains("is not a bag"),
        "{error}"
    );
    // A folder rosbag2 compressed itself: refused by name, not as damaged.
    std::fs::create_dir(dir.path().join("squeezed")).unwrap();
    std::fs::write(
        dir.path().join("squeezed/metadata.yaml"),
        "rosbag2_bagfile_information:\n  storage_identifier: mcap\n  compression_format: zstd\n  compression_mode: FILE\n  relative_file_paths:\n    - squeezed_0.mcap.zstd\n",
    )
    .unwrap();
    let error = refused(&["squeezed"]);
    assert!(
        error.contains("compression_format \"zstd\": a bag compressed by rosbag2 is not read here"),
        "{error}"
    );
    // Two DVL topics, none named.
    let two = dir.path().join("two.mcap");
    let mut writer = BagWriter::create(&two, Format::Mcap { compressed: false }).unwrap();
    for topic in ["/dvl/a", "/dvl/b"] {
        writer.topic(topic, "marine_acoustic_msgs/msg/Dvl").unwrap();
        writer
            .write(
                topic,
                1,
                &dvl_message(1, "base_link", [1.0, 0.0, 0.0], DvlStatus::BOTTOM_LOCK, 0.0),
            )
            .unwrap();
    }
    writer.topic("/odom", "nav_msgs/msg/Odometry").unwrap();
    writer.finish().unwrap();
    let error = refused(&["two.mcap"]);
    assert!(
        error.contains("2 topics could be the DVL: /dvl/a, /dvl/b; name one with --dvl-topic"),
        "{error}"
    );
    // A DVL frame with no transform to base_link.
    let untied = RosLayout {
        dvl_frame: "sonar_head",
        ..RosLayout::default()
    };
    let layout_bag = dir.path().join("untied.mcap");
    write_recording(
        &recording,
        &layout_bag,
        Format::Mcap { compressed: false },
        untied,
    )
    .unwrap();
    let error = refused(&["untied.mcap", "--frame", "hull"]);
    assert!(
        error.contains("gives its twist in base_link, not in hull"),
        "{error}"
    );
    // Cut short: refused at a byte, not a panic.
    let bytes = std::fs::read(&bag).unwrap();
    std::fs::write(dir.path().join("cut.mcap"), &bytes[..bytes.len() / 2]).unwrap();
    let error = refused(&["cut.mcap"]);
    assert!(
        error.contains("cut.mcap: damaged or cut short at byte"),
        "{error}"
    );
    // data info lists what the bag holds and what is read.
    let output = dcnet(dir.path(), &["data", "info", "dive.mcap"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let info = stdout(&output);
    assert!(info.contains("a MCAP bag, 1 file, 801 messages"), "{info}");
    assert!(
        info.contains(
            "/ins/odom  nav_msgs/msg/Odometry  400 messages, 1.00 Hz  (read as a reference)"
        ),
        "{info}"
    );
    assert!(
        info.contains("/tf_static  tf2_msgs/msg/TFMessage  1 messages  (read for the DVL's frame)"),
        "{info}"
    );
}

/// An A-KIT segment written as a ROS 2 vehicle writes it, as MCAP and as sqlite3, with
/// every tenth ping sent as lost bottom lock: every term within one standard deviation
/// of the CSV fit's (two with the lost-lock pings).
#[test]
#[ignore = "needs the A-KIT recordings: dcnet-exp data fetch akit"]
fn an_akit_segment_as_a_bag_calibrates_to_the_csv_terms() {
    let akit = akit();
    let dir = tempfile::tempdir().unwrap();
    let files = PairedFiles {
        dvl: akit.join("Trajectory3/DVL_trajectory3.csv"),
        reference: akit.join("Trajectory3/GT_trajectory3.csv"),
    };
    let recording = paired::read(&files, &PairedColumns::akit()).unwrap();
    let csv = calibrate(
        dir.path(),
        &[
            csv_args(&files)
                .iter()
                .map(String::as_str)
                .collect::<Vec<_>>(),
            vec![TERMS, "--out", "csv"],
        ]
        .concat(),
    );
    for (name, format, lost, sigmas) in [
        ("akit.mcap", Format::Mcap { compressed: true }, None, 1.0),
        ("akit.db3", Format::Sqlite, None, 1.0),
        (
            "lost.mcap",
            Format::Mcap { compressed: true },
            Some(10),
            2.0,
        ),
    ] {
        let layout = RosLayout {
            lost_lock_every: lost,
            ..RosLayout::default()
        };
        write_recording(&recording, &dir.path().join(name), format, layout).unwrap();
        let out = format!("out-{name}");
        let text = calibrate(dir.path(), &[name, TERMS, "--out", &out]);
        let (bag, csv) = (terms(&text), terms(&csv));
        assert_eq!(bag.len(), csv.len(), "{text}");
        for ((term, bag, _), (_, csv, std)) in bag.iter().zip(&csv) {
            assert!(
                (bag - csv).abs() <= sigmas * std,
                "{name}: {term}: {bag} against {csv} ± {std}"
            );
        }
    }
}

/// A study whose recordings are bags gives the held-out scores (to 1e-6 cm/s) of the same study over
/// the CSV files; a bag key on a CSV recording is refused at its key.
#[test]
fn a_study_of_bags_scores_as_the_study_of_their_csv_files() {
    use crate::common::installed::write_study_spec;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    crate::common::installed::write_installed(&d.join("data/syn"), 3, &[], INSTALLED, 5);
    write_study_spec(d, "csv", "syn", 3, "");
    std::fs::create_dir_all(d.join("data/bags")).unwrap();
    let mut spec = std::fs::read_to_string(d.join("experiments/csv.toml"))
        .unwrap()
        .replace("name = \"csv\"", "name = \"bags\"");
    for n in 1..=3 {
        let folder = d.join(format!("data/syn/Trajectory{n}"));
        let files = PairedFiles {
            dvl: folder.join(format!("DVL_trajectory{n}.csv")),
            reference: folder.join(format!("GT_trajectory{n}.csv")),
        };
        let recording = paired::read(&files, &PairedColumns::akit()).unwrap();
        let bag = d.join(format!("data/bags/S{n}.mcap"));
        write_recording(
            &recording,
            &bag,
            Format::Mcap { compressed: true },
            RosLayout::default(),
        )
        .unwrap();
        spec = spec.replace(
            &format!("dvl = \"../data/syn/Trajectory{n}/DVL_trajectory{n}.csv\"\nreference = \"../data/syn/Trajectory{n}/GT_trajectory{n}.csv\""),
            &format!("dvl = \"../data/bags/S{n}.mcap\"\ndvl_topic = \"/dvl/data\""),
        );
    }
    std::fs::write(d.join("experiments/bags.toml"), &spec).unwrap();
    crate::common::studies_score_alike(d, "csv", "bags");
    let wrong = spec
        .replace(
            "dvl = \"../data/bags/S1.mcap\"",
            "dvl = \"../data/syn/Trajectory1/DVL_trajectory1.csv\"",
        )
        .replace("name = \"bags\"", "name = \"wrong\"");
    std::fs::write(d.join("experiments/wrong.toml"), wrong).unwrap();
    let output = dcnet(d, &["validate", "experiments/wrong.toml"]);
    assert!(!output.status.success());
    assert!(
        stderr(&output).contains("recordings.trajectories[0].dvl_topic"),
        "{}",
        stderr(&output)
    );
}

/// `calibrate` or `correct` as typed in `dir`, refused as bad input (exit 1): its error.
fn refused_in(dir: &Path, args: &[&str]) -> String {
    let output = dcnet(dir, args);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    stderr(&output)
}

/// A rosbag2 folder `name` in `dir` holding the synthetic recording in one MCAP file
/// named `file`.
fn bag_folder(dir: &Path, name: &str, file: &str) -> PathBuf {
    let files = synthetic(dir);
    let recording = paired::read(&files, &PairedColumns::akit()).unwrap();
    let folder = dir.join(name);
    std::fs::create_dir_all(&folder).unwrap();
    let data = folder.join(file);
    write_recording(
        &recording,
        &data,
        Format::Mcap { compressed: true },
        RosLayout::default(),
    )
    .unwrap();
    std::fs::write(
        folder.join("metadata.yaml"),
        format!("rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  relative_file_paths:\n    - {file}\n"),
    )
    .unwrap();
    data
}

/// No output replaces a file a bag is read from: `--save` over its data file or its
/// `metadata.yaml`, the URDF `--save` writes beside its file over a data file of that
/// name, and `correct`'s corrected bag over a data file of its name are each refused,
/// naming the file, and the recording is left as it was.
#[test]
fn a_bags_own_files_are_inputs_no_output_replaces() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let data = bag_folder(d, "dive", "dive.mcap");
    let recorded = std::fs::read(&data).unwrap();
    for save in ["dive/dive.mcap", "dive/./metadata.yaml"] {
        let error = refused_in(d, &["calibrate", "dive", TERMS, "--save", save]);
        assert!(
            error.contains("calibrate would write over its input"),
            "{error}"
        );
        assert!(error.contains("give another --save"), "{error}");
    }
    assert_eq!(std::fs::read(&data).unwrap(), recorded);
    assert!(
        std::fs::read_to_string(d.join("dive/metadata.yaml"))
            .unwrap()
            .contains("dive.mcap")
    );

    let data = bag_folder(d, "named", "inst.urdf");
    let recorded = std::fs::read(&data).unwrap();
    let error = refused_in(
        d,
        &["calibrate", "named", TERMS, "--save", "named/inst.toml"],
    );
    assert!(
        error.contains("named/inst.urdf: calibrate would write over its input named/inst.urdf: give another --save"),
        "{error}"
    );
    assert_eq!(std::fs::read(&data).unwrap(), recorded);
    assert!(!d.join("named/inst.toml").exists());

    calibrate(
        d,
        &["dive", TERMS, "--out", "calibrated", "--save", "inst.toml"],
    );
    let data = bag_folder(d, "again", "again-corrected.mcap");
    let recorded = std::fs::read(&data).unwrap();
    let error = refused_in(
        d,
        &[
            "correct",
            "again",
            "--installation",
            "inst.toml",
            "--out",
            "again",
        ],
    );
    assert!(
        error.contains("again/again-corrected.mcap: correct would write over its input again/again-corrected.mcap"),
        "{error}"
    );
    assert_eq!(std::fs::read(&data).unwrap(), recorded);
    assert!(!d.join("again/again-corrected.csv").exists());
}

/// The synthetic recording as a sqlite3 bag `dive.db3` in `dir`, its connection, and
/// the ids of its messages on `topic` in time order.
fn sqlite_bag(dir: &Path, layout: RosLayout) -> PathBuf {
    let files = synthetic(dir);
    let recording = paired::read(&files, &PairedColumns::akit()).unwrap();
    let path = dir.join("dive.db3");
    let _ = std::fs::remove_file(&path);
    write_recording(&recording, &path, Format::Sqlite, layout).unwrap();
    path
}

/// The id and receive stamp of the `n`th message (1 = the first) of `topic` in the
/// sqlite3 bag at `path`, and the topic's id.
fn nth_message(path: &Path, topic: &str, n: usize) -> (i64, i64, i64) {
    let connection = rusqlite::Connection::open(path).unwrap();
    let topic_id: i64 = connection
        .query_row("SELECT id FROM topics WHERE name = ?1", [topic], |row| {
            row.get(0)
        })
        .unwrap();
    let (id, stamp) = connection
        .query_row(
            "SELECT id, timestamp FROM messages WHERE topic_id = ?1 ORDER BY timestamp, id LIMIT 1 OFFSET ?2",
            [topic_id, n as i64 - 1],
            |row| Ok((row.get(0)?, row.get(1)?)),
        )
        .unwrap();
    (id, stamp, topic_id)
}

/// Runs `sql` with `params` on the sqlite3 bag at `path`.
fn edit(path: &Path, sql: &str, params: impl rusqlite::Params) {
    rusqlite::Connection::open(path)
        .unwrap()
        .execute(sql, params)
        .unwrap();
}

/// Adds to the sqlite3 bag at `path` a second `/tf_static` message of `transforms`, just
/// after its first.
fn another_tf_static(path: &Path, transforms: &[(&str, &str, [f64; 3], [f64; 4])]) {
    use dcnet_exp::data::paired::bag::write::tf_message;
    let (_, stamp, tf) = nth_message(path, "/tf_static", 1);
    edit(
        path,
        "INSERT INTO messages (topic_id, timestamp, data) VALUES (?1, ?2, ?3)",
        rusqlite::params![tf, stamp + 1, tf_message(stamp, transforms)],
    );
}

/// Every number read from a bag is checked where it is read, and named by its topic
/// and message: a `/tf_static` translation of NaN (which reached the URDF), a zero
/// quaternion in the reference, a receive stamp before 1970 (once read as 0), a DVL
/// whose frame changes, two `/tf_static` transforms that disagree; one topic given
/// both roles, a folder with no `metadata.yaml` and a ROS 1 bag are said as such. A
/// DVL that names no frame is read as the body's, and says so.
#[test]
fn a_bags_numbers_and_frames_are_checked_where_read() {
    use dcnet_exp::data::paired::bag::write::odometry_message;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let nan = RosLayout {
        mount_translation_m: [f64::NAN, 0.0, 0.0],
        ..RosLayout::default()
    };
    let bag = sqlite_bag(d, nan);
    let error = refused_in(
        d,
        &[
            "calibrate",
            bag.to_str().unwrap(),
            "--terms=time_offset,bias",
            "--save",
            "i.toml",
        ],
    );
    assert!(
        error.contains("/tf_static, message 1: the /tf_static transform from base_link to dvl_link: its translation (m) [NaN, 0.0, 0.0] is not a finite number"),
        "{error}"
    );
    assert!(!d.join("i.toml").exists() && !d.join("i.urdf").exists());

    let bag = sqlite_bag(d, RosLayout::default());
    let (id, stamp, _) = nth_message(&bag, "/ins/odom", 10);
    let zero = odometry_message(
        stamp,
        ("odom", "base_link"),
        ([0.0; 3], [0.0; 4]),
        [1.0, 0.0, 0.0],
        [0.0; 3],
    );
    edit(
        &bag,
        "UPDATE messages SET data = ?1 WHERE id = ?2",
        rusqlite::params![zero, id],
    );
    let error = refused_in(d, &["calibrate", "dive.db3", TERMS]);
    assert!(
        error.contains("/ins/odom, message 10: its orientation quaternion [0.0, 0.0, 0.0, 0.0] is zero, which is no rotation"),
        "{error}"
    );

    let bag = sqlite_bag(d, RosLayout::default());
    let (id, _, _) = nth_message(&bag, "/dvl/data", 5);
    edit(
        &bag,
        "UPDATE messages SET timestamp = -5 WHERE id = ?1",
        [id],
    );
    let error = refused_in(d, &["calibrate", "dive.db3", TERMS, "--stamps", "receive"]);
    assert!(
        error.contains("/dvl/data, message 1: its receive stamp is -5 ns, before 1970"),
        "{error}"
    );

    let bag = sqlite_bag(d, RosLayout::default());
    let (id, stamp, _) = nth_message(&bag, "/dvl/data", 7);
    let moved = dvl_message(
        stamp,
        "other_link",
        [1.0, 0.0, 0.0],
        DvlStatus::BOTTOM_LOCK,
        4e-4,
    );
    edit(
        &bag,
        "UPDATE messages SET data = ?1 WHERE id = ?2",
        rusqlite::params![moved, id],
    );
    let error = refused_in(d, &["calibrate", "dive.db3", TERMS]);
    assert!(
        error.contains("/dvl/data, message 7: its frame_id is \"other_link\" where its first message's is \"dvl_link\""),
        "{error}"
    );

    let bag = sqlite_bag(d, RosLayout::default());
    another_tf_static(
        &bag,
        &[
            ("base_link", "dvl_link", [0.0; 3], [1.0, 0.0, 0.0, 0.0]),
            (
                "base_link",
                "dvl_link",
                [0.2, 0.0, 0.0],
                [0.0, 0.0, 0.0, 1.0],
            ),
        ],
    );
    let error = refused_in(d, &["calibrate", "dive.db3", TERMS]);
    assert!(error.contains("/tf_static places a frame on the DVL's mount twice, otherwise: base_link → dvl_link at (0.0000, 0.0000, 0.0000) m, roll 180.000°"), "{error}");
    assert!(
        error.contains("base_link → dvl_link at (0.2000, 0.0000, 0.0000) m, roll 0.000°"),
        "{error}"
    );

    // Two that disagree off the DVL's mount (a camera's) change nothing read.
    let bag = sqlite_bag(d, RosLayout::default());
    another_tf_static(
        &bag,
        &[
            ("base_link", "camera", [0.1, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]),
            ("base_link", "camera", [0.3, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]),
        ],
    );
    calibrate(d, &["dive.db3", TERMS, "--out", "camera"]);

    let bag = sqlite_bag(d, RosLayout::default());
    let error = refused_in(
        d,
        &[
            "calibrate",
            bag.to_str().unwrap(),
            "--dvl-topic",
            "/ins/odom",
            "--reference-topic",
            "/ins/odom",
        ],
    );
    assert!(
        error.contains("--reference-topic: /ins/odom is also --dvl-topic"),
        "{error}"
    );

    std::fs::create_dir(d.join("lost")).unwrap();
    std::fs::copy(&bag, d.join("lost/lost_0.db3")).unwrap();
    let error = refused_in(d, &["calibrate", "lost"]);
    assert!(
        error.contains("lost: a folder with no metadata.yaml, so not a bag"),
        "{error}"
    );
    std::fs::write(d.join("old.bag"), b"#ROSBAG V2.0\n").unwrap();
    let error = refused_in(d, &["calibrate", "old.bag"]);
    assert!(
        error.contains("old.bag: a ROS 1 bag, which this tool does not read"),
        "{error}"
    );

    let nameless = RosLayout {
        dvl_frame: "",
        mount_roll_deg: 0.0,
        ..RosLayout::default()
    };
    sqlite_bag(d, nameless);
    let text = calibrate(d, &["dive.db3", TERMS, "--out", "nameless"]);
    assert!(
        text.contains(
            "in frame (none: its messages' frame_id is empty, so it is read as the body's)"
        ),
        "{text}"
    );
}
