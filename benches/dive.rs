//! `cargo bench --bench dive`: the operator's two costs beside the recording's length.
//! `correct` of a dive at 10 Hz of a quarter, a half and a whole hour with an
//! installation saved from a 400-s calibration (its clock found again from the first
//! 60 s, the dive corrected and written, CSV and Parquet); and the joint calibration of
//! 10, 30 and 100 synthetic segments of 400 s at 1 Hz, each with its own clock (the
//! vehicle's lever arm, scale and bias shared). Prints the seconds of each, and per
//! 100,000 rows or per segment, which stay flat where the cost is linear. With
//! `-- --hour correct` or `-- --hour joint`, a case of its own instead: `correct` of an
//! hour's dive at 100 Hz (360,000 rows, its clock found again from the first 60 s), or
//! the joint `calibrate` of two such dives, with the process's peak resident memory.
//! With `-- --memory`: each command's peak resident memory, run as the binary on dives
//! of one and five hours, beside the estimate with which it refuses a recording beyond
//! the machine's memory before reading it (`-- --memory fixes`: `calibrate --fixes`
//! alone). With `-- --bag`: `calibrate` of a ROS 2 bag
//! (MCAP) of an hour's dive, the INS at 100 Hz and the DVL at 10 Hz, alone and beside a
//! camera topic the reading passes over, its seconds and peak resident memory. With
//! `-- --address-limits`: each command under an address-space limit of 60 MB to 2 GB,
//! finished or refused up front, never aborted.

#[allow(dead_code)]
#[path = "../tests/common/installed.rs"]
mod installed;

use dcnet_exp::data::paired::{PairedColumns, PairedFiles, read};
use dcnet_exp::installation::estimate::bound::{DEFAULT_TOLERANCES, Noise};
use dcnet_exp::installation::estimate::fit::fit;
use dcnet_exp::installation::estimate::joint::{JointRecording, joint_fit, starts_from};
use dcnet_exp::installation::frames::Reference;
use dcnet_exp::installation::terms::names::TermName;
use dcnet_exp::installation::terms::{PerAxis, TermSet};
use dcnet_exp::operator::calibrate::{CalibrateArgs, calibrate};
use dcnet_exp::operator::calibrate_joint::{JointArgs, calibrate_joint};
use dcnet_exp::operator::correct::{CorrectArgs, correct};
use dcnet_exp::operator::inputs::Reading;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(at) = args.iter().position(|a| a == "--hour") {
        return hour(args.get(at + 1).map(String::as_str));
    }
    if args.iter().any(|a| a == "--memory") {
        return memory();
    }
    if args.iter().any(|a| a == "--bag") {
        return bag();
    }
    if args.iter().any(|a| a == "--address-limits") {
        return address_limits();
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let saved = saved_installation(d);
    println!("| dive at 10 Hz | rows | correct s | s per 100,000 rows |");
    println!("|---|---|---|---|");
    for minutes in [15, 30, 60] {
        let rows = minutes * 600;
        let dive = d.join(format!("dive{minutes}"));
        let clocked = installed::Installed {
            time_offset_s: 7.3,
            ..installed::INSTALLED
        };
        installed::write_installed_sampled(&dive, 1, &[], clocked, 2, (rows, 0.1));
        let at = dive.join("Trajectory1");
        let (dvl, reference) = (
            at.join("DVL_trajectory1.csv"),
            at.join("GT_trajectory1.csv"),
        );
        let clock = Instant::now();
        let corrected = corrected((&dvl, &reference), &saved, &dive.join("out"));
        let seconds = clock.elapsed().as_secs_f64();
        let found = corrected.applied.time_offset_s;
        assert!((found - 7.3).abs() < 0.1, "the clock found again: {found}");
        println!(
            "| {minutes} min | {rows} | {seconds:.2} | {:.2} |",
            seconds / rows as f64 * 1e5
        );
    }
    println!();
    println!("| segments of 400 s at 1 Hz | joint fit s | s per segment |");
    println!("|---|---|---|");
    let noise = Noise {
        dvl_m_s: 0.02,
        reference_m_s: 0.005,
    };
    let set = TermSet {
        scale: PerAxis::Scalar,
        lever_arm: true,
        time_offset: true,
        bias: PerAxis::PerAxis,
        ..TermSet::NONE
    };
    let clock_only = TermSet {
        time_offset: true,
        ..TermSet::NONE
    };
    for count in [10, 30, 100] {
        let folder = d.join(format!("segments{count}"));
        let recordings: Vec<_> = (0..count)
            .map(|k| {
                let installed = installed::Installed {
                    time_offset_s: -2.0 + 4.0 * k as f64 / count as f64,
                    ..installed::INSTALLED
                };
                let at = folder.join(format!("s{k}"));
                installed::write_installed(&at, 1, &[], installed, 100 + k as u64);
                let recording = read(&PairedFiles::akit(&at, 1), &PairedColumns::akit()).unwrap();
                let reference = Reference::new(&recording);
                (recording, reference)
            })
            .collect();
        let joint: Vec<JointRecording> = recordings
            .iter()
            .map(|(r, reference)| JointRecording {
                time_s: &r.time_s,
                dvl_m_s: &r.dvl_m_s,
                reference,
            })
            .collect();
        let clock = Instant::now();
        let first = fit(joint[0].time_s, joint[0].dvl_m_s, joint[0].reference, set).unwrap();
        let starts = starts_from(&joint, first.installation, 30.0);
        let fitted = joint_fit(
            &joint,
            &starts,
            (set, clock_only),
            (noise, &DEFAULT_TOLERANCES),
        )
        .expect("the segments calibrate jointly");
        let seconds = clock.elapsed().as_secs_f64();
        assert_eq!(fitted.dives.len(), count);
        println!("| {count} | {seconds:.2} | {:.3} |", seconds / count as f64);
    }
}

/// The `--hour` case: `correct` (`which` = "correct") or the joint `calibrate` ("joint")
/// of dives of an hour at 100 Hz, each on its own clock.
fn hour(which: Option<&str>) {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let rows = 360_000;
    // The first within the ±3 s a fit alone scans (a joint calibration starts from its
    // fit), the second's clock found by the search.
    let dives: Vec<_> = [1.3, 7.3]
        .iter()
        .enumerate()
        .map(|(k, &time_offset_s)| {
            let at = d.join(format!("dive{k}"));
            let clocked = installed::Installed {
                time_offset_s,
                ..installed::INSTALLED
            };
            installed::write_installed_sampled(&at, 1, &[], clocked, 3 + k as u64, (rows, 0.01));
            let at = at.join("Trajectory1");
            (
                at.join("DVL_trajectory1.csv"),
                at.join("GT_trajectory1.csv"),
            )
        })
        .collect();
    let terms = [TermName::LeverArm, TermName::TimeOffset, TermName::Bias];
    let clock = Instant::now();
    match which {
        Some("correct") => {
            let saved = saved_installation(d);
            let clock = Instant::now();
            let corrected = corrected((&dives[1].0, &dives[1].1), &saved, &d.join("out"));
            let found = corrected.applied.time_offset_s;
            assert!((found - 7.3).abs() < 0.1, "the clock found again: {found}");
            report("correct", clock.elapsed().as_secs_f64());
        }
        Some("joint") => {
            let (dvls, references): (Vec<_>, Vec<_>) = dives.into_iter().unzip();
            let joint = calibrate_joint(&JointArgs {
                dvls: &dvls,
                references: &references,
                columns: None,
                reading: Reading::default(),
                terms: &terms,
                dive_terms: &[TermName::TimeOffset],
                window_s: None,
                dvl_noise_cm_s: 2.0,
                reference_noise_cm_s: 0.5,
                tolerance_pct: 10.0,
                out: &d.join("joint"),
                save: None,
                search_s: None,
            })
            .expect("the dives calibrate jointly");
            let found = joint.joint.dives[1].time_offset_s;
            assert!((found - 7.3).abs() < 0.1, "the second clock: {found}");
            report("joint calibrate", clock.elapsed().as_secs_f64());
        }
        _ => panic!("--hour takes correct or joint"),
    }
}

/// The `--memory` case: each command run as the binary, on dives of one and five hours
/// at 100 Hz (the DVL at 100 Hz, and at 10 Hz beside the reference at 100 Hz), its peak
/// resident memory beside the estimate that refuses it up front
/// ([`dcnet_exp::operator::cost`]).
fn memory() {
    use dcnet_exp::operator::cost::{CALIBRATE, CORRECT, Cost, FIXES, JOINT, PerRow, Rows};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let saved = saved_installation(d);
    // (name, rows at 100 Hz, the DVL at every n-th, its clock): the clock within the
    // ±3 s a fit alone scans, as a joint calibration's first recording needs.
    let dives = [
        ("1 h, DVL 100 Hz", 360_000, 1, 1.3),
        ("1 h, DVL 10 Hz", 360_000, 10, 1.3),
        ("5 h, DVL 100 Hz", 1_800_000, 1, 1.3),
    ];
    let files: Vec<(String, std::path::PathBuf, std::path::PathBuf)> = dives
        .iter()
        .enumerate()
        .map(|(k, &(name, rows, every, time_offset_s))| {
            let at = d.join(format!("dive{k}"));
            let clocked = installed::Installed {
                time_offset_s,
                ..installed::INSTALLED
            };
            installed::write_installed_at_rates(&at, 1, &[], clocked, 3, (rows, 0.01), every);
            let at = at.join("Trajectory1");
            let dvl = at.join("DVL_trajectory1.csv");
            (name.to_string(), dvl, at.join("GT_trajectory1.csv"))
        })
        .collect();
    println!("| command | recordings | rows | peak resident memory | estimate | bytes per row |");
    println!("|---|---|---|---|---|---|");
    let run = |per_row: PerRow, chosen: &[usize], extra: &[&str]| {
        let paths = |k: usize| (files[k].1.as_path(), Some(files[k].2.as_path()));
        let cost = Cost::of(
            per_row,
            &chosen.iter().map(|&k| paths(k)).collect::<Vec<_>>(),
        )
        .unwrap();
        let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_dcnet-exp"));
        command.arg(if per_row == CORRECT {
            "correct"
        } else {
            "calibrate"
        });
        command.args(chosen.iter().map(|&k| &files[k].1));
        for &k in chosen {
            command.arg("--reference").arg(&files[k].2);
        }
        let out = format!("out-{}-{}", per_row.command, chosen.len() * 10 + chosen[0]);
        command
            .args(extra)
            .arg("--out")
            .arg(d.join(out.replace(' ', "-")));
        let peak = peak_of(command);
        let names: Vec<&str> = chosen.iter().map(|&k| files[k].0.as_str()).collect();
        println!(
            "| {} | {} | {} | {:.0} MB | {:.0} MB | {:.0} |",
            per_row.command,
            names.join(" + "),
            cost.rows(),
            peak / 1e6,
            cost.need / 1e6,
            peak / cost.rows() as f64
        );
    };
    let installation = ["--installation", saved.to_str().unwrap()];
    // `-- --memory fixes`: `calibrate --fixes` alone.
    let only_fixes = std::env::args().any(|a| a == "fixes");
    for k in (0..dives.len()).filter(|_| !only_fixes) {
        run(CALIBRATE, &[k], &[]);
        run(CORRECT, &[k], &installation);
    }
    if !only_fixes {
        run(JOINT, &[0, 1], &[]);
        run(JOINT, &[2, 0], &[]);
    }
    // `calibrate --fixes`: the reference's own positions as fixes, every second of the
    // DVL at 100 Hz, and ten a second (a fix-heavy recording) of the DVL at 10 Hz.
    // Their dives have no bias, which fixes do not calibrate.
    let unbiased = installed::Installed {
        bias_m_s: [0.0; 3],
        ..installed::INSTALLED
    };
    for (k, every) in [(0, 100), (1, 10)] {
        let (name, rows, dvl_every, _) = dives[k];
        let at = d.join(format!("fixes{k}"));
        installed::write_installed_at_rates(&at, 1, &[], unbiased, 3, (rows, 0.01), dvl_every);
        let at = at.join("Trajectory1");
        let (dvl, reference) = (
            at.join("DVL_trajectory1.csv"),
            at.join("GT_trajectory1.csv"),
        );
        let fixes = write_fixes(d, k, (&dvl, &reference), every);
        let rows = Rows::count(&dvl, Some(&reference)).unwrap();
        let cost = Cost::on(
            FIXES,
            vec![rows.with_fixes(&fixes, None).unwrap()],
            f64::INFINITY,
        );
        let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_dcnet-exp"));
        command
            .arg("calibrate")
            .arg(&dvl)
            .arg("--attitude")
            .arg(&reference)
            .arg("--fixes")
            .arg(&fixes)
            .arg("--columns")
            .arg(d.join("fix_columns.toml"))
            .args(["--fix-noise-m", "0.5"])
            .arg("--out")
            .arg(d.join(format!("fixes{k}-out")));
        let peak = peak_of(command);
        println!(
            "| {} | {name}, a fix every {} s | {} | {:.0} MB | {:.0} MB | {:.0} |",
            FIXES.command,
            every as f64 / 100.0,
            cost.rows(),
            peak / 1e6,
            cost.need / 1e6,
            peak / cost.rows() as f64
        );
    }
}

/// Writes the reference's own positions (its NED velocity summed by the trapezoidal
/// rule) at every `every`-th of its rows as fixes in `d`, and the columns that read
/// them: the fixes' path.
fn write_fixes(
    d: &std::path::Path,
    k: usize,
    (dvl, reference): (&std::path::Path, &std::path::Path),
    every: usize,
) -> std::path::PathBuf {
    let files = PairedFiles {
        dvl: dvl.to_path_buf(),
        reference: reference.to_path_buf(),
    };
    let r = read(&files, &PairedColumns::akit()).unwrap();
    let (mut position, mut text) = ([0.0; 2], String::from("t,n,e\n"));
    for i in 0..r.reference_time_s.len() {
        if i > 0 {
            let dt = r.reference_time_s[i] - r.reference_time_s[i - 1];
            for (axis, p) in position.iter_mut().enumerate() {
                *p += 0.5 * dt * (r.velocity_ned_m_s[i][axis] + r.velocity_ned_m_s[i - 1][axis]);
            }
        }
        if i % every == 0 {
            let t = r.reference_time_s[i];
            text.push_str(&format!("{t},{},{}\n", position[0], position[1]));
        }
    }
    let path = d.join(format!("fixes{k}.csv"));
    std::fs::write(&path, text).unwrap();
    std::fs::write(
        d.join("fix_columns.toml"),
        "[fix_columns]\ntime = \"t\"\nnorth_east = [\"n\", \"e\"]\n",
    )
    .unwrap();
    path
}

/// The `--address-limits` case: each operator command on a dive of ten minutes at
/// 100 Hz (calibrate, correct, and the joint calibrate of two such dives), run as the
/// binary under an address-space limit (`ulimit -v`) of 60 MB to 2 GB: whether it
/// finished (0), was refused up front naming the memory (1, and nothing written), or
/// failed otherwise (an abort after it started): the last must never be seen.
fn address_limits() {
    use std::os::unix::process::CommandExt;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let saved = saved_installation(d);
    let at = d.join("dive");
    let clocked = installed::Installed {
        time_offset_s: 1.3,
        ..installed::INSTALLED
    };
    installed::write_installed_at_rates(&at, 2, &[], clocked, 3, (60_000, 0.01), 1);
    let file = |n: usize, name: &str| {
        at.join(format!("Trajectory{n}/{name}_trajectory{n}.csv"))
            .display()
            .to_string()
    };
    let (dvl, reference) = (file(1, "DVL"), file(1, "GT"));
    let installation = saved.display().to_string();
    let commands: [(&str, Vec<String>); 3] = [
        (
            "calibrate",
            vec![
                "calibrate".into(),
                dvl.clone(),
                "--reference".into(),
                reference.clone(),
            ],
        ),
        (
            "correct",
            vec![
                "correct".into(),
                dvl.clone(),
                "--reference".into(),
                reference.clone(),
                "--installation".into(),
                installation,
            ],
        ),
        (
            "joint calibrate",
            vec![
                "calibrate".into(),
                dvl,
                file(2, "DVL"),
                "--reference".into(),
                reference,
                "--reference".into(),
                file(2, "GT"),
            ],
        ),
    ];
    let limits_mb = [
        60, 80, 100, 125, 150, 200, 250, 300, 400, 500, 600, 800, 1000, 1100, 1200, 1500, 2000,
    ];
    println!(
        "| command | threads | {} |",
        limits_mb.map(|mb| format!("{mb} MB")).join(" | ")
    );
    println!("|---|---|{}", "---|".repeat(limits_mb.len()));
    for (name, args) in &commands {
        for threads in [1, 2] {
            let outcomes: Vec<String> = limits_mb
                .iter()
                .map(|&mb| {
                    let out = d.join(format!("out-{name}-{threads}-{mb}").replace(' ', "-"));
                    let limit = mb * 1_000_000u64;
                    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_dcnet-exp"));
                    command
                        .args(["--threads", &threads.to_string()])
                        .args(args)
                        .arg("--out")
                        .arg(&out);
                    // SAFETY: setrlimit only sets the child's own limit, between fork and exec.
                    unsafe {
                        command.pre_exec(move || {
                            let rlimit = libc::rlimit {
                                rlim_cur: limit,
                                rlim_max: limit,
                            };
                            match libc::setrlimit(libc::RLIMIT_AS, &rlimit) {
                                0 => Ok(()),
                                _ => Err(std::io::Error::last_os_error()),
                            }
                        });
                    }
                    let output = command.output().unwrap();
                    let stderr = String::from_utf8_lossy(&output.stderr);
                    match output.status.code() {
                        Some(0) => "done".to_string(),
                        Some(1) if stderr.contains("this process may use") && !out.exists() => {
                            "refused".to_string()
                        }
                        other => format!("**failed ({other:?})**"),
                    }
                })
                .collect();
            println!("| {name} | {threads} | {} |", outcomes.join(" | "));
        }
    }
}

/// The `--bag` case: `calibrate` of an hour's dive as an MCAP bag (`Odometry` at 100
/// Hz, `Dvl` at 10 Hz), alone and with a camera topic of 1 MB a second beside it (3.6
/// GB), run as the binary: seconds and peak resident memory of each, and the bag's
/// size.
fn bag() {
    use dcnet_exp::data::paired::bag::write::{Format, RosLayout, write_recording};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    installed::write_installed_at_rates(d, 1, &[], installed::INSTALLED, 3, (360_000, 0.01), 10);
    let files = PairedFiles {
        dvl: d.join("Trajectory1/DVL_trajectory1.csv"),
        reference: d.join("Trajectory1/GT_trajectory1.csv"),
    };
    let recording = read(&files, &PairedColumns::akit()).unwrap();
    println!("| bag (MCAP, zstd chunks) | size | calibrate s | peak resident memory |");
    println!("|---|---|---|---|");
    for (name, other) in [
        ("navigation only", 0),
        ("beside a camera of 1 MB/s", 1 << 20),
    ] {
        let path = d.join(format!("dive-{other}.mcap"));
        let layout = RosLayout {
            other_bytes_per_s: other,
            ..RosLayout::default()
        };
        write_recording(&recording, &path, Format::Mcap { compressed: true }, layout).unwrap();
        let size = std::fs::metadata(&path).unwrap().len();
        let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_dcnet-exp"));
        command
            .arg("calibrate")
            .arg(&path)
            .arg("--out")
            .arg(d.join(format!("out-{other}")));
        let start = Instant::now();
        let peak = peak_of(command);
        println!(
            "| {name} | {:.0} MB | {:.1} | {:.0} MB |",
            size as f64 / 1e6,
            start.elapsed().as_secs_f64(),
            peak / 1e6
        );
    }
}

/// Runs `command` to its end (it must succeed): its peak resident memory, bytes, as the
/// kernel counted it for the child.
fn peak_of(mut command: std::process::Command) -> f64 {
    // The child starts on this process's pages, and its peak starts at this process's
    // peak: hand the freed pages (the dives written) back, and start the peak again
    // (Linux's clear_refs "5").
    // SAFETY: malloc_trim only returns free memory of glibc's heap to the kernel.
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    unsafe {
        libc::malloc_trim(0);
    }
    let _ = std::fs::write("/proc/self/clear_refs", "5");
    let stderr = tempfile::tempfile().unwrap();
    let child = command
        .stdout(std::process::Stdio::null())
        .stderr(stderr.try_clone().unwrap())
        .spawn()
        .unwrap();
    let (mut status, mut usage) = (0, unsafe { std::mem::zeroed::<libc::rusage>() });
    // SAFETY: waits for the child just spawned, writing its status and usage.
    let waited = unsafe { libc::wait4(child.id() as i32, &mut status, 0, &mut usage) };
    assert_eq!(waited, child.id() as i32);
    if !(libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0) {
        use std::io::{Read, Seek};
        let (mut stderr, mut said) = (stderr, String::new());
        stderr.rewind().unwrap();
        stderr.read_to_string(&mut said).unwrap();
        panic!("{command:?} failed:\n{said}");
    }
    usage.ru_maxrss as f64 * 1024.0
}

/// Prints the `--hour` case's line.
fn report(what: &str, seconds: f64) {
    println!("| an hour at 100 Hz (360,000 rows) | s | peak resident memory |");
    println!("|---|---|---|");
    println!(
        "| {what} | {seconds:.1} | {} |",
        installed::peak_resident_memory()
    );
}

/// The installation `calibrate --save` finds on 400 s at 1 Hz (lever arm, time offset,
/// bias, scale), saved in `d`: its path.
fn saved_installation(d: &std::path::Path) -> std::path::PathBuf {
    installed::write_installed(&d.join("calibration"), 1, &[], installed::INSTALLED, 1);
    let at = d.join("calibration/Trajectory1");
    let saved = d.join("installation.toml");
    calibrate(&CalibrateArgs {
        dvl: &at.join("DVL_trajectory1.csv"),
        reference: Some(&at.join("GT_trajectory1.csv")),
        columns: None,
        reading: Reading::default(),
        terms: &[
            TermName::LeverArm,
            TermName::TimeOffset,
            TermName::Bias,
            TermName::Scale,
        ],
        window_s: None,
        dvl_noise_cm_s: 2.0,
        reference_noise_cm_s: 0.5,
        tolerance_pct: 10.0,
        out: &d.join("calibrated"),
        save: Some(&saved),
        dive_terms: &[TermName::TimeOffset],
        search_s: None,
    })
    .expect("the synthetic recording calibrates");
    saved
}

/// `correct` of the dive (`dvl`, `reference`) with the installation `saved`, its clock
/// found again from the first 60 s, into `out`.
fn corrected(
    (dvl, reference): (&std::path::Path, &std::path::Path),
    saved: &std::path::Path,
    out: &std::path::Path,
) -> dcnet_exp::operator::correct::Correction {
    correct(&CorrectArgs {
        dvl,
        reference: Some(reference),
        columns: None,
        reading: Reading::default(),
        installation: saved,
        window_s: 60.0,
        search_s: 30.0,
        time_offset_s: None,
        out,
    })
    .expect("the dive is corrected")
}
