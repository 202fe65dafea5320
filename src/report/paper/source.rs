//! Where each cell of the report's tables comes from. In: a [`StoredRun`]. Out: each
//! [`Table`], its rows in the paper's layout: a DVL's estimators down, error
//! models across, every cell found once among the run's calibration rows at T_conv or
//! its evaluation rows, and set beside its published value.

use crate::evaluate::{CalibrationRow, EvaluationRow};
use crate::report::kit::table::{Cell, Detail, Entry, RmseValue, Table};
use crate::results::read::StoredRun;
use crate::spec::published::PublishedCell;
use crate::vocab::{ErrorModel, EstimatorKind, Phase};

/// What the tables are built from: the run, its tolerance, and the error models, DVLs
/// and test trajectories that give their columns and rows.
pub(super) struct TableSource<'a> {
    run: &'a StoredRun,
    tolerance: f64,
    models: Vec<ErrorModel>,
    dvls: Vec<String>,
    trajectories: Vec<String>,
}

/// A calibration row's layout: its label, the estimator of the first value column and
/// that of the error-model columns.
type CalibrationKinds = (String, Option<EstimatorKind>, Option<EstimatorKind>);

impl<'a> TableSource<'a> {
    /// The error models, DVLs and test trajectories of `run`.
    pub(super) fn of(run: &'a StoredRun) -> TableSource<'a> {
        TableSource {
            run,
            tolerance: run.spec.report.tolerance_pct,
            models: crate::report::paper::printed::models_in(
                run.calibration.iter().map(|r| r.error_model),
            ),
            dvls: run.dvls(),
            trajectories: crate::first_seen(run.evaluation.iter().map(|r| r.trajectory.clone())),
        }
    }

    /// Whether the run's calibration holds estimator `kind`.
    pub(super) fn has(&self, kind: EstimatorKind) -> bool {
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

    /// The header of `labels` columns, then the value columns: `first`, then each
    /// error model.
    fn header(&self, labels: &[&str], first: &str) -> Vec<String> {
        labels
            .iter()
            .map(ToString::to_string)
            .chain(std::iter::once(first.to_string()))
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
    ) -> Vec<Entry> {
        let mut cells = vec![first.and_then(|kind| cell(kind, None))];
        for model in &self.models {
            cells.push(per_model.and_then(|kind| cell(kind, Some(*model))));
        }
        labelled(labels, cells)
    }

    /// Calibration, the paper's layout: DVL rows with the baseline and DCNet, then
    /// least squares and the floor.
    pub(super) fn calibration_table(&self) -> Table {
        let groups = self
            .dvls
            .iter()
            .map(|dvl| {
                self.calibration_kinds(dvl)
                    .into_iter()
                    .map(|(label, first, per_model)| {
                        self.row(vec![label], first, per_model, |kind, model| {
                            self.calibration_cell(dvl, kind, model)
                        })
                    })
                    .collect()
            })
            .collect();
        Table {
            header: self.header(&["DVL"], "Baseline"),
            label_columns: 1,
            groups,
            notes: Vec::new(),
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
    pub(super) fn efficiency_table(&self) -> Table {
        let cell = |rmse_cm_s: f64, ci_cm_s: Option<f64>, efficiency: Option<f64>| {
            Cell::alone(RmseValue {
                rmse_cm_s,
                ci_cm_s,
                detail: efficiency.map(Detail::Efficiency),
            })
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
                            at_t_conv.map(|r| cell(r.rmse_cm_s, r.rmse_ci_cm_s, r.efficiency)),
                        ];
                        cells.extend(self.trajectories.iter().map(|trajectory| {
                            self.evaluated(dvl, trajectory, kind, model)
                                .map(|r| cell(r.rmse_cm_s, r.rmse_ci_cm_s, r.efficiency))
                        }));
                        let t_conv = at_t_conv.map_or(String::new(), |r| r.window_s.to_string());
                        labelled(vec![dvl.clone(), label, t_conv], cells)
                    })
                    .collect()
            })
            .collect();
        let labels = ["DVL", "estimator", "T_conv s"].map(String::from);
        let rest = format!("{} rest", self.run.spec.calibration.trajectory);
        Table {
            header: labels
                .into_iter()
                .chain(std::iter::once(rest))
                .chain(self.trajectories.iter().cloned())
                .collect(),
            label_columns: 3,
            groups,
            notes: Vec::new(),
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
    ) -> Option<Cell> {
        self.at_t_conv(dvl, kind, model).map(|r| {
            let ours = RmseValue {
                rmse_cm_s: r.rmse_cm_s,
                ci_cm_s: r.rmse_ci_cm_s,
                detail: Some(Detail::TConv(r.window_s)),
            };
            let paper = self.published(dvl, kind, model, None);
            Cell::new(ours, paper, Phase::Calibration, self.tolerance)
        })
    }

    /// Evaluation, the paper's layout: one DVL × trajectory row per cell pair, `first`
    /// in the first value column, `per_model` with each error model in the others,
    /// beside the published cells when `with_paper`.
    pub(super) fn evaluation_table(
        &self,
        first_label: &str,
        first: EstimatorKind,
        per_model: EstimatorKind,
        with_paper: bool,
    ) -> Table {
        let groups = self
            .dvls
            .iter()
            .map(|dvl| {
                self.trajectories
                    .iter()
                    .map(|trajectory| {
                        let labels = vec![dvl.clone(), trajectory.clone()];
                        self.row(labels, Some(first), Some(per_model), |kind, model| {
                            self.evaluation_cell(dvl, trajectory, kind, model, with_paper)
                        })
                    })
                    .collect()
            })
            .collect();
        Table {
            header: self.header(&["DVL", "trajectory"], first_label),
            label_columns: 2,
            groups,
            notes: Vec::new(),
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
    ) -> Option<Cell> {
        self.evaluated(dvl, trajectory, kind, model).map(|r| {
            let ours = RmseValue {
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
            Cell::new(ours, paper, Phase::Evaluation, self.tolerance)
        })
    }
}

/// A row of `labels`, then `cells`, missing where there is none.
fn labelled(labels: Vec<String>, cells: Vec<Option<Cell>>) -> Vec<Entry> {
    let labels = labels.into_iter().map(Entry::Text);
    let cells = cells
        .into_iter()
        .map(|cell| cell.map_or(Entry::Missing, Entry::Published));
    labels.chain(cells).collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::report::kit::table::Tally;
    use crate::report::paper::ReportTables;
    use crate::results::Manifest;
    use crate::spec::file::SpecFile;
    use crate::spec::published::Published;
    use crate::vocab::ErrorModel::Em5;
    use EstimatorKind::{Baseline, Bound, Dcnet, Floor};

    fn calibration(
        dvl: &str,
        estimator: EstimatorKind,
        error_model: Option<ErrorModel>,
        window_s: f64,
        rmse_cm_s: f64,
        is_t_conv: bool,
    ) -> CalibrationRow {
        CalibrationRow {
            dvl: dvl.into(),
            estimator,
            error_model,
            window_s,
            rmse_cm_s,
            rmse_std_cm_s: 0.1,
            rmse_ci_cm_s: None,
            is_t_conv,
            efficiency: None,
        }
    }

    pub(crate) fn evaluation(
        estimator: EstimatorKind,
        error_model: Option<ErrorModel>,
        rmse_cm_s: f64,
        improvement_pct: Option<f64>,
    ) -> EvaluationRow {
        EvaluationRow {
            dvl: "DVL1".into(),
            estimator,
            error_model,
            trajectory: "S3".into(),
            t_conv_s: 20.0,
            rmse_cm_s,
            rmse_std_cm_s: 0.1,
            rmse_ci_cm_s: None,
            improvement_pct,
            efficiency: None,
        }
    }

    fn published(
        estimator: EstimatorKind,
        error_model: Option<ErrorModel>,
        trajectory: Option<&str>,
        rmse_cm_s: f64,
        t_conv_s: Option<f64>,
        improvement_pct: Option<f64>,
    ) -> PublishedCell {
        PublishedCell {
            dvl: "DVL1".into(),
            estimator,
            error_model,
            trajectory: trajectory.map(String::from),
            rmse_cm_s,
            t_conv_s,
            improvement_pct,
        }
    }

    /// quick.toml's spec (DVL1 and DVL2, calibration on SCal) at a 10 % tolerance, with
    /// DVL1's rows alone: the baseline and DCNet EM5 at T_conv and beside them the
    /// published cells, and the floor and the bound without any.
    pub(crate) fn run() -> StoredRun {
        let mut spec: SpecFile = toml::from_str(include_str!("../../../experiments/quick.toml"))
            .expect("quick.toml reads as a spec");
        spec.report.tolerance_pct = 10.0;
        let manifest = Manifest {
            name: "quick".into(),
            spec_sha256: String::new(),
            git_commit: String::new(),
            crate_version: String::new(),
            started_at: String::new(),
            finished_at: String::new(),
            threads: 1,
            backend: String::new(),
            host: String::new(),
            instruction_set: String::new(),
            data_files: Vec::new(),
            stage_seconds: Default::default(),
            results_key: String::new(),
            files_sha256: Default::default(),
            spec_file: String::new(),
        };
        let mut baseline_at_100 = calibration("DVL1", Baseline, None, 100.0, 5.92, true);
        baseline_at_100.efficiency = Some(0.8);
        StoredRun {
            folder: "results/quick".into(),
            spec,
            manifest,
            published: Some(Published {
                source: "the paper".into(),
                calibration: vec![
                    // 5.92 against 5.5: 7.6 % off, within the tolerance.
                    published(Baseline, None, None, 5.5, Some(100.0), None),
                    // The same RMSE at another T_conv.
                    published(Dcnet, Some(Em5), None, 5.0, Some(100.0), None),
                ],
                evaluation: vec![
                    published(Baseline, None, Some("S3"), 6.0, None, None),
                    // 4.0 against 5.0: 20 % off.
                    published(Dcnet, Some(Em5), Some("S3"), 5.0, None, Some(12.0)),
                ],
            }),
            runs: Vec::new(),
            held_out: Vec::new(),
            calibration_time: Vec::new(),
            terms_in_time: Vec::new(),
            calibration: vec![
                calibration("DVL1", Baseline, None, 20.0, 7.0, false),
                baseline_at_100,
                calibration("DVL1", Dcnet, Some(Em5), 20.0, 5.0, true),
                calibration("DVL1", Dcnet, Some(Em5), 100.0, 4.5, false),
                calibration("DVL1", Floor, None, 20.0, 3.0, true),
                calibration("DVL1", Bound, None, 100.0, 4.0, true),
            ],
            evaluation: vec![
                evaluation(Baseline, None, 6.1, Some(0.0)),
                evaluation(Dcnet, Some(Em5), 4.0, Some(34.4)),
            ],
            training: Vec::new(),
            trajectories: Vec::new(),
        }
    }

    fn texts(table: &Table) -> Vec<Vec<String>> {
        const SIGNS: crate::report::kit::table::Signs = crate::report::kit::table::Signs {
            percent: " %",
            minus: "-",
            plus_minus: " ± ",
        };
        let text = |value: &RmseValue| value.text(&SIGNS);
        table
            .groups
            .iter()
            .flatten()
            .map(|row| {
                row.iter()
                    .map(|entry| match entry {
                        Entry::Text(label) => label.clone(),
                        Entry::Published(cell) => {
                            let paper = cell.paper.as_ref().map(text);
                            format!(
                                "{}{}{}",
                                text(&cell.ours),
                                paper.map_or(String::new(), |p| format!(" | {p}")),
                                if cell.flagged { " !" } else { "" }
                            )
                        }
                        _ => "—".into(),
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn the_calibration_table_sets_each_t_conv_cell_beside_the_published_one() {
        let tables = ReportTables::of(&run());
        let table = &tables.calibration;
        assert_eq!(table.header[..table.label_columns], ["DVL"]);
        assert_eq!(table.header[table.label_columns..], ["Baseline", "EM5"]);
        assert_eq!(
            texts(table),
            [
                // The T_conv rows only; DCNet's is flagged for its other T_conv.
                vec![
                    "DVL1",
                    "5.92 (100) | 5.50 (100)",
                    "5.00 (20) | 5.00 (100) !"
                ],
                vec!["DVL1 floor (true terms)", "3.00 (20)", "—"],
                vec!["DVL1 information bound", "4.00 (100)", "—"],
                // DVL2 has no rows: the rows the run has, their cells empty.
                vec!["DVL2", "—", "—"],
                vec!["DVL2 floor (true terms)", "—", "—"],
                vec!["DVL2 information bound", "—", "—"],
            ]
        );
        assert_eq!(
            table.tally(),
            Tally {
                compared: 2,
                flagged: 1
            }
        );
    }

    #[test]
    fn the_evaluation_table_flags_an_rmse_beyond_the_tolerance() {
        let tables = ReportTables::of(&run());
        let table = &tables.evaluation;
        assert_eq!(table.header[..table.label_columns], ["DVL", "trajectory"]);
        assert_eq!(
            texts(table),
            [
                // The baseline's improvement over itself is left out.
                vec!["DVL1", "S3", "6.10 | 6.00", "4.00 (+34 %) | 5.00 (+12 %) !"],
                vec!["DVL2", "S3", "—", "—"],
            ]
        );
        assert_eq!(
            tables.tally(),
            Tally {
                compared: 4,
                flagged: 2
            }
        );
    }

    #[test]
    fn the_extra_tables_follow_the_estimators_the_run_has() {
        let tables = ReportTables::of(&run());
        // The floor without least squares: the floor's column, no published values.
        let beyond = tables.beyond.as_ref().expect("the run has the floor");
        assert_eq!(
            beyond.header[beyond.label_columns..],
            ["floor (true terms)", "EM5"]
        );
        assert_eq!(beyond.tally(), Tally::default());
        assert!(tables.ensemble.is_none());
        let efficiency = tables.efficiency.as_ref().expect("the run has the bound");
        assert_eq!(
            efficiency.header[..efficiency.label_columns],
            ["DVL", "estimator", "T_conv s"]
        );
        assert_eq!(
            efficiency.header[efficiency.label_columns..],
            ["SCal rest", "S3"]
        );
        assert_eq!(
            texts(efficiency),
            [
                vec!["DVL1", "baseline", "100", "5.92 (80 %)", "6.10"],
                vec!["DVL1", "DCNet EM5", "20", "5.00", "4.00"],
                vec!["DVL1", "information bound", "100", "4.00", "—"],
            ]
        );
    }
}
