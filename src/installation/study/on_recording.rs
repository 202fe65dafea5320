//! What every window of one calibration recording shares: the study, its recordings,
//! which one calibrates, the estimators, the noise and tolerances of the bound, the
//! Kalman filters' runs and each installation model's fit alone. The methods that
//! estimate (`estimates.rs`), score (`heldout.rs`) and re-find a dive's clock
//! (`dive.rs`) on it are written beside those jobs. In: what `calibrate_on` gathers.
//! Out: the recordings a method is scored on, and the fold of each.

use crate::installation::estimate::bound::{Noise, Tolerances};
use crate::installation::estimate::fit::FitError;
use crate::installation::study::estimators::Estimators;
use crate::installation::study::filters::FilterRun;
use crate::installation::study::recording::Recording;
use crate::installation::study::spec::StudySpec;
use crate::installation::terms::{Installation, TermSet};

/// What every window of one calibration trajectory shares: the study, the trajectories,
/// which one calibrates, the estimators, the noise and tolerances of the bound, and the
/// filters' runs over it up to the longest window.
pub(super) struct OnRecording<'a> {
    pub(super) spec: &'a StudySpec,
    pub(super) recordings: &'a [&'a Recording],
    pub(super) c: usize,
    pub(super) estimators: &'a Estimators<'a>,
    pub(super) noise: Noise,
    pub(super) tolerances: Tolerances,
    pub(super) filters: Vec<FilterRun>,
    /// Each installation model's fit of this recording on its longest window: where
    /// the joint fits over the others start, at every window.
    pub(super) alone: Vec<(TermSet, Result<Installation, FitError>)>,
}

impl OnRecording<'_> {
    /// The calibration recording.
    pub(super) fn calibration(&self) -> &Recording {
        self.recordings[self.c]
    }

    /// The fold of trajectory `i` under `[learned]`, where there is one.
    pub(super) fn fold_of(&self, i: usize) -> Option<usize> {
        self.spec.learned.as_ref().map(|learned| learned.fold_of(i))
    }

    /// The trajectories one method's terms are scored on: every other one (a learned
    /// method's, those of the calibration's fold only).
    pub(super) fn scored(&self, learned: bool) -> Vec<&Recording> {
        let c = self.c;
        self.recordings
            .iter()
            .enumerate()
            .filter(|&(s, _)| s != c && !(learned && self.fold_of(s) != self.fold_of(c)))
            .map(|(_, scored)| *scored)
            .collect()
    }
}
