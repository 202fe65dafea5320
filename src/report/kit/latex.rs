//! Any report's table set as LaTeX, for a paper to `\input`: a booktabs table
//! environment, and the escapes, labels and signs every `report.tex` shares. In: a
//! [`Table`] or [`Section`]s of the kit's model. Out: table environments only, no
//! preamble. A row with published values has the row of those values in italics below
//! it; a flagged cell carries a dagger, explained under its table.

use crate::report::kit::table::{Cell, Entry, Section, Signs, Table, symbols};
use std::fmt::Write;

pub const FILE: &str = "report.tex";

pub(crate) const SIGNS: Signs = Signs {
    percent: "\\,\\%",
    minus: "$-$",
    plus_minus: "\\,$\\pm$\\,",
};

/// One table environment of `table` under `caption` and `label` (both LaTeX): a rule
/// before each group of rows, below a row with published values the row of those values
/// in italics, the first label left empty under its group's first row where the rows
/// have several labels (the DVL is named once), and `notes` (LaTeX) under the table.
pub(crate) fn table(out: &mut String, table: &Table, caption: &str, label: &str, notes: &[String]) {
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
