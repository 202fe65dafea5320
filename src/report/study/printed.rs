//! The tables an installation study prints at the end of `run` and `collect`: a single
//! study's headline (each method's mean held-out RMSE at the largest window, on the
//! pairs inside the folds with `[learned]`, and the first fits that failed), and a sweep
//! of studies' table (each point's methods at its largest window). In: the study's
//! tables, or the sweep's as `results::study_sweep` reads them. Out: the text
//! printed.

use crate::installation::study::clock_kept_on;
use crate::installation::study::rows::StudyResults;
use crate::report::study::heldout::clocks_kept;
use crate::results::study_sweep::StoredStudySweep;
use comfy_table::{Table, presets::ASCII_MARKDOWN};
use std::fmt::Write;

/// The headline: each method's mean held-out RMSE at the largest window, with its
/// 95 % interval and its ratio to no calibration; with `[learned]`, on the pairs inside
/// the folds, where every method is scored on the same pairs as the learned ones.
pub fn headline(study: &StudyResults) -> String {
    let inside_folds: Vec<_> = study
        .folds
        .iter()
        .filter(|r| r.fold == "all")
        .map(|r| r.summary.clone())
        .collect();
    let (summary, which) = if inside_folds.is_empty() {
        (&study.summary, "held-out trajectories")
    } else {
        (
            &inside_folds,
            "held-out trajectories inside the folds (every method on the pairs the learned models never saw)",
        )
    };
    let largest = summary.iter().map(|s| s.window_s).fold(f64::NAN, f64::max);
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    table.set_header([
        "method",
        "held-out RMSE (cm/s)",
        "95 % interval",
        "÷ no calibration",
        "calibrations",
    ]);
    for row in summary.iter().filter(|s| s.window_s == largest) {
        table.add_row([
            row.method.clone(),
            format!("{:.2}", row.mean_cm_s),
            format!("± {:.2}", row.ci95_cm_s),
            format!("{:.3}", row.ratio),
            row.calibrations.to_string(),
        ]);
    }
    let mut text = format!("{which}, calibration windows of {largest} s:\n{table}");
    failed_fits(study, &mut text);
    gaps_and_losses(study, &mut text);
    text
}

/// Under the headline: each recording that had DVL samples left out or was cut into
/// pieces, as it was read.
fn gaps_and_losses(study: &StudyResults, text: &mut String) {
    for row in &study.recordings {
        let counts = row.counts();
        if counts.kept < counts.read() || counts.pieces > 1 {
            let _ = write!(text, "\n{} read: {counts}", row.recording);
        }
    }
}

/// Under the headline: how many fits failed, and the first three; then how many
/// scorings kept the calibration's clock.
fn failed_fits(study: &StudyResults, text: &mut String) {
    let failed: Vec<_> = study
        .failures
        .iter()
        .filter(|f| clock_kept_on(f).is_none())
        .collect();
    if !failed.is_empty() {
        let _ = write!(
            text,
            "\n{} failed, each leaving its method one calibration trajectory fewer at its window (failures.parquet lists them all), such as:",
            crate::count(failed.len(), "fit")
        );
    }
    for failure in failed.iter().take(3) {
        let _ = write!(
            text,
            "\n  {} on {} at {} s: {}",
            failure.method, failure.calibration, failure.window_s, failure.why
        );
    }
    if let Some(kept) = clocks_kept(study, None) {
        let _ = write!(text, "\n{kept}");
    }
}

/// A sweep's headline: each point's methods at its largest window, a column per cell.
pub fn sweep_table(stored: &StoredStudySweep) -> String {
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    table.set_header([
        "point",
        "method",
        "window (s)",
        "held-out RMSE (cm/s)",
        "95 % interval",
        "÷ no calibration",
        "calibrations",
    ]);
    for point in &stored.index.points {
        let rows: Vec<_> = stored.rows.iter().filter(|r| &r.point == point).collect();
        let largest = rows
            .iter()
            .map(|r| r.summary.window_s)
            .fold(f64::NAN, f64::max);
        for row in rows.iter().filter(|r| r.summary.window_s == largest) {
            let s = &row.summary;
            table.add_row([
                point.clone(),
                s.method.clone(),
                format!("{}", s.window_s),
                format!("{:.2}", s.mean_cm_s),
                format!("± {:.2}", s.ci95_cm_s),
                format!("{:.3}", s.ratio),
                s.calibrations.to_string(),
            ]);
        }
    }
    format!("held-out trajectories, each point at its largest calibration window:\n{table}")
}
