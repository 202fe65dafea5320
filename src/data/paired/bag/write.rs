//! Writes ROS 2 bags: one MCAP file (its chunks compressed or not) or one sqlite3
//! file, with the schemas rosbag2 writes, and the messages of the types this tool reads
//! encoded in CDR. `correct` writes the corrected DVL with it; the tests and the
//! benchmark write their bags with it.
//! In: topics, and messages as [`Message`]s. Out: a bag on disk.

use super::cdr::Encoder;
use super::definitions::{full_name, schema_text};
use crate::Vec3;
use std::collections::BTreeMap;
use std::io::BufWriter;
use std::path::Path;

/// How a written bag stores its messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// MCAP, its chunks zstd-compressed where `compressed`.
    Mcap {
        compressed: bool,
    },
    Sqlite,
}

/// A bag being written.
pub struct BagWriter {
    storage: Storage,
    /// Each topic's id, by name.
    topics: BTreeMap<String, u16>,
}

enum Storage {
    Mcap(Box<mcap::Writer<BufWriter<std::fs::File>>>),
    Sqlite(rusqlite::Connection),
}

/// Why a bag could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    #[error("{0}")]
    Mcap(#[from] mcap::McapError),
    #[error("{0}")]
    Sqlite(#[from] rusqlite::Error),
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

impl BagWriter {
    /// A new bag at `path` (replacing any file there).
    pub fn create(path: &Path, format: Format) -> Result<BagWriter, WriteError> {
        let storage = match format {
            Format::Mcap { compressed } => {
                let file = BufWriter::new(std::fs::File::create(path)?);
                let options = mcap::WriteOptions::new()
                    .profile("ros2")
                    .compression(compressed.then_some(mcap::Compression::Zstd));
                Storage::Mcap(Box::new(options.create(file)?))
            }
            Format::Sqlite => {
                if path.exists() {
                    std::fs::remove_file(path)?;
                }
                let connection = rusqlite::Connection::open(path)?;
                connection.execute_batch(
                    "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
                     INSERT INTO schema VALUES (3, 'humble');
                     CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
                     CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data BLOB NOT NULL);
                     CREATE INDEX timestamp_idx ON messages (timestamp ASC);
                     BEGIN;",
                )?;
                Storage::Sqlite(connection)
            }
        };
        Ok(BagWriter {
            storage,
            topics: BTreeMap::new(),
        })
    }

    /// A new MCAP bag written into the open `file`, its chunks zstd-compressed.
    pub fn mcap(file: std::fs::File) -> Result<BagWriter, WriteError> {
        let options = mcap::WriteOptions::new()
            .profile("ros2")
            .compression(Some(mcap::Compression::Zstd));
        Ok(BagWriter {
            storage: Storage::Mcap(Box::new(options.create(BufWriter::new(file))?)),
            topics: BTreeMap::new(),
        })
    }

    /// Adds the topic `name` of `type_name` (written with the carried definition).
    pub fn topic(&mut self, name: &str, type_name: &str) -> Result<(), WriteError> {
        let type_name = full_name(type_name);
        let id = match &mut self.storage {
            Storage::Mcap(writer) => {
                let schema =
                    writer.add_schema(&type_name, "ros2msg", schema_text(&type_name).as_bytes())?;
                writer.add_channel(schema, name, "cdr", &BTreeMap::new())?
            }
            Storage::Sqlite(connection) => {
                let id = self.topics.len() as u16 + 1;
                connection.execute(
                    "INSERT INTO topics VALUES (?1, ?2, ?3, 'cdr', '')",
                    rusqlite::params![id, name, type_name],
                )?;
                id
            }
        };
        self.topics.insert(name.to_string(), id);
        Ok(())
    }

    /// Writes `data` on `topic` (added before), recorded at `receive_ns`.
    pub fn write(&mut self, topic: &str, receive_ns: u64, data: &[u8]) -> Result<(), WriteError> {
        let id = self.topics[topic];
        match &mut self.storage {
            Storage::Mcap(writer) => writer.write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: id,
                    sequence: 0,
                    log_time: receive_ns,
                    publish_time: receive_ns,
                },
                data,
            )?,
            Storage::Sqlite(connection) => {
                connection
                    .prepare_cached(
                        "INSERT INTO messages (topic_id, timestamp, data) VALUES (?1, ?2, ?3)",
                    )?
                    .execute(rusqlite::params![id, receive_ns as i64, data])?;
            }
        }
        Ok(())
    }

    /// Closes the bag: its summary written (MCAP), its messages committed (sqlite3).
    pub fn finish(self) -> Result<(), WriteError> {
        match self.storage {
            Storage::Mcap(mut writer) => {
                writer.finish()?;
            }
            Storage::Sqlite(connection) => connection.execute_batch("COMMIT;")?,
        }
        Ok(())
    }
}

/// What a `marine_acoustic_msgs/msg/Dvl` ping says of its validity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DvlStatus {
    /// 1 bottom track, 2 water track.
    pub velocity_mode: u8,
    pub num_good_beams: u8,
    pub beam_velocities_valid: bool,
}

impl DvlStatus {
    pub const BOTTOM_LOCK: DvlStatus = DvlStatus {
        velocity_mode: 1,
        num_good_beams: 4,
        beam_velocities_valid: true,
    };
}

/// A `marine_acoustic_msgs/msg/Dvl` ping stamped `stamp_ns` in `frame`.
pub fn dvl_message(
    stamp_ns: i64,
    frame: &str,
    velocity_m_s: Vec3,
    status: DvlStatus,
    covariance: f64,
) -> Vec<u8> {
    let mut e = Encoder::default();
    e.header(stamp_ns, frame).u8(status.velocity_mode).u8(0);
    e.f64s(&velocity_m_s);
    let mut covar = [0.0; 9];
    for k in [0, 4, 8] {
        covar[k] = covariance;
    }
    e.f64s(&covar).f64s(&[
        10.0,
        velocity_m_s[1].atan2(velocity_m_s[0]),
        velocity_m_s[0].hypot(velocity_m_s[1]),
    ]);
    e.u8(status.num_good_beams)
        .f32(1500.0)
        .u8(1)
        .u8(status.beam_velocities_valid as u8);
    let s = 0.5f64;
    for (x, y) in [(s, s), (-s, s), (-s, -s), (s, -s)] {
        e.f64s(&[x, y, (1.0f64 - 2.0 * s * s).sqrt()]);
    }
    e.f64s(&[11.5; 4]);
    for _ in 0..16 {
        e.f32(0.0);
    }
    e.finish()
}

/// A `geometry_msgs/msg/TwistWithCovarianceStamped`: `linear_m_s` in `frame`, its 3×3
/// covariance (row-major, (m/s)²) in the linear block and −1 (unknown) on the angular
/// diagonal, as robot_localization reads it.
pub fn twist_with_covariance_message(
    stamp_ns: i64,
    frame: &str,
    linear_m_s: Vec3,
    covariance: [[f64; 3]; 3],
) -> Vec<u8> {
    let mut e = Encoder::default();
    e.header(stamp_ns, frame).f64s(&linear_m_s).f64s(&[0.0; 3]);
    let mut full = [0.0; 36];
    for i in 0..3 {
        for j in 0..3 {
            full[i * 6 + j] = covariance[i][j];
        }
        full[(i + 3) * 6 + i + 3] = -1.0;
    }
    e.f64s(&full);
    e.finish()
}

/// A `geometry_msgs/msg/TwistStamped`: `linear_m_s` in `frame`.
pub fn twist_message(stamp_ns: i64, frame: &str, linear_m_s: Vec3) -> Vec<u8> {
    let mut e = Encoder::default();
    e.header(stamp_ns, frame).f64s(&linear_m_s).f64s(&[0.0; 3]);
    e.finish()
}

/// A `nav_msgs/msg/Odometry`: the pose's position, m, in `world`, and its orientation
/// `[x, y, z, w]` (body to `world`), its covariance unknown (zeros); the twist's linear
/// and angular parts in the body frame `child`.
pub fn odometry_message(
    stamp_ns: i64,
    (world, child): (&str, &str),
    (position_m, orientation): (Vec3, [f64; 4]),
    linear_m_s: Vec3,
    angular_rad_s: Vec3,
) -> Vec<u8> {
    let mut e = Encoder::default();
    e.header(stamp_ns, world).text(child);
    e.f64s(&position_m).f64s(&orientation).f64s(&[0.0; 36]);
    e.f64s(&linear_m_s).f64s(&angular_rad_s).f64s(&[0.0; 36]);
    e.finish()
}

/// A `sensor_msgs/msg/Imu` in `frame`: its angular velocity, rad/s (its orientation
/// and acceleration unknown: zero, their covariances −1).
pub fn imu_message(stamp_ns: i64, frame: &str, angular_rad_s: Vec3) -> Vec<u8> {
    let mut e = Encoder::default();
    let unknown = [-1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    e.header(stamp_ns, frame)
        .f64s(&[0.0, 0.0, 0.0, 1.0])
        .f64s(&unknown);
    e.f64s(&angular_rad_s).f64s(&[0.0; 9]);
    e.f64s(&[0.0; 3]).f64s(&unknown);
    e.finish()
}

/// A `sensor_msgs/msg/NavSatFix` in `frame`: `status` (−1: no fix), latitude and
/// longitude, degrees, altitude, m, and the position's ENU covariance, m², where known
/// (a diagonal of the same variance east and north, another up), unknown otherwise.
pub fn nav_sat_fix_message(
    stamp_ns: i64,
    frame: &str,
    status: i8,
    [latitude_deg, longitude_deg, altitude_m]: Vec3,
    variance_m2: Option<[f64; 2]>,
) -> Vec<u8> {
    let mut e = Encoder::default();
    e.header(stamp_ns, frame).u8(status as u8).u16(1);
    e.f64s(&[latitude_deg, longitude_deg, altitude_m]);
    let (covariance, kind) = match variance_m2 {
        Some([horizontal, up]) => {
            let mut c = [0.0; 9];
            (c[0], c[4], c[8]) = (horizontal, horizontal, up);
            (c, 2)
        }
        None => ([0.0; 9], 0),
    };
    e.f64s(&covariance).u8(kind);
    e.finish()
}

/// A `geometry_msgs/msg/PoseWithCovarianceStamped` in the world frame `world`: the
/// position, m, an identity orientation, and the variance of x and y, m², on the
/// covariance's diagonal (zero, unknown, where none).
pub fn pose_with_covariance_message(
    stamp_ns: i64,
    world: &str,
    position_m: Vec3,
    variance_m2: Option<f64>,
) -> Vec<u8> {
    let mut e = Encoder::default();
    e.header(stamp_ns, world).f64s(&position_m);
    e.f64s(&[0.0, 0.0, 0.0, 1.0]);
    let mut covariance = [0.0; 36];
    if let Some(variance) = variance_m2 {
        (covariance[0], covariance[7]) = (variance, variance);
    }
    e.f64s(&covariance);
    e.finish()
}

/// A `tf2_msgs/msg/TFMessage` of static transforms: each its parent, child,
/// translation, m, and rotation `[x, y, z, w]`.
pub fn tf_message(stamp_ns: i64, transforms: &[(&str, &str, Vec3, [f64; 4])]) -> Vec<u8> {
    let mut e = Encoder::default();
    e.u32(transforms.len() as u32);
    for (parent, child, translation, rotation) in transforms {
        e.header(stamp_ns, parent)
            .text(child)
            .f64s(translation)
            .f64s(rotation);
    }
    e.finish()
}

/// How [`write_recording`] lays a recording out as a ROS 2 vehicle would: the DVL's
/// topic and frame, that frame's roll and yaw from the body frame (written to
/// `/tf_static` with its translation, the DVL's velocity in its own axes), and every how-many-th ping is
/// sent as lost bottom lock (water track, two good beams, a velocity of nothing).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RosLayout<'a> {
    pub dvl_topic: &'a str,
    pub dvl_frame: &'a str,
    pub mount_roll_deg: f64,
    pub mount_yaw_deg: f64,
    /// Where `/tf_static` places the DVL's frame in the body's, m.
    pub mount_translation_m: Vec3,
    pub lost_lock_every: Option<usize>,
    /// Whole seconds added to every stamp (a bag's stamps are times since the epoch).
    pub epoch_s: i64,
    /// Bytes a second of a topic this tool does not read (`/camera/image`, of type
    /// `sensor_msgs/msg/Image`, a message a second): a camera or a sonar beside the
    /// navigation, for a reading to pass over.
    pub other_bytes_per_s: usize,
    /// Topics of other sensors written beside (a USBL's fixes), each message recorded
    /// at its stamp.
    pub other_topics: &'a [OtherTopic<'a>],
}

/// A topic [`write_recording`] writes beside the DVL and the reference: its name, its
/// type, and its messages, each with its stamp, ns since the epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OtherTopic<'a> {
    pub name: &'a str,
    pub type_name: &'a str,
    pub messages: &'a [(i64, Vec<u8>)],
}

impl Default for RosLayout<'_> {
    fn default() -> Self {
        RosLayout {
            dvl_topic: "/dvl/data",
            dvl_frame: "dvl_link",
            mount_roll_deg: 180.0,
            mount_yaw_deg: 0.0,
            mount_translation_m: [0.0; 3],
            lost_lock_every: None,
            epoch_s: 1_700_000_000,
            other_bytes_per_s: 0,
            other_topics: &[],
        }
    }
}

/// Writes `recording` (this tool's axes: NED, forward-right-down) to a bag at `path`
/// as a ROS 2 vehicle records it: the DVL as `marine_acoustic_msgs/msg/Dvl` in its own
/// frame, placed by `/tf_static`; the reference as `nav_msgs/msg/Odometry` (`/ins/odom`)
/// in ENU and `base_link`'s forward-left-up axes, its body rate in the twist where the
/// recording has one. Each message is recorded at its stamp.
pub fn write_recording(
    recording: &crate::data::paired::PairedRecording,
    path: &Path,
    format: Format,
    layout: RosLayout,
) -> Result<(), WriteError> {
    use super::frames::{Axes, matrix_quaternion};
    use crate::rotation::{body_to_ned, multiply, transpose};
    let flu = Axes::ForwardLeftUp.to_frd();
    // The DVL's frame from the body's (FLU): rolled, then yawed.
    let mount = body_to_ned([
        layout.mount_roll_deg.to_radians(),
        0.0,
        layout.mount_yaw_deg.to_radians(),
    ]);
    let into_dvl = multiply(&transpose(&mount), &flu);
    let stamp = |t: f64| layout.epoch_s * 1_000_000_000 + (t * 1e9).round() as i64;
    let mut bag = BagWriter::create(path, format)?;
    bag.topic("/tf_static", "tf2_msgs/msg/TFMessage")?;
    bag.topic(layout.dvl_topic, "marine_acoustic_msgs/msg/Dvl")?;
    bag.topic("/ins/odom", "nav_msgs/msg/Odometry")?;
    let first = stamp(recording.reference_time_s[0].min(recording.time_s[0])) - 1_000_000;
    let tf = tf_message(
        first,
        &[(
            "base_link",
            layout.dvl_frame,
            layout.mount_translation_m,
            matrix_quaternion(&mount),
        )],
    );
    bag.write("/tf_static", first as u64, &tf)?;
    let mut messages = dvl_messages(recording, &layout, &into_dvl, &stamp);
    for (k, &t) in recording.reference_time_s.iter().enumerate() {
        messages.push((stamp(t), "/ins/odom", odometry_of(recording, k, stamp(t))));
    }
    if layout.other_bytes_per_s > 0 {
        bag.topic("/camera/image", "sensor_msgs/msg/Image")?;
        let (start, end) = (
            recording.reference_time_s[0],
            recording.reference_time_s[recording.reference_time_s.len() - 1],
        );
        // Each image made as it is written (below), so that they are never all held.
        for second in 0..=(end - start).floor() as usize {
            messages.push((stamp(start + second as f64), "/camera/image", Vec::new()));
        }
    }
    for other in layout.other_topics {
        bag.topic(other.name, other.type_name)?;
        let stamped = other.messages.iter();
        messages.extend(stamped.map(|(stamp, data)| (*stamp, other.name, data.clone())));
    }
    messages.sort_by_key(|(stamp, topic, _)| (*stamp, *topic));
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    for (stamp, topic, data) in messages {
        match topic {
            "/camera/image" => {
                let image = incompressible(layout.other_bytes_per_s, &mut state);
                bag.write(topic, stamp as u64, &image)?
            }
            _ => bag.write(topic, stamp as u64, &data)?,
        }
    }
    bag.finish()
}

/// The DVL samples of `recording` as `marine_acoustic_msgs/msg/Dvl` pings in the
/// DVL's axes (`into_dvl` from the tool's), each stamped by `stamp` and tagged with
/// its topic; every `layout.lost_lock_every`-th sent as lost bottom lock.
fn dvl_messages<'a>(
    recording: &crate::data::paired::PairedRecording,
    layout: &RosLayout<'a>,
    into_dvl: &crate::rotation::Mat3,
    stamp: &dyn Fn(f64) -> i64,
) -> Vec<(i64, &'a str, Vec<u8>)> {
    let lost_lock = DvlStatus {
        velocity_mode: 2,
        num_good_beams: 2,
        beam_velocities_valid: false,
    };
    (recording.time_s.iter().zip(&recording.dvl_m_s).enumerate())
        .map(|(k, (&t, &v))| {
            let lost = layout
                .lost_lock_every
                .is_some_and(|every| k % every == every - 1);
            let (velocity, status) = match lost {
                true => ([0.0; 3], lost_lock),
                false => (crate::rotation::apply(into_dvl, v), DvlStatus::BOTTOM_LOCK),
            };
            let ping = dvl_message(stamp(t), layout.dvl_frame, velocity, status, 4e-4);
            (stamp(t), layout.dvl_topic, ping)
        })
        .collect()
}

/// The reference sample `k` of `recording` as an INS's `nav_msgs/msg/Odometry`
/// stamped `stamp_ns`: its pose in ENU, its twist in base_link's FLU axes.
fn odometry_of(
    recording: &crate::data::paired::PairedRecording,
    k: usize,
    stamp_ns: i64,
) -> Vec<u8> {
    use super::frames::{Axes, matrix_quaternion};
    use crate::rotation::{apply, body_to_ned, multiply, transpose};
    let flu = Axes::ForwardLeftUp.to_frd();
    let enu = [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]];
    let body_to_ned_k = body_to_ned(recording.attitude_rad[k]);
    let pose = multiply(&multiply(&enu, &body_to_ned_k), &flu);
    let body_velocity = apply(
        &flu,
        apply(&transpose(&body_to_ned_k), recording.velocity_ned_m_s[k]),
    );
    let rate = (recording.rate_rad_s.as_ref()).map_or([0.0; 3], |rate| apply(&flu, rate[k]));
    odometry_message(
        stamp_ns,
        ("odom", "base_link"),
        ([0.0; 3], matrix_quaternion(&pose)),
        body_velocity,
        rate,
    )
}

/// `bytes` bytes no compressor shrinks, as a camera's JPEGs (xorshift64 from `state`).
fn incompressible(bytes: usize, state: &mut u64) -> Vec<u8> {
    (0..bytes)
        .map(|_| {
            *state ^= *state << 13;
            *state ^= *state >> 7;
            *state ^= *state << 17;
            *state as u8
        })
        .collect()
}
