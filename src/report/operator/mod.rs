//! The room of the operator's commands: what `calibrate` and `correct` print about
//! the recordings given on the command line, with the kit's readable terms. In: a
//! calibration of one recording or of several jointly ([`calibrate`]), of a DVL against
//! position fixes ([`fixes`]) or of several such dives jointly ([`fixes_joint`]), or a
//! recording's clock found again and its correction ([`correct`]). Out: the text printed on stdout.
//! They draw no figures: their results are the files `results::corrected` writes.

pub mod calibrate;
pub mod correct;
pub mod fixes;
pub mod fixes_joint;

use crate::installation::dead_reckoning::Drift;

/// The line that says how far a dead reckoning drifts with no terms and with the terms
/// applied, against the reference's positions; empty where it records none.
pub fn drift_line(drift: &Option<(Drift, Drift)>) -> String {
    let Some((before, after)) = drift else {
        return String::new();
    };
    format!(
        "dead-reckoning drift against the reference's positions (horizontal, each piece started at the reference's position, over the {:.0} m travelled): RMS {:.3} % of the distance with no terms, {:.3} % with the terms applied; at the end {:.3} % and {:.3} %\n",
        after.distance_m, before.rms_pct, after.rms_pct, before.end_pct, after.end_pct
    )
}
