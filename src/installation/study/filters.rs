//! The study's Kalman filters on one calibration trajectory: each filter of the spec
//! runs once over the trajectory up to the study's longest window; a window takes the filter's state after the
//! window's last sample, and every sample's terms become the rows of the terms against
//! time. In: the spec, the calibration segment and the noise. Out: each filter's run,
//! its terms at a window, and its [`FilterPoint`]s.

use crate::data::paired::PairedRecording;
use crate::installation::estimate::bound::Noise;
use crate::installation::estimate::filter::{FilterStep, run_filter};
use crate::installation::frames::Reference;
use crate::installation::study::rows::FilterPoint;
use crate::installation::study::spec::{Model, StudySpec};
use crate::installation::terms::names::term_set;
use crate::installation::terms::{Installation, TermSet};
use std::ops::Range;

/// One filter's pass over a calibration trajectory.
pub struct FilterRun {
    /// The method's label, "Kalman filter <model>".
    pub label: String,
    pub terms: TermSet,
    pub steps: Vec<FilterStep>,
}

/// The terms a filter holds at the end of a window: the installation, and each
/// parameter's name, value, standard deviation and the bound's.
pub type WindowTerms = (Installation, Vec<(&'static str, f64, f64, f64)>);

/// Every filter of `spec` run over `samples` of the calibration trajectory's
/// `recording`, beside its `reference`: those up to the study's longest window, as no
/// window reads a later one (a recording of hours calibrated on minutes keeps only
/// those minutes' steps).
pub fn run_filters(
    spec: &StudySpec,
    (recording, samples): (&PairedRecording, Range<usize>),
    reference: &Reference,
    noise: Noise,
) -> Vec<FilterRun> {
    spec.methods
        .iter()
        .filter_map(|method| match method {
            Model::Filter { terms, .. } => {
                let terms = term_set(terms);
                let steps = run_filter(
                    &recording.time_s[samples.clone()],
                    &recording.dvl_m_s[samples.clone()],
                    reference,
                    terms,
                    &spec.filter,
                    noise,
                );
                Some(FilterRun {
                    label: method.label(),
                    terms,
                    steps,
                })
            }
            _ => None,
        })
        .collect()
}

impl FilterRun {
    /// The terms after the last sample before `end` (a window's samples are `0..end`);
    /// `None` when the filter took none of them.
    pub fn at_window(&self, end: usize) -> Option<WindowTerms> {
        let step = self.steps.iter().take_while(|s| s.sample < end).last()?;
        let terms = self
            .terms
            .parameter_names()
            .into_iter()
            .zip(step.installation.to_parameters(&self.terms))
            .zip(step.std.iter().zip(&step.bound_std))
            .map(|((name, value), (&std, &bound_std))| (name, value, std, bound_std))
            .collect();
        Some((step.installation, terms))
    }

    /// Every sample's terms, with the filter's and the bound's standard deviations.
    pub fn points(&self, calibration: &str) -> Vec<FilterPoint> {
        let names = self.terms.parameter_names();
        self.steps
            .iter()
            .flat_map(|step| {
                let values = step.installation.to_parameters(&self.terms);
                names.iter().enumerate().map(move |(p, name)| FilterPoint {
                    method: self.label.clone(),
                    calibration: calibration.to_string(),
                    time_s: step.time_s,
                    term: name.to_string(),
                    value: values[p],
                    std: step.std[p],
                    bound_std: step.bound_std[p],
                })
            })
            .collect()
    }
}
