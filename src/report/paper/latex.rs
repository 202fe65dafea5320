//! `results/<name>/report.tex` of a paper run: the tables of `report.md` as booktabs
//! tables, for a paper to `\input`, set by the kit ([`latex`](crate::report::kit::latex)).
//! In: the run's [`ReportTables`], built once for both renderings. Out: table
//! environments only, no preamble; a comment on top names the one package they need
//! (booktabs). Each DVL's row holds our values, the row below it the published ones in
//! italics; a flagged cell carries a dagger explained under its table.

use super::tables::{ReportTables, replicates_note};
use crate::report::kit::latex::{escape, label, sections, table};
use crate::report::kit::table::Table;
use crate::results::read::StoredRun;
use std::fmt::Write;

/// The tables as LaTeX.
pub(crate) fn render(run: &StoredRun, tables: &ReportTables) -> String {
    let mut out = String::new();
    header(&mut out, &run.spec.name);
    let captions = Captions::of(run);
    let label = label(&run.spec.name);
    let tag = |table: &str| format!("tab:{label}-{table}");
    let calibration_note =
        captions.note(&tables.calibration, ", or another T\\textsubscript{conv}");
    table(
        &mut out,
        &tables.calibration,
        &captions.calibration(&tables.calibration),
        &tag("calibration"),
        calibration_note.as_slice(),
    );
    table(
        &mut out,
        &tables.evaluation,
        &captions.evaluation(&tables.evaluation),
        &tag("evaluation"),
        captions.note(&tables.evaluation, "").as_slice(),
    );
    if let Some(beyond) = &tables.beyond {
        table(&mut out, beyond, &captions.beyond(), &tag("beyond"), &[]);
    }
    if let Some(ensemble) = &tables.ensemble {
        table(
            &mut out,
            ensemble,
            &captions.ensemble(),
            &tag("ensemble"),
            &[],
        );
    }
    if let Some(efficiency) = &tables.efficiency {
        table(&mut out, efficiency, &captions.bound(), &tag("bound"), &[]);
    }
    let timing = super::calibration_time::sections(run);
    out.push_str(&sections(&timing, &format!("{label}-calibration-time")));
    out
}

/// The comment on top: where the tables come from, the package they need, and how
/// they sit on the page.
fn header(out: &mut String, name: &str) {
    let _ = writeln!(
        out,
        "% The tables of report.md ({}), written by dcnet-exp {}.",
        name,
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(
        out,
        "% \\input{{report.tex}} in a document that loads booktabs: \\usepackage{{booktabs}}."
    );
    let _ = writeln!(
        out,
        "% Each table is centred on the page, into the margins where it is wider than the text;\n% in a two-column layout, make it a table* or scale its tabular with \\resizebox."
    );
}

/// The caption of each table, and the note under those with published values: what
/// they say of the run.
struct Captions<'a> {
    run: &'a StoredRun,
    /// The experiment's name, escaped.
    name: String,
    /// Monte Carlo runs per value.
    runs: usize,
    /// In every caption when DCNet has replicates.
    replicates: String,
}

impl<'a> Captions<'a> {
    fn of(run: &'a StoredRun) -> Self {
        let spec = &run.spec;
        Captions {
            run,
            name: escape(&spec.name),
            runs: spec.calibration.monte_carlo_runs,
            replicates: replicates_note(spec.training.replicates)
                .map(|note| format!(" {}", escape(&note).replace('±', "$\\pm$")))
                .unwrap_or_default(),
        }
    }

    /// In the caption of a table with published values.
    fn below(table: &Table) -> &'static str {
        if table.tally().compared > 0 {
            "; the published value in italics in the row below ours"
        } else {
            ""
        }
    }

    /// Under a table with published values: what its daggers mean, and their count.
    fn note(&self, table: &Table, what: &str) -> Option<String> {
        let spec = &self.run.spec;
        let published = self.run.published.as_ref()?;
        let tally = table.tally();
        (tally.compared > 0).then(|| {
            format!(
                "\\dag{{}} flags an RMSE more than {}\\,\\% off the published one{what} ({} of {} cells). Published values: {}.",
                spec.report.tolerance_pct,
                tally.flagged,
                tally.compared,
                escape(&published.source)
            )
        })
    }

    fn calibration(&self, table: &Table) -> String {
        let Captions {
            run,
            name,
            runs,
            replicates,
        } = self;
        format!(
            "{name}: calibration on {}. RMSE in cm/s at T\\textsubscript{{conv}}, mean over {runs} Monte Carlo runs, T\\textsubscript{{conv}} in s in brackets{}. The floor corrects with the true terms, which no estimator can beat; the bound is the best mean RMSE of any unbiased estimator from the window's data.{replicates}",
            escape(&run.spec.calibration.trajectory),
            Self::below(table)
        )
    }

    fn evaluation(&self, table: &Table) -> String {
        let Captions {
            name,
            runs,
            replicates,
            ..
        } = self;
        format!(
            "{name}: evaluation with the T\\textsubscript{{conv}} terms. RMSE in cm/s, mean over {runs} Monte Carlo runs, improvement over the baseline in brackets{}.{replicates}",
            Self::below(table)
        )
    }

    fn beyond(&self) -> String {
        let Captions { name, runs, .. } = self;
        format!(
            "{name}: beyond the paper, least squares on the same data and the floor. RMSE in cm/s, mean over {runs} Monte Carlo runs, improvement over the baseline in brackets."
        )
    }

    fn ensemble(&self) -> String {
        let Captions {
            run, name, runs, ..
        } = self;
        format!(
            "{name}: the DCNet ensemble, the mean of the {} replicates' terms in each calibration window. RMSE in cm/s, mean over {runs} Monte Carlo runs, improvement over the baseline in brackets.",
            run.spec.training.replicates
        )
    }

    /// The caption of the table against the information bound.
    fn bound(&self) -> String {
        let Captions {
            run, name, runs, ..
        } = self;
        format!(
            "{name}: every estimator against the information bound, the mean RMSE of an efficient estimator of the DVL's scale and bias from the calibration window. RMSE in cm/s, mean over {runs} Monte Carlo runs, efficiency (bound / RMSE) in brackets; calibration at each estimator's T\\textsubscript{{conv}} on the rest of {}, evaluation with the T\\textsubscript{{conv}} terms.",
            escape(&run.spec.calibration.trajectory)
        )
    }
}
