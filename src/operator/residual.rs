//! A calibration's residual sample by sample: on each sample scored, the DVL less the
//! reference in the body frame with no terms (the reference read at the DVL's own
//! stamp) and with the terms applied (the corrected DVL less the reference at t + τ),
//! each by [`corrected_error`] where the reference covers it; the yaw rate there; and
//! whether the fit found it an outlier, which no RMSE counts. The RMSE `calibrate`
//! prints before and after are this trace's ([`Trace::rmse`]), and its report draws
//! it: one source for both. In: the recording, its reference, the samples scored, the
//! outliers and the terms. Out: its [`Trace`], with the recording's gap limit and the
//! times of its samples left out.

use crate::Vec3;
use crate::data::paired::PairedRecording;
use crate::installation::frames::Reference;
use crate::installation::terms::{AxisRmse, Installation, corrected_error};
use std::ops::Range;

/// One scored sample's residual before and after, m/s per body axis; `None` where the
/// reference does not cover it (at t before, at t + τ after: a clock searched seconds
/// away leaves some samples one or the other).
#[derive(Debug, Clone, PartialEq)]
pub struct ScoredResidual {
    /// The DVL's stamp, s on its clock.
    pub time_s: f64,
    pub before_m_s: Option<Vec3>,
    pub after_m_s: Option<Vec3>,
    /// The reference's yaw rate at the stamp or, beyond it, at t + τ, rad/s.
    pub yaw_rate_rad_s: f64,
    pub outlier: bool,
}

/// A recording's residual as a report draws it.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    pub samples: Vec<ScoredResidual>,
    /// The recording's gap limit, s: its pieces are cut at longer steps.
    pub gap_limit_s: f64,
    /// The stamps of the samples the recording left out, s.
    pub left_out_s: Vec<f64>,
}

impl Trace {
    /// The trace of `recording` beside `reference` on the samples `scored`, those at
    /// `outliers` (sorted) marked, with no terms and with `applied`.
    pub fn of(
        (recording, reference): (&PairedRecording, &Reference),
        (scored, outliers): (Range<usize>, &[usize]),
        applied: &Installation,
    ) -> Trace {
        Trace {
            samples: scored_residual((recording, reference), (scored, outliers), applied),
            gap_limit_s: recording.gap_limit_s,
            left_out_s: recording.left_out.iter().map(|l| l.time_s).collect(),
        }
    }

    /// The RMSE of its samples after the terms (before, with `before`), outliers
    /// aside: what the calibration prints, and its report draws.
    pub fn rmse(&self, before: bool) -> Option<AxisRmse> {
        AxisRmse::of_errors(
            (self.samples.iter())
                .filter(|r| !r.outlier)
                .filter_map(|r| if before { r.before_m_s } else { r.after_m_s }),
        )
    }
}

/// The residual of `recording` beside `reference` on the samples `scored`, those at
/// `outliers` (sorted) marked, with no terms and with `applied`.
fn scored_residual(
    (recording, reference): (&PairedRecording, &Reference),
    (scored, outliers): (Range<usize>, &[usize]),
    applied: &Installation,
) -> Vec<ScoredResidual> {
    let record = (&recording.time_s[..], &recording.dvl_m_s[..]);
    scored
        .filter_map(|i| {
            let before = corrected_error(&Installation::default(), record, reference, i);
            let after = corrected_error(applied, record, reference, i);
            let t = recording.time_s[i];
            let at = (reference.at(t)).or_else(|| reference.at(t + applied.time_offset_s))?;
            Some(ScoredResidual {
                time_s: t,
                before_m_s: before,
                after_m_s: after,
                yaw_rate_rad_s: at.rate_rad_s[2],
                outlier: outliers.binary_search(&i).is_ok(),
            })
        })
        .collect()
}
