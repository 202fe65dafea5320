//! `plot` and `compare`: figures and reports drawn from results folders alone, and two
//! folders set side by side; nothing is re-run.

use super::{CliError, failure, input, report_figures};
use crate::report::kit::plots::Format;
use crate::report::paper::figures::write_all;
use crate::report::paper::sweep::{Metric, write_sweep};
use crate::report::{self, compare};
use crate::results::held::Held;
use crate::results::read::StoredRun;
use crate::results::sweep;
use std::path::Path;

/// Draws the figures of a results folder, a single run's or a sweep's, and writes the
/// reports.
pub(super) fn plot(
    results: &Path,
    out: Option<&Path>,
    format: Format,
    metric: Metric,
) -> Result<(), CliError> {
    match Held::of(results) {
        held if held.is_study() => {
            return super::study::plot(results, out.unwrap_or(Path::new("plots")), format);
        }
        Held::Sweep => {}
        _ => return plot_run(results, out, format),
    }
    let index = sweep::read_index(results).map_err(input)?;
    for point in &index.points {
        plot_run(&results.join(point), out, format)?;
    }
    plot_sweep(results, out, format, metric)
}

/// Reads the results folder back, draws its figures into `out/<name>/` (none when
/// `out` is `None`) and writes its report.
pub(super) fn plot_run(results: &Path, out: Option<&Path>, format: Format) -> Result<(), CliError> {
    let stored = StoredRun::read(results).map_err(input)?;
    stored.check_tables().map_err(input)?;
    let figures = match out {
        Some(out) => {
            let folder = out.join(&stored.spec.name);
            remove_stale_partials(&folder)?;
            let figures = write_all(&stored, &folder, format).map_err(failure)?;
            report_figures(&figures, &folder);
            figures
        }
        None => Vec::new(),
    };
    let reported = report::Reported::Run {
        run: &stored,
        figures: &figures,
    };
    let [markdown, tex] = report::write(&reported).map_err(failure)?;
    eprintln!(
        "report written to {} and {}",
        markdown.display(),
        tex.display()
    );
    Ok(())
}

/// Draws a sweep's figures into `out/<name>/`.
pub(super) fn plot_sweep(
    results: &Path,
    out: Option<&Path>,
    format: Format,
    metric: Metric,
) -> Result<(), CliError> {
    let Some(out) = out else { return Ok(()) };
    let stored = sweep::read(results).map_err(input)?;
    let folder = out.join(&stored.index.name);
    remove_stale_partials(&folder)?;
    let figures = write_sweep(&stored, metric, &folder, format).map_err(failure)?;
    report_figures(&figures, &folder);
    Ok(())
}

/// Removes what figure writers killed mid-write left in `folder`.
fn remove_stale_partials(folder: &Path) -> Result<(), CliError> {
    crate::files::remove_stale_partials(folder)
        .map(|_| ())
        .map_err(|e| failure(anyhow::Error::new(e).context(folder.display().to_string())))
}

/// Prints the comparison of two results folders and writes it to `out`.
pub(super) fn compare_folders(first: &Path, second: &Path, out: &Path) -> Result<(), CliError> {
    if out.is_dir() {
        return Err(input(anyhow::anyhow!(
            "--out {}: is a folder; name the file to write the comparison to",
            out.display()
        )));
    }
    let markdown = compare::folders(first, second).map_err(input)?;
    print!("{markdown}");
    compare::write(out, &markdown).map_err(failure)?;
    eprintln!("comparison written to {}", out.display());
    Ok(())
}
