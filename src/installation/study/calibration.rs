//! One calibration recording of a study, every window and every method: each method
//! estimates the terms on the recording's first w seconds (no calibration first), and
//! those terms are scored on every other recording (a learned method's only on those of
//! its fold); with `[calibration.dive]`, each installation model is also fitted jointly
//! over the other recordings and scored on this one. In: the spec, the recordings, which
//! one calibrates, the estimators. Out: the [`Calibrated`] rows, the unit a run caches.

use crate::installation::estimate::fit::fit;
use crate::installation::study::estimates::Estimate;
use crate::installation::study::estimators::Estimators;
use crate::installation::study::filters::run_filters;
use crate::installation::study::method::Method;
use crate::installation::study::on_recording::OnRecording;
use crate::installation::study::recording::Recording;
use crate::installation::study::rows::{Calibrated, Estimated, NO_CALIBRATION};
use crate::installation::study::spec::{Model, StudySpec};
use crate::installation::terms::Installation;
use crate::installation::terms::names::term_set;
use rayon::prelude::*;

/// Calibrates on trajectory `c` of `recordings` (its first w seconds for each window of
/// `spec`) with every method, and scores each method's terms on every other trajectory
/// (a learned method's only on those of `c`'s fold, the trajectories its model never
/// saw).
pub fn calibrate_on(
    spec: &StudySpec,
    recordings: &[&Recording],
    c: usize,
    estimators: &Estimators,
) -> Calibrated {
    let noise = spec.noise();
    let calibration = recordings[c];
    let longest_s = spec.windows_s.iter().copied().fold(0.0, f64::max);
    let whole = calibration.first_seconds(longest_s).0;
    let recording = &calibration.recording;
    // The starts of the joint fits, which only `[calibration.dive]` asks for.
    let alone = spec
        .methods
        .iter()
        .filter_map(|model| match model {
            Model::Installation { terms, .. } if spec.dive.is_some() => Some(term_set(terms)),
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
    let on = OnRecording {
        alone,
        spec,
        recordings,
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

impl OnRecording<'_> {
    /// Every method on the first `window_s` seconds: its terms (no calibration first),
    /// their rows, and their scores on the other recordings.
    fn window(&self, window_s: f64) -> Calibrated {
        let (range, _) = self.calibration().first_seconds(window_s);
        let mut failures = Vec::new();
        // Each method, whether its model is a learned one, and its terms.
        let mut methods: Vec<(Method, bool, Estimate)> = vec![(
            Method::single(NO_CALIBRATION),
            false,
            Estimate::bare(Installation::default()),
        )];
        for model in &self.spec.methods {
            match self.estimate(model, range.clone(), window_s) {
                Ok(Some(estimate)) => {
                    let learned = matches!(model, Model::Learned { .. });
                    methods.push((Method::single(model.label()), learned, estimate));
                }
                Ok(None) => {}
                Err(failure) => failures.push(failure),
            }
        }
        let calibration = self.calibration().name.clone();
        let estimated = methods
            .iter()
            .map(|(method, _, estimate)| Estimated {
                method: method.to_string(),
                calibration: calibration.clone(),
                window_s,
                installation: estimate.installation,
            })
            .collect();
        let (mut terms, mut heldout) = (Vec::new(), Vec::new());
        for (method, learned, estimate) in &methods {
            let label = method.to_string();
            terms.extend(self.term_rows(&label, estimate, *learned, window_s));
            let scored = self.scored(*learned);
            let on = (calibration.as_str(), window_s);
            heldout.extend(self.transfer_rows(&label, &estimate.installation, &scored, on));
            let (refound, unfound) = self.refound_rows(method, &estimate.carried(), &scored, on);
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
            for model in &self.spec.methods {
                if let Model::Installation { terms, .. } = model {
                    let terms = term_set(terms);
                    self.jointly(
                        model,
                        (terms, dive.search.dive_terms),
                        window_s,
                        &mut calibrated,
                    );
                }
            }
        }
        calibrated
    }
}
