//! What `calibrate --fixes` prints on stdout: the DVL, attitude and fixes read, the
//! terms fitted to the fixes with their standard deviations, Fisher bound and 95 %
//! intervals, the terms the fixes cannot show and why (not applied), the fixes left out,
//! and the fixes' residual before and after as metres and as a share of the distance
//! travelled.
//! In: a [`FixCalibration`]. Out: the text.

use crate::installation::estimate::bound::ReadNoise;
use crate::installation::estimate::fixes::{FIX_LATENCY, FixFit};
use crate::installation::estimate::fixes::{FIX_TOLERANCES, MIN_HEADING_SPAN_RAD};
use crate::installation::estimate::robust::TUKEY_C_MODELLED;
use crate::installation::fix_drift::ANCHOR_S;
use crate::operator::calibrate_fixes::FixCalibration;
use crate::operator::fix_drifts::FixDrifts;
use crate::report::kit::readable::{readable_term, readable_why};

/// `fixes` fixes read, each `latency_s` before its stamp where there is a latency (and
/// where it is from, in words), and those left out before any fit, each with its
/// reason.
pub fn fixes_read(
    fixes: usize,
    left_out: &[(&str, usize)],
    latency: Option<(f64, &str)>,
) -> String {
    let mut text = match fixes {
        1 => "1 fix".to_string(),
        n => format!("{n} fixes"),
    };
    if let Some((latency_s, from)) = latency {
        text.push_str(&format!(
            " (each read {} s before its stamp, the latency {from})",
            crate::Shown(latency_s)
        ));
    }
    for (why, count) in left_out {
        text.push_str(&format!(" ({count} more left out: {why})"));
    }
    text
}

/// A latency given with `--fix-latency-s`, as [`fixes_read`] says it: none where zero.
pub fn given_latency(latency_s: f64) -> Option<(f64, &'static str)> {
    (latency_s != 0.0).then_some((latency_s, "given"))
}

/// For fixes read from a bag or a DVL's log, what was read there and how, a paragraph.
pub fn read_from(read: &Option<String>) -> String {
    match read {
        Some(read) => format!("Read {read}.\n\n"),
        None => String::new(),
    }
}

/// The fixes' noise per horizontal axis, `fix_m`, m: as given, or their median where
/// each fix is weighed by its `own` (its covariance).
pub fn fix_noise(fix_m: f64, own: bool) -> String {
    match own {
        true => format!("each of its own covariance, median {fix_m:.2} m per axis"),
        false => format!("{fix_m:.2} m per axis"),
    }
}

/// Everything `calibrate --fixes` prints; ends in a newline.
pub fn fixes_text(calibration: &FixCalibration) -> String {
    let FixCalibration { fit, noise, .. } = calibration;
    let table = super::terms_table(&fit.bound, |k| fit.estimated[k]);
    let mut text = read_from(&calibration.read_from);
    text.push_str(&format!(
        "read: {}; {}, {} fitted ({}{} outside the DVL's pieces, {} outliers beyond Tukey's {TUKEY_C_MODELLED} of their standard deviations, left out), over {} piece{} with a start position each\n{table}\n",
        calibration.read,
        fixes_read(
            calibration.fixes,
            &calibration.fixes_left_out,
            given_latency(calibration.fix_latency_s)
        ),
        fit.fitted,
        match &calibration.drifts.blackout {
            Some(blackout) => format!("{} withheld in the blackout, ", blackout.withheld.len()),
            None => String::new(),
        },
        fit.outside,
        fit.outliers.len(),
        fit.pieces,
        if fit.pieces == 1 { "" } else { "s" },
    ));
    let shape = fit.bound.residual_noise.shape;
    let wander = match shape.wander_ratio {
        0.0 => "white fixes".to_string(),
        ratio => format!(
            "fixes whose error also wanders, {:.2} m per axis with a correlation time of {:.0} s",
            ratio.sqrt() * noise.fix_m,
            shape.wander_time_s
        ),
    };
    text.push_str(&format!(
        "noise: as the residuals read it, the DVL's walk {} times that of white noise of {:.2} cm/s per axis (a DVL noise correlated in time walks further), and {wander}\n",
        crate::Shown(shape.walk_scale),
        100.0 * noise.dvl_m_s,
    ));
    text.push_str(&format!(
        "standard deviation: under that noise, scaled by the variance factor {} the fixes' whitened residuals show (1 where the noise is as given: fixes {}{}); bound: under the noise as given, white fixes and white DVL noise; 95 % interval: Student's t on {} degrees of freedom\n",
        crate::ThreeFigures(fit.bound.residual_noise.variance_factor),
        fix_noise(noise.fix_m, calibration.own_noise),
        if fit.axes == 3 { format!(", depth {:.2} m", noise.depth_m) } else { String::new() },
        fit.bound.residual_noise.freedom,
    ));
    if fit.axes == 2 {
        text.push_str("not estimated: the misalignment's roll and pitch and the lever arm's depth, which horizontal fixes do not feel (give the fixes' depth for roll and pitch)\n");
    }
    text.push_str(&unseen_lines(fit, ""));
    text.push_str(&clock_and_latency(fit));
    text.push_str(&format!(
        "fixes' horizontal residual RMS: {:.2} m with no terms (the start positions alone, to the same fixes), {:.2} m with the terms applied; over the {:.0} m travelled, {:.3} % and {:.3} % of the distance (the fixes' own noise included)\n",
        calibration.before_m,
        calibration.after_m,
        calibration.distance_m,
        100.0 * calibration.before_m / calibration.distance_m,
        100.0 * calibration.after_m / calibration.distance_m,
    ));
    text.push_str(&drift_lines(
        &calibration.drifts,
        noise.fix_m,
        "the terms applied",
    ));
    text.push_str(&format!(
        "every term is applied at its estimate with its standard deviation, however loosely the fixes show it (beyond its tolerance, scale {:.2} %, misalignment {:.2}°, lever arm {:.2} m, time offset {:.2} s, or tied beyond ±0.95 to another, it is said to be seen poorly, as is the yaw over headings spanning under {:.0}°), but where they cannot show it at all: the lever arm and the clock over those headings, or a term the residuals do not depend on; that one is held at zero, as the start positions take its place exactly; and a clock or a latency the fit ran to the edge of its search where that edge lies within its 95 % interval of zero, held at zero with its uncertainty carried into the others'\n",
        100.0 * FIX_TOLERANCES.scale,
        FIX_TOLERANCES.misalignment_rad.to_degrees(),
        FIX_TOLERANCES.lever_arm_m,
        FIX_TOLERANCES.time_offset_s,
        MIN_HEADING_SPAN_RAD.to_degrees(),
    ));
    text
}

/// The dead reckoning against the fixes, with no terms and with `terms` (in words):
/// over the whole dive, and across the blackout where one was asked, its fixes' noise
/// per axis `fix_m`; a line each.
pub fn drift_lines(drifts: &FixDrifts, fix_m: f64, terms: &str) -> String {
    let mut text = match &drifts.dive {
        Some((before, after)) => format!(
            "dead reckoning against the fixes (horizontal; each piece placed on its fixes of its first {ANCHOR_S} s and scored on those of its last {ANCHOR_S} s, the pieces' end errors summed, over the {:.0} m the dead reckoning with {terms} travelled): at the end {:.3} % of the distance with no terms, {:.3} % with {terms} ({:.2} m and {:.2} m)\n",
            after.distance_m(),
            before.end_pct_of(after.distance_m()),
            after.end_pct(),
            before.error_m(),
            after.error_m(),
        ),
        None => "dead reckoning against the fixes: not scored, no piece of the DVL's record holds fixes at both its ends\n".to_string(),
    };
    let Some(blackout) = &drifts.blackout else {
        return text;
    };
    let asked = blackout.asked;
    text.push_str(&format!(
        "blackout from {} s to {} s after the DVL's first sample: its {} fixes withheld from the fit; ",
        crate::Shown(asked.start_s),
        crate::Shown(asked.start_s + asked.length_s),
        blackout.withheld.len()
    ));
    match &blackout.drift {
        Ok((before, after)) => {
            let floor_m = after.noise_floor_m(fix_m);
            text.push_str(&format!(
                "the dead reckoning placed on the {} fixes of the {ANCHOR_S} s before it and scored on the {} of the {ANCHOR_S} s after it, over the {:.1} m travelled between them: at its end {:.3} % of the distance with no terms, {:.3} % with the terms fitted without its fixes ({:.2} m and {:.2} m); white fixes of {:.2} m per axis alone would leave about {floor_m:.2} m ({:.3} %)\n",
                after.anchored.0,
                after.anchored.1,
                after.distance_m,
                before.pct_of(after.distance_m),
                after.pct(),
                before.error_m(),
                after.error_m(),
                fix_m,
                100.0 * floor_m / after.distance_m,
            ));
        }
        Err(why) => text.push_str(&format!("not scored: {why}\n")),
    }
    text
}

/// Each term of `fit` seen poorly (applied) or not seen (not applied), with why, a line
/// each, each line opening with `prefix`.
pub fn unseen_lines(fit: &FixFit, prefix: &str) -> String {
    let mut text = String::new();
    for name in &fit.bound.names {
        let reasons: Vec<String> = (fit.bound.unseen.iter())
            .filter(|u| u.term == *name)
            .map(|u| u.why.to_string())
            .collect();
        if !reasons.is_empty() {
            text.push_str(&format!(
                "{prefix}{}: {}: {}\n",
                if fit.bound.is_applied(name) {
                    "seen poorly, applied"
                } else {
                    "not seen, not applied"
                },
                readable_term(name).0,
                readable_why(name, &reasons.join("; "))
            ));
        }
    }
    text
}

/// Where the DVL's clock and the fixes' latency are both applied, their sum: the shift
/// of the whole track against the fixes, which both make, where the clock alone also
/// reads the attitude at another time than the DVL's velocity. Fixes of metres see the
/// shift far better than that reading, so the two are often tied and their sum known
/// where neither is; where the fit could not place them apart, the clock is their sum
/// ([`FixFit::clock_is_the_sum`]), and the line says so. A line, or nothing.
fn clock_and_latency(fit: &FixFit) -> String {
    if fit.clock_is_the_sum() {
        return "the DVL's clock and the fixes' latency: the fit with both ran one to the edge of its search, and there they are tied (above); these fixes place the shift of the whole track against them, not how the two split it: the latency is held at zero, the time offset printed is their sum with the sum's interval, and the other terms' intervals carry the latency's uncertainty; a velocity corrected by this time offset is read late by the fixes' latency (give it with --fix-latency-s where it is known)\n".to_string();
    }
    let place =
        |name: &str| (fit.bound.names.iter()).position(|n| *n == name && fit.bound.is_applied(n));
    let (Some(clock), Some(latency)) = (place("time_offset_s"), place(FIX_LATENCY)) else {
        return String::new();
    };
    let correlation = fit.bound.correlation[clock][latency];
    let (a, b) = (fit.bound.std[clock], fit.bound.std[latency]);
    let std = (a * a + b * b + 2.0 * correlation * a * b).max(0.0).sqrt();
    let half_width = fit.bound.residual_noise.quantile_95() * std;
    format!(
        "the DVL's clock and the fixes' latency, correlated {correlation:.3}: their sum, the shift of the whole track against the fixes, {:.4} s, standard deviation {std:.4} s, 95 % interval ± {half_width:.4} s{}\n",
        fit.bound.value[clock] + fit.bound.value[latency],
        if correlation.abs() > crate::installation::estimate::bound::CORRELATION_LIMIT {
            " (the fixes tell the two apart only through the attitude read at the DVL's clock; the sum is what they show)"
        } else {
            ""
        },
    )
}
