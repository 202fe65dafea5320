//! `cargo bench --bench calibrate`: `calibrate` (fit, bound, Kalman filter, settling
//! curve, corrected files) on synthetic recordings at 100 Hz of 36,000 and 360,000 rows,
//! and with `-- --long` 3,600,000 (ten hours). Prints the seconds of each and the
//! seconds per 100,000 rows, which stays flat where the cost is linear in the
//! recording's length.

#[allow(dead_code)]
#[path = "../tests/common/installed.rs"]
mod installed;

use dcnet_exp::installation::term_names::TermName;
use dcnet_exp::results::calibrate::{CalibrateArgs, calibrate};
use std::time::Instant;

fn main() {
    let long = std::env::args().any(|a| a == "--long");
    let mut rows = vec![36_000, 360_000];
    if long {
        rows.push(3_600_000);
    }
    let terms = [
        TermName::LeverArm,
        TermName::TimeOffset,
        TermName::Bias,
        TermName::Scale,
    ];
    println!("| rows (100 Hz) | hours | calibrate s | s per 100,000 rows |");
    println!("|---|---|---|---|");
    for rows in rows {
        let dir = tempfile::tempdir().unwrap();
        installed::write_installed_sampled(
            dir.path(),
            1,
            &[],
            installed::INSTALLED,
            7,
            (rows, 0.01),
        );
        let segment = dir.path().join("Trajectory1");
        let dvl = segment.join("DVL_trajectory1.csv");
        let reference = segment.join("GT_trajectory1.csv");
        let out = dir.path().join("out");
        let args = CalibrateArgs {
            dvl: &dvl,
            reference: Some(&reference),
            columns: None,
            terms: &terms,
            window_s: None,
            dvl_noise_cm_s: 2.0,
            reference_noise_cm_s: 0.5,
            tolerance_pct: 10.0,
            out: &out,
        };
        let clock = Instant::now();
        let calibration = calibrate(&args).expect("the synthetic recording calibrates");
        let seconds = clock.elapsed().as_secs_f64();
        assert_eq!(calibration.recorded, rows);
        println!(
            "| {rows} | {:.1} | {seconds:.1} | {:.2} |",
            rows as f64 / 360_000.0,
            seconds / rows as f64 * 100_000.0
        );
    }
}
