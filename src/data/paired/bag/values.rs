//! The numbers a bag's message holds, checked where they are read: each finite, a
//! quaternion that is a rotation, a `/tf_static` transform that places its frame
//! somewhere. A refusal says what the message holds and its values; the reading names
//! the topic and the message. A message's stamp is read here too, one way for every
//! topic.
//! In: the values decoded. Out: nothing, or the problem.

use super::Stamps;
use super::frames::StaticTransform;

/// A message's stamp, ns since the epoch, on `stamps`: its header's `sec` and
/// `nanosec`, or the bag's `receive_ns`; a header before 1970, or a receive stamp beyond
/// what an `i64` of nanoseconds holds, refused.
pub fn stamp_ns([sec, nanosec]: [f64; 2], receive_ns: u64, stamps: Stamps) -> Result<i64, String> {
    match stamps {
        Stamps::Header if sec < 0.0 => Err(format!(
            "its header stamp is {sec} s, before 1970: read it on the bag's receive stamps (--stamps receive), or mend the driver's clock"
        )),
        Stamps::Header => Ok(sec as i64 * 1_000_000_000 + nanosec as i64),
        Stamps::Receive => i64::try_from(receive_ns).map_err(|_| {
            format!("its receive stamp {receive_ns} ns lies beyond the year 2262, which no clock of a dive reads")
        }),
    }
}

/// Refuses `values` (what a message holds as `what`) where one is not a finite number.
pub fn finite(what: &str, values: &[f64]) -> Result<(), String> {
    match values.iter().all(|v| v.is_finite()) {
        true => Ok(()),
        false => Err(format!(
            "{what} {values:?} is not a finite number on every axis"
        )),
    }
}

/// Refuses the quaternion `[x, y, z, w]` (what a message holds as `what`) where it is
/// no rotation: a number not finite, or all four (nearly) zero, which no normalising
/// turns into one.
pub fn rotation_quaternion(what: &str, quaternion: [f64; 4]) -> Result<(), String> {
    finite(&format!("{what} quaternion"), &quaternion)?;
    let norm = quaternion.iter().map(|q| q * q).sum::<f64>().sqrt();
    match norm > 1e-6 {
        true => Ok(()),
        false => Err(format!(
            "{what} quaternion {quaternion:?} is zero, which is no rotation (a driver that publishes no attitude yet)"
        )),
    }
}

/// Refuses a `/tf_static` transform whose translation or rotation `quaternion` is not a
/// number or no rotation: it would place the DVL nowhere, and reach the URDF and the
/// static transform written.
pub fn finite_transform(transform: &StaticTransform, quaternion: [f64; 4]) -> Result<(), String> {
    let what = format!(
        "the /tf_static transform from {} to {}",
        transform.parent, transform.child
    );
    finite(
        &format!("{what}: its translation (m)"),
        &transform.transform.translation_m,
    )?;
    rotation_quaternion(&format!("{what}: its rotation"), quaternion)
}
