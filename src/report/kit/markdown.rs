//! Any report's table set as Markdown, and what every `report.md` shares: the file's
//! name, the signs a cell is written with, a section under its heading, and a file's
//! link from the folder. In: a [`Table`] or [`Section`]s of the kit's model (or a
//! document's folder and a file). Out: Markdown text; a cell reads `ours · paper`,
//! flagged ⚠.

use crate::report::kit::table::{Cell, Entry, Section, Signs, Table};
use comfy_table::presets::ASCII_MARKDOWN;
use std::fmt::Write;
use std::path::{Path, PathBuf};

pub const FILE: &str = "report.md";
pub(crate) const FLAG: &str = "⚠";

pub(crate) const SIGNS: Signs = Signs {
    percent: " %",
    minus: "-",
    plus_minus: " ± ",
};

/// A report's table as Markdown, its groups run together, `—` where a cell has no
/// value.
pub(crate) fn table(table: &Table) -> comfy_table::Table {
    let mut markdown = comfy_table::Table::new();
    markdown.load_preset(ASCII_MARKDOWN);
    markdown.set_header(table.header.clone());
    for row in table.groups.iter().flatten() {
        markdown.add_row(row.iter().map(entry_text).collect::<Vec<_>>());
    }
    markdown
}

/// One cell as Markdown; a paper's cell with its published value beside it.
fn entry_text(entry: &Entry) -> String {
    match entry {
        Entry::Published(cell) => cell_text(cell),
        other => other.text(&SIGNS),
    }
}

/// Our value, then the published one beside it, flagged where they disagree.
fn cell_text(entry: &Cell) -> String {
    let ours = entry.ours.text(&SIGNS);
    let Some(paper) = &entry.paper else {
        return ours;
    };
    let flag = if entry.flagged {
        format!(" {FLAG}")
    } else {
        String::new()
    };
    format!("{ours} · paper {}{flag}", paper.text(&SIGNS))
}

/// `file` as a link from a document in `folder`.
pub(crate) fn relative_link(folder: &Path, file: &Path) -> String {
    path_from(folder, file)
        .unwrap_or_else(|| file.to_path_buf())
        .to_string_lossy()
        .replace(' ', "%20")
}

/// `file` as a path from `folder`, both taken through their links; none where there
/// is no such path.
pub(crate) fn path_from(folder: &Path, file: &Path) -> Option<PathBuf> {
    pathdiff::diff_paths(absolute(file), absolute(folder))
}

/// `path` made absolute through its links, or as it is when it cannot be.
fn absolute(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

/// `sections` as Markdown, each under a third-level heading.
pub(crate) fn sections(sections: &[Section]) -> String {
    let mut out = String::new();
    for section in sections {
        let _ = writeln!(out, "### {}\n", section.title);
        let _ = writeln!(out, "{}\n", section.caption);
        let _ = writeln!(out, "{}\n", table(&section.table));
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::kit::table::{Detail, RmseValue};

    fn value(rmse_cm_s: f64, t_conv_s: f64) -> RmseValue {
        RmseValue {
            rmse_cm_s,
            ci_cm_s: None,
            detail: Some(Detail::TConv(t_conv_s)),
        }
    }

    #[test]
    fn a_cell_reads_ours_then_the_paper_flagged_where_they_disagree() {
        let flagged = Cell {
            ours: value(5.0, 20.0),
            paper: Some(value(5.0, 100.0)),
            flagged: true,
        };
        let report_table = Table {
            header: vec!["DVL".into(), "Baseline".into(), "EM5".into()],
            label_columns: 1,
            groups: vec![vec![vec![
                Entry::Text("DVL1".into()),
                Entry::Missing,
                Entry::Published(flagged),
            ]]],
            notes: Vec::new(),
        };
        assert_eq!(
            table(&report_table).to_string(),
            "| DVL  | Baseline | EM5                            |\n\
             |------|----------|--------------------------------|\n\
             | DVL1 | —        | 5.00 (20) · paper 5.00 (100) ⚠ |"
        );
        assert_eq!(cell_text(&Cell::alone(value(0.74, 100.0))), "0.74 (100)");
    }
}
