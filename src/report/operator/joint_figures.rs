//! The figure of a joint calibration's report, against a velocity reference or fixes,
//! drawn with the kit's [`draw_forest`]: a forest plot, a panel per vehicle term, each
//! recording's own estimate (what the spread between dives is read from) with its 95 %
//! interval, the joint estimate with its, the vehicle's interval between dives and the
//! band a next dive's own fit should fall in. Its numbers are the printed ones: the
//! caption gives, per term, the joint estimate, its standard deviation and the two
//! intervals as the vehicle's table prints them; each recording's row is its printed
//! own fit (against a velocity reference its cell of the table of the recordings' own
//! fits, [`own_fit`], which both read; against fixes its cell of the dives' table, ±
//! Student's t times the standard deviation printed there). In: a
//! [`JointCalibration`] or a [`JointFixCalibration`]. Out: the figure.

use crate::installation::estimate::between_dives::{BetweenDives, MIN_DIVES};
use crate::installation::estimate::bound::ReadNoise;
use crate::operator::calibrate_fixes_joint::JointFixCalibration;
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

/// A joint calibration's vehicle terms as the forest plot draws them: the recordings'
/// names; each term's name, joint estimate, standard deviation and 95 % half-width, and
/// spread between dives; each recording's own estimate of each term and its 95 %
/// half-width, `[recording][term]`, where it shows it.
struct Forest<'a> {
    recordings: &'a [String],
    terms: &'a [&'static str],
    value: &'a [f64],
    std: &'a [f64],
    half_95: Vec<f64>,
    between: &'a [Option<BetweenDives>],
    own: Vec<Vec<Option<(f64, f64)>>>,
    /// What the joint estimate's 95 % half-width is, in words.
    joint_95: &'static str,
}

/// The figures of a joint `calibration`, each with its file's stem.
pub fn joint_figures(calibration: &JointCalibration) -> PlotResult<Vec<(String, Outcome)>> {
    let bound = &calibration.joint.bound;
    let terms = 0..bound.names.len();
    forest_figures(&Forest {
        recordings: &calibration.names,
        terms: &bound.names,
        value: &bound.value,
        std: &bound.std,
        half_95: terms.clone().map(|i| bound.half_width_95(i)).collect(),
        between: &calibration.joint.between,
        own: (0..calibration.names.len())
            .map(|k| terms.clone().map(|i| own_fit(calibration, k, i)).collect())
            .collect(),
        joint_95: "Student's t times its standard deviation",
    })
}

/// The figures of a joint `calibration` against fixes, each with its file's stem: each
/// dive's own estimate where the vehicle's weighs it (a yaw set aside is not drawn),
/// its 95 % half-width its own fit's Student's t times its standard deviation.
pub fn joint_fix_figures(calibration: &JointFixCalibration) -> PlotResult<Vec<(String, Outcome)>> {
    let vehicle = &calibration.vehicle;
    let own = (calibration.alone.iter().enumerate())
        .map(|(k, dive)| {
            let t = dive.fit.bound.residual_noise.quantile_95();
            (0..vehicle.names.len())
                .map(|i| vehicle.weighed(k, i).map(|(value, std)| (value, t * std)))
                .collect()
        })
        .collect();
    forest_figures(&Forest {
        recordings: &calibration.names,
        terms: &vehicle.names,
        value: &vehicle.value,
        std: &vehicle.std,
        half_95: vehicle.std.iter().map(|s| Z_975 * s).collect(),
        between: &vehicle.between,
        own,
        joint_95: "1.96 times its standard deviation",
    })
}

/// The normal distribution's 97.5 % quantile.
const Z_975: f64 = 1.959_964;

/// The figures of `forest`: the forest plot.
fn forest_figures(forest: &Forest) -> PlotResult<Vec<(String, Outcome)>> {
    crate::report::kit::plots::render::register_font();
    Ok(vec![("forest".to_string(), drawn_forest(forest)?)])
}

/// The forest plot: a panel per vehicle term the recordings show.
fn drawn_forest(forest: &Forest) -> PlotResult<Outcome> {
    let (mut panels, mut said) = (Vec::new(), Vec::new());
    for (i, name) in forest.terms.iter().enumerate() {
        if !forest.std[i].is_finite() {
            continue;
        }
        let (readable, unit, factor) = readable_term(name);
        let scaled = |(low, high): (f64, f64)| (factor * low, factor * high);
        let mut rows: Vec<ForestRow> = (forest.recordings.iter().enumerate())
            .filter_map(|(k, recording)| {
                let (value, half) = forest.own[k][i]?;
                Some(ForestRow {
                    label: recording.clone(),
                    value: factor * value,
                    interval: scaled((value - half, value + half)),
                    vehicle: false,
                })
            })
            .collect();
        let (value, half) = (forest.value[i], forest.half_95[i]);
        rows.push(ForestRow {
            label: "joint".into(),
            value: factor * value,
            interval: scaled((value - half, value + half)),
            vehicle: true,
        });
        let between = forest.between[i];
        let interval =
            |(low, high): (f64, f64)| format!("{:.4} to {:.4} {unit}", low * factor, high * factor);
        let mut words = format!(
            "{readable} joint {:.4} {unit}, standard deviation {:.4} {unit}",
            value * factor,
            forest.std[i] * factor
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
    let recordings = forest.recordings.len();
    let caption = format!(
        "the vehicle's terms over {recordings} recordings: each recording's own fit ■ and the joint estimate ◆, each with its 95 % interval (the joint one {}); the vehicle's 95 % interval between dives ◆ and a next dive's own fit's (shaded), where {MIN_DIVES} or more recordings show the term: {}",
        forest.joint_95,
        said.join("; ")
    );
    let title = format!("The vehicle's terms over {recordings} recordings, 95 % intervals");
    let svg = draw_forest(&title, &panels)?;
    Ok(Outcome::Drawn(Drawn { caption, svg }))
}
