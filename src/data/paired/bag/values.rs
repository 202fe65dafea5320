//! The numbers a bag's message holds, checked where they are read: each finite, a
//! quaternion that is a rotation, a `/tf_static` transform that places its frame
//! somewhere. A refusal says what the message holds and its values; the reading names
//! the topic and the message.
//! In: the values decoded. Out: nothing, or the problem.

use super::frames::StaticTransform;

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
