//! The Parquet tables of an installation study, in its results folder beside the
//! manifest: `heldout.parquet` (each method's held-out RMSE per calibration window and
//! scored trajectory, per axis and in total), `terms.parquet` (the terms each
//! calibration estimated, with the bound's standard deviation and why a term is not
//! seen), `summary.parquet` (the mean per method and window with its 95 % interval and
//! its ratio to no calibration) and `trace.parquet` (one trajectory's residual before
//! and after, with the yaw rate). In: a [`InstallationResults`]. Out: each table's bytes, written with
//! the fixed settings of every results table so the same study gives the same bytes;
//! [`read_installation`] reads them back into the same [`InstallationResults`].

use super::read::{Batch, ColumnError, ReadError, read_rows};
use super::{ResultsError, batch, floats, strings, table_bytes as parquet_table_bytes};
use crate::installation::rows::{
    FilterPoint, FitFailure, FoldSummaryRow, InstallationResults, InstallationTimeRow, SummaryRow,
    TermRow, TracePoint, TransferRow,
};
use arrow_array::RecordBatch;
use std::path::Path;

pub const HELDOUT: &str = "heldout.parquet";
pub const TERMS: &str = "terms.parquet";
pub const SUMMARY: &str = "summary.parquet";
pub const TRACE: &str = "trace.parquet";
pub const FAILURES: &str = "failures.parquet";
pub const TERMS_IN_TIME: &str = "terms_in_time.parquet";
pub const CALIBRATION_TIME: &str = "calibration_time.parquet";
/// The study's tables, in the order they are written.
pub const TABLES: [&str; 7] = [
    HELDOUT,
    TERMS,
    SUMMARY,
    TRACE,
    FAILURES,
    TERMS_IN_TIME,
    CALIBRATION_TIME,
];
/// With `[learned]`, written after [`TABLES`]: the summary inside the folds.
pub const FOLDS: &str = "folds.parquet";

/// Each table of `study` as (file name, Parquet bytes), in [`TABLES`] order, for the
/// caller to write atomically before the manifest.
pub fn table_bytes(
    study: &InstallationResults,
) -> Result<Vec<(&'static str, Vec<u8>)>, ResultsError> {
    let batches = [
        heldout_batch(&study.heldout),
        terms_batch(&study.terms),
        summary_batch(&study.summary),
        trace_batch(&study.trace),
        failures_batch(&study.failures),
        filtered_batch(&study.filtered),
        time_batch(&study.calibration_time),
    ];
    let mut tables: Vec<(&'static str, Vec<u8>)> = TABLES
        .iter()
        .zip(batches)
        .map(|(name, batch)| Ok((*name, parquet_table_bytes(Path::new(name), &batch)?)))
        .collect::<Result<_, ResultsError>>()?;
    if !study.folds.is_empty() {
        let bytes = parquet_table_bytes(Path::new(FOLDS), &folds_batch(&study.folds))?;
        tables.push((FOLDS, bytes));
    }
    Ok(tables)
}

/// Reads the study's tables from `folder`; an error names the file.
pub fn read_installation(folder: &Path) -> Result<InstallationResults, ReadError> {
    let read = |name: &str, empty: RecordBatch| {
        let path = folder.join(name);
        (path, empty.schema())
    };
    let (path, schema) = read(HELDOUT, heldout_batch(&[]));
    let heldout = read_rows(&path, &schema, heldout_rows)?;
    let (path, schema) = read(TERMS, terms_batch(&[]));
    let terms = read_rows(&path, &schema, term_rows)?;
    let (path, schema) = read(SUMMARY, summary_batch(&[]));
    let summary = read_rows(&path, &schema, summary_rows)?;
    let (path, schema) = read(TRACE, trace_batch(&[]));
    let trace = read_rows(&path, &schema, trace_rows)?;
    let (path, schema) = read(FAILURES, failures_batch(&[]));
    let failures = read_rows(&path, &schema, failure_rows)?;
    // Folders written before the Kalman filter lack these two.
    let (path, schema) = read(TERMS_IN_TIME, filtered_batch(&[]));
    let filtered = if path.exists() {
        read_rows(&path, &schema, filtered_rows)?
    } else {
        Vec::new()
    };
    let (path, schema) = read(CALIBRATION_TIME, time_batch(&[]));
    let calibration_time = if path.exists() {
        read_rows(&path, &schema, time_rows)?
    } else {
        Vec::new()
    };
    // Only a study with `[learned]` has it.
    let (path, schema) = read(FOLDS, folds_batch(&[]));
    let folds = if path.exists() {
        read_rows(&path, &schema, fold_rows)?
    } else {
        Vec::new()
    };
    Ok(InstallationResults {
        heldout,
        terms,
        summary,
        trace,
        failures,
        folds,
        filtered,
        calibration_time,
    })
}

/// One row per method × calibration trajectory.
pub fn time_batch(rows: &[InstallationTimeRow]) -> RecordBatch {
    batch(vec![
        ("method", strings(rows, |r| r.method.clone())),
        ("calibration", strings(rows, |r| r.calibration.clone())),
        ("t_conv_s", floats(rows, |r| r.t_conv_s)),
        (
            "calibration_time_s",
            super::optional_floats(rows, |r| r.calibration_time_s),
        ),
        ("rmse_at_time_cm_s", floats(rows, |r| r.rmse_at_time_cm_s)),
        (
            "long_window_rmse_cm_s",
            floats(rows, |r| r.long_window_rmse_cm_s),
        ),
        ("tolerance_pct", floats(rows, |r| r.tolerance_pct)),
    ])
}

fn time_rows(batch: &Batch) -> Result<Vec<InstallationTimeRow>, ColumnError> {
    let method = batch.strings("method")?;
    let calibration = batch.strings("calibration")?;
    let t_conv_s = batch.floats("t_conv_s")?;
    let time_s = batch.optional_floats("calibration_time_s");
    let at_time = batch.floats("rmse_at_time_cm_s")?;
    let long = batch.floats("long_window_rmse_cm_s")?;
    let tolerance = batch.floats("tolerance_pct")?;
    Ok((0..method.len())
        .map(|i| InstallationTimeRow {
            method: method[i].clone(),
            calibration: calibration[i].clone(),
            t_conv_s: t_conv_s[i],
            calibration_time_s: time_s[i],
            rmse_at_time_cm_s: at_time[i],
            long_window_rmse_cm_s: long[i],
            tolerance_pct: tolerance[i],
        })
        .collect())
}

/// One row per Kalman filter × calibration trajectory × sample × term, in the term's
/// stored unit.
pub fn filtered_batch(rows: &[FilterPoint]) -> RecordBatch {
    batch(vec![
        ("method", strings(rows, |r| r.method.clone())),
        ("calibration", strings(rows, |r| r.calibration.clone())),
        ("time_s", floats(rows, |r| r.time_s)),
        ("term", strings(rows, |r| r.term.clone())),
        ("value", floats(rows, |r| r.value)),
        ("std", floats(rows, |r| r.std)),
        ("bound_std", floats(rows, |r| r.bound_std)),
    ])
}

fn filtered_rows(batch: &Batch) -> Result<Vec<FilterPoint>, ColumnError> {
    let method = batch.strings("method")?;
    let calibration = batch.strings("calibration")?;
    let time_s = batch.floats("time_s")?;
    let term = batch.strings("term")?;
    let value = batch.floats("value")?;
    let std = batch.floats("std")?;
    let bound_std = batch.floats("bound_std")?;
    Ok((0..method.len())
        .map(|i| FilterPoint {
            method: method[i].clone(),
            calibration: calibration[i].clone(),
            time_s: time_s[i],
            term: term[i].clone(),
            value: value[i],
            std: std[i],
            bound_std: bound_std[i],
        })
        .collect())
}

/// One row per method × calibration trajectory × window × scored trajectory.
pub fn heldout_batch(rows: &[TransferRow]) -> RecordBatch {
    batch(vec![
        ("method", strings(rows, |r| r.method.clone())),
        ("calibration", strings(rows, |r| r.calibration.clone())),
        ("window_s", floats(rows, |r| r.window_s)),
        ("scored", strings(rows, |r| r.scored.clone())),
        ("rmse_x_cm_s", floats(rows, |r| r.rmse_cm_s[0])),
        ("rmse_y_cm_s", floats(rows, |r| r.rmse_cm_s[1])),
        ("rmse_z_cm_s", floats(rows, |r| r.rmse_cm_s[2])),
        ("rmse_cm_s", floats(rows, |r| r.total_cm_s)),
    ])
}

/// One row per method × calibration trajectory × window × estimated term.
pub fn terms_batch(rows: &[TermRow]) -> RecordBatch {
    batch(vec![
        ("method", strings(rows, |r| r.method.clone())),
        ("calibration", strings(rows, |r| r.calibration.clone())),
        ("window_s", floats(rows, |r| r.window_s)),
        ("term", strings(rows, |r| r.term.clone())),
        ("value", floats(rows, |r| r.value)),
        ("std", floats(rows, |r| r.std)),
        ("unseen", strings(rows, |r| r.unseen.clone())),
    ])
}

/// One row per method × window.
pub fn summary_batch(rows: &[SummaryRow]) -> RecordBatch {
    batch(vec![
        ("method", strings(rows, |r| r.method.clone())),
        ("window_s", floats(rows, |r| r.window_s)),
        ("rmse_cm_s", floats(rows, |r| r.mean_cm_s)),
        ("rmse_ci_cm_s", floats(rows, |r| r.ci95_cm_s)),
        ("ratio", floats(rows, |r| r.ratio)),
        ("calibrations", uints(rows, |r| r.calibrations)),
    ])
}

/// One row per fold (and "all") × method × window.
pub fn folds_batch(rows: &[FoldSummaryRow]) -> RecordBatch {
    batch(vec![
        ("fold", strings(rows, |r| r.fold.clone())),
        ("method", strings(rows, |r| r.summary.method.clone())),
        ("window_s", floats(rows, |r| r.summary.window_s)),
        ("rmse_cm_s", floats(rows, |r| r.summary.mean_cm_s)),
        ("rmse_ci_cm_s", floats(rows, |r| r.summary.ci95_cm_s)),
        ("ratio", floats(rows, |r| r.summary.ratio)),
        ("calibrations", uints(rows, |r| r.summary.calibrations)),
    ])
}

fn fold_rows(batch: &Batch) -> Result<Vec<FoldSummaryRow>, ColumnError> {
    let fold = batch.strings("fold")?;
    Ok(fold
        .into_iter()
        .zip(summary_rows(batch)?)
        .map(|(fold, summary)| FoldSummaryRow { fold, summary })
        .collect())
}

/// One row per method × calibration trajectory × window whose fit failed.
pub fn failures_batch(rows: &[FitFailure]) -> RecordBatch {
    batch(vec![
        ("method", strings(rows, |r| r.method.clone())),
        ("calibration", strings(rows, |r| r.calibration.clone())),
        ("window_s", floats(rows, |r| r.window_s)),
        ("why", strings(rows, |r| r.why.clone())),
    ])
}

fn uints<T>(rows: &[T], f: impl Fn(&T) -> usize) -> arrow_array::ArrayRef {
    std::sync::Arc::new(arrow_array::UInt32Array::from_iter_values(
        rows.iter().map(|r| f(r) as u32),
    ))
}

fn failure_rows(batch: &Batch) -> Result<Vec<FitFailure>, ColumnError> {
    let method = batch.strings("method")?;
    let calibration = batch.strings("calibration")?;
    let window_s = batch.floats("window_s")?;
    let why = batch.strings("why")?;
    Ok((0..method.len())
        .map(|i| FitFailure {
            method: method[i].clone(),
            calibration: calibration[i].clone(),
            window_s: window_s[i],
            why: why[i].clone(),
        })
        .collect())
}

/// One row per sample of the trajectory the residual figure draws.
pub fn trace_batch(rows: &[TracePoint]) -> RecordBatch {
    batch(vec![
        ("trajectory", strings(rows, |r| r.trajectory.clone())),
        ("method", strings(rows, |r| r.method.clone())),
        ("calibration", strings(rows, |r| r.calibration.clone())),
        ("time_s", floats(rows, |r| r.time_s)),
        ("before_x_cm_s", floats(rows, |r| r.before_cm_s[0])),
        ("before_y_cm_s", floats(rows, |r| r.before_cm_s[1])),
        ("before_z_cm_s", floats(rows, |r| r.before_cm_s[2])),
        ("after_x_cm_s", floats(rows, |r| r.after_cm_s[0])),
        ("after_y_cm_s", floats(rows, |r| r.after_cm_s[1])),
        ("after_z_cm_s", floats(rows, |r| r.after_cm_s[2])),
        ("yaw_rate_deg_s", floats(rows, |r| r.yaw_rate_deg_s)),
    ])
}

/// The x, y, z columns `prefix_x_cm_s`, … of `batch`, as vectors.
fn vectors(batch: &Batch, prefix: &str) -> Result<Vec<crate::Vec3>, ColumnError> {
    let [x, y, z] = ["x", "y", "z"].map(|axis| batch.floats(&format!("{prefix}_{axis}_cm_s")));
    let (x, y, z) = (x?, y?, z?);
    Ok((0..x.len()).map(|i| [x[i], y[i], z[i]]).collect())
}

fn heldout_rows(batch: &Batch) -> Result<Vec<TransferRow>, ColumnError> {
    let method = batch.strings("method")?;
    let calibration = batch.strings("calibration")?;
    let window_s = batch.floats("window_s")?;
    let scored = batch.strings("scored")?;
    let rmse = vectors(batch, "rmse")?;
    let total = batch.floats("rmse_cm_s")?;
    Ok((0..method.len())
        .map(|i| TransferRow {
            method: method[i].clone(),
            calibration: calibration[i].clone(),
            window_s: window_s[i],
            scored: scored[i].clone(),
            rmse_cm_s: rmse[i],
            total_cm_s: total[i],
        })
        .collect())
}

fn term_rows(batch: &Batch) -> Result<Vec<TermRow>, ColumnError> {
    let method = batch.strings("method")?;
    let calibration = batch.strings("calibration")?;
    let window_s = batch.floats("window_s")?;
    let term = batch.strings("term")?;
    let value = batch.floats("value")?;
    let std = batch.floats("std")?;
    let unseen = batch.strings("unseen")?;
    Ok((0..method.len())
        .map(|i| TermRow {
            method: method[i].clone(),
            calibration: calibration[i].clone(),
            window_s: window_s[i],
            term: term[i].clone(),
            value: value[i],
            std: std[i],
            unseen: unseen[i].clone(),
        })
        .collect())
}

pub(super) fn summary_rows(batch: &Batch) -> Result<Vec<SummaryRow>, ColumnError> {
    let method = batch.strings("method")?;
    let window_s = batch.floats("window_s")?;
    let mean = batch.floats("rmse_cm_s")?;
    let ci95 = batch.floats("rmse_ci_cm_s")?;
    let ratio = batch.floats("ratio")?;
    let calibrations = batch.uints("calibrations")?;
    Ok((0..method.len())
        .map(|i| SummaryRow {
            method: method[i].clone(),
            window_s: window_s[i],
            mean_cm_s: mean[i],
            ci95_cm_s: ci95[i],
            ratio: ratio[i],
            calibrations: calibrations[i],
        })
        .collect())
}

fn trace_rows(batch: &Batch) -> Result<Vec<TracePoint>, ColumnError> {
    let trajectory = batch.strings("trajectory")?;
    let method = batch.strings("method")?;
    let calibration = batch.strings("calibration")?;
    let time_s = batch.floats("time_s")?;
    let before = vectors(batch, "before")?;
    let after = vectors(batch, "after")?;
    let yaw_rate = batch.floats("yaw_rate_deg_s")?;
    Ok((0..trajectory.len())
        .map(|i| TracePoint {
            trajectory: trajectory[i].clone(),
            method: method[i].clone(),
            calibration: calibration[i].clone(),
            time_s: time_s[i],
            before_cm_s: before[i],
            after_cm_s: after[i],
            yaw_rate_deg_s: yaw_rate[i],
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A study of two trajectories with every kind of row, awkward values included.
    fn study() -> InstallationResults {
        InstallationResults {
            heldout: vec![
                TransferRow {
                    method: "no calibration".into(),
                    calibration: "T1".into(),
                    window_s: 400.0,
                    scored: "T2".into(),
                    rmse_cm_s: [4.0, 12.6, 2.4],
                    total_cm_s: 13.4,
                },
                TransferRow {
                    method: "installation lever+offset".into(),
                    calibration: "T2".into(),
                    window_s: 100.5,
                    scored: "T1".into(),
                    rmse_cm_s: [2.6, 3.8, 1.0 / 3.0],
                    total_cm_s: 4.6,
                },
            ],
            terms: vec![
                TermRow {
                    method: "installation lever+offset".into(),
                    calibration: "T2".into(),
                    window_s: 100.5,
                    term: "lever_arm_x_m".into(),
                    value: -1.89,
                    std: 0.017,
                    unseen: String::new(),
                },
                TermRow {
                    method: "installation lever+offset".into(),
                    calibration: "T2".into(),
                    window_s: 100.5,
                    term: "time_offset_s".into(),
                    value: 1.51,
                    std: f64::INFINITY,
                    unseen: "standard deviation 1e9 s; correlated −0.97 with bias_y_m_s".into(),
                },
            ],
            summary: vec![SummaryRow {
                method: "no calibration".into(),
                window_s: 400.0,
                mean_cm_s: 15.07,
                ci95_cm_s: 2.3,
                ratio: 1.0,
                calibrations: 13,
            }],
            failures: vec![FitFailure {
                method: "installation all".into(),
                calibration: "T12".into(),
                window_s: 50.0,
                why: "the fit did not converge: LostPatience".into(),
            }],
            trace: (0..3)
                .map(|i| TracePoint {
                    trajectory: "T1".into(),
                    method: "installation lever+offset".into(),
                    calibration: "T2".into(),
                    time_s: f64::from(i) * 400.0 / 399.0,
                    before_cm_s: [1.0, -17.0 + f64::from(i), 0.2],
                    after_cm_s: [0.1, -0.3, f64::from(i) * 1e-3],
                    yaw_rate_deg_s: -15.7 * f64::from(i),
                })
                .collect(),
            folds: ["1", "all"]
                .into_iter()
                .map(|fold| FoldSummaryRow {
                    fold: fold.into(),
                    summary: SummaryRow {
                        method: "DCNet trained on simulation".into(),
                        window_s: 20.0,
                        mean_cm_s: 9.02,
                        ci95_cm_s: 2.42,
                        ratio: 0.6,
                        calibrations: 4,
                    },
                })
                .collect(),
            filtered: (0..2)
                .map(|i| FilterPoint {
                    method: "Kalman filter lever+offset".into(),
                    calibration: "T1".into(),
                    time_s: f64::from(i),
                    term: "time_offset_s".into(),
                    value: 1.0 / 3.0,
                    std: f64::from(i) * 0.5,
                    bound_std: f64::INFINITY,
                })
                .collect(),
            calibration_time: vec![InstallationTimeRow {
                method: "Kalman filter lever+offset".into(),
                calibration: "T1".into(),
                t_conv_s: 400.0,
                calibration_time_s: None,
                rmse_at_time_cm_s: 6.5,
                long_window_rmse_cm_s: f64::INFINITY,
                tolerance_pct: 10.0,
            }],
        }
    }

    fn write(folder: &Path, tables: &[(&str, Vec<u8>)]) {
        for (name, bytes) in tables {
            std::fs::write(folder.join(name), bytes).unwrap();
        }
    }

    #[test]
    fn a_study_reads_back_exactly_and_writes_the_same_bytes_twice() {
        let folder = tempfile::tempdir().unwrap();
        let study = study();
        let tables = table_bytes(&study).unwrap();
        let names: Vec<&str> = tables.iter().map(|(name, _)| *name).collect();
        assert_eq!(
            names,
            [
                "heldout.parquet",
                "terms.parquet",
                "summary.parquet",
                "trace.parquet",
                "failures.parquet",
                "terms_in_time.parquet",
                "calibration_time.parquet",
                "folds.parquet"
            ]
        );
        write(folder.path(), &tables);
        assert_eq!(read_installation(folder.path()).unwrap(), study);
        assert_eq!(table_bytes(&study).unwrap(), tables);
        let empty = InstallationResults::default();
        let folder = tempfile::tempdir().unwrap();
        write(folder.path(), &table_bytes(&empty).unwrap());
        assert_eq!(read_installation(folder.path()).unwrap(), empty);
    }

    #[test]
    fn the_columns_are_named_as_the_results_document_says() {
        let names = |batch: RecordBatch| -> Vec<String> {
            batch
                .schema()
                .fields()
                .iter()
                .map(|f| f.name().clone())
                .collect()
        };
        assert_eq!(
            names(heldout_batch(&[])),
            [
                "method",
                "calibration",
                "window_s",
                "scored",
                "rmse_x_cm_s",
                "rmse_y_cm_s",
                "rmse_z_cm_s",
                "rmse_cm_s"
            ]
        );
        assert_eq!(
            names(summary_batch(&[])),
            [
                "method",
                "window_s",
                "rmse_cm_s",
                "rmse_ci_cm_s",
                "ratio",
                "calibrations"
            ]
        );
        assert_eq!(
            names(failures_batch(&[])),
            ["method", "calibration", "window_s", "why"]
        );
        assert_eq!(names(trace_batch(&[]))[4], "before_x_cm_s");
        assert_eq!(names(terms_batch(&[]))[6], "unseen");
    }

    #[test]
    fn a_missing_or_foreign_table_is_named() {
        let folder = tempfile::tempdir().unwrap();
        let tables = table_bytes(&study()).unwrap();
        write(folder.path(), &tables[..3]);
        let error = read_installation(folder.path()).unwrap_err();
        let trace = folder.path().join(TRACE);
        assert!(
            matches!(&error, ReadError::Missing { path } if *path == trace),
            "{error:?}"
        );
        // The summary's bytes under the name of the held-out table.
        std::fs::write(folder.path().join(HELDOUT), &tables[2].1).unwrap();
        let error = read_installation(folder.path()).unwrap_err();
        assert_eq!(
            error.to_string(),
            format!(
                "{}: column `calibration` is missing: this is not the schema dcnet-exp writes",
                folder.path().join(HELDOUT).display()
            )
        );
    }
}
