//! The figures of a calibration against position fixes, drawn with the kit's pieces
//! ([`crate::report::kit::plots::fixes`]): the dead reckoning in plan view against the
//! fixes, with no terms and with them, each piece placed on its first fixes, and the
//! blackout's own dead reckoning ([`track`]), its caption the printed drifts; and the
//! fixes' residual against time ([`fix_residual`]), its caption's RMS computed from the
//! very residuals drawn, which are those the printed RMS is of. In: a
//! [`FixCalibration`] and the recording's name. Out: each figure, or why there is none.

use crate::installation::fix_drift::{ANCHOR_S, PlacedTrack};
use crate::operator::calibrate_fixes::FixCalibration;
use crate::report::kit::plots::canvas::{Drawn, Outcome};
use crate::report::kit::plots::draw::PlotResult;
use crate::report::kit::plots::fixes::{FixResidualTrace, PlanView, draw_fix_residual, draw_plan};

/// The figures of `calibration` of the recording `name`, each with its file's stem.
pub fn fix_calibration_figures(
    calibration: &FixCalibration,
    name: &str,
) -> PlotResult<Vec<(String, Outcome)>> {
    crate::report::kit::plots::render::register_font();
    Ok(vec![
        ("track".to_string(), track(calibration, name)?),
        ("fix_residual".to_string(), fix_residual(calibration, name)?),
    ])
}

/// The plan view: the fixes, each piece's dead reckoning with no terms and with them,
/// and the blackout's.
fn track(calibration: &FixCalibration, name: &str) -> PlotResult<Outcome> {
    let drifts = &calibration.drifts;
    let Some((before, after)) = &drifts.dive else {
        return Ok(Outcome::NotApplicable(
            "no piece of the DVL's record holds fixes at both its ends".into(),
        ));
    };
    let fixes = &calibration.fitted_fixes;
    let outlier: Vec<bool> = (0..fixes.len())
        .map(|j| calibration.fit.outliers.contains(&j))
        .collect();
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
        "{name}: the dead reckoning in plan view against the fixes, each piece placed on its fixes of its first {ANCHOR_S} s: at the end {:.3} % of the {:.0} m travelled with no terms (grey), {:.3} % with the terms applied",
        before.end_pct(),
        after.distance_m(),
        after.end_pct(),
    );
    if let Some(blackout) = blackout {
        caption.push_str(&match &blackout.drift {
            Ok((before, after)) => format!(
                "; through the blackout (its {} fixes ringed, withheld from the fit), placed on the fixes before it: {:.3} % of the {:.1} m travelled in it with no terms, {:.3} % with the terms (red)",
                blackout.withheld.len(),
                before.pct(),
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
        before.end_pct(),
        after.end_pct()
    );
    let svg = draw_plan(&title, &plan)?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}

/// Each fitted fix's residual, north and east, with no terms and with them, against
/// time after the DVL's first sample.
fn fix_residual(calibration: &FixCalibration, name: &str) -> PlotResult<Outcome> {
    let residuals = &calibration.fit.residuals;
    let fixes = &calibration.fitted_fixes;
    let start_s = calibration.record_start_s;
    let trace = FixResidualTrace {
        time_s: (residuals.iter())
            .map(|r| fixes.time_s[r.fix] - start_s)
            .collect(),
        before_m: residuals.iter().map(|r| r.before_m).collect(),
        after_m: residuals.iter().map(|r| r.after_m).collect(),
        kept: residuals.iter().map(|r| r.kept).collect(),
        blackout_s: (calibration.drifts.blackout.as_ref())
            .map(|b| (b.window.0 - start_s, b.window.1 - start_s)),
    };
    let kept = trace.kept.iter().filter(|&&k| k).count();
    if kept == 0 {
        return Ok(Outcome::NotApplicable("no fix was kept by the fit".into()));
    }
    let rms = |of: &[[f64; 2]]| {
        let squares: f64 = (of.iter().zip(&trace.kept))
            .filter(|(_, kept)| **kept)
            .map(|(r, _)| r[0] * r[0] + r[1] * r[1])
            .sum();
        (squares / kept as f64).sqrt()
    };
    let outliers = trace.kept.len() - kept;
    let caption = format!(
        "{name}: the fixes' horizontal residual (the dead reckoning, each piece placed at the start fitted, less the fix) against time after the DVL's first sample: RMS {:.2} m with no terms, {:.2} m with the terms applied, over the {kept} fixes kept{}{}",
        rms(&trace.before_m),
        rms(&trace.after_m),
        match outliers {
            0 => String::new(),
            n => format!("; {n} outliers ×, left out"),
        },
        match &calibration.drifts.blackout {
            Some(blackout) => format!(
                "; the blackout shaded, its {} fixes withheld",
                blackout.withheld.len()
            ),
            None => String::new(),
        }
    );
    let title = format!(
        "{name}: the fixes' residual, RMS {:.2} m → {:.2} m",
        rms(&trace.before_m),
        rms(&trace.after_m)
    );
    let svg = draw_fix_residual(&title, &trace)?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}
