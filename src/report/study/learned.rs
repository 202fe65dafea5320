//! The tables of `[learned]`: (a) every method's held-out RMSE on the pairs inside the
//! folds, over all folds, for every window; (b) the same per fold at the largest window;
//! (c) each learned method against the installation fit with its terms, calibration by
//! calibration (a paired difference with its interval); (d) how far each learned model's terms, and the installation fit's with the same
//! terms, land from that fit's mean over every trajectory at the largest window, the
//! best estimate of the installation there is. In: the study's fold summary and terms.
//! Out: [`Section`]s.

use super::heldout::window_text;
use crate::installation::learned::spec::LEARNED_LABEL;
use crate::installation::study::method::Method;
use crate::installation::study::rows::{FoldSummaryRow, NO_CALIBRATION, StudyResults, TermRow};
use crate::report::kit::readable::readable_term;
use crate::report::kit::table::{Entry, Section, Table};

/// Whether `method` is one of `[learned]`'s.
pub(super) fn is_learned(method: &str) -> bool {
    method.starts_with(LEARNED_LABEL)
}

fn fold_entry<'a>(
    study: &'a StudyResults,
    fold: &str,
    method: &str,
    window_s: f64,
) -> Option<&'a FoldSummaryRow> {
    study
        .folds
        .iter()
        .find(|r| r.fold == fold && r.summary.method == method && r.summary.window_s == window_s)
}

/// The sections, none without a fold summary.
pub(super) fn learned_sections(
    study: &StudyResults,
    methods: &[&str],
    windows: &[f64],
) -> Vec<Section> {
    let Some(&largest) = windows.last() else {
        return Vec::new();
    };
    if study.folds.is_empty() {
        return Vec::new();
    }
    let folds = crate::first_seen(
        study
            .folds
            .iter()
            .map(|r| r.fold.as_str())
            .filter(|f| *f != "all"),
    );
    let methods: Vec<&str> = methods
        .iter()
        .copied()
        .filter(|m| study.folds.iter().any(|r| r.summary.method == *m))
        .collect();
    let mut sections = vec![
        inside_folds_section(study, &methods, windows),
        fold_by_fold_section(study, &methods, &folds, largest),
    ];
    if fitted_alike(study, &methods).is_none() {
        sections[0].table.notes.push("No installation model of [[calibration.models]] has the learned models' terms: add one for the paired comparison and the terms' table.".into());
    }
    sections.extend(paired(study, &methods, windows));
    sections.extend(term_errors(study, &methods, windows));
    sections
}

/// Every method on the pairs inside the folds, window by window.
fn inside_folds_section(study: &StudyResults, methods: &[&str], windows: &[f64]) -> Section {
    Section {
        title: "Inside the folds: learned against model-based".into(),
        caption: format!(
            "Every method on the same pairs only: calibration and scored trajectory in the same fold, which the fold's learned models never saw, as simulation or as reality, and at each window only the pairs every method scored. Mean held-out RMSE in cm/s ± its 95 % interval over calibration trajectories, and (in brackets) its ratio to {NO_CALIBRATION} on those pairs."
        ),
        table: Table::new(
            window_header(windows),
            methods
                .iter()
                .map(|method| {
                    std::iter::once(Entry::Text(method.to_string()))
                        .chain(windows.iter().map(|&w| {
                            fold_entry(study, "all", method, w).map_or(Entry::Missing, |r| {
                                Entry::RmseRatio {
                                    mean_cm_s: r.summary.mean_cm_s,
                                    ci95_cm_s: r.summary.ci95_cm_s,
                                    ratio: r.summary.ratio,
                                }
                            })
                        }))
                        .collect()
                })
                .collect(),
            if methods.iter().any(|m| m.contains("the vehicle")) {
                vec!["DCNet trained on the vehicle has seen this installation, on the real DVL of the trajectories outside the fold: a prior the DCNet trained on simulation does not have.".into()]
            } else {
                Vec::new()
            },
        ),
        paragraph: None,
    }
}

/// Every method fold by fold at the largest window.
fn fold_by_fold_section(
    study: &StudyResults,
    methods: &[&str],
    folds: &[&str],
    largest: f64,
) -> Section {
    Section {
        title: format!("Fold by fold, window {}", window_text(largest)),
        caption: format!(
            "Mean held-out RMSE in cm/s ± its 95 % interval over each fold's calibration trajectories, calibrated on the first {}.",
            window_text(largest)
        ),
        table: Table::new(
            std::iter::once("method".to_string())
                .chain(folds.iter().map(|f| format!("fold {f}")))
                .collect(),
            methods
                .iter()
                .map(|method| {
                    std::iter::once(Entry::Text(method.to_string()))
                        .chain(folds.iter().map(|fold| {
                            fold_entry(study, fold, method, largest).map_or(Entry::Missing, |r| {
                                Entry::Rmse {
                                    mean_cm_s: r.summary.mean_cm_s,
                                    ci95_cm_s: r.summary.ci95_cm_s,
                                }
                            })
                        }))
                        .collect()
                })
                .collect(),
            Vec::new(),
        ),
        paragraph: None,
    }
}

/// The installation fit with the learned models' terms: the model-based method whose
/// term names are theirs.
fn fitted_alike<'a>(study: &StudyResults, methods: &[&'a str]) -> Option<&'a str> {
    let learned = methods.iter().find(|m| is_learned(m))?;
    let terms = term_names(study, learned);
    methods
        .iter()
        .copied()
        .find(|m| !is_learned(m) && term_names(study, m) == terms)
}

/// The names of the terms `method` estimated, in the order of its rows.
fn term_names<'a>(study: &'a StudyResults, method: &str) -> Vec<&'a str> {
    crate::first_seen(
        study
            .terms
            .iter()
            .filter(|r| r.method == method)
            .map(|r| r.term.as_str()),
    )
}

/// A header of `method` then one column per window.
fn window_header(windows: &[f64]) -> Vec<String> {
    std::iter::once("method".to_string())
        .chain(windows.iter().map(|&w| window_text(w)))
        .collect()
}

/// Each calibration trajectory's mean held-out RMSE of `learned` and of `fitted` at
/// `window_s`, both over the pairs they both scored (those inside the fold), by
/// calibration.
fn per_calibration<'a>(
    study: &'a StudyResults,
    learned: &str,
    fitted: &str,
    window_s: f64,
) -> Vec<(&'a str, f64, f64)> {
    let pairs = |method: &str| -> Vec<(&'a str, &'a str)> {
        study
            .heldout
            .iter()
            .filter(|r| r.method == method && r.window_s == window_s)
            .map(|r| (r.calibration.as_str(), r.scored.as_str()))
            .collect()
    };
    let theirs = pairs(fitted);
    let common: Vec<(&str, &str)> = pairs(learned)
        .into_iter()
        .filter(|pair| theirs.contains(pair))
        .collect();
    let mean = |method: &str, calibration: &str| {
        let scores: Vec<f64> = study
            .heldout
            .iter()
            .filter(|r| {
                r.method == method
                    && r.window_s == window_s
                    && r.calibration == calibration
                    && common.contains(&(r.calibration.as_str(), r.scored.as_str()))
            })
            .map(|r| r.total_cm_s)
            .collect();
        scores.iter().sum::<f64>() / scores.len() as f64
    };
    crate::first_seen(common.iter().map(|(c, _)| *c))
        .into_iter()
        .map(|c| (c, mean(learned, c), mean(fitted, c)))
        .collect()
}

/// Each learned method against the installation fit with its terms, calibration by
/// calibration on the same pairs, each with the same clock (carried, or re-found from
/// the same seconds): the mean difference of held-out RMSE with its 95 % interval, and
/// on how many calibration trajectories the learned one is lower.
fn paired(study: &StudyResults, methods: &[&str], windows: &[f64]) -> Option<Section> {
    let fitted = fitted_alike(study, methods)?;
    let learned: Vec<&str> = methods.iter().copied().filter(|m| is_learned(m)).collect();
    let rows = learned
        .iter()
        .map(|method| {
            // The fit's method with the learned one's variant.
            let against = Method {
                model: fitted.to_string(),
                ..Method::parse(method)
            }
            .to_string();
            std::iter::once(Entry::Text(method.to_string()))
                .chain(windows.iter().map(|&w| {
                    let differences: Vec<f64> = per_calibration(study, method, &against, w)
                        .iter()
                        .map(|(_, ours, theirs)| ours - theirs)
                        .collect();
                    if differences.len() < 2 {
                        return Entry::Missing;
                    }
                    let (mean, ci95) = crate::evaluate::statistics::mean_ci95(&differences);
                    Entry::Difference {
                        mean_cm_s: mean,
                        ci95_cm_s: ci95,
                        lower: differences.iter().filter(|d| **d < 0.0).count(),
                        of: differences.len(),
                    }
                }))
                .collect()
        })
        .collect();
    Some(Section {
        title: format!("Learned against {fitted}, calibration by calibration"),
        caption: format!(
            "The learned method's mean held-out RMSE minus {fitted}'s with the same clock (carried, or re-found from the same seconds), each calibration trajectory on the same pairs inside its fold, in cm/s: the mean difference ± its 95 % interval (Student t over calibration trajectories; negative where the learned one is better), and on how many calibration trajectories the learned one is lower."
        ),
        table: Table::new(window_header(windows), rows, Vec::new()),
        paragraph: None,
    })
}

/// (d): the mean absolute difference, per term and window, of each learned method's
/// terms and the installation fit's with the same terms from that fit's mean over every
/// calibration trajectory at the largest window.
fn term_errors(study: &StudyResults, methods: &[&str], windows: &[f64]) -> Option<Section> {
    let largest = *windows.last()?;
    let learned: Vec<&str> = methods.iter().copied().filter(|m| is_learned(m)).collect();
    let terms = term_names(study, learned.first()?);
    let fitted = fitted_alike(study, methods)?;
    let rows_of = |method: &str, window_s: f64| -> Vec<&TermRow> {
        study
            .terms
            .iter()
            .filter(|r| r.method == method && r.window_s == window_s)
            .collect()
    };
    let mean = |values: &[f64]| values.iter().sum::<f64>() / values.len().max(1) as f64;
    let reference: Vec<f64> = terms
        .iter()
        .map(|term| {
            let values: Vec<f64> = rows_of(fitted, largest)
                .iter()
                .filter(|r| r.term == *term)
                .map(|r| r.value)
                .collect();
            mean(&values)
        })
        .collect();
    let readable_terms: Vec<(String, &str, f64)> = terms.iter().map(|t| readable_term(t)).collect();
    let mut rows = vec![
        std::iter::once(Entry::Text(format!("{fitted}, mean of every trajectory")))
            .chain(std::iter::once(Entry::Text(window_text(largest))))
            .chain(
                reference
                    .iter()
                    .zip(&readable_terms)
                    .map(|(value, (_, _, factor))| Entry::Value(value * factor)),
            )
            .collect(),
    ];
    for method in learned.iter().copied().chain(std::iter::once(fitted)) {
        for &window_s in windows {
            let rows_here = rows_of(method, window_s);
            if rows_here.is_empty() {
                continue;
            }
            let mut row = vec![
                Entry::Text(method.to_string()),
                Entry::Text(window_text(window_s)),
            ];
            row.extend(term_error_cells(
                &rows_here,
                &terms,
                &reference,
                &readable_terms,
            ));
            rows.push(row);
        }
    }
    Some(Section {
        title: "Learned terms against the fit of every trajectory".into(),
        caption: format!(
            "First row: the mean over calibration trajectories of {fitted}'s terms on all {} of each, the best estimate of this installation there is. Then, per method and window, the mean over calibration trajectories of each term's absolute difference from it, in the units of the header.",
            window_text(largest)
        ),
        table: Table::new(
            ["method".to_string(), "window".to_string()]
                .into_iter()
                .chain(
                    readable_terms
                        .iter()
                        .map(|(name, unit, _)| format!("{name} ({unit})")),
                )
                .collect(),
            rows,
            Vec::new(),
        ),
        paragraph: None,
    })
}

/// One method's mean absolute difference from `reference`, term by term, in the
/// readable unit; `—` for a term it has no row of.
fn term_error_cells(
    rows: &[&TermRow],
    terms: &[&str],
    reference: &[f64],
    readable_terms: &[(String, &str, f64)],
) -> Vec<Entry> {
    let mean = |values: &[f64]| values.iter().sum::<f64>() / values.len().max(1) as f64;
    let mut cells = Vec::new();
    for ((term, value), (_, _, factor)) in terms.iter().zip(reference).zip(readable_terms) {
        let errors: Vec<f64> = rows
            .iter()
            .filter(|r| r.term == *term)
            .map(|r| (r.value - value).abs())
            .collect();
        cells.push(if errors.is_empty() {
            Entry::Missing
        } else {
            Entry::Value(mean(&errors) * factor)
        });
    }
    cells
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::installation::study::rows::TransferRow;

    #[test]
    fn a_learned_method_is_set_against_the_fit_with_the_same_clock() {
        let fit = "installation lever";
        let learned = "DCNet trained on the vehicle";
        let refound = |method: &str| Method::single(method).refound(60.0).to_string();
        let term = |method: &str, calibration: &str| TermRow {
            method: method.into(),
            calibration: calibration.into(),
            window_s: 400.0,
            term: "lever_arm_x_m".into(),
            value: -1.9,
            std: 0.01,
            bound_std: 0.01,
            unseen: String::new(),
            asked: String::new(),
            between_dives_std: f64::NAN,
            next_dive_low: f64::NAN,
            next_dive_high: f64::NAN,
        };
        let score = |method: &str, calibration: &str, total_cm_s| TransferRow {
            method: method.into(),
            calibration: calibration.into(),
            window_s: 400.0,
            scored: "C".into(),
            rmse_cm_s: [total_cm_s; 3],
            total_cm_s,
            drift_rms_pct: f64::NAN,
            drift_end_pct: f64::NAN,
        };
        let mut study = StudyResults::default();
        for calibration in ["A", "B"] {
            study
                .terms
                .extend([term(fit, calibration), term(learned, calibration)]);
            study.heldout.extend([
                score(fit, calibration, 6.0),
                score(&refound(fit), calibration, 3.0),
                score(learned, calibration, 5.0),
                score(&refound(learned), calibration, 4.0),
            ]);
        }
        let (fit_refound, learned_refound) = (refound(fit), refound(learned));
        let methods = [fit, fit_refound.as_str(), learned, learned_refound.as_str()];
        let section = paired(&study, &methods, &[400.0]).unwrap();
        let difference = |row: &[Entry]| match row[1] {
            Entry::Difference {
                mean_cm_s, lower, ..
            } => (mean_cm_s, lower),
            ref other => panic!("{other:?}"),
        };
        let rows = &section.table.groups[0];
        // Carried against carried: 5 − 6; re-found against re-found: 4 − 3, not 4 − 6.
        assert_eq!(difference(&rows[0]), (-1.0, 2));
        assert_eq!(difference(&rows[1]), (1.0, 0));
    }
}
