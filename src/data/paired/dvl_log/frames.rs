//! From a PD0 ensemble's bottom track to the vehicle's velocity in this tool's DVL
//! axes (x forward, y starboard, z down), and the ping's validity as the instrument
//! states it.
//! - A ping of the DVL looking up (its system configuration, which a Workhorse may
//!   change between ensembles as it is turned over) is left out: no bottom below.
//! - Out of beam coordinates, a marker (−32768) on x, y or z says the instrument made no
//!   solution: the ping is left out.
//! - A beam is good where, in beam coordinates, it has a velocity and, where
//!   thresholds are set, its correlation (and, in beam coordinates, its percent good)
//!   reaches them: unset, the instrument's own verdict stands (it marks a beam below
//!   its own BC and BA with −32768, and its BC is not comparable between firmware
//!   versions: logs keep four-beam solutions of correlations below it). Fewer than three good
//!   beams leave the ping out, counted by the first reason; three make a three-beam
//!   solution, kept and marked, as is one the instrument states (the first percent-good
//!   field out of beam coordinates).
//! - Beam coordinates are turned into the instrument's axes by the beam geometry the
//!   file states (angle, convex or concave; RDI's transformation, the error velocity
//!   set to zero for three beams). Earth coordinates are turned back by the ensemble's
//!   own heading, pitch and roll (RDI's matrix, the pitch corrected for the internal
//!   tilt sensor, the tilts left out where the file did not use them); levelled ship
//!   coordinates by its pitch and roll.
//! - Every frame is turned back into the instrument's axes (x to starboard of beam 3, y
//!   toward beam 3, z up, for a DVL looking down: ship axes by EA too), which are the
//!   vehicle's turned by the heading alignment EA; bottom track is the bottom's velocity
//!   relative to the instrument, so the vehicle's is its negative.
//!
//! In: an [`Ensemble`] and the [`Thresholds`]. Out: a [`Ping`].

use super::pd0::{Ensemble, FixedLeader, Frame, NO_VELOCITY_MM_S};
use crate::Vec3;
use crate::data::paired::LeftOutWhy;
use crate::rotation::{Mat3, apply, rotation_z, transpose};

/// The thresholds a beam must reach to count, where set (the instrument's own verdict
/// stands otherwise).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Thresholds {
    /// Bottom track's correlation, counts (0–255).
    pub correlation_min: Option<u8>,
    /// Bottom track's percent good, %.
    pub percent_good_min: Option<u8>,
}

/// A ping as read: the vehicle's velocity, m/s, in the DVL's axes, or why it is left
/// out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Ping {
    Kept {
        velocity_m_s: Vec3,
        three_beam: bool,
    },
    LeftOut(LeftOutWhy),
}

/// The vehicle's velocity that `ensemble` measured, or why it is left out.
pub fn ping(ensemble: &Ensemble, thresholds: Thresholds) -> Ping {
    let leader = &ensemble.leader;
    if leader.looking_up {
        return Ping::LeftOut(LeftOutWhy::LookingUp);
    }
    let Some(bottom) = &ensemble.bottom else {
        return Ping::LeftOut(LeftOutWhy::NoVelocity);
    };
    let in_beams = leader.frame == Frame::Beam;
    let axes = bottom.velocity_mm_s.map(|v| f64::from(v) / 1000.0);
    // Out of beam coordinates the instrument made the solution: a marker on an axis
    // says it made none.
    if !in_beams && bottom.velocity_mm_s[..3].contains(&NO_VELOCITY_MM_S) {
        return Ping::LeftOut(LeftOutWhy::Marker);
    }
    let correlation_min = thresholds.correlation_min.unwrap_or(0);
    let percent_good_min = thresholds.percent_good_min.unwrap_or(0);
    // Percent good is per beam in beam coordinates only (out of them its four fields
    // count the ping's three-beam, rejected, too-few-beam and four-beam solutions).
    let why_not = |k: usize| {
        if in_beams && bottom.velocity_mm_s[k] == NO_VELOCITY_MM_S {
            Some(LeftOutWhy::Marker)
        } else if bottom.correlation[k] < correlation_min {
            Some(LeftOutWhy::LowCorrelation)
        } else if in_beams && bottom.percent_good[k] < percent_good_min {
            Some(LeftOutWhy::LowPercentGood)
        } else {
            None
        }
    };
    let bad: Vec<(usize, LeftOutWhy)> = (0..4).filter_map(|k| why_not(k).map(|w| (k, w))).collect();
    if let [_, _, ..] = bad[..] {
        return Ping::LeftOut(bad.iter().map(|b| b.1).min().unwrap_or(LeftOutWhy::Marker));
    }
    let (instrument, three_beam) = if in_beams {
        let missing = bad.first().map(|b| b.0);
        (
            beams_to_instrument(axes, leader, missing),
            missing.is_some(),
        )
    } else {
        let three_beam = !bad.is_empty() || bottom.percent_good[0] > 0;
        (
            to_instrument([axes[0], axes[1], axes[2]], ensemble),
            three_beam,
        )
    };
    Ping::Kept {
        velocity_m_s: vehicle_axes(instrument, leader),
        three_beam,
    }
}

/// The instrument-axes velocity (m/s) of four beam velocities, the beam `missing`
/// replaced so that the error velocity is zero (RDI's three-beam solution).
fn beams_to_instrument(beams_m_s: [f64; 4], leader: &FixedLeader, missing: Option<usize>) -> Vec3 {
    let mut b = beams_m_s;
    if let Some(k) = missing {
        // The error velocity is in proportion to b1 + b2 − b3 − b4.
        b[k] = match k {
            0 => b[2] + b[3] - b[1],
            1 => b[2] + b[3] - b[0],
            2 => b[0] + b[1] - b[3],
            _ => b[0] + b[1] - b[2],
        };
    }
    let angle = leader.beam_angle_deg.to_radians();
    let c = if leader.convex { 1.0 } else { -1.0 };
    let a = 1.0 / (2.0 * angle.sin());
    let z = 1.0 / (4.0 * angle.cos());
    [
        c * a * (b[0] - b[1]),
        c * a * (b[3] - b[2]),
        z * (b[0] + b[1] + b[2] + b[3]),
    ]
}

/// RDI's matrix from the instrument's axes to earth's (east, north, up) for a heading,
/// pitch and roll in radians.
pub fn instrument_to_earth([h, p, r]: Vec3) -> Mat3 {
    let (sh, ch, sp, cp, sr, cr) = (h.sin(), h.cos(), p.sin(), p.cos(), r.sin(), r.cos());
    [
        [ch * cr + sh * sp * sr, sh * cp, ch * sr - sh * sp * cr],
        [-sh * cr + ch * sp * sr, ch * cp, -sh * sr - ch * sp * cr],
        [-cp * sr, sp, cp * cr],
    ]
}

/// The ensemble's roll, pitch and yaw (this tool's order), degrees, as its velocities
/// are turned by: the pitch as a gimbal's where the internal tilt sensor gave it.
pub fn roll_pitch_yaw_deg(ensemble: &Ensemble) -> Vec3 {
    let [heading, pitch, roll] = ensemble.attitude_deg;
    let pitch = match ensemble.leader.sensor_source & 0b1000 != 0 {
        true => (pitch.to_radians().tan() * roll.to_radians().cos())
            .atan()
            .to_degrees(),
        false => pitch,
    };
    [roll, pitch, heading]
}

/// Ship or earth axes turned back into the instrument's: earth's by the ensemble's
/// heading (taken as beam 3's), pitch and roll, ship's by EA and, where they were
/// levelled, pitch and roll (RDI builds both with one matrix).
fn to_instrument(axes: Vec3, ensemble: &Ensemble) -> Vec3 {
    let leader = &ensemble.leader;
    let [heading, pitch, roll] = ensemble.attitude_deg.map(f64::to_radians);
    let (pitch, roll) = match leader.tilts_used {
        false => (0.0, 0.0),
        // The internal tilt sensor's pitch is not a gimbal's (EZ bit 3).
        true if leader.sensor_source & 0b1000 != 0 => ((pitch.tan() * roll.cos()).atan(), roll),
        true => (pitch, roll),
    };
    // Ship axes are the instrument's turned by EA (and levelled where tilts were used).
    let heading = match leader.frame {
        Frame::Earth => heading,
        _ => leader.heading_alignment_deg.to_radians(),
    };
    apply(
        &transpose(&instrument_to_earth([heading, pitch, roll])),
        axes,
    )
}

/// The vehicle's velocity in the DVL's axes (forward, starboard, down) from the
/// bottom's in the instrument's, turned by the heading alignment EA.
fn vehicle_axes([x, y, z]: Vec3, leader: &FixedLeader) -> Vec3 {
    let [forward, starboard, down] = [-y, -x, z];
    let alignment = leader.heading_alignment_deg.to_radians();
    apply(&rotation_z(alignment), [forward, starboard, down])
}
