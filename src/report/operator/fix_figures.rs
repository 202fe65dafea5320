//! The figures of a calibration against position fixes, or of a correction carried to
//! a dive with fixes, drawn with the kit's pieces ([`crate::report::kit::plots::fixes`]):
//! the dead reckoning in plan view against the fixes, with no terms and with them, each
//! piece placed on its first fixes, and the blackout's own dead reckoning ([`track`]),
//! its caption the printed drifts; and the fixes' residual against time
//! ([`fix_residual`]), its caption's RMS computed from the very residuals drawn, which
//! are those the printed RMS is of. In: a [`FixCalibration`] or a [`FixCorrection`] and
//! the recording's name. Out: each figure, or why there is none.

use crate::data::fixes::Fixes;
use crate::installation::estimate::fixes::FixResidual;
use crate::installation::fix_drift::{ANCHOR_S, PlacedTrack};
use crate::operator::calibrate_fixes::FixCalibration;
use crate::operator::correct_fixes::FixCorrection;
use crate::operator::fix_drifts::FixDrifts;
use crate::report::kit::plots::canvas::{Drawn, Outcome};
use crate::report::kit::plots::draw::PlotResult;
use crate::report::kit::plots::fixes::{
    FixResidualTrace, PlanView, ResidualPoint, draw_fix_residual, draw_plan,
};

/// A fit to fixes as its figures draw it: the fixes fitted; of each, by its index, its
/// residual with no terms and with them, each fit's own (and whether that fit kept it);
/// the dead reckoning's drifts, the DVL's first stamp (the times count from it), and
/// what "the terms" were, in words.
struct FixesDrawn<'a> {
    fixes: &'a Fixes,
    before: Vec<(usize, [f64; 2], bool)>,
    after: Vec<(usize, [f64; 2], bool)>,
    drifts: &'a FixDrifts,
    record_start_s: f64,
    terms: &'static str,
}

/// The figures of `calibration` of the recording `name`, each with its file's stem.
pub fn fix_calibration_figures(
    calibration: &FixCalibration,
    name: &str,
) -> PlotResult<Vec<(String, Outcome)>> {
    figures(
        &FixesDrawn {
            fixes: &calibration.fitted_fixes,
            before: (calibration.fit.residuals.iter())
                .map(|r| (r.fix, r.before_m, r.kept))
                .collect(),
            after: after_of(&calibration.fit.residuals),
            drifts: &calibration.drifts,
            record_start_s: calibration.record_start_s,
            terms: "the terms applied",
        },
        name,
    )
}

/// The figures of `correction` of the dive `name`, each with its file's stem.
pub fn fix_correction_figures(
    correction: &FixCorrection,
    name: &str,
) -> PlotResult<Vec<(String, Outcome)>> {
    figures(
        &FixesDrawn {
            fixes: &correction.fitted_fixes,
            before: after_of(&correction.before_residuals),
            after: after_of(&correction.after_residuals),
            drifts: &correction.drifts,
            record_start_s: correction.record_start_s,
            terms: "the installation applied",
        },
        name,
    )
}

/// Each fix of a fit, its residual with the fit's terms and whether the fit kept it.
fn after_of(residuals: &[FixResidual]) -> Vec<(usize, [f64; 2], bool)> {
    (residuals.iter())
        .map(|r| (r.fix, r.after_m, r.kept))
        .collect()
}

/// The plan view and the fixes' residual of `drawn`.
fn figures(drawn: &FixesDrawn, name: &str) -> PlotResult<Vec<(String, Outcome)>> {
    crate::report::kit::plots::render::register_font();
    Ok(vec![
        ("track".to_string(), track(drawn, name)?),
        ("fix_residual".to_string(), fix_residual(drawn, name)?),
    ])
}

/// The plan view: the fixes, each piece's dead reckoning with no terms and with them,
/// and the blackout's.
fn track(drawn: &FixesDrawn, name: &str) -> PlotResult<Outcome> {
    let drifts = drawn.drifts;
    let Some((before, after)) = &drifts.dive else {
        return Ok(Outcome::NotApplicable(
            "no piece of the DVL's record holds fixes at both its ends".into(),
        ));
    };
    let fixes = drawn.fixes;
    let mut outlier = vec![false; fixes.len()];
    for &(fix, _, _) in drawn.after.iter().filter(|p| !p.2) {
        outlier[fix] = true;
    }
    let positions = |outliers: bool| -> Vec<[f64; 2]> {
        (fixes.north_east_m.iter().zip(&outlier))
            .filter(|(_, o)| **o == outliers)
            .map(|(p, _)| *p)
            .collect()
    };
    let tracks = |spans: &[crate::installation::fix_drift::SpanDrift]| -> Vec<Vec<[f64; 2]>> {
        spans.iter().map(|s| s.track.north_east_m.clone()).collect()
    };
    let blackout = drifts.blackout.as_ref();
    let scored = blackout.and_then(|b| b.drift.as_ref().ok());
    let plan = PlanView {
        reference: Vec::new(),
        fixes: positions(false),
        outliers: positions(true),
        withheld: blackout.map_or(Vec::new(), |b| b.withheld.north_east_m.clone()),
        before: tracks(&before.spans),
        after: tracks(&after.spans),
        blackout: scored.map(|(_, after): &(_, _)| {
            let PlacedTrack { north_east_m, .. } = &after.track;
            north_east_m.clone()
        }),
    };
    let mut caption = format!(
        "{name}: the dead reckoning in plan view against the fixes, each piece placed on its fixes of its first {ANCHOR_S} s: at the end {:.3} % of the {:.0} m travelled with no terms (grey), {:.3} % with {}",
        before.end_pct_of(after.distance_m()),
        after.distance_m(),
        after.end_pct(),
        drawn.terms,
    );
    if let Some(blackout) = blackout {
        caption.push_str(&match &blackout.drift {
            Ok((before, after)) => format!(
                "; through the blackout (its {} fixes ringed, withheld from the fit), placed on the fixes before it: {:.3} % of the {:.1} m travelled in it with no terms, {:.3} % with the terms (red)",
                blackout.withheld.len(),
                before.pct_of(after.distance_m),
                after.distance_m,
                after.pct(),
            ),
            Err(why) => format!("; the blackout not scored: {why}"),
        });
    }
    if !plan.outliers.is_empty() {
        caption.push_str(&format!("; {} outliers ×", plan.outliers.len()));
    }
    let title = format!(
        "{name}: dead reckoning against the fixes, end drift {:.3} % → {:.3} %",
        before.end_pct_of(after.distance_m()),
        after.end_pct()
    );
    let svg = draw_plan(&title, &plan)?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}

/// Each fitted fix's residual, north and east, with no terms and with them, against
/// time after the DVL's first sample.
fn fix_residual(drawn: &FixesDrawn, name: &str) -> PlotResult<Outcome> {
    let start_s = drawn.record_start_s;
    let timed = |of: &[(usize, [f64; 2], bool)]| -> Vec<ResidualPoint> {
        (of.iter())
            .map(|&(fix, residual, kept)| (drawn.fixes.time_s[fix] - start_s, residual, kept))
            .collect()
    };
    let trace = FixResidualTrace {
        before: timed(&drawn.before),
        after: timed(&drawn.after),
        blackout_s: (drawn.drifts.blackout.as_ref())
            .map(|b| (b.window.0 - start_s, b.window.1 - start_s)),
    };
    let kept = trace.after.iter().filter(|p| p.2).count();
    let kept_before = trace.before.iter().filter(|p| p.2).count();
    if kept == 0 {
        return Ok(Outcome::NotApplicable("no fix was kept by the fit".into()));
    }
    // Each fit's RMS over the fixes it kept, as it is printed.
    let rms = |of: &[ResidualPoint]| {
        let kept: Vec<&ResidualPoint> = of.iter().filter(|p| p.2).collect();
        let squares: f64 = kept.iter().map(|p| p.1[0].powi(2) + p.1[1].powi(2)).sum();
        (squares / kept.len() as f64).sqrt()
    };
    let outliers = trace.after.len() - kept;
    let caption = format!(
        "{name}: the fixes' horizontal residual (the dead reckoning, each piece placed at the start fitted, less the fix) against time after the DVL's first sample: RMS {:.2} m with no terms, {:.2} m with {}, over the {kept} fixes kept{}{}{}",
        rms(&trace.before),
        rms(&trace.after),
        drawn.terms,
        match kept_before == kept {
            true => String::new(),
            false => format!(" ({kept_before} with no terms, that fit's own)"),
        },
        match outliers {
            0 => String::new(),
            n => format!("; {n} outliers ×, left out"),
        },
        match &drawn.drifts.blackout {
            Some(blackout) => format!(
                "; the blackout shaded, its {} fixes withheld",
                blackout.withheld.len()
            ),
            None => String::new(),
        }
    );
    let title = format!(
        "{name}: the fixes' residual, RMS {:.2} m → {:.2} m",
        rms(&trace.before),
        rms(&trace.after)
    );
    let svg = draw_fix_residual(&title, &trace)?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}
