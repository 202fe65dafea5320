//! `results/<name>/report.md` of a paper run: the paper's tables ([`ReportTables`]) set
//! as Markdown by the kit ([`markdown`](crate::report::kit::markdown)) with the
//! captions that explain them, then how long to calibrate, the training summary, wall
//! time per stage, provenance from the manifest, and the figures. In: a [`StoredRun`],
//! its tables and the figures drawn. Out: the Markdown text; a cell reads
//! `ours · paper`, flagged ⚠.

use super::tables::{ReportTables, replicates_note};
use crate::report::kit::markdown::{FLAG, relative_link, sections, table};
use crate::report::kit::plots::{Caption, Written};
use crate::results::read::StoredRun;
use comfy_table::presets::ASCII_MARKDOWN;
use std::fmt::Write;

/// The report as Markdown.
pub(crate) fn render(run: &StoredRun, tables: &ReportTables, figures: &[Written]) -> String {
    let spec = &run.spec;
    let tolerance = spec.report.tolerance_pct;
    let mut out = String::new();
    let _ = writeln!(out, "# {}: results beside the published ones\n", spec.name);
    let _ = writeln!(
        out,
        "RMSE in cm/s, mean over {} Monte Carlo runs. Calibration cells give T_conv in s in brackets, evaluation cells the improvement over the baseline.\n",
        spec.calibration.monte_carlo_runs
    );
    if let Some(note) = replicates_note(spec.training.replicates) {
        let _ = writeln!(out, "{note}\n");
    }
    match &run.published {
        Some(published) => {
            let _ = writeln!(
                out,
                "A cell reads `ours · paper`; {FLAG} flags an RMSE more than {tolerance} % off the published one, or another T_conv. Published values: {}.\n",
                published.source
            );
        }
        None => {
            let _ = writeln!(
                out,
                "The spec names no published values (`report.published`), so only ours are shown.\n"
            );
        }
    }

    let _ = writeln!(out, "## Calibration on {}\n", spec.calibration.trajectory);
    let _ = writeln!(
        out,
        "The DVL rows hold the baseline and DCNet, as in the paper. The floor corrects with the true terms, which no estimator can beat; the bound is the best mean RMSE any unbiased estimator can reach from the window's data (see \"Against the information bound\").\n\n{}\n",
        table(&tables.calibration)
    );
    let _ = writeln!(out, "## Evaluation with the T_conv terms\n");
    let _ = writeln!(out, "{}\n", table(&tables.evaluation));
    if let Some(beyond) = &tables.beyond {
        let _ = writeln!(
            out,
            "Beyond the paper: least squares on the same data, and the floor.\n\n{}\n",
            table(beyond)
        );
    }
    if let Some(ensemble) = &tables.ensemble {
        let _ = writeln!(
            out,
            "The DCNet ensemble: the mean of the {} replicates' terms in each calibration window.\n\n{}\n",
            spec.training.replicates,
            table(ensemble)
        );
    }
    if let Some(efficiency) = &tables.efficiency {
        let _ = writeln!(out, "## Against the information bound\n");
        let _ = writeln!(
            out,
            "The bound is the mean RMSE of an efficient estimator of the DVL's scale and bias from the calibration window (the Cramér–Rao bound on the terms, propagated to the corrected velocity): no unbiased calibration from that much data does better on average. The floor is the limit with perfect terms; the bound, the limit with w seconds of data. In brackets, each estimator's efficiency: the bound at its T_conv over its RMSE.\n\n{}\n",
            table(efficiency)
        );
    }
    let timing = super::calibration_time::sections(run);
    if !timing.is_empty() {
        let _ = writeln!(out, "## How long to calibrate\n");
        let _ = writeln!(out, "{}", sections(&timing));
    }
    if run.published.is_some() {
        let tally = tables.tally();
        let _ = writeln!(
            out,
            "**{} of {} cells compared with the paper are flagged {FLAG}.**\n",
            tally.flagged, tally.compared
        );
    }

    training_section(run, &mut out);
    provenance_section(run, &mut out);
    figures_section(run, figures, &mut out);
    out
}

fn training_section(run: &StoredRun, out: &mut String) {
    if run.training.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "## DCNet training\n\nEpoch times are those of the run that trained each model; a model taken from the cache costs this run no training time.\n"
    );
    let mut table = comfy_table::Table::new();
    table.load_preset(ASCII_MARKDOWN);
    table.set_header([
        "EM",
        "epochs",
        "stopped by",
        "best epoch",
        "best validation loss (cm/s)²",
        "training s",
    ]);
    let models = run.trained_models();
    for (model, replicate) in models {
        let epochs: Vec<_> = run
            .training
            .iter()
            .filter(|e| e.error_model == model && e.replicate == replicate)
            .collect();
        let best = epochs.iter().find(|e| e.is_best);
        table.add_row(vec![
            match replicate {
                Some(r) => format!("{model}, replicate {}", r + 1),
                None => model.to_string(),
            },
            epochs.len().to_string(),
            epochs
                .first()
                .map(|e| e.stop.to_string())
                .unwrap_or_default(),
            best.map(|e| e.record.epoch.to_string()).unwrap_or_default(),
            best.map(|e| format!("{:.4}", e.record.validation_loss))
                .unwrap_or_default(),
            format!(
                "{:.0}",
                epochs.iter().map(|e| e.record.seconds).sum::<f64>()
            ),
        ]);
    }
    let _ = writeln!(out, "{table}\n");
}

fn provenance_section(run: &StoredRun, out: &mut String) {
    let m = &run.manifest;
    let s = &m.stage_seconds;
    let _ = writeln!(
        out,
        "## Run\n\nWall time of the process that wrote this folder, over every point of its spec; work taken from the cache counts nothing.\n"
    );
    let mut table = comfy_table::Table::new();
    table.load_preset(ASCII_MARKDOWN);
    table.set_header(["stage", "wall time s"]);
    for (stage, seconds) in [
        ("load", s.load),
        ("dataset", s.dataset),
        ("training", s.training),
        ("protocol", s.protocol),
        ("total", s.load + s.dataset + s.training + s.protocol),
    ] {
        table.add_row(vec![stage.to_string(), format!("{seconds:.2}")]);
    }
    let _ = writeln!(out, "{table}\n");
    let products = if m.instruction_set.is_empty() {
        String::new()
    } else {
        format!(", matrix products on {}", m.instruction_set)
    };
    let _ = writeln!(
        out,
        "- backend: {}, {} threads, host {}{products}",
        m.backend, m.threads, m.host
    );
    let _ = writeln!(
        out,
        "- dcnet-exp {} at commit {}",
        m.crate_version, m.git_commit
    );
    let _ = writeln!(
        out,
        "- started {}, finished {}",
        m.started_at, m.finished_at
    );
    let _ = writeln!(
        out,
        "- spec sha256 {} (`spec.toml` beside this report)",
        m.spec_sha256
    );
    for file in &m.data_files {
        let _ = writeln!(out, "- data {} sha256 {}", file.path.display(), file.sha256);
    }
    let _ = writeln!(out);
}

fn figures_section(run: &StoredRun, figures: &[Written], out: &mut String) {
    if figures.is_empty() {
        let _ = writeln!(
            out,
            "## Figures\n\nNone drawn (`--no-plots`); `dcnet-exp plot {}` draws them.",
            run.folder.display()
        );
        return;
    }
    let _ = writeln!(out, "## Figures\n");
    for figure in figures {
        match &figure.caption {
            Caption::Drawn(caption) => {
                let links: Vec<String> = figure
                    .files
                    .iter()
                    .map(|f| relative_link(&run.folder, f))
                    .collect();
                match links.iter().find(|l| l.ends_with(".png")) {
                    Some(png) => {
                        let _ = writeln!(out, "![{caption}]({png})\n");
                    }
                    None => {
                        let _ = writeln!(out, "- {caption}: {}\n", links.join(", "));
                    }
                }
            }
            Caption::NotApplicable(why) => {
                let _ = writeln!(out, "- {}: not drawn, {why}\n", figure.stem);
            }
        }
    }
}
