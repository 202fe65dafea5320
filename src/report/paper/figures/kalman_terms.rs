//! The paper run's terms against time: for each DVL, the beam-model Kalman filter's
//! terms (or EM5's) after every sample of the first run's calibration trajectory, each
//! beside its true value, drawn as the kit's grid of term panels
//! ([`draw_panels`]). In: a [`StoredRun`]'s `terms_in_time` table. Out: the figure, or
//! why the run has none.

use crate::report::kit::plots::canvas::{Drawn, Outcome};
use crate::report::kit::plots::draw::PlotResult;
use crate::report::kit::plots::term_panels::{TermPanel, draw_panels};
use crate::results::read::StoredRun;
use crate::vocab::{ErrorModel, EstimatorKind};

/// How a stored term is shown: its title, the factor to the unit shown, the unit.
fn shown(term: &str) -> (String, f64, &'static str) {
    if term.starts_with("scale") {
        (term.to_string(), 100.0, "%")
    } else {
        (term.trim_end_matches("_m_s").to_string(), 100.0, "cm/s")
    }
}

/// For each DVL, the beam-model filter's terms (EM5's, without it) against time on the
/// first run's calibration trajectory.
pub fn kalman_terms(run: &StoredRun) -> PlotResult<Outcome> {
    let rows = &run.terms_in_time;
    let chosen = [
        (EstimatorKind::KalmanBeam, None),
        (EstimatorKind::Kalman, Some(ErrorModel::Em5)),
    ]
    .into_iter()
    .find(|&(e, m)| rows.iter().any(|r| r.estimator == e && r.error_model == m));
    let Some((estimator, error_model)) = chosen else {
        return Ok(Outcome::NotApplicable(
            "the run has no beam-model or EM5 Kalman filter".into(),
        ));
    };
    let mut grid = Vec::new();
    for dvl in run.dvls() {
        let of: Vec<_> = rows
            .iter()
            .filter(|r| r.dvl == dvl && r.estimator == estimator && r.error_model == error_model)
            .collect();
        let panels = crate::first_seen(of.iter().map(|r| r.term.as_str()))
            .into_iter()
            .map(|term| {
                let (title, factor, unit) = shown(term);
                let samples: Vec<_> = of.iter().filter(|r| r.term == term).collect();
                TermPanel {
                    title,
                    unit,
                    points: samples
                        .iter()
                        .map(|r| (r.time_s, factor * r.estimate, factor * r.std))
                        .collect(),
                    reference: samples[0].true_value.map(|v| factor * v),
                    bound_std: samples.iter().map(|r| factor * r.bound_std).collect(),
                }
            })
            .collect();
        grid.push((dvl, panels));
    }
    let caption = format!(
        "{} on {}, first run: the terms against time",
        estimator.label_with(error_model),
        run.spec.calibration.trajectory
    );
    let svg = draw_panels(&caption, &grid, "true value")?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}
