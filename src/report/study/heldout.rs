//! The held-out tables: (a) each method's mean held-out RMSE at the largest window, total
//! and per axis, with its 95 % interval and its ratio to no calibration, and (b) the same means for every
//! window. In: the study's summary rows. Out: two [`Section`]s; also the order of the
//! methods and windows the other tables follow, and the sentence on the scorings whose
//! clock could not be found again.

use crate::installation::study::clock_kept_on;
use crate::installation::study::method::Method;
use crate::installation::study::rows::{NO_CALIBRATION, StudyResults, SummaryRow};
use crate::report::kit::table::{Entry, Section, Table};

/// The methods in the order the study lists them, no calibration first.
pub(super) fn methods(study: &StudyResults) -> Vec<&str> {
    let mut methods = crate::first_seen(
        study
            .summary
            .iter()
            .map(|r| r.method.as_str())
            .chain(study.heldout.iter().map(|r| r.method.as_str())),
    );
    methods.sort_by_key(|m| *m != NO_CALIBRATION);
    methods
}

/// The windows of the summary, in increasing order.
pub(super) fn windows(study: &StudyResults) -> Vec<f64> {
    let mut windows = crate::first_seen(study.summary.iter().map(|r| r.window_s));
    windows.sort_by(f64::total_cmp);
    windows
}

/// A window as the tables write it: `400 s`.
pub(super) fn window_text(window_s: f64) -> String {
    format!("{window_s} s")
}

fn summary_entry<'a>(
    study: &'a StudyResults,
    method: &str,
    window_s: f64,
) -> Option<&'a SummaryRow> {
    study
        .summary
        .iter()
        .find(|r| r.method == method && r.window_s == window_s)
}

/// With the clock re-found: how many of the scorings (at `window_s`, or at every
/// window) kept the calibration's clock, since the scored trajectory's first seconds
/// did not show its own, and on which trajectories, most first; `None` where none did.
pub fn clocks_kept(study: &StudyResults, window_s: Option<f64>) -> Option<String> {
    let at = |w: f64| window_s.is_none_or(|window_s| w == window_s);
    let kept: Vec<&str> = study
        .failures
        .iter()
        .filter(|f| at(f.window_s))
        .filter_map(clock_kept_on)
        .collect();
    if kept.is_empty() {
        return None;
    }
    let scorings = study
        .heldout
        .iter()
        .filter(|r| at(r.window_s) && Method::parse(&r.method).is_refound())
        .count();
    let mut on: Vec<(&str, usize)> = crate::first_seen(kept.iter().copied())
        .into_iter()
        .map(|scored| (scored, kept.iter().filter(|k| **k == scored).count()))
        .collect();
    on.sort_by_key(|&(_, n)| std::cmp::Reverse(n));
    let on: Vec<String> = on
        .iter()
        .map(|(scored, n)| format!("{scored} {n}"))
        .collect();
    Some(format!(
        "{} of the {scorings} scorings with the clock re-found kept the calibration's clock, since the scored trajectory's first seconds did not show its own (failures.parquet says why): on {}.",
        kept.len(),
        on.join(", ")
    ))
}

/// (a): each method's mean held-out RMSE at the largest window and its ratio.
pub(super) fn heldout_section(study: &StudyResults, methods: &[&str], window_s: f64) -> Section {
    let rows = methods
        .iter()
        .map(|method| {
            let row = summary_entry(study, method, window_s);
            vec![
                Entry::Text(method.to_string()),
                row.map_or(Entry::Missing, |r| Entry::Rmse {
                    mean_cm_s: r.mean_cm_s,
                    ci95_cm_s: r.ci95_cm_s,
                }),
                row.map_or(Entry::Missing, |r| Entry::Rmse {
                    mean_cm_s: r.mean_cm_s / 3f64.sqrt(),
                    ci95_cm_s: r.ci95_cm_s / 3f64.sqrt(),
                }),
                row.map_or(Entry::Missing, |r| Entry::Ratio(r.ratio)),
            ]
        })
        .collect();
    Section {
        title: format!("Held-out RMSE, window {}", window_text(window_s)),
        caption: format!(
            "Mean held-out RMSE in cm/s ± the half-width of its 95 % interval over calibration trajectories, calibrated on the first {} of each, and its ratio to {NO_CALIBRATION}. Total: the three axes together, the root of the sum of their squares; per axis: the root mean square over x, y and z (the total divided by the square root of 3), the figure to hold against a DVL's per-axis noise specification.",
            window_text(window_s)
        ),
        table: Table::new(
            vec![
                "method".into(),
                "held-out RMSE, total (cm/s)".into(),
                "per axis (cm/s)".into(),
                format!("ratio to {NO_CALIBRATION}"),
            ],
            rows,
            Vec::new(),
        ),
        paragraph: None,
    }
}

/// (b): the same means, one column per window.
pub(super) fn windows_section(study: &StudyResults, methods: &[&str], windows: &[f64]) -> Section {
    let rows = methods
        .iter()
        .map(|method| {
            std::iter::once(Entry::Text(method.to_string()))
                .chain(windows.iter().map(|&w| {
                    summary_entry(study, method, w).map_or(Entry::Missing, |r| Entry::Rmse {
                        mean_cm_s: r.mean_cm_s,
                        ci95_cm_s: r.ci95_cm_s,
                    })
                }))
                .collect()
        })
        .collect();
    Section {
        title: "Held-out RMSE against the calibration window".into(),
        caption: "Mean held-out RMSE in cm/s, total over the three axes (per axis is the total divided by the square root of 3), ± the half-width of its 95 % interval, for each calibration window (the first w seconds of each calibration trajectory).".into(),
        table: Table::new(
            std::iter::once("method".to_string())
                .chain(windows.iter().map(|&w| format!("w = {}", window_text(w))))
                .collect(),
            rows,
            Vec::new(),
        ),
        paragraph: None,
    }
}
