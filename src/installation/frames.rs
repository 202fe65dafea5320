//! Frames and time: the body-to-NED rotation of an attitude (aerospace ZYX: yaw, then
//! pitch, then roll), the body angular rate from the attitude's Euler-angle rates (yaw
//! unwrapped, central differences) where no rate is recorded, and the reference in the
//! body frame at any time between its samples (linear interpolation).
//! In: a [`PairedRecording`]. Out: a [`Reference`] to read at any time.
//!
//! Frames: NED is north, east, down; the body frame is x forward, y starboard, z down.
//! Angles are roll φ, pitch θ, yaw ψ in radians; C_b^n = Rz(ψ) · Ry(θ) · Rx(φ) takes a
//! body-frame vector into NED, and C_n^b = (C_b^n)ᵀ takes it back.

use crate::Vec3;
use crate::data::interpolate::Between;
use crate::data::paired::{PairedRecording, REFERENCE_GAP_INTERVALS, sample_interval};
use std::f64::consts::PI;
use std::ops::Range;

pub use crate::rotation::{
    Mat3, apply, body_to_ned, cross, multiply, rotation_x, rotation_y, rotation_z, transpose,
};

/// Angles with the 2π jumps of a wrapped angle removed: each step between neighbours
/// is brought into [−π, π) by whole turns, so a yaw that crosses ±π keeps going.
pub fn unwrap(angles_rad: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(angles_rad.len());
    let mut offset = 0.0;
    for (index, &angle) in angles_rad.iter().enumerate() {
        if index > 0 {
            let step = angle - angles_rad[index - 1];
            offset -= (2.0 * PI) * ((step + PI) / (2.0 * PI)).floor();
        }
        out.push(angle + offset);
    }
    out
}

/// The time derivative of each component of `values`, sampled at `time_s`: a central
/// difference (v[i+1] − v[i−1]) / (t[i+1] − t[i−1]) inside, one-sided at the two ends.
fn derivative(time_s: &[f64], values: &[Vec3]) -> Vec<Vec3> {
    let n = values.len();
    (0..n)
        .map(|i| {
            let (before, after) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let span_s = time_s[after] - time_s[before];
            [0, 1, 2].map(|k| (values[after][k] - values[before][k]) / span_s)
        })
        .collect()
}

/// The body angular rate (p, q, r) in rad/s from the attitude (roll, pitch, yaw in
/// radians) and its time derivative, by the ZYX Euler-angle kinematics:
/// p = φ̇ − ψ̇ sinθ, q = θ̇ cosφ + ψ̇ sinφ cosθ, r = −θ̇ sinφ + ψ̇ cosφ cosθ.
pub fn body_rate(attitude_rad: Vec3, attitude_rate_rad_s: Vec3) -> Vec3 {
    let [roll, pitch, _] = attitude_rad;
    let [roll_rate, pitch_rate, yaw_rate] = attitude_rate_rad_s;
    let (sin_roll, cos_roll) = roll.sin_cos();
    let (sin_pitch, cos_pitch) = pitch.sin_cos();
    [
        roll_rate - yaw_rate * sin_pitch,
        pitch_rate * cos_roll + yaw_rate * sin_roll * cos_pitch,
        -pitch_rate * sin_roll + yaw_rate * cos_roll * cos_pitch,
    ]
}

/// An attitude to read at any time: roll, pitch and yaw (unwrapped) at each recorded
/// time, linearly interpolated between two samples no further apart than
/// [`REFERENCE_GAP_INTERVALS`] of its median interval.
#[derive(Debug, Clone)]
pub struct Attitude {
    /// Seconds, strictly increasing.
    pub time_s: Vec<f64>,
    /// Roll, pitch, yaw, radians, yaw unwrapped.
    pub angles_rad: Vec<Vec3>,
    pub max_gap_s: f64,
}

impl Attitude {
    /// The attitude recorded at `time_s` (yaw wrapped or not).
    pub fn new(time_s: &[f64], attitude_rad: &[Vec3]) -> Attitude {
        let yaw: Vec<f64> = attitude_rad.iter().map(|a| a[2]).collect();
        Attitude {
            time_s: time_s.to_vec(),
            angles_rad: (attitude_rad.iter().zip(unwrap(&yaw)))
                .map(|(a, yaw)| [a[0], a[1], yaw])
                .collect(),
            max_gap_s: REFERENCE_GAP_INTERVALS * sample_interval(time_s),
        }
    }

    /// The attitude of a recording's reference.
    pub fn of(recording: &PairedRecording) -> Attitude {
        Attitude::new(&recording.reference_time_s, &recording.attitude_rad)
    }

    /// C_b^n at `time_s`; `None` outside the recorded span or inside a gap.
    pub fn body_to_ned_at(&self, time_s: f64) -> Option<Mat3> {
        let at = Between::locate(&self.time_s, time_s, self.max_gap_s)?;
        Some(body_to_ned(at.of(&self.angles_rad)))
    }
}

/// The reference as the body sees it, at each recorded time.
#[derive(Debug, Clone)]
pub struct Reference {
    /// Seconds, strictly increasing.
    pub time_s: Vec<f64>,
    /// v_b = C_n^b · v_n, m/s: the reference point's velocity in body axes.
    pub velocity_body_m_s: Vec<Vec3>,
    /// ω_b = (p, q, r), rad/s, body axes: recorded, or derived from the attitude.
    pub rate_rad_s: Vec<Vec3>,
    /// The longest interval between two samples read across, s: inside a longer gap
    /// the reference is not read ([`REFERENCE_GAP_INTERVALS`] of its median interval).
    pub max_gap_s: f64,
    /// The recording's gap limit, s: two DVL samples read beside this reference further
    /// apart lie in different pieces ([`PairedRecording::gap_limit_s`]).
    pub dvl_gap_limit_s: f64,
}

/// The reference's body velocity and body rate at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceAt {
    pub velocity_body_m_s: Vec3,
    pub rate_rad_s: Vec3,
}

impl Reference {
    /// The reference of a recording: v_b = C_n^b · v_n at every sample, and ω_b as
    /// recorded, or else from the attitude: yaw unwrapped, the Euler angles
    /// differentiated (central differences inside, one-sided at the ends), then
    /// [`body_rate`]. A recording whose reference has no velocity (an attitude beside
    /// fixes) gives the body rate alone: [`Self::at`] reads nothing of it, and
    /// [`Self::rate_at`] its rate.
    pub fn new(recording: &PairedRecording) -> Self {
        let velocity_body_m_s = recording
            .attitude_rad
            .iter()
            .zip(&recording.velocity_ned_m_s)
            .map(|(&attitude, &velocity)| apply(&transpose(&body_to_ned(attitude)), velocity))
            .collect();
        let rate_rad_s = match &recording.rate_rad_s {
            Some(rate) => rate.clone(),
            None => {
                let yaw: Vec<f64> = recording.attitude_rad.iter().map(|a| a[2]).collect();
                let attitude: Vec<Vec3> = recording
                    .attitude_rad
                    .iter()
                    .zip(unwrap(&yaw))
                    .map(|(a, yaw)| [a[0], a[1], yaw])
                    .collect();
                let attitude_rate = derivative(&recording.reference_time_s, &attitude);
                attitude
                    .iter()
                    .zip(&attitude_rate)
                    .map(|(&angles, &rates)| body_rate(angles, rates))
                    .collect()
            }
        };
        Reference {
            max_gap_s: REFERENCE_GAP_INTERVALS * sample_interval(&recording.reference_time_s),
            dvl_gap_limit_s: recording.gap_limit_s,
            time_s: recording.reference_time_s.clone(),
            velocity_body_m_s,
            rate_rad_s,
        }
    }

    /// The reference at `time_s`, linearly interpolated between the two samples around
    /// it (exact at a sample); `None` outside [t₀, t_N], inside a gap longer than
    /// [`Self::max_gap_s`], or when not finite.
    pub fn at(&self, time_s: f64) -> Option<ReferenceAt> {
        self.read(time_s, self.max_gap_s)
    }

    /// The reference at `time_s` as [`Self::at`] reads it, but across any gap: for a
    /// least-squares fit's trial time offsets, which may step beyond the margin that
    /// keeps its samples clear of the gaps (a fit that ends there fails).
    pub fn across_gaps(&self, time_s: f64) -> Option<ReferenceAt> {
        self.read(time_s, f64::INFINITY)
    }

    /// The body rate at `time_s`, where [`Self::at`] would read the reference (with or
    /// without a velocity): what corrects a DVL's lever arm.
    pub fn rate_at(&self, time_s: f64) -> Option<Vec3> {
        let at = Between::locate(&self.time_s, time_s, self.max_gap_s)?;
        Some(at.of(&self.rate_rad_s))
    }

    /// The reference at `time_s`, read across gaps up to `max_gap_s`.
    fn read(&self, time_s: f64, max_gap_s: f64) -> Option<ReferenceAt> {
        if self.velocity_body_m_s.is_empty() {
            return None;
        }
        let at = Between::locate(&self.time_s, time_s, max_gap_s)?;
        Some(ReferenceAt {
            velocity_body_m_s: at.of(&self.velocity_body_m_s),
            rate_rad_s: at.of(&self.rate_rad_s),
        })
    }

    /// Whether each sample of a DVL record stamped `time_s` follows the one before it
    /// within a piece (no step beyond the recording's gap limit; the first follows
    /// none): where noise correlated in time is read, and not across a gap.
    pub fn follows(&self, time_s: &[f64]) -> Vec<bool> {
        (0..time_s.len())
            .map(|i| i > 0 && time_s[i] - time_s[i - 1] <= self.dvl_gap_limit_s)
            .collect()
    }

    /// The samples of a record stamped `time_s` whose t + τ lies inside the reference
    /// for every |τ| ≤ `margin_s`: a fixed mask, the same whatever τ, so costs at
    /// different τ compare. Empty when there is none.
    pub fn interior(&self, time_s: &[f64], margin_s: f64) -> Range<usize> {
        let (Some(&first), Some(&last)) = (self.time_s.first(), self.time_s.last()) else {
            return 0..0;
        };
        let start = time_s.partition_point(|&t| t - margin_s < first);
        let end = time_s.partition_point(|&t| t + margin_s <= last);
        start..end.max(start)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3, tolerance: f64) -> bool {
        (0..3).all(|k| (a[k] - b[k]).abs() <= tolerance)
    }

    fn recording(
        time_s: Vec<f64>,
        attitude_rad: Vec<Vec3>,
        velocity_ned_m_s: Vec<Vec3>,
    ) -> PairedRecording {
        PairedRecording {
            dvl_m_s: vec![[0.0; 3]; time_s.len()],
            left_out: Vec::new(),
            reference_time_s: time_s.clone(),
            time_s,
            velocity_ned_m_s,
            attitude_rad,
            rate_rad_s: None,
            position_ne_m: None,
            gap_limit_s: 3.0,
            reference_read: None,
        }
    }

    #[test]
    fn heading_east_the_body_x_axis_points_east_and_a_northward_velocity_is_to_port() {
        let c_b_n = body_to_ned([0.0, 0.0, PI / 2.0]);
        assert!(close(
            apply(&c_b_n, [1.0, 0.0, 0.0]),
            [0.0, 1.0, 0.0],
            1e-15
        ));
        // v_b = C_n^b · v_n: north seen from a vehicle heading east is −y (port).
        assert!(close(
            apply(&transpose(&c_b_n), [1.0, 0.0, 0.0]),
            [0.0, -1.0, 0.0],
            1e-15
        ));
    }

    #[test]
    fn pitched_up_the_body_x_axis_points_up_and_rolled_to_starboard_y_points_down() {
        // θ = +90°: nose up, so body x is NED up (−down).
        let pitched = body_to_ned([0.0, PI / 2.0, 0.0]);
        assert!(close(
            apply(&pitched, [1.0, 0.0, 0.0]),
            [0.0, 0.0, -1.0],
            1e-15
        ));
        // φ = +90°: starboard wing down, so body y is NED down.
        let rolled = body_to_ned([PI / 2.0, 0.0, 0.0]);
        assert!(close(
            apply(&rolled, [0.0, 1.0, 0.0]),
            [0.0, 0.0, 1.0],
            1e-15
        ));
    }

    #[test]
    fn the_rotation_is_yaw_then_pitch_then_roll() {
        // Rz(ψ) Ry(θ) Rx(φ) applied to body z: roll first, then pitch, then yaw.
        let (roll, pitch, yaw) = (0.3, -0.2, 2.5);
        let expected = apply(
            &rotation_z(yaw),
            apply(
                &rotation_y(pitch),
                apply(&rotation_x(roll), [0.0, 0.0, 1.0]),
            ),
        );
        let got = apply(&body_to_ned([roll, pitch, yaw]), [0.0, 0.0, 1.0]);
        assert!(close(got, expected, 1e-15));
        // Its (3,3) element is cosθ cosφ.
        assert!((body_to_ned([roll, pitch, yaw])[2][2] - pitch.cos() * roll.cos()).abs() < 1e-15);
    }

    #[test]
    fn a_constant_yaw_rate_through_the_wrap_is_the_body_rate() {
        // 10°/s of yaw, level, crossing ±π many times; the rate must be r = 10°/s
        // everywhere, ends included.
        let yaw_rate_rad_s = 10f64.to_radians();
        let time_s: Vec<f64> = (0..200).map(|i| i as f64 * 0.5).collect();
        let attitude: Vec<Vec3> = time_s
            .iter()
            .map(|t| {
                let yaw = (yaw_rate_rad_s * t + PI).rem_euclid(2.0 * PI) - PI;
                [0.0, 0.0, yaw]
            })
            .collect();
        let reference = Reference::new(&recording(
            time_s.clone(),
            attitude,
            vec![[1.0, 0.0, 0.0]; 200],
        ));
        for rate in &reference.rate_rad_s {
            assert!(close(*rate, [0.0, 0.0, yaw_rate_rad_s], 1e-12), "{rate:?}");
        }
    }

    #[test]
    fn a_yaw_rate_while_pitched_shows_on_x_and_z() {
        // ψ̇ with θ fixed: p = −ψ̇ sinθ, q = 0, r = ψ̇ cosθ.
        let (pitch, yaw_rate) = (0.4, 0.1);
        let time_s: Vec<f64> = (0..20).map(f64::from).collect();
        let attitude: Vec<Vec3> = time_s.iter().map(|t| [0.0, pitch, yaw_rate * t]).collect();
        let reference = Reference::new(&recording(time_s, attitude, vec![[0.0; 3]; 20]));
        let expected = [-yaw_rate * pitch.sin(), 0.0, yaw_rate * pitch.cos()];
        assert!(close(reference.rate_rad_s[7], expected, 1e-12));
    }

    #[test]
    fn a_recorded_rate_is_kept() {
        let mut paired = recording(vec![0.0, 1.0], vec![[0.0; 3]; 2], vec![[0.0; 3]; 2]);
        paired.rate_rad_s = Some(vec![[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]]);
        assert_eq!(
            Reference::new(&paired).rate_rad_s,
            vec![[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]]
        );
    }

    #[test]
    fn interpolation_is_exact_at_samples_linear_between_and_none_outside() {
        let time_s = vec![0.0, 1.0, 3.0];
        let attitude = vec![[0.0; 3]; 3];
        let velocity = vec![[1.0, 2.0, 3.0], [3.0, 2.0, 1.0], [5.0, 0.0, 1.0]];
        let reference = Reference::new(&recording(time_s.clone(), attitude, velocity.clone()));
        for (index, t) in time_s.iter().enumerate() {
            assert_eq!(reference.at(*t).unwrap().velocity_body_m_s, velocity[index]);
        }
        // A quarter of the way from t = 1 to t = 3.
        let between = reference.at(1.5).unwrap().velocity_body_m_s;
        assert!(close(between, [3.5, 1.5, 1.0], 1e-15));
        assert!(reference.at(-1e-9).is_none());
        assert!(reference.at(3.0 + 1e-9).is_none());
        assert!(reference.at(f64::NAN).is_none());
    }

    #[test]
    fn the_interior_keeps_the_samples_a_margin_away_from_the_ends() {
        let time_s: Vec<f64> = (0..400).map(|i| i as f64 * 400.0 / 399.0).collect();
        let recording = recording(time_s.clone(), vec![[0.0; 3]; 400], vec![[0.0; 3]; 400]);
        // Three samples dropped at each end for a 3 s margin at 400/399 s spacing.
        assert_eq!(Reference::new(&recording).interior(&time_s, 3.0), 3..397);
    }
}
