//! The room of the installation study (`kind = "installation"`): its section of the
//! report, its printed tables and its figures, each built with the kit. In: an
//! [`StudyResults`] (as `results::study` reads it back), or a stored
//! sweep of studies. Out: the section as Markdown ([`markdown`]) and as LaTeX
//! ([`latex`]), both set from the same tables, the text `run` prints ([`printed`]), and
//! the figures ([`draw_all`], [`draw_sweep`]). In data-flow order:
//!
//! - [`heldout`]: the mean held-out RMSE of each method at the largest window with its
//!   95 % interval and its ratio to no calibration, and the same means per window;
//! - [`drift`]: every method's dead-reckoning drift on the trajectories it corrects,
//!   where they record positions;
//! - [`terms`]: for each installation model, the terms each calibration trajectory
//!   estimated with their standard deviations, in readable units, those the window
//!   cannot show marked and why listed under the table;
//! - [`agreement`]: the paragraph on where those estimates agree across calibration
//!   trajectories within their intervals;
//! - [`next_dive`]: for a joint method, how far its terms move between trajectories,
//!   and how often the one it left out falls inside its interval for a next dive;
//! - [`learned`]: with `[learned]`, every method on the pairs inside the folds, fold by
//!   fold, and the learned terms against the installation fit of every trajectory;
//! - [`timing`]: each method's calibration time on each calibration trajectory;
//! - [`printed`]: the study's headline and a sweep of studies' table, printed by `run`
//!   and `collect`;
//! - [`figures`]: the study's figures, written as a paper run's are;
//! - this module: the tables in order, set as Markdown and as LaTeX.

pub mod heldout;
pub mod drift;
pub mod terms;
pub mod agreement;
pub mod next_dive;
pub mod learned;
pub mod timing;
pub mod printed;
pub mod figures;

pub use figures::{draw_all, draw_sweep};

use crate::installation::study::method::Method;
use crate::installation::study::rows::{NO_CALIBRATION, StudyResults, TermRow};
use crate::report::kit::table::{Section, symbols};
use agreement::agreement;
use heldout::{clocks_kept, heldout_section, methods, windows, windows_section};
use next_dive::next_dive_section;
use std::fmt::Write;
use terms::terms_section;

/// The section as Markdown, second-level heading first.
pub fn markdown(study: &StudyResults) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "## Installation study: held-out trajectories\n");
    let _ = writeln!(out, "{}\n", introduction());
    out.push_str(&crate::report::kit::markdown::sections(&sections(study)));
    out
}

/// The section as LaTeX table environments and paragraphs; `name` keys the labels.
pub fn latex(study: &StudyResults, name: &str) -> String {
    use crate::report::kit::latex::escape;
    let mut out = String::new();
    let _ = writeln!(out, "% The installation study's tables ({name}).");
    let _ = writeln!(out, "{}", symbols(&escape(&introduction())));
    let key = format!("{}-installation", crate::report::kit::latex::label(name));
    out.push_str(&crate::report::kit::latex::sections(&sections(study), &key));
    out
}

/// What the section's numbers are, above its tables.
fn introduction() -> String {
    format!(
        "Every trajectory in turn is the calibration segment (its first w seconds for each window w); the terms each method estimates there correct the DVL of every other trajectory, scored against the reference in the body frame (RMSE over the three axes, cm/s). A method's held-out RMSE is the mean over calibration trajectories of each one's mean over the trajectories it corrects, ± the half-width of its 95 % interval (Student t over calibration trajectories); the ratio divides it by {NO_CALIBRATION}'s on the same pairs."
    )
}

/// Every table of the section, in order.
fn sections(study: &StudyResults) -> Vec<Section> {
    let windows = windows(study);
    let Some(&largest) = windows.last() else {
        return Vec::new();
    };
    let methods = methods(study);
    // The calibrations a method fits on: one trajectory each, or all but one for a
    // joint fit.
    let calibrations = |joint: bool| -> Vec<&str> {
        crate::first_seen(
            study
                .terms
                .iter()
                .filter(|r| r.window_s == largest && Method::parse(&r.method).is_joint() == joint)
                .map(|r| r.calibration.as_str()),
        )
    };
    let calibrations = [calibrations(false), calibrations(true)];
    let mut sections = vec![heldout_section(study, &methods, largest)];
    sections[0]
        .table
        .notes
        .extend(clocks_kept(study, Some(largest)));
    sections.extend(drift::drift_section(study, &methods, largest));
    if windows.len() > 1 {
        sections.push(windows_section(study, &methods, &windows));
    }
    if methods.iter().any(|m| learned::is_learned(m)) {
        sections[0].table.notes.push(
            "The DCNets trained on simulation and on the vehicle are scored inside their folds only (trajectories their models never saw), and their ratio divides by no calibration's over every pair: compare them with the others on the same pairs in the tables of the folds below.".into(),
        );
    }
    sections.extend(learned::learned_sections(study, &methods, &windows));
    sections.extend(timing::timing_section(study, &methods, &windows));
    for method in methods.iter().filter(|m| !learned::is_learned(m)) {
        let rows: Vec<&TermRow> = study
            .terms
            .iter()
            .filter(|r| r.method == *method && r.window_s == largest)
            .collect();
        if !rows.is_empty() {
            let mut section = terms_section(method, largest, &rows);
            section.paragraph = Some(agreement(method, &rows));
            let missing: Vec<&str> = calibrations[usize::from(Method::parse(method).is_joint())]
                .iter()
                .copied()
                .filter(|c| !rows.iter().any(|r| r.calibration == *c))
                .collect();
            if !missing.is_empty() {
                section.table.notes.push(format!(
                    "No estimate on {}: the fit of {method} failed there, so {} in none of its held-out means either.",
                    missing.join(", "),
                    if missing.len() == 1 { "it is" } else { "they are" }
                ));
            }
            for failure in study
                .failures
                .iter()
                .filter(|f| f.method == *method && f.window_s == largest)
            {
                section
                    .table
                    .notes
                    .push(format!("{}: {}.", failure.calibration, failure.why));
            }
            sections.push(section);
            if Method::parse(method).is_joint() {
                sections.extend(next_dive_section(method, largest, &rows, &study.terms));
            }
        }
    }
    sections
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::installation::study::rows::SummaryRow;

    /// A small study: three trajectories, two windows, no calibration, least squares
    /// EM1 and one installation model whose lever arm T12 cannot show.
    pub(super) fn small() -> StudyResults {
        let summary = |method: &str, window_s, mean_cm_s, ci95_cm_s, ratio| SummaryRow {
            method: method.into(),
            window_s,
            mean_cm_s,
            ci95_cm_s,
            ratio,
            calibrations: 3,
        };
        let term = |calibration: &str, term: &str, value, std, unseen: &str| TermRow {
            method: "installation lever+offset".into(),
            calibration: calibration.into(),
            window_s: 400.0,
            term: term.into(),
            value,
            std,
            bound_std: std,
            unseen: unseen.into(),
            asked: String::new(),
            between_dives_std: f64::NAN,
            next_dive_low: f64::NAN,
            next_dive_high: f64::NAN,
        };
        StudyResults {
            heldout: Vec::new(),
            terms: vec![
                term("T1", "lever_arm_x_m", -1.87, 0.013, ""),
                term("T1", "time_offset_s", 1.42, 0.009, ""),
                term("T1", "bias_y_m_s", 0.0007, 0.001, ""),
                term("T2", "lever_arm_x_m", -1.89, 0.017, ""),
                term("T2", "time_offset_s", 1.51, 0.018, ""),
                term("T2", "bias_y_m_s", 0.0078, 0.001, ""),
                term(
                    "T12",
                    "lever_arm_x_m",
                    -1.72,
                    0.36,
                    "standard deviation 3.600e-1 above its tolerance 1.000e-1",
                ),
                term("T12", "time_offset_s", 0.56, 0.038, ""),
                term("T12", "bias_y_m_s", 0.0078, 0.001, ""),
            ],
            summary: vec![
                summary("least squares EM1", 100.0, 15.2, 0.81, 1.01),
                summary(NO_CALIBRATION, 100.0, 15.07, 0.8, 1.0),
                summary("installation lever+offset", 100.0, 8.4, 1.2, 0.557),
                summary("least squares EM1", 400.0, 15.08, 0.8, 1.0007),
                summary(NO_CALIBRATION, 400.0, 15.07, 0.8, 1.0),
                summary("installation lever+offset", 400.0, 6.0, 0.4, 0.398),
            ],
            trace: Vec::new(),
            failures: Vec::new(),
            folds: Vec::new(),
            filtered: Vec::new(),
            calibration_time: Vec::new(),
            recordings: Vec::new(),
        }
    }

    #[test]
    fn a_clock_kept_is_counted_apart_from_failed_fits_and_a_joint_calibration_is_no_failure() {
        use crate::installation::study::rows::{FitFailure, TransferRow};
        let mut study = small();
        let single = "installation lever+offset";
        let joint = Method::single(single).jointly().to_string();
        let refound = Method::single(single).refound(60.0).to_string();
        let joint_term = TermRow {
            method: joint.clone(),
            calibration: "all but T1".into(),
            ..study.terms[0].clone()
        };
        study.terms.push(joint_term);
        study.summary.push(SummaryRow {
            method: refound.clone(),
            ..study.summary[5].clone()
        });
        for scored in ["T2", "T12"] {
            study.heldout.push(TransferRow {
                method: refound.clone(),
                calibration: "T1".into(),
                window_s: 400.0,
                scored: scored.into(),
                rmse_cm_s: [3.0; 3],
                total_cm_s: 5.2,
                drift_rms_pct: f64::NAN,
                drift_end_pct: f64::NAN,
            });
        }
        let failure = |method: &str, why: &str| FitFailure {
            method: method.into(),
            calibration: "T2".into(),
            window_s: 400.0,
            why: why.into(),
        };
        study.failures = vec![
            failure(
                &refound,
                "on T12: flat; its terms are scored with the calibration's clock",
            ),
            failure(single, "the fit did not converge"),
        ];
        let text = markdown(&study);
        assert!(
            text.contains("1 of the 2 scorings with the clock re-found kept the calibration's clock, since the scored trajectory's first seconds did not show its own (failures.parquet says why): on T12 1."),
            "{text}"
        );
        // The single fit's section names T2's failure only, not the joint calibration.
        assert!(text.contains("T2: the fit did not converge."), "{text}");
        assert!(!text.contains("No estimate on all but T1"), "{text}");
        let printed = crate::report::study::printed::headline(&study);
        assert!(
            printed.contains("\n1 fit failed, each leaving"),
            "{printed}"
        );
        assert!(printed.contains("\n1 of the 2 scorings"), "{printed}");
    }

    #[test]
    fn a_recording_with_samples_left_out_or_gaps_is_said_under_the_headline() {
        use crate::data::paired::{LeftOutWhy, ReadCounts};
        use crate::installation::study::rows::RecordingRow;
        let counts = |left_out: Vec<(LeftOutWhy, usize)>, pieces| ReadCounts {
            kept: 370,
            left_out,
            reference: 4000,
            beside: "reference",
            pieces,
            gap_limit_s: 3.0,
            longest_loss_s: 16.0,
            reference_read: None,
        };
        let mut study = small();
        study.recordings = vec![
            RecordingRow::of("T1", &counts(Vec::new(), 1)),
            RecordingRow::of("T2", &counts(vec![(LeftOutWhy::NoVelocity, 30)], 4)),
        ];
        assert_eq!(
            study.recordings[1].counts(),
            counts(vec![(LeftOutWhy::NoVelocity, 30)], 4)
        );
        let printed = crate::report::study::printed::headline(&study);
        assert!(
            printed.ends_with("\nT2 read: the DVL's 400 samples, 370 kept (30 left out: 30 with no velocity), beside the reference's 4000 on its own stamps; 4 pieces (gaps over 3.00 s cut it), the longest loss 16.00 s"),
            "{printed}"
        );
        assert!(!printed.contains("T1 read"), "{printed}");
    }

    #[test]
    fn the_markdown_section_has_each_table_in_spec_order_no_calibration_first() {
        let text = markdown(&small());
        let lines: Vec<&str> = text.lines().collect();
        let has = |line: &str| {
            assert!(lines.contains(&line), "missing {line:?} in\n{text}");
        };
        has("### Held-out RMSE, window 400 s");
        has(
            "| method                    | held-out RMSE, total (cm/s) | per axis (cm/s) | ratio to no calibration |",
        );
        has(
            "| no calibration            | 15.07 ± 0.80                | 8.70 ± 0.46     | 1.00                    |",
        );
        has(
            "| least squares EM1         | 15.08 ± 0.80                | 8.71 ± 0.46     | 1.00                    |",
        );
        has(
            "| installation lever+offset | 6.00 ± 0.40                 | 3.46 ± 0.23     | 0.40                    |",
        );
        has("### Held-out RMSE against the calibration window");
        has("| method                    | w = 100 s    | w = 400 s    |");
        has("| installation lever+offset | 8.40 ± 1.20  | 6.00 ± 0.40  |");
        has("### Estimated terms: installation lever+offset, window 400 s");
        has("| calibration | lever arm x (m)         | time offset (s) | bias y (cm/s) |");
        has("| T1          | -1.870 ± 0.013          | 1.4200 ± 0.0090 | 0.07 ± 0.10   |");
        has("| T12         | -1.72 ± 0.36 (not seen) | 0.560 ± 0.038   | 0.78 ± 0.10   |");
        has("- T12, not seen: lever arm x (standard deviation 0.36 m above its tolerance 0.1 m).");
        let order: Vec<usize> = [NO_CALIBRATION, "least squares EM1", "installation"]
            .iter()
            .map(|m| text.find(&format!("| {m}")).unwrap())
            .collect();
        assert!(order.windows(2).all(|w| w[0] < w[1]), "{text}");
    }

    #[test]
    fn the_latex_section_escapes_its_text_and_sets_each_table() {
        let text = latex(&small(), "akit");
        assert_eq!(text.matches("\\begin{table}").count(), 3, "{text}");
        assert!(text.contains("\\label{tab:akit-installation-1}"), "{text}");
        assert!(
            text.contains(
                "    no calibration & 15.07\\,$\\pm$\\,0.80 & 8.70\\,$\\pm$\\,0.46 & 1.00 \\\\"
            ),
            "{text}"
        );
        assert!(
            text.contains("    T12 & $-$1.72\\,$\\pm$\\,0.36 (not seen) & 0.560\\,$\\pm$\\,0.038 & 0.78\\,$\\pm$\\,0.10 \\\\"),
            "{text}"
        );
        assert!(text.contains("95 \\% interval"), "{text}");
        assert!(
            text.contains(
                "T12, not seen: lever arm x (standard deviation 0.36 m above its tolerance 0.1 m)."
            ),
            "{text}"
        );
        assert!(
            text.contains("0.9 $\\times$ the median $\\sigma$ of 0.015 m"),
            "{text}"
        );
        assert_eq!(symbols("ρ −0.97 ≥ 0.95"), "$\\rho$ $-$0.97 $\\geq$ 0.95");
    }
}
