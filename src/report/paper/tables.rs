//! The paper's tables of a run, built once for both renderings. In: the run's
//! calibration and evaluation rows and the published values it names. Out:
//! [`ReportTables`], the paper's two tables in its layout with our value beside the
//! published one in every cell and cells off by more than the spec's tolerance flagged,
//! then the tables of our extra estimators and the bound.

use super::source::TableSource;
use crate::report::kit::table::{Table, Tally};
use crate::results::read::StoredRun;
use crate::vocab::EstimatorKind;

/// The report's tables, each cell computed once for both renderings.
pub struct ReportTables {
    /// Calibration at T_conv: DVL rows with the baseline and DCNet, then least squares
    /// and the floor.
    pub(crate) calibration: Table,
    /// Evaluation with the T_conv terms: DVL × trajectory rows, baseline and DCNet.
    pub(crate) evaluation: Table,
    /// The same for the floor and least squares, when the run has either.
    pub(crate) beyond: Option<Table>,
    /// The same for the ensemble of DCNet replicates, when the run has several.
    pub(crate) ensemble: Option<Table>,
    /// Every estimator against the information bound, when the run has one.
    pub(crate) efficiency: Option<Table>,
}

impl ReportTables {
    /// Every table of `run`'s report.
    pub(crate) fn of(run: &StoredRun) -> ReportTables {
        let source = TableSource::of(run);
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
        ReportTables {
            calibration,
            evaluation,
            beyond,
            ensemble,
            efficiency,
        }
    }

    /// The cells compared with a published value and those flagged, in every table.
    pub(crate) fn tally(&self) -> Tally {
        let tables = [&self.calibration, &self.evaluation]
            .into_iter()
            .chain(self.beyond.as_ref())
            .chain(self.ensemble.as_ref())
            .chain(self.efficiency.as_ref());
        tables.fold(Tally::default(), |sum, table| {
            let tally = table.tally();
            Tally {
                compared: sum.compared + tally.compared,
                flagged: sum.flagged + tally.flagged,
            }
        })
    }
}

/// What a DCNet cell holds when there are several replicates, for the captions.
pub(crate) fn replicates_note(replicates: usize) -> Option<String> {
    (replicates > 1).then(|| {
        format!(
            "DCNet cells give the mean over {replicates} replicates (models trained from independent seeds) ± the half-width of its 95 % confidence interval across them (Student t); their T_conv is that of the mean curve in calibration, the mean of the replicates' in evaluation."
        )
    })
}
