//! A DVL recording corrected by its calibration's terms, written as CSV and as Parquet with the
//! same columns: the sample's own time stamp, the time the corrected velocity is valid
//! at (the stamp plus the time offset), the corrected body-frame velocity in the
//! columns a CSV recording is read from by default ([`crate::VELOCITY_COLUMNS`]), so the
//! corrected file can be named as a recording's DVL as it is, and `left_out`. Every
//! sample the DVL file held is a row, in the order of their stamps: one left out as the
//! recording was read, or whose t + τ lies outside the reference (its correction needs
//! the body rate there), has no velocity (empty cells, Parquet nulls; read again, it is
//! left out again) and says why in `left_out` ([`NotCorrected::key`]); nothing is
//! invented for it.
//! Beside it, the Kalman filter's terms after every sample of the recording.
//! Both Parquet files record the SHA-256 of the DVL file they come from, so that a
//! later `calibrate` or `correct` into the same folder never replaces another recording's.
//! A dive read from a ROS 2 bag is also written as a bag of its own, its corrected
//! velocities as ROS carries them ([`write_bag`]).
//! In: the corrected samples and the filter's terms. Out: `<stem>-corrected.csv` and
//! `.parquet`, and `<stem>-terms-in-time.parquet` ([`Outputs`]); for a bag,
//! `<stem>-corrected.mcap`.

use super::record::{Record, encode};
use super::{ResultsError, io, write_table};
use crate::Vec3;
use crate::data::paired::bag::BagFrames;
use crate::data::paired::bag::write::{BagWriter, twist_with_covariance_message};
use crate::data::paired::{LeftOutWhy, PairedRecording};
use crate::files::write_atomic;
use crate::installation::frames::Reference;
use crate::installation::study::rows::FilterPoint;
use crate::installation::terms::Installation;
use crate::rotation::apply;
use arrow_array::RecordBatch;
use std::path::{Path, PathBuf};

/// One sample of the DVL file, corrected where it can be.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorrectedSample {
    /// The DVL sample's own stamp, s.
    pub time_s: f64,
    /// When the corrected velocity is valid: the stamp plus the time offset, s.
    pub valid_at_s: f64,
    /// The corrected velocity, body frame, m/s, or why there is none.
    pub velocity_m_s: Result<Vec3, NotCorrected>,
}

/// Why a sample of the DVL file has no corrected velocity.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NotCorrected {
    /// Left out as the recording was read.
    LeftOut(LeftOutWhy),
    /// Its t + τ lies outside the reference, or in a gap of it.
    OutsideReference,
}

impl NotCorrected {
    /// What the `left_out` column says.
    pub fn key(self) -> &'static str {
        match self {
            NotCorrected::LeftOut(why) => why.key(),
            NotCorrected::OutsideReference => "outside_reference",
        }
    }
}

/// Every sample of `recording`'s DVL, kept and left out, in the order of their stamps,
/// each kept one corrected by `installation` and valid at its stamp plus the time
/// offset where t + τ lies inside the `reference`.
pub fn corrected_samples(
    installation: &Installation,
    recording: &PairedRecording,
    reference: &Reference,
) -> Vec<CorrectedSample> {
    let tau = installation.time_offset_s;
    let kept = recording
        .time_s
        .iter()
        .zip(&recording.dvl_m_s)
        .map(|(&t, &dvl)| {
            let velocity_m_s = reference
                .rate_at(t + tau)
                .map(|rate| installation.correct(dvl, rate))
                .ok_or(NotCorrected::OutsideReference);
            CorrectedSample {
                time_s: t,
                valid_at_s: t + tau,
                velocity_m_s,
            }
        });
    let left_out = recording.left_out.iter().map(|l| CorrectedSample {
        time_s: l.time_s,
        valid_at_s: l.time_s + tau,
        velocity_m_s: Err(NotCorrected::LeftOut(l.why)),
    });
    let mut samples: Vec<CorrectedSample> = kept.chain(left_out).collect();
    samples.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
    samples
}

/// The column names, in order.
const TIME: &str = "time_s";
const VALID_AT: &str = "valid_at_s";
const LEFT_OUT: &str = "left_out";

/// A row of `<stem>-corrected.parquet`: the columns of the CSV file, the velocity's
/// named as [`crate::VELOCITY_COLUMNS`] names them.
#[derive(serde::Serialize, serde::Deserialize)]
struct CorrectedRecord {
    time_s: f64,
    valid_at_s: f64,
    vx_m_s: Option<f64>,
    vy_m_s: Option<f64>,
    vz_m_s: Option<f64>,
    left_out: String,
}

impl Record for CorrectedRecord {}

/// The CSV text of `samples`, every number with all its digits.
pub fn csv_text(samples: &[CorrectedSample]) -> String {
    let [x, y, z] = crate::VELOCITY_COLUMNS;
    let mut text = format!("{TIME},{VALID_AT},{x},{y},{z},{LEFT_OUT}\n");
    for s in samples {
        let velocity = match s.velocity_m_s {
            Ok([vx, vy, vz]) => format!("{vx},{vy},{vz},"),
            Err(why) => format!(",,,{}", why.key()),
        };
        text.push_str(&format!("{},{},{velocity}\n", s.time_s, s.valid_at_s));
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
        .map(|s| {
            let velocity = s.velocity_m_s.ok();
            CorrectedRecord {
                time_s: s.time_s,
                valid_at_s: s.valid_at_s,
                vx_m_s: velocity.map(|v| v[0]),
                vy_m_s: velocity.map(|v| v[1]),
                vz_m_s: velocity.map(|v| v[2]),
                left_out: s.velocity_m_s.err().map_or("", NotCorrected::key).into(),
            }
        })
        .collect();
    let table = of_recording(encode(&records), recording_sha256);
    let parquet = outputs.parquet.clone();
    write_table(&parquet, &table)?;
    Ok(vec![csv, parquet])
}

/// Writes the corrected samples of a dive read from a bag as a bag of their own at
/// `path` (MCAP): a `geometry_msgs/msg/TwistWithCovarianceStamped` per sample with a
/// velocity, on `topic`, in the body frame of `frames` and its own axes, stamped when
/// it is valid (its stamp plus the time offset, since the epoch) with `covariance`,
/// (m/s)² in those axes. A sample with no velocity has no message: the CSV and Parquet
/// files hold it with its reason. Gives how many messages were written.
pub fn write_bag(
    path: &Path,
    topic: &str,
    samples: &[CorrectedSample],
    frames: &BagFrames,
    covariance: [[f64; 3]; 3],
) -> Result<usize, ResultsError> {
    let fault = |e: String| ResultsError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(e),
    };
    let partial = crate::files::partial_beside(path).map_err(io(path))?;
    let mut bag =
        BagWriter::mcap(partial.reopen().map_err(io(path))?).map_err(|e| fault(e.to_string()))?;
    bag.topic(topic, "geometry_msgs/msg/TwistWithCovarianceStamped")
        .map_err(|e| fault(e.to_string()))?;
    let to_body = frames.axes.to_frd();
    let mut written = 0;
    for sample in samples {
        let Ok(velocity) = sample.velocity_m_s else {
            continue;
        };
        let stamp_ns = frames.origin_s * 1_000_000_000 + (sample.valid_at_s * 1e9).round() as i64;
        let message = twist_with_covariance_message(
            stamp_ns,
            &frames.body,
            apply(&to_body, velocity),
            covariance,
        );
        bag.write(topic, stamp_ns.max(0) as u64, &message)
            .map_err(|e| fault(e.to_string()))?;
        written += 1;
    }
    bag.finish().map_err(|e| fault(e.to_string()))?;
    crate::files::persist_partial(partial, path).map_err(io(path))?;
    Ok(written)
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
    fn every_sample_is_a_row_and_one_left_out_has_no_velocity_but_its_reason() {
        let sample = |time_s: f64, velocity_m_s| CorrectedSample {
            time_s,
            valid_at_s: time_s + 1.5,
            velocity_m_s,
        };
        let samples = [
            sample(0.0, Ok([1.25, -0.5, 0.0625])),
            sample(1.0, Err(NotCorrected::LeftOut(LeftOutWhy::AllZero))),
            sample(2.0, Ok([1.5, 0.1, -0.2])),
            sample(3.0, Err(NotCorrected::OutsideReference)),
        ];
        let folder = tempfile::tempdir().unwrap();
        let outputs = Outputs::of(folder.path(), "dvl");
        let written = write(&outputs, &samples, "ab12").unwrap();
        assert_eq!(written[0], folder.path().join("dvl-corrected.csv"));
        assert_eq!(
            std::fs::read_to_string(&written[0]).unwrap(),
            "time_s,valid_at_s,vx_m_s,vy_m_s,vz_m_s,left_out\n\
             0,1.5,1.25,-0.5,0.0625,\n\
             1,2.5,,,,all_zero\n\
             2,3.5,1.5,0.1,-0.2,\n\
             3,4.5,,,,outside_reference\n"
        );
        // The Parquet file holds the same rows, the velocity null where there is none.
        let file = std::fs::File::open(&written[1]).unwrap();
        let batch = parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder::try_new(file)
            .unwrap()
            .build()
            .unwrap()
            .next()
            .unwrap()
            .unwrap();
        let records: Vec<CorrectedRecord> = crate::results::record::decode(&batch).unwrap();
        let vx: Vec<Option<f64>> = records.iter().map(|r| r.vx_m_s).collect();
        assert_eq!(vx, [Some(1.25), None, Some(1.5), None]);
        let why: Vec<&str> = records.iter().map(|r| r.left_out.as_str()).collect();
        assert_eq!(why, ["", "all_zero", "", "outside_reference"]);
        assert_eq!(
            outputs.recording_sha256(),
            Some((outputs.parquet.as_path(), "ab12".to_string()))
        );
    }

    #[test]
    fn the_samples_left_out_are_put_back_in_their_place_uncorrected() {
        use crate::data::paired::LeftOut;
        let time_s: Vec<f64> = (0..20).map(f64::from).collect();
        let recording = PairedRecording {
            time_s: time_s.iter().copied().filter(|&t| t != 5.0).collect(),
            dvl_m_s: vec![[1.0, 0.0, 0.0]; 19],
            left_out: vec![LeftOut {
                time_s: 5.0,
                line: 7,
                why: LeftOutWhy::NoVelocity,
            }],
            reference_time_s: time_s.clone(),
            velocity_ned_m_s: vec![[1.0, 0.0, 0.0]; 20],
            attitude_rad: vec![[0.0; 3]; 20],
            rate_rad_s: None,
            position_ne_m: None,
            gap_limit_s: 3.0,
            reference_read: None,
        };
        let installation = Installation {
            time_offset_s: 2.0,
            bias_m_s: [0.25, 0.0, 0.0],
            ..Installation::default()
        };
        let samples = corrected_samples(&installation, &recording, &Reference::new(&recording));
        assert_eq!(samples.len(), 20);
        let why: Vec<(f64, &str)> = samples
            .iter()
            .filter_map(|s| s.velocity_m_s.err().map(|why| (s.time_s, why.key())))
            .collect();
        // Sample 5 left out as read; 18 and 19 valid at 20 s and 21 s, past the
        // reference's last sample, 19 s.
        assert_eq!(
            why,
            [
                (5.0, "no_velocity"),
                (18.0, "outside_reference"),
                (19.0, "outside_reference")
            ]
        );
        assert_eq!(samples[0].velocity_m_s, Ok([0.75, 0.0, 0.0]));
        assert_eq!(samples[0].valid_at_s, 2.0);
    }
}
