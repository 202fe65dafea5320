//! `results/<name>/report.md`: the paper's two tables in its layout with our value
//! beside the published one in every cell, cells off by more than the spec's tolerance
//! flagged, our extra estimators and the floor, the training summary, wall time per
//! stage and provenance from the manifest, and the figures. Drawn from a
//! [`StoredRun`] alone, like the figures.

use crate::estimators::{ErrorModel, EstimatorKind};
use crate::plots::Written;
use crate::published::PublishedCell;
use crate::results::read::StoredRun;
use comfy_table::{Table, presets::ASCII_MARKDOWN};
use std::fmt::Write;
use std::path::Path;

pub const FILE: &str = "report.md";
const FLAG: &str = "⚠";

/// Writes the report into the results folder, atomically; returns its path.
pub fn write(run: &StoredRun, figures: &[Written]) -> std::io::Result<std::path::PathBuf> {
    let path = run.folder.join(FILE);
    crate::results::write_atomic(&path, render(run, figures).as_bytes())?;
    Ok(path)
}

/// Counts the cells compared with a published value and those flagged.
#[derive(Debug, Default)]
struct Tally {
    compared: usize,
    flagged: usize,
}

/// Our RMSE (cm/s), with the published cell beside it when there is one.
struct Cell<'a> {
    rmse_cm_s: f64,
    /// T_conv (calibration) or the improvement over the baseline (evaluation).
    detail: Detail,
    published: Option<&'a PublishedCell>,
}

enum Detail {
    TConv(f64),
    Improvement(Option<f64>),
}

impl Cell<'_> {
    fn render(&self, tolerance_pct: f64, tally: &mut Tally) -> String {
        let ours = match self.detail {
            Detail::TConv(t) => format!("{:.2} ({t})", self.rmse_cm_s),
            Detail::Improvement(Some(pct)) => format!("{:.2} ({pct:+.0} %)", self.rmse_cm_s),
            Detail::Improvement(None) => format!("{:.2}", self.rmse_cm_s),
        };
        let Some(paper) = self.published else {
            return ours;
        };
        tally.compared += 1;
        let mut flagged =
            (self.rmse_cm_s - paper.rmse_cm_s).abs() > tolerance_pct / 100.0 * paper.rmse_cm_s;
        let theirs = match (&self.detail, paper.t_conv_s, paper.improvement_pct) {
            (Detail::TConv(ours), Some(t), _) => {
                flagged |= *ours != t;
                format!("{:.2} ({t})", paper.rmse_cm_s)
            }
            (Detail::Improvement(_), _, Some(pct)) => {
                format!("{:.2} ({pct:+.0} %)", paper.rmse_cm_s)
            }
            _ => format!("{:.2}", paper.rmse_cm_s),
        };
        tally.flagged += usize::from(flagged);
        let flag = if flagged {
            format!(" {FLAG}")
        } else {
            String::new()
        };
        format!("{ours} · paper {theirs}{flag}")
    }
}

/// The report as Markdown.
pub fn render(run: &StoredRun, figures: &[Written]) -> String {
    let spec = &run.spec;
    let tolerance = spec.report.tolerance_pct;
    let mut tally = Tally::default();
    let mut out = String::new();
    let _ = writeln!(out, "# {}: results beside the published ones\n", spec.name);
    let _ = writeln!(
        out,
        "RMSE in cm/s, mean over {} Monte Carlo runs. Calibration cells give T_conv in s in brackets, evaluation cells the improvement over the baseline.\n",
        spec.calibration.monte_carlo_runs
    );
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

    let models = crate::tables::models_in(run.calibration.iter().map(|r| r.error_model));
    let dvls = run.dvls();
    let has = |kind: EstimatorKind| run.calibration.iter().any(|r| r.estimator == kind);
    let published = |dvl: &str, kind, model, trajectory: Option<&str>| {
        run.published
            .as_ref()
            .and_then(|p| p.find(dvl, kind, model, trajectory))
    };

    // Calibration, the paper's layout: DVL rows with the baseline and DCNet.
    let _ = writeln!(out, "## Calibration on {}\n", spec.calibration.trajectory);
    let mut table = markdown_table("", &models, "Baseline");
    for dvl in &dvls {
        let cell = |kind: EstimatorKind, model: Option<ErrorModel>, tally: &mut Tally| {
            run.calibration
                .iter()
                .find(|r| {
                    r.is_t_conv && &r.dvl == dvl && r.estimator == kind && r.error_model == model
                })
                .map(|r| {
                    Cell {
                        rmse_cm_s: r.rmse_cm_s,
                        detail: Detail::TConv(r.window_s),
                        published: published(dvl, kind, model, None),
                    }
                    .render(tolerance, tally)
                })
                .unwrap_or_else(|| "—".into())
        };
        // (label, estimator of the first column, estimator of the error-model columns)
        let mut rows = vec![(
            dvl.clone(),
            Some(EstimatorKind::Baseline),
            Some(EstimatorKind::Dcnet),
        )];
        if has(EstimatorKind::LeastSquares) {
            rows.push((
                format!("{dvl} least squares"),
                None,
                Some(EstimatorKind::LeastSquares),
            ));
        }
        if has(EstimatorKind::Floor) {
            rows.push((
                format!("{dvl} floor (true terms)"),
                Some(EstimatorKind::Floor),
                None,
            ));
        }
        for (label, first, per_model) in rows {
            let mut cells = vec![label];
            cells.push(first.map_or("—".into(), |kind| cell(kind, None, &mut tally)));
            for model in &models {
                cells.push(
                    per_model.map_or("—".into(), |kind| cell(kind, Some(*model), &mut tally)),
                );
            }
            table.add_row(cells);
        }
    }
    let _ = writeln!(
        out,
        "The DVL rows hold the baseline and DCNet, as in the paper; the floor corrects with the true terms, a bound no estimator can beat.\n\n{table}\n"
    );

    // Evaluation, the paper's layout: DVL × trajectory rows, the baseline and DCNet.
    let _ = writeln!(out, "## Evaluation with the T_conv terms\n");
    let trajectories = crate::first_seen(run.evaluation.iter().map(|r| r.trajectory.clone()));
    let evaluation_cell =
        |dvl: &str, trajectory: &str, kind, model, with_paper: bool, tally: &mut Tally| {
            run.evaluation
                .iter()
                .find(|r| {
                    r.dvl == dvl
                        && r.trajectory == trajectory
                        && r.estimator == kind
                        && r.error_model == model
                })
                .map(|r| {
                    Cell {
                        rmse_cm_s: r.rmse_cm_s,
                        detail: Detail::Improvement(
                            r.improvement_pct
                                .filter(|_| kind != EstimatorKind::Baseline),
                        ),
                        published: published(dvl, kind, model, Some(trajectory))
                            .filter(|_| with_paper),
                    }
                    .render(tolerance, tally)
                })
                .unwrap_or_else(|| "—".into())
        };
    // One DVL × trajectory row per cell pair: `first` in the first value column, `per_model`
    // with each error model in the others.
    let mut evaluation_table = |first_label: &str, first, per_model, with_paper: bool| {
        let mut table = markdown_table("trajectory", &models, first_label);
        for dvl in &dvls {
            for trajectory in &trajectories {
                let mut cells = vec![dvl.clone(), trajectory.clone()];
                cells.push(evaluation_cell(
                    dvl, trajectory, first, None, with_paper, &mut tally,
                ));
                for model in &models {
                    cells.push(evaluation_cell(
                        dvl,
                        trajectory,
                        per_model,
                        Some(*model),
                        with_paper,
                        &mut tally,
                    ));
                }
                table.add_row(cells);
            }
        }
        table
    };
    let paper = evaluation_table(
        "Baseline",
        EstimatorKind::Baseline,
        EstimatorKind::Dcnet,
        true,
    );
    let _ = writeln!(out, "{paper}\n");
    if has(EstimatorKind::LeastSquares) || has(EstimatorKind::Floor) {
        let beyond = evaluation_table(
            "floor (true terms)",
            EstimatorKind::Floor,
            EstimatorKind::LeastSquares,
            false,
        );
        let _ = writeln!(
            out,
            "Beyond the paper: least squares on the same data, and the floor.\n\n{beyond}\n"
        );
    }
    if run.published.is_some() {
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

/// A Markdown table with a DVL column, an optional second label column, a first value
/// column and one column per error model.
fn markdown_table(second: &str, models: &[ErrorModel], first: &str) -> Table {
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    let mut header = vec!["DVL".to_string()];
    if !second.is_empty() {
        header.push(second.to_string());
    }
    header.push(first.to_string());
    header.extend(models.iter().map(ToString::to_string));
    table.set_header(header);
    table
}

fn training_section(run: &StoredRun, out: &mut String) {
    if run.training.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "## DCNet training\n\nEpoch times are those of the run that trained each model; a model taken from the cache costs this run no training time.\n"
    );
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    table.set_header([
        "EM",
        "epochs",
        "best epoch",
        "best validation loss (cm/s)²",
        "training s",
    ]);
    let mut models: Vec<ErrorModel> = run.training.iter().map(|e| e.error_model).collect();
    models.dedup();
    for model in models {
        let epochs: Vec<_> = run
            .training
            .iter()
            .filter(|e| e.error_model == model)
            .collect();
        let best = epochs.iter().find(|e| e.is_best);
        table.add_row(vec![
            model.to_string(),
            epochs.len().to_string(),
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
    let mut table = Table::new();
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
    let _ = writeln!(
        out,
        "- backend: {}, {} threads, host {}",
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
            Ok(caption) => {
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
            Err(why) => {
                let _ = writeln!(out, "- {}: not drawn, {why}\n", figure.stem);
            }
        }
    }
}

/// `file` as a link from a document in `folder`.
fn relative_link(folder: &Path, file: &Path) -> String {
    let absolute = |p: &Path| std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
    pathdiff::diff_paths(absolute(file), absolute(folder))
        .unwrap_or_else(|| file.to_path_buf())
        .to_string_lossy()
        .replace(' ', "%20")
}
