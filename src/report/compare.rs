//! `dcnet-exp compare A B`: what changed between two results folders, two runs or two
//! points of a sweep. In: the two folders, read back and schema-checked as
//! [`StoredRun`]s. Out: one Markdown text, printed and written to a file: the keys of
//! the resolved `spec.toml` that differ, every calibration cell (DVL, estimator, error
//! model, window) and evaluation cell (DVL, estimator, error model, trajectory) with
//! A, B and B − A, each RMSE difference marked when it exceeds twice the combined Monte
//! Carlo standard error, then the DCNet training times and the wall time per stage side
//! by side, and a count of the marked cells.

use crate::evaluate::{CalibrationRow, EvaluationRow};
use crate::files::write_atomic;
use crate::results::read::{ReadError, StoredRun};
use crate::results::sweep;
use crate::vocab::{ErrorModel, EstimatorKind};
use comfy_table::{Table, presets::ASCII_MARKDOWN};
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Where the comparison is written unless `--out` says otherwise: the current folder.
pub const DEFAULT_FILE: &str = "compare.md";
/// Marks a cell whose difference is beyond [`STANDARD_ERRORS`] combined standard errors.
const FLAG: &str = "⚠";
/// How many combined standard errors a difference must exceed to be marked.
pub const STANDARD_ERRORS: f64 = 2.0;
/// Share of the larger mean below which a difference between two means of standard
/// error 0 (deterministic estimators) is rounding, not a change.
pub const FLOAT_NOISE: f64 = 1e-9;

#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    #[error(transparent)]
    Read(#[from] ReadError),
    #[error(
        "{}: a sweep folder, not a results folder; compare two of its points: {}",
        path.display(),
        points.join(", ")
    )]
    Sweep { path: PathBuf, points: Vec<String> },
    #[error("writing {}: {error}", path.display())]
    Write {
        path: PathBuf,
        error: std::io::Error,
    },
}

/// Reads the results folder `folder`; a sweep folder is refused with its points listed.
pub fn read(folder: &Path) -> Result<StoredRun, CompareError> {
    if folder.join(sweep::INDEX).is_file() {
        let index = sweep::read_index(folder)?;
        return Err(CompareError::Sweep {
            path: folder.to_path_buf(),
            points: index
                .points
                .iter()
                .map(|point| folder.join(point).display().to_string())
                .collect(),
        });
    }
    Ok(StoredRun::read(folder)?)
}

/// Writes the comparison to `path`, atomically, making its folder if need be.
pub fn write(path: &Path, markdown: &str) -> Result<(), CompareError> {
    let failed = |error| CompareError::Write {
        path: path.to_path_buf(),
        error,
    };
    if let Some(folder) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(folder).map_err(failed)?;
    }
    write_atomic(path, markdown.as_bytes()).map_err(failed)
}

/// A mean RMSE over Monte Carlo runs with the standard deviation over those runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mean {
    pub rmse_cm_s: f64,
    pub std_cm_s: f64,
    pub runs: usize,
}

impl Mean {
    /// A mean RMSE of `run`'s tables, over its Monte Carlo runs.
    fn of(run: &StoredRun, rmse_cm_s: f64, std_cm_s: f64) -> Mean {
        Mean {
            rmse_cm_s,
            std_cm_s,
            runs: run.spec.calibration.monte_carlo_runs,
        }
    }

    /// The standard error of the mean, std / √n; none for a single run, whose stored
    /// standard deviation of 0 says nothing about the spread.
    pub fn standard_error(&self) -> Option<f64> {
        (self.runs >= 2).then(|| self.std_cm_s / (self.runs as f64).sqrt())
    }
}

/// How B's mean stands against A's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Difference {
    /// B − A in cm/s.
    pub cm_s: f64,
    /// √(se_A² + se_B²); none when a side has a single run.
    pub standard_error: Option<f64>,
    /// What |B − A| must exceed to be marked: [`STANDARD_ERRORS`] combined standard
    /// errors, and never less than [`FLOAT_NOISE`] of the larger mean.
    pub threshold_cm_s: Option<f64>,
}

impl Difference {
    pub fn between(a: Mean, b: Mean) -> Self {
        let standard_error = a
            .standard_error()
            .zip(b.standard_error())
            .map(|(a, b)| a.hypot(b));
        let noise = FLOAT_NOISE * a.rmse_cm_s.abs().max(b.rmse_cm_s.abs());
        Difference {
            cm_s: b.rmse_cm_s - a.rmse_cm_s,
            standard_error,
            threshold_cm_s: standard_error.map(|se| (STANDARD_ERRORS * se).max(noise)),
        }
    }

    /// Whether |B − A| exceeds the threshold; none when it cannot be tested.
    pub fn is_beyond(&self) -> Option<bool> {
        self.threshold_cm_s.map(|t| self.cm_s.abs() > t)
    }

    /// (B − A) in combined standard errors, as printed: `±∞` for a change between two
    /// means of standard error 0, `—` for none, `n/a` when it cannot be tested.
    pub fn z_text(&self) -> String {
        match (self.standard_error, self.is_beyond()) {
            (None, _) => "n/a".into(),
            (Some(se), _) if se > 0.0 => format!("{:+.1}", self.cm_s / se),
            (Some(_), Some(true)) if self.cm_s > 0.0 => "+∞".into(),
            (Some(_), Some(true)) => "-∞".into(),
            (Some(_), _) => "—".into(),
        }
    }
}

/// A spec key whose value differs; `None` where a side lacks the key.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyDifference {
    pub key: String,
    pub a: Option<String>,
    pub b: Option<String>,
}

/// The spec as `dotted.key = value` pairs in file order: tables open into dotted keys,
/// arrays of tables into `key[i]` as `--set` writes them (`dvl[1].noise_cm_s`), and any
/// other value, arrays of numbers included, stays whole as TOML text.
pub fn flatten(table: &toml::Table) -> Vec<(String, String)> {
    let mut pairs = Vec::new();
    for (key, value) in table {
        flatten_into(key.clone(), value, &mut pairs);
    }
    pairs
}

fn flatten_into(key: String, value: &toml::Value, pairs: &mut Vec<(String, String)>) {
    match value {
        toml::Value::Table(table) => {
            for (name, value) in table {
                flatten_into(format!("{key}.{name}"), value, pairs);
            }
        }
        toml::Value::Array(items) if !items.is_empty() && items.iter().all(|i| i.is_table()) => {
            for (index, item) in items.iter().enumerate() {
                flatten_into(format!("{key}[{index}]"), item, pairs);
            }
        }
        other => pairs.push((key, other.to_string())),
    }
}

/// The keys whose values differ, A's order first, then the keys only B has.
pub fn spec_differences(a: &toml::Table, b: &toml::Table) -> Vec<KeyDifference> {
    let (a, b) = (flatten(a), flatten(b));
    let find = |pairs: &[(String, String)], key: &str| {
        pairs.iter().find(|(k, _)| k == key).map(|(_, v)| v.clone())
    };
    let mut differences: Vec<KeyDifference> = a
        .iter()
        .filter_map(|(key, value)| {
            let other = find(&b, key);
            (other.as_ref() != Some(value)).then(|| KeyDifference {
                key: key.clone(),
                a: Some(value.clone()),
                b: other,
            })
        })
        .collect();
    differences.extend(
        b.iter()
            .filter(|(key, _)| find(&a, key).is_none())
            .map(|(key, value)| KeyDifference {
                key: key.clone(),
                a: None,
                b: Some(value.clone()),
            }),
    );
    differences
}

/// The rows of A and B paired by `key`: A's rows in order, each with B's row of the
/// same key if there is one, then B's rows that A lacks.
fn pair<'r, R, K: PartialEq>(
    a: &'r [R],
    b: &'r [R],
    key: impl Fn(&R) -> K,
) -> Vec<(Option<&'r R>, Option<&'r R>)> {
    let mut pairs: Vec<_> = a
        .iter()
        .map(|row| (Some(row), b.iter().find(|other| key(other) == key(row))))
        .collect();
    pairs.extend(
        b.iter()
            .filter(|row| !a.iter().any(|other| key(other) == key(row)))
            .map(|row| (None, Some(row))),
    );
    pairs
}

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

fn new_table(header: &[&str]) -> Table {
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
    spec_section(a, b, &mut out);
    calibration_section(a, b, &mut tally, &mut out);
    evaluation_section(a, b, &mut tally, &mut out);
    training_section(a, b, &mut out);
    stage_section(a, b, &mut out);
    let _ = writeln!(out, "{}", tally.summary());
    out
}

fn spec_table(run: &StoredRun) -> toml::Table {
    toml::Table::try_from(&run.spec).expect("a stored spec serializes")
}

fn spec_section(a: &StoredRun, b: &StoredRun, out: &mut String) {
    let _ = writeln!(out, "## Spec\n");
    let differences = spec_differences(&spec_table(a), &spec_table(b));
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
    let models = crate::report::tables::models_in(
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
    fn the_standard_error_is_the_std_over_the_root_of_the_runs() {
        assert_eq!(mean(1.0, 0.4, 16).standard_error(), Some(0.1));
        assert!((mean(1.0, 0.3, 9).standard_error().unwrap() - 0.1).abs() < 1e-15);
        assert_eq!(mean(1.0, 0.0, 1).standard_error(), None);
    }

    #[test]
    fn a_difference_is_marked_beyond_two_combined_standard_errors() {
        // se_A = 0.3/√9 = 0.1, se_B = 0.4/√16 = 0.1: combined 0.1414, threshold 0.2828.
        let a = mean(1.0, 0.3, 9);
        let within = Difference::between(a, mean(1.25, 0.4, 16));
        assert!((within.standard_error.unwrap() - 0.141_421_356).abs() < 1e-9);
        assert!((within.threshold_cm_s.unwrap() - 0.282_842_712).abs() < 1e-9);
        assert_eq!(within.is_beyond(), Some(false));
        assert_eq!(within.z_text(), "+1.8");
        let beyond = Difference::between(a, mean(0.7, 0.4, 16));
        assert_eq!(beyond.is_beyond(), Some(true));
        assert_eq!(beyond.z_text(), "-2.1");
    }

    #[test]
    fn deterministic_means_differ_beyond_rounding_only() {
        let a = mean(0.74, 0.0, 20);
        let same = Difference::between(a, a);
        assert_eq!(
            (same.is_beyond(), same.z_text().as_str()),
            (Some(false), "—")
        );
        // A mean summed in another order: 1e-15 off, far below 1e-9 of 0.74.
        let rounded = Difference::between(a, mean(0.74 + 1e-15, 0.0, 20));
        assert_eq!(rounded.is_beyond(), Some(false));
        let changed = Difference::between(a, mean(0.74 - 1e-6, 0.0, 20));
        assert_eq!(
            (changed.is_beyond(), changed.z_text().as_str()),
            (Some(true), "-∞")
        );
    }

    #[test]
    fn a_single_run_leaves_a_cell_untested() {
        let untested = Difference::between(mean(1.0, 0.0, 1), mean(5.0, 0.2, 20));
        assert_eq!(untested.is_beyond(), None);
        assert_eq!(untested.z_text(), "n/a");
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

    #[test]
    fn specs_flatten_to_set_keys_and_differ_key_by_key() {
        let a: toml::Table = toml::from_str(
            "name = \"quick\"\n[calibration]\nwindow_sizes_s = [20.0, 40.0]\nmonte_carlo_runs = 3\n[[dvl]]\nname = \"DVL1\"\nnoise_cm_s = 2.0\n[[dvl]]\nname = \"DVL2\"\nnoise_cm_s = 0.02\n",
        )
        .unwrap();
        assert_eq!(
            flatten(&a)
                .iter()
                .map(|(k, v)| format!("{k} = {v}"))
                .collect::<Vec<_>>(),
            [
                "name = \"quick\"",
                "calibration.window_sizes_s = [20.0, 40.0]",
                "calibration.monte_carlo_runs = 3",
                "dvl[0].name = \"DVL1\"",
                "dvl[0].noise_cm_s = 2.0",
                "dvl[1].name = \"DVL2\"",
                "dvl[1].noise_cm_s = 0.02",
            ]
        );
        let b: toml::Table = toml::from_str(
            "name = \"quick\"\nseed = 1\n[calibration]\nwindow_sizes_s = [20.0, 60.0]\n[[dvl]]\nname = \"DVL1\"\nnoise_cm_s = 2.0\n[[dvl]]\nname = \"DVL2\"\nnoise_cm_s = 0.05\n",
        )
        .unwrap();
        let text = |value: &str| Some(value.to_string());
        assert_eq!(
            spec_differences(&a, &b),
            vec![
                KeyDifference {
                    key: "calibration.window_sizes_s".into(),
                    a: text("[20.0, 40.0]"),
                    b: text("[20.0, 60.0]"),
                },
                KeyDifference {
                    key: "calibration.monte_carlo_runs".into(),
                    a: text("3"),
                    b: None,
                },
                KeyDifference {
                    key: "dvl[1].noise_cm_s".into(),
                    a: text("0.02"),
                    b: text("0.05"),
                },
                KeyDifference {
                    key: "seed".into(),
                    a: None,
                    b: text("1"),
                },
            ]
        );
        assert!(spec_differences(&a, &a).is_empty());
    }

    #[test]
    fn rows_pair_by_key_in_a_order_then_b_only() {
        let a = [("x", 1), ("y", 2), ("z", 3)];
        let b = [("w", 9), ("z", 30), ("x", 10)];
        let pairs: Vec<_> = pair(&a, &b, |r| r.0)
            .into_iter()
            .map(|(a, b)| (a.map(|r| r.1), b.map(|r| r.1)))
            .collect();
        assert_eq!(
            pairs,
            [
                (Some(1), Some(10)),
                (Some(2), None),
                (Some(3), Some(30)),
                (None, Some(9))
            ]
        );
    }
}
