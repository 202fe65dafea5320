//! Synthetic recordings of an installed DVL beside an INS reference, written in the
//! A-KIT format (a DVL file and a reference file per trajectory), with known
//! installation terms: the known answer of the installation study's end-to-end tests.
//! The motion is analytic (turns, speed changes, pitch), so the reference at t + τ and
//! the body rate are exact.

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use std::fmt::Write;
use std::path::Path;

/// The terms a synthetic DVL is installed with.
#[derive(Debug, Clone, Copy)]
pub struct Installed {
    pub scale: f64,
    pub lever_arm_m: [f64; 3],
    pub time_offset_s: f64,
    pub bias_m_s: [f64; 3],
    pub noise_m_s: f64,
}

/// The installation the end-to-end tests recover: the DVL 1.9 m aft of the
/// reference point and 0.4 m below it, its stamps 0.6 s ahead, 1 % scale, a small bias.
pub const INSTALLED: Installed = Installed {
    scale: 0.01,
    lever_arm_m: [-1.9, 0.05, 0.4],
    time_offset_s: 0.6,
    bias_m_s: [0.01, -0.005, 0.003],
    noise_m_s: 0.02,
};

/// What a trajectory does with its heading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// Turns of up to about 12°/s one way and the other, and speed changes: the shape
    /// the end-to-end tests calibrate on.
    Turning,
    /// The heading held, the same speed changes.
    Straight,
    /// A survey's lines: 100-s legs at a steady speed, each joined to the next by a
    /// 30-s half turn, the next one the other way.
    Lawnmower,
    /// Circles one way, then the other: the turn rate a sine of 200 s.
    FigureEight,
    /// 80-s legs and 40-s half turns, every turn the same way.
    Racetrack,
}

impl Shape {
    /// The shapes held out from the end-to-end tests' `Turning`: surveys at a steady
    /// speed whose turns alone show the lever arm and the clock.
    pub const SURVEYS: [Shape; 3] = [Shape::Lawnmower, Shape::FigureEight, Shape::Racetrack];

    fn steady(self) -> bool {
        !matches!(self, Shape::Turning | Shape::Straight)
    }
}

/// Yaw (rad) and its rate at `t` for legs of `leg_s` joined by half turns of `turn_s`
/// whose rate rises and falls as 1 − cos; each turn the other way where `alternate`.
fn legs_and_turns(t: f64, leg_s: f64, turn_s: f64, alternate: bool) -> (f64, f64) {
    use std::f64::consts::PI;
    let cycle = leg_s + turn_s;
    let n = (t / cycle).floor();
    let within = t - n * cycle;
    let way = |i: f64| {
        if alternate && i % 2.0 == 1.0 {
            -1.0
        } else {
            1.0
        }
    };
    let before = if alternate { PI * (n % 2.0) } else { PI * n };
    if within < leg_s {
        return (before, 0.0);
    }
    let w = within - leg_s;
    let phase = 2.0 * PI * w / turn_s;
    let rate = PI / turn_s * (1.0 - phase.cos());
    let turned = PI / turn_s * (w - turn_s / (2.0 * PI) * phase.sin());
    (before + way(n) * turned, way(n) * rate)
}

/// Roll, pitch, yaw (rad) and their rates at `t` for trajectory `k` of `shape`, with
/// a slow pitch and roll.
fn attitude(t: f64, k: usize, shape: Shape) -> ([f64; 3], [f64; 3]) {
    use std::f64::consts::PI;
    let phase = 0.7 * k as f64;
    let w = 2.0 * PI / (60.0 + 10.0 * k as f64);
    let heading = 0.3 * k as f64;
    let (yaw, yaw_rate) = match shape {
        Shape::Turning => {
            let amplitude = 1.6;
            (
                amplitude * (w * t + phase).sin() + heading,
                amplitude * w * (w * t + phase).cos(),
            )
        }
        Shape::Straight => (heading, 0.0),
        Shape::Lawnmower => {
            let (yaw, rate) = legs_and_turns(t, 100.0, 30.0, true);
            (yaw + heading, rate)
        }
        Shape::Racetrack => {
            let (yaw, rate) = legs_and_turns(t, 80.0, 40.0, false);
            (yaw + heading, rate)
        }
        Shape::FigureEight => {
            let period = 200.0;
            let peak = 2.0 * PI * PI / period;
            let u = 2.0 * PI * t / period;
            (heading - PI * u.cos(), peak * u.sin())
        }
    };
    let wp = 2.0 * PI / 90.0;
    let pitch = 0.08 * (wp * t).sin();
    let pitch_rate = 0.08 * wp * (wp * t).cos();
    let roll = 0.03 * (wp * 1.7 * t).cos();
    let roll_rate = -0.03 * wp * 1.7 * (wp * 1.7 * t).sin();
    ([roll, pitch, yaw], [roll_rate, pitch_rate, yaw_rate])
}

/// C_b^n for roll, pitch, yaw (aerospace ZYX).
fn body_to_ned([roll, pitch, yaw]: [f64; 3]) -> [[f64; 3]; 3] {
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sy, cy) = yaw.sin_cos();
    [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
}

/// The body velocity (m/s) at `t`: surge with speed changes (a survey's held within
/// 5 cm/s), a little heave.
fn body_velocity(t: f64, k: usize, shape: Shape) -> [f64; 3] {
    let change = if shape.steady() { 0.05 } else { 0.3 };
    let surge = 1.8 + change * (2.0 * std::f64::consts::PI * t / (75.0 + 5.0 * k as f64)).sin();
    [surge, 0.0, 0.05 * (t / 13.0).sin()]
}

/// The body rate (p, q, r) from the Euler angles and their rates.
fn body_rate([roll, pitch, _]: [f64; 3], [droll, dpitch, dyaw]: [f64; 3]) -> [f64; 3] {
    [
        droll - dyaw * pitch.sin(),
        dpitch * roll.cos() + dyaw * roll.sin() * pitch.cos(),
        -dpitch * roll.sin() + dyaw * roll.cos() * pitch.cos(),
    ]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Writes `TrajectoryN/DVL_trajectoryN.csv` and `GT_trajectoryN.csv` for N = 1..=count
/// into `folder`, 400 samples at 1 Hz each; trajectories listed in `straight` hold
/// their heading.
pub fn write_installed(
    folder: &Path,
    count: usize,
    straight: &[usize],
    installed: Installed,
    seed: u64,
) {
    write_installed_sampled(folder, count, straight, installed, seed, (400, 1.0));
}

/// [`write_installed`] with `(rows, step_s)`: that many samples, that far apart.
pub fn write_installed_sampled(
    folder: &Path,
    count: usize,
    straight: &[usize],
    installed: Installed,
    seed: u64,
    sampling: (usize, f64),
) {
    write_installed_at_rates(folder, count, straight, installed, seed, sampling, 1);
}

/// [`write_installed_sampled`] with the DVL at every `dvl_every`-th of the reference's
/// `rows` only: the reference at 1 / `step_s` Hz, the DVL at a `dvl_every`-th of it.
pub fn write_installed_at_rates(
    folder: &Path,
    count: usize,
    straight: &[usize],
    installed: Installed,
    seed: u64,
    (rows, step_s): (usize, f64),
    dvl_every: usize,
) {
    let shapes: Vec<Shape> = (1..=count)
        .map(|n| match straight.contains(&n) {
            true => Shape::Straight,
            false => Shape::Turning,
        })
        .collect();
    write_shaped(folder, &shapes, installed, seed, (rows, step_s), dvl_every);
}

/// Trajectory N = 1, 2, … of `folder` in the shape `shapes[N − 1]`, as
/// [`write_installed_at_rates`] writes them.
pub fn write_shaped(
    folder: &Path,
    shapes: &[Shape],
    installed: Installed,
    seed: u64,
    (rows, step_s): (usize, f64),
    dvl_every: usize,
) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let noise = Normal::new(0.0, installed.noise_m_s).unwrap();
    for (n, &shape) in (1..).zip(shapes) {
        let segment = folder.join(format!("Trajectory{n}"));
        std::fs::create_dir_all(&segment).unwrap();
        let mut dvl = String::from("Time [s],DVL X [m/s],DVL Y [m/s],DVL Z [m/s]\n");
        let mut reference = String::from(
            "Time [s],Longitude [rad],Latitude [rad],Altitude [m],V North [m/s],V East [m/s],V Down [m/s],Roll [rad],Pitch [rad],Yaw [rad]\n",
        );
        for i in 0..rows {
            let t = i as f64 * step_s;
            let (angles, _) = attitude(t, n, shape);
            let c = body_to_ned(angles);
            let v_b = body_velocity(t, n, shape);
            let v_n: Vec<f64> = (0..3)
                .map(|r| (0..3).map(|k| c[r][k] * v_b[k]).sum())
                .collect();
            // Yaw as an INS records it: wrapped to (−π, π].
            let yaw = (angles[2] + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
                - std::f64::consts::PI;
            writeln!(
                reference,
                "{t},0.6,0.57,-20.0,{},{},{},{},{},{yaw}",
                v_n[0], v_n[1], v_n[2], angles[0], angles[1]
            )
            .unwrap();
            if i % dvl_every != 0 {
                continue;
            }
            let later = t + installed.time_offset_s;
            let (angles, rates) = attitude(later, n, shape);
            let omega = body_rate(angles, rates);
            let lever = cross(omega, installed.lever_arm_m);
            let v = body_velocity(later, n, shape);
            let measured: Vec<f64> = (0..3)
                .map(|a| {
                    (1.0 + installed.scale) * (v[a] + lever[a])
                        + installed.bias_m_s[a]
                        + noise.sample(&mut rng)
                })
                .collect();
            writeln!(dvl, "{t},{},{},{}", measured[0], measured[1], measured[2]).unwrap();
        }
        std::fs::write(segment.join(format!("DVL_trajectory{n}.csv")), dvl).unwrap();
        std::fs::write(segment.join(format!("GT_trajectory{n}.csv")), reference).unwrap();
    }
}

/// The columns of a reference file [`add_positions`] wrote, with its positions, as
/// `--columns` reads them.
pub const COLUMNS_WITH_POSITIONS: &str = "[columns]\ntime = \"Time [s]\"\ndvl = [\"DVL X [m/s]\", \"DVL Y [m/s]\", \"DVL Z [m/s]\"]\nvelocity_ned = [\"V North [m/s]\", \"V East [m/s]\", \"V Down [m/s]\"]\nattitude = [\"Roll [rad]\", \"Pitch [rad]\", \"Yaw [rad]\"]\nnorth_east = [\"North [m]\", \"East [m]\"]\n";

/// Adds to the reference file `path` its positions, north and east of its first, m (its
/// north and east velocity summed over time by the trapezoidal rule), as the columns
/// `North [m]` and `East [m]`; each row's time and position.
pub fn add_positions(path: &Path) -> Vec<(f64, [f64; 2])> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let mut rows = vec![format!("{},North [m],East [m]", lines.next().unwrap())];
    let mut positions: Vec<(f64, [f64; 2])> = Vec::new();
    let mut previous = None::<(f64, [f64; 2])>;
    for line in lines {
        let cells: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        let (t, velocity) = (cells[0], [cells[4], cells[5]]);
        let position = match (previous, positions.last()) {
            (Some((before_s, before)), Some((_, at))) => {
                [0, 1].map(|k| at[k] + 0.5 * (t - before_s) * (before[k] + velocity[k]))
            }
            _ => [0.0; 2],
        };
        rows.push(format!("{line},{},{}", position[0], position[1]));
        positions.push((t, position));
        previous = Some((t, velocity));
    }
    std::fs::write(path, rows.join("\n") + "\n").unwrap();
    positions
}

/// An installation spec over `count` trajectories in `data/<folder>/` of `dir`.
pub fn write_study_spec(dir: &Path, name: &str, folder: &str, count: usize, extra: &str) {
    let mut text = format!("name = \"{name}\"\nkind = \"installation\"\n\n[recordings]\n");
    for n in 1..=count {
        text.push_str(&format!(
            "\n[[recordings.trajectories]]\nname = \"S{n}\"\ndvl = \"../data/{folder}/Trajectory{n}/DVL_trajectory{n}.csv\"\nreference = \"../data/{folder}/Trajectory{n}/GT_trajectory{n}.csv\"\n"
        ));
    }
    text.push_str(
        "\n[noise]\ndvl_cm_s = 2.0\nreference_cm_s = 0.0\n\n[calibration]\nwindow_s = [100.0, 400.0]\nmethods = [\"baseline\", \"EM5\"]\n\n[[calibration.models]]\nname = \"lever+offset+bias+scale\"\nterms = [\"lever_arm\", \"time_offset\", \"bias\", \"scale\"]\n",
    );
    text.push_str(extra);
    std::fs::create_dir_all(dir.join("experiments")).unwrap();
    std::fs::write(dir.join(format!("experiments/{name}.toml")), text).unwrap();
}

/// This process's peak resident memory so far, as Linux's `VmHWM` gives it ("1571248
/// kB"), for a benchmark to state; what it says where there is no `/proc`.
pub fn peak_resident_memory() -> String {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|status| {
            let line = status
                .lines()
                .find(|l| l.starts_with("VmHWM:"))?
                .to_string();
            Some(line.trim_start_matches("VmHWM:").trim().to_string())
        })
        .unwrap_or_else(|| "not measured (no /proc/self/status)".into())
}
