//! The rows of an installation study, as the study computes them and its tables store
//! them: each method's held-out RMSE per calibration window and scored trajectory, the
//! terms each calibration estimated with their bound, the mean per method and window,
//! and the samples of the residual figure; and what one calibration recording gives
//! ([`Calibrated`], the unit a run caches), every method's terms among it. In: nothing
//! (data types only). Out: the [`StudyResults`] that `study` fills,
//! `results::study` writes and reads, and `report::study` sets as tables
//! and figures.

use crate::Vec3;
use crate::data::paired::{LeftOutWhy, ReadCounts};
use crate::installation::terms::Installation;

/// The label of the row that corrects nothing.
pub const NO_CALIBRATION: &str = "no calibration";

/// The held-out RMSE of one method's terms from one calibration window, on one other
/// trajectory, cm/s.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TransferRow {
    pub method: String,
    pub calibration: String,
    /// The window as the spec gives it, s.
    pub window_s: f64,
    pub scored: String,
    pub rmse_cm_s: Vec3,
    pub total_cm_s: f64,
    /// The dead reckoning's horizontal drift over the scored trajectory, RMS and at its
    /// end, % of the distance travelled; NaN where its reference records no position.
    pub drift_rms_pct: f64,
    pub drift_end_pct: f64,
}

/// One estimated term of one calibration, with its standard deviations.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TermRow {
    pub method: String,
    pub calibration: String,
    pub window_s: f64,
    /// Such as `lever_arm_x_m`.
    pub term: String,
    pub value: f64,
    /// The standard deviation, in the term's unit: a fit's from the noise its residuals
    /// show, a Kalman filter's likewise (read as it runs); NaN for a learned method's.
    pub std: f64,
    /// The Fisher bound's, under the specified white noise (a filter's: of the samples
    /// it took).
    pub bound_std: f64,
    /// Why the window cannot show the term; empty when it can.
    pub unseen: String,
    /// The terms the fit left out that its residuals still follow, with their score
    /// test's χ² (`scale χ² 48.1`, `; `-separated), the same on each term of a fit;
    /// empty when none, or for a method that is not a fit.
    pub asked: String,
    /// Of a joint method's vehicle term over three calibration trajectories or more
    /// ([`crate::installation::estimate::between_dives`]): its standard deviation from
    /// one trajectory to the next beyond their noise, and the 95 % interval a next
    /// trajectory's own fit should fall in, in the term's unit; NaN otherwise (and in
    /// tables written before them).
    #[serde(default = "not_a_number")]
    pub between_dives_std: f64,
    #[serde(default = "not_a_number")]
    pub next_dive_low: f64,
    #[serde(default = "not_a_number")]
    pub next_dive_high: f64,
}

/// What a term row holds where it has no spread between dives.
pub(crate) fn not_a_number() -> f64 {
    f64::NAN
}

/// A method's mean held-out RMSE over calibration trajectories, with its 95 % interval.
#[derive(Debug, Clone, PartialEq)]
pub struct SummaryRow {
    pub method: String,
    pub window_s: f64,
    pub mean_cm_s: f64,
    pub ci95_cm_s: f64,
    /// The mean divided by no calibration's on the same pairs.
    pub ratio: f64,
    /// How many calibration trajectories the mean is over: fewer than the study's
    /// where a fit failed (see [`StudyResults::failures`]).
    pub calibrations: usize,
}

/// A calibration window on which a method's fit failed, and why: that window gives
/// the method no held-out rows and no terms.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FitFailure {
    pub method: String,
    pub calibration: String,
    pub window_s: f64,
    pub why: String,
}

/// How one recording of the study was read: the DVL's samples, those kept and those
/// left out per reason (a column per [`LeftOutWhy`]), the reference's samples, and
/// the pieces its gaps cut it into.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RecordingRow {
    pub recording: String,
    pub dvl_samples: u64,
    pub kept: u64,
    pub left_out_flagged: u64,
    pub left_out_no_velocity: u64,
    pub left_out_invalid_marker: u64,
    pub left_out_all_zero: u64,
    #[serde(default)]
    pub left_out_low_correlation: u64,
    #[serde(default)]
    pub left_out_low_percent_good: u64,
    #[serde(default)]
    pub left_out_water_track: u64,
    #[serde(default)]
    pub left_out_looking_up: u64,
    pub left_out_reference_gap: u64,
    pub reference_samples: u64,
    pub pieces: u64,
    pub gap_limit_s: f64,
    pub longest_loss_s: f64,
}

impl RecordingRow {
    /// The row of `counts`, the recording `recording` as read.
    pub fn of(recording: &str, counts: &ReadCounts) -> RecordingRow {
        let left_out = |why: LeftOutWhy| {
            let found = counts.left_out.iter().find(|(w, _)| *w == why);
            found.map_or(0, |&(_, count)| count as u64)
        };
        RecordingRow {
            recording: recording.to_string(),
            dvl_samples: counts.read() as u64,
            kept: counts.kept as u64,
            left_out_flagged: left_out(LeftOutWhy::Flagged),
            left_out_no_velocity: left_out(LeftOutWhy::NoVelocity),
            left_out_invalid_marker: left_out(LeftOutWhy::Marker),
            left_out_all_zero: left_out(LeftOutWhy::AllZero),
            left_out_low_correlation: left_out(LeftOutWhy::LowCorrelation),
            left_out_low_percent_good: left_out(LeftOutWhy::LowPercentGood),
            left_out_water_track: left_out(LeftOutWhy::WaterTrack),
            left_out_looking_up: left_out(LeftOutWhy::LookingUp),
            left_out_reference_gap: left_out(LeftOutWhy::ReferenceGap),
            reference_samples: counts.reference as u64,
            pieces: counts.pieces as u64,
            gap_limit_s: counts.gap_limit_s,
            longest_loss_s: counts.longest_loss_s,
        }
    }

    /// The samples left out for reason `why`.
    fn left_out_for(&self, why: LeftOutWhy) -> u64 {
        match why {
            LeftOutWhy::Flagged => self.left_out_flagged,
            LeftOutWhy::NoVelocity => self.left_out_no_velocity,
            LeftOutWhy::Marker => self.left_out_invalid_marker,
            LeftOutWhy::AllZero => self.left_out_all_zero,
            LeftOutWhy::LowCorrelation => self.left_out_low_correlation,
            LeftOutWhy::LowPercentGood => self.left_out_low_percent_good,
            LeftOutWhy::WaterTrack => self.left_out_water_track,
            LeftOutWhy::LookingUp => self.left_out_looking_up,
            LeftOutWhy::ReferenceGap => self.left_out_reference_gap,
        }
    }

    /// The counts it holds, as the recording's reading gave them.
    pub fn counts(&self) -> ReadCounts {
        ReadCounts {
            kept: self.kept as usize,
            left_out: (LeftOutWhy::ALL.into_iter())
                .map(|why| (why, self.left_out_for(why) as usize))
                .filter(|&(_, count)| count > 0)
                .collect(),
            reference: self.reference_samples as usize,
            beside: "reference",
            pieces: self.pieces as usize,
            gap_limit_s: self.gap_limit_s,
            longest_loss_s: self.longest_loss_s,
            reference_read: None,
        }
    }
}

/// One sample of the residual figure: a held-out trajectory's DVL against the
/// reference in the body frame, before and after the best method's correction, with the
/// yaw rate under it.
#[derive(Debug, Clone, PartialEq)]
pub struct TracePoint {
    /// The trajectory drawn.
    pub trajectory: String,
    /// The method whose correction is drawn, and the trajectory it calibrated on.
    pub method: String,
    pub calibration: String,
    pub time_s: f64,
    pub before_cm_s: Vec3,
    pub after_cm_s: Vec3,
    pub yaw_rate_deg_s: f64,
}

/// A method's calibration time on one calibration trajectory, beside its T_conv.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StudyTimeRow {
    pub method: String,
    pub calibration: String,
    /// The window of lowest held-out RMSE.
    pub t_conv_s: f64,
    /// The shortest window after which the held-out RMSE stays within the tolerance
    /// (of what calibration can change) of its value at the longest window; `None`:
    /// never, or no better than no calibration.
    pub calibration_time_s: Option<f64>,
    pub rmse_at_time_cm_s: f64,
    pub long_window_rmse_cm_s: f64,
    pub tolerance_pct: f64,
    /// What perfect terms leave: the specified noise, total over three axes, cm/s.
    pub noise_floor_cm_s: f64,
}

/// One term of a Kalman filter after one sample of a calibration trajectory, in the
/// term's stored unit.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FilterPoint {
    pub method: String,
    pub calibration: String,
    /// From the first sample of the calibration trajectory, s.
    pub time_s: f64,
    pub term: String,
    pub value: f64,
    pub std: f64,
    /// The bound's standard deviation from a batch of the samples so far.
    pub bound_std: f64,
}

/// Everything the study computes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StudyResults {
    pub heldout: Vec<TransferRow>,
    pub terms: Vec<TermRow>,
    pub summary: Vec<SummaryRow>,
    pub trace: Vec<TracePoint>,
    pub failures: Vec<FitFailure>,
    /// With `[learned]`: every method on the pairs inside a fold only, fold by fold and
    /// over all folds, the learned models' side-by-side comparison.
    pub folds: Vec<FoldSummaryRow>,
    /// The Kalman filters' terms after every sample of every calibration trajectory.
    pub filtered: Vec<FilterPoint>,
    /// Every method's calibration time on every calibration trajectory.
    pub calibration_time: Vec<StudyTimeRow>,
    /// How each recording was read.
    pub recordings: Vec<RecordingRow>,
}

/// A summary over the (calibration, scored) pairs inside one fold, or inside any
/// (`fold` = "all").
#[derive(Debug, Clone, PartialEq)]
pub struct FoldSummaryRow {
    /// "1" to the number of folds, or "all".
    pub fold: String,
    pub summary: SummaryRow,
}

/// The terms one method estimated on one calibration window.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Estimated {
    pub method: String,
    pub calibration: String,
    pub window_s: f64,
    pub installation: Installation,
}

/// What one calibration trajectory gives, over every window and method: the held-out
/// rows, the terms with their bound, every method's terms, and the fits that failed. The
/// unit a run stores in its cache and a shard computes.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Calibrated {
    pub heldout: Vec<TransferRow>,
    pub terms: Vec<TermRow>,
    pub estimated: Vec<Estimated>,
    pub failures: Vec<FitFailure>,
    pub filtered: Vec<FilterPoint>,
}

impl Calibrated {
    /// The rows of `parts`, one after another.
    pub fn concat(parts: impl IntoIterator<Item = Calibrated>) -> Calibrated {
        let mut all = Calibrated::default();
        for part in parts {
            all.heldout.extend(part.heldout);
            all.terms.extend(part.terms);
            all.estimated.extend(part.estimated);
            all.failures.extend(part.failures);
            all.filtered.extend(part.filtered);
        }
        all
    }
}
