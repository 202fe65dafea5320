//! The figures of a calibration's report, drawn with the kit's pieces: the residual
//! before and after against time ([`residual`], the kit's [`draw_residual`]), each
//! caption's RMSE computed from the very samples drawn, which are those the printed
//! RMSE is of; and the Kalman filter's terms against time with their ± band beside the
//! fit of the whole recording ([`filter_terms`], the kit's [`draw_panels`]), the
//! settling time in the caption. `correct`'s report draws its clock search (the RMS
//! at each offset tried, the kit's [`draw_search`]) and its dive's residual before and
//! after the installation carried. In: a [`Calibration`] or a [`Correction`] and the
//! recording's name. Out: each figure, or why there is none.

use crate::data::paired::pieces;
use crate::installation::study::rows::FilterPoint;
use crate::operator::calibrate::Calibration;
use crate::operator::correct::Correction;
use crate::operator::residual::Trace;
use crate::report::kit::plots::canvas::{Drawn, Outcome};
use crate::report::kit::plots::draw::PlotResult;
use crate::report::kit::plots::residual::{ResidualSample, ResidualTrace, draw_residual};
use crate::report::kit::plots::search::{SearchCurve, draw_search};
use crate::report::kit::plots::term_panels::{TermPanel, draw_panels};
use crate::report::kit::readable::readable_term;

/// The figures of `correction` of the dive `name`: its clock search, and its residual
/// before and after the installation carried, after the seconds that found its clock.
pub fn correction_figures(
    correction: &Correction,
    name: &str,
) -> PlotResult<Vec<(String, Outcome)>> {
    crate::report::kit::plots::render::register_font();
    Ok(vec![
        ("clock_search".to_string(), clock_search(correction, name)?),
        ("residual".to_string(), residual(&correction.trace, name)?),
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
    let stride = per_term.div_ceil(FILTER_POINTS_DRAWN).max(1);
    // A row per kind of term (its axes side by side), each panel titled by its term.
    let (mut kinds, mut rows): (Vec<String>, Vec<(String, Vec<TermPanel>)>) = Default::default();
    for term in terms {
        let (title, unit, factor) = readable_term(term);
        let kind = title.trim_end_matches([' ', 'x', 'y', 'z']).to_string();
        let own: Vec<&FilterPoint> = points.iter().filter(|p| p.term == term).collect();
        // A long recording's filter is drawn at every `stride`-th sample and its last.
        let last = own.len().saturating_sub(1);
        let own: Vec<&FilterPoint> = (own.iter().enumerate())
            .filter(|(k, _)| k % stride == 0 || *k == last)
            .map(|(_, p)| *p)
            .collect();
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
        match stride {
            1 => String::new(),
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
