//! The study's first Kalman filter against time, on the calibration trajectory whose
//! turns show the lever arm best and on the one that shows it least, each term beside
//! that trajectory's own fit of the same model, drawn as the kit's grid of term panels
//! ([`draw_panels`]). In: an [`StudyResults`]' filtered points and terms. Out:
//! the figure, or why the study has none.

use crate::installation::study::rows::{FilterPoint, StudyResults};
use crate::report::kit::plots::canvas::{Drawn, Outcome};
use crate::report::kit::plots::draw::PlotResult;
use crate::report::kit::plots::term_panels::{TermPanel, draw_panels};
use crate::report::kit::readable::readable_term;

/// Trajectory `calibration`'s own fit of `term` at its longest window, by the
/// installation model with the terms of filter `method`; none where it has no fit.
/// (Segments of one vehicle need not share a term, a time offset least: a mean over
/// them could sit where no segment is.)
fn own_fit(study: &StudyResults, method: &str, calibration: &str, term: &str) -> Option<f64> {
    let fitted = method.replacen("Kalman filter", "installation", 1);
    study
        .terms
        .iter()
        .filter(|r| r.method == fitted && r.calibration == calibration && r.term == term)
        .max_by(|a, b| a.window_s.total_cmp(&b.window_s))
        .map(|r| r.value)
}

/// The installation study's first Kalman filter against time on two calibration
/// trajectories: the one whose turns show the lever arm best (the smallest bound on
/// it after the whole trajectory) and the one that shows it least, each term beside
/// that trajectory's own fit of the same model at its longest window.
pub fn kalman_terms(study: &StudyResults) -> PlotResult<Outcome> {
    let Some(method) = study.filtered.first().map(|p| p.method.clone()) else {
        return Ok(Outcome::NotApplicable(
            "the study runs no Kalman filter ([calibration.kalman] models)".into(),
        ));
    };
    let points: Vec<&FilterPoint> = study
        .filtered
        .iter()
        .filter(|p| p.method == method)
        .collect();
    let terms = crate::first_seen(points.iter().map(|p| p.term.as_str()));
    let shown_term = terms
        .iter()
        .copied()
        .find(|t| t.starts_with("lever_arm"))
        .unwrap_or(terms[0]);
    // Each calibration trajectory's last bound on that term.
    let mut last_bound: Vec<(&str, f64)> = Vec::new();
    for p in points.iter().filter(|p| p.term == shown_term) {
        match last_bound.iter_mut().find(|(c, _)| *c == p.calibration) {
            Some(entry) => entry.1 = p.bound_std,
            None => last_bound.push((p.calibration.as_str(), p.bound_std)),
        }
    }
    let by_bound = |a: &&(&str, f64), b: &&(&str, f64)| a.1.total_cmp(&b.1);
    let (Some(turning), Some(straight)) = (
        last_bound.iter().min_by(by_bound),
        last_bound.iter().max_by(by_bound),
    ) else {
        return Ok(Outcome::NotApplicable("the filter kept no sample".into()));
    };
    let grid: Vec<(String, Vec<TermPanel>)> = [turning.0, straight.0]
        .iter()
        .map(|&calibration| {
            let panels = terms
                .iter()
                .map(|&term| {
                    let (title, unit, factor) = readable_term(term);
                    let samples: Vec<&&FilterPoint> = points
                        .iter()
                        .filter(|p| p.calibration == calibration && p.term == term)
                        .collect();
                    TermPanel {
                        title,
                        unit,
                        points: samples
                            .iter()
                            .map(|p| (p.time_s, factor * p.value, factor * p.std))
                            .collect(),
                        reference: own_fit(study, &method, calibration, term).map(|v| factor * v),
                        bound_std: samples.iter().map(|p| factor * p.bound_std).collect(),
                    }
                })
                .collect();
            (calibration.to_string(), panels)
        })
        .collect();
    let caption = format!(
        "{method} against time on {} (its turns show the {} best) and {} (least)",
        turning.0,
        readable_term(shown_term).0,
        straight.0
    );
    let svg = draw_panels(&caption, &grid, "the trajectory's own fit")?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}
