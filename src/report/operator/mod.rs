//! The room of the operator's commands: what `calibrate` and `correct` print about
//! the recordings given on the command line, with the kit's readable terms. In: a
//! calibration of one recording or of several jointly ([`calibrate`]), of a DVL against
//! position fixes ([`fixes`]) or of several such dives jointly ([`fixes_joint`]), or a
//! recording's clock found again and its correction ([`correct`]). Out: the text printed on stdout.
//! With `--report`, a calibration's [`figures`] (against fixes, [`fix_figures`]; of
//! several recordings, [`joint_figures`]) and its [`page`]: `report.md` and a
//! self-contained `report.html`; with `--accept`, its [`acceptance`].

pub mod acceptance;
pub mod calibrate;
pub mod correct;
pub mod figures;
pub mod fix_figures;
pub mod page;
pub mod fixes;
pub mod fixes_joint;
pub mod joint_figures;

use crate::installation::dead_reckoning::Reckoning;
use crate::installation::estimate::bound::{ReadNoise, TermBound};
use crate::report::kit::readable::readable_term;
use comfy_table::{Table, presets::ASCII_MARKDOWN};

/// The terms of a calibration against any reference, those `shown` (a fit to
/// horizontal fixes estimates no roll or pitch): each one's estimate, standard
/// deviation, Fisher bound, whether it is applied (and seen poorly), and its 95 %
/// interval, in readable units.
pub fn terms_table<N: ReadNoise>(bound: &TermBound<N>, shown: impl Fn(usize) -> bool) -> Table {
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    table.set_header([
        "term",
        "estimate",
        "standard deviation",
        "bound (specified noise)",
        "applied",
        "95 % interval",
    ]);
    for (k, name) in bound.names.iter().enumerate().filter(|(k, _)| shown(*k)) {
        let (readable, unit, factor) = readable_term(name);
        let applied = match (bound.applied[k], bound.is_unseen(name)) {
            (true, false) => "yes",
            (true, true) => "yes, seen poorly",
            (false, _) => "no, not seen",
        };
        table.add_row([
            readable,
            format!("{:.4} {unit}", bound.value[k] * factor),
            format!("{:.4} {unit}", bound.std[k] * factor),
            format!("{:.4} {unit}", bound.bound_std[k] * factor),
            applied.to_string(),
            format!("± {:.4} {unit}", bound.half_width_95(k) * factor),
        ]);
    }
    table
}

/// The line that says how far a dead reckoning drifts with no terms and with the terms
/// applied, against the reference's positions, both end errors over the distance the
/// one with the terms travelled (on its clock); empty where it records none.
pub fn drift_line(drift: &Option<(Reckoning, Reckoning)>) -> String {
    let Some((before, after)) = drift else {
        return String::new();
    };
    let (before, after) = (before.drift, after.drift);
    format!(
        "dead-reckoning drift against the reference's positions (horizontal, each piece started at the reference's position, over the {:.0} m travelled): RMS {:.3} % of the distance with no terms, {:.3} % with the terms applied; at the end {:.3} % and {:.3} %\n",
        after.distance_m,
        before.rms_pct,
        after.rms_pct,
        before.end_pct_of(after.distance_m),
        after.end_pct
    )
}
