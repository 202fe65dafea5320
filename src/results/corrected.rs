//! A DVL recording corrected by its calibration's terms, written as CSV and as Parquet with the
//! same columns: the sample's own time stamp, the time the corrected velocity is valid
//! at (the stamp plus the time offset), and the corrected body-frame velocity in the
//! columns a CSV recording is read from by default ([`crate::VELOCITY_COLUMNS`]), so the
//! corrected file can be named in a spec as it is.
//! Beside it, the Kalman filter's terms after every sample of the recording.
//! In: the corrected samples and the filter's terms. Out: `<stem>-corrected.csv` and
//! `.parquet`, and `<stem>-terms-in-time.parquet`.

use super::record::{Record, encode};
use super::{ResultsError, io, write_table};
use crate::Vec3;
use crate::files::write_atomic;
use crate::installation::frames::Reference;
use crate::installation::rows::FilterPoint;
use crate::installation::terms::Installation;
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

/// Writes `out/<stem>-corrected.csv` and `.parquet`, each atomically; their paths.
pub fn write(
    out: &Path,
    stem: &str,
    samples: &[CorrectedSample],
) -> Result<Vec<PathBuf>, ResultsError> {
    crate::files::create_folder(out).map_err(io(out))?;
    let csv = out.join(format!("{stem}-corrected.csv"));
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
    let table = encode(&records);
    let parquet = out.join(format!("{stem}-corrected.parquet"));
    write_table(&parquet, &table)?;
    Ok(vec![csv, parquet])
}

/// Writes the Kalman filter's terms after every sample to
/// `out/<stem>-terms-in-time.parquet`, the columns of a study's `terms_in_time.parquet`;
/// returns its path.
pub fn write_terms_in_time(
    out: &Path,
    stem: &str,
    points: &[FilterPoint],
) -> Result<PathBuf, ResultsError> {
    let path = out.join(format!("{stem}-terms-in-time.parquet"));
    write_table(&path, &super::installation::filtered_batch(points))?;
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
        let written = write(folder.path(), "dvl", &samples).unwrap();
        assert_eq!(written[0], folder.path().join("dvl-corrected.csv"));
        let columns = crate::VELOCITY_COLUMNS.map(String::from);
        let read = crate::data::csv::read_velocities(&written[0], &columns).unwrap();
        assert_eq!(read, vec![samples[0].velocity_m_s, samples[1].velocity_m_s]);
        assert_eq!(
            std::fs::read_to_string(&written[0]).unwrap().lines().next(),
            Some("time_s,valid_at_s,vx_m_s,vy_m_s,vz_m_s")
        );
        assert!(written[1].is_file());
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
