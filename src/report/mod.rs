//! Everything drawn from results folders alone, never from a run's memory, so that it
//! can be redrawn without re-running. In: a [`StoredRun`] (or a study's tables, a
//! sweep's table, a calibration, two folders). Out: text and files for people. A kit
//! that every content uses, then one room per content:
//!
//! - [`kit`]: the one model of a report's tables (a header, label columns, rows of
//!   cells in groups, notes; a section around a table) and its two renderings, Markdown
//!   and LaTeX; the drawing kit of the figures (canvas, axes, looks, legends, term
//!   panels, the PNG and SVG files); how a number and an error term are written. It
//!   imports no room;
//! - [`paper`]: the paper's experiment: its tables beside the published ones, how long
//!   to calibrate, `report.md` and `report.tex` of a run, the tables `run` prints, the
//!   figures of a run and of a sweep;
//! - [`study`]: the installation study: its sections, its printed headline and sweep
//!   table, its figures;
//! - [`operator`]: what `calibrate` and `correct` print;
//! - [`compare`]: two results folders side by side;
//! - this module: `results/<name>/report.md` and `report.tex` of every kind, from one
//!   entry ([`documents`], [`write`]), written once the run's folder is and sealed with
//!   its manifest and figures ([`SEAL`], [`is_complete`]).

pub mod kit;
pub mod paper;
pub mod study;
pub mod operator;
pub mod compare;

pub use kit::markdown::FILE;

use crate::installation::study::rows::StudyResults;
use crate::results::read::StoredRun;
use kit::plots::Written;
use paper::ReportTables;
use std::fmt::Write;
use std::path::{Path, PathBuf};

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
                paper::markdown::render(run, &tables, figures),
                paper::latex::render(run, &tables),
            )
        }
        Reported::Study { study, name, .. } => (study::markdown(study), study::latex(study, name)),
    };
    [(FILE, markdown), (kit::latex::FILE, tex)]
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
        let shown = kit::markdown::path_from(folder, &path).unwrap_or(path);
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
        && [crate::results::MANIFEST, FILE, kit::latex::FILE]
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
