//! `cargo bench --bench dvl_log`: an hour of a DVL's PD0 log at 8 Hz (28,800 ensembles,
//! each with a 30-cell velocity, correlation, echo and percent-good profile beside its
//! leaders and bottom track, as a Workhorse records them) read by `dvl_log::read`: the
//! seconds of the read (the median of five), the file's size, and the process's peak
//! resident memory (Linux's VmHWM) before and after the reads, which grows by the
//! samples kept, not by the file (it is streamed in chunks of 1 MiB).

#[allow(dead_code)]
#[path = "../tests/common/pd0.rs"]
mod pd0;

use dcnet_exp::data::paired::dvl_log::{self, LogFormat, Thresholds};
use std::time::Instant;

/// The process's peak resident memory, MiB (Linux), or NaN.
fn peak_mib() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    (status.lines())
        .find_map(|line| line.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn main() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("hour.pd0");
    let setup = pd0::Setup {
        frame: 1,
        beam_angle_code: 2,
        convex: true,
        alignment_deg: 0.0,
    };
    let cells = 30;
    let profile = |id: u16, bytes_per_beam: usize| {
        let mut block = id.to_le_bytes().to_vec();
        block.extend((0..cells * 4 * bytes_per_beam).map(|k| (k % 251) as u8));
        block
    };
    {
        use std::io::Write;
        let mut file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        for k in 0..28_800u32 {
            let t = f64::from(k) * 0.125;
            let ping =
                pd0::Ping::good(1.6e9 + t, [(300.0 * (t * 0.01).sin()) as i16, -1500, 20, 3]);
            let [fixed, variable, bottom] = pd0::blocks(&setup, k + 1, &ping);
            let blocks = [
                fixed,
                variable,
                profile(0x0100, 2),
                profile(0x0200, 1),
                profile(0x0300, 1),
                profile(0x0400, 1),
                bottom,
            ];
            file.write_all(&pd0::framed(&blocks)).unwrap();
        }
    }
    let size_mib = std::fs::metadata(&path).unwrap().len() as f64 / (1 << 20) as f64;
    let before = peak_mib();
    let mut seconds = Vec::new();
    let mut pings = 0;
    for _ in 0..5 {
        let start = Instant::now();
        let log = dvl_log::read(&path, LogFormat::Pd0, Thresholds::default()).unwrap();
        seconds.push(start.elapsed().as_secs_f64());
        pings = log.time_s.len();
    }
    seconds.sort_by(f64::total_cmp);
    println!("| log | file MiB | pings | read s (median of 5) | peak memory MiB before, after |");
    println!("|---|---|---|---|---|");
    println!(
        "| an hour at 8 Hz, PD0 with 30-cell profiles | {size_mib:.1} | {pings} | {:.3} | {before:.1}, {:.1} |",
        seconds[2],
        peak_mib()
    );
}
