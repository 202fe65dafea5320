//! What a sweep of installation studies adds to its points' results folders:
//! `results/<name>/sweep.parquet`, each point's summary (one row per point × method ×
//! window: the mean held-out RMSE over calibration trajectories, its 95 % interval, its
//! ratio to no calibration, how many calibrations) with the swept values as columns,
//! and `sweep.json`, the index of the points (`"kind": "installation"`), written last.
//! In: the experiment and each point's summary rows. Out: the two files.

use crate::installation::study::rows::SummaryRow;
use crate::installation::study::spec::{KIND, StudySpec};
use crate::results::ResultsError;
use crate::results::read::{Batch, ReadError, read_rows, records};
use crate::results::study::SummaryRecord;
use crate::results::sweep::{
    INDEX, PointRecord, SweepIndex, TABLE, point_columns, point_folder, read_index, swept,
    write_table_and_index,
};
use crate::spec::Experiment;
use arrow_array::{ArrayRef, RecordBatch};
use std::path::Path;

/// Whether `folder`'s index is that of a study sweep whose points have `results_keys`,
/// and its table is intact.
pub fn is_current(folder: &Path, results_keys: &[String]) -> bool {
    read_index(folder).is_ok_and(|index| {
        index.kind == KIND && index.results_keys == results_keys && index.table_is_intact(folder)
    })
}

/// Writes `sweep.parquet` from each point's summary (`(point index, rows)` in point
/// order), then `sweep.json`.
pub fn write(
    folder: &Path,
    experiment: &Experiment<StudySpec>,
    summaries: &[(usize, Vec<SummaryRow>)],
    results_keys: &[String],
) -> Result<(), ResultsError> {
    let points: Vec<(&str, Vec<_>)> = experiment
        .points
        .iter()
        .map(|point| {
            (
                point_folder(&point.spec.name),
                point.values.iter().map(swept).collect(),
            )
        })
        .collect();
    let rows: Vec<(usize, &SummaryRow)> = summaries
        .iter()
        .flat_map(|(p, rows)| rows.iter().map(move |row| (*p, row)))
        .collect();
    let keyed: Vec<(&str, &[_])> = rows
        .iter()
        .map(|(p, _)| (points[*p].0, &points[*p].1[..]))
        .collect();
    let summary: Vec<SummaryRow> = rows.iter().map(|(_, row)| (*row).clone()).collect();
    let mut columns: Vec<(String, ArrayRef)> = point_columns(&experiment.swept, &keyed);
    let fixed = crate::results::study::summary_batch(&summary);
    for (field, column) in fixed.schema().fields().iter().zip(fixed.columns()) {
        columns.push((field.name().clone(), column.clone()));
    }
    let batch =
        RecordBatch::try_from_iter(columns).expect("columns of one table have equal lengths");
    let index = SweepIndex {
        name: experiment.name.clone(),
        swept: experiment.swept.clone(),
        points: points.iter().map(|(name, _)| name.to_string()).collect(),
        results_keys: results_keys.to_vec(),
        table_sha256: String::new(),
        kind: KIND.to_string(),
    };
    write_table_and_index(folder, &batch, index)
}

/// A stored sweep of studies: its index and each point's summary rows.
#[derive(Debug, Clone)]
pub struct StoredStudySweep {
    pub index: SweepIndex,
    pub rows: Vec<StudySweepRow>,
}

/// One row of a study sweep's table: a point's summary row.
#[derive(Debug, Clone, PartialEq)]
pub struct StudySweepRow {
    /// The point's folder name.
    pub point: String,
    pub summary: SummaryRow,
}

/// Reads the sweep of studies stored in `folder`; a paper sweep's index is refused.
pub fn read(folder: &Path) -> Result<StoredStudySweep, ReadError> {
    let index = read_index(folder)?;
    if index.kind != KIND {
        return Err(ReadError::OtherKind {
            path: folder.join(INDEX),
            why: "the index of a sweep of the paper's experiments, not of installation studies"
                .into(),
        });
    }
    let mut expected = point_columns(&[], &[]);
    let fixed = crate::results::study::summary_batch(&[]);
    for (field, column) in fixed.schema().fields().iter().zip(fixed.columns()) {
        expected.push((field.name().clone(), column.clone()));
    }
    let expected = RecordBatch::try_from_iter(expected)
        .expect("empty columns of one table")
        .schema();
    let rows = read_rows(&folder.join(TABLE), &expected, |batch: &Batch| {
        let points = records(batch, |r: PointRecord| Ok(r.point))?;
        let summaries = records(batch, |r: SummaryRecord| Ok(SummaryRow::from(r)))?;
        Ok(points
            .into_iter()
            .zip(summaries)
            .map(|(point, summary)| StudySweepRow { point, summary })
            .collect())
    })?;
    Ok(StoredStudySweep { index, rows })
}
