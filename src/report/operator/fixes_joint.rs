//! What a joint `calibrate` with position fixes prints on stdout: each dive read, the
//! vehicle's terms over the dives with their spread between dives (the table a joint
//! velocity calibration prints), then each dive: its fixes fitted, its own estimate of
//! each term, its clock alone and with the vehicle's terms, and the fixes' residual with
//! no terms, with its own and with the vehicle's.
//! In: a [`JointFixCalibration`]. Out: the text.

use crate::installation::estimate::fixes::{FIX_LATENCY, FixFit};
use crate::operator::calibrate_fixes_joint::JointFixCalibration;
use crate::operator::calibrate_joint::AGREEMENT_P_VALUE;
use crate::report::kit::readable::readable_term;
use crate::report::operator::calibrate::{VehicleRows, between_dives_text, vehicle_rows};
use crate::report::operator::fixes::{
    fix_noise, fixes_read, given_latency, read_from, unseen_lines,
};
use comfy_table::{Table, presets::ASCII_MARKDOWN};

/// Everything a joint `calibrate` with fixes prints; ends in a newline.
pub fn joint_fixes_text(calibration: &JointFixCalibration) -> String {
    let JointFixCalibration {
        names,
        alone,
        vehicle,
        ..
    } = calibration;
    let mut text = String::new();
    for (name, dive) in names.iter().zip(alone) {
        text.push_str(&read_from(&dive.read_from));
        text.push_str(&format!(
            "read {name}: {}; {}; the fixes' noise {}\n",
            dive.read,
            fixes_read(
                dive.fixes,
                &dive.fixes_left_out,
                given_latency(dive.fix_latency_s)
            ),
            fix_noise(dive.noise.fix_m, dive.own_noise),
        ));
    }
    let table = vehicle_rows(&VehicleRows {
        names: &vehicle.names,
        value: &vehicle.value,
        std: &vehicle.std,
        bound_std: None,
        between: &vehicle.between,
        agreement: &calibration.agreement,
        recordings: names.len(),
    });
    text.push_str(&format!(
        "calibrated jointly on {} dives with position fixes: each dive fitted alone (as `calibrate --fixes` fits one: its clock, its pieces' start positions and the noise its residuals read its own); each vehicle term is the dives' estimates weighed by their information in it, term by term (each dive's clock profiled out; a dive weighs in on the terms it applied); standard deviation: of that weighed mean, from the dives' noise alone (where the dives disagree beyond it, χ² below, it says too little: the vehicle's 95 % interval, about the random-effects mean, is the one that holds)\n{table}\n",
        names.len()
    ));
    text.push_str(&between_dives_text(names.len()));
    text.push_str(&format!(
        "alone: χ², Σ ((alone − joint) / its standard deviation)² over the dives that applied the term, and its p-value on one fewer degrees of freedom (under {AGREEMENT_P_VALUE}: the dives disagree beyond their intervals)\n"
    ));
    text.push_str(&format!(
        "each dive: its fixes fitted and left out as outliers; its own estimate of each term (± its standard deviation; - where it did not apply it); its clock (and the fixes' latency, where fitted) alone and with the vehicle's terms carried (found again from its fixes: those it is written corrected with; a clock marked {SUM_MARK} is the two summed, where the fixes place their sum and not its split, the latency held at zero; the clock saved, the dives' mean with the vehicle's terms, is then marked so too); the fixes' horizontal residual RMS with no terms, with its own terms and with the vehicle's, m\n{}\n",
        dives_table(calibration)
    ));
    for (name, dive) in names.iter().zip(alone) {
        text.push_str(&unseen_lines(&dive.fit, &format!("{name} alone: ")));
    }
    text
}

/// Each dive's fixes, own terms, clocks and residuals.
fn dives_table(calibration: &JointFixCalibration) -> Table {
    let JointFixCalibration {
        names,
        alone,
        vehicle,
        carried,
        ..
    } = calibration;
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    let mut header = vec!["dive".to_string(), "fixes fitted (outliers)".to_string()];
    header.extend(vehicle.names.iter().map(|n| {
        let (readable, unit, _) = readable_term(n);
        format!("{readable}, alone ({unit})")
    }));
    let latency = alone[0].fit.bound.names.contains(&FIX_LATENCY);
    header.extend([
        "clock alone (s)".to_string(),
        "clock, vehicle's terms (s)".to_string(),
    ]);
    if latency {
        header.extend([
            "fixes' latency alone (s)".to_string(),
            "fixes' latency, vehicle's terms (s)".to_string(),
        ]);
    }
    header.push("residual: none / own / vehicle's (m)".to_string());
    table.set_header(header);
    for (k, name) in names.iter().enumerate() {
        let fit = &alone[k].fit;
        let mut row = vec![
            name.clone(),
            format!("{} ({})", fit.fitted, fit.outliers.len()),
        ];
        row.extend(vehicle.names.iter().enumerate().map(|(i, n)| {
            let (_, _, factor) = readable_term(n);
            let aside = if vehicle.set_aside[k][i] {
                " (set aside: few headings)"
            } else {
                ""
            };
            vehicle.own[k][i].map_or("-".to_string(), |(value, std)| {
                format!("{:.4} ± {:.4}{aside}", value * factor, std * factor)
            })
        }));
        row.push(shown(fit, "time_offset_s"));
        row.push(shown(&carried[k], "time_offset_s"));
        if latency {
            row.push(shown(fit, FIX_LATENCY));
            row.push(shown(&carried[k], FIX_LATENCY));
        }
        let after = carried[k].residual_rms_m;
        row.push(format!(
            "{:.2} / {:.2} / {:.2}",
            alone[k].before_m,
            alone[k].after_m,
            after[0].hypot(after[1])
        ));
        table.add_row(row);
    }
    table
}

/// A fit's clock (that of its installation, where it fitted one about a carried clock)
/// or its fixes' latency, named `name`, and its standard deviation, a clock marked
/// where it is the sum of the clock and the latency ([`FixFit::clock_is_the_sum`]);
/// "-" where it applied none.
fn shown(fit: &FixFit, name: &str) -> String {
    let value = |k: usize| match name {
        "time_offset_s" => fit.installation.time_offset_s,
        _ => fit.bound.value[k],
    };
    let sum = match name == "time_offset_s" && fit.clock_is_the_sum() {
        true => format!(" {SUM_MARK}"),
        false => String::new(),
    };
    match fit.bound.names.iter().position(|n| *n == name) {
        Some(k) if fit.bound.applied[k] => {
            format!("{:.3} ± {:.3}{sum}", value(k), fit.bound.std[k])
        }
        _ => "-".to_string(),
    }
}

/// What marks a clock that is the sum of the DVL's clock and the fixes' latency.
const SUM_MARK: &str = "(clock + latency)";
