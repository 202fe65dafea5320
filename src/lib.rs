//! dcnet-exp reproduces the experiments of "DCNet: A Data-Driven Framework for DVL
//! Calibration" (Yampolsky & Klein). One experiment flows through the modules in this
//! order:
//!
//! 1. [`spec`]: the TOML experiment spec, read, overridden and checked;
//! 2. [`data`]: the trajectories (`.npy` or `.csv` recordings, or synthetic) and their
//!    ground truth;
//! 3. [`noise`]: the beam-level DVL and GNSS-RTK measurement model;
//! 4. [`dataset`]: the training windows over the error-term grid;
//! 5. [`model`] and [`train`]: DCNet and its closed-loop training;
//! 6. [`estimators`]: calibration methods behind one trait, DCNet among them;
//! 7. [`evaluate`]: the Monte Carlo calibration and evaluation protocol;
//! 8. [`results`] and [`tables`]: Parquet files, manifest, and the printed tables;
//! 9. [`plots`] and [`report`]: the figures and the comparison with the [`published`]
//!    values, drawn from a results folder alone; [`compare`] sets two results folders
//!    side by side;
//! 10. [`pipeline`]: the stages as tasks, cached by content in [`cache`] (with the
//!     models of [`checkpoint`]), resumable, and shared out over shards; a spec's
//!     [`sweep`] runs as many points;
//! 11. [`cli`]: the subcommands.
//!
//! Beneath them all, importing no other module: [`vocab`], the words every stage
//! shares (error models, methods, corrections, activation, backend, stop reason,
//! phase), and [`files`], atomic writes and content hashes. No module imports one
//! that imports it back (`tools/import_cycles.py` checks the whole of `src/`).

pub mod cli;
pub mod data;
pub mod dataset;
pub mod estimators;
pub mod evaluate;
pub mod files;
pub mod model;
pub mod noise;
pub mod pipeline;
pub mod progress;
pub mod report;
pub mod results;
pub mod rng;
pub mod spec;
pub mod train;
pub mod vocab;

/// A velocity (or any xyz vector): x, y, z in m/s unless a name says otherwise.
pub type Vec3 = [f64; 3];

/// The names of a velocity's x, y, z columns: in `trajectories.parquet`, and the
/// columns read from a `.csv` recording whose spec names none.
pub const VELOCITY_COLUMNS: [&str; 3] = ["vx_m_s", "vy_m_s", "vz_m_s"];

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
