//! Position fixes read from a bag's topic: a GNSS's or a USBL's
//! `sensor_msgs/msg/NavSatFix` (latitude and longitude carried to metres on the plane
//! tangent at the first fix, as a fixes file's are), or a pose in the world frame, a
//! `geometry_msgs/msg/PoseWithCovarianceStamped` or a `nav_msgs/msg/Odometry`'s (ENU,
//! or NED where the frame's name ends in `_ned`). Each fix's horizontal noise is read
//! from its covariance where it gives one (the mean of its east and north variances);
//! a NavSatFix without a fix (status −1) or without a horizontal position (not a
//! number) is left out and counted; the fixes have a depth where every one has an
//! altitude. The stamps are those of the recording the fixes go with.
//! In: the bag, the topic, the stamps and the frames of the DVL's reading. Out:
//! [`BagFixes`].

use super::cdr::{Value, decode};
use super::definitions::Definitions;
use super::frames::{frame_name, world_is_ned};
use super::storage::Bag;
use super::values::stamp_ns;
use super::{BagError, BagTopics, Stamps};
use crate::data::local_plane::{north_east_m, off_the_globe};
use crate::data::paired::{PairedError, ReadRecording};
use crate::data::position_fixes::Fixes;
use std::path::Path;

/// The fixes of a bag's topic, and those left out.
#[derive(Debug, Clone, PartialEq)]
pub struct BagFixes {
    /// Their `lines` are the messages' places in the topic (1 for the first).
    pub fixes: Fixes,
    pub topic: String,
    pub type_name: String,
    /// Messages left out: a NavSatFix with no fix (status −1), or a latitude and
    /// longitude (x and y) that is not a number.
    pub no_fix: usize,
    pub not_a_number: usize,
    /// Fixes read that carry no covariance.
    pub without_covariance: usize,
}

/// Where a type keeps a fix.
#[derive(Debug, Clone)]
enum Layout {
    /// A NavSatFix's: its status, latitude, longitude, altitude, covariance and the
    /// covariance's type.
    Geographic {
        status: Vec<usize>,
        position: [Vec<usize>; 3],
        covariance: Vec<usize>,
        covariance_type: Vec<usize>,
    },
    /// A pose's position, x, y, z, and its 6 × 6 covariance.
    Pose {
        position: [Vec<usize>; 3],
        covariance: Vec<usize>,
    },
}

/// The types a fixes topic may be, in words.
const FIX_TYPES: &str = "sensor_msgs/msg/NavSatFix, geometry_msgs/msg/PoseWithCovarianceStamped or nav_msgs/msg/Odometry (or a type with their fields)";

/// Where `type_name` keeps a fix, where it is a type fixes are read from.
fn layout(type_name: &str, definitions: &Definitions) -> Option<Layout> {
    let path = |p: &str| definitions.path(type_name, p).map(|(indices, _)| indices);
    path("header.stamp.sec")?;
    if let (Some(status), Some(latitude)) = (path("status.status"), path("latitude")) {
        return Some(Layout::Geographic {
            status,
            position: [latitude, path("longitude")?, path("altitude")?],
            covariance: path("position_covariance")?,
            covariance_type: path("position_covariance_type")?,
        });
    }
    Some(Layout::Pose {
        position: [
            path("pose.pose.position.x")?,
            path("pose.pose.position.y")?,
            path("pose.pose.position.z")?,
        ],
        covariance: path("pose.covariance")?,
    })
}

/// One message's fix as read: its stamp, ns; its position (latitude and longitude,
/// degrees, and altitude, m; or x, y, z in the world frame, m); its horizontal
/// variance, m², where its covariance gives one.
struct Read {
    stamp_ns: i64,
    message: u64,
    position: [f64; 3],
    variance_m2: Option<f64>,
}

/// What one message gives: a fix, or why it is left out.
enum Message {
    Fix(Read),
    NoFix,
    NotANumber,
}

/// The fixes of `topic` in the bag at `path`, on `stamps`, in seconds from the whole
/// second `origin_s` since the epoch (that of the DVL's reading, [`super::BagFrames`]).
pub fn read_fix_topic(
    path: &Path,
    topic: &str,
    stamps: Stamps,
    origin_s: i64,
) -> Result<BagFixes, BagError> {
    let bag = Bag::open(path)?;
    let survey = bag.counts()?;
    let refused = |problem: String| BagError::Topic {
        path: path.to_path_buf(),
        problem,
        topics: super::topic_lines(&survey),
    };
    let Some(found) = survey.topics.iter().find(|t| t.name == topic) else {
        return Err(refused(format!(
            "--fixes-topic: no topic {topic} in the bag"
        )));
    };
    if layout(&found.type_name, &survey.definitions).is_none() {
        return Err(refused(format!(
            "--fixes-topic: {topic} is {}, not a type fixes are read from: {FIX_TYPES}",
            found.type_name
        )));
    }
    let mut read = Vec::new();
    let (mut no_fix, mut not_a_number, mut world) = (0, 0, None);
    let wanted = topic.to_string();
    bag.stream(
        &move |name, _, _| name == wanted,
        &mut |topic, definitions, receive_ns, data| {
            let fault = |problem: String| BagError::Message {
                path: path.to_path_buf(),
                topic: topic.name.clone(),
                message: topic.count,
                problem,
            };
            let value =
                decode(data, &topic.type_name, definitions).map_err(|e| fault(e.to_string()))?;
            let layout = layout(&topic.type_name, definitions).expect("a fixes type");
            let stamp_ns =
                stamp(&value, definitions, &topic.type_name, receive_ns, stamps).map_err(fault)?;
            if world.is_none() {
                world = (definitions.path(&topic.type_name, "header.frame_id"))
                    .and_then(|(p, _)| value.at(&p)?.text().map(|f| frame_name(f).to_string()));
            }
            match message(&value, &layout).map_err(fault)? {
                Message::Fix(fix) => read.push(Read {
                    stamp_ns,
                    message: topic.count,
                    ..fix
                }),
                Message::NoFix => no_fix += 1,
                Message::NotANumber => not_a_number += 1,
            }
            Ok(())
        },
    )?;
    let geographic = matches!(
        layout(&found.type_name, &survey.definitions),
        Some(Layout::Geographic { .. })
    );
    let fixes = fixes_of(path, topic, &read, origin_s, (geographic, world.as_deref()))?;
    Ok(BagFixes {
        without_covariance: read.iter().filter(|r| r.variance_m2.is_none()).count(),
        fixes,
        topic: topic.to_string(),
        type_name: found.type_name.clone(),
        no_fix,
        not_a_number,
    })
}

/// The DVL of the bag at `path` beside its reference's attitude, read as `topics`
/// says (no velocity is read from the reference), and the fixes of its topic
/// `fix_topic`, on the DVL's clock.
pub fn read_bag_beside_attitude(
    path: &Path,
    topics: &BagTopics,
    fix_topic: &str,
) -> Result<(ReadRecording, BagFixes), PairedError> {
    let read = crate::data::paired::read_bag_without_velocity(path, topics)?;
    let frames = read
        .frames
        .as_ref()
        .expect("a bag's reading has its frames");
    let fixes = read_fix_topic(path, fix_topic, topics.stamps, frames.origin_s)?;
    Ok((read, fixes))
}

/// The stamp of the message `value` of `type_name`, ns: its header's or its
/// recording's, as `stamps` says.
fn stamp(
    value: &Value,
    definitions: &Definitions,
    type_name: &str,
    receive_ns: u64,
    stamps: Stamps,
) -> Result<i64, String> {
    let field = |p: &str| {
        (definitions.path(type_name, p))
            .and_then(|(indices, _)| value.at(&indices)?.number())
            .ok_or_else(|| format!("its {p} is missing or not a number"))
    };
    let header = [field("header.stamp.sec")?, field("header.stamp.nanosec")?];
    stamp_ns(header, receive_ns, stamps)
}

/// The fix of one message `value` laid out as `layout`.
fn message(value: &Value, layout: &Layout) -> Result<Message, String> {
    let missing = |what: &str| format!("its {what} is missing or not a number");
    let number = |path: &[usize], what: &str| {
        (value.at(path).and_then(Value::number)).ok_or_else(|| missing(what))
    };
    let element = |path: &[usize], k: usize, what: &str| {
        let mut at = path.to_vec();
        at.push(k);
        number(&at, what)
    };
    let triple = |paths: &[Vec<usize>; 3]| -> Result<[f64; 3], String> {
        Ok([
            number(&paths[0], "position")?,
            number(&paths[1], "position")?,
            number(&paths[2], "position")?,
        ])
    };
    let (position, variance_m2) = match layout {
        Layout::Geographic {
            status,
            position,
            covariance,
            covariance_type,
        } => {
            if number(status, "status")? < 0.0 {
                return Ok(Message::NoFix);
            }
            let position = triple(position)?;
            if !horizontal_finite(&position) {
                return Ok(Message::NotANumber);
            }
            let known = number(covariance_type, "position_covariance_type")? > 0.0;
            let variance = match known {
                true => Some(horizontal_variance(
                    element(covariance, 0, "position_covariance")?,
                    element(covariance, 4, "position_covariance")?,
                    "position_covariance (east, north)",
                )?),
                false => None,
            };
            (position, variance)
        }
        Layout::Pose {
            position,
            covariance,
        } => {
            let position = triple(position)?;
            if !horizontal_finite(&position) {
                return Ok(Message::NotANumber);
            }
            let (x, y) = (
                element(covariance, 0, "pose.covariance")?,
                element(covariance, 7, "pose.covariance")?,
            );
            // A pose's covariance of zeros is one its source did not give.
            let variance = match x == 0.0 && y == 0.0 {
                true => None,
                false => Some(horizontal_variance(x, y, "pose.covariance (x, y)")?),
            };
            (position, variance)
        }
    };
    Ok(Message::Fix(Read {
        stamp_ns: 0,
        message: 0,
        position,
        variance_m2,
    }))
}

/// Whether a fix's horizontal position (latitude and longitude, or x and y) is a
/// number: its altitude may not be (a NavSatFix without one), and is then no depth.
fn horizontal_finite(position: &[f64; 3]) -> bool {
    position[0].is_finite() && position[1].is_finite()
}

/// The mean of a fix's two horizontal variances, m², each a positive number.
fn horizontal_variance(first: f64, second: f64, what: &str) -> Result<f64, String> {
    match first.is_finite() && second.is_finite() && first > 0.0 && second > 0.0 {
        true => Ok(0.5 * (first + second)),
        false => Err(format!(
            "its {what} variances are {first} and {second} m²: a variance is a positive number"
        )),
    }
}

/// The fixes `read`, in metres north and east (and depth, down), their times in
/// seconds from `origin_s`, their stamps increasing; `geographic` where they are
/// latitude and longitude, in the world frame `world` otherwise.
fn fixes_of(
    path: &Path,
    topic: &str,
    read: &[Read],
    origin_s: i64,
    (geographic, world): (bool, Option<&str>),
) -> Result<Fixes, BagError> {
    let fault = |message: u64, problem: String| BagError::Message {
        path: path.to_path_buf(),
        topic: topic.to_string(),
        message,
        problem,
    };
    for pair in read.windows(2) {
        if pair[1].stamp_ns <= pair[0].stamp_ns {
            return Err(fault(
                pair[1].message,
                format!(
                    "its stamp is not after that of message {} before it: fixes are read in the order of their times",
                    pair[0].message
                ),
            ));
        }
    }
    let (north_east, depth_m): (Vec<[f64; 2]>, Vec<f64>) = match geographic {
        true => {
            let degrees: Vec<[f64; 2]> = read
                .iter()
                .map(|r| [r.position[0], r.position[1]])
                .collect();
            if let Some((k, axis)) = off_the_globe(&degrees, true) {
                let what = ["latitude", "longitude"][axis];
                return Err(fault(
                    read[k].message,
                    format!("its {what} {}° lies off the globe", degrees[k][axis]),
                ));
            }
            let radians: Vec<[f64; 2]> = degrees.iter().map(|p| p.map(f64::to_radians)).collect();
            let origin = radians.first().copied().unwrap_or_default();
            let depth = read.iter().map(|r| -r.position[2]).collect();
            (north_east_m(origin, &radians), depth)
        }
        false => {
            let ned = world.is_some_and(world_is_ned);
            read.iter()
                .map(|r| {
                    let [x, y, z] = r.position;
                    match ned {
                        true => ([x, y], z),
                        false => ([y, x], -z),
                    }
                })
                .unzip()
        }
    };
    let noise_m = (read.iter())
        .map(|r| r.variance_m2.map(f64::sqrt))
        .collect::<Option<Vec<f64>>>();
    // The depth where every fix has one.
    let depth_m = depth_m.iter().all(|d| d.is_finite()).then_some(depth_m);
    Ok(Fixes {
        lines: read.iter().map(|r| r.message).collect(),
        time_s: (read.iter())
            .map(|r| (r.stamp_ns - origin_s * 1_000_000_000) as f64 / 1e9)
            .collect(),
        north_east_m: north_east,
        depth_m,
        noise_m,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::paired::bag::write::{
        BagWriter, Format, nav_sat_fix_message, odometry_message, pose_with_covariance_message,
    };

    /// A bag at `path` of NavSatFix messages on `/fix`, each its stamp, s, status,
    /// position and variance.
    fn bag(path: &Path, messages: &[(f64, i8, [f64; 3], Option<[f64; 2]>)]) {
        let mut bag = BagWriter::create(path, Format::Mcap { compressed: false }).unwrap();
        bag.topic("/fix", "sensor_msgs/msg/NavSatFix").unwrap();
        for &(t, status, position, variance) in messages {
            let stamp = (t * 1e9) as i64;
            let data = nav_sat_fix_message(stamp, "gps", status, position, variance);
            bag.write("/fix", stamp as u64, &data).unwrap();
        }
        bag.finish().unwrap();
    }

    /// Fixes without a fix or a number are counted and left out, the rest carried to
    /// metres with their noise; a stamp that goes back, a position off the globe and a
    /// variance that is no variance refused at their message.
    #[test]
    fn a_navsatfix_topic_reads_its_fixes_and_counts_those_left_out() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("fixes.mcap");
        let good = |t: f64, north_m: f64| {
            let latitude = 45.0 + north_m / 111_132.0;
            (t, 0, [latitude, 7.0, -3.0], Some([0.25, 1.0]))
        };
        bag(
            &path,
            &[
                good(100.0, 0.0),
                (101.0, -1, [0.0, 0.0, 0.0], None),
                good(102.0, 10.0),
                (103.0, 0, [f64::NAN, 7.0, 0.0], Some([f64::NAN, 1.0])),
                good(104.0, 20.0),
            ],
        );
        let read = read_fix_topic(&path, "/fix", Stamps::Header, 90).unwrap();
        assert_eq!(
            (read.no_fix, read.not_a_number, read.without_covariance),
            (1, 1, 0)
        );
        let fixes = &read.fixes;
        assert_eq!(fixes.lines, [1, 3, 5]);
        assert_eq!(fixes.time_s, [10.0, 12.0, 14.0]);
        assert!((fixes.north_east_m[2][0] - 20.0).abs() < 0.05, "{fixes:?}");
        assert!(fixes.north_east_m[2][1].abs() < 1e-9);
        assert_eq!(fixes.noise_m, Some(vec![0.5; 3]));
        assert_eq!(fixes.depth_m, Some(vec![3.0; 3]));
        let refused = |messages: &[(f64, i8, [f64; 3], Option<[f64; 2]>)], expected: &str| {
            bag(&path, messages);
            let fault = read_fix_topic(&path, "/fix", Stamps::Header, 90).unwrap_err();
            assert!(fault.to_string().contains(expected), "{fault}");
        };
        // An altitude that is not a number: the fixes stand, with no depth.
        bag(
            &path,
            &[good(100.0, 0.0), (101.0, 0, [45.0, 7.0, f64::NAN], None)],
        );
        let read = read_fix_topic(&path, "/fix", Stamps::Header, 90).unwrap();
        assert_eq!((read.fixes.len(), read.not_a_number), (2, 0));
        assert_eq!(read.fixes.depth_m, None);
        refused(
            &[good(100.0, 0.0), good(99.0, 1.0)],
            "/fix, message 2: its stamp is not after",
        );
        refused(
            &[good(100.0, 0.0), (101.0, 0, [95.0, 7.0, 0.0], None)],
            "/fix, message 2: its latitude 95° lies off the globe",
        );
        refused(
            &[(100.0, 0, [45.0, 7.0, 0.0], Some([-1.0, 1.0]))],
            "/fix, message 1: its position_covariance (east, north) variances are -1 and -1 m²",
        );
    }

    /// A pose's position is read in its world frame: ENU (`map`: x east, y north, z up)
    /// or NED (`map_ned`), carried to north, east and down; a covariance of zeros is
    /// none, and counted; with `Stamps::Receive` a fix's time is its recording's, not
    /// its header's.
    #[test]
    fn a_pose_topic_reads_its_fixes_in_its_world_frame_on_either_stamp() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("poses.mcap");
        let poses = |world: &str| {
            let mut bag = BagWriter::create(&path, Format::Mcap { compressed: false }).unwrap();
            bag.topic("/usbl", "geometry_msgs/msg/PoseWithCovarianceStamped")
                .unwrap();
            for (k, variance) in [Some(4.0), None, Some(1.0)].into_iter().enumerate() {
                let header_ns = (100 + k as i64) * 1_000_000_000;
                let position = [1.0 + k as f64, 2.0, 3.0];
                let data = pose_with_covariance_message(header_ns, world, position, variance);
                // Received half a second after its stamp.
                bag.write("/usbl", header_ns as u64 + 500_000_000, &data)
                    .unwrap();
            }
            bag.finish().unwrap();
        };
        poses("map");
        let read = read_fix_topic(&path, "/usbl", Stamps::Header, 90).unwrap();
        assert_eq!(read.without_covariance, 1);
        assert_eq!(read.fixes.time_s, [10.0, 11.0, 12.0]);
        // ENU: north is y, east is x, down is −z.
        assert_eq!(read.fixes.north_east_m[1], [2.0, 2.0]);
        assert_eq!(read.fixes.north_east_m[2], [2.0, 3.0]);
        assert_eq!(read.fixes.depth_m, Some(vec![-3.0; 3]));
        // Without every fix's covariance, none carries its own noise.
        assert_eq!(read.fixes.noise_m, None);
        let read = read_fix_topic(&path, "/usbl", Stamps::Receive, 90).unwrap();
        assert_eq!(read.fixes.time_s, [10.5, 11.5, 12.5]);
        poses("/map_ned");
        let read = read_fix_topic(&path, "/usbl", Stamps::Header, 90).unwrap();
        // NED: north is x, east is y, down is z.
        assert_eq!(read.fixes.north_east_m[2], [3.0, 2.0]);
        assert_eq!(read.fixes.depth_m, Some(vec![3.0; 3]));
    }

    /// An odometry's pose is a fix as a pose's is (in `odom`, ENU), its twist not read;
    /// its covariance of zeros is none.
    #[test]
    fn an_odometry_topic_gives_its_pose_as_fixes() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("odometry.mcap");
        let mut bag = BagWriter::create(&path, Format::Mcap { compressed: false }).unwrap();
        bag.topic("/odom", "nav_msgs/msg/Odometry").unwrap();
        for k in 0..3 {
            let stamp_ns = (100 + k) * 1_000_000_000;
            let pose = ([10.0 * k as f64, -5.0, -2.0], [0.0, 0.0, 0.0, 1.0]);
            let data = odometry_message(stamp_ns, ("odom", "base_link"), pose, [1.0; 3], [0.0; 3]);
            bag.write("/odom", stamp_ns as u64, &data).unwrap();
        }
        bag.finish().unwrap();
        let read = read_fix_topic(&path, "/odom", Stamps::Header, 100).unwrap();
        assert_eq!(read.type_name, "nav_msgs/msg/Odometry");
        assert_eq!((read.fixes.len(), read.without_covariance), (3, 3));
        assert_eq!(read.fixes.time_s, [0.0, 1.0, 2.0]);
        assert_eq!(read.fixes.north_east_m[2], [-5.0, 20.0]);
        assert_eq!(read.fixes.depth_m, Some(vec![2.0; 3]));
        assert_eq!(read.fixes.noise_m, None);
    }
}
