//! The operator's report: what a command printed, set as Markdown (each line a
//! paragraph, its tables as tables), then its figures, each with its caption, written
//! as `report.md` beside the figures' PNG and SVG files, and as one self-contained
//! `report.html`, the same Markdown rendered with every figure inlined as a `data:`
//! URI: it opens with no network, no script and no other file, and can be handed on
//! alone. In: the folder, a title, the printed text and the figures drawn. Out: the
//! files written, each atomically.

use crate::files::write_atomic;
use crate::report::kit::plots::canvas::Outcome;
use crate::report::kit::plots::{Caption, Format, PlotError, Written, write_figures};
use base64::Engine;
use pulldown_cmark::{Event, Options, Parser, Tag};
use std::path::{Path, PathBuf};

/// The report's Markdown and HTML files' names.
pub const MARKDOWN: &str = "report.md";
pub const HTML: &str = "report.html";

/// Writes the report titled `title` into `folder`: the `printed` text and the figures
/// `drawn` (their files first, then `report.md`, then `report.html`).
pub fn write_report(
    folder: &Path,
    title: &str,
    printed: &str,
    drawn: Vec<(String, Outcome)>,
) -> Result<Vec<PathBuf>, PlotError> {
    let figures = write_figures(drawn, folder, Format::Both)?;
    let markdown = markdown(title, printed, &figures);
    let io = |path: PathBuf| move |source| PlotError::Io { path, source };
    let mut written: Vec<PathBuf> = figures.iter().flat_map(|f| f.files.clone()).collect();
    let path = folder.join(MARKDOWN);
    write_atomic(&path, markdown.as_bytes()).map_err(io(path.clone()))?;
    written.push(path);
    let html = html(title, &markdown, folder)?;
    let path = folder.join(HTML);
    write_atomic(&path, html.as_bytes()).map_err(io(path.clone()))?;
    written.push(path);
    Ok(written)
}

/// The line `text` as a Markdown paragraph of that text: its leading spaces dropped
/// (four would open a code block), a line-start marker of a list, a rule or a heading
/// escaped, and the characters inline markup reads ([`inline`]).
fn escaped(text: &str) -> String {
    let text = text.trim_start();
    let mut out = String::with_capacity(text.len() + 8);
    if text.starts_with(['-', '+', '=']) {
        out.push('\\');
    }
    // An ordered list's marker: digits, then `.` or `)` and a space (digits are ASCII).
    let digits = text.bytes().take_while(u8::is_ascii_digit).count();
    let (number, rest) = text.split_at(digits);
    out.push_str(number);
    if digits > 0
        && (rest.starts_with(". ") || rest.starts_with(") ") || rest == "." || rest == ")")
    {
        out.push('\\');
    }
    out.push_str(&inline(rest));
    out
}

/// `text` with each character inline Markdown reads as markup escaped.
fn inline(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if matches!(
            c,
            '\\' | '*' | '_' | '<' | '>' | '[' | ']' | '`' | '#' | '&'
        ) {
            out.push('\\');
        }
        out.push(c);
    }
    out
}

/// The report's Markdown: the title, each printed line a paragraph (a table's rows
/// kept together as its table), then each figure (its PNG) under its caption, or why
/// it was not drawn.
fn markdown(title: &str, printed: &str, figures: &[Written]) -> String {
    let mut out = format!("# {}\n\n", escaped(title));
    let mut in_table = false;
    for line in printed.lines() {
        let table_row = line.starts_with('|');
        if in_table && !table_row {
            out.push('\n');
        }
        match (table_row, line.trim().is_empty()) {
            (true, _) => {
                let row: Vec<String> = line.split('|').map(inline).collect();
                out.push_str(&row.join("|"));
                out.push('\n');
            }
            (false, true) => {}
            (false, false) => {
                out.push_str(&escaped(line));
                out.push_str("\n\n");
            }
        }
        in_table = table_row;
    }
    out.push_str("\n## Figures\n\n");
    let mut number = 0;
    for figure in figures {
        match &figure.caption {
            Caption::Drawn(caption) => {
                number += 1;
                let png = format!("{}.png", figure.stem);
                out.push_str(&format!(
                    "![{}](<{png}>)\n\n*Figure {number}.* {}\n\n",
                    escaped(caption),
                    escaped(caption)
                ));
            }
            Caption::NotApplicable(why) => {
                out.push_str(&format!(
                    "*{}*: not drawn, {}\n\n",
                    figure.stem,
                    escaped(why)
                ));
            }
        }
    }
    out
}

/// The page of `markdown`, each image read from `folder` and inlined.
fn html(title: &str, markdown: &str, folder: &Path) -> Result<String, PlotError> {
    let mut events = Vec::new();
    for event in Parser::new_ext(markdown, Options::ENABLE_TABLES) {
        events.push(match event {
            Event::Start(Tag::Image {
                link_type,
                dest_url,
                title,
                id,
            }) => {
                let path = folder.join(dest_url.as_ref());
                let bytes = std::fs::read(&path).map_err(|source| PlotError::Io {
                    path: path.clone(),
                    source,
                })?;
                let encoded = base64::engine::general_purpose::STANDARD.encode(bytes);
                Event::Start(Tag::Image {
                    link_type,
                    dest_url: format!("data:image/png;base64,{encoded}").into(),
                    title,
                    id,
                })
            }
            other => other,
        });
    }
    let mut body = String::new();
    pulldown_cmark::html::push_html(&mut body, events.into_iter());
    let mut escaped_title = String::new();
    pulldown_cmark_escape::escape_html(&mut escaped_title, title)
        .expect("writing to a String never fails");
    let title = escaped_title;
    Ok(format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{title}</title>\n<style>\n{STYLE}</style>\n</head>\n<body>\n{body}</body>\n</html>\n"
    ))
}

/// The page's look: readable widths, tables ruled, figures within the page.
const STYLE: &str = "body { font-family: sans-serif; max-width: 72em; margin: 2em auto; padding: 0 1em; line-height: 1.4; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.9em; }
th, td { border: 1px solid #bbb; padding: 0.2em 0.5em; text-align: left; }
img { max-width: 100%; height: auto; }
";

#[cfg(test)]
mod tests {
    use super::*;

    /// The printed lines become paragraphs and the table a table; markup in the text is
    /// kept as text.
    #[test]
    fn printed_lines_are_paragraphs_and_tables_tables() {
        let printed = "read: 400 samples, *none* left out\n| term | estimate |\n|------|----------|\n| scale | -0.2 % |\nafter <all> of it &amp; more\n    - 1. four spaces, a list\n2. a number\n2.81 cm/s\n";
        let markdown = markdown("T1", printed, &[]);
        let html = html("T1 & T2", &markdown, Path::new(".")).unwrap();
        assert!(
            html.contains("<p>read: 400 samples, *none* left out</p>"),
            "{html}"
        );
        assert!(html.contains("<td>-0.2 %</td>"), "{html}");
        assert!(
            html.contains("<p>after &lt;all&gt; of it &amp;amp; more</p>"),
            "{html}"
        );
        assert!(html.contains("<p>- 1. four spaces, a list</p>"), "{html}");
        assert!(html.contains("<p>2. a number</p>"), "{html}");
        assert!(html.contains("<p>2.81 cm/s</p>"), "{html}");
        assert!(html.contains("<title>T1 &amp; T2</title>"), "{html}");
    }
}
