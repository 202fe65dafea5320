//! `results/<name>/report.tex`: the tables of `report.md` as booktabs tables, for a
//! paper to `\input`. In: the report's [`ReportTables`], built once for both renderings.
//! Out: table environments only, no preamble; a comment on top names the one package
//! they need (booktabs). Each DVL's row holds our values, the row below it the
//! published ones in italics; a flagged cell carries a dagger explained under its table.

use crate::report::table::{
    Cell, Entry, ReportTables, Section, Signs, Table, replicates_note, symbols,
};
use crate::results::read::StoredRun;
use std::fmt::Write;

pub const FILE: &str = "report.tex";

pub(crate) const SIGNS: Signs = Signs {
    percent: "\\,\\%",
    minus: "$-$",
    plus_minus: "\\,$\\pm$\\,",
};

/// The tables as LaTeX.
pub(super) fn render(run: &StoredRun, tables: &ReportTables) -> String {
    let mut out = String::new();
    header(&mut out, &run.spec.name);
    let captions = Captions::of(run);
    let label = label(&run.spec.name);
    let tag = |table: &str| format!("tab:{label}-{table}");
    let calibration_note =
        captions.note(&tables.calibration, ", or another T\\textsubscript{conv}");
    table(
        &mut out,
        &tables.calibration,
        &captions.calibration(&tables.calibration),
        &tag("calibration"),
        calibration_note.as_slice(),
    );
    table(
        &mut out,
        &tables.evaluation,
        &captions.evaluation(&tables.evaluation),
        &tag("evaluation"),
        captions.note(&tables.evaluation, "").as_slice(),
    );
    if let Some(beyond) = &tables.beyond {
        table(&mut out, beyond, &captions.beyond(), &tag("beyond"), &[]);
    }
    if let Some(ensemble) = &tables.ensemble {
        table(
            &mut out,
            ensemble,
            &captions.ensemble(),
            &tag("ensemble"),
            &[],
        );
    }
    if let Some(efficiency) = &tables.efficiency {
        table(&mut out, efficiency, &captions.bound(), &tag("bound"), &[]);
    }
    let timing = crate::report::calibration_time::sections(run);
    out.push_str(&sections(&timing, &format!("{label}-calibration-time")));
    out
}

/// The comment on top: where the tables come from, the package they need, and how
/// they sit on the page.
fn header(out: &mut String, name: &str) {
    let _ = writeln!(
        out,
        "% The tables of report.md ({}), written by dcnet-exp {}.",
        name,
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(
        out,
        "% \\input{{report.tex}} in a document that loads booktabs: \\usepackage{{booktabs}}."
    );
    let _ = writeln!(
        out,
        "% Each table is centred on the page, into the margins where it is wider than the text;\n% in a two-column layout, make it a table* or scale its tabular with \\resizebox."
    );
}

/// The caption of each table, and the note under those with published values: what
/// they say of the run.
struct Captions<'a> {
    run: &'a StoredRun,
    /// The experiment's name, escaped.
    name: String,
    /// Monte Carlo runs per value.
    runs: usize,
    /// In every caption when DCNet has replicates.
    replicates: String,
}

impl<'a> Captions<'a> {
    fn of(run: &'a StoredRun) -> Self {
        let spec = &run.spec;
        Captions {
            run,
            name: escape(&spec.name),
            runs: spec.calibration.monte_carlo_runs,
            replicates: replicates_note(spec.training.replicates)
                .map(|note| format!(" {}", escape(&note).replace('±', "$\\pm$")))
                .unwrap_or_default(),
        }
    }

    /// In the caption of a table with published values.
    fn below(table: &Table) -> &'static str {
        if table.tally().compared > 0 {
            "; the published value in italics in the row below ours"
        } else {
            ""
        }
    }

    /// Under a table with published values: what its daggers mean, and their count.
    fn note(&self, table: &Table, what: &str) -> Option<String> {
        let spec = &self.run.spec;
        let published = self.run.published.as_ref()?;
        let tally = table.tally();
        (tally.compared > 0).then(|| {
            format!(
                "\\dag{{}} flags an RMSE more than {}\\,\\% off the published one{what} ({} of {} cells). Published values: {}.",
                spec.report.tolerance_pct,
                tally.flagged,
                tally.compared,
                escape(&published.source)
            )
        })
    }

    fn calibration(&self, table: &Table) -> String {
        let Captions {
            run,
            name,
            runs,
            replicates,
        } = self;
        format!(
            "{name}: calibration on {}. RMSE in cm/s at T\\textsubscript{{conv}}, mean over {runs} Monte Carlo runs, T\\textsubscript{{conv}} in s in brackets{}. The floor corrects with the true terms, which no estimator can beat; the bound is the best mean RMSE of any unbiased estimator from the window's data.{replicates}",
            escape(&run.spec.calibration.trajectory),
            Self::below(table)
        )
    }

    fn evaluation(&self, table: &Table) -> String {
        let Captions {
            name,
            runs,
            replicates,
            ..
        } = self;
        format!(
            "{name}: evaluation with the T\\textsubscript{{conv}} terms. RMSE in cm/s, mean over {runs} Monte Carlo runs, improvement over the baseline in brackets{}.{replicates}",
            Self::below(table)
        )
    }

    fn beyond(&self) -> String {
        let Captions { name, runs, .. } = self;
        format!(
            "{name}: beyond the paper, least squares on the same data and the floor. RMSE in cm/s, mean over {runs} Monte Carlo runs, improvement over the baseline in brackets."
        )
    }

    fn ensemble(&self) -> String {
        let Captions {
            run, name, runs, ..
        } = self;
        format!(
            "{name}: the DCNet ensemble, the mean of the {} replicates' terms in each calibration window. RMSE in cm/s, mean over {runs} Monte Carlo runs, improvement over the baseline in brackets.",
            run.spec.training.replicates
        )
    }

    /// The caption of the table against the information bound.
    fn bound(&self) -> String {
        let Captions {
            run, name, runs, ..
        } = self;
        format!(
            "{name}: every estimator against the information bound, the mean RMSE of an efficient estimator of the DVL's scale and bias from the calibration window. RMSE in cm/s, mean over {runs} Monte Carlo runs, efficiency (bound / RMSE) in brackets; calibration at each estimator's T\\textsubscript{{conv}} on the rest of {}, evaluation with the T\\textsubscript{{conv}} terms.",
            escape(&run.spec.calibration.trajectory)
        )
    }
}

/// One table environment of `table` under `caption` and `label` (both LaTeX): a rule
/// before each group of rows, below a row with published values the row of those values
/// in italics, the first label left empty under its group's first row where the rows
/// have several labels (the DVL is named once), and `notes` (LaTeX) under the table.
fn table(out: &mut String, table: &Table, caption: &str, label: &str, notes: &[String]) {
    let labels = table.label_columns;
    let _ = writeln!(out, "\n\\begin{{table}}[htbp]");
    let _ = writeln!(out, "  \\centering\\small\\setlength{{\\tabcolsep}}{{4pt}}");
    let _ = writeln!(out, "  \\caption{{{caption}}}");
    let _ = writeln!(out, "  \\label{{{label}}}");
    // Centred on the page, into both margins when wider than the text.
    let _ = writeln!(out, "  \\makebox[\\linewidth]{{%");
    let _ = writeln!(
        out,
        "  \\begin{{tabular}}{{{}{}}}",
        "l".repeat(labels),
        "r".repeat(table.header.len() - labels)
    );
    let _ = writeln!(out, "    \\toprule");
    let header: Vec<String> = table.header.iter().map(|h| symbols(&escape(h))).collect();
    row(out, &header);
    for group in &table.groups {
        let _ = writeln!(out, "    \\midrule");
        for (r, line) in group.iter().enumerate() {
            let named_above = r > 0 && labels > 1;
            let ours: Vec<String> = line
                .iter()
                .enumerate()
                .map(|(i, entry)| {
                    if i == 0 && named_above {
                        String::new()
                    } else {
                        entry_text(entry)
                    }
                })
                .collect();
            row(out, &ours);
            if let Some(published) = published_cells(line, labels) {
                row(out, &published);
            }
        }
    }
    let _ = writeln!(out, "    \\bottomrule");
    let _ = writeln!(out, "  \\end{{tabular}}}}");
    if !notes.is_empty() {
        let _ = writeln!(out, "  \\par\\smallskip");
        let _ = writeln!(
            out,
            "  {{\\footnotesize\\raggedright {}\\par}}",
            notes.join("\\\\\n  ")
        );
    }
    let _ = writeln!(out, "\\end{{table}}");
}

/// One cell as LaTeX: a label as text, a paper's cell as ours with a dagger where the
/// Markdown report has its ⚠, `---` where there is no value.
fn entry_text(entry: &Entry) -> String {
    match entry {
        Entry::Text(text) => escape(text),
        Entry::Published(cell) => ours(cell),
        Entry::Missing => "---".into(),
        other => symbols(&other.text(&SIGNS)),
    }
}

/// The row below `line` where it has published values: `paper` in its last label
/// column, then those values in italics, empty where there is none.
fn published_cells(line: &[Entry], labels: usize) -> Option<Vec<String>> {
    let paper = |entry: &Entry| match entry {
        Entry::Published(cell) => cell.paper.as_ref().map(|p| p.text(&SIGNS)),
        _ => None,
    };
    line.iter().any(|entry| paper(entry).is_some()).then(|| {
        let mut cells = vec![String::new(); labels - 1];
        cells.push("\\quad\\textit{paper}".into());
        cells.extend(line[labels..].iter().map(|entry| match paper(entry) {
            Some(text) => format!("\\textit{{{text}}}"),
            None => String::new(),
        }));
        cells
    })
}

fn row(out: &mut String, cells: &[String]) {
    let _ = writeln!(out, "    {} \\\\", cells.join(" & "));
}

/// Our value, with a dagger where the Markdown report has its ⚠.
fn ours(entry: &Cell) -> String {
    let text = entry.ours.text(&SIGNS);
    if entry.flagged {
        format!("{text}\\rlap{{\\textsuperscript{{\\dag}}}}")
    } else {
        text
    }
}

/// `text` with the characters LaTeX treats as special written as text.
pub(crate) fn escape(text: &str) -> String {
    let mut escaped = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '\\' => escaped.push_str("\\textbackslash{}"),
            '~' => escaped.push_str("\\textasciitilde{}"),
            '^' => escaped.push_str("\\textasciicircum{}"),
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                escaped.push('\\');
                escaped.push(c);
            }
            _ => escaped.push(c),
        }
    }
    escaped
}

/// A `\label` key from the experiment's name: letters and digits, other characters `-`.
pub(crate) fn label(name: &str) -> String {
    name.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect()
}

/// `sections` as LaTeX table environments, each followed by its paragraph; the i-th
/// table is labelled `tab:<key>-<i>`.
pub(crate) fn sections(sections: &[Section], key: &str) -> String {
    let mut out = String::new();
    for (i, section) in sections.iter().enumerate() {
        let caption = format!(
            "{}: {}",
            escape(&section.title),
            symbols(&escape(&section.caption))
        );
        let notes: Vec<String> = section
            .table
            .notes
            .iter()
            .map(|note| symbols(&escape(note)))
            .collect();
        let label = format!("tab:{key}-{}", i + 1);
        table(&mut out, &section.table, &caption, &label, &notes);
        if let Some(paragraph) = &section.paragraph {
            let _ = writeln!(out, "\n{}", symbols(&escape(paragraph)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specials_are_escaped_and_labels_are_plain() {
        assert_eq!(
            escape("T10_Cal & 50% #2 {a} $x ~^\\"),
            "T10\\_Cal \\& 50\\% \\#2 \\{a\\} \\$x \\textasciitilde{}\\textasciicircum{}\\textbackslash{}"
        );
        assert_eq!(label("sweep/lr=0.5,c=8"), "sweep-lr-0-5-c-8");
    }
}
