//! The held-out study: every trajectory in turn is the calibration segment (its first w
//! seconds, for each window of the spec), each method estimates the installation's
//! terms there, and those terms correct the DVL of every other trajectory, scored
//! against the reference in the body frame beside no calibration at all. The paper's
//! methods (baseline, least squares EM1 to EM5, DCNet) estimate a scale and a bias from
//! the DVL and the reference's body velocity on the same time stamps; the installation
//! models fit their term sets by nonlinear least squares, with their Fisher bound.
//! In: an [`StudySpec`] and its recordings. Out: a [`StudyResults`]: held-out rows,
//! estimated terms with their bound, and the summary per method.

pub mod spec;
pub mod rows;
pub mod filters;
pub mod calibration_time;

use crate::Vec3;
use crate::data::paired::PairedRecording;
use crate::data::paired::sample_interval;
use crate::estimators::{Baseline, Estimator, LeastSquares};
use crate::evaluate::statistics::{mean_ci95, mean_std};
use crate::installation::estimate::bound::{Noise, TermBound, Tolerances, bound};
use crate::installation::estimate::clock::{Carried, DEFAULT_SEARCH_S, refind};
use crate::installation::estimate::fit::FitError;
use crate::installation::estimate::fit::{TIME_OFFSET_MARGIN_S, fit};
use crate::installation::estimate::joint::{self, JointRecording, joint_fit};
use crate::installation::estimate::missing::{Asked, asked_for};
use crate::installation::frames::Reference;
use crate::installation::learned::spec::TrainingSource;
use crate::installation::study::calibration_time::calibration_times;
use crate::installation::study::filters::{FilterRun, run_filters};
use crate::installation::study::rows::{
    FilterPoint, FitFailure, FoldSummaryRow, NO_CALIBRATION, StudyResults, SummaryRow, TermRow,
    TransferRow,
};
use crate::installation::study::spec::{Method, StudySpec};
use crate::installation::terms::TermSet;
use crate::installation::terms::names::{TermName, term_set};
use crate::installation::terms::{Installation, score};
use crate::vocab::{Correction, ErrorModel};
use nalgebra::DMatrix;
use rayon::prelude::*;
use std::ops::Range;

/// One recording with its reference in the body frame.
pub struct Segment {
    pub name: String,
    pub recording: PairedRecording,
    pub reference: Reference,
}

impl Segment {
    pub fn new(name: String, recording: PairedRecording) -> Self {
        let reference = Reference::new(&recording);
        Segment {
            name,
            recording,
            reference,
        }
    }

    /// The samples of the first `window_s` seconds (all of them when the recording is
    /// shorter), and the seconds they span.
    pub fn first_seconds(&self, window_s: f64) -> (std::ops::Range<usize>, f64) {
        let time = &self.recording.time_s;
        let start = time[0];
        let end = time.partition_point(|&t| t - start < window_s);
        let span = time[end - 1] - start + sample_interval(time);
        (0..end, span.min(window_s))
    }
}

/// What a method estimated on one window.
struct Estimate {
    installation: Installation,
    bound: Option<TermBound>,
    /// A fit's left-out terms that its residuals still follow.
    asked: Vec<Asked>,
    /// A filter's terms: each parameter's name, value and standard deviation.
    filtered: Option<Vec<(&'static str, f64, f64, f64)>>,
    /// The terms a fit or a filter estimated, with their covariance: what a dive that
    /// carries them inherits.
    uncertainty: Option<(TermSet, DMatrix<f64>)>,
}

/// The terms one method estimated on one calibration window.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Estimated {
    pub method: String,
    pub calibration: String,
    pub window_s: f64,
    pub installation: Installation,
}

/// How DCNet estimates a scale and a bias from a DVL window and the reference's body
/// velocity on its stamps, for an error model; `None` where it cannot (no model, or a
/// window shorter than the network's).
pub type DcnetEstimate<'a> = dyn Fn(ErrorModel, &[Vec3], &[Vec3]) -> Option<Correction> + Sync + 'a;

/// Which of `[learned]`'s models: what it trained on, which replicate, which fold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LearnedModel {
    pub source: TrainingSource,
    pub replicate: usize,
    pub fold: usize,
}

/// How one of `[learned]`'s models estimates the terms from samples of a calibration
/// segment; `None` where it cannot.
pub type LearnedEstimate<'a> =
    dyn Fn(LearnedModel, &Segment, std::ops::Range<usize>) -> Option<Installation> + Sync + 'a;

/// The learned methods' estimators.
pub struct Estimators<'a> {
    pub dcnet: &'a DcnetEstimate<'a>,
    pub learned: &'a LearnedEstimate<'a>,
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

/// The reference's body velocity on the DVL's own time stamps, where it is recorded.
fn reference_on_stamps(segment: &Segment, range: std::ops::Range<usize>) -> (Vec<Vec3>, Vec<Vec3>) {
    let recording = &segment.recording;
    range
        .filter_map(|i| {
            let at = segment.reference.at(recording.time_s[i])?;
            Some((recording.dvl_m_s[i], at.velocity_body_m_s))
        })
        .unzip()
}

/// What one calibration trajectory gives, over every window and method: the held-out
/// rows, the terms with their bound, every method's terms, and the fits that failed. The
/// unit a run stores in its cache and a shard computes.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Calibrated {
    pub heldout: Vec<TransferRow>,
    pub terms: Vec<TermRow>,
    pub estimated: Vec<Estimated>,
    pub failures: Vec<FitFailure>,
    pub filtered: Vec<FilterPoint>,
}

impl Calibrated {
    /// The rows of `parts`, one after another.
    pub fn concat(parts: impl IntoIterator<Item = Calibrated>) -> Calibrated {
        let mut all = Calibrated::default();
        for part in parts {
            all.heldout.extend(part.heldout);
            all.terms.extend(part.terms);
            all.estimated.extend(part.estimated);
            all.failures.extend(part.failures);
            all.filtered.extend(part.filtered);
        }
        all
    }
}

/// Runs the study of `spec` over `segments` (in spec order), with `estimators` for the
/// DCNet methods; also gives back every method's terms on every window.
pub fn run(
    spec: &StudySpec,
    segments: &[&Segment],
    estimators: &Estimators,
) -> (StudyResults, Vec<Estimated>) {
    let parts: Vec<Calibrated> = (0..segments.len())
        .into_par_iter()
        .map(|c| calibrate_on(spec, segments, c, estimators))
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
                .filter(|r| !is_joint(&r.method))
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
    };
    let study = StudyResults {
        calibration_time: calibration_times(
            &study.heldout,
            spec.time_tolerance,
            100.0 * (3.0 * (spec.dvl_noise_m_s.powi(2) + spec.reference_noise_m_s.powi(2))).sqrt(),
        ),
        ..study
    };
    (study, all.estimated)
}

/// Calibrates on trajectory `c` of `segments` (its first w seconds for each window of
/// `spec`) with every method, and scores each method's terms on every other trajectory
/// (a learned method's only on those of `c`'s fold, the trajectories its model never
/// saw).
pub fn calibrate_on(
    spec: &StudySpec,
    segments: &[&Segment],
    c: usize,
    estimators: &Estimators,
) -> Calibrated {
    let noise = Noise {
        dvl_m_s: spec.dvl_noise_m_s,
        reference_m_s: spec.reference_noise_m_s,
    };
    let calibration = segments[c];
    let longest_s = spec.windows_s.iter().copied().fold(0.0, f64::max);
    let whole = calibration.first_seconds(longest_s).0;
    let recording = &calibration.recording;
    // The starts of the joint fits, which only `[calibration.dive]` asks for.
    let alone = spec
        .methods
        .iter()
        .filter_map(|method| match method {
            Method::Installation { terms, .. } if spec.dive.is_some() => Some(term_set(terms)),
            _ => None,
        })
        .map(|terms| {
            let fitted = fit(
                &recording.time_s[whole.clone()],
                &recording.dvl_m_s[whole.clone()],
                &calibration.reference,
                terms,
            );
            (terms, fitted.map(|fitted| fitted.installation))
        })
        .collect();
    let on = OnTrajectory {
        alone,
        spec,
        segments,
        c,
        estimators,
        noise,
        tolerances: spec.observability.tolerances(),
        filters: run_filters(
            spec,
            (
                &calibration.recording,
                calibration.first_seconds(longest_s).0,
            ),
            &calibration.reference,
            noise,
        ),
    };
    let per_window: Vec<Calibrated> = spec
        .windows_s
        .par_iter()
        .map(|&window_s| on.window(window_s))
        .collect();
    let mut calibrated = Calibrated::concat(per_window);
    for run in &on.filters {
        calibrated.filtered.extend(run.points(&calibration.name));
    }
    calibrated
}

impl Estimate {
    /// Terms with neither a bound nor a filter's standard deviations.
    fn bare(installation: Installation) -> Estimate {
        Estimate {
            installation,
            bound: None,
            asked: Vec::new(),
            filtered: None,
            uncertainty: None,
        }
    }

    /// The terms as a dive carries them.
    fn carried(&self) -> Carried {
        Carried {
            installation: self.installation,
            uncertainty: self.uncertainty.clone(),
        }
    }
}

/// What every window of one calibration trajectory shares: the study, the trajectories,
/// which one calibrates, the estimators, the noise and tolerances of the bound, and the
/// filters' runs over it up to the longest window.
struct OnTrajectory<'a> {
    spec: &'a StudySpec,
    segments: &'a [&'a Segment],
    c: usize,
    estimators: &'a Estimators<'a>,
    noise: Noise,
    tolerances: Tolerances,
    filters: Vec<FilterRun>,
    /// Each installation model's fit of this trajectory on its longest window: where
    /// the joint fits over the others start, at every window.
    alone: Vec<(TermSet, Result<Installation, FitError>)>,
}

impl OnTrajectory<'_> {
    fn calibration(&self) -> &Segment {
        self.segments[self.c]
    }

    /// The fold of trajectory `i` under `[learned]`, where there is one.
    fn fold_of(&self, i: usize) -> Option<usize> {
        self.spec.learned.as_ref().map(|learned| learned.fold_of(i))
    }

    /// Every method on the first `window_s` seconds: its terms (no calibration first),
    /// their rows, and their scores on the other trajectories.
    fn window(&self, window_s: f64) -> Calibrated {
        let (range, _) = self.calibration().first_seconds(window_s);
        let mut failures = Vec::new();
        let mut methods: Vec<(String, Estimate)> = vec![(
            NO_CALIBRATION.to_string(),
            Estimate::bare(Installation::default()),
        )];
        for method in &self.spec.methods {
            match self.estimate(method, range.clone(), window_s) {
                Ok(Some(estimate)) => methods.push((method.label(), estimate)),
                Ok(None) => {}
                Err(failure) => failures.push(failure),
            }
        }
        let learned_labels: Vec<String> = self
            .spec
            .methods
            .iter()
            .filter(|m| matches!(m, Method::Learned { .. }))
            .map(Method::label)
            .collect();
        let estimated = methods
            .iter()
            .map(|(label, estimate)| Estimated {
                method: label.clone(),
                calibration: self.calibration().name.clone(),
                window_s,
                installation: estimate.installation,
            })
            .collect();
        let (mut terms, mut heldout) = (Vec::new(), Vec::new());
        let calibration = self.calibration().name.clone();
        for (label, estimate) in &methods {
            let learned = learned_labels.contains(label);
            terms.extend(self.term_rows(label, estimate, learned, window_s));
            let scored = self.scored(learned);
            let on = (calibration.as_str(), window_s);
            heldout.extend(self.transfer_rows(label, &estimate.installation, &scored, on));
            let (refound, unfound) = self.refound_rows(label, &estimate.carried(), &scored, on);
            heldout.extend(refound);
            failures.extend(unfound);
        }
        let mut calibrated = Calibrated {
            heldout,
            terms,
            estimated,
            failures,
            filtered: Vec::new(),
        };
        if let Some(dive) = &self.spec.dive {
            for method in &self.spec.methods {
                if let Method::Installation { terms, .. } = method {
                    let terms = term_set(terms);
                    self.jointly(
                        method,
                        (terms, dive.search.dive_terms),
                        window_s,
                        &mut calibrated,
                    );
                }
            }
        }
        calibrated
    }

    /// With `[calibration.dive]`, the joint calibration of `method`'s `terms` over the
    /// first `window_s` seconds of every trajectory but this one (the `dive` terms one
    /// set each), scored on this one: its terms' rows and its held-out rows, as
    /// "<method>, joint", calibrated on "all but <trajectory>".
    fn jointly(
        &self,
        method: &Method,
        terms: (TermSet, TermSet),
        window_s: f64,
        into: &mut Calibrated,
    ) {
        if self.scored(false).len() < 2 {
            return;
        }
        let label = joint_label(&method.label());
        let calibration = format!("all but {}", self.calibration().name);
        let estimate = match self.joint_estimate(terms, window_s) {
            Ok(estimate) => estimate,
            Err(why) => {
                into.failures.push(FitFailure {
                    method: label,
                    calibration,
                    window_s,
                    why,
                });
                return;
            }
        };
        into.terms.extend(
            self.term_rows(&label, &estimate, false, window_s)
                .into_iter()
                .map(|row| TermRow {
                    calibration: calibration.clone(),
                    ..row
                }),
        );
        let here = [self.calibration()];
        let on = (calibration.as_str(), window_s);
        into.heldout
            .extend(self.transfer_rows(&label, &estimate.installation, &here, on));
        let (refound, unfound) = self.refound_rows(&label, &estimate.carried(), &here, on);
        into.heldout.extend(refound);
        into.failures.extend(unfound);
    }

    /// The joint fit of `terms` (the vehicle's and the dive's) over the first
    /// `window_s` seconds of every other trajectory, started from this one's fit alone,
    /// as the terms this trajectory carries: the vehicle's, and the mean of the others'
    /// dive terms (it has none of its own); or why it failed.
    fn joint_estimate(
        &self,
        (terms, dive): (TermSet, TermSet),
        window_s: f64,
    ) -> Result<Estimate, String> {
        let others = self.scored(false);
        let ranges: Vec<Range<usize>> =
            others.iter().map(|s| s.first_seconds(window_s).0).collect();
        let recordings = joint_recordings(&others, &ranges);
        let (_, start) = self
            .alone
            .iter()
            .find(|(set, _)| *set == terms)
            .expect("every model fitted alone");
        let start = start
            .as_ref()
            .map_err(|why| format!("its start, {} fitted alone: {why}", self.calibration().name))?;
        let search_s = self
            .spec
            .dive
            .as_ref()
            .map_or(DEFAULT_SEARCH_S, |d| d.search.search_s);
        let starts = joint::starts_from(&recordings, *start, search_s);
        let joint = joint_fit(
            &recordings,
            &starts,
            (terms, dive),
            (self.noise, &self.tolerances),
        )
        .map_err(|why| why.to_string())?;
        let installation = joint
            .vehicle
            .with_parameters(&joint.dive_terms, &joint.mean_dive());
        let bound = &joint.bound;
        let carried = Carried::with(
            installation,
            joint.vehicle_terms,
            &bound.std,
            &bound.correlation,
        );
        Ok(Estimate {
            installation,
            bound: Some(joint.bound),
            asked: Vec::new(),
            filtered: None,
            uncertainty: carried.uncertainty,
        })
    }

    /// What `method` estimates on the samples `range`: `None` where it cannot (no
    /// network, a window too short for it, a filter that took no sample), and the
    /// failure of a fit.
    fn estimate(
        &self,
        method: &Method,
        range: Range<usize>,
        window_s: f64,
    ) -> Result<Option<Estimate>, FitFailure> {
        Ok(match method {
            Method::Baseline | Method::LeastSquares(_) | Method::Dcnet(_) => {
                self.corrected(method, range)
            }
            Method::Filter { .. } => {
                let label = method.label();
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
                    }
                })
            }
            Method::Learned { source, replicate } => self.fold_of(self.c).and_then(|fold| {
                let model = LearnedModel {
                    source: *source,
                    replicate: *replicate,
                    fold,
                };
                (self.estimators.learned)(model, self.calibration(), range).map(Estimate::bare)
            }),
            Method::Installation { terms, .. } => {
                Some(self.fitted(method, terms, range, window_s)?)
            }
        })
    }

    /// The scale-and-bias correction of one of the paper's methods, from the DVL and the
    /// reference's body velocity on the same stamps.
    fn corrected(&self, method: &Method, range: Range<usize>) -> Option<Estimate> {
        let (dvl, reference) = reference_on_stamps(self.calibration(), range);
        let correction = match method {
            Method::Baseline => Baseline.estimate(&dvl, &reference),
            Method::LeastSquares(model) => LeastSquares(*model).estimate(&dvl, &reference),
            Method::Dcnet(model) => (self.estimators.dcnet)(*model, &dvl, &reference)?,
            Method::Installation { .. } | Method::Filter { .. } | Method::Learned { .. } => {
                unreachable!()
            }
        };
        Some(Estimate::bare(from_correction(&correction)))
    }

    /// The fit of an installation model's `terms` on the samples `range`, with its bound.
    fn fitted(
        &self,
        method: &Method,
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
                })
            }
            Err(why) => Err(FitFailure {
                method: method.label(),
                calibration: calibration.name.clone(),
                window_s,
                why: why.to_string(),
            }),
        }
    }

    /// The rows of one method's terms: a learned method's (no standard deviation), a
    /// filter's, and a fit's with its bound and why a term cannot be seen.
    fn term_rows(
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
                rows.push(row(
                    name,
                    bound.value[i],
                    (bound.std[i], bound.bound_std[i]),
                    unseen,
                ));
            }
        }
        rows
    }

    /// The trajectories one method's terms are scored on: every other one (a learned
    /// method's, those of the calibration's fold only).
    fn scored(&self, learned: bool) -> Vec<&Segment> {
        let c = self.c;
        self.segments
            .iter()
            .enumerate()
            .filter(|&(s, _)| s != c && !(learned && self.fold_of(s) != self.fold_of(c)))
            .map(|(_, scored)| *scored)
            .collect()
    }

    /// With `[calibration.dive]`, one method's RMSE on every trajectory it is scored on
    /// with the dive's terms found again, for each of the dive's windows w: from the
    /// trajectory's first w seconds with the method's other terms carried, scored on its
    /// samples after them. Labelled "<method>, clock re-found in <w> s". Where the clock
    /// cannot be found, the calibration's is kept and the failure says so.
    fn refound_rows(
        &self,
        label: &str,
        carried: &Carried,
        scored: &[&Segment],
        (calibration, window_s): (&str, f64),
    ) -> (Vec<TransferRow>, Vec<FitFailure>) {
        let Some(dive) = &self.spec.dive else {
            return (Vec::new(), Vec::new());
        };
        let (mut rows, mut failures) = (Vec::new(), Vec::new());
        for &dive_s in &dive.windows_s {
            let method = refound_label(label, dive_s);
            for scored in scored {
                let recording = &scored.recording;
                let (first, _) = scored.first_seconds(dive_s);
                let inside = scored
                    .reference
                    .interior(&recording.time_s, TIME_OFFSET_MARGIN_S);
                let after = first.end.max(inside.start)..inside.end;
                let window = (&recording.time_s[first.clone()], &recording.dvl_m_s[first]);
                let found = refind(
                    window,
                    &scored.reference,
                    carried,
                    dive.search,
                    (self.noise, &self.tolerances),
                );
                let installation = match found {
                    Ok(clock) => clock.installation,
                    Err(why) => {
                        let on = (calibration, window_s);
                        failures.push(clock_kept(&method, on, &scored.name, &why.to_string()));
                        carried.installation
                    }
                };
                let on = (calibration, window_s);
                if let Some(row) = transfer_row(&method, &installation, scored, after, on) {
                    rows.push(row);
                }
            }
        }
        (rows, failures)
    }

    /// One method's RMSE on each trajectory of `scored`, on its samples inside the
    /// reference.
    fn transfer_rows(
        &self,
        label: &str,
        installation: &Installation,
        scored: &[&Segment],
        on: (&str, f64),
    ) -> Vec<TransferRow> {
        scored
            .iter()
            .filter_map(|scored| {
                // Every method is scored on the same samples, those inside the
                // reference whatever the time offset.
                let samples = scored
                    .reference
                    .interior(&scored.recording.time_s, TIME_OFFSET_MARGIN_S);
                transfer_row(label, installation, scored, samples, on)
            })
            .collect()
    }
}

/// The row of `installation` scored on `samples` of `scored`, calibrated on
/// `calibration`'s first `window_s` seconds.
fn transfer_row(
    method: &str,
    installation: &Installation,
    scored: &Segment,
    samples: Range<usize>,
    (calibration, window_s): (&str, f64),
) -> Option<TransferRow> {
    let recording = &scored.recording;
    let rmse = score(
        installation,
        &recording.time_s,
        &recording.dvl_m_s,
        &scored.reference,
        samples,
    )?;
    Some(TransferRow {
        method: method.to_string(),
        calibration: calibration.to_string(),
        window_s,
        scored: scored.name.clone(),
        rmse_cm_s: [100.0 * rmse.x_m_s, 100.0 * rmse.y_m_s, 100.0 * rmse.z_m_s],
        total_cm_s: 100.0 * rmse.total_m_s,
    })
}

/// The samples `ranges` of `segments`, as a joint fit takes them.
fn joint_recordings<'a>(
    segments: &[&'a Segment],
    ranges: &[Range<usize>],
) -> Vec<JointRecording<'a>> {
    segments
        .iter()
        .zip(ranges)
        .map(|(s, range)| JointRecording {
            time_s: &s.recording.time_s[range.clone()],
            dvl_m_s: &s.recording.dvl_m_s[range.clone()],
            reference: &s.reference,
        })
        .collect()
}

/// The label of a method's joint calibration over the other trajectories.
pub fn joint_label(method: &str) -> String {
    format!("{method}{JOINT}")
}

/// What a method's label says after its name when it is a joint fit.
pub const JOINT: &str = ", joint";

/// Whether `method` is a joint fit's, its clock re-found or not.
pub fn is_joint(method: &str) -> bool {
    method.contains(JOINT)
}

/// What a method's label says after its name when its rows have the dive's clock found
/// again, before the seconds that found it.
pub const CLOCK_REFOUND: &str = ", clock re-found in ";

/// Whether `method` is the label of rows with the dive's clock found again.
pub fn is_refound(method: &str) -> bool {
    method.contains(CLOCK_REFOUND)
}

/// The label of a method's rows with the dive's clock found again from its first
/// `dive_s` seconds.
pub fn refound_label(method: &str, dive_s: f64) -> String {
    format!("{method}{CLOCK_REFOUND}{dive_s} s")
}

/// Where the clock of `scored` could not be found again for `method` (a re-found
/// label), calibrated on `calibration` over `window_s`: its row is scored with the
/// calibration's clock, and this entry of the failures says so and why.
fn clock_kept(
    method: &str,
    (calibration, window_s): (&str, f64),
    scored: &str,
    why: &str,
) -> FitFailure {
    FitFailure {
        method: method.to_string(),
        calibration: calibration.to_string(),
        window_s,
        why: format!("on {scored}: {why}; its terms are scored with the calibration's clock"),
    }
}

/// The scored trajectory of a failures entry that is no failed fit but a clock kept
/// ([`clock_kept`]: a re-found method fits nothing of its own); `None` for a fit that
/// failed.
pub fn clock_kept_on(failure: &FitFailure) -> Option<&str> {
    if !is_refound(&failure.method) {
        return None;
    }
    let (scored, _) = failure.why.strip_prefix("on ")?.split_once(": ")?;
    Some(scored)
}

/// [`summarize`] on the pairs whose calibration and scored trajectories share a fold,
/// and at each window only those every method scored there (a fit that failed, or a
/// window too short for a network, leaves the pair out for every method): fold by fold
/// ("1", "2", …), then over every fold ("all"), every method on the same pairs.
pub fn summarize_folds(
    heldout: &[TransferRow],
    windows_s: &[f64],
    folds: usize,
    fold_of: impl Fn(&str) -> usize,
) -> Vec<FoldSummaryRow> {
    let mut inside = Vec::new();
    for &window_s in windows_s {
        let rows: Vec<&TransferRow> = heldout
            .iter()
            .filter(|r| r.window_s == window_s && fold_of(&r.calibration) == fold_of(&r.scored))
            .collect();
        let methods = crate::first_seen(rows.iter().map(|r| r.method.as_str()));
        let pairs = |method: &str| -> Vec<(&str, &str)> {
            rows.iter()
                .filter(|r| r.method == method)
                .map(|r| (r.calibration.as_str(), r.scored.as_str()))
                .collect()
        };
        let every: Vec<Vec<(&str, &str)>> = methods.iter().map(|m| pairs(m)).collect();
        inside.extend(
            rows.iter()
                .filter(|r| {
                    let pair = (r.calibration.as_str(), r.scored.as_str());
                    every.iter().all(|p| p.contains(&pair))
                })
                .map(|r| (*r).clone()),
        );
    }
    let mut rows = Vec::new();
    for fold in 0..folds {
        let of_fold: Vec<TransferRow> = inside
            .iter()
            .filter(|r| fold_of(&r.calibration) == fold)
            .cloned()
            .collect();
        rows.extend(
            summarize(&of_fold, windows_s)
                .into_iter()
                .map(|summary| FoldSummaryRow {
                    fold: (fold + 1).to_string(),
                    summary,
                }),
        );
    }
    rows.extend(
        summarize(&inside, windows_s)
            .into_iter()
            .map(|summary| FoldSummaryRow {
                fold: "all".to_string(),
                summary,
            }),
    );
    rows
}

/// Per method and window: the mean over calibration trajectories of each one's mean
/// held-out RMSE, its 95 % interval, and its ratio to no calibration's.
pub fn summarize(heldout: &[TransferRow], windows_s: &[f64]) -> Vec<SummaryRow> {
    let methods = crate::first_seen(heldout.iter().map(|r| r.method.as_str()));
    let per_calibration = |method: &str, window_s: f64| -> Vec<f64> {
        let calibrations = crate::first_seen(
            heldout
                .iter()
                .filter(|r| r.method == method && r.window_s == window_s)
                .map(|r| r.calibration.as_str()),
        );
        calibrations
            .iter()
            .map(|c| {
                let scores: Vec<f64> = heldout
                    .iter()
                    .filter(|r| r.method == method && r.window_s == window_s && r.calibration == *c)
                    .map(|r| r.total_cm_s)
                    .collect();
                scores.iter().sum::<f64>() / scores.len() as f64
            })
            .collect()
    };
    let mut rows = Vec::new();
    for &window_s in windows_s {
        let (none, _) = mean_std(per_calibration(NO_CALIBRATION, window_s).into_iter());
        for method in &methods {
            let values = per_calibration(method, window_s);
            if values.is_empty() {
                continue;
            }
            // One calibration trajectory bounds nothing: its interval is unbounded.
            let (mean, ci95) = match values.len() {
                1 => (values[0], f64::INFINITY),
                _ => mean_ci95(&values),
            };
            rows.push(SummaryRow {
                method: method.to_string(),
                window_s,
                mean_cm_s: mean,
                ci95_cm_s: ci95,
                ratio: mean / none,
                calibrations: values.len(),
            });
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(method: &str, calibration: &str, scored: &str, total_cm_s: f64) -> TransferRow {
        TransferRow {
            method: method.into(),
            calibration: calibration.into(),
            window_s: 100.0,
            scored: scored.into(),
            rmse_cm_s: [total_cm_s, 0.0, 0.0],
            total_cm_s,
        }
    }

    /// Inside the folds, every method is averaged over the same pairs: those inside a
    /// fold that every method scored.
    #[test]
    fn the_fold_summary_keeps_the_pairs_inside_a_fold_that_every_method_scored() {
        // Folds: A, C | B, D. The fit failed on C → A; the cross-fold pairs are out.
        let heldout = vec![
            row(NO_CALIBRATION, "A", "C", 10.0),
            row(NO_CALIBRATION, "C", "A", 20.0),
            row(NO_CALIBRATION, "A", "B", 99.0),
            row(NO_CALIBRATION, "B", "D", 12.0),
            row(NO_CALIBRATION, "D", "B", 14.0),
            row("fit", "A", "C", 4.0),
            row("fit", "A", "B", 99.0),
            row("fit", "B", "D", 6.0),
            row("fit", "D", "B", 8.0),
            row("learned", "A", "C", 5.0),
            row("learned", "C", "A", 7.0),
            row("learned", "B", "D", 3.0),
            row("learned", "D", "B", 5.0),
        ];
        let fold_of = |name: &str| usize::from(name == "B" || name == "D");
        let rows = summarize_folds(&heldout, &[100.0], 2, fold_of);
        let mean = |fold: &str, method: &str| {
            let r = rows
                .iter()
                .find(|r| r.fold == fold && r.summary.method == method)
                .unwrap();
            (r.summary.mean_cm_s, r.summary.calibrations)
        };
        // Fold 1 keeps only A → C; fold 2 both pairs.
        assert_eq!(mean("1", NO_CALIBRATION), (10.0, 1));
        assert_eq!(mean("1", "learned"), (5.0, 1));
        assert_eq!(mean("2", "fit"), (7.0, 2));
        // Over all folds: A 5, B 3, D 5.
        assert_eq!(mean("all", "learned"), ((5.0 + 3.0 + 5.0) / 3.0, 3));
        assert_eq!(mean("all", NO_CALIBRATION), (12.0, 3));
    }

    #[test]
    fn a_clock_kept_is_told_from_a_failed_fit_and_names_its_scored_trajectory() {
        let method = refound_label("installation lever", 60.0);
        let kept = clock_kept(&method, ("T1", 400.0), "T12", "a: b");
        assert_eq!(clock_kept_on(&kept), Some("T12"));
        assert!(kept.why.starts_with("on T12: a: b;"), "{}", kept.why);
        let failed = FitFailure {
            method: "installation lever".into(),
            calibration: "T1".into(),
            window_s: 400.0,
            why: "on T12: it failed".into(),
        };
        assert_eq!(clock_kept_on(&failed), None);
    }
}
