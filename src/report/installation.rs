//! The installation study's section of the report, and its figures. In: a [`Study`]
//! (as `results::installation` reads it back). Out: the section as Markdown
//! ([`markdown`]) and as LaTeX ([`latex`]), both set from the same tables: the mean
//! held-out RMSE of each method at the largest window with its 95 % interval and its
//! ratio to no calibration; the same means per window; for each installation model,
//! the terms each calibration trajectory estimated with the bound's standard
//! deviation, in readable units, those the window cannot show marked and why listed
//! under the table; and a paragraph on where the estimates agree across calibration
//! trajectories within their intervals. [`draw_all`] writes the study's figures
//! (`plots::figures::installation_*`) as a run's are written.

use crate::installation::rows::{NO_CALIBRATION, Study, SummaryRow, TermRow};
use crate::installation::study::table_unit;
use crate::report::plots::canvas::Outcome;
use crate::report::plots::figures::{
    installation_matrix, installation_residual, installation_windows,
};
use crate::report::plots::scale::three_digits;
use crate::report::plots::{Format, PlotError, Written, render, write_figures};
use crate::report::table::{RmseValue, Signs};
use comfy_table::{Table as MarkdownTable, presets::ASCII_MARKDOWN};
use std::fmt::Write;
use std::path::Path;

/// The z-value of a two-sided 95 % interval: estimates agree across calibration
/// trajectories when their spread is at most this many times the median bound.
const AGREEMENT_Z: f64 = 1.96;

/// The section as Markdown, second-level heading first.
pub fn markdown(study: &Study) -> String {
    let signs = &crate::report::markdown::SIGNS;
    let mut out = String::new();
    let _ = writeln!(out, "## Installation study: held-out trajectories\n");
    let _ = writeln!(out, "{}\n", introduction());
    for section in sections(study) {
        let _ = writeln!(out, "### {}\n", section.title);
        let _ = writeln!(out, "{}\n", section.caption);
        let _ = writeln!(out, "{}\n", markdown_table(&section.table, signs));
        if !section.table.notes.is_empty() {
            for note in &section.table.notes {
                let _ = writeln!(out, "- {note}");
            }
            let _ = writeln!(out);
        }
        if let Some(paragraph) = &section.paragraph {
            let _ = writeln!(out, "{paragraph}\n");
        }
    }
    out
}

/// The section as LaTeX table environments and paragraphs; `name` keys the labels.
pub fn latex(study: &Study, name: &str) -> String {
    use crate::report::latex::{SIGNS, escape, label};
    let mut out = String::new();
    let _ = writeln!(out, "% The installation study's tables ({name}).");
    let _ = writeln!(out, "{}", symbols(&escape(&introduction())));
    for (i, section) in sections(study).iter().enumerate() {
        let table = &section.table;
        let _ = writeln!(out, "\n\\begin{{table}}[htbp]");
        let _ = writeln!(out, "  \\centering\\small\\setlength{{\\tabcolsep}}{{4pt}}");
        let _ = writeln!(
            out,
            "  \\caption{{{}: {}}}",
            escape(&section.title),
            escape(&section.caption)
        );
        let _ = writeln!(
            out,
            "  \\label{{tab:{}-installation-{}}}",
            label(name),
            i + 1
        );
        let _ = writeln!(out, "  \\makebox[\\linewidth]{{%");
        let _ = writeln!(
            out,
            "  \\begin{{tabular}}{{l{}}}",
            "r".repeat(table.header.len() - 1)
        );
        let _ = writeln!(out, "    \\toprule");
        let header: Vec<String> = table.header.iter().map(|h| escape(h)).collect();
        let _ = writeln!(out, "    {} \\\\", header.join(" & "));
        let _ = writeln!(out, "    \\midrule");
        for row in &table.rows {
            let cells: Vec<String> = row
                .iter()
                .map(|entry| match entry {
                    Entry::Text(text) => escape(text),
                    other => symbols(&other.text(&SIGNS)),
                })
                .collect();
            let _ = writeln!(out, "    {} \\\\", cells.join(" & "));
        }
        let _ = writeln!(out, "    \\bottomrule");
        let _ = writeln!(out, "  \\end{{tabular}}}}");
        if !table.notes.is_empty() {
            let notes: Vec<String> = table.notes.iter().map(|n| symbols(&escape(n))).collect();
            let _ = writeln!(out, "  \\par\\smallskip");
            let _ = writeln!(
                out,
                "  {{\\footnotesize\\raggedright {}\\par}}",
                notes.join("\\\\\n  ")
            );
        }
        let _ = writeln!(out, "\\end{{table}}");
        if let Some(paragraph) = &section.paragraph {
            let _ = writeln!(out, "\n{}", symbols(&escape(paragraph)));
        }
    }
    out
}

/// Draws the study's figures into `folder`, each file written atomically: the
/// calibration × scored matrix of each method, held-out RMSE against the window, and
/// one trajectory's residual before and after.
pub fn draw_all(study: &Study, folder: &Path, format: Format) -> Result<Vec<Written>, PlotError> {
    render::register_font();
    let draw = || -> crate::report::plots::draw::PlotResult<Vec<(String, Outcome)>> {
        let mut drawn = installation_matrix::installation_matrix(study)?;
        drawn.push((
            "installation_windows".into(),
            installation_windows::installation_windows(study)?,
        ));
        drawn.push((
            "installation_residual".into(),
            installation_residual::installation_residual(study)?,
        ));
        Ok(drawn)
    };
    let drawn = draw().map_err(|source| PlotError::Draw {
        what: "installation study's",
        source,
    })?;
    write_figures(drawn, folder, format)
}

/// The characters of our text and of the bound's reasons that LaTeX sets in math mode
/// (or that its default font would set as other glyphs: `<` and `>`), and how.
const MATH: [(char, &str); 16] = [
    ('±', "$\\pm$"),
    ('σ', "$\\sigma$"),
    ('τ', "$\\tau$"),
    ('δ', "$\\delta$"),
    ('ω', "$\\omega$"),
    ('ρ', "$\\rho$"),
    ('×', "$\\times$"),
    ('∞', "$\\infty$"),
    ('−', "$-$"),
    ('≥', "$\\geq$"),
    ('≤', "$\\leq$"),
    ('>', "$>$"),
    ('<', "$<$"),
    ('°', "$^\\circ$"),
    ('→', "$\\to$"),
    ('|', "$|$"),
];

/// `text` with the characters of [`MATH`] written as LaTeX sets them.
fn symbols(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match MATH.iter().find(|(m, _)| *m == c) {
            Some((_, latex)) => out.push_str(latex),
            None => out.push(c),
        }
    }
    out
}

/// What the section's numbers are, above its tables.
fn introduction() -> String {
    format!(
        "Every trajectory in turn is the calibration segment (its first w seconds for each window w); the terms each method estimates there correct the DVL of every other trajectory, scored against the reference in the body frame (RMSE over the three axes, cm/s). A method's held-out RMSE is the mean over calibration trajectories of each one's mean over the trajectories it corrects, ± the half-width of its 95 % interval (Student t over calibration trajectories); the ratio divides it by {NO_CALIBRATION}'s on the same pairs."
    )
}

/// One table of the section, with its title, caption and what follows it.
struct Section {
    title: String,
    caption: String,
    table: Table,
    paragraph: Option<String>,
}

/// A table of text: its header and rows, and the notes set under it.
struct Table {
    header: Vec<String>,
    rows: Vec<Vec<Entry>>,
    notes: Vec<String>,
}

/// One cell, written by each rendering with its own signs.
#[derive(Debug, Clone, PartialEq)]
enum Entry {
    Text(String),
    /// A mean RMSE and the half-width of its 95 % interval, cm/s.
    Rmse {
        mean_cm_s: f64,
        ci95_cm_s: f64,
    },
    Ratio(f64),
    /// A term in its readable unit, its bound's standard deviation, whether it is seen.
    Term {
        value: f64,
        std: f64,
        seen: bool,
    },
    Missing,
}

impl Entry {
    fn text(&self, signs: &Signs) -> String {
        match self {
            Entry::Text(text) => text.clone(),
            Entry::Rmse {
                mean_cm_s,
                ci95_cm_s,
            } => RmseValue {
                rmse_cm_s: *mean_cm_s,
                ci_cm_s: Some(*ci95_cm_s),
                detail: None,
            }
            .text(signs),
            Entry::Ratio(ratio) => format!("{ratio:.2}"),
            Entry::Term { value, std, seen } => {
                let decimals = decimals(*std);
                let value = format!("{value:.decimals$}");
                let value = match value.strip_prefix('-') {
                    Some(magnitude) => format!("{}{magnitude}", signs.minus),
                    None => value,
                };
                let std = if std.is_finite() {
                    format!("{std:.decimals$}")
                } else {
                    "∞".into()
                };
                let unseen = if *seen { "" } else { " (not seen)" };
                format!("{value}{}{std}{unseen}", signs.plus_minus)
            }
            Entry::Missing => "—".into(),
        }
    }
}

/// The decimals that show `std` with two significant digits (0 to 4), and a value
/// beside it to the same place; 2 when it is not a positive number.
fn decimals(std: f64) -> usize {
    if !(std.is_finite() && std > 0.0) {
        return 2;
    }
    (1 - std.log10().floor() as i32).clamp(0, 4) as usize
}

/// A term's name for people and its unit, and the factor from the stored value (SI,
/// radians, a fraction for a scale) to that unit, the unit as the study's tables give
/// it ([`table_unit`]) and the name without its unit suffix:
/// `lever_arm_x_m` → ("lever arm x", "m", 1), `bias_x_m_s` → ("bias x", "cm/s", 100),
/// `misalignment_x_rad` → degrees, `scale_x` → %.
pub(crate) fn readable_term(term: &str) -> (String, &'static str, f64) {
    readable(term)
}

fn readable(term: &str) -> (String, &'static str, f64) {
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

/// The methods in the order the study lists them, no calibration first.
fn methods(study: &Study) -> Vec<&str> {
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
fn windows(study: &Study) -> Vec<f64> {
    let mut windows = crate::first_seen(study.summary.iter().map(|r| r.window_s));
    windows.sort_by(f64::total_cmp);
    windows
}

/// A window as the tables write it: `400 s`.
fn window_text(window_s: f64) -> String {
    format!("{window_s} s")
}

fn summary_entry<'a>(study: &'a Study, method: &str, window_s: f64) -> Option<&'a SummaryRow> {
    study
        .summary
        .iter()
        .find(|r| r.method == method && r.window_s == window_s)
}

/// Every table of the section, in order.
fn sections(study: &Study) -> Vec<Section> {
    let windows = windows(study);
    let Some(&largest) = windows.last() else {
        return Vec::new();
    };
    let methods = methods(study);
    let calibrations: Vec<&str> = crate::first_seen(
        study
            .terms
            .iter()
            .filter(|r| r.window_s == largest)
            .map(|r| r.calibration.as_str()),
    );
    let mut sections = vec![heldout_section(study, &methods, largest)];
    if windows.len() > 1 {
        sections.push(windows_section(study, &methods, &windows));
    }
    for method in &methods {
        let rows: Vec<&TermRow> = study
            .terms
            .iter()
            .filter(|r| r.method == *method && r.window_s == largest)
            .collect();
        if !rows.is_empty() {
            let mut section = terms_section(method, largest, &rows);
            let missing: Vec<&str> = calibrations
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
        }
    }
    sections
}

/// (a): each method's mean held-out RMSE at the largest window and its ratio.
fn heldout_section(study: &Study, methods: &[&str], window_s: f64) -> Section {
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
                row.map_or(Entry::Missing, |r| Entry::Ratio(r.ratio)),
            ]
        })
        .collect();
    Section {
        title: format!("Held-out RMSE, window {}", window_text(window_s)),
        caption: format!(
            "Mean held-out RMSE in cm/s ± the half-width of its 95 % interval over calibration trajectories, calibrated on the first {} of each, and its ratio to {NO_CALIBRATION}.",
            window_text(window_s)
        ),
        table: Table {
            header: vec![
                "method".into(),
                "held-out RMSE (cm/s)".into(),
                format!("ratio to {NO_CALIBRATION}"),
            ],
            rows,
            notes: Vec::new(),
        },
        paragraph: None,
    }
}

/// (b): the same means, one column per window.
fn windows_section(study: &Study, methods: &[&str], windows: &[f64]) -> Section {
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
        caption: "Mean held-out RMSE in cm/s ± the half-width of its 95 % interval, for each calibration window (the first w seconds of each calibration trajectory).".into(),
        table: Table {
            header: std::iter::once("method".to_string())
                .chain(windows.iter().map(|&w| format!("w = {}", window_text(w))))
                .collect(),
            rows,
            notes: Vec::new(),
        },
        paragraph: None,
    }
}

/// (c) and (d): one installation model's terms per calibration trajectory, the terms
/// not seen and why, and where the estimates agree.
fn terms_section(method: &str, window_s: f64, rows: &[&TermRow]) -> Section {
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
        paragraph: Some(agreement(method, &terms, &calibrations, rows)),
    }
}

/// One term's estimates across the calibration trajectories that see it.
#[derive(Debug, Clone, PartialEq)]
struct Agreement {
    name: String,
    unit: &'static str,
    /// How many calibration trajectories see it.
    seen: usize,
    /// The sample standard deviation of their estimates, in the readable unit.
    spread: f64,
    /// The median of their bound's standard deviations.
    median_std: f64,
}

impl Agreement {
    fn of(term: &str, rows: &[&TermRow]) -> Agreement {
        let (name, unit, factor) = readable(term);
        let seen: Vec<&&TermRow> = rows
            .iter()
            .filter(|r| r.term == term && r.unseen.is_empty())
            .collect();
        let values: Vec<f64> = seen.iter().map(|r| factor * r.value).collect();
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let spread = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let mut stds: Vec<f64> = seen.iter().map(|r| factor * r.std).collect();
        stds.sort_by(f64::total_cmp);
        let median_std = match stds.len() {
            0 => f64::NAN,
            k if k % 2 == 1 => stds[k / 2],
            k => 0.5 * (stds[k / 2 - 1] + stds[k / 2]),
        };
        Agreement {
            name,
            unit,
            seen: values.len(),
            spread,
            median_std,
        }
    }

    fn agrees(&self) -> bool {
        self.spread <= AGREEMENT_Z * self.median_std
    }

    /// `lever arm x (spread 0.080 m, 8.0 × the median σ of 0.010 m, 11 trajectories)`.
    fn text(&self) -> String {
        let decimals = decimals(self.median_std);
        let unit = |value: f64| {
            if self.unit.is_empty() {
                format!("{value:.decimals$}")
            } else {
                format!("{value:.decimals$} {}", self.unit)
            }
        };
        format!(
            "{} (spread {}, {:.1} × the median σ of {}, {} trajectories)",
            self.name,
            unit(self.spread),
            self.spread / self.median_std,
            unit(self.median_std),
            self.seen
        )
    }
}

/// (d): which terms' estimates agree across the calibration trajectories within the
/// bound's 95 % intervals, which do not, and where terms are not seen.
fn agreement(method: &str, terms: &[&str], calibrations: &[&str], rows: &[&TermRow]) -> String {
    let all: Vec<Agreement> = terms.iter().map(|t| Agreement::of(t, rows)).collect();
    let list = |items: Vec<String>| items.join(", ");
    let agree: Vec<String> = all
        .iter()
        .filter(|a| a.seen >= 2 && a.agrees())
        .map(Agreement::text)
        .collect();
    let disagree: Vec<String> = all
        .iter()
        .filter(|a| a.seen >= 2 && !a.agrees())
        .map(Agreement::text)
        .collect();
    let few: Vec<String> = all
        .iter()
        .filter(|a| a.seen < 2)
        .map(|a| a.name.clone())
        .collect();
    let mut text = format!(
        "Across the {} calibration trajectories, {method}'s estimates of a term agree within their intervals when the standard deviation of the estimates where the term is seen (the spread) is at most {AGREEMENT_Z} times the median of their bound's standard deviations (σ).",
        calibrations.len()
    );
    text += &match agree.is_empty() {
        true => " No term's estimates agree.".to_string(),
        false => format!(" They agree for {}.", list(agree)),
    };
    if !disagree.is_empty() {
        text += &format!(" They do not for {}.", list(disagree));
    }
    if !few.is_empty() {
        text += &format!(
            " Seen on fewer than two trajectories, so not compared: {}.",
            list(few)
        );
    }
    let unseen: Vec<String> = terms
        .iter()
        .filter_map(|term| {
            let on: Vec<&str> = rows
                .iter()
                .filter(|r| r.term == *term && !r.unseen.is_empty())
                .map(|r| r.calibration.as_str())
                .collect();
            (!on.is_empty()).then(|| format!("{} on {}", readable(term).0, on.join(", ")))
        })
        .collect();
    if !unseen.is_empty() {
        text += &format!(" Not seen: {}.", unseen.join("; "));
    }
    text
}

/// A table as Markdown, with the figures' signs.
fn markdown_table(table: &Table, signs: &Signs) -> MarkdownTable {
    let mut markdown = MarkdownTable::new();
    markdown.load_preset(ASCII_MARKDOWN);
    markdown.set_header(table.header.clone());
    for row in &table.rows {
        markdown.add_row(row.iter().map(|e| e.text(signs)).collect::<Vec<_>>());
    }
    markdown
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::installation::rows::{HeldOutRow, TracePoint};

    /// A small study: three trajectories, two windows, no calibration, least squares
    /// EM1 and one installation model whose lever arm T12 cannot show.
    fn small() -> Study {
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
            unseen: unseen.into(),
        };
        Study {
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
        }
    }

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
    fn terms_read_in_their_units_with_two_significant_digits_of_the_bound() {
        assert_eq!(readable("lever_arm_x_m"), ("lever arm x".into(), "m", 1.0));
        assert_eq!(readable("bias_x_m_s"), ("bias x".into(), "cm/s", 100.0));
        assert_eq!(readable("time_offset_s"), ("time offset".into(), "s", 1.0));
        assert_eq!(readable("scale_x"), ("scale x".into(), "%", 100.0));
        assert_eq!(readable("scale"), ("scale".into(), "%", 100.0));
        let (name, unit, factor) = readable("misalignment_z_rad");
        assert_eq!((name.as_str(), unit), ("misalignment z", "deg"));
        assert!((factor * std::f64::consts::PI - 180.0).abs() < 1e-12);
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

    #[test]
    fn the_markdown_section_has_each_table_in_spec_order_no_calibration_first() {
        let text = markdown(&small());
        let lines: Vec<&str> = text.lines().collect();
        let has = |line: &str| {
            assert!(lines.contains(&line), "missing {line:?} in\n{text}");
        };
        has("### Held-out RMSE, window 400 s");
        has("| method                    | held-out RMSE (cm/s) | ratio to no calibration |");
        has("| no calibration            | 15.07 ± 0.80         | 1.00                    |");
        has("| least squares EM1         | 15.08 ± 0.80         | 1.00                    |");
        has("| installation lever+offset | 6.00 ± 0.40          | 0.40                    |");
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
    fn the_paragraph_says_which_terms_agree_within_their_intervals() {
        let study = small();
        let rows: Vec<&TermRow> = study.terms.iter().collect();
        let lever = Agreement::of("lever_arm_x_m", &rows);
        // T1 and T2 only: spread of (-1.87, -1.89) is 0.01414, median σ 0.015.
        assert_eq!(lever.seen, 2);
        assert!((lever.spread - 0.02 / 2f64.sqrt()).abs() < 1e-12);
        assert!((lever.median_std - 0.015).abs() < 1e-12);
        assert!(lever.agrees());
        let paragraph = agreement(
            "installation lever+offset",
            &["lever_arm_x_m", "time_offset_s", "bias_y_m_s"],
            &["T1", "T2", "T12"],
            &rows,
        );
        assert!(
            paragraph.contains(" They agree for lever arm x (spread 0.014 m, 0.9 × the median σ of 0.015 m, 2 trajectories)."),
            "{paragraph}"
        );
        assert!(
            paragraph.contains(" They do not for time offset (spread 0.524 s, 29.1 × the median σ of 0.018 s, 3 trajectories), bias y (spread 0.41 cm/s, 4.1 × the median σ of 0.10 cm/s, 3 trajectories)."),
            "{paragraph}"
        );
        assert!(
            paragraph.ends_with(" Not seen: lever arm x on T12."),
            "{paragraph}"
        );
    }

    #[test]
    fn the_latex_section_escapes_its_text_and_sets_each_table() {
        let text = latex(&small(), "akit");
        assert_eq!(text.matches("\\begin{table}").count(), 3, "{text}");
        assert!(text.contains("\\label{tab:akit-installation-1}"), "{text}");
        assert!(
            text.contains("    no calibration & 15.07\\,$\\pm$\\,0.80 & 1.00 \\\\"),
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

    /// A deterministic jitter in -1..1 from `seed`.
    fn jitter(seed: u64) -> f64 {
        let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
        x ^= x >> 31;
        x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x ^= x >> 27;
        (x % 20_001) as f64 / 10_000.0 - 1.0
    }

    /// A study resembling the A-KIT one: 13 trajectories, three windows, no
    /// calibration, least squares EM1 to EM5 and two installation models.
    pub(crate) fn akit_like() -> Study {
        let none = [
            20.0, 13.4, 11.8, 23.1, 13.3, 10.9, 11.3, 24.2, 24.4, 14.5, 22.9, 2.9, 3.1,
        ];
        let ratio = [
            0.33, 0.337, 0.33, 0.34, 0.529, 0.473, 0.332, 0.342, 0.313, 0.343, 0.421, 0.505, 0.549,
        ];
        let names: Vec<String> = (1..=13).map(|i| format!("T{i}")).collect();
        let mut methods: Vec<String> = vec![NO_CALIBRATION.into()];
        methods.extend((1..=5).map(|k| format!("least squares EM{k}")));
        methods.extend([
            "installation lever+offset".to_string(),
            "installation lever+offset+bias".to_string(),
        ]);
        let windows = [100.0, 200.0, 400.0];
        let mut heldout = Vec::new();
        let mut seed = 0;
        for &window_s in &windows {
            for (c, calibration) in names.iter().enumerate() {
                for (m, method) in methods.iter().enumerate() {
                    for (s, scored) in names.iter().enumerate() {
                        if s == c {
                            continue;
                        }
                        seed += 1;
                        let factor = match m {
                            0 => 1.0,
                            1..=5 => 1.0 + 0.02 * m as f64 + 0.05 * jitter(seed),
                            _ => {
                                let short = 400.0 / window_s;
                                (ratio[c] * (1.0 + 0.1 * (short - 1.0)) - 0.01 * (m - 6) as f64)
                                    * (1.0 + 0.3 * jitter(seed))
                            }
                        };
                        let total = none[s] * factor;
                        let share = [0.37, 0.82, 0.33];
                        let norm = share.iter().map(|v: &f64| v * v).sum::<f64>().sqrt();
                        heldout.push(HeldOutRow {
                            method: method.clone(),
                            calibration: calibration.clone(),
                            window_s,
                            scored: scored.clone(),
                            rmse_cm_s: share.map(|v| v / norm * total),
                            total_cm_s: total,
                        });
                    }
                }
            }
        }
        let mut summary = Vec::new();
        for &window_s in &windows {
            let per_calibration = |method: &str| -> Vec<f64> {
                names
                    .iter()
                    .map(|c| {
                        let scores: Vec<f64> = heldout
                            .iter()
                            .filter(|r| {
                                r.method == method && r.window_s == window_s && r.calibration == *c
                            })
                            .map(|r| r.total_cm_s)
                            .collect();
                        scores.iter().sum::<f64>() / scores.len() as f64
                    })
                    .collect()
            };
            let (reference, _) = crate::evaluate::mean_ci95(&per_calibration(NO_CALIBRATION));
            for method in &methods {
                let (mean, ci) = crate::evaluate::mean_ci95(&per_calibration(method));
                summary.push(SummaryRow {
                    method: method.clone(),
                    window_s,
                    mean_cm_s: mean,
                    ci95_cm_s: ci,
                    ratio: mean / reference,
                    calibrations: 13,
                });
            }
        }
        let mut terms = Vec::new();
        for &window_s in &windows {
            for method in &methods[6..] {
                for (c, calibration) in names.iter().enumerate() {
                    let straight = c >= 11;
                    let cluster_b = [4, 5, 10, 11].contains(&c);
                    seed += 1;
                    let mut push = |term: &str, value: f64, std: f64, unseen: &str| {
                        terms.push(TermRow {
                            method: method.clone(),
                            calibration: calibration.clone(),
                            window_s,
                            term: term.into(),
                            value,
                            std,
                            unseen: unseen.into(),
                        })
                    };
                    let lever_std = if straight { 0.36 } else { 0.013 };
                    let why = if straight {
                        "standard deviation 0.36 m, beyond 0.1 m"
                    } else {
                        ""
                    };
                    push("lever_arm_x_m", -1.9 + 0.08 * jitter(seed), lever_std, why);
                    push(
                        "lever_arm_y_m",
                        -0.03 + 0.03 * jitter(seed + 1),
                        lever_std,
                        why,
                    );
                    push("lever_arm_z_m", 0.5 + 0.3 * jitter(seed + 2), 0.06, "");
                    let tau = if cluster_b { 0.58 } else { 1.46 };
                    push("time_offset_s", tau + 0.03 * jitter(seed + 3), 0.009, "");
                    if method.ends_with("bias") {
                        for (axis, b) in ["x", "y", "z"].iter().zip([0.005, 0.006, -0.003]) {
                            push(
                                &format!("bias_{axis}_m_s"),
                                b + 0.002 * jitter(seed + 4),
                                0.001,
                                "",
                            );
                        }
                    }
                }
            }
        }
        let trace = (0..399)
            .map(|i| {
                let time_s = f64::from(i) * 400.0 / 399.0;
                let turn = (time_s / 40.0 * std::f64::consts::TAU).sin();
                let yaw_rate_deg_s = 15.0 * turn.powi(3);
                let noise = |k: u64| 1.5 * jitter(10_000 + 3 * i as u64 + k);
                TracePoint {
                    trajectory: "T1".into(),
                    method: "installation lever+offset+bias".into(),
                    calibration: "T2".into(),
                    time_s,
                    before_cm_s: [
                        3.0 * turn.abs() + noise(0),
                        -1.64 * yaw_rate_deg_s.to_radians() * 100.0 + noise(1),
                        1.0 + noise(2),
                    ],
                    after_cm_s: [noise(0), 0.5 * noise(1), noise(2)],
                    yaw_rate_deg_s,
                }
            })
            .collect();
        Study {
            heldout,
            terms,
            summary,
            trace,
            failures: Vec::new(),
        }
    }

    #[test]
    fn the_figures_of_a_study_are_written_with_their_captions() {
        // Set DCNET_INSTALLATION_FIGURES to a folder to keep the figures and look at them.
        let kept = std::env::var_os("DCNET_INSTALLATION_FIGURES").map(std::path::PathBuf::from);
        let temporary = tempfile::tempdir().unwrap();
        let folder = kept.as_deref().unwrap_or(temporary.path());
        let written = draw_all(&akit_like(), folder, Format::Png).unwrap();
        let stems: Vec<&str> = written.iter().map(|w| w.stem.as_str()).collect();
        assert_eq!(
            stems,
            [
                "installation_matrix_no_calibration",
                "installation_matrix_least_squares_em1",
                "installation_matrix_least_squares_em2",
                "installation_matrix_least_squares_em3",
                "installation_matrix_least_squares_em4",
                "installation_matrix_least_squares_em5",
                "installation_matrix_installation_lever_offset",
                "installation_matrix_installation_lever_offset_bias",
                "installation_windows",
                "installation_residual",
            ]
        );
        for figure in &written {
            assert!(
                matches!(figure.caption, crate::report::plots::Caption::Drawn(_)),
                "{figure:?}"
            );
            assert_eq!(figure.files.len(), 1);
            assert!(figure.files[0].is_file());
        }
        let empty = Study::default();
        let written = draw_all(&empty, temporary.path(), Format::Png).unwrap();
        assert!(written.iter().all(|w| w.files.is_empty()), "{written:?}");
        assert_eq!(markdown(&empty).lines().count(), 4);
    }
}
