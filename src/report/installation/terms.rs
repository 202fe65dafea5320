//! The terms table of one installation model: the terms each calibration trajectory
//! estimated at the largest window, ± the bound's standard deviation, in units people
//! read ([`readable_term`]: lever arm in m, bias in cm/s, misalignment in degrees, scale
//! in %), those the window cannot show marked and why listed under the table
//! ([`readable_why`]). In: the study's term rows of one method. Out: a [`Section`].

use super::heldout::window_text;
use crate::installation::protocol::table_unit;
use crate::installation::rows::TermRow;
use crate::report::plots::scale::three_digits;
use crate::report::section::{Entry, Section, Table};

/// A term's name for people and its unit, and the factor from the stored value (SI,
/// radians, a fraction for a scale) to that unit, the unit as the study's tables give
/// it ([`table_unit`]) and the name without its unit suffix:
/// `lever_arm_x_m` → ("lever arm x", "m", 1), `bias_x_m_s` → ("bias x", "cm/s", 100),
/// `misalignment_x_rad` → degrees, `scale_x` → %.
pub(crate) fn readable_term(term: &str) -> (String, &'static str, f64) {
    readable(term)
}

pub(super) fn readable(term: &str) -> (String, &'static str, f64) {
    let (factor, unit) = table_unit(term);
    let stem = ["_m_s", "_rad", "_m", "_s"]
        .iter()
        .find_map(|suffix| term.strip_suffix(suffix))
        .filter(|_| !term.starts_with("scale"))
        .unwrap_or(term);
    (stem.replace('_', " "), unit, factor)
}

/// A value of a reason in its table unit: three significant digits, trailing zeros
/// dropped (0.136, 0.1, 1.02).
fn reason_number(value: f64) -> String {
    let text = three_digits(value);
    if text.contains('.') && !text.contains('e') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// Why a term is not seen, as the bound stored it ("standard deviation 1.361e-1 above
/// its tolerance 1.000e-1; correlated -0.969 with bias_y_m_s"), in the term's table
/// unit and with the other terms' names for people ("standard deviation 0.136 m above
/// its tolerance 0.1 m, correlated -0.969 with bias y"). A reason of another form is
/// kept as it is.
pub(crate) fn readable_why(term: &str, why: &str) -> String {
    let (_, unit, factor) = readable(term);
    let name = |other: &str| readable(other).0;
    let reason = |reason: &str| -> Option<String> {
        if let Some(rest) = reason.strip_prefix("standard deviation ") {
            let (std, tolerance) = rest.split_once(" above its tolerance ")?;
            let [std, tolerance] = [std, tolerance].map(|v| v.trim().parse::<f64>().ok());
            return Some(format!(
                "standard deviation {} {unit} above its tolerance {} {unit}",
                reason_number(factor * std?),
                reason_number(factor * tolerance?)
            ));
        }
        if let Some(rest) = reason.strip_prefix("correlated ") {
            let (correlation, other) = rest.split_once(" with ")?;
            return Some(format!("correlated {correlation} with {}", name(other)));
        }
        let others = reason.strip_prefix("flat together with ")?;
        let others: Vec<String> = others.split(", ").map(name).collect();
        Some(format!("flat together with {}", others.join(", ")))
    };
    why.split("; ")
        .map(|part| reason(part).unwrap_or_else(|| part.to_string()))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `name (unit)`, or the name alone.
fn with_unit(term: &str) -> String {
    let (name, unit, _) = readable(term);
    if unit.is_empty() {
        name
    } else {
        format!("{name} ({unit})")
    }
}

/// (c): one installation model's terms per calibration trajectory and the terms not
/// seen and why; the paragraph after it (`agreement.rs`) is left to
/// the caller.
pub(super) fn terms_section(method: &str, window_s: f64, rows: &[&TermRow]) -> Section {
    let terms = crate::first_seen(rows.iter().map(|r| r.term.as_str()));
    let calibrations = crate::first_seen(rows.iter().map(|r| r.calibration.as_str()));
    let find = |calibration: &str, term: &str| {
        rows.iter()
            .find(|r| r.calibration == calibration && r.term == term)
    };
    let mut table_rows = Vec::new();
    let mut notes = Vec::new();
    for calibration in &calibrations {
        let mut row = vec![Entry::Text(calibration.to_string())];
        let mut unseen = Vec::new();
        for term in &terms {
            row.push(match find(calibration, term) {
                Some(r) => {
                    let (name, _, factor) = readable(term);
                    if !r.unseen.is_empty() {
                        unseen.push(format!("{name} ({})", readable_why(term, &r.unseen)));
                    }
                    Entry::Term {
                        value: factor * r.value,
                        std: factor * r.std,
                        seen: r.unseen.is_empty(),
                    }
                }
                None => Entry::Missing,
            });
        }
        if !unseen.is_empty() {
            notes.push(format!("{calibration}, not seen: {}.", unseen.join("; ")));
        }
        table_rows.push(row);
    }
    Section {
        title: format!(
            "Estimated terms: {method}, window {}",
            window_text(window_s)
        ),
        caption: format!(
            "The terms {method} estimated on the first {} of each calibration trajectory, ± the standard deviation of the Fisher bound; (not seen) marks a term the window cannot show.",
            window_text(window_s)
        ),
        table: Table {
            header: std::iter::once("calibration".to_string())
                .chain(terms.iter().map(|t| with_unit(t)))
                .collect(),
            rows: table_rows,
            notes,
        },
        paragraph: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn why_a_term_is_not_seen_reads_in_its_table_unit() {
        assert_eq!(
            readable_why(
                "lever_arm_z_m",
                "standard deviation 1.361e-1 above its tolerance 1.000e-1"
            ),
            "standard deviation 0.136 m above its tolerance 0.1 m"
        );
        assert_eq!(
            readable_why(
                "lever_arm_x_m",
                "standard deviation 4.081e-1 above its tolerance 1.000e-1; correlated -0.969 with bias_y_m_s"
            ),
            "standard deviation 0.408 m above its tolerance 0.1 m, correlated -0.969 with bias y"
        );
        assert_eq!(
            readable_why(
                "bias_z_m_s",
                "standard deviation 1.019e-2 above its tolerance 1.000e-2"
            ),
            "standard deviation 1.02 cm/s above its tolerance 1 cm/s"
        );
        assert_eq!(
            readable_why(
                "misalignment_x_rad",
                "standard deviation 9.734e-3 above its tolerance 8.727e-3"
            ),
            "standard deviation 0.558 deg above its tolerance 0.5 deg"
        );
        assert_eq!(
            readable_why("scale", "correlated -0.970 with bias_x_m_s"),
            "correlated -0.970 with bias x"
        );
        assert_eq!(
            readable_why("time_offset_s", "flat together with lever_arm_x_m, scale"),
            "flat together with lever arm x, scale"
        );
        assert_eq!(
            readable_why("time_offset_s", "the residuals do not depend on it"),
            "the residuals do not depend on it"
        );
    }

    #[test]
    fn terms_read_in_their_units() {
        assert_eq!(readable("lever_arm_x_m"), ("lever arm x".into(), "m", 1.0));
        assert_eq!(readable("bias_x_m_s"), ("bias x".into(), "cm/s", 100.0));
        assert_eq!(readable("time_offset_s"), ("time offset".into(), "s", 1.0));
        assert_eq!(readable("scale_x"), ("scale x".into(), "%", 100.0));
        assert_eq!(readable("scale"), ("scale".into(), "%", 100.0));
        let (name, unit, factor) = readable("misalignment_z_rad");
        assert_eq!((name.as_str(), unit), ("misalignment z", "deg"));
        assert!((factor * std::f64::consts::PI - 180.0).abs() < 1e-12);
    }

    #[test]
    fn terms_read_with_two_significant_digits_of_the_bound() {
        let signs = &crate::report::markdown::SIGNS;
        let term = |value, std, seen| Entry::Term { value, std, seen }.text(signs);
        assert_eq!(term(-1.72, 0.36, false), "-1.72 ± 0.36 (not seen)");
        assert_eq!(term(-1.87, 0.013, true), "-1.870 ± 0.013");
        assert_eq!(term(0.72, 0.10, true), "0.72 ± 0.10");
        assert_eq!(term(1234.0, 56.0, true), "1234 ± 56");
        assert_eq!(term(1.0, f64::INFINITY, false), "1.00 ± ∞ (not seen)");
        let latex = Entry::Term {
            value: -1.72,
            std: 0.36,
            seen: true,
        }
        .text(&crate::report::latex::SIGNS);
        assert_eq!(latex, "$-$1.72\\,$\\pm$\\,0.36");
    }
}
