//! A ROS 2 bag as a paired recording: the DVL's topic and the reference's read from a
//! rosbag2 bag (MCAP or sqlite3, `storage.rs`), each message decoded from CDR
//! (`cdr.rs`) by its type's definition (`definitions.rs`: the bag's own schema, or the
//! definitions carried for a sqlite3 bag), and carried from ROS's conventions into
//! this tool's (`frames.rs`: REP-103/105, an ENU world and a forward-left-up body,
//! the DVL's frame placed by `/tf_static`) as the samples every format gives the
//! plausibility checks. `write.rs` writes bags: the corrected DVL `correct` writes, and
//! the bags the tests write.
//! The DVL is read from `marine_acoustic_msgs/msg/Dvl` (a ping counts only in bottom
//! track with at least 3 good beams and its beam velocities valid; the rest are left
//! out, flagged), `geometry_msgs/msg/TwistWithCovarianceStamped` or `TwistStamped`, or
//! a vendor's type with the same fields; the reference from `nav_msgs/msg/Odometry` (or
//! the same fields), its body rate from an IMU's `sensor_msgs/msg/Imu` where one is
//! named. The stamps are the headers' (the time of validity), or the
//! recording's with [`Stamps::Receive`]. Position fixes are read from a topic of
//! their own (`fix_topic.rs`: a NavSatFix, or a pose) on the same clock.
//! In: a bag's path and the [`BagTopics`] to read. Out: a [`ReadBag`].

mod cdr;
mod definitions;
mod fix_topic;
mod frames;
mod messages;
mod storage;
mod values;
pub mod write;

pub use cdr::{Value, decode};
pub use definitions::Definitions;
pub use fix_topic::{BagFixes, read_bag_beside_attitude, read_fix_topic};
pub use frames::{Axes, BagFrames, euler_zyx, matrix_quaternion};
pub use messages::{ReadBag, message_counts, read, topic_lines};
pub use storage::{Bag, Storage, Survey, Topic, is_bag};

use std::path::PathBuf;

/// Which stamps a bag's samples are read on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Stamps {
    /// The header's stamp: when the measurement was valid.
    #[default]
    Header,
    /// When the bag recorded the message.
    Receive,
}

/// What to read from a bag: the topics (each found by its type where not named), the
/// stamps, the vehicle's body frame (the frame the installation is reported in), and the
/// longest step that does not cut the DVL's record.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct BagTopics {
    pub dvl: Option<String>,
    pub reference: Option<String>,
    /// An IMU's topic for the body rate, where one is named (the reference's twist
    /// otherwise).
    pub rate: Option<String>,
    pub stamps: Stamps,
    pub frame: String,
    pub gap_limit_s: Option<crate::data::paired::GapLimit>,
}

impl Default for BagTopics {
    fn default() -> Self {
        BagTopics {
            dvl: None,
            reference: None,
            rate: None,
            stamps: Stamps::Header,
            frame: "base_link".into(),
            gap_limit_s: None,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum BagError {
    #[error("{}: {problem}", path.display())]
    Bag { path: PathBuf, problem: String },
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: damaged or cut short at byte {byte}: {problem}", path.display())]
    Damaged {
        path: PathBuf,
        byte: u64,
        problem: String,
    },
    #[error("{}: {topic}, message {message}: {problem}", path.display())]
    Message {
        path: PathBuf,
        topic: String,
        message: u64,
        problem: String,
    },
    #[error("{}: {problem}\nits topics:\n{topics}", path.display())]
    Topic {
        path: PathBuf,
        problem: String,
        topics: String,
    },
    #[error("{}: {problem}", path.display())]
    Frames { path: PathBuf, problem: String },
}
