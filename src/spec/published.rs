//! Values a paper published, read from a TOML data file so that the report can put ours
//! beside them (`experiments/published/dcnet-paper.toml` holds the DCNet paper's two
//! tables). One entry per table cell: the DVL, the estimator, the error model and, in
//! the evaluation table, the trajectory; the RMSE, and T_conv or the improvement over
//! the baseline where the paper gives them.

use crate::spec::toml_file::{SpecErrors, TomlFile};
use crate::vocab::{ErrorModel, EstimatorKind};
use serde::Deserialize;
use std::path::Path;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct PublishedFile {
    source: String,
    #[serde(default)]
    calibration: Vec<CellFile>,
    #[serde(default)]
    evaluation: Vec<CellFile>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct CellFile {
    dvl: String,
    estimator: String,
    #[serde(default)]
    error_model: Option<String>,
    #[serde(default)]
    trajectory: Option<String>,
    rmse_cm_s: f64,
    #[serde(default)]
    t_conv_s: Option<f64>,
    #[serde(default)]
    improvement_pct: Option<f64>,
}

/// The published tables.
#[derive(Debug, Clone, PartialEq)]
pub struct Published {
    /// Where the values come from, as the file says.
    pub source: String,
    /// Calibration-phase cells (no trajectory).
    pub calibration: Vec<PublishedCell>,
    /// Evaluation-phase cells, one per test trajectory.
    pub evaluation: Vec<PublishedCell>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct PublishedCell {
    pub dvl: String,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
    pub trajectory: Option<String>,
    pub rmse_cm_s: f64,
    pub t_conv_s: Option<f64>,
    pub improvement_pct: Option<f64>,
}

impl Published {
    /// Reads and checks `path`; the error names the file, line and key of every fault.
    pub fn read(path: &Path) -> Result<Self, SpecErrors> {
        let file = TomlFile::<PublishedFile>::read(path).map_err(|e| SpecErrors(vec![e]))?;
        let mut faults = Vec::new();
        let mut cells = |table: &str, entries: &[CellFile]| -> Vec<PublishedCell> {
            let mut cells = Vec::new();
            for (i, entry) in entries.iter().enumerate() {
                let key = |field: &str| format!("{table}[{i}].{field}");
                let estimator = entry
                    .estimator
                    .parse()
                    .map_err(|message: String| faults.push(file.fault(&key("estimator"), message)));
                let error_model = match &entry.error_model {
                    None => Ok(None),
                    Some(name) => name.parse().map(Some).map_err(|message: String| {
                        faults.push(file.fault(&key("error_model"), message))
                    }),
                };
                if (table == "evaluation") != entry.trajectory.is_some() {
                    let message = if table == "evaluation" {
                        "an evaluation cell needs a trajectory"
                    } else {
                        "a calibration cell has no trajectory"
                    };
                    faults.push(file.fault(&format!("{table}[{i}]"), message));
                }
                if !(entry.rmse_cm_s.is_finite() && entry.rmse_cm_s >= 0.0) {
                    let message = format!("{} must be zero or positive", entry.rmse_cm_s);
                    faults.push(file.fault(&key("rmse_cm_s"), message));
                }
                if let (Ok(estimator), Ok(error_model)) = (estimator, error_model) {
                    cells.push(PublishedCell {
                        dvl: entry.dvl.clone(),
                        estimator,
                        error_model,
                        trajectory: entry.trajectory.clone(),
                        rmse_cm_s: entry.rmse_cm_s,
                        t_conv_s: entry.t_conv_s,
                        improvement_pct: entry.improvement_pct,
                    });
                }
            }
            cells
        };
        let calibration = cells("calibration", &file.value.calibration);
        let evaluation = cells("evaluation", &file.value.evaluation);
        if !faults.is_empty() {
            return Err(SpecErrors(faults));
        }
        Ok(Published {
            source: file.value.source.clone(),
            calibration,
            evaluation,
        })
    }

    /// The published cell of a calibration or (with `trajectory`) an evaluation row.
    pub fn find(
        &self,
        dvl: &str,
        estimator: EstimatorKind,
        error_model: Option<ErrorModel>,
        trajectory: Option<&str>,
    ) -> Option<&PublishedCell> {
        let table = match trajectory {
            None => &self.calibration,
            Some(_) => &self.evaluation,
        };
        table.iter().find(|c| {
            c.dvl == dvl
                && c.estimator == estimator
                && c.error_model == error_model
                && c.trajectory.as_deref() == trajectory
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<Published, String> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("published.toml");
        std::fs::write(&path, text).unwrap();
        Published::read(&path)
            .map_err(|e| e.to_string().replace(&path.display().to_string(), "FILE"))
    }

    #[test]
    fn the_papers_file_reads_and_holds_both_tables() {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/published/dcnet-paper.toml");
        let published = Published::read(&path).unwrap();
        assert_eq!(published.calibration.len(), 12);
        assert_eq!(published.evaluation.len(), 60);
        let em5 = published
            .find("DVL2", EstimatorKind::Dcnet, Some(ErrorModel::Em5), None)
            .unwrap();
        assert_eq!((em5.rmse_cm_s, em5.t_conv_s), (0.2, Some(20.0)));
        let t10 = published
            .find(
                "DVL2",
                EstimatorKind::Dcnet,
                Some(ErrorModel::Em4),
                Some("T10Test"),
            )
            .unwrap();
        assert_eq!(t10.rmse_cm_s, 1.26);
    }

    #[test]
    fn faults_name_the_line_and_key() {
        let text = "source = \"x\"\ncalibration = [\n  { dvl = \"DVL1\", estimator = \"baseline\", rmse_cm_s = 1.0 },\n  { dvl = \"DVL1\", estimator = \"magic\", rmse_cm_s = 1.0 },\n]\n";
        let error = read(text).unwrap_err();
        assert!(
            error.starts_with("FILE:4: calibration[1].estimator: "),
            "{error}"
        );
        let error = read("source = \"x\"\nevaluation = [{ dvl = \"DVL1\", estimator = \"baseline\", rmse_cm_s = 1.0 }]\n")
            .unwrap_err();
        assert_eq!(
            error,
            "FILE:2: evaluation[0]: an evaluation cell needs a trajectory"
        );
        let error = read("source = 3\n").unwrap_err();
        assert!(error.starts_with("FILE:1: source: invalid type"), "{error}");
    }
}
