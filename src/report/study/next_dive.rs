//! The next-dive table of one joint method: for each vehicle term, how far it moves
//! between the calibration trajectories (the median over the joint calibrations of the
//! spread each found), and how often the trajectory a joint calibration left out falls,
//! by its own fit of the same model on the same window, inside that calibration's 95 %
//! interval for a next dive. In: the joint method's term rows and every term row (the
//! left-out trajectories' own fits). Out: a [`Section`], or none where no row has such an
//! interval.

use super::heldout::window_text;
use crate::installation::study::method::Method;
use crate::installation::study::rows::TermRow;
use crate::report::kit::readable::readable_term;
use crate::report::kit::table::{Entry, Section, Table};

/// The calibration label of a joint fit: all the trajectories but this one.
const ALL_BUT: &str = "all but ";

/// The next-dive section of `method` (a joint one) at `window_s`, from its `rows`; the
/// own fits are the single method's rows of `all`.
pub(super) fn next_dive_section(
    method: &str,
    window_s: f64,
    rows: &[&TermRow],
    all: &[TermRow],
) -> Option<Section> {
    let single = Method::single(Method::parse(method).model).to_string();
    let terms = crate::first_seen(
        rows.iter()
            .filter(|r| r.next_dive_low.is_finite())
            .map(|r| r.term.as_str()),
    );
    if terms.is_empty() {
        return None;
    }
    let own_fit = |trajectory: &str, term: &str| {
        all.iter()
            .find(|r| {
                r.method == single
                    && r.window_s == window_s
                    && r.calibration == trajectory
                    && r.term == term
            })
            .map(|r| r.value)
    };
    let table_rows = terms
        .iter()
        .map(|&term| {
            let (name, unit, factor) = readable_term(term);
            let with_interval: Vec<&&TermRow> = (rows.iter())
                .filter(|r| r.term == term && r.next_dive_low.is_finite())
                .collect();
            let mut spreads: Vec<f64> = with_interval.iter().map(|r| r.between_dives_std).collect();
            spreads.sort_by(f64::total_cmp);
            let median = factor * spreads[spreads.len() / 2];
            let judged: Vec<bool> = with_interval
                .iter()
                .filter_map(|r| {
                    let left_out = r.calibration.strip_prefix(ALL_BUT)?;
                    let value = own_fit(left_out, term)?;
                    Some((r.next_dive_low..=r.next_dive_high).contains(&value))
                })
                .collect();
            let inside = judged.iter().filter(|&&i| i).count();
            vec![
                Entry::Text(name),
                Entry::Text(format!("{median:.4} {unit}")),
                Entry::Text(format!("{inside} of {}", judged.len())),
            ]
        })
        .collect();
    Some(Section {
        title: format!("The next dive: {method}, window {}", window_text(window_s)),
        caption: format!(
            "Each joint calibration of {method} over all the trajectories but one states, per vehicle term, how far the term moves from one trajectory to the next beyond their noise (a random-effects model over each trajectory's own estimate; the median over the joint calibrations here) and the 95 % interval a next trajectory's own fit should fall in. The trajectory it left out is that next one: its own fit ({single}, the first {} of it) inside the interval, of the left-out trajectories with one. The intervals are `next_dive_low` and `next_dive_high` in terms.parquet.",
            window_text(window_s)
        ),
        table: Table::new(
            vec![
                "term".into(),
                "between dives (median)".into(),
                "left-out trajectory's own fit inside".into(),
            ],
            table_rows,
            Vec::new(),
        ),
        paragraph: None,
    })
}
