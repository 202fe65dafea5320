//! ROS's frames carried into this tool's. ROS (REP-103, REP-105) gives a world frame
//! east-north-up and a body frame forward-left-up (`base_link`); this tool works in
//! north-east-down and forward-right-down. A world frame whose name ends in `_ned`, or a
//! body frame whose name ends in `_frd`, is taken as already so. The DVL's velocity is
//! in its own frame (its message's `frame_id`), placed in the body frame by the chain
//! of `/tf_static` transforms between them.
//! In: quaternions, vectors and the static transforms. Out: attitudes, NED velocities,
//! forward-right-down body vectors, and the [`BagFrames`] a reading used.

use crate::Vec3;
use crate::rotation::{Mat3, apply, multiply, transpose};

/// The axes of a body frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axes {
    /// x forward, y left, z up: REP-103's body frame.
    ForwardLeftUp,
    /// x forward, y right, z down.
    ForwardRightDown,
}

impl Axes {
    /// The axes of the body frame named `frame`: forward-right-down where its name ends
    /// in `_frd`, REP-103's forward-left-up otherwise.
    pub fn of_body(frame: &str) -> Axes {
        match frame.ends_with("_frd") {
            true => Axes::ForwardRightDown,
            false => Axes::ForwardLeftUp,
        }
    }

    /// Takes a vector in these axes into forward-right-down (and back: it is its own
    /// inverse).
    pub fn to_frd(self) -> Mat3 {
        match self {
            Axes::ForwardLeftUp => [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]],
            Axes::ForwardRightDown => IDENTITY,
        }
    }

    pub fn words(self) -> &'static str {
        match self {
            Axes::ForwardLeftUp => "FLU: x forward, y left, z up",
            Axes::ForwardRightDown => "FRD: x forward, y right, z down",
        }
    }
}

pub const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// ENU into NED (its own inverse).
const ENU_TO_NED: Mat3 = [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]];

/// Whether the world frame named `frame` is north-east-down (its name ends in `_ned`)
/// rather than REP-103's east-north-up.
pub fn world_is_ned(frame: &str) -> bool {
    frame.ends_with("_ned")
}

/// The rotation of the unit quaternion `[x, y, z, w]` (normalised first).
pub fn quaternion_matrix([x, y, z, w]: [f64; 4]) -> Mat3 {
    let n = (x * x + y * y + z * z + w * w).sqrt();
    let (x, y, z, w) = (x / n, y / n, z / n, w / n);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - z * w),
            2.0 * (x * z + y * w),
        ],
        [
            2.0 * (x * y + z * w),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - x * w),
        ],
        [
            2.0 * (x * z - y * w),
            2.0 * (y * z + x * w),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// The quaternion `[x, y, z, w]` of the rotation `r` (w ≥ 0), read from the matrix's
/// largest diagonal term (Shepperd's method), exact at any attitude.
pub fn matrix_quaternion(r: &Mat3) -> [f64; 4] {
    let trace = r[0][0] + r[1][1] + r[2][2];
    let q = if trace > r[0][0].max(r[1][1]).max(r[2][2]) {
        let w = 0.5 * (1.0 + trace).sqrt();
        let f = 0.25 / w;
        [
            (r[2][1] - r[1][2]) * f,
            (r[0][2] - r[2][0]) * f,
            (r[1][0] - r[0][1]) * f,
            w,
        ]
    } else if r[0][0] >= r[1][1] && r[0][0] >= r[2][2] {
        let x = 0.5 * (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt();
        let f = 0.25 / x;
        [
            x,
            (r[0][1] + r[1][0]) * f,
            (r[0][2] + r[2][0]) * f,
            (r[2][1] - r[1][2]) * f,
        ]
    } else if r[1][1] >= r[2][2] {
        let y = 0.5 * (1.0 - r[0][0] + r[1][1] - r[2][2]).sqrt();
        let f = 0.25 / y;
        [
            (r[0][1] + r[1][0]) * f,
            y,
            (r[1][2] + r[2][1]) * f,
            (r[0][2] - r[2][0]) * f,
        ]
    } else {
        let z = 0.5 * (1.0 - r[0][0] - r[1][1] + r[2][2]).sqrt();
        let f = 0.25 / z;
        [
            (r[0][2] + r[2][0]) * f,
            (r[1][2] + r[2][1]) * f,
            z,
            (r[1][0] - r[0][1]) * f,
        ]
    };
    match q[3] < 0.0 {
        true => q.map(|v| -v),
        false => q,
    }
}

/// Roll, pitch, yaw (ZYX, as ROS's rpy and this tool's attitude), radians, of `r`; at
/// pitch ±90°, where only roll − yaw (or roll + yaw) is defined, roll 0.
pub fn euler_zyx(r: &Mat3) -> Vec3 {
    let pitch = (-r[2][0]).clamp(-1.0, 1.0).asin();
    if r[2][0].abs() > 1.0 - 1e-12 {
        return [0.0, pitch, (-r[0][1]).atan2(r[1][1])];
    }
    [r[2][1].atan2(r[2][2]), pitch, r[1][0].atan2(r[0][0])]
}

/// The body-to-NED rotation of a vehicle whose pose in the world frame `world` says
/// `orientation` (body frame `body` to world), bodies in forward-right-down.
pub fn body_to_ned(orientation: [f64; 4], world_ned: bool, body: Axes) -> Mat3 {
    let world_to_ned = if world_ned { IDENTITY } else { ENU_TO_NED };
    multiply(
        &multiply(&world_to_ned, &quaternion_matrix(orientation)),
        &body.to_frd(),
    )
}

/// A rigid transform: a vector in the child frame is `rotation · v` in the parent's,
/// and the child's origin is at `translation_m` in the parent's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    pub rotation: Mat3,
    pub translation_m: Vec3,
}

impl Transform {
    fn then(&self, inner: &Transform) -> Transform {
        let moved = apply(&self.rotation, inner.translation_m);
        Transform {
            rotation: multiply(&self.rotation, &inner.rotation),
            translation_m: [0, 1, 2].map(|k| moved[k] + self.translation_m[k]),
        }
    }

    fn inverse(&self) -> Transform {
        let rotation = transpose(&self.rotation);
        let back = apply(&rotation, self.translation_m);
        Transform {
            rotation,
            translation_m: back.map(|v| -v),
        }
    }
}

/// One static transform: from `parent` to `child`.
#[derive(Debug, Clone, PartialEq)]
pub struct StaticTransform {
    pub parent: String,
    pub child: String,
    pub transform: Transform,
}

/// A frame's name without the leading `/` ROS 1 put there.
pub fn frame_name(name: &str) -> &str {
    name.trim_start_matches('/')
}

/// The problem with `transforms` where two of `/tf_static`'s join the same two frames otherwise
/// and those frames lie on the DVL's mount, the chain from `body` to `dvl_frame`: which
/// mount held is not known. Both are named, with where they place the child. Two that
/// disagree off the chain (a camera's, say) change nothing read.
pub fn one_mount(
    transforms: &[StaticTransform],
    (body, dvl_frame): (&str, &str),
) -> Result<(), String> {
    let Some((_, on_the_mount)) = reach(transforms, body, dvl_frame) else {
        return Ok(());
    };
    let matters = |&(k, _): &(usize, usize)| {
        let t: &StaticTransform = &transforms[k];
        [&t.parent, &t.child]
            .iter()
            .all(|f| on_the_mount.iter().any(|m| m == frame_name(f)))
    };
    let Some(&(k, j)) = disagreeing(transforms).iter().find(|pair| matters(pair)) else {
        return Ok(());
    };
    let placed = |t: &StaticTransform| {
        let [roll, pitch, yaw] = euler_zyx(&t.transform.rotation).map(f64::to_degrees);
        let [x, y, z] = t.transform.translation_m;
        format!(
            "{} → {} at ({x:.4}, {y:.4}, {z:.4}) m, roll {roll:.3}°, pitch {pitch:.3}°, yaw {yaw:.3}°",
            frame_name(&t.parent),
            frame_name(&t.child)
        )
    };
    Err(format!(
        "/tf_static places a frame on the DVL's mount twice, otherwise: {}, and {}: which mount held is not known, so the DVL is not placed: write the bag again with the one that held",
        placed(&transforms[k]),
        placed(&transforms[j])
    ))
}

/// The pairs of `transforms` (by their places) that join the same two frames (either
/// way) but place the child otherwise: by more than a micrometre, or a turn of more
/// than a microradian. A `/tf_static` published again with other numbers.
pub fn disagreeing(transforms: &[StaticTransform]) -> Vec<(usize, usize)> {
    let ends = |t: &StaticTransform| {
        (
            frame_name(&t.parent).to_string(),
            frame_name(&t.child).to_string(),
        )
    };
    let mut pairs = Vec::new();
    for (k, first) in transforms.iter().enumerate() {
        for (j, again) in transforms.iter().enumerate().skip(k + 1) {
            let (parent, child) = ends(first);
            let seen = match ends(again) {
                same if same == (parent.clone(), child.clone()) => again.transform,
                swapped if swapped == (child, parent) => again.transform.inverse(),
                _ => continue,
            };
            if !same_transform(&seen, &first.transform) {
                pairs.push((k, j));
            }
        }
    }
    pairs
}

/// Whether `a` and `b` place a frame alike: within a micrometre, and a turn within a
/// microradian.
pub fn same_transform(a: &Transform, b: &Transform) -> bool {
    let moved = (0..3).any(|i| (a.translation_m[i] - b.translation_m[i]).abs() > 1e-6);
    let turned = (a.rotation.iter().flatten())
        .zip(b.rotation.iter().flatten())
        .any(|(x, y)| (x - y).abs() > 1e-6);
    !(moved || turned)
}

/// The transform from `from` to `to` through the chain of `transforms` that joins
/// them (either way along each), where one does.
pub fn chain(transforms: &[StaticTransform], from: &str, to: &str) -> Option<Transform> {
    reach(transforms, from, to).map(|(transform, _)| transform)
}

/// [`chain`]'s transform, and the frames it passes through from `from` to `to`, both
/// included.
pub fn reach(
    transforms: &[StaticTransform],
    from: &str,
    to: &str,
) -> Option<(Transform, Vec<String>)> {
    let identity = Transform {
        rotation: IDENTITY,
        translation_m: [0.0; 3],
    };
    // Each frame reached, the transform to it, and the frame it was reached from.
    let mut reached: Vec<(String, Transform, usize)> = vec![(from.to_string(), identity, 0)];
    let mut at = 0;
    while at < reached.len() {
        let (frame, so_far, _) = reached[at].clone();
        if frame == to {
            let mut path = vec![frame];
            let mut back = at;
            while back != 0 {
                back = reached[back].2;
                path.push(reached[back].0.clone());
            }
            path.reverse();
            return Some((so_far, path));
        }
        for edge in transforms {
            let (next, step) = if frame_name(&edge.parent) == frame {
                (frame_name(&edge.child), edge.transform)
            } else if frame_name(&edge.child) == frame {
                (frame_name(&edge.parent), edge.transform.inverse())
            } else {
                continue;
            };
            if !reached.iter().any(|(f, _, _)| f == next) {
                reached.push((next.to_string(), so_far.then(&step), at));
            }
        }
        at += 1;
    }
    None
}

/// The frames a bag's reading used: the topics, the body frame and its axes, the
/// world frame, and where the DVL's frame sits in the body's.
#[derive(Debug, Clone, PartialEq)]
pub struct BagFrames {
    pub dvl_topic: String,
    pub dvl_type: String,
    pub reference_topic: String,
    pub reference_type: String,
    pub body: String,
    pub axes: Axes,
    pub world: String,
    pub world_ned: bool,
    pub dvl_frame: String,
    /// Whether the DVL's messages say whether each ping had bottom lock.
    pub dvl_flags_lock: bool,
    /// The DVL's frame in the body's, from `/tf_static` (the identity where they are
    /// one frame).
    pub mount: Transform,
    /// Whether `mount` came from `/tf_static`.
    pub from_tf_static: bool,
    /// The whole second since the epoch the samples' times count from (the first
    /// stamp's), so that they keep their nanoseconds.
    pub origin_s: i64,
}

impl std::fmt::Display for BagFrames {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [roll, pitch, yaw] = euler_zyx(&self.mount.rotation).map(f64::to_degrees);
        let [x, y, z] = self.mount.translation_m;
        write!(
            f,
            "the DVL from {} ({}) in frame {}, {}, ",
            self.dvl_topic,
            self.dvl_type,
            match self.dvl_frame.is_empty() {
                true => "(none: its messages' frame_id is empty, so it is read as the body's)",
                false => &self.dvl_frame,
            },
            match self.dvl_flags_lock {
                true => "each ping's bottom lock read from its message",
                false =>
                    "its messages saying nothing of bottom lock (only pings of exactly 0, 0, 0 are left out as lost)",
            }
        )?;
        if self.from_tf_static {
            write!(
                f,
                "placed in {} by /tf_static at ({x:.3}, {y:.3}, {z:.3}) m, roll {roll:.1}°, pitch {pitch:.1}°, yaw {yaw:.1}°",
                self.body
            )?;
        } else {
            write!(f, "the body frame itself")?;
        }
        write!(
            f,
            "; the reference from {} ({}), world {} ({}), body {} ({}); read into north-east-down and forward-right-down, times in seconds from {} s after the epoch",
            self.reference_topic,
            self.reference_type,
            self.world,
            if self.world_ned { "NED" } else { "ENU" },
            self.body,
            self.axes.words(),
            self.origin_s
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rotation::body_to_ned as attitude_matrix;
    use std::f64::consts::PI;

    fn close(a: Vec3, b: Vec3) {
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < 1e-12, "{a:?} against {b:?}");
        }
    }

    /// A vehicle heading north-east in ENU (yaw 45° from east, so 45° from north too),
    /// pitched 10° nose up in FLU: in NED its yaw is 45°, its pitch +10° (nose up is
    /// positive pitch both ways), and a body x velocity points north-east and up.
    #[test]
    fn an_enu_flu_pose_reads_as_the_ned_frd_attitude() {
        let (pitch, yaw) = (10f64.to_radians(), 45f64.to_radians());
        // FLU to ENU: yaw about up, then pitch about left (nose up is negative about y
        // in FLU's right-handed axes).
        let (sy, cy) = (yaw / 2.0).sin_cos();
        let (sp, cp) = (-pitch / 2.0).sin_cos();
        let q = [-sy * sp, cy * sp, sy * cp, cy * cp];
        let r = body_to_ned(q, false, Axes::ForwardLeftUp);
        close(euler_zyx(&r), [0.0, pitch, yaw]);
        let r_tool = attitude_matrix([0.0, pitch, yaw]);
        for (row, expected) in r.iter().zip(r_tool) {
            close(*row, expected);
        }
        let north_east_up = apply(&r, [1.0, 0.0, 0.0]);
        let horizontal = pitch.cos() / 2f64.sqrt();
        close(north_east_up, [horizontal, horizontal, -pitch.sin()]);
    }

    /// A rotation's quaternion and angles give it back at any attitude, pitch ±90°
    /// and a 180° roll among them.
    #[test]
    fn rotations_round_trip_through_quaternions_and_angles_at_any_attitude() {
        for attitude in [
            [0.3, 0.2, -2.0],
            [PI, 0.0, 0.0],
            [0.0, PI / 2.0, 0.7],
            [0.0, -PI / 2.0, -0.4],
            [1.0, 0.4, PI],
        ] {
            let r = attitude_matrix(attitude);
            let again = attitude_matrix(euler_zyx(&r));
            let from_quaternion = quaternion_matrix(matrix_quaternion(&r));
            for k in 0..3 {
                close(again[k], r[k]);
                close(from_quaternion[k], r[k]);
            }
        }
    }

    /// A chain of two static transforms is composed, and walked backwards too.
    #[test]
    fn static_transforms_chain_both_ways() {
        let yawed = |deg: f64, at: Vec3| Transform {
            rotation: attitude_matrix([0.0, 0.0, deg.to_radians()]),
            translation_m: at,
        };
        let transforms = vec![
            StaticTransform {
                parent: "base_link".into(),
                child: "mount".into(),
                transform: yawed(90.0, [1.0, 0.0, 0.0]),
            },
            StaticTransform {
                parent: "/mount".into(),
                child: "dvl".into(),
                transform: yawed(0.0, [2.0, 0.0, 0.0]),
            },
        ];
        let chained = chain(&transforms, "base_link", "dvl").unwrap();
        close(chained.translation_m, [1.0, 2.0, 0.0]);
        close(apply(&chained.rotation, [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0]);
        let back = chain(&transforms, "dvl", "base_link").unwrap();
        close(apply(&back.rotation, [0.0, 1.0, 0.0]), [1.0, 0.0, 0.0]);
        close(back.translation_m, [-2.0, 1.0, 0.0]);
        assert!(chain(&transforms, "base_link", "camera").is_none());
        let q = matrix_quaternion(&chained.rotation);
        let again = quaternion_matrix(q);
        for (a, b) in again.iter().zip(chained.rotation) {
            close(*a, b);
        }
    }
}
