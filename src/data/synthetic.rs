//! AUV-like synthetic recordings for runs without the Snapir data: the vehicle speeds
//! up from rest, cruises on straight legs at speeds drawn from a range, turns between
//! legs (a short sway in the body frame), heaves gently, and ends with a drift at the
//! surface where waves move it up and down. Body-frame velocity in m/s, one sample per
//! `1 / sample_rate_hz` seconds, drawn from a generator seeded by the spec seed and the
//! trajectory's name.

use crate::Vec3;
use crate::rng::task_rng;
use crate::spec::Spec;
use rand::RngExt;
use rand_distr::{Distribution, StandardNormal};
use std::f64::consts::TAU;

/// Largest change of forward speed, m/s².
const ACCELERATION_M_S2: f64 = 0.05;
/// Forward speed while drifting at the surface, m/s.
const SURFACE_SPEED_M_S: f64 = 0.3;
/// Vertical velocity amplitude from the waves at the surface, m/s.
const SURFACE_WAVE_M_S: f64 = 0.15;
/// Period of the waves and of the submerged heave, s.
const WAVE_PERIOD_S: f64 = 8.0;
const HEAVE_PERIOD_S: f64 = 45.0;
/// Sway per unit of forward speed and turn rate (rad/s): the vehicle skids in a turn.
const SWAY_PER_TURN: f64 = 2.0;

/// `samples` of the synthetic trajectory `name`.
pub fn generate(name: &str, samples: usize, spec: &Spec) -> Vec<Vec3> {
    let params = &spec.synthetic;
    let dt = 1.0 / spec.sample_rate_hz;
    let mut rng = task_rng(spec.seed, &[&"synthetic", &name]);
    let surface_start = samples.saturating_sub((params.surface_s / dt).round() as usize);
    let recording_noise = params.recording_noise_cm_s / 100.0;
    let heave_phase = rng.random_range(0.0..TAU);

    let mut speed = 0.0;
    let mut target_speed = 0.0;
    let mut leg_left_s = 0.0;
    let mut turn_left_s = 0.0;
    let mut turn_rate = 0.0;
    let mut velocities = Vec::with_capacity(samples);
    for i in 0..samples {
        let t = i as f64 * dt;
        let at_surface = i >= surface_start;
        if leg_left_s <= 0.0 {
            let [low, high] = params.speed_m_s;
            target_speed = rng.random_range(low..=high);
            let [shortest, longest] = params.leg_duration_s;
            leg_left_s = rng.random_range(shortest..=longest);
            turn_left_s = rng.random_range(10.0..=40.0_f64).min(leg_left_s / 2.0);
            turn_rate = rng
                .random_range(-params.turn_rate_deg_s..=params.turn_rate_deg_s)
                .to_radians();
        }
        let wanted = if at_surface {
            SURFACE_SPEED_M_S
        } else {
            target_speed
        };
        speed += (wanted - speed).clamp(-ACCELERATION_M_S2 * dt, ACCELERATION_M_S2 * dt);
        let turning = if turn_left_s > 0.0 && !at_surface {
            turn_rate
        } else {
            0.0
        };
        let heave = if at_surface {
            SURFACE_WAVE_M_S * (TAU * t / WAVE_PERIOD_S).sin()
        } else {
            params.heave_amplitude_m_s * (TAU * t / HEAVE_PERIOD_S + heave_phase).sin()
        };
        let clean = [speed, SWAY_PER_TURN * speed * turning, heave];
        velocities.push(std::array::from_fn(|axis| {
            let noise: f64 = StandardNormal.sample(&mut rng);
            clean[axis] + recording_noise * noise
        }));
        leg_left_s -= dt;
        turn_left_s -= dt;
    }
    velocities
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::{ground_truth, norm};
    use crate::spec::quick_spec;

    #[test]
    fn trajectories_are_auv_like_and_repeatable() {
        let spec = quick_spec(&[]);
        let a = generate("S1", 1200, &spec);
        assert_eq!(a, generate("S1", 1200, &spec));
        assert_ne!(a, generate("S2", 1200, &spec));
        let gt = ground_truth(&a, 5);
        let cruise = &gt[300..1200 - 120];
        let mean_speed = cruise.iter().map(|v| norm(*v)).sum::<f64>() / cruise.len() as f64;
        assert!(
            (1.0..=2.1).contains(&mean_speed),
            "cruise speed {mean_speed}"
        );
        assert!(
            cruise.iter().all(|v| v[2].abs() < 0.1),
            "heave stays small while submerged"
        );
        let surface = &gt[1200 - 40..];
        assert!(
            surface.iter().all(|v| v[0] < 1.0),
            "the vehicle slows down at the surface"
        );
    }
}
