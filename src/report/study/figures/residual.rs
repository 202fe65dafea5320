//! The installation study's residual figure: one held-out trajectory's DVL minus the
//! reference in the body frame against time, before the correction (grey) and after
//! it (in colour), one panel per axis, and the yaw rate in a panel under them, so that
//! a residual that follows the turns shows as such, drawn by the kit's
//! [`draw_residual`]. A sample whose residual after has a component beyond Tukey's
//! [`TUKEY_C`] scales of the rest (the fit's outliers' test) is marked with a cross and
//! counted in the caption; the lines break where the trace's samples are further apart
//! than the default gap limit (a lost bottom lock). In: a [`StudyResults`]'s trace.
//! Out: the figure, or why the study holds no trace.

use crate::data::paired::{default_gap_limit_s, pieces};
use crate::installation::estimate::robust::{TUKEY_C, outliers_among};
use crate::installation::study::rows::{StudyResults, TracePoint};
use crate::report::kit::plots::canvas::{Drawn, Outcome};
use crate::report::kit::plots::draw::PlotResult;
use crate::report::kit::plots::residual::{ResidualSample, ResidualTrace, draw_residual};

/// Whether each of `points`' residuals after the correction is an outlier.
fn outliers(points: &[&TracePoint]) -> Vec<bool> {
    outliers_among(&points.iter().map(|p| p.after_cm_s).collect::<Vec<_>>())
}

/// One trajectory's residual before and after, per axis, with the yaw rate under it.
pub fn residual(study: &StudyResults) -> PlotResult<Outcome> {
    let Some(first) = study.trace.first() else {
        return Ok(Outcome::NotApplicable(
            "the study holds no residual trace".into(),
        ));
    };
    let points: Vec<&TracePoint> = study
        .trace
        .iter()
        .filter(|p| p.trajectory == first.trajectory)
        .collect();
    let outlying = outliers(&points);
    let count = outlying.iter().filter(|&&o| o).count();
    let caption = caption(&points, count);
    let times: Vec<f64> = points.iter().map(|p| p.time_s).collect();
    let trace = ResidualTrace {
        pieces: pieces(&times, default_gap_limit_s(&times)),
        samples: (points.iter().zip(outlying))
            .map(|(p, outlier)| ResidualSample {
                time_s: p.time_s,
                before_cm_s: Some(p.before_cm_s),
                after_cm_s: Some(p.after_cm_s),
                yaw_rate_deg_s: p.yaw_rate_deg_s,
                outlier,
            })
            .collect(),
        left_out_s: Vec::new(),
        outlier_is: format!("outlier after (beyond {TUKEY_C} scales)"),
    };
    let svg = draw_residual(&caption, &trace)?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}

/// The figure's caption: the trajectory, the method and its calibration, the RMSE
/// before and after over `points`, and the `outliers` marked.
fn caption(points: &[&TracePoint], outliers: usize) -> String {
    let rms = |f: &dyn Fn(&TracePoint) -> f64| {
        (points.iter().map(|p| f(p).powi(2)).sum::<f64>() / points.len() as f64).sqrt()
    };
    let total = |v: [f64; 3]| v.iter().map(|c| c * c).sum::<f64>();
    let before = rms(&|p| total(p.before_cm_s).sqrt());
    let after = rms(&|p| total(p.after_cm_s).sqrt());
    let first = points[0];
    format!(
        "{}: DVL − reference in the body frame, before and after {} calibrated on {} (RMSE {before:.1} → {after:.1} cm/s{})",
        first.trajectory,
        first.method,
        first.calibration,
        match outliers {
            0 => String::new(),
            1 => "; 1 outlier, ×".into(),
            n => format!("; {n} outliers, ×"),
        }
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spikes_after_are_marked_and_counted() {
        // 1 Hz with 30 s lost from 100 s, a 1 cm/s wobble after, and two spikes of 60
        // cm/s (one on y, one on z): they alone are marked.
        let trace: Vec<TracePoint> = (0..300u32)
            .filter(|i| !(100..130).contains(i))
            .map(|i| {
                let wobble = (f64::from(i) * 0.7).sin();
                let mut after_cm_s = [wobble, -wobble, 0.5 * wobble];
                match i {
                    50 => after_cm_s[1] += 60.0,
                    200 => after_cm_s[2] -= 60.0,
                    _ => {}
                }
                TracePoint {
                    trajectory: "T1".into(),
                    method: "installation".into(),
                    calibration: "T2".into(),
                    time_s: f64::from(i),
                    before_cm_s: [5.0, 2.0, 1.0],
                    after_cm_s,
                    yaw_rate_deg_s: 0.0,
                }
            })
            .collect();
        let points: Vec<&TracePoint> = trace.iter().collect();
        let marked: Vec<f64> = (points.iter().zip(outliers(&points)))
            .filter(|(_, o)| *o)
            .map(|(p, _)| p.time_s)
            .collect();
        assert_eq!(marked, [50.0, 200.0]);
        let study = StudyResults {
            trace,
            ..StudyResults::default()
        };
        crate::report::kit::plots::render::register_font();
        let Outcome::Drawn(drawn) = residual(&study).unwrap() else {
            panic!("drawn");
        };
        assert!(
            drawn.caption.ends_with("; 2 outliers, ×)"),
            "{}",
            drawn.caption
        );
    }
}
