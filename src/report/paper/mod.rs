//! The room of the paper's experiment (a spec without `kind`): what a Monte Carlo run's
//! results folder is reported as, built with the kit. In: a [`StoredRun`] (or a stored
//! sweep of runs). Out: its report, its printed tables and its figures. In data-flow
//! order:
//!
//! - [`source`] and [`tables`]: the paper's tables of a run ([`ReportTables`]) in its
//!   layout, each cell found once among its rows and set beside its published value,
//!   those off by more than the spec's tolerance flagged;
//! - [`calibration_time`]: how long each method needs to calibrate, and the paper's
//!   claim of a calibration 80 % shorter, as sections of the kit's model;
//! - [`markdown`] and [`latex`]: the run's `report.md` (the tables with their
//!   captions, the training summary, wall time per stage, provenance from the manifest,
//!   the figures) and `report.tex` (the tables as booktabs tables);
//! - [`printed`]: the calibration and evaluation tables `run` prints;
//! - [`figures`]: the run's figures, one file per figure or family;
//! - [`sweep`]: the figures of a sweep of runs, drawn from its `sweep.parquet`.
//!
//! [`StoredRun`]: crate::results::read::StoredRun

pub mod source;
pub mod tables;
pub mod calibration_time;
pub mod markdown;
pub mod latex;
pub mod printed;
pub mod figures;
pub mod sweep;

pub use tables::ReportTables;
