//! A bag's DVL and reference topics read into samples: one pass over the bag decodes
//! the messages of every topic that could be the DVL, the reference or `/tf_static`
//! (by the fields of its type), then the topics asked for (or the only one of a kind)
//! are chosen, and their samples carried into north-east-down and forward-right-down
//! (`frames.rs`).
//! In: a bag's path and the [`BagTopics`]. Out: a [`ReadBag`]: the samples for the
//! plausibility checks, where each came from, the bag's files with their SHA-256, and
//! the frames used.

use super::cdr::{Value, decode};
use super::definitions::Definitions;
use super::frames::{self, Axes, BagFrames, StaticTransform, Transform, frame_name};
use super::storage::{Bag, Survey};
use super::values::{finite, finite_transform, rotation_quaternion, stamp_ns};
use super::{BagError, BagTopics, Stamps};
use crate::Vec3;
use crate::data::interpolate::Between;
use crate::data::paired::{LeftOutWhy, Locator, PairedColumns, SourceFile, Unchecked};
use crate::rotation::{Mat3, apply, multiply};
use std::collections::BTreeMap;
use std::path::Path;

/// What a bag gave: the samples, where each came from, its files, and its frames.
#[derive(Debug, Clone)]
pub struct ReadBag {
    pub samples: Unchecked,
    pub at: Locator,
    pub files: Vec<SourceFile>,
    pub frames: BagFrames,
}

/// What a topic can be, by the fields of its type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Dvl,
    Reference,
    /// An IMU's body rate, read where one is named.
    Rate,
    Transforms,
}

impl Role {
    fn words(self) -> &'static str {
        match self {
            Role::Dvl => {
                "DVL (marine_acoustic_msgs/msg/Dvl, geometry_msgs/msg/TwistWithCovarianceStamped or TwistStamped, or a type with their fields)"
            }
            Role::Reference => "reference (nav_msgs/msg/Odometry, or a type with its fields)",
            Role::Rate => "body rate (sensor_msgs/msg/Imu, or a type with its fields)",
            Role::Transforms => "static transform",
        }
    }

    fn flag(self) -> &'static str {
        match self {
            Role::Dvl => "--dvl-topic",
            Role::Rate => "--rate-topic",
            _ => "--reference-topic",
        }
    }
}

/// Where a type keeps what a role reads: each a path of field indices.
#[derive(Debug, Clone)]
struct Layout {
    role: Role,
    stamp: [Vec<usize>; 2],
    frame_id: Vec<usize>,
    /// The DVL's velocity, or the reference's body velocity.
    velocity: [Vec<usize>; 3],
    /// The reference's orientation, x, y, z, w, and body rate.
    orientation: Option<[Vec<usize>; 4]>,
    rate: Option<[Vec<usize>; 3]>,
    child_frame_id: Option<Vec<usize>>,
    /// The DVL's validity: its mode, good beams and beam velocities' flag, where its
    /// type has them.
    mode: Option<Vec<usize>>,
    good_beams: Option<Vec<usize>>,
    beams_valid: Option<Vec<usize>>,
}

/// The layout of `type_name` on `topic`, where it is a type a role reads.
fn layout(topic: &str, type_name: &str, definitions: &Definitions) -> Option<Layout> {
    let path = |p: &str| definitions.path(type_name, p).map(|(indices, _)| indices);
    let triple = |prefix: &str| -> Option<[Vec<usize>; 3]> {
        Some([
            path(&format!("{prefix}.x"))?,
            path(&format!("{prefix}.y"))?,
            path(&format!("{prefix}.z"))?,
        ])
    };
    if topic == "/tf_static" && path("transforms").is_some() {
        return Some(Layout {
            role: Role::Transforms,
            stamp: [vec![], vec![]],
            frame_id: vec![],
            velocity: [vec![], vec![], vec![]],
            orientation: None,
            rate: None,
            child_frame_id: None,
            mode: None,
            good_beams: None,
            beams_valid: None,
        });
    }
    let stamp = [path("header.stamp.sec")?, path("header.stamp.nanosec")?];
    let frame_id = path("header.frame_id")?;
    let base = |role, velocity| Layout {
        role,
        stamp: stamp.clone(),
        frame_id: frame_id.clone(),
        velocity,
        orientation: None,
        rate: None,
        child_frame_id: None,
        mode: path("velocity_mode"),
        good_beams: path("num_good_beams"),
        beams_valid: path("beam_velocities_valid"),
    };
    if let (Some(orientation), Some(child), Some(linear)) = (
        (|| {
            Some([
                path("pose.pose.orientation.x")?,
                path("pose.pose.orientation.y")?,
                path("pose.pose.orientation.z")?,
                path("pose.pose.orientation.w")?,
            ])
        })(),
        path("child_frame_id"),
        triple("twist.twist.linear"),
    ) {
        return Some(Layout {
            orientation: Some(orientation),
            rate: triple("twist.twist.angular"),
            child_frame_id: Some(child),
            ..base(Role::Reference, linear)
        });
    }
    if let (Some(rate), Some(_)) = (triple("angular_velocity"), path("linear_acceleration.x")) {
        return Some(base(Role::Rate, rate));
    }
    let velocity = triple("velocity")
        .or_else(|| triple("twist.twist.linear"))
        .or_else(|| triple("twist.linear"))?;
    Some(base(Role::Dvl, velocity))
}

/// One message's samples as read, before frames are applied.
#[derive(Debug, Clone, Default)]
struct Samples {
    layout: Option<Layout>,
    type_name: String,
    frame_id: Option<String>,
    child_frame_id: Option<String>,
    /// Each message's stamp, ns since the epoch.
    stamp_ns: Vec<i64>,
    message: Vec<u64>,
    velocity: Vec<Vec3>,
    orientation: Vec<[f64; 4]>,
    rate: Vec<Vec3>,
    valid: Vec<bool>,
    transforms: Vec<StaticTransform>,
}

/// The numbers at `paths` of `value`.
fn numbers<const N: usize>(value: &Value, paths: &[Vec<usize>; N]) -> Option<[f64; N]> {
    let mut out = [0.0; N];
    for (k, path) in paths.iter().enumerate() {
        out[k] = value.at(path)?.number()?;
    }
    Some(out)
}

impl Samples {
    /// Adds the message `value`, recorded at `receive_ns`, the `message`th of its topic.
    fn add(
        &mut self,
        value: &Value,
        receive_ns: u64,
        message: u64,
        stamps: Stamps,
    ) -> Result<(), String> {
        let layout = self.layout.as_ref().expect("a wanted topic has a layout");
        let missing = || "a field of its type is missing or not a number".to_string();
        if layout.role == Role::Transforms {
            for transform in value.at(&[0]).and_then(list).ok_or_else(missing)? {
                let (transform, quaternion) = static_transform(transform).ok_or_else(missing)?;
                finite_transform(&transform, quaternion)?;
                self.transforms.push(transform);
            }
            return Ok(());
        }
        let header = numbers(value, &layout.stamp).ok_or_else(missing)?;
        self.stamp_ns.push(stamp_ns(header, receive_ns, stamps)?);
        self.message.push(message);
        let frame = |path: &[usize]| value.at(path).and_then(Value::text).map(frame_name);
        let frames = (
            frame(&layout.frame_id),
            (layout.child_frame_id.as_deref()).and_then(frame),
        );
        match (&self.frame_id, &self.child_frame_id) {
            (None, _) => {
                self.frame_id = frames.0.map(String::from);
                self.child_frame_id = frames.1.map(String::from);
            }
            (first, first_child) => {
                for ((now, then), key) in [(frames.0, first), (frames.1, first_child)]
                    .into_iter()
                    .zip(["frame_id", "child_frame_id"])
                {
                    if now != then.as_deref() {
                        return Err(format!(
                            "its {key} is {:?} where its first message's is {:?}: a topic's velocities are read in one frame, so a recording whose frame changes is not read",
                            now.unwrap_or(""),
                            then.as_deref().unwrap_or("")
                        ));
                    }
                }
            }
        }
        let velocity = numbers(value, &layout.velocity).ok_or_else(missing)?;
        // A DVL's velocity that is not a number is a ping with none (left out and
        // counted where the recording is checked); the reference's must be a number.
        if layout.role != Role::Dvl {
            finite("its velocity", &velocity)?;
        }
        self.velocity.push(velocity);
        if let Some(orientation) = &layout.orientation {
            let quaternion = numbers(value, orientation).ok_or_else(missing)?;
            rotation_quaternion("its orientation", quaternion)?;
            self.orientation.push(quaternion);
        }
        if let Some(rate) = &layout.rate {
            let rate = numbers(value, rate).ok_or_else(missing)?;
            finite("its angular velocity", &rate)?;
            self.rate.push(rate);
        }
        let flag = |path: &Option<Vec<usize>>| path.as_ref().and_then(|p| value.at(p)?.number());
        let bottom_track = flag(&layout.mode).is_none_or(|mode| mode == 1.0);
        let good_beams = flag(&layout.good_beams).is_none_or(|beams| beams >= 3.0);
        let beams_valid = flag(&layout.beams_valid).is_none_or(|valid| valid != 0.0);
        self.valid.push(bottom_track && good_beams && beams_valid);
        Ok(())
    }
}

fn list(value: &Value) -> Option<&[Value]> {
    match value {
        Value::List(items) => Some(items),
        _ => None,
    }
}

/// A `geometry_msgs/TransformStamped`'s parent, child and transform; `None` where a
/// field is missing. Its numbers are checked where it is read, with its frames named
/// ([`finite_transform`]).
fn static_transform(value: &Value) -> Option<(StaticTransform, [f64; 4])> {
    let number = |path: &[usize]| value.at(path)?.number();
    let vector = |k: usize| {
        Some([
            number(&[2, k, 0])?,
            number(&[2, k, 1])?,
            number(&[2, k, 2])?,
        ])
    };
    let rotation = [
        number(&[2, 1, 0])?,
        number(&[2, 1, 1])?,
        number(&[2, 1, 2])?,
        number(&[2, 1, 3])?,
    ];
    let transform = StaticTransform {
        parent: value.at(&[0, 1])?.text()?.to_string(),
        child: value.at(&[1])?.text()?.to_string(),
        transform: Transform {
            rotation: frames::quaternion_matrix(rotation),
            translation_m: vector(0)?,
        },
    };
    Some((transform, rotation))
}

/// Reads the bag at `path` as `topics` says.
pub fn read(path: &Path, topics: &BagTopics) -> Result<ReadBag, BagError> {
    let (survey, by_topic) = decoded(path, topics.stamps)?;
    let dvl_topic = choose(
        path,
        &survey,
        &|name| by_topic.contains_key(name),
        Role::Dvl,
        topics.dvl.as_deref(),
    )?;
    let reference_topic = choose(
        path,
        &survey,
        &|name| name != dvl_topic && by_topic.contains_key(name),
        Role::Reference,
        topics.reference.as_deref(),
    )?;
    let transforms: Vec<StaticTransform> = (by_topic.values())
        .flat_map(|samples| samples.transforms.iter().cloned())
        .collect();
    let dvl = &by_topic[&dvl_topic];
    let reference = &by_topic[&reference_topic];
    let frames = bag_frames(
        path,
        topics,
        (&dvl_topic, dvl),
        (&reference_topic, reference),
        &transforms,
    )?;
    let mut samples = unchecked(dvl, reference, &frames);
    let rate_topic = match topics.rate.as_deref() {
        Some(given) => Some(choose(
            path,
            &survey,
            &|name| by_topic.contains_key(name),
            Role::Rate,
            Some(given),
        )?),
        None => None,
    };
    if let Some(rate_topic) = &rate_topic {
        let imu = &by_topic[rate_topic];
        samples.rate = Some(imu_rate(
            path,
            (rate_topic, imu),
            &reference.stamp_ns,
            &frames,
            &transforms,
        )?);
    }
    let at = locator(
        path,
        topics,
        (&dvl_topic, dvl),
        (&reference_topic, reference),
        match (&rate_topic, samples.rate.is_some()) {
            (Some(imu), _) => Some(format!("{imu} angular_velocity")),
            (None, true) => Some(format!("{reference_topic} twist.twist.angular")),
            (None, false) => None,
        },
    );
    let files = (survey.sha256.into_iter())
        .map(|(path, sha256)| SourceFile { path, sha256 })
        .collect();
    Ok(ReadBag {
        samples,
        at,
        files,
        frames,
    })
}

/// One pass over the bag at `path`: its survey, and the samples of each topic that
/// could play a role, stamped by `stamps`.
fn decoded(path: &Path, stamps: Stamps) -> Result<(Survey, BTreeMap<String, Samples>), BagError> {
    let bag = Bag::open(path)?;
    let mut by_topic: BTreeMap<String, Samples> = BTreeMap::new();
    let survey = bag.stream(
        &|topic, type_name, definitions| layout(topic, type_name, definitions).is_some(),
        &mut |topic, definitions, receive_ns, data| {
            let fault = |problem: String| BagError::Message {
                path: path.to_path_buf(),
                topic: topic.name.clone(),
                message: topic.count,
                problem,
            };
            let samples = by_topic
                .entry(topic.name.clone())
                .or_insert_with(|| Samples {
                    layout: layout(&topic.name, &topic.type_name, definitions),
                    type_name: topic.type_name.clone(),
                    ..Samples::default()
                });
            let value =
                decode(data, &topic.type_name, definitions).map_err(|e| fault(e.to_string()))?;
            samples
                .add(&value, receive_ns, topic.count, stamps)
                .map_err(fault)
        },
    )?;
    Ok((survey, by_topic))
}

/// The topic that plays `role`: the one `given`, or the bag's only topic with messages
/// (as `has_messages` says, which also leaves out a topic already chosen) of a type the
/// role reads.
fn choose(
    path: &Path,
    survey: &Survey,
    has_messages: &dyn Fn(&str) -> bool,
    role: Role,
    given: Option<&str>,
) -> Result<String, BagError> {
    // A topic plays the role its type's fields give it; a topic named as the DVL may
    // also be an odometry's twist (a DVL driver that publishes one).
    let plays = |name: &str, named: bool| {
        let topic = survey.topics.iter().find(|t| t.name == name);
        topic
            .and_then(|t| layout(&t.name, &t.type_name, &survey.definitions))
            .is_some_and(|l| {
                l.role == role || (named && role == Role::Dvl && l.role == Role::Reference)
            })
    };
    let refused = |problem: String| BagError::Topic {
        path: path.to_path_buf(),
        problem,
        topics: topic_lines(survey),
    };
    match given {
        Some(name) => {
            let Some(topic) = survey.topics.iter().find(|t| t.name == name) else {
                return Err(refused(format!(
                    "{}: no topic {name} in the bag",
                    role.flag()
                )));
            };
            if !plays(name, true) {
                return Err(refused(format!(
                    "{}: {name} is {} with {} messages, not a {} type this tool reads",
                    role.flag(),
                    topic.type_name,
                    topic.count,
                    role.words()
                )));
            }
            if !has_messages(name) {
                return Err(refused(format!("{}: {name} has no messages", role.flag())));
            }
            Ok(name.to_string())
        }
        None => {
            let candidates: Vec<&str> = (survey.topics.iter())
                .map(|t| t.name.as_str())
                .filter(|name| plays(name, false) && has_messages(name))
                .collect();
            match candidates.as_slice() {
                [only] => Ok(only.to_string()),
                [] => Err(refused(format!(
                    "no topic is a {} type this tool reads",
                    role.words()
                ))),
                several => Err(refused(format!(
                    "{} topics could be the {}: {}; name one with {}",
                    several.len(),
                    role.words().split(' ').next().unwrap_or(""),
                    several.join(", "),
                    role.flag()
                ))),
            }
        }
    }
}

/// The bag's topics, a line each: name, type, message count, rate, and whether this
/// tool reads it.
pub fn topic_lines(survey: &Survey) -> String {
    let readable = |name: &str, type_name: &str| match layout(name, type_name, &survey.definitions)
    {
        Some(l) if l.role == Role::Dvl => "read as a DVL",
        Some(l) if l.role == Role::Reference => "read as a reference",
        Some(l) if l.role == Role::Rate => "read for the body rate where named",
        Some(_) => "read for the DVL's frame",
        None => "not read",
    };
    (survey.topics.iter())
        .map(|t| {
            format!(
                "  {}  {}  {} messages{}  ({})",
                t.name,
                t.type_name,
                t.count,
                t.rate_hz()
                    .map(|r| format!(", {r:.2} Hz"))
                    .unwrap_or_default(),
                readable(&t.name, &t.type_name)
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The frames of a reading: the body's (as `topics` names it, and the reference's
/// twist is in), the world's, and the DVL's frame placed in the body's.
fn bag_frames(
    path: &Path,
    topics: &BagTopics,
    (dvl_topic, dvl): (&str, &Samples),
    (reference_topic, reference): (&str, &Samples),
    transforms: &[StaticTransform],
) -> Result<BagFrames, BagError> {
    let refused = |problem: String| BagError::Frames {
        path: path.to_path_buf(),
        problem,
    };
    let body = frame_name(&topics.frame).to_string();
    let child = reference.child_frame_id.clone().unwrap_or_default();
    if !child.is_empty() && child != body {
        return Err(refused(format!(
            "the reference {reference_topic} gives its twist in {child}, not in {body}: name the body frame with --frame {child}"
        )));
    }
    // An odometry's twist is in its child frame, any other DVL message's in its frame.
    let dvl_layout = dvl.layout.as_ref().expect("chosen topics have layouts");
    let dvl_frame = match dvl_layout.role {
        Role::Reference => dvl.child_frame_id.clone(),
        _ => dvl.frame_id.clone(),
    }
    .unwrap_or_default();
    let (mount, from_tf_static) = if dvl_frame.is_empty() || dvl_frame == body {
        (
            Transform {
                rotation: frames::IDENTITY,
                translation_m: [0.0; 3],
            },
            false,
        )
    } else {
        frames::one_mount(transforms, (&body, &dvl_frame)).map_err(refused)?;
        let mount = frames::chain(transforms, &body, &dvl_frame).ok_or_else(|| {
            let known: Vec<String> = (transforms.iter())
                .map(|t| format!("{} → {}", frame_name(&t.parent), frame_name(&t.child)))
                .collect();
            refused(format!(
                "the DVL {dvl_topic} is in frame {dvl_frame}, which /tf_static does not join to {body} ({}): the tool cannot turn its velocity into the body's axes",
                match known.is_empty() {
                    true => "the bag has no /tf_static".to_string(),
                    false => format!("it holds {}", known.join(", ")),
                }
            ))
        })?;
        (mount, true)
    };
    let world = reference.frame_id.clone().unwrap_or_default();
    let first_ns = (dvl
        .stamp_ns
        .first()
        .into_iter()
        .chain(reference.stamp_ns.first()))
    .min()
    .copied()
    .unwrap_or(0);
    Ok(BagFrames {
        origin_s: first_ns.div_euclid(1_000_000_000),
        dvl_topic: dvl_topic.to_string(),
        dvl_type: dvl.type_name.clone(),
        reference_topic: reference_topic.to_string(),
        reference_type: reference.type_name.clone(),
        axes: Axes::of_body(&body),
        body,
        world_ned: frames::world_is_ned(&world),
        world,
        dvl_frame,
        dvl_flags_lock: dvl_layout.mode.is_some()
            || dvl_layout.good_beams.is_some()
            || dvl_layout.beams_valid.is_some(),
        mount,
        from_tf_static,
    })
}

/// The body rate of the IMU `imu` at each of the reference's stamps `at_ns`,
/// forward-right-down, rad/s: its angular velocity turned from its frame into the
/// body's (by `/tf_static` where they differ), read linearly between its two samples
/// either side; a reference stamp beyond the IMU's first or last sample is refused.
fn imu_rate(
    path: &Path,
    (topic, imu): (&str, &Samples),
    at_ns: &[i64],
    frames: &BagFrames,
    transforms: &[StaticTransform],
) -> Result<Vec<Vec3>, BagError> {
    let refused = |problem: String| BagError::Frames {
        path: path.to_path_buf(),
        problem,
    };
    let frame = imu.frame_id.clone().unwrap_or_default();
    let into_body =
        match frame.is_empty() || frame == frames.body {
            true => frames::IDENTITY,
            false => frames::chain(transforms, &frames.body, &frame)
                .ok_or_else(|| {
                    refused(format!(
                        "the IMU {topic} is in frame {frame}, which /tf_static does not join to {}",
                        frames.body
                    ))
                })?
                .rotation,
        };
    let to_frd = multiply(&frames.axes.to_frd(), &into_body);
    let stamps = &imu.stamp_ns;
    let seconds = |ns: i64| (ns - frames.origin_s * 1_000_000_000) as f64 / 1e9;
    at_ns
        .iter()
        .map(|&t| {
            let at = Between::locate(stamps, t, f64::INFINITY).ok_or_else(|| {
                refused(format!(
                    "the IMU {topic} runs from {:.3} s to {:.3} s, and the reference has a sample at {:.3} s beyond it: its body rate there was not recorded",
                    seconds(stamps.first().copied().unwrap_or(0)),
                    seconds(stamps.last().copied().unwrap_or(0)),
                    seconds(t)
                ))
            })?;
            let rate: Vec3 = at.of(&imu.velocity);
            Ok(apply(&to_frd, rate))
        })
        .collect()
}

/// The samples of `dvl` and `reference` in north-east-down and forward-right-down.
fn unchecked(dvl: &Samples, reference: &Samples, frames: &BagFrames) -> Unchecked {
    let to_frd = frames.axes.to_frd();
    let dvl_to_frd: Mat3 = multiply(&to_frd, &frames.mount.rotation);
    let layout = dvl.layout.as_ref().expect("chosen topics have layouts");
    let flagged =
        layout.mode.is_some() || layout.good_beams.is_some() || layout.beams_valid.is_some();
    let mut velocity_ned = Vec::with_capacity(reference.stamp_ns.len());
    let mut attitude = Vec::with_capacity(reference.stamp_ns.len());
    let seconds = |stamps: &[i64]| -> Vec<f64> {
        (stamps.iter())
            .map(|&ns| (ns - frames.origin_s * 1_000_000_000) as f64 / 1e9)
            .collect()
    };
    for (orientation, velocity) in reference.orientation.iter().zip(&reference.velocity) {
        let body_to_ned = frames::body_to_ned(*orientation, frames.world_ned, frames.axes);
        velocity_ned.push(apply(&body_to_ned, apply(&to_frd, *velocity)));
        attitude.push(frames::euler_zyx(&body_to_ned));
    }
    let recorded_rate = reference
        .rate
        .iter()
        .any(|rate| rate.iter().any(|&r| r != 0.0));
    Unchecked {
        dvl_time_s: seconds(&dvl.stamp_ns),
        dvl_m_s: dvl
            .velocity
            .iter()
            .map(|v| apply(&dvl_to_frd, *v))
            .collect(),
        dvl_stated: flagged.then(|| {
            (dvl.valid.iter())
                .map(|&valid| (!valid).then_some(LeftOutWhy::Flagged))
                .collect()
        }),
        reference_time_s: seconds(&reference.stamp_ns),
        velocity_ned_m_s: velocity_ned,
        attitude,
        rate: recorded_rate.then(|| reference.rate.iter().map(|r| apply(&to_frd, *r)).collect()),
        angles_in_degrees: false,
        position: None,
        reference_read: None,
    }
}

/// Where each sample came from: the bag, each message's place in its topic, and the
/// fields that gave each quantity.
fn locator(
    path: &Path,
    topics: &BagTopics,
    (dvl_topic, dvl): (&str, &Samples),
    (reference_topic, reference): (&str, &Samples),
    rate: Option<String>,
) -> Locator {
    let names = |topic: &str, what: &str, axes: [&str; 3]| {
        axes.map(|axis| format!("{topic} {what} {axis}"))
    };
    let layout = dvl.layout.as_ref().expect("chosen topics have layouts");
    let flagged =
        layout.mode.is_some() || layout.good_beams.is_some() || layout.beams_valid.is_some();
    Locator {
        dvl: path.to_path_buf(),
        reference: path.to_path_buf(),
        dvl_lines: dvl.message.clone(),
        reference_lines: reference.message.clone(),
        names: PairedColumns {
            time: match topics.stamps {
                Stamps::Header => "header.stamp".into(),
                Stamps::Receive => "recording time".into(),
            },
            dvl: names(dvl_topic, "velocity", ["forward", "right", "down"]),
            velocity_ned: names(reference_topic, "velocity", ["north", "east", "down"]),
            attitude: names(reference_topic, "attitude", ["roll", "pitch", "yaw"]),
            rate: rate.map(|source| names(&source, "body rate", ["p", "q", "r"])),
            angles_in_degrees: false,
            valid: flagged
                .then(|| format!("{dvl_topic} bottom track, good beams, beam velocities valid")),
            zero_is_valid: false,
            gap_limit_s: topics.gap_limit_s,
            latitude_longitude: None,
            north_east: None,
        },
    }
}

/// How many messages of `bag` a reading of `topics` decodes: the DVL's and the
/// reference's (each topic's named, or every topic that could be one), from the bag's
/// counts.
pub fn message_counts(path: &Path, topics: Option<&BagTopics>) -> Result<(u64, u64), BagError> {
    let survey = Bag::open(path)?.counts()?;
    let count = |role: Role, given: Option<&str>| -> u64 {
        (survey.topics.iter())
            .filter(|t| match given {
                Some(name) => t.name == name,
                None => layout(&t.name, &t.type_name, &survey.definitions)
                    .is_some_and(|l| l.role == role),
            })
            .map(|t| t.count)
            .sum()
    };
    Ok((
        count(Role::Dvl, topics.and_then(|t| t.dvl.as_deref())),
        count(Role::Reference, topics.and_then(|t| t.reference.as_deref())),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::paired::bag::write::{
        BagWriter, Format, imu_message, odometry_message, twist_message,
        twist_with_covariance_message,
    };

    /// A vehicle turning left at 0.1 rad/s in ENU/FLU (yaw growing from east towards
    /// north), 2 m/s forward and 0.1 m/s left, its DVL in base_link as `type_name`:
    /// each `step_s` for 20 samples, each recorded 5 ms after its stamp.
    fn turning_bag(path: &Path, type_name: &str) {
        let mut bag = BagWriter::create(path, Format::Mcap { compressed: false }).unwrap();
        bag.topic("/dvl", type_name).unwrap();
        bag.topic("/odom", "nav_msgs/msg/Odometry").unwrap();
        bag.topic("/imu", "sensor_msgs/msg/Imu").unwrap();
        // The IMU 50 ms before each reference sample, and once after the last: its
        // rate about z 0.2 rad/s and rising 0.01 rad/s a sample.
        for k in 0..21 {
            let stamp_ns = 950_000_000 + k * 100_000_000;
            let imu = imu_message(stamp_ns, "base_link", [0.0, 0.0, 0.2 + 0.01 * k as f64]);
            bag.write("/imu", stamp_ns as u64, &imu).unwrap();
        }
        for k in 0..20 {
            let stamp_ns = 1_000_000_000 + k * 100_000_000;
            let yaw = 0.1 * k as f64 * 0.1;
            let orientation = [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()];
            let odometry = odometry_message(
                stamp_ns,
                ("odom", "base_link"),
                ([0.0; 3], orientation),
                [2.0, 0.1, 0.0],
                [0.0, 0.0, 0.1],
            );
            let velocity = [2.0, 0.1, -0.05];
            let dvl = match type_name {
                "geometry_msgs/msg/TwistStamped" => twist_message(stamp_ns, "base_link", velocity),
                _ => twist_with_covariance_message(
                    stamp_ns,
                    "base_link",
                    velocity,
                    [[1e-4, 0.0, 0.0], [0.0, 1e-4, 0.0], [0.0, 0.0, 1e-4]],
                ),
            };
            let receive = (stamp_ns + 5_000_000) as u64;
            bag.write("/odom", receive, &odometry).unwrap();
            bag.write("/dvl", receive, &dvl).unwrap();
        }
        bag.finish().unwrap();
    }

    /// Turning left in FLU is a negative yaw rate in FRD, a left velocity a negative y,
    /// and the heading east-then-north of ENU is a yaw from 90° falling in NED; each
    /// twist type reads; receive stamps are the recording's.
    #[test]
    fn a_turning_vehicle_reads_in_ned_and_forward_right_down() {
        let dir = tempfile::tempdir().unwrap();
        for type_name in [
            "geometry_msgs/msg/TwistStamped",
            "geometry_msgs/msg/TwistWithCovarianceStamped",
        ] {
            let path = dir.path().join("turning.mcap");
            turning_bag(&path, type_name);
            let read = read(&path, &BagTopics::default()).unwrap();
            let samples = &read.samples;
            assert_eq!(read.frames.origin_s, 1);
            assert_eq!(samples.dvl_time_s[3], 0.3);
            assert_eq!(samples.dvl_m_s[0], [2.0, -0.1, 0.05], "{type_name}");
            assert_eq!(samples.dvl_stated, None);
            let rate = samples.rate.as_ref().unwrap();
            assert_eq!(rate[5], [0.0, 0.0, -0.1]);
            let [roll, pitch, yaw] = samples.attitude[10];
            assert!(roll.abs() < 1e-12 && pitch.abs() < 1e-12);
            assert!(
                (yaw - (std::f64::consts::FRAC_PI_2 - 0.1)).abs() < 1e-12,
                "{yaw}"
            );
            // Forward along yaw, left of it: in NED, north cos·2 + ..., as the body
            // velocity (2, −0.1, 0) FRD turned by the yaw.
            let (s, c) = yaw.sin_cos();
            let v = samples.velocity_ned_m_s[10];
            assert!(
                (v[0] - (2.0 * c + 0.1 * s)).abs() < 1e-12
                    && (v[1] - (2.0 * s - 0.1 * c)).abs() < 1e-12,
                "{v:?}"
            );
            assert_eq!(read.frames.dvl_type, type_name);
            assert!(!read.frames.from_tf_static);
            // An IMU named: its rate, read between its samples either side, in FRD.
            let with_imu = BagTopics {
                rate: Some("/imu".into()),
                ..BagTopics::default()
            };
            let rate = super::read(&path, &with_imu).unwrap().samples.rate.unwrap();
            for (k, rate) in rate.iter().enumerate() {
                assert!(
                    (rate[2] + 0.2 + 0.01 * (k as f64 + 0.5)).abs() < 1e-12,
                    "{k}: {rate:?}"
                );
            }
            let error = super::read(
                &path,
                &BagTopics {
                    rate: Some("/odom".into()),
                    ..BagTopics::default()
                },
            )
            .unwrap_err();
            assert!(
                error.to_string().contains(
                    "--rate-topic: /odom is nav_msgs/msg/Odometry with 20 messages, not a body rate"
                ),
                "{error}"
            );
            let receive = BagTopics {
                stamps: Stamps::Receive,
                ..BagTopics::default()
            };
            let read = super::read(&path, &receive).unwrap();
            assert!((read.samples.dvl_time_s[3] - 0.305).abs() < 1e-12);
        }
    }
}
