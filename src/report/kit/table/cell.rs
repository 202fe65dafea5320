//! One value cell of the report's tables. In: our RMSE with what goes beside it, and the
//! published cell of the same place if there is one. Out: a [`Cell`] that knows whether
//! the two disagree beyond the spec's tolerance, and an [`RmseValue`] that either
//! renderer writes with its own [`Signs`].

use crate::spec::published::PublishedCell;
use crate::vocab::Phase;

/// Counts the cells compared with a published value and those flagged.
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub(crate) struct Tally {
    pub(crate) compared: usize,
    pub(crate) flagged: usize,
}

/// One value cell: our value, the published one beside it, and whether they disagree.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    pub(crate) ours: RmseValue,
    pub(crate) paper: Option<RmseValue>,
    pub(crate) flagged: bool,
}

/// An RMSE (cm/s) and what the table sets beside it.
#[derive(Debug, Clone, PartialEq)]
pub struct RmseValue {
    pub(crate) rmse_cm_s: f64,
    /// Half-width of the 95 % confidence interval over DCNet replicates.
    pub(crate) ci_cm_s: Option<f64>,
    pub(crate) detail: Option<Detail>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Detail {
    TConv(f64),
    Improvement(f64),
    /// The bound over the RMSE.
    Efficiency(f64),
}

/// How a rendering writes the signs of an [`RmseValue`].
pub struct Signs {
    pub(crate) percent: &'static str,
    pub(crate) minus: &'static str,
    pub(crate) plus_minus: &'static str,
}

impl Tally {
    /// Of `cells`: those with a published value, and those flagged.
    pub(crate) fn of<'a>(cells: impl IntoIterator<Item = &'a Cell>) -> Tally {
        cells.into_iter().filter(|cell| cell.paper.is_some()).fold(
            Tally::default(),
            |tally, cell| Tally {
                compared: tally.compared + 1,
                flagged: tally.flagged + usize::from(cell.flagged),
            },
        )
    }
}

impl RmseValue {
    /// `5.93 (100)` with T_conv, `0.86 (+12 %)` with the improvement, `0.17 (94 %)`
    /// with the efficiency, `0.74` alone; `0.09 ± 0.01 (20)` with a confidence interval.
    pub(crate) fn text(&self, signs: &Signs) -> String {
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
    /// Our value beside the published cell: flagged when the RMSE is more than
    /// `tolerance_pct` off, or the calibration's T_conv differs.
    pub(crate) fn new(
        ours: RmseValue,
        published: Option<&PublishedCell>,
        phase: Phase,
        tolerance_pct: f64,
    ) -> Cell {
        let paper = published.map(|cell| RmseValue {
            rmse_cm_s: cell.rmse_cm_s,
            ci_cm_s: None,
            detail: match phase {
                Phase::Calibration => cell.t_conv_s.map(Detail::TConv),
                Phase::Evaluation => cell.improvement_pct.map(Detail::Improvement),
                Phase::HeldOut => None,
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
        Cell {
            ours,
            paper,
            flagged,
        }
    }

    /// Our value alone, compared with nothing.
    pub(crate) fn alone(ours: RmseValue) -> Cell {
        Cell {
            ours,
            paper: None,
            flagged: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vocab::{ErrorModel, EstimatorKind};

    const SIGNS: Signs = Signs {
        percent: " %",
        minus: "-",
        plus_minus: " ± ",
    };

    fn value(rmse_cm_s: f64, detail: Option<Detail>) -> RmseValue {
        RmseValue {
            rmse_cm_s,
            ci_cm_s: None,
            detail,
        }
    }

    fn published(
        rmse_cm_s: f64,
        t_conv_s: Option<f64>,
        improvement_pct: Option<f64>,
    ) -> PublishedCell {
        PublishedCell {
            dvl: "DVL1".into(),
            estimator: EstimatorKind::Dcnet,
            error_model: Some(ErrorModel::Em5),
            trajectory: None,
            rmse_cm_s,
            t_conv_s,
            improvement_pct,
        }
    }

    #[test]
    fn a_value_reads_with_its_detail_in_brackets() {
        assert_eq!(
            value(5.934, Some(Detail::TConv(100.0))).text(&SIGNS),
            "5.93 (100)"
        );
        assert_eq!(
            value(0.86, Some(Detail::Improvement(12.4))).text(&SIGNS),
            "0.86 (+12 %)"
        );
        assert_eq!(
            value(6.03, Some(Detail::Improvement(-1.2))).text(&SIGNS),
            "6.03 (-1 %)"
        );
        assert_eq!(
            value(0.17, Some(Detail::Efficiency(0.94))).text(&SIGNS),
            "0.17 (94 %)"
        );
        assert_eq!(value(0.74, None).text(&SIGNS), "0.74");
        let with_ci = RmseValue {
            ci_cm_s: Some(0.012),
            ..value(0.09, Some(Detail::TConv(20.0)))
        };
        assert_eq!(with_ci.text(&SIGNS), "0.09 ± 0.01 (20)");
        let latex = Signs {
            percent: "\\,\\%",
            minus: "$-$",
            plus_minus: "\\,$\\pm$\\,",
        };
        assert_eq!(
            value(6.03, Some(Detail::Improvement(-1.2))).text(&latex),
            "6.03 ($-$1\\,\\%)"
        );
    }

    #[test]
    fn a_cell_more_than_the_tolerance_off_the_published_value_is_flagged() {
        let mut cells = Vec::new();
        // 10 % of 1.00 is 0.10: 1.09 is within it, 1.11 beyond, on either side.
        let paper = published(1.0, None, Some(20.0));
        let mut cell = |rmse| {
            let cell = Cell::new(value(rmse, None), Some(&paper), Phase::Evaluation, 10.0);
            cells.push(cell.clone());
            cell
        };
        assert!(!cell(1.09).flagged);
        assert!(cell(1.11).flagged);
        assert!(cell(0.89).flagged);
        let within = cell(0.91);
        assert!(!within.flagged);
        assert_eq!(
            within.paper,
            Some(value(1.0, Some(Detail::Improvement(20.0))))
        );
        assert_eq!(
            Tally::of(&cells),
            Tally {
                compared: 4,
                flagged: 2
            }
        );
    }

    #[test]
    fn another_t_conv_is_flagged_in_calibration_only() {
        let paper = published(5.0, Some(100.0), Some(3.0));
        let same = Cell::new(
            value(5.0, Some(Detail::TConv(100.0))),
            Some(&paper),
            Phase::Calibration,
            10.0,
        );
        assert!(!same.flagged);
        assert_eq!(same.paper, Some(value(5.0, Some(Detail::TConv(100.0)))));
        let other = Cell::new(
            value(5.0, Some(Detail::TConv(80.0))),
            Some(&paper),
            Phase::Calibration,
            10.0,
        );
        assert!(other.flagged);
        // A published cell without T_conv leaves the window untested.
        let untimed = published(5.0, None, None);
        let cell = Cell::new(
            value(5.0, Some(Detail::TConv(80.0))),
            Some(&untimed),
            Phase::Calibration,
            10.0,
        );
        assert!(!cell.flagged);
        assert_eq!(cell.paper, Some(value(5.0, None)));
        assert_eq!(
            Tally::of([&same, &other, &cell]),
            Tally {
                compared: 3,
                flagged: 1
            }
        );
    }

    #[test]
    fn a_cell_without_a_published_value_is_neither_compared_nor_flagged() {
        let cell = Cell::new(
            value(9.0, Some(Detail::TConv(20.0))),
            None,
            Phase::Calibration,
            10.0,
        );
        assert_eq!(cell, Cell::alone(value(9.0, Some(Detail::TConv(20.0)))));
        assert_eq!(Tally::of([&cell]), Tally::default());
    }
}
