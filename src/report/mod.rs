//! Everything drawn from results folders alone, never from a run's memory, so that it
//! can be redrawn without re-running. In: a [`StoredRun`] (or a sweep's table, or two
//! folders). Out: text and files for people.
//!
//! - [`tables`]: the calibration and evaluation tables that `run` prints;
//! - [`plots`]: the figures of a run and of a sweep;
//! - this module: `results/<name>/report.md` and `report.tex`, the paper's two tables
//!   in its layout with our value beside the published one in every cell, cells off by
//!   more than the spec's tolerance flagged, our extra estimators and the floor; the
//!   Markdown report adds the training summary, wall time per stage, provenance from
//!   the manifest, and the figures. The tables are built once (`Tables`) and set as
//!   Markdown here and as LaTeX in `latex`;
//! - [`compare`]: two results folders side by side.

pub mod compare;
mod latex;
pub mod plots;
pub mod tables;
use crate::evaluate::{CalibrationRow, EvaluationRow};
use crate::report::plots::Written;
use crate::results::read::StoredRun;
use crate::spec::published::PublishedCell;
use crate::vocab::{ErrorModel, EstimatorKind, Phase};
use comfy_table::{Table, presets::ASCII_MARKDOWN};
use std::fmt::Write;
use std::path::{Path, PathBuf};

pub const FILE: &str = "report.md";
const FLAG: &str = "⚠";

/// The seal of what a finished run promises beyond its tables, written last: the
/// SHA-256 of `manifest.json`, both reports and every figure drawn, one
/// `<sha256>  <path from the results folder>` line each (`sha256sum -c` reads it).
pub const SEAL: &str = "report.sha256";

/// Writes `report.md` and `report.tex` into the results folder, then [`SEAL`], each
/// atomically; returns the reports' paths.
pub fn write(run: &StoredRun, figures: &[Written]) -> std::io::Result<[PathBuf; 2]> {
    let tables = Tables::of(run);
    let markdown = run.folder.join(FILE);
    crate::files::write_atomic(&markdown, render(run, &tables, figures).as_bytes())?;
    let tex = run.folder.join(latex::FILE);
    crate::files::write_atomic(&tex, latex::render(run, &tables).as_bytes())?;
    let mut sealed = vec![
        run.folder.join(crate::results::MANIFEST),
        markdown.clone(),
        tex.clone(),
    ];
    sealed.extend(figures.iter().flat_map(|f| f.files.iter().cloned()));
    let mut seal = String::new();
    for path in sealed {
        let bytes = std::fs::read(&path)?;
        let shown = pathdiff::diff_paths(absolute(&path), absolute(&run.folder)).unwrap_or(path);
        let _ = writeln!(
            seal,
            "{}  {}",
            crate::files::sha256_hex(&bytes),
            shown.display()
        );
    }
    crate::files::write_atomic(&run.folder.join(SEAL), seal.as_bytes())?;
    Ok([markdown, tex])
}

/// `path` made absolute through its links, or as it is when it cannot be.
fn absolute(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

/// Whether `folder` holds everything a finished run promises beyond its tables, with
/// the bytes it was written with: its manifest, both reports and every figure its
/// [`SEAL`] names (a report drawn with `--no-plots` says so and names none).
pub fn is_complete(folder: &Path) -> bool {
    let Ok(seal) = std::fs::read_to_string(folder.join(SEAL)) else {
        return false;
    };
    let mut named = Vec::new();
    for line in seal.lines() {
        let Some((digest, path)) = line.split_once("  ") else {
            return false;
        };
        let intact = std::fs::read(folder.join(path))
            .is_ok_and(|bytes| crate::files::sha256_hex(&bytes) == digest);
        if !intact {
            return false;
        }
        named.push(path);
    }
    [crate::results::MANIFEST, FILE, latex::FILE]
        .iter()
        .all(|required| named.contains(required))
}

/// Counts the cells compared with a published value and those flagged.
#[derive(Debug, Default)]
struct Tally {
    compared: usize,
    flagged: usize,
}

/// The report's tables, each cell computed once for both renderings.
struct Tables {
    /// Calibration at T_conv: DVL rows with the baseline and DCNet, then least squares
    /// and the floor.
    calibration: ReportTable,
    /// Evaluation with the T_conv terms: DVL × trajectory rows, baseline and DCNet.
    evaluation: ReportTable,
    /// The same for the floor and least squares, when the run has either.
    beyond: Option<ReportTable>,
    /// The same for the ensemble of DCNet replicates, when the run has several.
    ensemble: Option<ReportTable>,
    /// Every estimator against the information bound, when the run has one.
    efficiency: Option<ReportTable>,
}

/// A table of label columns, a first value column and one column per error model, its
/// rows in one group per DVL.
struct ReportTable {
    /// Headers of the label columns: "DVL", and "trajectory" in the evaluation.
    labels: Vec<&'static str>,
    /// Headers of the value columns.
    columns: Vec<String>,
    groups: Vec<Vec<Row>>,
    /// Its cells compared with a published value, and those flagged.
    tally: Tally,
}

struct Row {
    labels: Vec<String>,
    /// One per value column; `None` where the run has no such value.
    cells: Vec<Option<Cell>>,
}

/// One value cell: our figure, the published one beside it, and whether they disagree.
struct Cell {
    ours: Figure,
    paper: Option<Figure>,
    flagged: bool,
}

/// An RMSE (cm/s) and what the table sets beside it.
struct Figure {
    rmse_cm_s: f64,
    /// Half-width of the 95 % confidence interval over DCNet replicates.
    ci_cm_s: Option<f64>,
    detail: Option<Detail>,
}

#[derive(Clone, Copy)]
enum Detail {
    TConv(f64),
    Improvement(f64),
    /// The bound over the RMSE.
    Efficiency(f64),
}

/// How a rendering writes the signs of a [`Figure`].
struct Signs {
    percent: &'static str,
    minus: &'static str,
    plus_minus: &'static str,
}

impl Figure {
    /// `5.93 (100)` with T_conv, `0.86 (+12 %)` with the improvement, `0.17 (94 %)`
    /// with the efficiency, `0.74` alone; `0.09 ± 0.01 (20)` with a confidence interval.
    fn text(&self, signs: &Signs) -> String {
        let rmse = match self.ci_cm_s {
            Some(ci) => format!("{:.2}{}{ci:.2}", self.rmse_cm_s, signs.plus_minus),
            None => format!("{:.2}", self.rmse_cm_s),
        };
        match self.detail {
            None => rmse,
            Some(Detail::TConv(t)) => format!("{rmse} ({t})"),
            Some(Detail::Improvement(pct)) => {
                let pct = format!("{pct:+.0}");
                let pct = match pct.strip_prefix('-') {
                    Some(magnitude) => format!("{}{magnitude}", signs.minus),
                    None => pct,
                };
                format!("{rmse} ({pct}{})", signs.percent)
            }
            Some(Detail::Efficiency(ratio)) => {
                format!("{rmse} ({:.0}{})", 100.0 * ratio, signs.percent)
            }
        }
    }
}

impl Cell {
    /// Our figure beside the published cell: flagged when the RMSE is more than
    /// `tolerance_pct` off, or the calibration's T_conv differs.
    fn new(
        ours: Figure,
        published: Option<&PublishedCell>,
        phase: Phase,
        tolerance_pct: f64,
        tally: &mut Tally,
    ) -> Cell {
        let paper = published.map(|cell| Figure {
            rmse_cm_s: cell.rmse_cm_s,
            ci_cm_s: None,
            detail: match phase {
                Phase::Calibration => cell.t_conv_s.map(Detail::TConv),
                Phase::Evaluation => cell.improvement_pct.map(Detail::Improvement),
            },
        });
        let flagged = paper.as_ref().is_some_and(|paper| {
            let off =
                (ours.rmse_cm_s - paper.rmse_cm_s).abs() > tolerance_pct / 100.0 * paper.rmse_cm_s;
            let other_t_conv = matches!(
                (ours.detail, paper.detail),
                (Some(Detail::TConv(a)), Some(Detail::TConv(b))) if a != b
            );
            off || other_t_conv
        });
        if paper.is_some() {
            tally.compared += 1;
            tally.flagged += usize::from(flagged);
        }
        Cell {
            ours,
            paper,
            flagged,
        }
    }

    fn markdown(&self) -> String {
        const SIGNS: Signs = Signs {
            percent: " %",
            minus: "-",
            plus_minus: " ± ",
        };
        let ours = self.ours.text(&SIGNS);
        let Some(paper) = &self.paper else {
            return ours;
        };
        let flag = if self.flagged {
            format!(" {FLAG}")
        } else {
            String::new()
        };
        format!("{ours} · paper {}{flag}", paper.text(&SIGNS))
    }
}

impl Tables {
    /// Every table of `run`'s report.
    fn of(run: &StoredRun) -> Tables {
        let source = Source::of(run);
        let calibration = source.calibration_table();
        let evaluation = source.evaluation_table(
            "Baseline",
            EstimatorKind::Baseline,
            EstimatorKind::Dcnet,
            true,
        );
        let beyond = (source.has(EstimatorKind::LeastSquares) || source.has(EstimatorKind::Floor))
            .then(|| {
                source.evaluation_table(
                    "floor (true terms)",
                    EstimatorKind::Floor,
                    EstimatorKind::LeastSquares,
                    false,
                )
            });
        let ensemble = source.has(EstimatorKind::DcnetEnsemble).then(|| {
            source.evaluation_table(
                "Baseline",
                EstimatorKind::Baseline,
                EstimatorKind::DcnetEnsemble,
                false,
            )
        });
        let efficiency = source
            .has(EstimatorKind::Bound)
            .then(|| source.efficiency_table());
        Tables {
            calibration,
            evaluation,
            beyond,
            ensemble,
            efficiency,
        }
    }

    /// The cells compared with a published value and those flagged, in every table.
    fn tally(&self) -> Tally {
        let tables = [&self.calibration, &self.evaluation]
            .into_iter()
            .chain(self.beyond.as_ref())
            .chain(self.ensemble.as_ref())
            .chain(self.efficiency.as_ref());
        tables.fold(Tally::default(), |sum, table| Tally {
            compared: sum.compared + table.tally.compared,
            flagged: sum.flagged + table.tally.flagged,
        })
    }
}

/// What the tables are built from: the run, its tolerance, and the error models, DVLs
/// and test trajectories that give their columns and rows.
struct Source<'a> {
    run: &'a StoredRun,
    tolerance: f64,
    models: Vec<ErrorModel>,
    dvls: Vec<String>,
    trajectories: Vec<String>,
}

/// A calibration row's layout: its label, the estimator of the first value column and
/// that of the error-model columns.
type CalibrationKinds = (String, Option<EstimatorKind>, Option<EstimatorKind>);

impl<'a> Source<'a> {
    /// The error models, DVLs and test trajectories of `run`.
    fn of(run: &'a StoredRun) -> Source<'a> {
        Source {
            run,
            tolerance: run.spec.report.tolerance_pct,
            models: crate::report::tables::models_in(run.calibration.iter().map(|r| r.error_model)),
            dvls: run.dvls(),
            trajectories: crate::first_seen(run.evaluation.iter().map(|r| r.trajectory.clone())),
        }
    }

    /// Whether the run's calibration holds estimator `kind`.
    fn has(&self, kind: EstimatorKind) -> bool {
        self.run.calibration.iter().any(|r| r.estimator == kind)
    }

    /// The published cell of a calibration or (with `trajectory`) an evaluation row.
    fn published(
        &self,
        dvl: &str,
        kind: EstimatorKind,
        model: Option<ErrorModel>,
        trajectory: Option<&str>,
    ) -> Option<&'a PublishedCell> {
        self.run
            .published
            .as_ref()
            .and_then(|p| p.find(dvl, kind, model, trajectory))
    }

    /// The value columns' headers: `first`, then each error model.
    fn columns(&self, first: &str) -> Vec<String> {
        std::iter::once(first.to_string())
            .chain(self.models.iter().map(ToString::to_string))
            .collect()
    }

    /// A row of `labels`: estimator `first` in the first value column and `per_model`
    /// with each error model in the others, each cell as `cell` finds it.
    fn row(
        &self,
        labels: Vec<String>,
        first: Option<EstimatorKind>,
        per_model: Option<EstimatorKind>,
        mut cell: impl FnMut(EstimatorKind, Option<ErrorModel>) -> Option<Cell>,
    ) -> Row {
        let mut cells = vec![first.and_then(|kind| cell(kind, None))];
        for model in &self.models {
            cells.push(per_model.and_then(|kind| cell(kind, Some(*model))));
        }
        Row { labels, cells }
    }

    /// Calibration, the paper's layout: DVL rows with the baseline and DCNet, then
    /// least squares and the floor.
    fn calibration_table(&self) -> ReportTable {
        let mut tally = Tally::default();
        let groups = self
            .dvls
            .iter()
            .map(|dvl| {
                self.calibration_kinds(dvl)
                    .into_iter()
                    .map(|(label, first, per_model)| {
                        self.row(vec![label], first, per_model, |kind, model| {
                            self.calibration_cell(dvl, kind, model, &mut tally)
                        })
                    })
                    .collect()
            })
            .collect();
        ReportTable {
            labels: vec!["DVL"],
            columns: self.columns("Baseline"),
            groups,
            tally,
        }
    }

    /// The calibration rows of `dvl`: the baseline and DCNet, then least squares and
    /// the floor where the run has them.
    fn calibration_kinds(&self, dvl: &str) -> Vec<CalibrationKinds> {
        let mut kinds = vec![(
            dvl.to_string(),
            Some(EstimatorKind::Baseline),
            Some(EstimatorKind::Dcnet),
        )];
        if self.has(EstimatorKind::DcnetEnsemble) {
            kinds.push((
                format!("{dvl} DCNet ensemble"),
                None,
                Some(EstimatorKind::DcnetEnsemble),
            ));
        }
        if self.has(EstimatorKind::LeastSquares) {
            kinds.push((
                format!("{dvl} least squares"),
                None,
                Some(EstimatorKind::LeastSquares),
            ));
        }
        for kind in [
            EstimatorKind::BeamWls,
            EstimatorKind::Floor,
            EstimatorKind::Bound,
        ] {
            if self.has(kind) {
                kinds.push((format!("{dvl} {}", kind.label()), Some(kind), None));
            }
        }
        kinds
    }

    /// Every estimator of each DVL, then the bound itself: the RMSE with the
    /// efficiency (bound / RMSE) in brackets, calibrating at the estimator's T_conv on
    /// the rest of the calibration trajectory, then on each test trajectory with the
    /// T_conv terms.
    fn efficiency_table(&self) -> ReportTable {
        let figure = |rmse_cm_s: f64, ci_cm_s: Option<f64>, efficiency: Option<f64>| Cell {
            ours: Figure {
                rmse_cm_s,
                ci_cm_s,
                detail: efficiency.map(Detail::Efficiency),
            },
            paper: None,
            flagged: false,
        };
        let groups = self
            .dvls
            .iter()
            .map(|dvl| {
                let series = crate::first_seen(
                    self.run
                        .calibration
                        .iter()
                        .filter(|r| r.dvl == *dvl && r.estimator != EstimatorKind::Floor)
                        .map(|r| (r.estimator, r.error_model)),
                );
                series
                    .into_iter()
                    .map(|(kind, model)| {
                        let label = kind.label_with(model);
                        let at_t_conv = self.at_t_conv(dvl, kind, model);
                        let mut cells = vec![
                            at_t_conv.map(|r| figure(r.rmse_cm_s, r.rmse_ci_cm_s, r.efficiency)),
                        ];
                        cells.extend(self.trajectories.iter().map(|trajectory| {
                            self.evaluated(dvl, trajectory, kind, model)
                                .map(|r| figure(r.rmse_cm_s, r.rmse_ci_cm_s, r.efficiency))
                        }));
                        let t_conv = at_t_conv.map_or(String::new(), |r| r.window_s.to_string());
                        Row {
                            labels: vec![dvl.clone(), label, t_conv],
                            cells,
                        }
                    })
                    .collect()
            })
            .collect();
        ReportTable {
            labels: vec!["DVL", "estimator", "T_conv s"],
            columns: std::iter::once(format!("{} rest", self.run.spec.calibration.trajectory))
                .chain(self.trajectories.iter().cloned())
                .collect(),
            groups,
            tally: Tally::default(),
        }
    }

    /// The calibration row at T_conv of `dvl`, `kind` and `model`.
    fn at_t_conv(
        &self,
        dvl: &str,
        kind: EstimatorKind,
        model: Option<ErrorModel>,
    ) -> Option<&'a CalibrationRow> {
        self.run
            .calibration
            .iter()
            .find(|r| r.is_t_conv && r.dvl == dvl && r.estimator == kind && r.error_model == model)
    }

    /// The evaluation row of `dvl` on `trajectory`, `kind` and `model`.
    fn evaluated(
        &self,
        dvl: &str,
        trajectory: &str,
        kind: EstimatorKind,
        model: Option<ErrorModel>,
    ) -> Option<&'a EvaluationRow> {
        self.run.evaluation.iter().find(|r| {
            r.dvl == dvl
                && r.trajectory == trajectory
                && r.estimator == kind
                && r.error_model == model
        })
    }

    /// The calibration cell at T_conv of `dvl`, `kind` and `model`, beside the
    /// published one.
    fn calibration_cell(
        &self,
        dvl: &str,
        kind: EstimatorKind,
        model: Option<ErrorModel>,
        tally: &mut Tally,
    ) -> Option<Cell> {
        self.at_t_conv(dvl, kind, model).map(|r| {
            let ours = Figure {
                rmse_cm_s: r.rmse_cm_s,
                ci_cm_s: r.rmse_ci_cm_s,
                detail: Some(Detail::TConv(r.window_s)),
            };
            let paper = self.published(dvl, kind, model, None);
            Cell::new(ours, paper, Phase::Calibration, self.tolerance, tally)
        })
    }

    /// Evaluation, the paper's layout: one DVL × trajectory row per cell pair, `first`
    /// in the first value column, `per_model` with each error model in the others,
    /// beside the published cells when `with_paper`.
    fn evaluation_table(
        &self,
        first_label: &str,
        first: EstimatorKind,
        per_model: EstimatorKind,
        with_paper: bool,
    ) -> ReportTable {
        let mut tally = Tally::default();
        let groups = self
            .dvls
            .iter()
            .map(|dvl| {
                self.trajectories
                    .iter()
                    .map(|trajectory| {
                        let labels = vec![dvl.clone(), trajectory.clone()];
                        self.row(labels, Some(first), Some(per_model), |kind, model| {
                            self.evaluation_cell(
                                dvl, trajectory, kind, model, with_paper, &mut tally,
                            )
                        })
                    })
                    .collect()
            })
            .collect();
        ReportTable {
            labels: vec!["DVL", "trajectory"],
            columns: self.columns(first_label),
            groups,
            tally,
        }
    }

    /// The evaluation cell of `dvl` on `trajectory`, `kind` and `model`, beside the
    /// published one when `with_paper`.
    fn evaluation_cell(
        &self,
        dvl: &str,
        trajectory: &str,
        kind: EstimatorKind,
        model: Option<ErrorModel>,
        with_paper: bool,
        tally: &mut Tally,
    ) -> Option<Cell> {
        self.evaluated(dvl, trajectory, kind, model).map(|r| {
            let ours = Figure {
                rmse_cm_s: r.rmse_cm_s,
                ci_cm_s: r.rmse_ci_cm_s,
                detail: r
                    .improvement_pct
                    .filter(|_| kind != EstimatorKind::Baseline)
                    .map(Detail::Improvement),
            };
            let paper = self
                .published(dvl, kind, model, Some(trajectory))
                .filter(|_| with_paper);
            Cell::new(ours, paper, Phase::Evaluation, self.tolerance, tally)
        })
    }
}

/// The report as Markdown.
fn render(run: &StoredRun, tables: &Tables, figures: &[Written]) -> String {
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
        markdown_table(&tables.calibration)
    );
    let _ = writeln!(out, "## Evaluation with the T_conv terms\n");
    let _ = writeln!(out, "{}\n", markdown_table(&tables.evaluation));
    if let Some(beyond) = &tables.beyond {
        let _ = writeln!(
            out,
            "Beyond the paper: least squares on the same data, and the floor.\n\n{}\n",
            markdown_table(beyond)
        );
    }
    if let Some(ensemble) = &tables.ensemble {
        let _ = writeln!(
            out,
            "The DCNet ensemble: the mean of the {} replicates' terms in each calibration window.\n\n{}\n",
            spec.training.replicates,
            markdown_table(ensemble)
        );
    }
    if let Some(efficiency) = &tables.efficiency {
        let _ = writeln!(out, "## Against the information bound\n");
        let _ = writeln!(
            out,
            "The bound is the mean RMSE of an efficient estimator of the DVL's scale and bias from the calibration window (the Cramér–Rao bound on the terms, propagated to the corrected velocity): no unbiased calibration from that much data does better on average. The floor is the limit with perfect terms; the bound, the limit with w seconds of data. In brackets, each estimator's efficiency: the bound at its T_conv over its RMSE.\n\n{}\n",
            markdown_table(efficiency)
        );
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

/// What a DCNet cell holds when there are several replicates, for the captions.
fn replicates_note(replicates: usize) -> Option<String> {
    (replicates > 1).then(|| {
        format!(
            "DCNet cells give the mean over {replicates} replicates (models trained from independent seeds) ± the half-width of its 95 % confidence interval across them (Student t); their T_conv is that of the mean curve in calibration, the mean of the replicates' in evaluation."
        )
    })
}

/// A report table as Markdown, `—` where a cell has no value.
fn markdown_table(table: &ReportTable) -> Table {
    let mut markdown = Table::new();
    markdown.load_preset(ASCII_MARKDOWN);
    let header: Vec<String> = table
        .labels
        .iter()
        .map(ToString::to_string)
        .chain(table.columns.iter().cloned())
        .collect();
    markdown.set_header(header);
    for row in table.groups.iter().flatten() {
        let cells = row.cells.iter().map(|cell| {
            cell.as_ref()
                .map_or_else(|| "—".to_string(), Cell::markdown)
        });
        markdown.add_row(row.labels.iter().cloned().chain(cells).collect::<Vec<_>>());
    }
    markdown
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
        "stopped by",
        "best epoch",
        "best validation loss (cm/s)²",
        "training s",
    ]);
    let mut models: Vec<(ErrorModel, Option<usize>)> = run
        .training
        .iter()
        .map(|e| (e.error_model, e.replicate))
        .collect();
    models.dedup();
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
    pathdiff::diff_paths(absolute(file), absolute(folder))
        .unwrap_or_else(|| file.to_path_buf())
        .to_string_lossy()
        .replace(' ', "%20")
}
