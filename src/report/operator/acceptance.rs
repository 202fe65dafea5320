//! What `--accept` prints of a calibration: each check's value, its 95 % interval, its
//! limit and verdict as a table, then the verdict over them and why. In: an
//! [`Acceptance`]. Out: the text, ending in a newline.

use crate::operator::acceptance::{Acceptance, Verdict};
use comfy_table::{Table, presets::ASCII_MARKDOWN};

/// The acceptance table and the verdict line.
pub fn acceptance_text(acceptance: &Acceptance) -> String {
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    table.set_header(["check", "value", "95 % interval", "limit", "verdict"]);
    for check in &acceptance.checks {
        let unit = check.unit;
        let value = match check.value.is_finite() {
            true => format!("{:.3} {unit}", check.value),
            false => "-".into(),
        };
        let interval = match check.half_width_95 {
            Some(h) if h.is_finite() => format!("± {h:.3} {unit}"),
            _ => "-".into(),
        };
        let limit = match check.marginal_to {
            Some(marginal) => format!(
                "{:.3} {unit} (marginal to {marginal:.3} {unit})",
                check.limit
            ),
            None => format!("{:.3} {unit}", check.limit),
        };
        let verdict = match &check.not_made {
            Some(why) => format!("{}: {why}", check.verdict.words()),
            None => check.verdict.words().to_string(),
        };
        table.add_row([check.what.to_string(), value, interval, limit, verdict]);
    }
    let named = |verdict: Verdict| -> Vec<&str> {
        (acceptance.checks.iter())
            .filter(|c| c.verdict == verdict)
            .map(|c| c.name)
            .collect()
    };
    let verdict = match acceptance.verdict() {
        Verdict::Pass => "accepted: every check passed".to_string(),
        Verdict::Marginal => format!(
            "accepted, marginal: {}",
            named(Verdict::Marginal).join(", ")
        ),
        Verdict::NotChecked | Verdict::Fail => {
            let (failed, unchecked) = (named(Verdict::Fail), named(Verdict::NotChecked));
            let mut why = Vec::new();
            if !failed.is_empty() {
                why.push(format!("failed: {}", failed.join(", ")));
            }
            if !unchecked.is_empty() {
                why.push(format!("not checked: {}", unchecked.join(", ")));
            }
            format!("rejected ({})", why.join("; "))
        }
    };
    let terms = match acceptance.checks.iter().any(|c| c.name != "drift") {
        true => {
            "a term passes where its whole 95 % interval lies within its limit, is marginal where the limit falls inside the interval, fails where the interval lies beyond; "
        }
        false => "",
    };
    format!(
        "acceptance (--accept): {terms}the drift passes within its limit, is marginal within twice it\n{table}\nverdict: {verdict}\n"
    )
}
