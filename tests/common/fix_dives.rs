//! Synthetic dives for a fit to position fixes, written from the model in
//! docs/installation.md alone (not from the tool's own prediction): a horizontal
//! vehicle on an analytic track (a weaving transect, a three-petal clover, a widening
//! spiral), its heading the track's course plus a slow crab of ±4°, the attitude at
//! 10 Hz, the DVL at 2 Hz on its own clock, the fixes every 5 s on the attitude's clock,
//! late by a latency, each with white noise; the DVL's noise white or AR(1) in time.
//!
//! The DVL sample stamped t measures, at t + τ, v_dvl = (1 + s) · Rz(δz)ᵀ · [C_n^b ·
//! v_n + ω_b × l] + noise, with C_n^b = Rz(ψ)ᵀ and ω_b = (0, 0, ψ̇) for a level vehicle;
//! the fix stamped t is the reference point's position at t − latency.

use dcnet_exp::Vec3;
use dcnet_exp::data::fixes::Fixes;
use dcnet_exp::installation::estimate::fixes::{FIX_LATENCY, FixFit};
use dcnet_exp::installation::frames::Attitude;
use dcnet_exp::installation::terms::Installation;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};
use std::f64::consts::PI;

/// How long each dive lasts, s.
pub const DIVE_S: f64 = 600.0;

/// The DVL's sample interval, s, and its white noise per axis per sample, m/s.
pub const DVL_STEP_S: f64 = 0.5;
pub const DVL_NOISE_M_S: f64 = 0.03;

/// The interval between fixes, s.
pub const FIX_INTERVAL_S: f64 = 5.0;

/// A case of the coverage study: the fixes' noise per axis, m; the DVL noise's AR(1)
/// correlation from one sample to the next (0 for white); the DVL's clock τ, s; the
/// fixes' latency, s; and how far each fix's own noise spreads about `fix_m`, as a
/// factor (1: every fix's is `fix_m`, and the fixes carry none of their own; 4: each
/// fix's is drawn log-uniform from a quarter to four times `fix_m`, and carried with it,
/// as a USBL's covariance grows with its range); and whether the fit estimates the
/// fixes' latency.
#[derive(Debug, Clone, Copy)]
pub struct Case {
    pub fix_m: f64,
    pub correlation: f64,
    pub clock_s: f64,
    pub latency_s: f64,
    pub noise_spread: f64,
    pub fits_latency: bool,
}

/// The installation of every dive, the clock of `case`: the independent check's.
pub fn truth(case: &Case) -> Installation {
    Installation {
        scale: [0.007; 3],
        misalignment_rad: [0.0, 0.0, 1.1f64.to_radians()],
        lever_arm_m: [0.3, -0.6, 0.0],
        time_offset_s: case.clock_s,
        bias_m_s: [0.0; 3],
    }
}

/// The three tracks, in turn by seed.
#[derive(Debug, Clone, Copy)]
enum Track {
    Weave,
    Clover,
    Spiral,
}

impl Track {
    /// Position (north, east), m, and velocity, m/s, at `t`.
    fn at(self, t: f64) -> ([f64; 2], [f64; 2]) {
        match self {
            Track::Weave => {
                let (speed, amplitude, period) = (1.5, 40.0, 120.0);
                let w = 2.0 * PI / period;
                (
                    [speed * t, amplitude * (w * t).sin()],
                    [speed, amplitude * w * (w * t).cos()],
                )
            }
            Track::Clover => {
                // r = R cos 3θ, θ = ωt: speed Rω √(9 sin² 3θ + cos² 3θ).
                let (radius, w) = (150.0, 0.0048);
                let theta = w * t + 0.1;
                let r = radius * (3.0 * theta).cos();
                let dr = -3.0 * radius * (3.0 * theta).sin() * w;
                let (c, s) = (theta.cos(), theta.sin());
                ([r * c, r * s], [dr * c - r * s * w, dr * s + r * c * w])
            }
            Track::Spiral => {
                let (w, r0, growth) = (0.03, 40.0, 0.1);
                let r = r0 + growth * t;
                let (c, s) = ((w * t).cos(), (w * t).sin());
                (
                    [r * c, r * s],
                    [growth * c - r * w * s, growth * s + r * w * c],
                )
            }
        }
    }

    /// The heading, rad, unwrapped by continuity from `before`: the course plus a crab
    /// of ±4° over 47 s.
    fn heading(self, t: f64, before: f64) -> f64 {
        let (_, v) = self.at(t);
        let course = v[1].atan2(v[0]) + 4f64.to_radians() * (2.0 * PI * t / 47.0).sin();
        course + 2.0 * PI * ((before - course) / (2.0 * PI)).round()
    }
}

/// One dive: the DVL's stamps and velocities, the attitude and the fixes.
pub struct Dive {
    pub time_s: Vec<f64>,
    pub dvl_m_s: Vec<Vec3>,
    pub attitude: Attitude,
    pub fixes: Fixes,
}

/// The dive of `seed` under `case`, [`DIVE_S`] long with a fix every
/// [`FIX_INTERVAL_S`], on each track in turn by seed.
pub fn dive(case: &Case, seed: u64) -> Dive {
    let track = [Track::Weave, Track::Clover, Track::Spiral][seed as usize % 3];
    dive_on(track, case, seed, (DIVE_S, FIX_INTERVAL_S))
}

/// A weaving transect of `dive_s` seconds with a fix every `fix_interval_s`, under
/// `case` (the benchmark's long dives: the other tracks leave a bounded area).
pub fn long_dive(case: &Case, seed: u64, (dive_s, fix_interval_s): (f64, f64)) -> Dive {
    dive_on(Track::Weave, case, seed, (dive_s, fix_interval_s))
}

/// The dive of `seed` on `track` under `case`.
fn dive_on(track: Track, case: &Case, seed: u64, (dive_s, fix_interval_s): (f64, f64)) -> Dive {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let unit = Normal::new(0.0, 1.0).unwrap();
    let truth = truth(case);
    // The attitude at 10 Hz over the dive and 5 s either side.
    let attitude_time: Vec<f64> = (0..((dive_s + 10.0) * 10.0) as usize + 1)
        .map(|i| -5.0 + 0.1 * i as f64)
        .collect();
    let mut heading = 0.0;
    let angles: Vec<Vec3> = (attitude_time.iter())
        .map(|&t| {
            heading = track.heading(t, heading);
            [0.0, 0.0, heading]
        })
        .collect();
    let heading_at = |t: f64| track.heading(t, heading_near(&attitude_time, &angles, t));
    let time_s: Vec<f64> = (0..(dive_s / DVL_STEP_S) as usize + 1)
        .map(|i| i as f64 * DVL_STEP_S)
        .collect();
    let (rho, mut noise) = (case.correlation, [0.0; 3]);
    let dvl_m_s = (time_s.iter())
        .map(|&stamp| {
            let t = stamp + truth.time_offset_s;
            let (_, v) = track.at(t);
            let psi = heading_at(t);
            let rate = (heading_at(t + 1e-4) - heading_at(t - 1e-4)) / 2e-4;
            // C_n^b v_n + ω × l, then Rz(δz)ᵀ and the scale.
            let body = rotate_z_transposed(psi, [v[0], v[1]]);
            let point = [
                body[0] - rate * truth.lever_arm_m[1],
                body[1] + rate * truth.lever_arm_m[0],
            ];
            let dvl = rotate_z_transposed(truth.misalignment_rad[2], point);
            for n in &mut noise {
                *n = rho * *n + (1.0 - rho * rho).sqrt() * DVL_NOISE_M_S * unit.sample(&mut rng);
            }
            let s = 1.0 + truth.scale[0];
            [s * dvl[0] + noise[0], s * dvl[1] + noise[1], noise[2]]
        })
        .collect();
    let fix_time: Vec<f64> = (0..(dive_s / fix_interval_s) as usize)
        .map(|k| fix_interval_s / 2.0 + fix_interval_s * k as f64)
        .collect();
    // Drawn only where they spread, so that the other cases' draws stay as they were.
    let own_noise_m: Vec<f64> = (fix_time.iter())
        .map(|_| match case.noise_spread == 1.0 {
            true => case.fix_m,
            false => case.fix_m * case.noise_spread.powf(2.0 * rng.random::<f64>() - 1.0),
        })
        .collect();
    let north_east_m = (fix_time.iter().zip(&own_noise_m))
        .map(|(&t, &noise_m)| {
            let (p, _) = track.at(t - case.latency_s);
            [0, 1].map(|k| p[k] + noise_m * unit.sample(&mut rng))
        })
        .collect();
    Dive {
        time_s,
        dvl_m_s,
        attitude: Attitude::new(&attitude_time, &angles),
        fixes: Fixes {
            lines: (0..fix_time.len() as u64).collect(),
            time_s: fix_time,
            north_east_m,
            depth_m: None,
            noise_m: (case.noise_spread != 1.0).then_some(own_noise_m),
        },
    }
}

/// Writes `dive` into `folder` as a user's files: the DVL (`dvl.csv`) and the attitude
/// (`attitude.csv`) in A-KIT's columns, the fixes (`fixes.csv`: `t`, `n`, `e`, metres)
/// and `columns.toml` naming the fixes' columns; the paths of the first three.
pub fn write(dive: &Dive, folder: &std::path::Path) -> [std::path::PathBuf; 3] {
    use std::fmt::Write;
    let mut dvl = String::from("Time [s],DVL X [m/s],DVL Y [m/s],DVL Z [m/s]\n");
    for (t, v) in dive.time_s.iter().zip(&dive.dvl_m_s) {
        writeln!(dvl, "{t},{},{},{}", v[0], v[1], v[2]).unwrap();
    }
    let mut attitude = String::from("Time [s],Roll [rad],Pitch [rad],Yaw [rad]\n");
    for (t, a) in dive.attitude.time_s.iter().zip(&dive.attitude.angles_rad) {
        writeln!(attitude, "{t},{},{},{}", a[0], a[1], a[2]).unwrap();
    }
    let mut fixes = String::from("t,n,e\n");
    for (t, p) in dive.fixes.time_s.iter().zip(&dive.fixes.north_east_m) {
        writeln!(fixes, "{t},{},{}", p[0], p[1]).unwrap();
    }
    let columns = "[fix_columns]\ntime = \"t\"\nnorth_east = [\"n\", \"e\"]\n";
    std::fs::write(folder.join("columns.toml"), columns).unwrap();
    let files = ["dvl.csv", "attitude.csv", "fixes.csv"].map(|name| folder.join(name));
    for (path, text) in files.iter().zip([dvl, attitude, fixes]) {
        std::fs::write(path, text).unwrap();
    }
    files
}

/// The unwrapped heading sampled nearest `t`, to unwrap another by.
fn heading_near(time_s: &[f64], angles: &[Vec3], t: f64) -> f64 {
    let i = time_s.partition_point(|&s| s < t).min(time_s.len() - 1);
    angles[i][2]
}

/// Rz(a)ᵀ · (x, y): a horizontal vector turned into axes yawed by a.
fn rotate_z_transposed(a: f64, v: [f64; 2]) -> [f64; 2] {
    let (c, s) = (a.cos(), a.sin());
    [c * v[0] + s * v[1], -s * v[0] + c * v[1]]
}

/// The fits of `dives` dives of `case` (seeds 0 on), `None` for each refused; and the
/// truth of each of their parameters (the fixes' latency last).
pub fn fits(case: &Case, dives: u64) -> (Vec<Option<FixFit>>, Vec<f64>) {
    use dcnet_exp::installation::estimate::fixes::{
        FixNoise, FixTerms, default_fix_terms, fit_fixes,
    };
    use dcnet_exp::installation::terms::names::term_set;
    use rayon::prelude::*;
    let terms = FixTerms {
        set: term_set(&default_fix_terms()),
        fix_latency: case.fits_latency,
    };
    let mut truth = truth(case).to_parameters(&terms.set);
    truth.push(case.latency_s);
    let fits = (0..dives)
        .into_par_iter()
        .map(|seed| {
            let dive = dive(case, seed);
            let pieces = vec![0..dive.time_s.len()];
            let dvl = (&dive.time_s[..], &dive.dvl_m_s[..]);
            // The fixes' own noise where they carry it, their median standing for
            // them, as `calibrate --fixes-topic` takes it.
            let fix_m = dive
                .fixes
                .noise_m
                .as_deref()
                .map_or(case.fix_m, dcnet_exp::median);
            let noise = FixNoise {
                fix_m,
                depth_m: fix_m,
                dvl_m_s: DVL_NOISE_M_S,
            };
            fit_fixes(dvl, &pieces, &dive.attitude, &dive.fixes, terms, noise).ok()
        })
        .collect();
    (fits, truth)
}

/// Of `dives` dives of `case` (seeds 0 on), per term estimated: the share of those that
/// applied it whose 95 % interval holds the truth, and how many applied it; and how
/// many dives the fit refused.
pub fn coverage(case: &Case, dives: u64) -> (Vec<(&'static str, f64, usize)>, usize) {
    let (fits, truth) = fits(case, dives);
    coverage_of(&fits, &truth)
}

/// Of `fits` (`None` for a dive refused) of parameters whose truth is `truth`, per term
/// estimated (a clock that is the sum of itself and the fixes' latency against the sum
/// of their truths): the share of those that applied it whose 95 % interval holds the
/// truth, and how many applied it; and how many dives were refused.
pub fn coverage_of(
    fits: &[Option<FixFit>],
    truth: &[f64],
) -> (Vec<(&'static str, f64, usize)>, usize) {
    let refused = fits.iter().filter(|f| f.is_none()).count();
    let fits: Vec<Vec<(&'static str, Option<bool>)>> = (fits.iter().flatten())
        .map(|fit| {
            // A clock that carries the fixes' latency too is their sum.
            let latency = (fit.bound.names.iter()).position(|n| *n == FIX_LATENCY);
            (0..fit.bound.names.len())
                .filter(|&k| fit.estimated[k])
                .map(|k| {
                    let truth = match (fit.bound.names[k], latency) {
                        ("time_offset_s", Some(l)) if fit.clock_is_the_sum() => truth[k] + truth[l],
                        _ => truth[k],
                    };
                    let error = (fit.bound.value[k] - truth).abs();
                    let covered = error <= fit.bound.half_width_95(k);
                    (fit.bound.names[k], fit.bound.applied[k].then_some(covered))
                })
                .collect()
        })
        .collect();
    let names: Vec<&'static str> = fits[0].iter().map(|(name, _)| *name).collect();
    let table = (names.iter().enumerate())
        .map(|(k, &name)| {
            let applied: Vec<bool> = fits.iter().filter_map(|fit| fit[k].1).collect();
            let covered = applied.iter().filter(|&&inside| inside).count();
            let share = covered as f64 / applied.len().max(1) as f64;
            (name, share, applied.len())
        })
        .collect();
    (table, refused)
}

/// How often a joint calibration's intervals hold, per vehicle term, over `fits` taken
/// four at a time (each group's dives of the same truth `truth`): the first three
/// calibrated jointly, the fourth the next dive. The shares of groups whose joint
/// estimate ± 1.96 standard deviations, whose vehicle's 95 % interval (where the dives
/// differ) and whose next dive's 95 % interval (the fourth dive's own estimate) hold
/// the truth, of the groups whose four dives were fitted and applied the term (their
/// count last).
pub fn joint_coverage(
    fits: &[Option<FixFit>],
    truth: &[f64],
) -> Vec<(&'static str, [f64; 3], usize)> {
    use dcnet_exp::installation::estimate::fix_joint::fix_vehicle;
    let groups: Vec<Vec<FixFit>> = (fits.chunks_exact(4))
        .filter_map(|group| group.iter().cloned().collect::<Option<Vec<FixFit>>>())
        .collect();
    let names = fix_vehicle(&groups[0][..3], &["time_offset_s"]).names;
    let (mut held, mut shown) = (vec![[0usize; 3]; names.len()], vec![0; names.len()]);
    for group in &groups {
        let vehicle = fix_vehicle(&group[..3], &["time_offset_s"]);
        let next = &group[3];
        for (i, name) in vehicle.names.iter().enumerate() {
            let k = next
                .bound
                .names
                .iter()
                .position(|n| n == name)
                .expect("a term");
            let Some(between) = vehicle.between[i].filter(|_| next.bound.applied[k]) else {
                continue;
            };
            let inside = |(low, high): (f64, f64), x: f64| low <= x && x <= high;
            let joint = (vehicle.value[i] - truth[k]).abs() <= 1.96 * vehicle.std[i];
            let counts = [
                joint,
                inside(between.vehicle_95(), truth[k]),
                inside(between.next_dive_95(), next.bound.value[k]),
            ];
            for (count, inside) in held[i].iter_mut().zip(counts) {
                *count += usize::from(inside);
            }
            shown[i] += 1;
        }
    }
    (names.into_iter().zip(held).zip(shown))
        .map(|((name, held), shown)| (name, held.map(|c| c as f64 / shown.max(1) as f64), shown))
        .collect()
}
