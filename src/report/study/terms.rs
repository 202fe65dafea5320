//! The terms table of one installation model: the terms each calibration trajectory
//! estimated at the largest window, ± their standard deviation, in units people
//! read ([`readable_term`]: lever arm in m, bias in cm/s, misalignment in degrees, scale
//! in %), those the window cannot show marked and why listed under the table
//! ([`readable_why`]), and the terms left out that a fit's residuals still follow. In: the study's term rows of one method. Out: a [`Section`].

use super::heldout::window_text;
use crate::installation::study::rows::TermRow;
use crate::report::kit::readable::{readable_term, readable_why};
use crate::report::kit::table::{Entry, Section, Table};

/// `name (unit)`, or the name alone.
fn with_unit(term: &str) -> String {
    let (name, unit, _) = readable_term(term);
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
                    let (name, _, factor) = readable_term(term);
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
        if let Some(r) = rows
            .iter()
            .find(|r| r.calibration == *calibration && !r.asked.is_empty())
        {
            notes.push(format!(
                "{calibration}, the residuals still follow a term left out (score test, p < 0.001): {}; the terms above may be absorbing it.",
                r.asked
            ));
        }
        table_rows.push(row);
    }
    Section {
        title: format!(
            "Estimated terms: {method}, window {}",
            window_text(window_s)
        ),
        caption: format!(
            "The terms {method} estimated on the first {} of each calibration trajectory, ± its standard deviation (a fit's from the noise its residuals leave, their level and their correlation in time, a Kalman filter's likewise, read as it runs; the Fisher bound at the specified noise is `bound_std` in terms.parquet); (not seen) marks a term the window cannot show.",
            window_text(window_s)
        ),
        table: Table::new(
            std::iter::once("calibration".to_string())
                .chain(terms.iter().map(|t| with_unit(t)))
                .collect(),
            table_rows,
            notes,
        ),
        paragraph: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terms_read_with_two_significant_digits_of_the_bound() {
        let signs = &crate::report::kit::markdown::SIGNS;
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
        .text(&crate::report::kit::latex::SIGNS);
        assert_eq!(latex, "$-$1.72\\,$\\pm$\\,0.36");
    }
}
