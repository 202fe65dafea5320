//! The terms against time: one panel per term of a Kalman filter, its estimate after
//! every sample with a ±σ band, the reference value (the true term of a simulated DVL,
//! or the trajectory's own batch fit of a real one) dashed, and that value ± the
//! bound's σ for a batch of the samples so far dotted: where the band meets the dotted
//! lines, the filter knows the term as well as the data allow. [`draw_panels`] draws
//! any such grid; [`kalman_terms`] a run's, the beam-model filter's terms (or EM5's)
//! for each DVL. In: a [`StoredRun`]'s `terms_in_time` table, or the installation
//! study's. Out: the figure, or why the run has none.

use crate::installation::study::rows::{FilterPoint, StudyResults};
use crate::report::plots::canvas::{Drawn, Outcome, draw_svg};
use crate::report::plots::draw::*;
use crate::report::plots::scale::Scale;
use crate::report::readable::readable_term;
use crate::results::read::StoredRun;
use crate::vocab::{ErrorModel, EstimatorKind};
use plotters::prelude::*;

/// The colour of the estimate.
const ESTIMATE: RGBColor = RGBColor(31, 119, 180);
/// The colour of its ±σ band: the estimate's, a fifth of it over white.
const BAND: RGBColor = RGBColor(210, 228, 240);

/// One term's panel, in the unit it is shown in.
pub struct TermPanel {
    pub title: String,
    pub unit: &'static str,
    /// (time s, estimate, σ) after each sample.
    pub points: Vec<(f64, f64, f64)>,
    pub reference: Option<f64>,
    /// The bound's σ after each sample, as `points`.
    pub bound_std: Vec<f64>,
}

/// The y range that shows the panel once the first tenth of it has passed.
fn y_scale(panel: &TermPanel) -> Scale {
    let start = panel.points.len() / 10;
    let settled = panel.points.iter().zip(&panel.bound_std).skip(start);
    let mut values: Vec<f64> = Vec::new();
    for (&(_, estimate, std), &bound) in settled {
        values.extend([estimate - std, estimate + std]);
        if let Some(reference) = panel.reference {
            values.extend([reference - bound, reference + bound, reference]);
        }
    }
    let (low, high) = values
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if !(low.is_finite() && high.is_finite()) {
        return Scale::linear(-1.0..1.0);
    }
    let pad = if high > low { 0.08 * (high - low) } else { 1.0 };
    Scale::linear((low - pad)..(high + pad))
}

/// A grid of term panels, one row per entry of `rows` (its name, its panels), under
/// `caption`; `reference` names the dashed line in the legend.
pub fn draw_panels(
    caption: &str,
    rows: &[(String, Vec<TermPanel>)],
    reference: &str,
) -> PlotResult<String> {
    let columns = rows.iter().map(|(_, p)| p.len()).max().unwrap_or(1).max(1);
    let panel_width = if columns > 3 { 330 } else { 420 };
    let width = panel_width * columns as u32 + LEGEND_WIDTH;
    let height = 60 + 300 * rows.len() as u32;
    draw_svg((width, height), |root| {
        let (panels, legend_area) = panels_and_legend(root, caption, width, 1)?;
        let grid = panels[0].split_evenly((rows.len(), columns));
        for (r, (name, row)) in rows.iter().enumerate() {
            for (c, panel) in row.iter().enumerate() {
                let area = &grid[r * columns + c];
                let start = panel.points.first().map_or(0.0, |p| p.0);
                let end = panel.points.last().map_or(1.0, |p| p.0).max(start + 1.0);
                let mut chart = chart_on(area, &format!("{name}: {}", panel.title), 60)
                    .build_cartesian_2d(Scale::linear(0.0..end), y_scale(panel))?;
                mesh(&mut chart)
                    .x_desc("time [s]")
                    .y_desc(format!("[{}]", panel.unit))
                    .draw()?;
                let (y_low, y_high) = {
                    let range = chart.y_range();
                    (range.start, range.end)
                };
                let clip = |v: f64| v.clamp(y_low, y_high);
                let band: Vec<(f64, f64)> = panel
                    .points
                    .iter()
                    .map(|&(t, e, s)| (t, clip(e + s)))
                    .chain(panel.points.iter().rev().map(|&(t, e, s)| (t, clip(e - s))))
                    .collect();
                chart.draw_series(std::iter::once(Polygon::new(band, BAND.filled())))?;
                let estimate = panel.points.iter().map(|&(t, e, _)| (t, clip(e))).collect();
                line(&mut chart, estimate, ESTIMATE, Stroke::Solid)?;
                if let Some(reference) = panel.reference {
                    line(
                        &mut chart,
                        vec![(0.0, reference), (end, reference)],
                        BLACK,
                        Stroke::Dashed,
                    )?;
                    for sign in [-1.0, 1.0] {
                        let bound: Vec<(f64, f64)> = panel
                            .points
                            .iter()
                            .zip(&panel.bound_std)
                            .filter(|(_, b)| b.is_finite())
                            .map(|(&(t, _, _), &b)| (t, clip(reference + sign * b)))
                            .collect();
                        line(&mut chart, bound, GREY, Stroke::Dotted)?;
                    }
                }
            }
        }
        legend(
            &legend_area,
            "Kalman filter",
            &[
                (Swatch::Line(ESTIMATE, Stroke::Solid), "estimate".into()),
                (Swatch::Bar(BAND), "± σ".into()),
                (Swatch::Line(BLACK, Stroke::Dashed), reference.into()),
                (
                    Swatch::Line(GREY, Stroke::Dotted),
                    "± the bound's σ, batch".into(),
                ),
            ],
        )
    })
}

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
pub fn installation_kalman_terms(study: &StudyResults) -> PlotResult<Outcome> {
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
