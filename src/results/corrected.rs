//! A DVL recording corrected by its calibration's terms, written as CSV and as Parquet with the
//! same columns: the sample's own time stamp, the time the corrected velocity is valid
//! at (the stamp plus the time offset), and the corrected body-frame velocity in the
//! columns a CSV recording is read from by default ([`crate::VELOCITY_COLUMNS`]), so the
//! corrected file can be named in a spec as it is.
//! Beside it, the Kalman filter's terms after every sample of the recording.
//! Both Parquet files record the SHA-256 of the DVL file they come from, so that a
//! later `calibrate` or `correct` into the same folder never replaces another recording's.
//! In: the corrected samples and the filter's terms. Out: `<stem>-corrected.csv` and
//! `.parquet`, and `<stem>-terms-in-time.parquet` ([`Outputs`]).

use super::record::{Record, encode};
use super::{ResultsError, io, write_table};
use crate::Vec3;
use crate::files::write_atomic;
use crate::installation::frames::Reference;
use crate::installation::study::rows::FilterPoint;
use crate::installation::terms::Installation;
use arrow_array::RecordBatch;
use std::path::{Path, PathBuf};

/// One corrected sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorrectedSample {
    /// The DVL sample's own stamp, s.
    pub time_s: f64,
    /// When the corrected velocity is valid: the stamp plus the time offset, s.
    pub valid_at_s: f64,
    /// The corrected velocity, body frame, m/s.
    pub velocity_m_s: Vec3,
}

/// The samples of a DVL record (`time_s`, `dvl_m_s`) corrected by `installation`,
/// each valid at its stamp plus the time offset; a sample whose t + τ lies outside the
/// reference is left out, since its correction needs the body rate there.
pub fn corrected_samples(
    installation: &Installation,
    time_s: &[f64],
    dvl_m_s: &[Vec3],
    reference: &Reference,
) -> Vec<CorrectedSample> {
    time_s
        .iter()
        .zip(dvl_m_s)
        .filter_map(|(&t, &dvl)| {
            let valid_at_s = t + installation.time_offset_s;
            let at = reference.at(valid_at_s)?;
            Some(CorrectedSample {
                time_s: t,
                valid_at_s,
                velocity_m_s: installation.correct(dvl, at.rate_rad_s),
            })
        })
        .collect()
}

/// The column names, in order.
const TIME: &str = "time_s";
const VALID_AT: &str = "valid_at_s";

/// A row of `<stem>-corrected.parquet`: the columns of the CSV file, the velocity's
/// named as [`crate::VELOCITY_COLUMNS`] names them.
#[derive(serde::Serialize, serde::Deserialize)]
struct CorrectedRecord {
    time_s: f64,
    valid_at_s: f64,
    vx_m_s: f64,
    vy_m_s: f64,
    vz_m_s: f64,
}

impl Record for CorrectedRecord {}

/// The CSV text of `samples`, every number with all its digits.
pub fn csv_text(samples: &[CorrectedSample]) -> String {
    let [x, y, z] = crate::VELOCITY_COLUMNS;
    let mut text = format!("{TIME},{VALID_AT},{x},{y},{z}\n");
    for s in samples {
        let [vx, vy, vz] = s.velocity_m_s;
        text.push_str(&format!("{},{},{vx},{vy},{vz}\n", s.time_s, s.valid_at_s));
    }
    text
}

/// The files `calibrate` writes for a DVL file of stem `stem` into `out`.
#[derive(Debug, Clone, PartialEq)]
pub struct Outputs {
    /// The DVL file's stem, which names the three files and the terms' trajectory.
    pub stem: String,
    pub csv: PathBuf,
    pub parquet: PathBuf,
    pub terms_in_time: PathBuf,
}

/// The key of the Parquet files' metadata that holds the SHA-256 of the DVL file they
/// were computed from.
pub const RECORDING_SHA256: &str = "dcnet.recording_sha256";

/// A DVL file's name without its extension: what its outputs are named after.
pub fn stem(dvl: &Path) -> String {
    dvl.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "recording".into())
}

impl Outputs {
    pub fn of(out: &Path, stem: &str) -> Outputs {
        Outputs {
            stem: stem.to_string(),
            csv: out.join(format!("{stem}-corrected.csv")),
            parquet: out.join(format!("{stem}-corrected.parquet")),
            terms_in_time: out.join(format!("{stem}-terms-in-time.parquet")),
        }
    }

    pub fn all(&self) -> [&Path; 3] {
        [&self.csv, &self.parquet, &self.terms_in_time]
    }

    /// Refuses outputs already there that hold the results of another recording than
    /// `dvl`, whose file's SHA-256 is `ours`.
    pub fn not_another_recordings(&self, dvl: &Path, ours: &str) -> Result<(), OtherRecording> {
        match self.recording_sha256() {
            Some((output, theirs)) if theirs != ours => Err(OtherRecording {
                output: output.to_path_buf(),
                theirs,
                dvl: dvl.to_path_buf(),
            }),
            _ => Ok(()),
        }
    }

    /// The SHA-256 of the recording the Parquet files already there were computed
    /// from, where one records it.
    fn recording_sha256(&self) -> Option<(&Path, String)> {
        [&self.parquet, &self.terms_in_time]
            .into_iter()
            .find_map(|path| {
                let file = std::fs::File::open(path).ok()?;
                let reader =
                    parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder::try_new(file)
                        .ok()?;
                let sha256 = reader.schema().metadata().get(RECORDING_SHA256)?.clone();
                Some((path.as_path(), sha256))
            })
    }
}

/// An output already there holds another recording's results.
#[derive(Debug, thiserror::Error)]
#[error(
    "{}: holds the results of another recording (SHA-256 {}…), which {} would replace: give another --out, or remove the file",
    output.display(),
    &theirs[..theirs.len().min(12)],
    dvl.display()
)]
pub struct OtherRecording {
    pub output: PathBuf,
    pub theirs: String,
    pub dvl: PathBuf,
}

/// `batch` with the SHA-256 of its recording in its schema's metadata.
fn of_recording(batch: RecordBatch, recording_sha256: &str) -> RecordBatch {
    let metadata = arrow_schema::Metadata::default().with(RECORDING_SHA256, recording_sha256);
    let schema = batch.schema().as_ref().clone().with_metadata(metadata);
    batch
        .with_schema(std::sync::Arc::new(schema))
        .expect("only the metadata changes")
}

/// Writes the CSV and Parquet files of `outputs`, each atomically, the latter recording
/// `recording_sha256`; their paths.
pub fn write(
    outputs: &Outputs,
    samples: &[CorrectedSample],
    recording_sha256: &str,
) -> Result<Vec<PathBuf>, ResultsError> {
    let csv = outputs.csv.clone();
    if let Some(out) = csv.parent().filter(|p| !p.as_os_str().is_empty()) {
        crate::files::create_folder(out).map_err(io(out))?;
    }
    write_atomic(&csv, csv_text(samples).as_bytes()).map_err(io(&csv))?;
    let records: Vec<CorrectedRecord> = samples
        .iter()
        .map(|s| CorrectedRecord {
            time_s: s.time_s,
            valid_at_s: s.valid_at_s,
            vx_m_s: s.velocity_m_s[0],
            vy_m_s: s.velocity_m_s[1],
            vz_m_s: s.velocity_m_s[2],
        })
        .collect();
    let table = of_recording(encode(&records), recording_sha256);
    let parquet = outputs.parquet.clone();
    write_table(&parquet, &table)?;
    Ok(vec![csv, parquet])
}

/// Writes the Kalman filter's terms after every sample to the terms file of `outputs`,
/// the columns of a study's `terms_in_time.parquet`, recording `recording_sha256`;
/// returns its path.
pub fn write_terms_in_time(
    outputs: &Outputs,
    points: &[FilterPoint],
    recording_sha256: &str,
) -> Result<PathBuf, ResultsError> {
    let path = outputs.terms_in_time.clone();
    let batch = of_recording(super::study::filtered_batch(points), recording_sha256);
    write_table(&path, &batch)?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_csv_reads_back_as_a_recording_of_the_corrected_velocity() {
        let samples = [
            CorrectedSample {
                time_s: 0.0,
                valid_at_s: 1.5,
                velocity_m_s: [1.25, -0.5, 0.0625],
            },
            CorrectedSample {
                time_s: 1.0,
                valid_at_s: 2.5,
                velocity_m_s: [1.5, 0.1, -0.2],
            },
        ];
        let folder = tempfile::tempdir().unwrap();
        let outputs = Outputs::of(folder.path(), "dvl");
        let written = write(&outputs, &samples, "ab12").unwrap();
        assert_eq!(written[0], folder.path().join("dvl-corrected.csv"));
        let columns = crate::VELOCITY_COLUMNS.map(String::from);
        let read = crate::data::csv::read_velocities(&written[0], &columns).unwrap();
        assert_eq!(read, vec![samples[0].velocity_m_s, samples[1].velocity_m_s]);
        assert_eq!(
            std::fs::read_to_string(&written[0]).unwrap().lines().next(),
            Some("time_s,valid_at_s,vx_m_s,vy_m_s,vz_m_s")
        );
        assert!(written[1].is_file());
        assert_eq!(
            outputs.recording_sha256(),
            Some((outputs.parquet.as_path(), "ab12".to_string()))
        );
        let names: Vec<String> = crate::results::record::fields::<CorrectedRecord>()
            .iter()
            .map(|f| f.name().clone())
            .collect();
        assert_eq!(
            names,
            ["time_s", "valid_at_s", "vx_m_s", "vy_m_s", "vz_m_s"]
        );
    }
}
