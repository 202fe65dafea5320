//! Why a run stopped, for either kind of spec: the one error of
//! [`execute`](super::execute), each variant keeping its cause. In: the stages' own
//! errors. Out: [`ExecuteError`].

use super::cache::{ModelStoreError, calibrations::CalibrationStoreError};
use super::owner::OwnerError;
use super::plan::PlanError;
use super::training::job::TrainingJobError;
use crate::data::paired::PairedError;
use crate::results::{ResultsError, read::ReadError};
use crate::spec::SpecErrors;
use crate::vocab::ErrorModel;
use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum ExecuteError {
    #[error(transparent)]
    Results(#[from] ResultsError),
    #[error(transparent)]
    Read(#[from] ReadError),
    #[error(transparent)]
    Models(#[from] ModelStoreError),
    #[error("{0} is not a finite number; nothing of it is stored")]
    NonFinite(String),
    #[error(transparent)]
    Owner(#[from] OwnerError),
    #[error("{count} tasks are not done yet, so there is nothing to collect:\n{list}")]
    Incomplete { count: usize, list: String },
    /// A recording of an installation study; the reader's error says the file, line and
    /// column, and the spec's key follows.
    #[error("{error} (the spec's recordings.trajectories[{index}], {name})")]
    Recording {
        index: usize,
        name: String,
        error: PairedError,
    },
    #[error(
        "{point}{method} could not be fitted on any calibration trajectory with a window of {window_s} s ({why}); its results are not written: give calibration.window_s values that leave samples for its terms, or fewer terms"
    )]
    NoFit {
        /// "point <name>: " in a sweep, else empty.
        point: String,
        method: String,
        window_s: f64,
        why: String,
    },
    #[error("the DCNet models of {}", spec.display())]
    DcnetSpec {
        spec: PathBuf,
        #[source]
        source: DcnetSpecError,
    },
    #[error(
        "the DCNet {error_model} model of {} is not trained: run `dcnet-exp run {} --out {}` first, or leave \"dcnet\" out of calibration.methods",
        spec.display(), spec.display(), out.display()
    )]
    DcnetMissing {
        spec: PathBuf,
        out: PathBuf,
        error_model: ErrorModel,
    },
    /// A `[learned]` setting that no model can train with.
    #[error("DCNet {model}: {why}")]
    Learned { model: String, why: String },
    /// A model of `[learned]` that could not be trained or stored.
    #[error("DCNet {model}")]
    Training {
        model: String,
        #[source]
        source: TrainingJobError,
    },
    /// Points of an installation sweep with a window on which a method fitted on no
    /// calibration trajectory; the other points' folders are written.
    #[error(
        "{}\n{written} other point{} written; the sweep's table is not",
        errors.join("\n"),
        if *written == 1 { "" } else { "s" }
    )]
    Unfitted { errors: Vec<String>, written: usize },
    #[error(transparent)]
    Calibrations(#[from] CalibrationStoreError),
    #[error(
        "{}: {missing_count} of {total} calibrations are not in the cache, such as {}",
        out.display(), missing.join("; ")
    )]
    NotCollected {
        out: PathBuf,
        /// The first few missing, as "point: trajectory".
        missing: Vec<String>,
        missing_count: usize,
        total: usize,
    },
}

impl ExecuteError {
    /// Whether the fault lies in what was given (the spec, its recordings, its models)
    /// rather than in writing or storing while running (a full disk, say), which is a
    /// failure: the run can be resumed once the cause is gone.
    pub fn is_input(&self) -> bool {
        !matches!(
            self,
            ExecuteError::Results(_)
                | ExecuteError::Models(_)
                | ExecuteError::Training { .. }
                | ExecuteError::Calibrations(CalibrationStoreError::Io { .. })
        )
    }
}

/// Why the paper spec whose DCNet models an installation study applies gave none.
#[derive(Debug, thiserror::Error)]
pub enum DcnetSpecError {
    #[error(transparent)]
    Spec(#[from] SpecErrors),
    #[error(transparent)]
    Plan(#[from] PlanError),
    #[error(transparent)]
    Models(#[from] ModelStoreError),
}
