//! The figure of a joint calibration's report, drawn with the kit's [`draw_forest`]: a
//! forest plot, a panel per vehicle term, each recording's own estimate (its dive terms
//! free, as the spread between dives is read from) with its 95 % interval, the joint
//! estimate with its, the vehicle's interval between dives and the band a next dive's
//! own fit should fall in. Its numbers are the printed ones: the caption gives, per
//! term, the joint estimate and the two intervals as the vehicle's table prints them,
//! and each recording's row is its cell of the printed table of the recordings' own
//! fits ([`own_fit`], which both read). In: a [`JointCalibration`]. Out: the figure.

use crate::operator::calibrate_joint::JointCalibration;
use crate::report::kit::plots::canvas::{Drawn, Outcome};
use crate::report::kit::plots::draw::PlotResult;
use crate::report::kit::plots::forest::{ForestPanel, ForestRow, draw_forest};
use crate::report::kit::readable::readable_term;

/// Recording `k`'s own estimate of the vehicle term `i` of `calibration` and its 95 %
/// half-width, in the term's unit; `None` where the recording does not show it.
pub fn own_fit(calibration: &JointCalibration, k: usize, i: usize) -> Option<(f64, f64)> {
    let own = &calibration.joint.own[k];
    let term = calibration.joint.bound.names[i];
    let at = own.names.iter().position(|n| *n == term)?;
    own.std[at]
        .is_finite()
        .then(|| (own.value[at], own.half_width_95(at)))
}

/// The figures of a joint `calibration`, each with its file's stem.
pub fn joint_figures(calibration: &JointCalibration) -> PlotResult<Vec<(String, Outcome)>> {
    crate::report::kit::plots::render::register_font();
    Ok(vec![("forest".to_string(), forest(calibration)?)])
}

/// The forest plot: a panel per vehicle term the recordings show.
fn forest(calibration: &JointCalibration) -> PlotResult<Outcome> {
    let bound = &calibration.joint.bound;
    let (mut panels, mut said) = (Vec::new(), Vec::new());
    for (i, name) in bound.names.iter().enumerate() {
        if !bound.std[i].is_finite() {
            continue;
        }
        let (readable, unit, factor) = readable_term(name);
        let scaled = |(low, high): (f64, f64)| (factor * low, factor * high);
        let mut rows: Vec<ForestRow> = (calibration.names.iter().enumerate())
            .filter_map(|(k, recording)| {
                let (value, half) = own_fit(calibration, k, i)?;
                Some(ForestRow {
                    label: recording.clone(),
                    value: factor * value,
                    interval: scaled((value - half, value + half)),
                    vehicle: false,
                })
            })
            .collect();
        let half = bound.half_width_95(i);
        rows.push(ForestRow {
            label: "joint".into(),
            value: factor * bound.value[i],
            interval: scaled((bound.value[i] - half, bound.value[i] + half)),
            vehicle: true,
        });
        let between = calibration.joint.between[i];
        let interval =
            |(low, high): (f64, f64)| format!("{:.4} to {:.4} {unit}", low * factor, high * factor);
        let mut words = format!(
            "{readable} joint {:.4} {unit} ± {:.4} {unit}",
            bound.value[i] * factor,
            half * factor
        );
        if let Some(between) = between {
            rows.push(ForestRow {
                label: "vehicle, between dives".into(),
                value: factor * between.mean,
                interval: scaled(between.vehicle_95()),
                vehicle: true,
            });
            words.push_str(&format!(
                ", vehicle {}, next dive {}",
                interval(between.vehicle_95()),
                interval(between.next_dive_95())
            ));
        }
        said.push(words);
        panels.push(ForestPanel {
            title: readable,
            unit,
            rows,
            band: between.map(|b| scaled(b.next_dive_95())),
        });
    }
    if panels.is_empty() {
        return Ok(Outcome::NotApplicable(
            "no vehicle term is shown by the recordings".into(),
        ));
    }
    let recordings = calibration.names.len();
    let caption = format!(
        "the vehicle's terms over {recordings} recordings: each recording's own fit (its dive terms free) ■ and the joint estimate ◆, each with its 95 % interval; the vehicle's 95 % interval between dives ◆ and a next dive's own fit's (shaded), where {} or more recordings show the term: {}",
        crate::installation::estimate::between_dives::MIN_DIVES,
        said.join("; ")
    );
    let title = format!("The vehicle's terms over {recordings} recordings, 95 % intervals");
    let svg = draw_forest(&title, &panels)?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}
