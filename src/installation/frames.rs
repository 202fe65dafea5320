//! Frames and time: the body-to-NED rotation of an attitude (aerospace ZYX: yaw, then
//! pitch, then roll), the body angular rate from the attitude's Euler-angle rates (yaw
//! unwrapped, central differences) where no rate is recorded, and the reference in the
//! body frame at any time between its samples (linear interpolation).
//! In: a [`PairedRecording`]. Out: a [`Reference`] to read at any time.

use crate::Vec3;
use crate::data::paired::PairedRecording;

/// A 3×3 matrix, row by row.
pub type Mat3 = [[f64; 3]; 3];

/// C_b^n: rotates a body-frame vector into NED, for roll, pitch, yaw in radians.
pub fn body_to_ned(attitude_rad: Vec3) -> Mat3 {
    let _ = attitude_rad;
    todo!("issue 26")
}

/// The reference as the body sees it, at each recorded time.
#[derive(Debug, Clone)]
pub struct Reference {
    pub time_s: Vec<f64>,
    /// C_n^b · v_n, m/s.
    pub velocity_body_m_s: Vec<Vec3>,
    /// ω_b, rad/s: recorded, or derived from the attitude.
    pub rate_rad_s: Vec<Vec3>,
}

/// The reference's body velocity and body rate at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceAt {
    pub velocity_body_m_s: Vec3,
    pub rate_rad_s: Vec3,
}

impl Reference {
    pub fn new(recording: &PairedRecording) -> Self {
        let _ = recording;
        todo!("issue 26")
    }

    /// The reference at `time_s`, interpolated; `None` outside the recorded times.
    pub fn at(&self, time_s: f64) -> Option<ReferenceAt> {
        let _ = time_s;
        todo!("issue 26")
    }
}
