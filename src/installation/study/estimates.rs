//! What each method estimates on a calibration window: the paper's scale and bias
//! (baseline, least squares, DCNet), a learned model's terms, a Kalman filter's terms
//! after the window, an installation model's fit with its bound and the terms it left
//! out that its residuals still follow; and the rows of those terms. In: a method's
//! model and the window's samples. Out: an [`Estimate`] and its [`TermRow`]s.

use crate::data::fixes::{FixSimulation, simulate_fixes};
use crate::estimators::{Baseline, Estimator, LeastSquares};
use crate::installation::estimate::between_dives::BetweenDives;
use crate::installation::estimate::bound::{TermBound, bound};
use crate::installation::estimate::clock::Carried;
use crate::installation::estimate::fit::fit;
use crate::installation::estimate::fixes::{FixFitError, FixNoise, default_fix_terms, fit_fixes};
use crate::installation::estimate::missing::{Asked, asked_for};
use crate::installation::frames::Attitude;
use crate::installation::study::estimators::LearnedModel;
use crate::installation::study::on_recording::OnRecording;
use crate::installation::study::rows::{FitFailure, TermRow};
use crate::installation::study::spec::Model;
use crate::installation::terms::names::{TermName, term_set};
use crate::installation::terms::{Installation, TermSet};
use crate::rng::task_rng;
use crate::vocab::Correction;
use nalgebra::DMatrix;
use std::ops::Range;

/// What a method estimated on one window.
pub(super) struct Estimate {
    pub(super) installation: Installation,
    pub(super) bound: Option<TermBound>,
    /// A fit's left-out terms that its residuals still follow.
    pub(super) asked: Vec<Asked>,
    /// A filter's terms: each parameter's name, value and standard deviation.
    pub(super) filtered: Option<Vec<(&'static str, f64, f64, f64)>>,
    /// The terms a fit or a filter estimated, with their covariance: what a dive that
    /// carries them inherits.
    pub(super) uncertainty: Option<(TermSet, DMatrix<f64>)>,
    /// A joint fit's spread between dives, per term of `bound`; empty otherwise.
    pub(super) between: Vec<Option<BetweenDives>>,
}

impl Estimate {
    /// Terms with neither a bound nor a filter's standard deviations.
    pub(super) fn bare(installation: Installation) -> Estimate {
        Estimate {
            installation,
            bound: None,
            asked: Vec::new(),
            filtered: None,
            uncertainty: None,
            between: Vec::new(),
        }
    }

    /// The terms as a dive carries them.
    pub(super) fn carried(&self) -> Carried {
        Carried {
            installation: self.installation,
            uncertainty: self.uncertainty.clone(),
        }
    }
}

/// A scale-and-bias correction as installation terms: `(v − b) ⊘ (1 + k)` is the
/// installation's correction with no misalignment, lever arm or time offset.
pub fn from_correction(correction: &Correction) -> Installation {
    Installation {
        scale: correction.scale,
        bias_m_s: correction.bias_m_s,
        ..Installation::default()
    }
}

impl OnRecording<'_> {
    /// What `model` estimates on the samples `range`: `None` where it cannot (no
    /// network, a window too short for it, a filter that took no sample), and the
    /// failure of a fit.
    pub(super) fn estimate(
        &self,
        model: &Model,
        range: Range<usize>,
        window_s: f64,
    ) -> Result<Option<Estimate>, FitFailure> {
        Ok(match model {
            Model::Baseline | Model::LeastSquares(_) | Model::Dcnet(_) => {
                self.corrected(model, range)
            }
            Model::Filter { .. } => {
                let label = model.label();
                let run = self
                    .filters
                    .iter()
                    .find(|run| run.label == label)
                    .expect("every filter ran");
                run.at_window(range.end).map(|(installation, terms)| {
                    // Its standard deviations, uncorrelated: the filter keeps no
                    // correlations in its steps.
                    let std: Vec<f64> = terms.iter().map(|t| t.2).collect();
                    let identity: Vec<Vec<f64>> = (0..std.len())
                        .map(|i| {
                            (0..std.len())
                                .map(|j| f64::from(u8::from(i == j)))
                                .collect()
                        })
                        .collect();
                    let uncertainty =
                        Carried::with(installation, run.terms, &std, &identity).uncertainty;
                    Estimate {
                        installation,
                        bound: None,
                        asked: Vec::new(),
                        filtered: Some(terms),
                        uncertainty,
                        between: Vec::new(),
                    }
                })
            }
            Model::Learned { source, replicate } => self.fold_of(self.c).and_then(|fold| {
                let learned = LearnedModel {
                    source: *source,
                    replicate: *replicate,
                    fold,
                };
                (self.estimators.learned)(learned, self.calibration(), range).map(Estimate::bare)
            }),
            Model::Installation { terms, .. } => Some(self.fitted(model, terms, range, window_s)?),
            Model::Fixes { simulation, seed } => {
                self.fitted_to_fixes(model, (simulation, *seed), range, window_s)?
            }
        })
    }

    /// The installation fitted to fixes simulated by `simulation` from the calibration
    /// trajectory's positions (one draw per trajectory, from `seed` and its name, the
    /// same for every window), those of the samples `range`; `None` where the window
    /// holds fewer fixes than the fit has parameters.
    fn fitted_to_fixes(
        &self,
        model: &Model,
        (simulation, seed): (&FixSimulation, u64),
        range: Range<usize>,
        window_s: f64,
    ) -> Result<Option<Estimate>, FitFailure> {
        let calibration = self.calibration();
        let recording = &calibration.recording;
        let failure = |why: String| FitFailure {
            method: model.label(),
            calibration: calibration.name.clone(),
            window_s,
            why,
        };
        let Some(positions) = &recording.position_ne_m else {
            return Err(failure(
                "the recording has no positions to simulate fixes from".into(),
            ));
        };
        let mut rng = task_rng(seed, &[&"fixes", &calibration.name]);
        let fixes = simulate_fixes(
            (&recording.reference_time_s, positions),
            simulation,
            &mut rng,
        );
        let window = (
            &recording.time_s[range.clone()],
            &recording.dvl_m_s[range.clone()],
        );
        let pieces: Vec<Range<usize>> = (recording.pieces().into_iter())
            .map(|p| p.start.min(range.end)..p.end.min(range.end))
            .filter(|p| !p.is_empty())
            .collect();
        let noise = FixNoise {
            fix_m: simulation.noise_m,
            depth_m: simulation.noise_m,
            dvl_m_s: self.noise.dvl_m_s,
        };
        let terms = term_set(&default_fix_terms());
        let attitude = Attitude::of(recording);
        match fit_fixes(window, &pieces, &attitude, &fixes, terms, noise) {
            Ok(fitted) => Ok(Some(Estimate::bare(fitted.installation))),
            Err(FixFitError::TooFewFixes { .. } | FixFitError::NoOverlap { .. }) => Ok(None),
            Err(fault) => Err(failure(fault.to_string())),
        }
    }

    /// The scale-and-bias correction of one of the paper's methods, from the DVL and the
    /// reference's body velocity on the same stamps.
    fn corrected(&self, model: &Model, range: Range<usize>) -> Option<Estimate> {
        let (dvl, reference) = self.calibration().reference_on_stamps(range);
        let correction = match model {
            Model::Baseline => Baseline.estimate(&dvl, &reference),
            Model::LeastSquares(error_model) => {
                LeastSquares(*error_model).estimate(&dvl, &reference)
            }
            Model::Dcnet(error_model) => (self.estimators.dcnet)(*error_model, &dvl, &reference)?,
            Model::Installation { .. }
            | Model::Filter { .. }
            | Model::Learned { .. }
            | Model::Fixes { .. } => {
                unreachable!()
            }
        };
        Some(Estimate::bare(from_correction(&correction)))
    }

    /// The fit of an installation model's `terms` on the samples `range`, with its bound.
    fn fitted(
        &self,
        model: &Model,
        terms: &[TermName],
        range: Range<usize>,
        window_s: f64,
    ) -> Result<Estimate, FitFailure> {
        let calibration = self.calibration();
        let recording = &calibration.recording;
        let window = (&recording.time_s[range.clone()], &recording.dvl_m_s[range]);
        match fit(window.0, window.1, &calibration.reference, term_set(terms)) {
            Ok(fitted) => {
                let bounded = bound(&fitted, self.noise, &self.tolerances);
                Ok(Estimate {
                    installation: fitted.installation,
                    asked: asked_for(
                        &fitted,
                        window,
                        &calibration.reference,
                        &bounded.residual_noise,
                    ),
                    uncertainty: Carried::with(
                        fitted.installation,
                        fitted.terms,
                        &bounded.std,
                        &bounded.correlation,
                    )
                    .uncertainty,
                    bound: Some(bounded),
                    filtered: None,
                    between: Vec::new(),
                })
            }
            Err(why) => Err(FitFailure {
                method: model.label(),
                calibration: calibration.name.clone(),
                window_s,
                why: why.to_string(),
            }),
        }
    }

    /// The rows of one method's terms: a learned method's (no standard deviation), a
    /// filter's, and a fit's with its bound and why a term cannot be seen.
    pub(super) fn term_rows(
        &self,
        label: &str,
        estimate: &Estimate,
        learned: bool,
        window_s: f64,
    ) -> Vec<TermRow> {
        let asked = estimate
            .asked
            .iter()
            .map(|a| format!("{} χ² {:.1}", a.term, a.statistic))
            .collect::<Vec<_>>()
            .join("; ");
        let row = |term: &str, value: f64, (std, bound_std): (f64, f64), unseen: String| TermRow {
            method: label.to_string(),
            calibration: self.calibration().name.clone(),
            window_s,
            term: term.to_string(),
            value,
            std,
            bound_std,
            unseen,
            asked: asked.clone(),
            between_dives_std: f64::NAN,
            next_dive_low: f64::NAN,
            next_dive_high: f64::NAN,
        };
        let mut rows = Vec::new();
        // A learned method's terms (no standard deviation), or a filter's.
        let learned_terms = self.spec.learned.as_ref().filter(|_| learned).map(|l| {
            let set = term_set(&l.terms);
            let values = estimate.installation.to_parameters(&set);
            let names = set.parameter_names().into_iter();
            names
                .zip(values)
                .map(|(name, value)| (name, value, f64::NAN, f64::NAN))
                .collect()
        });
        for &(name, value, std, bound_std) in
            learned_terms.iter().chain(&estimate.filtered).flatten()
        {
            rows.push(row(name, value, (std, bound_std), String::new()));
        }
        if let Some(bound) = &estimate.bound {
            for (i, name) in bound.names.iter().enumerate() {
                let unseen = bound
                    .unseen
                    .iter()
                    .filter(|u| u.term == *name)
                    .map(|u| u.why.to_string())
                    .collect::<Vec<_>>()
                    .join("; ");
                let mut term = row(
                    name,
                    bound.value[i],
                    (bound.std[i], bound.bound_std[i]),
                    unseen,
                );
                if let Some(Some(between)) = estimate.between.get(i) {
                    let (low, high) = between.next_dive_95();
                    term.between_dives_std = between.std;
                    (term.next_dive_low, term.next_dive_high) = (low, high);
                }
                rows.push(term);
            }
        }
        rows
    }
}
