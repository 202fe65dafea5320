//! What `correct` prints on stdout: the installation applied (the vehicle's terms
//! carried, the dive's found again with their standard deviations), then how well it
//! fits the dive after the seconds that found its clock, against the specified noise
//! and the residual at calibration, with a warning where it fits far worse.
//! `correct --fixes` prints the same installation, its clock found again from the
//! fixes, and the fixes' horizontal residual with no terms and with it.
//! In: a [`Correction`] or a [`FixCorrection`]. Out: the text.

use crate::installation::estimate::between_dives::MIN_DIVES;
use crate::installation::estimate::robust::TUKEY_C;
use crate::operator::correct::Correction;
use crate::operator::correct_fixes::{FixCorrection, LatencyFrom};
use crate::operator::installation_file::{SavedInstallation, no_spread_why};
use crate::report::kit::readable::readable_term;
use comfy_table::{Table, presets::ASCII_MARKDOWN};

/// Everything `correct` prints; ends in a newline.
pub fn correction_text(correction: &Correction) -> String {
    let saved = &correction.saved;
    let table = applied_table(correction);
    let mut text = format!(
        "read: {}\ninstallation of {} (calibrated on {}) applied\n{table}\n{}",
        correction.read,
        correction.installation_file.display(),
        saved.recording,
        spread_text(saved),
    );
    if let Some(clock) = &correction.clock {
        text.push_str(&format!(
            "clock found again: the search over ±{} s put the time offset at {:.2} s, least squares at {:.4} s ± {:.4} s (95 %: ± {:.4} s, Student's t on the window's noise){}\n",
            correction.search_s,
            clock.search.best.0,
            clock.installation.time_offset_s,
            clock.time_offset_std_s(),
            clock.time_offset_half_width_95_s(),
            if clock.time_offset_unseen() { " (not seen: its standard deviation is beyond the 0.05 s a clock is held to, or it is tied to another term: these seconds show the clock poorly, and a longer --window-s shows it better)" } else { "" }
        ));
    }
    match correction.after {
        Some(after) => {
            text.push_str(&format!(
                "residual after the first {} s: {:.2} cm/s in total (x {:.2}, y {:.2}, z {:.2} cm/s, body axes, over {} samples, {} outliers aside: a component beyond {TUKEY_C} scales of the rest); the specified noise leaves {:.2}, {}\n",
                correction.window_s,
                100.0 * after.total_m_s,
                100.0 * after.x_m_s,
                100.0 * after.y_m_s,
                100.0 * after.z_m_s,
                after.sample_count,
                correction.outliers,
                correction.noise_cm_s,
                match correction.saved.residual_measured {
                    true => format!("the calibration left {:.2}", correction.calibration_cm_s),
                    false => format!(
                        "the calibration, against fixes, measured no velocity residual (the DVL noise it was given, {:.2}, stands for it)",
                        correction.calibration_cm_s
                    ),
                },
            ));
            if correction.fits_far_worse() {
                text.push_str(&format!(
                    "warning: the installation fits this dive far worse than the calibration (over {:.2} cm/s): a DVL remounted, another vehicle, or a clock that moved; calibrate this dive\n",
                    correction.warning_cm_s()
                ));
            }
            if let Some(block) = correction.jumped() {
                text.push_str(&format!(
                    "warning: from {:.0} s to {:.0} s the residual rises to {:.2} cm/s (over {:.2}, where {:.0} to {:.0} s left {:.2}): a clock that jumped mid-dive or a DVL disturbed; correct the dive in parts\n",
                    block.from_s,
                    block.to_s,
                    100.0 * block.rmse.total_m_s,
                    correction.warning_cm_s(),
                    correction.blocks[0].from_s,
                    correction.blocks[0].to_s,
                    100.0 * correction.blocks[0].rmse.total_m_s,
                ));
            }
        }
        None => text.push_str("no sample after the first seconds to score the installation on\n"),
    }
    text.push_str(&super::drift_line(&correction.drift));
    text
}

/// What the next-dive column says: the spread between the dives calibrated on, or
/// that the file holds none.
fn spread_text(saved: &SavedInstallation) -> String {
    if saved.between_dives.is_empty() {
        return format!(
            "the file holds no spread between dives ({}): on this dive the vehicle's terms may differ by more than their standard deviations (a lever arm absorbs what a dive's model leaves out, a DVL's bias moves between dives); a joint calibration over at least {MIN_DIVES} dives gives an interval that holds on the next one\n",
            no_spread_why(saved.dives)
        );
    }
    format!(
        "next dive, 95 %: where this dive's own calibration should find each vehicle term, from how far the terms moved between the {} dives calibrated jointly\n",
        saved.dives
    )
}

/// Each term applied: its value, its standard deviation, whether it was carried, found
/// again on this dive or given, and where a carried term's next-dive interval lies.
fn applied_table(correction: &Correction) -> Table {
    let saved = &correction.saved;
    let mut table = applied_header();
    let dive = saved.dive_term_set().parameter_names();
    let applied = correction.applied.to_parameters(&saved.term_set());
    for (k, term) in saved.terms.iter().enumerate() {
        let (readable, unit, factor) = readable_term(&term.name);
        let found = correction
            .clock
            .as_ref()
            .filter(|_| dive.contains(&term.name.as_str()))
            .and_then(|clock| {
                let i = clock.bound.names.iter().position(|n| *n == term.name)?;
                Some(clock.std[i])
            });
        let (std, from) = match (dive.contains(&term.name.as_str()), found) {
            (true, Some(std)) => (std, format!("this dive's first {} s", correction.window_s)),
            (true, None) => (f64::NAN, "given".to_string()),
            (false, _) => (term.std, "carried".to_string()),
        };
        let std = match std.is_nan() {
            true => "-".to_string(),
            false => format!("{:.4} {unit}", std * factor),
        };
        table.add_row([
            readable,
            format!("{:.4} {unit}", applied[k] * factor),
            std,
            from,
            next_dive(saved, &term.name),
        ]);
    }
    table
}

/// The table of the terms a correction applied, its header alone: each term's value,
/// standard deviation, where it is from, and where a next dive should find it.
fn applied_header() -> Table {
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    table.set_header([
        "term",
        "value",
        "standard deviation",
        "from",
        "next dive, 95 %",
    ]);
    table
}

/// Where a next dive's own calibration should find the term `name`, from the spread
/// between the dives `saved` was calibrated on; "-" where it holds none.
fn next_dive(saved: &SavedInstallation, name: &str) -> String {
    let (_, unit, factor) = readable_term(name);
    saved.spread_of(name).map_or("-".to_string(), |s| {
        let [low, high] = s.next_dive;
        format!("{:.4} to {:.4} {unit}", low * factor, high * factor)
    })
}

/// Everything `correct --fixes` prints; ends in a newline.
pub fn fix_correction_text(correction: &FixCorrection) -> String {
    let saved = &correction.saved;
    let mut table = applied_header();
    let applied = correction.applied.to_parameters(&saved.term_set());
    for (k, term) in saved.terms.iter().enumerate() {
        let (readable, unit, factor) = readable_term(&term.name);
        let (std, from) = match (term.name.as_str(), &correction.clock) {
            ("time_offset_s", Some(clock)) if clock.fit.bound.is_applied("time_offset_s") => (
                format!("{:.4} {unit}", clock.fit.bound.std[0] * factor),
                "this dive's fixes".to_string(),
            ),
            ("time_offset_s", Some(_)) => ("-".to_string(), "carried".to_string()),
            ("time_offset_s", None) => ("-".to_string(), "given".to_string()),
            _ => (
                format!("{:.4} {unit}", term.std * factor),
                "carried".to_string(),
            ),
        };
        let value = format!("{:.4} {unit}", applied[k] * factor);
        table.add_row([readable, value, std, from, next_dive(saved, &term.name)]);
    }
    let mut text = super::fixes::read_from(&correction.read_from);
    text.push_str(&format!(
        "read: {}; {}\ninstallation of {} (calibrated on {}) applied\n{table}\n",
        correction.read,
        super::fixes::fixes_read(
            correction.fixes,
            &correction.fixes_left_out,
            correction.fix_latency.map(|(latency_s, from)| {
                let from = match from {
                    LatencyFrom::Given => "given",
                    LatencyFrom::Carried =>
                        "carried with the installation (its calibration estimated it; --fix-latency-s gives another)",
                };
                (latency_s, from)
            })
        ),
        correction.installation_file.display(),
        saved.recording,
    ));
    text.push_str(&spread_text(saved));
    if let Some(clock) = &correction.clock {
        text.push_str(&clock_text(clock));
    }
    let (before, after) = (correction.before, correction.after);
    text.push_str(&format!(
        "fixes' horizontal residual RMS, each piece of the DVL record started where the fixes put it, over the {:.0} m travelled: {:.2} m ({:.3} % of the distance) with no terms, {:.2} m ({:.3} %) with the installation applied; white fixes of {} alone leave about {:.2} m\n",
        after.distance_m,
        before.rms_m,
        before.pct(),
        after.rms_m,
        after.pct(),
        super::fixes::fix_noise(correction.fix_noise_m, correction.own_noise),
        correction.white_fixes_leave_m,
    ));
    text.push_str(&super::fixes::drift_lines(
        &correction.drifts,
        correction.fix_noise_m,
        "the installation applied",
    ));
    if correction.outside > 0 {
        text.push_str(&format!(
            "{} of the dive's samples lie outside the attitude (or in a gap of it) at the clock applied: written without a velocity, marked outside_reference\n",
            correction.outside
        ));
    }
    text
}

/// How the clock was found again from the fixes, or why the carried one stands.
fn clock_text(clock: &crate::operator::correct_fixes::FixClock) -> String {
    let fit = &clock.fit;
    if !fit.bound.is_applied("time_offset_s") {
        let why: Vec<String> = fit.bound.unseen.iter().map(|u| u.why.to_string()).collect();
        return format!(
            "clock not found again: the {} fixes cannot show it ({}); the carried {:.4} s is applied\n",
            clock.fixes_used,
            why.join("; "),
            clock.carried_s
        );
    }
    format!(
        "clock found again from {} fixes: the time offset at {:.4} s ± {:.4} s (95 %: ± {:.4} s, Student's t on {} degrees of freedom), {:+.4} s from the {:.4} s carried{}\n",
        clock.fixes_used,
        clock.time_offset_s(),
        fit.bound.std[0],
        fit.bound.half_width_95(0),
        fit.bound.residual_noise.freedom,
        fit.bound.value[0],
        clock.carried_s,
        match fit.bound.unseen.is_empty() {
            true => "",
            false =>
                " (seen poorly: its standard deviation is beyond the tolerance a clock is held to)",
        }
    )
}
