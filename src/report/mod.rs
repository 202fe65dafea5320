//! Everything drawn from results folders alone, never from a run's memory, so that it
//! can be redrawn without re-running. In: a [`StoredRun`] (or a sweep's table, or two
//! folders). Out: text and files for people.
//!
//! - [`printed`]: the calibration and evaluation tables that `run` prints;
//! - [`plots`]: the figures of a run and of a sweep;
//! - [`table`]: the one model of a report's tables (a header, label columns, rows of
//!   cells in groups, notes; a section around a table), the paper's tables built from a
//!   run in its layout, our value beside the published one and cells off by more than
//!   the spec's tolerance flagged; [`calibration_time`] (how long each method needs to
//!   calibrate) and the installation study's sections ([`installation`]) build theirs
//!   in the same model;
//! - [`markdown`] and [`latex`]: any such table set as Markdown and as LaTeX; the
//!   paper's report.md adds the training summary, wall time per stage, provenance from
//!   the manifest and the figures;
//! - this module: `results/<name>/report.md` and `report.tex` of every kind, from one
//!   entry ([`documents`], [`write`]), written once the run's folder is and sealed with
//!   its manifest and figures ([`SEAL`], [`is_complete`]);
//! - [`compare`]: two results folders side by side;
//! - [`readable`]: error terms in the units people read, below the tables, figures and
//!   printed lines that show them.

pub mod calibration_time;
pub mod compare;
pub mod installation;
pub mod latex;
pub mod markdown;
pub mod plots;
pub mod printed;
pub mod readable;
pub mod table;

pub use markdown::FILE;

use crate::installation::study::rows::StudyResults;
use crate::report::plots::Written;
use crate::results::read::StoredRun;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use table::ReportTables;

/// The seal of what a finished run promises beyond its tables, written last: the
/// SHA-256 of `manifest.json`, both reports and every figure drawn, one
/// `<sha256>  <path from the results folder>` line each (`sha256sum -c` reads it).
pub const SEAL: &str = "report.sha256";

/// What a results folder's reports are written from, one variant per kind of run.
pub enum Reported<'a> {
    /// A paper run read back, and the figures drawn for it (none with `--no-plots`).
    Run {
        run: &'a StoredRun,
        figures: &'a [Written],
    },
    /// An installation study's tables, in `folder`; `name` keys its LaTeX labels; and
    /// the figures drawn for it.
    Study {
        study: &'a StudyResults,
        name: &'a str,
        folder: &'a Path,
        figures: &'a [Written],
    },
}

/// A results folder's two reports, `report.md` then `report.tex`, each with its file
/// name: a pure function of what is reported, so `plot` writes them again to the same
/// bytes.
pub fn documents(reported: &Reported) -> [(&'static str, String); 2] {
    let (markdown, tex) = match reported {
        Reported::Run { run, figures } => {
            let tables = ReportTables::of(run);
            (
                markdown::render(run, &tables, figures),
                latex::render(run, &tables),
            )
        }
        Reported::Study { study, name, .. } => (
            installation::markdown(study),
            installation::latex(study, name),
        ),
    };
    [(FILE, markdown), (latex::FILE, tex)]
}

/// Writes a results folder's [`documents`] into it, each atomically, then seals them
/// with its manifest and figures ([`SEAL`]), whatever the kind; returns their paths.
pub fn write(reported: &Reported) -> std::io::Result<[PathBuf; 2]> {
    let (folder, figures) = match reported {
        Reported::Run { run, figures } => (run.folder.as_path(), *figures),
        Reported::Study {
            folder, figures, ..
        } => (*folder, *figures),
    };
    let [markdown, tex] = documents(reported).map(|(name, text)| (folder.join(name), text));
    for (path, text) in [&markdown, &tex] {
        crate::files::write_atomic(path, text.as_bytes())?;
    }
    seal(folder, figures, [&markdown.0, &tex.0])?;
    Ok([markdown.0, tex.0])
}

/// Writes [`SEAL`] in `folder`: the SHA-256 of its manifest, its reports and every
/// figure.
fn seal(folder: &Path, figures: &[Written], reports: [&PathBuf; 2]) -> std::io::Result<()> {
    let mut sealed = vec![folder.join(crate::results::MANIFEST)];
    sealed.extend(reports.map(PathBuf::clone));
    sealed.extend(figures.iter().flat_map(|f| f.files.iter().cloned()));
    let mut seal = String::new();
    for path in sealed {
        let bytes = std::fs::read(&path)?;
        let shown = markdown::path_from(folder, &path).unwrap_or(path);
        let _ = writeln!(
            seal,
            "{}  {}",
            crate::files::sha256_hex(&bytes),
            shown.display()
        );
    }
    crate::files::write_atomic(&folder.join(SEAL), seal.as_bytes())
}

/// Whether `folder` holds everything a finished run promises beyond its tables, with
/// the bytes it was written with: its manifest, both reports and every figure its
/// [`SEAL`] names (a report drawn with `--no-plots` says so and names none).
pub fn is_complete(folder: &Path) -> bool {
    let Ok(seal) = std::fs::read_to_string(folder.join(SEAL)) else {
        return false;
    };
    // `<sha256>  <path>` lines, digest first.
    let Some(named) = seal
        .lines()
        .map(|line| line.split_once("  ").map(|(digest, path)| (path, digest)))
        .collect::<Option<Vec<_>>>()
    else {
        return false;
    };
    crate::results::files_intact(folder, named.iter().copied())
        && [crate::results::MANIFEST, FILE, latex::FILE]
            .iter()
            .all(|required| named.iter().any(|(path, _)| path == required))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A folder holding `files`, sealed with their SHA-256 as `seal` lists them.
    fn sealed(files: &[(&str, &str)], seal: impl Fn(&str, &str) -> String) -> tempfile::TempDir {
        let folder = tempfile::tempdir().unwrap();
        let mut lines = String::new();
        for (name, text) in files {
            std::fs::create_dir_all(folder.path().join(name).parent().unwrap()).unwrap();
            std::fs::write(folder.path().join(name), text).unwrap();
            lines.push_str(&seal(&crate::files::sha256_hex(text.as_bytes()), name));
        }
        std::fs::write(folder.path().join(SEAL), lines).unwrap();
        folder
    }

    const REPORTS: [(&str, &str); 4] = [
        ("manifest.json", "{}"),
        ("report.md", "# quick"),
        ("report.tex", "% quick"),
        ("../plots/quick/velocity.png", "png"),
    ];

    #[test]
    fn a_folder_is_complete_while_its_seal_holds() {
        let line = |digest: &str, path: &str| format!("{digest}  {path}\n");
        let folder = sealed(&REPORTS[..3], line);
        assert!(is_complete(folder.path()));
        std::fs::write(folder.path().join("report.tex"), "% changed").unwrap();
        assert!(!is_complete(folder.path()));
        // A figure outside the folder, named by its path from it.
        let nested = tempfile::tempdir().unwrap();
        let results = nested.path().join("results");
        std::fs::create_dir_all(&results).unwrap();
        let mut seal = String::new();
        for (name, text) in REPORTS {
            let path = results.join(name);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, text).unwrap();
            seal.push_str(&line(&crate::files::sha256_hex(text.as_bytes()), name));
        }
        std::fs::write(results.join(SEAL), &seal).unwrap();
        assert!(is_complete(&results));
        std::fs::remove_file(results.join("../plots/quick/velocity.png")).unwrap();
        assert!(!is_complete(&results));
    }

    #[test]
    fn a_seal_without_a_report_or_with_a_stray_line_is_not_complete() {
        let line = |digest: &str, path: &str| format!("{digest}  {path}\n");
        assert!(!is_complete(sealed(&REPORTS[..2], line).path()));
        let one_space = |digest: &str, path: &str| format!("{digest} {path}\n");
        assert!(!is_complete(sealed(&REPORTS[..3], one_space).path()));
        assert!(!is_complete(tempfile::tempdir().unwrap().path()));
    }
}
