//! The comparison as Markdown. In: the two [`StoredRun`]s. Out: the text `compare`
//! prints and writes: both folders named, the spec keys that differ, every calibration
//! and evaluation cell with A, B, B − A and z, marked ⚠ beyond [`STANDARD_ERRORS`]
//! combined standard errors, the training times and wall time per stage side by side,
//! and a count of the marked cells.

use super::difference::{Difference, FLOAT_NOISE, Mean, STANDARD_ERRORS};
use super::pairs::pair;
use super::spec_keys::spec_differences;
use crate::evaluate::{CalibrationRow, EvaluationRow};
use crate::results::read::StoredRun;
use crate::vocab::{ErrorModel, EstimatorKind};
use comfy_table::{Table, presets::ASCII_MARKDOWN};
use std::fmt::Write;

/// Marks a cell whose difference is beyond [`STANDARD_ERRORS`] combined standard errors.
const FLAG: &str = "⚠";

/// What the cells came to.
#[derive(Debug, Default, Clone, Copy, PartialEq)]
struct Tally {
    /// Cells in both folders with a standard error on both sides.
    tested: usize,
    /// Of those, the cells marked.
    beyond: usize,
    /// Cells in both folders with a single run on a side.
    untested: usize,
    /// Cells in one folder only.
    one_sided: usize,
}

impl Tally {
    /// The closing line: "N of M cells differ beyond 2 combined standard errors".
    fn summary(&self) -> String {
        let mut line = format!(
            "{} of {} cells differ beyond {STANDARD_ERRORS} combined standard errors",
            self.beyond, self.tested
        );
        if self.one_sided > 0 {
            let _ = write!(line, "; {} in one folder only", cells(self.one_sided));
        }
        if self.untested > 0 {
            let _ = write!(
                line,
                "; {} not tested (a single Monte Carlo run gives no standard error)",
                cells(self.untested)
            );
        }
        line
    }
}

/// "1 cell", "3 cells".
fn cells(count: usize) -> String {
    if count == 1 {
        "1 cell".into()
    } else {
        format!("{count} cells")
    }
}

/// The A, B, B − A, z and mark columns of one cell, counted into `tally`.
fn rmse_columns(a: Option<Mean>, b: Option<Mean>, tally: &mut Tally) -> [String; 5] {
    let value = |mean: Option<Mean>| mean.map_or("—".into(), |m| format!("{:.4}", m.rmse_cm_s));
    let (difference, z, mark) = match (a, b) {
        (Some(a), Some(b)) => {
            let difference = Difference::between(a, b);
            let mark = match difference.is_beyond() {
                Some(beyond) => {
                    tally.tested += 1;
                    tally.beyond += usize::from(beyond);
                    if beyond { FLAG } else { "" }
                }
                None => {
                    tally.untested += 1;
                    ""
                }
            };
            (
                format!("{:+.4}", difference.cm_s),
                difference.z_text(),
                mark.to_string(),
            )
        }
        (Some(_), None) | (None, Some(_)) => {
            tally.one_sided += 1;
            let side = if a.is_some() { "A" } else { "B" };
            (format!("only in {side}"), String::new(), String::new())
        }
        (None, None) => unreachable!("a pair holds a row of A or of B"),
    };
    [value(a), value(b), difference, z, mark]
}

fn optional(value: Option<f64>, format: impl Fn(f64) -> String) -> String {
    value.map_or("—".into(), format)
}

/// A Markdown table with `header`.
pub(super) fn new_table(header: &[&str]) -> Table {
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    table.set_header(header.to_vec());
    table
}

fn model_text(model: Option<ErrorModel>) -> String {
    model.map_or("-".into(), |m| m.to_string())
}

/// The DVL, estimator and error model of a row, whichever side holds it.
fn row_labels<R>(
    a: Option<&R>,
    b: Option<&R>,
    of: impl Fn(&R) -> (&str, EstimatorKind, Option<ErrorModel>),
) -> [String; 3] {
    let (dvl, estimator, model) = of(a.or(b).expect("a pair holds a row of A or of B"));
    [
        dvl.to_string(),
        estimator.label().to_string(),
        model_text(model),
    ]
}

/// The comparison of `a` with `b` as Markdown.
pub fn render(a: &StoredRun, b: &StoredRun) -> String {
    let mut out = String::new();
    let mut tally = Tally::default();
    let _ = writeln!(out, "# Comparison of two results folders\n");
    for (side, run) in [("A", a), ("B", b)] {
        let m = &run.manifest;
        let _ = writeln!(
            out,
            "- {side}: `{}` ({}, {} Monte Carlo runs, dcnet-exp {} at commit {}, finished {})",
            run.folder.display(),
            run.spec.name,
            run.spec.calibration.monte_carlo_runs,
            m.crate_version,
            m.git_commit,
            m.finished_at
        );
    }
    let _ = writeln!(out);
    let _ = writeln!(
        out,
        "RMSE in cm/s, mean over the Monte Carlo runs. z = (B − A) / √(se_A² + se_B²), with se = rmse_std_cm_s / √n and n each folder's `calibration.monte_carlo_runs`; {FLAG} marks |B − A| > {STANDARD_ERRORS} √(se_A² + se_B²). Where both standard errors are 0 (deterministic estimators), any difference beyond rounding ({FLOAT_NOISE:e} of the larger mean) is marked (z ±∞); with a single run on a side there is no standard error and the cell is not tested (n/a). The rule takes A and B as independent; folders of one seed share their random draws, so for them it is conservative.\n"
    );
    spec_section(&spec_table(a), &spec_table(b), &mut out);
    calibration_section(a, b, &mut tally, &mut out);
    evaluation_section(a, b, &mut tally, &mut out);
    super::calibration_time::calibration_time_section(a, b, &mut out);
    training_section(a, b, &mut out);
    stage_section(a, b, &mut out);
    let _ = writeln!(out, "{}", tally.summary());
    out
}

fn spec_table(run: &StoredRun) -> toml::Table {
    toml::Table::try_from(&run.spec).expect("a stored spec serializes")
}

/// The keys of two resolved specs that differ, as a section.
pub(super) fn spec_section(a: &toml::Table, b: &toml::Table, out: &mut String) {
    let _ = writeln!(out, "## Spec\n");
    let differences = spec_differences(a, b);
    if differences.is_empty() {
        let _ = writeln!(out, "The resolved specs are the same.\n");
        return;
    }
    let mut table = new_table(&["key", "A", "B"]);
    let shown = |value: &Option<String>| value.clone().unwrap_or_else(|| "(absent)".into());
    for difference in &differences {
        table.add_row(vec![
            format!("`{}`", difference.key),
            shown(&difference.a),
            shown(&difference.b),
        ]);
    }
    let _ = writeln!(
        out,
        "The keys of the resolved `spec.toml` that differ, arrays of tables numbered as `--set` writes them:\n\n{table}\n"
    );
}

fn calibration_section(a: &StoredRun, b: &StoredRun, tally: &mut Tally, out: &mut String) {
    let mut table = new_table(&[
        "DVL",
        "estimator",
        "EM",
        "window s",
        "A",
        "B",
        "B − A",
        "z",
        "",
    ]);
    let key = |r: &CalibrationRow| (r.dvl.clone(), r.estimator, r.error_model, r.window_s);
    for (row_a, row_b) in pair(&a.calibration, &b.calibration, key) {
        let mut cells = row_labels(row_a, row_b, |r| (&r.dvl, r.estimator, r.error_model)).to_vec();
        cells.push(
            row_a
                .or(row_b)
                .map(|r| r.window_s.to_string())
                .expect("a row"),
        );
        let mean_a = row_a.map(|r| Mean::of(a, r.rmse_cm_s, r.rmse_std_cm_s));
        let mean_b = row_b.map(|r| Mean::of(b, r.rmse_cm_s, r.rmse_std_cm_s));
        cells.extend(rmse_columns(mean_a, mean_b, tally));
        table.add_row(cells);
    }
    let _ = writeln!(
        out,
        "## Calibration\n\nOn {} (A) and {} (B), every window.\n\n{table}\n",
        a.spec.calibration.trajectory, b.spec.calibration.trajectory
    );
}

fn evaluation_section(a: &StoredRun, b: &StoredRun, tally: &mut Tally, out: &mut String) {
    let mut table = new_table(&[
        "DVL",
        "estimator",
        "EM",
        "trajectory",
        "T_conv s A",
        "T_conv s B",
        "A",
        "B",
        "B − A",
        "z",
        "",
        "improvement % A",
        "improvement % B",
    ]);
    let key = |r: &EvaluationRow| {
        (
            r.dvl.clone(),
            r.estimator,
            r.error_model,
            r.trajectory.clone(),
        )
    };
    for (row_a, row_b) in pair(&a.evaluation, &b.evaluation, key) {
        let mut cells = row_labels(row_a, row_b, |r| (&r.dvl, r.estimator, r.error_model)).to_vec();
        cells.push(
            row_a
                .or(row_b)
                .map(|r| r.trajectory.clone())
                .expect("a row"),
        );
        let t_conv =
            |row: Option<&EvaluationRow>| optional(row.map(|r| r.t_conv_s), |t| t.to_string());
        cells.push(t_conv(row_a));
        cells.push(t_conv(row_b));
        let mean_a = row_a.map(|r| Mean::of(a, r.rmse_cm_s, r.rmse_std_cm_s));
        let mean_b = row_b.map(|r| Mean::of(b, r.rmse_cm_s, r.rmse_std_cm_s));
        cells.extend(rmse_columns(mean_a, mean_b, tally));
        // The baseline's improvement over itself is 0 by definition: left out.
        let improvement = |row: Option<&EvaluationRow>| {
            optional(
                row.filter(|r| r.estimator != EstimatorKind::Baseline)
                    .and_then(|r| r.improvement_pct),
                |pct| format!("{pct:+.1}"),
            )
        };
        cells.push(improvement(row_a));
        cells.push(improvement(row_b));
        table.add_row(cells);
    }
    let _ = writeln!(
        out,
        "## Evaluation\n\nEach run's T_conv terms on the test trajectories; the improvement is over the baseline of the same folder, DVL and trajectory.\n\n{table}\n"
    );
}

/// Epochs, training seconds summed over epochs and mean samples/s of each error model.
fn training_of(run: &StoredRun, model: ErrorModel) -> Option<(usize, f64, f64)> {
    let epochs: Vec<_> = run
        .training
        .iter()
        .filter(|e| e.error_model == model)
        .collect();
    if epochs.is_empty() {
        return None;
    }
    let seconds = epochs.iter().map(|e| e.record.seconds).sum();
    let rate = epochs.iter().map(|e| e.record.samples_per_s).sum::<f64>() / epochs.len() as f64;
    Some((epochs.len(), seconds, rate))
}

fn training_section(a: &StoredRun, b: &StoredRun, out: &mut String) {
    let _ = writeln!(out, "## DCNet training\n");
    let models = crate::report::paper::printed::models_in(
        a.training
            .iter()
            .chain(&b.training)
            .map(|e| Some(e.error_model)),
    );
    if models.is_empty() {
        let _ = writeln!(out, "Neither folder holds a trained DCNet.\n");
        return;
    }
    let mut table = new_table(&[
        "EM",
        "epochs A",
        "epochs B",
        "training s A",
        "training s B",
        "samples/s A",
        "samples/s B",
    ]);
    for model in models {
        let (in_a, in_b) = (training_of(a, model), training_of(b, model));
        let column = |f: fn(&(usize, f64, f64)) -> String| {
            [
                in_a.as_ref().map_or("—".into(), f),
                in_b.as_ref().map_or("—".into(), f),
            ]
        };
        let mut cells = vec![model.to_string()];
        cells.extend(column(|t| t.0.to_string()));
        cells.extend(column(|t| format!("{:.1}", t.1)));
        cells.extend(column(|t| format!("{:.0}", t.2)));
        table.add_row(cells);
    }
    let _ = writeln!(
        out,
        "Measured times of the run that trained each model (summed over epochs; samples/s the mean over epochs); they vary from run to run and are not tested.\n\n{table}\n"
    );
}

fn stage_section(a: &StoredRun, b: &StoredRun, out: &mut String) {
    let mut table = new_table(&["stage", "A s", "B s"]);
    let stages = |run: &StoredRun| {
        let s = &run.manifest.stage_seconds;
        [
            s.load,
            s.dataset,
            s.training,
            s.protocol,
            s.load + s.dataset + s.training + s.protocol,
        ]
    };
    let (in_a, in_b) = (stages(a), stages(b));
    for (i, stage) in ["load", "dataset", "training", "protocol", "total"]
        .iter()
        .enumerate()
    {
        table.add_row(vec![
            stage.to_string(),
            format!("{:.2}", in_a[i]),
            format!("{:.2}", in_b[i]),
        ]);
    }
    let _ = writeln!(
        out,
        "## Wall time per stage\n\nFrom each `manifest.json`: the time of the process that wrote the folder; work taken from the cache counts nothing.\n\n{table}\n"
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mean(rmse_cm_s: f64, std_cm_s: f64, runs: usize) -> Mean {
        Mean {
            rmse_cm_s,
            std_cm_s,
            runs,
        }
    }

    #[test]
    fn the_tally_counts_tested_marked_one_sided_and_untested_cells() {
        let mut tally = Tally::default();
        let a = mean(1.0, 0.3, 9);
        let columns = rmse_columns(Some(a), Some(mean(0.7, 0.4, 16)), &mut tally);
        assert_eq!(
            columns,
            ["1.0000", "0.7000", "-0.3000", "-2.1", FLAG].map(String::from)
        );
        rmse_columns(Some(a), Some(a), &mut tally);
        let columns = rmse_columns(None, Some(a), &mut tally);
        assert_eq!(
            columns,
            ["—", "1.0000", "only in B", "", ""].map(String::from)
        );
        rmse_columns(Some(mean(1.0, 0.0, 1)), Some(a), &mut tally);
        assert_eq!(
            tally,
            Tally {
                tested: 2,
                beyond: 1,
                untested: 1,
                one_sided: 1
            }
        );
        assert_eq!(
            tally.summary(),
            "1 of 2 cells differ beyond 2 combined standard errors; 1 cell in one folder only; 1 cell not tested (a single Monte Carlo run gives no standard error)"
        );
    }
}
