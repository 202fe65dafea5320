//! The held-out study: every recording in turn is the calibration one (its first w
//! seconds, for each window of the spec), each method estimates the installation's
//! terms there, and those terms correct the DVL of every other recording, scored
//! against the reference in the body frame beside no calibration at all. The paper's
//! methods (baseline, least squares EM1 to EM5, DCNet) estimate a scale and a bias from
//! the DVL and the reference's body velocity on the same time stamps; the installation
//! models fit their term sets by nonlinear least squares, with their Fisher bound.
//! In data-flow order: [`spec`] the study's spec; [`recording`] the recordings, each
//! with its reference in the body frame; [`method`] a method as its rows name it (its
//! model and its variant); [`calibration`] one calibration recording over every window
//! and method, through [`estimates`] (what each method estimates), [`filters`] (the
//! Kalman filters' runs), [`heldout`] (the scores on the other recordings) and [`dive`]
//! (each dive's clock re-found, and the joint fit); [`summary`] and
//! [`calibration_time`] what the rows add up to; [`rows`] the rows themselves.
//! In: a [`StudySpec`] and its recordings. Out: a [`StudyResults`]: held-out rows,
//! estimated terms with their bound, and the summary per method.

pub mod spec;
pub mod rows;
pub mod recording;
pub mod method;
pub mod estimators;
pub mod on_recording;
pub mod estimates;
pub mod filters;
pub mod heldout;
pub mod dive;
pub mod calibration;
pub mod summary;
pub mod calibration_time;

pub use calibration::calibrate_on;
pub use dive::{RefoundClock, clock_kept_on, refind_clock};
pub use estimators::{DcnetEstimate, Estimators, LearnedEstimate, LearnedModel};
pub use method::Method;
pub use recording::Recording;
pub use rows::{Calibrated, Estimated};
pub use summary::{summarize, summarize_folds};

use crate::installation::study::calibration_time::calibration_times;
use crate::installation::study::rows::{StudyResults, TransferRow};
use crate::installation::study::spec::StudySpec;
use rayon::prelude::*;

/// Runs the study of `spec` over `recordings` (in spec order), with `estimators` for the
/// DCNet methods; also gives back every method's terms on every window.
pub fn run(
    spec: &StudySpec,
    recordings: &[&Recording],
    estimators: &Estimators,
) -> (StudyResults, Vec<Estimated>) {
    let parts: Vec<Calibrated> = (0..recordings.len())
        .into_par_iter()
        .map(|c| calibrate_on(spec, recordings, c, estimators))
        .collect();
    assemble(spec, parts)
}

/// The study of `spec` from what each calibration trajectory gave, in spec order.
pub fn assemble(spec: &StudySpec, parts: Vec<Calibrated>) -> (StudyResults, Vec<Estimated>) {
    let all = Calibrated::concat(parts);
    let summary = summarize(&all.heldout, &spec.windows_s);
    let folds = match &spec.learned {
        Some(learned) => {
            let fold_of = |name: &str| {
                let index = spec.trajectories.iter().position(|(n, _)| n == name);
                learned.fold_of(index.expect("a trajectory of the spec"))
            };
            // A joint fit is calibrated on every other trajectory, inside no fold.
            let single: Vec<TransferRow> = all
                .heldout
                .iter()
                .filter(|r| !Method::parse(&r.method).is_joint())
                .cloned()
                .collect();
            summarize_folds(&single, &spec.windows_s, learned.folds, fold_of)
        }
        None => Vec::new(),
    };
    let study = StudyResults {
        heldout: all.heldout,
        terms: all.terms,
        summary,
        trace: Vec::new(),
        failures: all.failures,
        folds,
        filtered: all.filtered,
        calibration_time: Vec::new(),
        recordings: Vec::new(),
    };
    let study = StudyResults {
        calibration_time: calibration_times(
            &study.heldout,
            spec.time_tolerance,
            100.0 * (3.0 * spec.noise().variance_m2_s2()).sqrt(),
        ),
        ..study
    };
    (study, all.estimated)
}
