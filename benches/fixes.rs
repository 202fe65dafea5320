//! `cargo bench --bench fixes`: a fit to position fixes, its cost and its intervals.
//! First its time and peak resident memory at 10,000 and 100,000 fixes (a weaving
//! transect with a fix every second and the DVL at 2 Hz, each size in a process of its
//! own), which grow linearly with the fixes: the fixes' noise is whitened by a Kalman
//! filter, never held as an n × n covariance. Then the coverage of every applied term's
//! 95 % interval over 400 synthetic dives (`tests/common/fix_dives.rs`) in each case of
//! the study in docs/installation.md: fixes of 0.5, 2 and 5 m, DVL noise white and
//! AR(1) 0.8 and 0.9, clocks of 0, 0.6 and 1.5 s, fixes' latencies of 0 and 1 s (fitted
//! with `--fix-latency`'s parameter, and once not, to show what a latency left out
//! does), and fixes each of its own noise (a quarter to four times 1 m, as a bag's
//! covariances give them); each level in at least one case; the tests assert two of them. With `-- --fixes N`: one fit of N fixes, its seconds and
//! peak memory (what the first part runs); with `-- --coverage`: the coverage alone; with
//! `-- --coverage K`: only the table's row K (from 1).

#[allow(dead_code)]
#[path = "../tests/common/fix_dives.rs"]
mod fix_dives;

use dcnet_exp::installation::estimate::fixes::{FixNoise, default_fix_terms, fit_fixes};
use dcnet_exp::installation::terms::names::term_set;
use fix_dives::{Case, DVL_NOISE_M_S, coverage, long_dive};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(at) = args.iter().position(|a| a == "--fixes") {
        let count = args
            .get(at + 1)
            .and_then(|n| n.parse().ok())
            .expect("--fixes N");
        return one_fit(count);
    }
    let coverage_at = args.iter().position(|a| a == "--coverage");
    let only_row: Option<usize> = coverage_at
        .and_then(|at| args.get(at + 1))
        .map(|k| k.parse().expect("--coverage K, a row from 1"));
    if coverage_at.is_none() {
        println!("| fixes | seconds | peak resident memory, MB |\n|---|---|---|");
        for count in [10_000, 100_000] {
            let output = std::process::Command::new(std::env::current_exe().unwrap())
                .args(["--fixes", &count.to_string()])
                .output()
                .expect("the benchmark runs itself");
            print!("{}", String::from_utf8_lossy(&output.stdout));
        }
    }
    println!(
        "\n| fixes, m | DVL noise | clock, s | fixes' latency, s | dives refused | scale | yaw | lever arm x | lever arm y | clock | latency |\n|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for (row, case) in CASES.into_iter().enumerate() {
        if only_row.is_some_and(|k| k != row + 1) {
            continue;
        }
        let (table, refused) = coverage(&case, 400);
        let mut shares: Vec<String> = (table.iter())
            .map(|(_, share, applied)| format!("{:.1} % of {applied}", 100.0 * share))
            .collect();
        let noise = match case.correlation {
            0.0 => "white".to_string(),
            rho => format!("AR(1) {rho}"),
        };
        let latency = match case.fits_latency {
            true => format!("{}, fitted", case.latency_s),
            false => format!("{}, not fitted", case.latency_s),
        };
        if !case.fits_latency {
            shares.push("–".into());
        }
        let fixes = match case.noise_spread {
            1.0 => format!("{}", case.fix_m),
            spread => format!("{}, each its own (÷{spread} to ×{spread})", case.fix_m),
        };
        println!(
            "| {fixes} | {noise} | {} | {latency} | {refused} | {} |",
            case.clock_s,
            shares.join(" | ")
        );
    }
}

/// The cases of the coverage study.
const CASES: [Case; 10] = [
    case(0.5, 0.0, 0.0),
    Case {
        noise_spread: 4.0,
        ..case(1.0, 0.0, 0.6)
    },
    case(2.0, 0.0, 1.5),
    case(0.5, 0.8, 0.6),
    case(0.5, 0.9, 0.6),
    case(2.0, 0.9, 0.0),
    case(5.0, 0.9, 0.6),
    late(0.5, true),
    late(2.0, true),
    late(2.0, false),
];

/// Fixes of `fix_m` a second late, white DVL noise, a clock of 0.6 s; the latency
/// fitted or not.
const fn late(fix_m: f64, fits_latency: bool) -> Case {
    Case {
        latency_s: 1.0,
        fits_latency,
        ..case(fix_m, 0.0, 0.6)
    }
}

const fn case(fix_m: f64, correlation: f64, clock_s: f64) -> Case {
    Case {
        fix_m,
        correlation,
        clock_s,
        latency_s: 0.0,
        noise_spread: 1.0,
        fits_latency: false,
    }
}

/// One fit of `count` fixes, a second apart, fixes of 2 m: prints its row of the table.
fn one_fit(count: usize) {
    let case = case(2.0, 0.0, 0.6);
    let dive = long_dive(&case, 1, (count as f64, 1.0));
    let noise = FixNoise {
        fix_m: case.fix_m,
        depth_m: case.fix_m,
        dvl_m_s: DVL_NOISE_M_S,
    };
    let terms = term_set(&default_fix_terms());
    let started = Instant::now();
    let pieces = vec![0..dive.time_s.len()];
    let dvl = (&dive.time_s[..], &dive.dvl_m_s[..]);
    let fit = fit_fixes(dvl, &pieces, &dive.attitude, &dive.fixes, terms, noise).expect("a fit");
    let seconds = started.elapsed().as_secs_f64();
    assert_eq!(
        fit.fitted + fit.outliers.len(),
        dive.fixes.len() - fit.outside
    );
    println!("| {count} | {seconds:.1} | {:.0} |", peak_resident_mb());
}

/// This process's peak resident memory, MB (VmHWM).
fn peak_resident_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").expect("/proc/self/status");
    let line = status
        .lines()
        .find(|l| l.starts_with("VmHWM:"))
        .expect("VmHWM");
    let kb: f64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    kb / 1024.0
}
