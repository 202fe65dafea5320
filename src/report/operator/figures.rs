//! The figures of a calibration's report, drawn with the kit's pieces: the residual
//! before and after against time ([`residual`], the kit's [`draw_residual`]), each
//! caption's RMSE computed from the very samples drawn, which are those the printed
//! RMSE is of; and the Kalman filter's terms against time with their ± band beside the
//! fit of the whole recording ([`filter_terms`], the kit's [`draw_panels`]), the
//! settling time in the caption; and, where the reference records positions, the dead
//! reckoning in plan view against them, with no terms and with them ([`track`], the
//! kit's [`draw_plan`]), its caption's drifts computed from the very lines drawn, which
//! are the printed ones. `correct`'s report draws its clock search (the RMS at each
//! offset tried, the kit's [`draw_search`]), its dive's residual before and after the
//! installation carried, and its plan view. In: a [`Calibration`] or a [`Correction`]
//! and the recording's name. Out: each figure, or why there is none.

use crate::data::paired::pieces;
use crate::installation::dead_reckoning::{PlacedPiece, Reckoning};
use crate::installation::study::rows::FilterPoint;
use crate::operator::calibrate::Calibration;
use crate::operator::correct::Correction;
use crate::operator::residual::Trace;
use crate::report::kit::plots::canvas::{Drawn, Outcome};
use crate::report::kit::plots::draw::{PlotResult, strided};
use crate::report::kit::plots::fixes::{PlanView, draw_plan};
use crate::report::kit::plots::residual::{ResidualSample, ResidualTrace, draw_residual};
use crate::report::kit::plots::search::{SearchCurve, draw_search};
use crate::report::kit::plots::term_panels::{TermPanel, draw_panels};
use crate::report::kit::readable::readable_term;

/// The figures of `correction` of the dive `name`: its clock search, its residual before
/// and after the installation carried, after the seconds that found its clock, and its
/// dead reckoning in plan view where the reference records positions.
pub fn correction_figures(
    correction: &Correction,
    name: &str,
) -> PlotResult<Vec<(String, Outcome)>> {
    crate::report::kit::plots::render::register_font();
    let terms = "the installation applied";
    Ok(vec![
        ("clock_search".to_string(), clock_search(correction, name)?),
        ("residual".to_string(), residual(&correction.trace, name)?),
        ("track".to_string(), track(&correction.drift, name, terms)?),
    ])
}

/// The clock search of a correction: the RMS at each offset tried, its best, the clock
/// least squares found from there, the search's edges.
fn clock_search(correction: &Correction, name: &str) -> PlotResult<Outcome> {
    let Some(clock) = &correction.clock else {
        return Ok(Outcome::NotApplicable(
            "the clock was given (--time-offset-s), not searched".into(),
        ));
    };
    let search = &clock.search;
    let (low, high) = search.edges_s;
    let curve = SearchCurve {
        tried: (search.tried.iter())
            .map(|&(t, rms)| (t, 100.0 * rms))
            .collect(),
        edges_s: search.edges_s,
        best: (search.best.0, 100.0 * search.best.1),
        found_s: clock.installation.time_offset_s,
    };
    let caption = format!(
        "{name}: the clock search over ±{} s about the carried time offset {:.2} s, on the dive's first {} s: the RMS of the DVL against the carried installation's prediction (all three axes) at each of the {} offsets tried; its best {:.2} s at {:.2} cm/s ◆; least squares from there {:.4} s ± {:.4} s (95 %)",
        correction.search_s,
        (low + high) / 2.0,
        correction.window_s,
        curve.tried.len(),
        curve.best.0,
        curve.best.1,
        curve.found_s,
        clock.time_offset_half_width_95_s(),
    );
    let title = format!(
        "{name}: the clock search, its best {:.2} s at {:.2} cm/s, least squares {:.4} s",
        curve.best.0, curve.best.1, curve.found_s
    );
    let svg = draw_search(&title, &curve)?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}

/// The figures of `calibration` of the recording `name`, each with its file's stem.
pub fn calibration_figures(
    calibration: &Calibration,
    name: &str,
) -> PlotResult<Vec<(String, Outcome)>> {
    crate::report::kit::plots::render::register_font();
    Ok(vec![
        ("residual".to_string(), residual(&calibration.trace, name)?),
        ("filter_terms".to_string(), filter_terms(calibration, name)?),
        (
            "track".to_string(),
            track(&calibration.drift, name, "the terms applied")?,
        ),
    ])
}

/// The residual before and after on every sample scored, per axis, with the yaw rate.
pub fn residual(trace: &Trace, name: &str) -> PlotResult<Outcome> {
    let Some(after) = trace.rmse(false) else {
        return Ok(Outcome::NotApplicable(
            "no sample was scored against the reference".into(),
        ));
    };
    // None where the two clocks lie so far apart that no stamp is in the reference.
    let before =
        (trace.rmse(true)).map_or("-".to_string(), |r| format!("{:.2}", 100.0 * r.total_m_s));
    let times: Vec<f64> = trace.samples.iter().map(|s| s.time_s).collect();
    let cm = |v: Option<[f64; 3]>| v.map(|v| v.map(|c| 100.0 * c));
    // The samples left out within the span drawn.
    let (first, last) = (times[0], times[times.len() - 1]);
    let left_out_s: Vec<f64> = (trace.left_out_s.iter().copied())
        .filter(|t| (first..=last).contains(t))
        .collect();
    let drawn = ResidualTrace {
        samples: (trace.samples.iter())
            .map(|s| ResidualSample {
                time_s: s.time_s,
                before_cm_s: cm(s.before_m_s),
                after_cm_s: cm(s.after_m_s),
                yaw_rate_deg_s: s.yaw_rate_rad_s.to_degrees(),
                outlier: s.outlier,
            })
            .collect(),
        pieces: pieces(&times, trace.gap_limit_s),
        left_out_s: left_out_s.clone(),
        outlier_is: "the fit's outlier (not scored)".into(),
    };
    let outliers = trace.samples.iter().filter(|s| s.outlier).count();
    let caption = format!(
        "{name}: DVL − reference (body frame) before and after the terms: RMSE {before} → {:.2} cm/s, total over the {} samples scored, outliers aside{}{}",
        100.0 * after.total_m_s,
        after.sample_count,
        match outliers {
            0 => String::new(),
            1 => "; 1 outlier ×".to_string(),
            n => format!("; {n} outliers ×"),
        },
        match left_out_s.len() {
            0 => String::new(),
            1 => "; 1 sample left out ▼".to_string(),
            n => format!("; {n} samples left out ▼"),
        },
    );
    let svg = draw_residual(&caption, &drawn)?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}

/// The most samples of a term the filter's figure draws: a longer run is drawn at every
/// k-th sample (the filter's estimate moves slowly; its SVG stays small).
const FILTER_POINTS_DRAWN: usize = 2000;

/// The Kalman filter's terms against time, a row per kind of term, each beside the fit
/// of the whole recording.
pub fn filter_terms(calibration: &Calibration, name: &str) -> PlotResult<Outcome> {
    let points: Vec<FilterPoint> = calibration.filter.points(name);
    if points.is_empty() {
        return Ok(Outcome::NotApplicable("the filter kept no sample".into()));
    }
    let fit = &calibration.bound;
    let terms = crate::first_seen(points.iter().map(|p| p.term.as_str()));
    let per_term = points.len() / terms.len().max(1);
    // A row per kind of term (its axes side by side), each panel titled by its term.
    let (mut kinds, mut rows): (Vec<String>, Vec<(String, Vec<TermPanel>)>) = Default::default();
    for term in terms {
        let (title, unit, factor) = readable_term(term);
        let kind = title.trim_end_matches([' ', 'x', 'y', 'z']).to_string();
        let own: Vec<&FilterPoint> = points.iter().filter(|p| p.term == term).collect();
        // A long recording's filter is drawn at every k-th sample and its last.
        let own = strided(&own, FILTER_POINTS_DRAWN);
        let panel = TermPanel {
            title,
            unit,
            points: (own.iter())
                .map(|p| (p.time_s, factor * p.value, factor * p.std))
                .collect(),
            reference: (fit.names.iter().position(|n| *n == term)).map(|k| factor * fit.value[k]),
            bound_std: own.iter().map(|p| factor * p.bound_std).collect(),
        };
        match kinds.last() {
            Some(last) if *last == kind => rows.last_mut().expect("a row per kind").1.push(panel),
            _ => {
                kinds.push(kind);
                rows.push((String::new(), vec![panel]));
            }
        }
    }
    let caption = format!(
        "{name}: {} against time, each term ± its standard deviation, beside the fit of the whole recording (dashed){}{}",
        calibration.filter.label,
        match per_term.div_ceil(FILTER_POINTS_DRAWN) {
            0 | 1 => String::new(),
            k => format!(", drawn at one sample in {k} of its {per_term}"),
        },
        match calibration.settled_s {
            Some(settled_s) => format!("; settled after {settled_s:.0} s"),
            None => "; it diverged: its terms leave no finite RMSE".to_string(),
        }
    );
    let svg = draw_panels(&caption, &rows, "the fit of the whole recording")?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}

/// The dead reckoning in plan view against the reference's positions, each piece
/// placed on the reference's position at its first sample, with no terms and with
/// `terms`; its caption's end drifts computed from the very lines drawn, both over the
/// distance the reference travelled along the pieces with the terms (each dead
/// reckoning is on its own clock: the reference's path is drawn along both).
fn track(drift: &Option<(Reckoning, Reckoning)>, name: &str, terms: &str) -> PlotResult<Outcome> {
    let Some((before, after)) = drift else {
        return Ok(Outcome::NotApplicable(
            "the reference records no positions (or none along a piece of the DVL's record)".into(),
        ));
    };
    let lines = |of: &Reckoning, reference: bool| -> Vec<Vec<[f64; 2]>> {
        (of.pieces.iter())
            .map(|p| match reference {
                true => p.reference_ne_m.clone(),
                false => p.reckoned_ne_m.clone(),
            })
            .collect()
    };
    let plan = PlanView {
        reference: [lines(before, true), lines(after, true)].concat(),
        fixes: Vec::new(),
        outliers: Vec::new(),
        withheld: Vec::new(),
        before: lines(before, false),
        after: lines(after, false),
        blackout: None,
    };
    let distance_m: f64 = after.pieces.iter().map(PlacedPiece::travelled_m).sum();
    let (before_pct, after_pct) = (
        100.0 * end_error_m(before) / distance_m,
        100.0 * end_error_m(after) / distance_m,
    );
    let caption = format!(
        "{name}: the dead reckoning in plan view against the reference's positions (black), {} placed on the reference's position at its first sample: at the end {before_pct:.3} % of the {distance_m:.0} m travelled with no terms (grey), {after_pct:.3} % with {terms} (blue); RMS over every sample {:.3} % and {:.3} %",
        match after.pieces.len() {
            1 => "its one piece".to_string(),
            n => format!("each of its {n} pieces"),
        },
        before.drift.rms_pct,
        after.drift.rms_pct,
    );
    let title = format!(
        "{name}: dead reckoning against the reference's positions, end drift {before_pct:.3} % → {after_pct:.3} %"
    );
    let svg = draw_plan(&title, &plan)?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}

/// The pieces' horizontal errors at their ends against the reference, summed, m.
fn end_error_m(reckoning: &Reckoning) -> f64 {
    reckoning.pieces.iter().map(PlacedPiece::end_error_m).sum()
}
