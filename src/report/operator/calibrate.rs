//! What `calibrate` prints on stdout: the fit's terms with their standard deviations,
//! the terms the recording cannot show and the RMSE before and after; then the Kalman
//! filter's terms after a few lengths of the recording and how long it needed; and of a
//! joint calibration, the vehicle's terms, their agreement across the recordings and
//! each recording's clock.
//! In: a [`Calibration`] or a [`JointCalibration`]. Out: the text.

use crate::evaluate::calibration_time::tolerance_band;
use crate::installation::estimate::between_dives::BetweenDives;
use crate::installation::estimate::between_dives::MIN_DIVES;
use crate::installation::estimate::bound::ReadNoise;
use crate::installation::estimate::filter::GATE_CHI2;
use crate::installation::estimate::fit::TIME_OFFSET_MARGIN_S;
use crate::installation::estimate::residual_noise::ResidualNoise;
use crate::installation::estimate::robust::TUKEY_C;
use crate::installation::estimate::settling::SettlingPoint;
use crate::installation::terms::AxisRmse;
use crate::operator::calibrate::Calibration;
use crate::operator::calibrate_joint::{AGREEMENT_P_VALUE, Agreement, JointCalibration};
use crate::operator::ros::body_axes_terms;
use crate::report::kit::readable::{readable_term, readable_why};
use crate::report::operator::joint_figures::own_fit;
use comfy_table::{Table, presets::ASCII_MARKDOWN};

/// Everything `calibrate` prints: the fit, a blank line, the filter; ends in a newline.
pub fn calibration_text(calibration: &Calibration) -> String {
    format!(
        "{}{}\n\n{}\n",
        printed_frames(calibration),
        printed_fit(calibration),
        printed_settling(calibration)
    )
}

/// For a bag: the topics and frames it was read in, then (after the fit) the terms in
/// the body frame's own axes, and the DVL's frame as ROS places it.
fn printed_frames(calibration: &Calibration) -> String {
    let Some(frames) = &calibration.frames else {
        return String::new();
    };
    format!("Read from the bag: {frames}. The terms below are in forward-right-down axes.\n\n")
}

/// For a bag: the terms in the body frame's own axes, and the DVL's frame placed.
fn printed_ros(calibration: &Calibration) -> String {
    let (Some(frames), Some(ros)) = (&calibration.frames, &calibration.ros) else {
        return String::new();
    };
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    table.set_header(["term", "estimate", "standard deviation"]);
    for (name, value, std) in body_axes_terms(&calibration.bound, frames.axes) {
        let (readable, unit, factor) = readable_term(&name);
        table.add_row([
            readable,
            format!("{:.4} {unit}", value * factor),
            format!("{:.4} {unit}", std * factor),
        ]);
    }
    format!(
        "\n\nThe same terms in {}'s own axes ({}):\n\n{table}\n\nThe DVL's frame {} in {}, as found: {}\n",
        frames.body,
        frames.axes.words(),
        ros.dvl_frame,
        ros.body,
        ros.static_transform_publisher()
    )
}

/// The terms of a calibration with their standard deviations, the terms the window
/// cannot show and why, and the RMSE against the reference before and after.
fn printed_fit(calibration: &Calibration) -> String {
    let Calibration {
        bound,
        fitted,
        noise,
        ..
    } = calibration;
    let table = super::terms_table(bound, |_| true);
    let shown = bound.residual_noise;
    let assumed = 100.0 * noise.per_axis_m_s();
    let mut text = format!(
        "read: {}\ncalibrated on {} samples (those {TIME_OFFSET_MARGIN_S} s inside the reference), {} of them outliers (a residual component beyond {TUKEY_C} scales of the rest), given no weight\n{table}\n",
        calibration.read,
        fitted.sample_count,
        fitted.outliers()
    );
    let (level, correlation) = residual_noise(&shown);
    text.push_str(&format!(
        "standard deviation: from the noise the fit leaves, per axis x, y, z {level} cm/s with a correlation of {correlation} from one sample to the next (an AR(1) noise); 95 % interval: ± {:.3} standard deviations, Student's t on the {:.0} degrees of freedom that noise is read with; bound: from the specified white noise of {assumed:.2} cm/s per axis, the best these samples could give\n",
        shown.quantile_95(),
        shown.freedom(),
    ));
    for asked in &calibration.asked {
        text.push_str(&format!(
            "the residuals still follow a term left out: {} (score test χ² {:.1} on {} degree{} of freedom, p {}): the terms fitted without it may be absorbing it, and their intervals cannot show that; add it with --terms\n",
            asked.term,
            asked.statistic,
            asked.freedom,
            if asked.freedom == 1 { "" } else { "s" },
            if asked.p_value < 1e-6 { "< 1e-6".to_string() } else { format!("{:.1e}", asked.p_value) },
        ));
    }
    for unseen in &bound.unseen {
        text.push_str(&format!(
            "not seen here: {}: {}\n",
            readable_term(unseen.term).0,
            readable_why(unseen.term, &unseen.why.to_string())
        ));
    }
    // Each side's RMSE over the samples the reference covers on its clock (at t before,
    // at t + τ after): a clock searched seconds away leaves the ends one side only.
    let counted = |rmse: Option<AxisRmse>| rmse.map_or(calibration.scored, |r| r.sample_count);
    let before_on = match counted(calibration.before) == counted(calibration.after) {
        true => String::new(),
        false => format!(" (on the {} it covers at t)", counted(calibration.before)),
    };
    text.push_str(&format!(
        "RMSE against the reference, body frame, on the {} of {} samples {TIME_OFFSET_MARGIN_S} s inside it, outliers aside: {}{before_on} before, {} after",
        counted(calibration.after),
        calibration.recorded,
        printed_rmse(calibration.before),
        printed_rmse(calibration.after)
    ));
    let drift = super::drift_line(&calibration.drift);
    text.push_str(format!("\n{drift}").trim_end());
    text.push_str(&printed_ros(calibration));
    text
}

/// An RMSE in cm/s, its total and each axis.
fn printed_rmse(rmse: Option<AxisRmse>) -> String {
    match rmse {
        Some(r) => format!(
            "{:.2} cm/s (x {:.2}, y {:.2}, z {:.2})",
            100.0 * r.total_m_s,
            100.0 * r.x_m_s,
            100.0 * r.y_m_s,
            100.0 * r.z_m_s
        ),
        None => "no sample inside the reference".into(),
    }
}

/// The lengths the printed table shows: round ones below the recording's, the settling
/// time and the whole recording.
const SHOWN_LENGTHS_S: [f64; 9] = [5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0, 2000.0];

/// The filter's terms after a few lengths of the recording (of its first `window`
/// seconds where that was asked), each ± its standard deviation, and the RMSE they leave
/// on the whole recording; then how long the recording needed.
fn printed_settling(calibration: &Calibration) -> String {
    let Some(all) = calibration.curve.last() else {
        return "the Kalman filter took no sample: none lies inside the reference".into();
    };
    let shown = shown_points(calibration, all);
    let gated = calibration.filter.steps.iter().filter(|s| s.gated).count();
    let mut text = format!(
        "the Kalman filter over the same samples, its terms constant, starting at zero{} with standard deviations {}, {gated} of {} samples gated as outliers (innovation beyond χ²₃ {GATE_CHI2} at the specified noise); its terms after each length, ± its standard deviation (from the noise its residuals show so far, as the fit's):\n{}\n",
        match calibration.fitted.mask_centre_s {
            Some(searched) if searched != 0.0 =>
                format!(" but the clock, at the search's {searched:.2} s"),
            _ => String::new(),
        },
        priors(calibration).join(", "),
        calibration.filter.steps.len(),
        settling_table(calibration, &shown, all)
    );
    text.push_str(&verdict(calibration, all));
    text
}

/// The points of the curve the table shows: those at [`SHOWN_LENGTHS_S`], the settling
/// time, and the last.
fn shown_points<'a>(
    calibration: &'a Calibration,
    all: &'a SettlingPoint,
) -> Vec<&'a SettlingPoint> {
    let settled = calibration.settled_s;
    let mut shown: Vec<&SettlingPoint> = calibration
        .curve
        .iter()
        .filter(|p| SHOWN_LENGTHS_S.contains(&p.length_s) || settled == Some(p.length_s))
        .collect();
    if shown.last().is_none_or(|p| p.length_s != all.length_s) {
        shown.push(all);
    }
    shown
}

/// One column per shown length, one row per term, and the RMSE each leaves.
fn settling_table(
    calibration: &Calibration,
    shown: &[&SettlingPoint],
    all: &SettlingPoint,
) -> Table {
    let calibrated_on = if calibration.window_s.is_some() {
        "window"
    } else {
        "all"
    };
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    let mut header = vec!["after".to_string()];
    header.extend(shown.iter().map(|p| {
        if p.length_s == all.length_s {
            format!("{} s ({calibrated_on})", p.length_s)
        } else if calibration.settled_s == Some(p.length_s) {
            format!("{} s (settled)", p.length_s)
        } else {
            format!("{} s", p.length_s)
        }
    }));
    table.set_header(header);
    let terms = calibration.filter.terms;
    for (i, name) in terms.parameter_names().iter().enumerate() {
        let (readable, unit, factor) = readable_term(name);
        let mut row = vec![format!("{readable} ({unit})")];
        row.extend(shown.iter().map(|p| {
            let value = p.step.installation.to_parameters(&terms)[i];
            format!("{:.3} ± {:.3}", value * factor, p.step.std[i] * factor)
        }));
        table.add_row(row);
    }
    let mut rmse = vec!["RMSE on the recording (cm/s)".to_string()];
    rmse.extend(shown.iter().map(|p| format!("{:.2}", p.rmse_cm_s)));
    table.add_row(rmse);
    table
}

/// Each prior of the filter's terms once, with its unit: the lever arm's three
/// components share one.
fn priors(calibration: &Calibration) -> Vec<String> {
    let terms = calibration.filter.terms;
    let mut prior: Vec<String> = Vec::new();
    for (&kind, name) in terms.parameter_kinds().iter().zip(terms.parameter_names()) {
        let (_, unit, factor) = readable_term(name);
        let std = format!("{} {unit}", calibration.settings.prior.of(kind) * factor);
        if !prior.contains(&std) {
            prior.push(std);
        }
    }
    prior
}

/// How long the recording (or its window) needed, or that the filter diverged.
fn verdict(calibration: &Calibration, all: &SettlingPoint) -> String {
    let tolerance_pct = calibration.tolerance_pct;
    let of = if calibration.window_s.is_some() {
        "of the window"
    } else {
        "of the recording"
    };
    let before_cm_s = calibration.before.map_or(f64::NAN, |r| 100.0 * r.total_m_s);
    let after_cm_s = calibration.after.map_or(f64::NAN, |r| 100.0 * r.total_m_s);
    let band_cm_s = tolerance_band(tolerance_pct / 100.0, before_cm_s, after_cm_s);
    match calibration.settled_s {
        Some(length_s) => format!(
            "after {length_s} s the filter's terms leave an RMSE on the whole recording within ±{band_cm_s:.2} cm/s of the {:.2} cm/s they leave after all {} s {of} ({tolerance_pct} % of what calibration changes here: {before_cm_s:.2} cm/s before it, {after_cm_s:.2} after the fit of all of it), and stay there, though a term whose ± is still wide then is not pinned down (scored on this recording, not on another dive)",
            all.rmse_cm_s, all.length_s,
        ),
        None => format!(
            "the filter's terms after all {} s {of} leave no finite RMSE on the recording: the filter diverged",
            all.length_s
        ),
    }
}

/// What a joint `calibrate` prints: the vehicle's terms over every recording with their
/// standard deviations and bound, beside the spread of the recordings fitted alone and
/// whether they agree; then each recording's own terms (its clock) and residual.
pub fn joint_text(calibration: &JointCalibration) -> String {
    let JointCalibration {
        joint,
        names,
        noise,
        ..
    } = calibration;
    let bound = &joint.bound;
    let table = vehicle_table(calibration);
    let samples: usize = joint.sample_counts.iter().sum();
    let mut text: String = names
        .iter()
        .zip(&calibration.reads)
        .map(|(name, read)| format!("read {name}: {read}\n"))
        .collect();
    text += &format!(
        "calibrated jointly on {} recordings, {samples} samples (those {TIME_OFFSET_MARGIN_S} s inside each reference), {} of them outliers (a residual component beyond {TUKEY_C} scales of the rest; {} per recording), given no weight: the vehicle's terms shared, each recording's {} its own\n{table}\n",
        names.len(),
        joint.outliers.iter().sum::<usize>(),
        joint
            .outliers
            .iter()
            .map(usize::to_string)
            .collect::<Vec<_>>()
            .join(", "),
        joint.dive_terms.parameter_names().join(", ")
    );
    let shown = bound.residual_noise;
    let specified = 100.0 * noise.per_axis_m_s();
    let level = (shown.std_m_s.iter().map(|s| s * s).sum::<f64>() / 3.0).sqrt() * 100.0;
    let (per_axis, correlation) = residual_noise(&shown);
    text.push_str(&format!(
        "residuals: {per_axis} cm/s per axis x, y, z (correlation {correlation} from one sample to the next) against the specified {specified:.2} cm/s per axis: {}; the standard deviations are from the noise the residuals show, the bound's from the specified noise\n",
        if level <= 1.2 * specified { "consistent with the noise" } else { "above the noise: the model leaves something out, or the noise is larger than specified" }
    ));
    text.push_str(&between_dives_text(names.len()));
    text.push_str(&format!(
        "alone: each recording fitted by itself; χ², Σ ((alone − joint) / its standard deviation)² over the {} recordings, and its p-value on {} degrees of freedom (under {AGREEMENT_P_VALUE}: the recordings disagree beyond their intervals)\n",
        names.len(),
        names.len() - 1
    ));
    text.push_str(&format!("{}\n", dives_table(calibration)));
    text.push_str(&format!(
        "each recording's own fit of the vehicle's terms, its dive terms free (what the spread between dives is read from): estimate ± its 95 % interval\n{}\n",
        own_table(calibration)
    ));
    text
}

/// What the columns of the spread between dives say, for `dives` recordings; or, for
/// fewer than three, that there is none.
pub(crate) fn between_dives_text(dives: usize) -> String {
    if dives < MIN_DIVES {
        return format!(
            "between dives: with {dives} recordings the spread of the terms from one dive to the next cannot be estimated (it takes {MIN_DIVES} or more): on the next dive the terms may differ by more than their standard deviations; calibrate jointly over at least {MIN_DIVES} dives\n"
        );
    }
    format!(
        "between dives: how far each term moves from one recording to the next beyond their noise (a random-effects model over each recording's own estimate, its spread by Paule and Mandel's method, over the recordings that show the term); vehicle's term, 95 %: its interval where the dives differ, about the recordings' random-effects mean (Hartung and Knapp, Student's t on {} degrees of freedom, fewer where a term is shown by fewer recordings; where the recordings agree more closely than their noise it can be narrower than the standard deviation's, and holds 95 % over calibrations); next dive's own fit, 95 %: where a next dive's own calibration, as long as these, should find the term\n",
        dives - 1
    )
}

/// The noise a fit's residuals show, as both calibrations print it: its level per axis
/// x, y, z in cm/s, and its correlation from one sample to the next, each "a, b, c".
fn residual_noise(shown: &ResidualNoise) -> (String, String) {
    let [x, y, z] = shown.std_m_s.map(|s| 100.0 * s);
    let [rx, ry, rz] = shown.lag_one;
    (
        format!("{x:.2}, {y:.2}, {z:.2}"),
        format!("{rx:.2}, {ry:.2}, {rz:.2}"),
    )
}

/// The vehicle's terms of a joint calibration, beside the recordings fitted alone.
fn vehicle_table(calibration: &JointCalibration) -> Table {
    let bound = &calibration.joint.bound;
    vehicle_rows(&VehicleRows {
        names: &bound.names,
        value: &bound.value,
        std: &bound.std,
        bound_std: Some(&bound.bound_std),
        between: &calibration.joint.between,
        agreement: &calibration.agreement,
        recordings: calibration.names.len(),
    })
}

/// The vehicle's terms of a joint calibration, as its table shows them.
pub(crate) struct VehicleRows<'a> {
    pub names: &'a [&'static str],
    pub value: &'a [f64],
    /// Each term's standard deviation; infinite for one no recording shows.
    pub std: &'a [f64],
    /// The Fisher bound's standard deviations, where the calibration gives one.
    pub bound_std: Option<&'a [f64]>,
    pub between: &'a [Option<BetweenDives>],
    pub agreement: &'a [Agreement],
    pub recordings: usize,
}

/// The table of the vehicle's terms `rows`: each one's joint estimate and standard
/// deviation (and bound), its spread between dives with the vehicle's and a next dive's
/// 95 % intervals, and how far the recordings alone lie from it.
pub(crate) fn vehicle_rows(rows: &VehicleRows) -> Table {
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    let mut header = vec!["vehicle term", "joint estimate", "standard deviation"];
    if rows.bound_std.is_some() {
        header.push("bound (specified noise)");
    }
    header.extend([
        "between dives",
        "vehicle's term, 95 %",
        "next dive's own fit, 95 %",
        "alone: χ² (p)",
    ]);
    table.set_header(header);
    for (i, name) in rows.names.iter().enumerate() {
        let (readable, unit, factor) = readable_term(name);
        if !rows.std[i].is_finite() {
            table.add_row([readable, "0 (not applied: no recording shows it)".into()]);
            continue;
        }
        let agree = &rows.agreement[i];
        let mark = if agree.p_value < AGREEMENT_P_VALUE {
            ", disagree"
        } else {
            ""
        };
        let interval =
            |(low, high): (f64, f64)| format!("{:.4} to {:.4} {unit}", low * factor, high * factor);
        let between = rows.between[i];
        let none = || "-".to_string();
        let mut row = vec![
            readable,
            format!("{:.4} {unit}", rows.value[i] * factor),
            format!("{:.4} {unit}", rows.std[i] * factor),
        ];
        if let Some(bound_std) = rows.bound_std {
            row.push(format!("{:.4} {unit}", bound_std[i] * factor));
        }
        row.extend([
            between.map_or_else(none, |b| {
                let of = match b.dives == rows.recordings {
                    true => String::new(),
                    false => format!(" ({} of {} recordings)", b.dives, rows.recordings),
                };
                format!("{:.4} {unit}{of}", b.std * factor)
            }),
            between.map_or_else(none, |b| interval(b.vehicle_95())),
            between.map_or_else(none, |b| interval(b.next_dive_95())),
            format!("{:.1} ({:.1e}{mark})", agree.chi_square, agree.p_value),
        ]);
        table.add_row(row);
    }
    table
}

/// Each recording's own fit of the vehicle's terms, a row each: estimate ± 95 %
/// half-width ([`own_fit`]), of each term the joint fit shows.
fn own_table(calibration: &JointCalibration) -> Table {
    let bound = &calibration.joint.bound;
    let shown: Vec<usize> = (0..bound.names.len())
        .filter(|&i| bound.std[i].is_finite())
        .collect();
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    let mut header = vec!["recording".to_string()];
    header.extend(shown.iter().map(|&i| {
        let (readable, unit, _) = readable_term(bound.names[i]);
        format!("{readable} ({unit})")
    }));
    table.set_header(header);
    for (k, name) in calibration.names.iter().enumerate() {
        let mut row = vec![name.clone()];
        row.extend(shown.iter().map(|&i| {
            let (_, _, factor) = readable_term(bound.names[i]);
            match own_fit(calibration, k, i) {
                Some((value, half)) => format!("{:.4} ± {:.4}", value * factor, half * factor),
                None => "-".to_string(),
            }
        }));
        table.add_row(row);
    }
    table
}

/// Each recording's own terms (its clock) with their standard deviations, and the
/// residual it leaves.
fn dives_table(calibration: &JointCalibration) -> Table {
    let JointCalibration { joint, names, .. } = calibration;
    let mut dives = Table::new();
    dives.load_preset(ASCII_MARKDOWN);
    let dive_names = joint.dive_terms.parameter_names();
    let mut header = vec!["recording".to_string()];
    header.extend(dive_names.iter().map(|n| {
        let (readable, unit, _) = readable_term(n);
        format!("{readable} ({unit})")
    }));
    header.push("residual, total (cm/s)".into());
    dives.set_header(header);
    for (k, name) in names.iter().enumerate() {
        let values = joint.dives[k].to_parameters(&joint.dive_terms);
        let mut row = vec![name.clone()];
        row.extend(dive_names.iter().enumerate().map(|(j, n)| {
            let (_, _, factor) = readable_term(n);
            format!(
                "{:.4} ± {:.4}",
                values[j] * factor,
                joint.dive_std[k][j] * factor
            )
        }));
        let r = joint.residual_rms_m_s[k];
        row.push(format!(
            "{:.2}",
            100.0 * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt()
        ));
        dives.add_row(row);
    }
    dives
}
