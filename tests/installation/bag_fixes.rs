//! Position fixes from a ROS 2 bag: a dive written as a vehicle with a USBL records it
//! (the DVL, an odometry for the attitude, the fixes as `sensor_msgs/msg/NavSatFix`
//! with their covariances, or as `geometry_msgs/msg/PoseWithCovarianceStamped`)
//! calibrates with `--fixes-topic` to what the same fixes give as a CSV file, the
//! messages without a fix left out and counted; the installation carried to another
//! dive's bag finds its clock again; what does not apply refused by name.

use crate::common::{self, installed};
use crate::fixes::{FIX_TRUTH, number_after, positions, refused_naming, write_fixes};
use dcnet_exp::data::paired::PairedFiles;
use dcnet_exp::data::paired::bag::write::{
    Format, OtherTopic, RosLayout, nav_sat_fix_message, pose_with_covariance_message,
    write_recording,
};
use dcnet_exp::operator::installation_file::SavedInstallation;
use rand::SeedableRng;
use rand_distr::Distribution;
use std::path::{Path, PathBuf};

/// Where the fixes of the bags written lie: latitude and longitude of the first, deg.
const ORIGIN_DEG: [f64; 2] = [43.25, 5.37];

/// The fixes' noise per horizontal axis the bags' covariances give, m.
const FIX_NOISE_M: f64 = 0.5;

/// How a bag's fixes are written.
#[derive(Clone, Copy, PartialEq)]
enum Written {
    /// NavSatFix with its covariance, and a message without a fix (status −1, a
    /// position of nothing) after every tenth.
    NavSatFix,
    /// NavSatFix whose covariance is unknown.
    NavSatFixNoCovariance,
    /// PoseWithCovarianceStamped in the ENU `map` frame.
    Pose,
    /// NavSatFix with its covariance, every tenth fix of 2 m noise and the others of
    /// 5 cm (an RTK GNSS that loses its fix now and then), each drawn with its noise.
    Mixed,
}

/// Latitude and longitude, degrees, of the point `north_east_m` from [`ORIGIN_DEG`] on
/// the WGS-84 plane tangent there (the inverse of the tool's local plane).
fn latitude_longitude([north, east]: [f64; 2]) -> [f64; 2] {
    let (a, e2) = (6_378_137.0, 6.694_379_990_14e-3);
    let latitude = ORIGIN_DEG[0].to_radians();
    let curvature = 1.0 - e2 * latitude.sin().powi(2);
    let meridian_m = a * (1.0 - e2) / curvature.powf(1.5);
    let prime_vertical_m = a / curvature.sqrt();
    [
        ORIGIN_DEG[0] + (north / meridian_m).to_degrees(),
        ORIGIN_DEG[1] + (east / (prime_vertical_m * latitude.cos())).to_degrees(),
    ]
}

/// A dive written by `common::installed` under `truth` into `folder`, as a bag
/// (`dive.mcap`) with its reference's positions every 5 s as fixes on `/usbl/fix`
/// written as `written`, and as a CSV fixes file beside it (`fixes.csv`, north and
/// east): the bag's path and the CSV recording's DVL, attitude and fixes paths.
fn bag_dive(folder: &Path, truth: installed::Installed, seed: u64, written: Written) -> PathBuf {
    installed::write_installed(folder, 1, &[], truth, seed);
    let files = [PairedFiles::akit(folder, 1)];
    let segment = &crate::coverage::segments(&files)[0];
    write_fixes(&folder.join("fixes.csv"), segment, 5);
    let layout = RosLayout::default();
    let stamp = |t: f64| layout.epoch_s * 1_000_000_000 + (t * 1e9).round() as i64;
    let variance = FIX_NOISE_M * FIX_NOISE_M;
    let mut messages = Vec::new();
    let time_s = &segment.recording.reference_time_s;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let unit = rand_distr::Normal::new(0.0, 1.0).unwrap();
    for (k, (i, &[north, east])) in positions(segment).iter().enumerate().step_by(5).enumerate() {
        let at = stamp(time_s[i]);
        let noise_m = if k % 10 == 4 { 5.0 } else { 0.02 };
        let (north, east) = match written {
            Written::Mixed => (
                north + noise_m * unit.sample(&mut rng),
                east + noise_m * unit.sample(&mut rng),
            ),
            _ => (north, east),
        };
        let [latitude, longitude] = latitude_longitude([north, east]);
        messages.push(match written {
            Written::NavSatFix => (
                at,
                nav_sat_fix_message(
                    at,
                    "usbl",
                    0,
                    [latitude, longitude, -5.0],
                    Some([variance, 1.0]),
                ),
            ),
            Written::Mixed => (
                at,
                nav_sat_fix_message(
                    at,
                    "usbl",
                    0,
                    [latitude, longitude, -5.0],
                    Some([noise_m * noise_m, 1.0]),
                ),
            ),
            Written::NavSatFixNoCovariance => (
                at,
                nav_sat_fix_message(at, "usbl", 0, [latitude, longitude, -5.0], None),
            ),
            Written::Pose => (
                at,
                pose_with_covariance_message(at, "map", [east, north, -5.0], Some(variance)),
            ),
        });
        if written == Written::NavSatFix && k % 10 == 9 {
            let later = at + 2_500_000_000;
            let none = nav_sat_fix_message(later, "usbl", -1, [0.0, 0.0, 0.0], None);
            messages.push((later, none));
        }
    }
    let type_name = match written {
        Written::Pose => "geometry_msgs/msg/PoseWithCovarianceStamped",
        _ => "sensor_msgs/msg/NavSatFix",
    };
    let topics = [OtherTopic {
        name: "/usbl/fix",
        type_name,
        messages: &messages,
    }];
    let bag = folder.join("dive.mcap");
    let layout = RosLayout {
        other_topics: &topics,
        ..layout
    };
    write_recording(
        &segment.recording,
        &bag,
        Format::Mcap { compressed: true },
        layout,
    )
    .unwrap();
    bag
}

/// The installation `dcnet-exp` saved to `file` in `dir` after `args`, and what it
/// printed.
fn saved_after(dir: &Path, args: &[&str], file: &str) -> (SavedInstallation, String) {
    let output = common::dcnet(dir, args);
    assert!(
        output.status.success(),
        "{args:?}: {}",
        common::stderr(&output)
    );
    let saved = SavedInstallation::read(&dir.join(file)).unwrap();
    (saved, common::stdout(&output))
}

/// Each saved term's value and standard deviation, by name.
fn values(saved: &SavedInstallation) -> Vec<(String, f64, f64)> {
    (saved.terms.iter())
        .map(|term| (term.name.clone(), term.value, term.std))
        .collect()
}

/// `calibrate --fixes-topic` on a bag whose NavSatFix fixes carry their covariances
/// gives the terms the same fixes give as a CSV file with their noise given, the
/// messages without a fix counted; PoseWithCovarianceStamped fixes give them too.
#[test]
fn fixes_from_a_bags_topic_calibrate_as_the_same_fixes_from_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bag = bag_dive(&d.join("navsat"), FIX_TRUTH, 1, Written::NavSatFix);
    let bag = bag.to_str().unwrap();
    let (read_from, stdout) = saved_after(
        d,
        &[
            "calibrate",
            bag,
            "--fixes-topic",
            "/usbl/fix",
            "--save",
            "bag.toml",
            "--out",
            "bag",
        ],
        "bag.toml",
    );
    assert!(
        stdout.contains("80 fixes (8 more left out: no fix (NavSatFix status −1))"),
        "{stdout}"
    );
    assert!(
        stdout.contains("each of its own covariance, median 0.50 m per axis"),
        "{stdout}"
    );
    assert!(
        stdout.contains("the fixes from /usbl/fix (sensor_msgs/msg/NavSatFix)"),
        "{stdout}"
    );
    let folder = d.join("navsat/Trajectory1");
    let [dvl, attitude] = ["DVL_trajectory1.csv", "GT_trajectory1.csv"]
        .map(|f| folder.join(f).to_str().unwrap().to_string());
    std::fs::write(
        d.join("columns.toml"),
        "[fix_columns]\ntime = \"t\"\nnorth_east = [\"n\", \"e\"]\n",
    )
    .unwrap();
    let fixes = d.join("navsat/fixes.csv");
    let (from_file, _) = saved_after(
        d,
        &[
            "calibrate",
            &dvl,
            "--fixes",
            fixes.to_str().unwrap(),
            "--attitude",
            &attitude,
            "--columns",
            "columns.toml",
            "--fix-noise-m",
            "0.5",
            "--save",
            "file.toml",
            "--out",
            "file",
        ],
        "file.toml",
    );
    // The same fixes and noise: the same terms, but for the bag's nanosecond stamps
    // and the latitude and longitude's round trip (millimetres).
    let close = |bag: &[(String, f64, f64)], file: &[(String, f64, f64)]| {
        assert_eq!(bag.len(), file.len());
        for ((name, value, std), (_, expected, expected_std)) in bag.iter().zip(file) {
            assert!(
                (value - expected).abs() <= 0.05 * expected_std.min(1.0) + 1e-6,
                "{name}: {value} from the bag, {expected} ± {expected_std} from the file"
            );
            let same_std = match expected_std.is_finite() {
                true => (std / expected_std - 1.0).abs() < 0.02,
                false => *std == *expected_std,
            };
            assert!(same_std, "{name}: {std} against {expected_std}");
        }
    };
    close(&values(&read_from), &values(&from_file));
    assert!(
        (read_from.installation().time_offset_s - FIX_TRUTH.time_offset_s).abs() < 0.15,
        "{:?}",
        read_from.installation()
    );
    // The same fixes as poses in ENU.
    let bag = bag_dive(&d.join("pose"), FIX_TRUTH, 1, Written::Pose);
    let (from_pose, stdout) = saved_after(
        d,
        &[
            "calibrate",
            bag.to_str().unwrap(),
            "--fixes-topic",
            "/usbl/fix",
            "--save",
            "pose.toml",
            "--out",
            "pose",
        ],
        "pose.toml",
    );
    assert!(stdout.contains("; 80 fixes, "), "{stdout}");
    close(&values(&from_pose), &values(&from_file));
}

/// `correct --fixes-topic`: the installation a bag's fixes gave, carried to another
/// dive's bag whose clock is 0.8 s later, finds that clock again from its fixes and
/// writes the dive corrected; a bag whose fixes carry no covariance needs
/// `--fix-noise-m`; what does not apply refused by name, exit 1.
#[test]
fn a_bags_installation_carries_to_the_next_dives_bag_and_bad_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let first = bag_dive(&d.join("first"), FIX_TRUTH, 1, Written::NavSatFix);
    let (saved, _) = saved_after(
        d,
        &[
            "calibrate",
            first.to_str().unwrap(),
            "--fixes-topic",
            "/usbl/fix",
            "--save",
            "fixes.toml",
        ],
        "fixes.toml",
    );
    let later = installed::Installed {
        time_offset_s: 1.8,
        ..FIX_TRUTH
    };
    let second = bag_dive(&d.join("second"), later, 2, Written::NavSatFixNoCovariance);
    let second = second.to_str().unwrap();
    let correct = |extra: &[&str]| {
        let mut args = vec!["correct", second, "--installation", "fixes.toml"];
        args.extend(extra);
        common::dcnet(d, &args)
    };
    let output = correct(&["--fixes-topic", "/usbl/fix", "--fix-noise-m", "0.5"]);
    assert!(output.status.success(), "{}", common::stderr(&output));
    let stdout = common::stdout(&output);
    let found = number_after(&stdout, "the time offset at ");
    let carried = saved.installation().time_offset_s;
    assert!(
        (found - carried - 0.8).abs() < 0.1,
        "found {found} s, carried {carried} s: {stdout}"
    );
    assert!(
        stdout.contains("white fixes of 0.50 m per axis"),
        "{stdout}"
    );
    let corrected = std::fs::read_to_string(d.join("corrected/dive-corrected.csv")).unwrap();
    assert_eq!(
        corrected.lines().count(),
        401,
        "a row per DVL sample and a header"
    );
    let refused = |extra: &[&str], expected: &str| refused_naming(&correct(extra), expected, extra);
    refused(
        &["--fixes-topic", "/usbl/fix", "--out", "none"],
        "--fixes-topic /usbl/fix: give the fixes' noise per horizontal axis with --fix-noise-m (metres): 80 of its 80 fixes carry no covariance",
    );
    refused(
        &[
            "--fixes-topic",
            "/usbl/nothing",
            "--fix-noise-m",
            "0.5",
            "--out",
            "none",
        ],
        "--fixes-topic: no topic /usbl/nothing in the bag",
    );
    refused(
        &[
            "--fixes-topic",
            "/dvl/data",
            "--fix-noise-m",
            "0.5",
            "--out",
            "none",
        ],
        "--fixes-topic: /dvl/data is marine_acoustic_msgs/msg/Dvl, not a type fixes are read from",
    );
    refused(
        &[
            "--fixes-topic",
            "/usbl/fix",
            "--attitude",
            "a.csv",
            "--out",
            "none",
        ],
        "--attitude: with --fixes-topic the attitude is the bag's own",
    );
    refused(
        &[
            "--fixes-topic",
            "/usbl/fix",
            "--fixes",
            "f.csv",
            "--out",
            "none",
        ],
        "fixes come from a file (--fixes) or from a bag's topic (--fixes-topic): give one",
    );
    assert!(!d.join("none").exists());
    // A CSV recording has no topics.
    let csv = d.join("second/Trajectory1/DVL_trajectory1.csv");
    let output = common::dcnet(
        d,
        &[
            "calibrate",
            csv.to_str().unwrap(),
            "--fixes-topic",
            "/usbl/fix",
            "--fix-noise-m",
            "0.5",
        ],
    );
    refused_naming(
        &output,
        "DVL_trajectory1.csv: --fixes-topic: not a bag",
        &["--fixes-topic on a CSV file"],
    );
    // A bag's fixes are not a file's.
    let fixes = d.join("second/fixes.csv");
    let attitude = d.join("second/Trajectory1/GT_trajectory1.csv");
    let output = correct(&[
        "--fixes",
        fixes.to_str().unwrap(),
        "--attitude",
        attitude.to_str().unwrap(),
        "--fix-noise-m",
        "0.5",
    ]);
    refused_naming(
        &output,
        "dive.mcap: --fixes: a bag's fixes are read from its own topic with --fixes-topic",
        &["--fixes beside a bag"],
    );
}

/// Fixes of centimetres with one in ten of metres, each its covariance: each is judged
/// by its own noise, so none of the metre fixes is taken for gross (measured against
/// the centimetres, 8 of them were left out as outliers) and the terms are the truth's.
#[test]
fn fixes_of_mixed_noise_are_each_judged_by_their_own() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A DVL installed as the vehicle's frame: the dead reckoning with no terms is
    // already near the track, and the fixes' own noise is what the jumps show.
    let truth = installed::Installed {
        scale: 0.0,
        lever_arm_m: [0.0; 3],
        time_offset_s: 0.0,
        ..FIX_TRUTH
    };
    let bag = bag_dive(&d.join("mixed"), truth, 3, Written::Mixed);
    let (saved, stdout) = saved_after(
        d,
        &[
            "calibrate",
            bag.to_str().unwrap(),
            "--fixes-topic",
            "/usbl/fix",
            "--save",
            "mixed.toml",
        ],
        "mixed.toml",
    );
    assert!(stdout.contains(", 0 outliers beyond Tukey's"), "{stdout}");
    assert!(stdout.contains("median 0.02 m per axis"), "{stdout}");
    let found = saved.installation();
    assert!(found.time_offset_s.abs() < 0.15, "{found:?}");
    assert!(found.lever_arm_m[0].abs() < 0.1, "{found:?}");
}
