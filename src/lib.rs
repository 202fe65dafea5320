//! dcnet-exp does two jobs, each from a TOML spec. It reproduces the experiments of
//! "DCNet: A Data-Driven Framework for DVL Calibration" (Yampolsky & Klein): noisy
//! training sets from AUV recordings, one DCNet trained per error model, every
//! calibration method through the paper's Monte Carlo protocol. And it calibrates a
//! real DVL installation (scale, misalignment, lever arm, time offset, bias) against a
//! reference with attitude: an installation study (`kind = "installation"`) calibrates
//! on each paired recording in turn and scores the terms on the others, with the
//! model-based fit, Kalman filters, the paper's methods and DCNets that learn the
//! installation (`[learned]`); `calibrate` does it for one recording. Both go through
//! one pipeline (docs/architecture.md). The modules, in data-flow order, each importing
//! only modules above it in this list:
//!
//! 1. [`spec`]: the TOML experiment spec, read, overridden and swept
//!    ([`spec::load`](mod@spec::load)), checked section by section ([`spec::check`]),
//!    with the [`spec::published`] values it is compared with and the
//!    [`spec::recordings`] it may name;
//! 2. [`data`]: the trajectories (`.npy` or `.csv` recordings, or synthetic) and their
//!    ground truth, the paired recordings of a DVL beside a reference
//!    ([`data::paired`]: one way in, a [`data::paired::Source`] read into a
//!    [`data::paired::ReadRecording`] with its files' SHA-256, checked whatever its
//!    format), and the published recordings ([`data::catalogue`]) and their download
//!    ([`data::fetch`]);
//! 3. [`noise`]: the beam-level DVL and GNSS-RTK measurement model, and [`bound`]: the
//!    information bound it puts on any calibration from w seconds of data, and
//!    [`kalman`]: the recursive estimate of the terms, sample by sample;
//! 4. [`dataset`]: the training windows over the error-term grid;
//! 5. [`kernels`]: the network's hot operations on burn's CPU backend, [`model`],
//!    [`rmsprop`] and [`train`]: DCNet, its optimizer and its closed-loop training;
//! 6. [`estimators`]: calibration methods behind one trait, DCNet among them;
//! 7. [`evaluate`]: the paper's Monte Carlo calibration and evaluation protocol (its
//!    runs, the tables summed from them, the bound's efficiency); [`installation`]: a
//!    real installation's terms ([`installation::terms`]), their estimates
//!    ([`installation::estimate`]: fit, bound, clock, joint fit, Kalman filter), the
//!    study of an installation ([`installation::study`]: its spec and held-out
//!    protocol) and the DCNets of `[learned]` ([`installation::learned`]); and [`footprint`]:
//!    the memory and time a spec asks for, known before it runs;
//! 8. [`results`]: the results folders of both kinds (Parquet tables and manifest,
//!    written atomically), the corrected recording of `calibrate` and `correct`, and a
//!    sweep's table;
//! 9. [`operator`]: the operator's commands on recordings of their own: `calibrate`
//!    (one recording, or several jointly), the saved installation file, and `correct`;
//! 10. [`report`]: what is drawn from results folders alone: a rendering kit
//!    ([`report::kit`]: one table model of the report set as Markdown and as LaTeX, the
//!    drawing kit of the figures, how numbers and terms are written), then one room per
//!    content, each with its tables, printed text and figures: the paper's experiment
//!    ([`report::paper`]), the installation study ([`report::study`]), the operator's
//!    commands ([`report::operator`]), and two folders compared ([`report::compare`]);
//! 11. [`pipeline`]: the one front door of a run of either kind, planned, keyed by
//!     content (datasets) and cached by content (models, Monte Carlo blocks,
//!     calibrations), resumable, and shared out over shards;
//! 12. [`cli`]: the subcommands, which read a spec's kind once.
//!
//! Beneath them all, importing no other module: [`vocab`], the words every stage
//! shares (a DVL's error terms, error models, methods, corrections, activation,
//! backend, stop reason, phase); [`files`], atomic writes and content hashes; [`memory`],
//! the allocator's settings and counts; [`rng`], the seeded streams; [`rotation`], 3×3
//! rotations; and [`progress`], the progress bars. The modules are declared
//! below in this order, and `tests/layering.rs` fails on an import that points up it or
//! on any import cycle in `src/`.

pub mod files;
pub mod memory;
pub mod progress;
pub mod rng;
pub mod rotation;
pub mod vocab;

pub mod spec;
pub mod data;
pub mod noise;
pub mod bound;
pub mod kalman;
pub mod dataset;
pub mod kernels;
pub mod model;
pub mod rmsprop;
pub mod train;
pub mod estimators;
pub mod evaluate;
pub mod installation;
pub mod footprint;
pub mod results;
pub mod operator;
pub mod report;
pub mod pipeline;
pub mod cli;

/// A velocity (or any xyz vector): x, y, z in m/s unless a name says otherwise.
pub type Vec3 = [f64; 3];

/// The names of a velocity's x, y, z columns: in `trajectories.parquet`, and the
/// columns read from a `.csv` recording whose spec names none.
pub const VELOCITY_COLUMNS: [&str; 3] = ["vx_m_s", "vy_m_s", "vz_m_s"];

/// A number as a message shows it: as Rust writes it, but in scientific notation
/// where that would run to more than 15 digits or start with more than four zeros
/// (`1e200`, not two hundred digits).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shown(pub f64);

impl std::fmt::Display for Shown {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let magnitude = self.0.abs();
        if magnitude == 0.0 || !magnitude.is_finite() || (1e-4..1e15).contains(&magnitude) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// A computed number as a message shows it: three significant figures, at least two
/// decimals (a variance factor of 0.00432 is not 0.00, a ratio of 5890.76 not
/// 5890.756046138612), and in scientific notation from 1e15 on (not 300 digits).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThreeFigures(pub f64);

impl std::fmt::Display for ThreeFigures {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let value = self.0;
        if value.is_finite() && value.abs() >= 1e15 {
            return write!(f, "{value:.2e}");
        }
        let decimals = match value.is_finite() && value != 0.0 {
            true => (2 - value.abs().log10().floor() as i32).max(2) as usize,
            false => 2,
        };
        write!(f, "{value:.decimals$}")
    }
}

/// `n` of `what`, with a plural `s` where `n` is not 1: `1 model`, `5 models`.
pub fn count(n: usize, what: &str) -> String {
    match n {
        1 => format!("1 {what}"),
        _ => format!("{n} {what}s"),
    }
}

/// The median of `values` (the upper of the middle two where their count is even);
/// NaN where there are none.
pub fn median(values: &[f64]) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.get(sorted.len() / 2).copied().unwrap_or(f64::NAN)
}

/// The distinct values of `values`, in the order they first appear.
pub fn first_seen<T: PartialEq>(values: impl IntoIterator<Item = T>) -> Vec<T> {
    let mut seen = Vec::new();
    for value in values {
        if !seen.contains(&value) {
            seen.push(value);
        }
    }
    seen
}

#[cfg(test)]
mod tests {
    use super::ThreeFigures;

    #[test]
    fn a_computed_number_keeps_three_figures_and_two_decimals() {
        let shown = |value| ThreeFigures(value).to_string();
        assert_eq!(shown(0.004321), "0.00432");
        assert_eq!(shown(0.0321), "0.0321");
        assert_eq!(shown(1.0749), "1.07");
        assert_eq!(shown(5890.756046138612), "5890.76");
        assert_eq!(shown(0.0), "0.00");
        assert_eq!(shown(1e308), "1.00e308");
    }
}
