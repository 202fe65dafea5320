//! A dive's clock and the joint fit, with `[calibration.dive]`: each scored recording's
//! clock re-found from its first w seconds with the method's other terms carried, and
//! scored on its samples after them (where its first seconds cannot show the clock, the
//! calibration's is kept and the failures say so); and each installation model fitted
//! jointly over every recording but the calibration one, each with its own clock, and
//! scored on it. In: a method's terms as a dive carries them. Out: held-out rows, term
//! rows and failures under the method's re-found and joint variants.

use crate::installation::estimate::bound::{Noise, Tolerances};
use crate::installation::estimate::clock::{
    self, Carried, ClockError, ClockSearch, DEFAULT_SEARCH_S, refind,
};
use crate::installation::estimate::fit::TIME_OFFSET_MARGIN_S;
use crate::installation::estimate::joint::{self, JointRecording, joint_fit};
use crate::installation::study::estimates::Estimate;
use crate::installation::study::heldout::transfer_row;
use crate::installation::study::method::Method;
use crate::installation::study::on_recording::OnRecording;
use crate::installation::study::recording::Recording;
use crate::installation::study::rows::{Calibrated, FitFailure, TermRow, TransferRow};
use crate::installation::study::spec::{DiveSpec, Model};
use crate::installation::terms::TermSet;
use std::ops::Range;

/// A `[calibration.dive]` window that no trajectory outlasts (each trajectory's name and
/// time stamps, s), as `(key, message)`: no clock would be found from it and nothing
/// scored after it, where the study would run and say nothing. `validate` and `run`
/// refuse it alike.
pub fn beyond_the_recordings(
    dive: &DiveSpec,
    recordings: &[(&str, &[f64])],
) -> Option<(String, String)> {
    let (name, longest_s) = recordings
        .iter()
        .map(|&(name, time_s)| {
            let span = time_s
                .first()
                .zip(time_s.last())
                .map_or(0.0, |(a, b)| b - a);
            (name, span)
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    let window_s = dive.windows_s.iter().find(|&&w| w >= longest_s)?;
    Some((
        "calibration.dive.window_s".into(),
        format!(
            "{} s is not shorter than any trajectory (the longest, {name:?}, lasts {longest_s:.1} s): no dive's clock would be found from it and nothing scored after it; give a shorter window",
            crate::Shown(*window_s)
        ),
    ))
}

/// A scored recording's clock re-found from its first seconds, and the samples it is
/// scored on after them.
pub struct RefoundClock {
    /// The clock found, with the carried terms; or why the first seconds cannot show it.
    pub found: Result<clock::Clock, ClockError>,
    /// The samples after the first seconds, inside the reference whatever the time
    /// offset.
    pub after: Range<usize>,
}

/// The clock of `scored` re-found from its first `dive_s` seconds with `carried`'s
/// other terms (the dive's terms and their search from `search`; the bound from
/// `noise`, the flag from `tolerances`), and the samples after them that the study
/// scores it on.
pub fn refind_clock(
    scored: &Recording,
    dive_s: f64,
    carried: &Carried,
    search: ClockSearch,
    (noise, tolerances): (Noise, &Tolerances),
) -> RefoundClock {
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
        search,
        (noise, tolerances),
    );
    RefoundClock { found, after }
}

impl OnRecording<'_> {
    /// With `[calibration.dive]`, one method's RMSE on every trajectory it is scored on
    /// with the dive's terms found again, for each of the dive's windows w: from the
    /// trajectory's first w seconds with the method's other terms carried, scored on its
    /// samples after them, as `method` with its clock re-found in w s. Where the clock
    /// cannot be found, the calibration's is kept and the failure says so.
    pub(super) fn refound_rows(
        &self,
        method: &Method,
        carried: &Carried,
        scored: &[&Recording],
        (calibration, window_s): (&str, f64),
    ) -> (Vec<TransferRow>, Vec<FitFailure>) {
        let Some(dive) = &self.spec.dive else {
            return (Vec::new(), Vec::new());
        };
        let (mut rows, mut failures) = (Vec::new(), Vec::new());
        for &dive_s in &dive.windows_s {
            let method = method.clone().refound(dive_s);
            let label = method.to_string();
            for scored in scored {
                let bound = (self.noise, &self.tolerances);
                let clock = refind_clock(scored, dive_s, carried, dive.search, bound);
                let installation = match clock.found {
                    Ok(clock) => clock.installation,
                    Err(why) => {
                        let on = (calibration, window_s);
                        failures.push(clock_kept(&method, on, &scored.name, &why.to_string()));
                        carried.installation
                    }
                };
                let on = (calibration, window_s);
                if let Some(row) = transfer_row(&label, &installation, scored, clock.after, on) {
                    rows.push(row);
                }
            }
        }
        (rows, failures)
    }

    /// With `[calibration.dive]`, the joint calibration of `model`'s `terms` over the
    /// first `window_s` seconds of every recording but this one (the `dive` terms one
    /// set each), scored on this one: its terms' rows and its held-out rows, as the
    /// model's joint method, calibrated on "all but <recording>".
    pub(super) fn jointly(
        &self,
        model: &Model,
        terms: (TermSet, TermSet),
        window_s: f64,
        into: &mut Calibrated,
    ) {
        if self.scored(false).len() < 2 {
            return;
        }
        let method = Method::single(model.label()).jointly();
        let label = method.to_string();
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
        let (refound, unfound) = self.refound_rows(&method, &estimate.carried(), &here, on);
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
            between: joint.between,
        })
    }
}

/// The samples `ranges` of `recordings`, as a joint fit takes them.
fn joint_recordings<'a>(
    recordings: &[&'a Recording],
    ranges: &[Range<usize>],
) -> Vec<JointRecording<'a>> {
    recordings
        .iter()
        .zip(ranges)
        .map(|(s, range)| JointRecording {
            time_s: &s.recording.time_s[range.clone()],
            dvl_m_s: &s.recording.dvl_m_s[range.clone()],
            reference: &s.reference,
        })
        .collect()
}

/// Where the clock of `scored` could not be found again for `method` (a re-found
/// one), calibrated on `calibration` over `window_s`: its row is scored with the
/// calibration's clock, and this entry of the failures says so and why.
fn clock_kept(
    method: &Method,
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
    if !Method::parse(&failure.method).is_refound() {
        return None;
    }
    let (scored, _) = failure.why.strip_prefix("on ")?.split_once(": ")?;
    Some(scored)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_clock_kept_is_told_from_a_failed_fit_and_names_its_scored_trajectory() {
        let method = Method::single("installation lever").refound(60.0);
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
