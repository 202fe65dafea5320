//! The Parquet tables of an installation study, in its results folder beside the
//! manifest: `heldout.parquet` (each method's held-out RMSE per calibration window and
//! scored trajectory, per axis and in total), `terms.parquet` (the terms each
//! calibration estimated, with the bound's standard deviation and why a term is not
//! seen), `summary.parquet` (the mean per method and window with its 95 % interval and
//! its ratio to no calibration) and `trace.parquet` (one trajectory's residual before
//! and after, with the yaw rate). In: a [`StudyResults`]. Out: each table's bytes, written with
//! the fixed settings of every results table so the same study gives the same bytes,
//! from one flat record per row (the rows themselves where their fields are the
//! columns); [`read_study`] reads them back into the same [`StudyResults`].

use crate::installation::study::rows::{
    FilterPoint, FitFailure, FoldSummaryRow, RecordingRow, StudyResults, StudyTimeRow, SummaryRow,
    TermRow, TracePoint, TransferRow,
};
use crate::results::read::{ReadError, read_records};
use crate::results::record::{Record, encode};
use crate::results::{ResultsError, table_bytes as parquet_table_bytes};
use arrow_array::RecordBatch;
use serde::{Deserialize, Serialize};
use std::path::Path;

pub const HELDOUT: &str = "heldout.parquet";
pub const TERMS: &str = "terms.parquet";
pub const SUMMARY: &str = "summary.parquet";
pub const TRACE: &str = "trace.parquet";
pub const FAILURES: &str = "failures.parquet";
pub const TERMS_IN_TIME: &str = "terms_in_time.parquet";
pub const CALIBRATION_TIME: &str = "calibration_time.parquet";
pub const RECORDINGS: &str = "recordings.parquet";
/// The study's tables, in the order they are written.
pub const TABLES: [&str; 8] = [
    HELDOUT,
    TERMS,
    SUMMARY,
    TRACE,
    FAILURES,
    TERMS_IN_TIME,
    CALIBRATION_TIME,
    RECORDINGS,
];
/// With `[learned]`, written after [`TABLES`]: the summary inside the folds.
pub const FOLDS: &str = "folds.parquet";

/// Each table of `study` as (file name, Parquet bytes), in [`TABLES`] order, for the
/// caller to write atomically before the manifest.
pub fn table_bytes(study: &StudyResults) -> Result<Vec<(&'static str, Vec<u8>)>, ResultsError> {
    let batches = [
        heldout_batch(&study.heldout),
        terms_batch(&study.terms),
        summary_batch(&study.summary),
        trace_batch(&study.trace),
        failures_batch(&study.failures),
        filtered_batch(&study.filtered),
        time_batch(&study.calibration_time),
        encode(&study.recordings),
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
/// [`read_study`] of a folder whose manifest is there and whose every file has
/// the bytes the manifest records: what `plot` reports again, so that it never writes
/// a report of altered or missing tables.
pub fn read_checked(folder: &Path) -> Result<StudyResults, ReadError> {
    let manifest = crate::results::read::manifest(folder)?;
    let names: Vec<&str> = manifest.files_sha256.keys().map(String::as_str).collect();
    crate::results::read::check_files(folder, &manifest, &names)?;
    read_study(folder)
}

pub fn read_study(folder: &Path) -> Result<StudyResults, ReadError> {
    let path = |name: &str| folder.join(name);
    // Folders written before the Kalman filter lack two tables, before the recordings'
    // reading was counted one more; only a study with `[learned]` has the folds.
    let later = |name: &str| path(name).exists();
    Ok(StudyResults {
        heldout: read_records(&path(HELDOUT), |r: TransferRecord| Ok(r.into()))?,
        terms: read_records(&path(TERMS), Ok)?,
        summary: read_records(&path(SUMMARY), |r: SummaryRecord| Ok(r.into()))?,
        trace: read_records(&path(TRACE), |r: TraceRecord| Ok(r.into()))?,
        failures: read_records(&path(FAILURES), Ok)?,
        filtered: match later(TERMS_IN_TIME) {
            true => read_records(&path(TERMS_IN_TIME), Ok)?,
            false => Vec::new(),
        },
        calibration_time: match later(CALIBRATION_TIME) {
            true => read_records(&path(CALIBRATION_TIME), Ok)?,
            false => Vec::new(),
        },
        recordings: match later(RECORDINGS) {
            true => read_records(&path(RECORDINGS), Ok)?,
            false => Vec::new(),
        },
        folds: match later(FOLDS) {
            true => read_records(&path(FOLDS), |r: FoldRecord| Ok(r.into()))?,
            false => Vec::new(),
        },
    })
}

impl Record for TermRow {}
impl Record for FitFailure {}
impl Record for FilterPoint {}
impl Record for StudyTimeRow {}
impl Record for RecordingRow {}

/// One row per method × calibration trajectory.
pub fn time_batch(rows: &[StudyTimeRow]) -> RecordBatch {
    encode(rows)
}

/// One row per Kalman filter × calibration trajectory × sample × term, in the term's
/// stored unit.
pub fn filtered_batch(rows: &[FilterPoint]) -> RecordBatch {
    encode(rows)
}

/// One row per method × calibration trajectory × window × estimated term.
pub fn terms_batch(rows: &[TermRow]) -> RecordBatch {
    encode(rows)
}

/// One row per method × calibration trajectory × window whose fit failed.
pub fn failures_batch(rows: &[FitFailure]) -> RecordBatch {
    encode(rows)
}

/// A row of `heldout.parquet`: a [`TransferRow`], its RMSE per axis as three columns.
#[derive(Serialize, Deserialize)]
struct TransferRecord {
    method: String,
    calibration: String,
    window_s: f64,
    scored: String,
    rmse_x_cm_s: f64,
    rmse_y_cm_s: f64,
    rmse_z_cm_s: f64,
    rmse_cm_s: f64,
    #[serde(default = "crate::installation::study::rows::not_a_number")]
    drift_rms_pct: f64,
    #[serde(default = "crate::installation::study::rows::not_a_number")]
    drift_end_pct: f64,
}

impl Record for TransferRecord {}

impl From<&TransferRow> for TransferRecord {
    fn from(row: &TransferRow) -> Self {
        let [rmse_x_cm_s, rmse_y_cm_s, rmse_z_cm_s] = row.rmse_cm_s;
        TransferRecord {
            method: row.method.clone(),
            calibration: row.calibration.clone(),
            window_s: row.window_s,
            scored: row.scored.clone(),
            rmse_x_cm_s,
            rmse_y_cm_s,
            rmse_z_cm_s,
            rmse_cm_s: row.total_cm_s,
            drift_rms_pct: row.drift_rms_pct,
            drift_end_pct: row.drift_end_pct,
        }
    }
}

impl From<TransferRecord> for TransferRow {
    fn from(record: TransferRecord) -> Self {
        TransferRow {
            method: record.method,
            calibration: record.calibration,
            window_s: record.window_s,
            scored: record.scored,
            rmse_cm_s: [record.rmse_x_cm_s, record.rmse_y_cm_s, record.rmse_z_cm_s],
            total_cm_s: record.rmse_cm_s,
            drift_rms_pct: record.drift_rms_pct,
            drift_end_pct: record.drift_end_pct,
        }
    }
}

/// One row per method × calibration trajectory × window × scored trajectory.
pub fn heldout_batch(rows: &[TransferRow]) -> RecordBatch {
    encode(&rows.iter().map(TransferRecord::from).collect::<Vec<_>>())
}

/// A row of `summary.parquet`, and of a study sweep's table after its point columns:
/// a [`SummaryRow`] under the names the results document gives its columns.
#[derive(Serialize, Deserialize)]
pub(super) struct SummaryRecord {
    method: String,
    window_s: f64,
    rmse_cm_s: f64,
    rmse_ci_cm_s: f64,
    ratio: f64,
    calibrations: u32,
}

impl Record for SummaryRecord {}

impl From<&SummaryRow> for SummaryRecord {
    fn from(row: &SummaryRow) -> Self {
        SummaryRecord {
            method: row.method.clone(),
            window_s: row.window_s,
            rmse_cm_s: row.mean_cm_s,
            rmse_ci_cm_s: row.ci95_cm_s,
            ratio: row.ratio,
            calibrations: row.calibrations as u32,
        }
    }
}

impl From<SummaryRecord> for SummaryRow {
    fn from(record: SummaryRecord) -> Self {
        SummaryRow {
            method: record.method,
            window_s: record.window_s,
            mean_cm_s: record.rmse_cm_s,
            ci95_cm_s: record.rmse_ci_cm_s,
            ratio: record.ratio,
            calibrations: record.calibrations as usize,
        }
    }
}

/// One row per method × window.
pub fn summary_batch(rows: &[SummaryRow]) -> RecordBatch {
    encode(&rows.iter().map(SummaryRecord::from).collect::<Vec<_>>())
}

/// A row of `folds.parquet`: a [`FoldSummaryRow`], its fold before the summary's
/// columns.
#[derive(Serialize, Deserialize)]
struct FoldRecord {
    fold: String,
    method: String,
    window_s: f64,
    rmse_cm_s: f64,
    rmse_ci_cm_s: f64,
    ratio: f64,
    calibrations: u32,
}

impl Record for FoldRecord {}

impl From<&FoldSummaryRow> for FoldRecord {
    fn from(row: &FoldSummaryRow) -> Self {
        let SummaryRecord {
            method,
            window_s,
            rmse_cm_s,
            rmse_ci_cm_s,
            ratio,
            calibrations,
        } = SummaryRecord::from(&row.summary);
        FoldRecord {
            fold: row.fold.clone(),
            method,
            window_s,
            rmse_cm_s,
            rmse_ci_cm_s,
            ratio,
            calibrations,
        }
    }
}

impl From<FoldRecord> for FoldSummaryRow {
    fn from(record: FoldRecord) -> Self {
        let summary = SummaryRecord {
            method: record.method,
            window_s: record.window_s,
            rmse_cm_s: record.rmse_cm_s,
            rmse_ci_cm_s: record.rmse_ci_cm_s,
            ratio: record.ratio,
            calibrations: record.calibrations,
        };
        FoldSummaryRow {
            fold: record.fold,
            summary: summary.into(),
        }
    }
}

/// One row per fold (and "all") × method × window.
pub fn folds_batch(rows: &[FoldSummaryRow]) -> RecordBatch {
    encode(&rows.iter().map(FoldRecord::from).collect::<Vec<_>>())
}

/// A row of `trace.parquet`: a [`TracePoint`], each residual as three columns.
#[derive(Serialize, Deserialize)]
struct TraceRecord {
    trajectory: String,
    method: String,
    calibration: String,
    time_s: f64,
    before_x_cm_s: f64,
    before_y_cm_s: f64,
    before_z_cm_s: f64,
    after_x_cm_s: f64,
    after_y_cm_s: f64,
    after_z_cm_s: f64,
    yaw_rate_deg_s: f64,
}

impl Record for TraceRecord {}

impl From<&TracePoint> for TraceRecord {
    fn from(point: &TracePoint) -> Self {
        let [before_x_cm_s, before_y_cm_s, before_z_cm_s] = point.before_cm_s;
        let [after_x_cm_s, after_y_cm_s, after_z_cm_s] = point.after_cm_s;
        TraceRecord {
            trajectory: point.trajectory.clone(),
            method: point.method.clone(),
            calibration: point.calibration.clone(),
            time_s: point.time_s,
            before_x_cm_s,
            before_y_cm_s,
            before_z_cm_s,
            after_x_cm_s,
            after_y_cm_s,
            after_z_cm_s,
            yaw_rate_deg_s: point.yaw_rate_deg_s,
        }
    }
}

impl From<TraceRecord> for TracePoint {
    fn from(record: TraceRecord) -> Self {
        TracePoint {
            trajectory: record.trajectory,
            method: record.method,
            calibration: record.calibration,
            time_s: record.time_s,
            before_cm_s: [
                record.before_x_cm_s,
                record.before_y_cm_s,
                record.before_z_cm_s,
            ],
            after_cm_s: [
                record.after_x_cm_s,
                record.after_y_cm_s,
                record.after_z_cm_s,
            ],
            yaw_rate_deg_s: record.yaw_rate_deg_s,
        }
    }
}

/// One row per sample of the trajectory the residual figure draws.
pub fn trace_batch(rows: &[TracePoint]) -> RecordBatch {
    encode(&rows.iter().map(TraceRecord::from).collect::<Vec<_>>())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A study of two trajectories with every kind of row, awkward values included.
    fn study() -> StudyResults {
        StudyResults {
            heldout: vec![
                TransferRow {
                    method: "no calibration".into(),
                    calibration: "T1".into(),
                    window_s: 400.0,
                    scored: "T2".into(),
                    rmse_cm_s: [4.0, 12.6, 2.4],
                    total_cm_s: 13.4,
                    drift_rms_pct: 0.25,
                    drift_end_pct: 0.5,
                },
                TransferRow {
                    method: "installation lever+offset".into(),
                    calibration: "T2".into(),
                    window_s: 100.5,
                    scored: "T1".into(),
                    rmse_cm_s: [2.6, 3.8, 1.0 / 3.0],
                    total_cm_s: 4.6,
                    drift_rms_pct: 0.25,
                    drift_end_pct: 0.5,
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
                    bound_std: 0.012,
                    unseen: String::new(),
                    asked: "scale χ² 48.1".into(),
                    between_dives_std: 0.01,
                    next_dive_low: -1.95,
                    next_dive_high: -1.85,
                },
                TermRow {
                    method: "installation lever+offset".into(),
                    calibration: "T2".into(),
                    window_s: 100.5,
                    term: "time_offset_s".into(),
                    value: 1.51,
                    std: f64::INFINITY,
                    bound_std: f64::INFINITY,
                    unseen: "standard deviation 1e9 s; correlated −0.97 with bias_y_m_s".into(),
                    asked: String::new(),
                    between_dives_std: 0.01,
                    next_dive_low: -1.95,
                    next_dive_high: -1.85,
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
            calibration_time: vec![StudyTimeRow {
                method: "Kalman filter lever+offset".into(),
                calibration: "T1".into(),
                t_conv_s: 400.0,
                calibration_time_s: None,
                rmse_at_time_cm_s: 6.5,
                long_window_rmse_cm_s: f64::INFINITY,
                tolerance_pct: 10.0,
                noise_floor_cm_s: 3.57,
            }],
            recordings: vec![RecordingRow {
                recording: "T1".into(),
                dvl_samples: 400,
                kept: 370,
                left_out_flagged: 0,
                left_out_no_velocity: 25,
                left_out_invalid_marker: 0,
                left_out_all_zero: 5,
                left_out_low_correlation: 0,
                left_out_low_percent_good: 0,
                left_out_water_track: 0,
                left_out_looking_up: 0,
                left_out_reference_gap: 0,
                reference_samples: 4000,
                pieces: 3,
                gap_limit_s: 3.0,
                longest_loss_s: 1.0 / 3.0,
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
                "recordings.parquet",
                "folds.parquet"
            ]
        );
        write(folder.path(), &tables);
        assert_eq!(read_study(folder.path()).unwrap(), study);
        assert_eq!(table_bytes(&study).unwrap(), tables);
        let empty = StudyResults::default();
        let folder = tempfile::tempdir().unwrap();
        write(folder.path(), &table_bytes(&empty).unwrap());
        assert_eq!(read_study(folder.path()).unwrap(), empty);
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
                "rmse_cm_s",
                "drift_rms_pct",
                "drift_end_pct"
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
        assert_eq!(
            names(terms_batch(&[]))[5..],
            [
                "std",
                "bound_std",
                "unseen",
                "asked",
                "between_dives_std",
                "next_dive_low",
                "next_dive_high"
            ]
        );
    }

    #[test]
    fn a_terms_table_written_before_the_spread_between_dives_reads_it_as_none() {
        let folder = tempfile::tempdir().unwrap();
        let path = folder.path().join(TERMS);
        let mut older = terms_batch(&study().terms);
        for column in ["between_dives_std", "next_dive_low", "next_dive_high"] {
            older.remove_column(older.schema().index_of(column).unwrap());
        }
        crate::results::write_table(&path, &older).unwrap();
        let rows: Vec<TermRow> = read_records(&path, Ok).unwrap();
        assert_eq!(rows.len(), study().terms.len());
        assert!(
            rows.iter()
                .all(|r| r.next_dive_low.is_nan() && r.between_dives_std.is_nan())
        );
        assert_eq!(rows[0].value, study().terms[0].value);
    }

    #[test]
    fn a_missing_or_foreign_table_is_named() {
        let folder = tempfile::tempdir().unwrap();
        let tables = table_bytes(&study()).unwrap();
        write(folder.path(), &tables[..3]);
        let error = read_study(folder.path()).unwrap_err();
        let trace = folder.path().join(TRACE);
        assert!(
            matches!(&error, ReadError::Missing { path } if *path == trace),
            "{error:?}"
        );
        // The summary's bytes under the name of the held-out table.
        std::fs::write(folder.path().join(HELDOUT), &tables[2].1).unwrap();
        let error = read_study(folder.path()).unwrap_err();
        assert_eq!(
            error.to_string(),
            format!(
                "{}: column `calibration` is missing: this is not the schema dcnet-exp writes",
                folder.path().join(HELDOUT).display()
            )
        );
    }
}
