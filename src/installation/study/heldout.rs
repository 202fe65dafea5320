//! Held-out scoring: a method's terms correct the DVL of a scored recording, scored
//! against the reference in the body frame on the samples inside it whatever the time
//! offset, and, where the reference records positions, dead-reckon it: its drift. In: the terms and the recordings they are scored on. Out: [`TransferRow`]s.

use crate::installation::dead_reckoning::drift_of;
use crate::installation::estimate::fit::TIME_OFFSET_MARGIN_S;
use crate::installation::study::on_recording::OnRecording;
use crate::installation::study::recording::Recording;
use crate::installation::study::rows::TransferRow;
use crate::installation::terms::{Installation, score};
use std::ops::Range;

impl OnRecording<'_> {
    /// One method's RMSE on each trajectory of `scored`, on its samples inside the
    /// reference.
    pub(super) fn transfer_rows(
        &self,
        label: &str,
        installation: &Installation,
        scored: &[&Recording],
        on: (&str, f64),
    ) -> Vec<TransferRow> {
        scored
            .iter()
            .filter_map(|scored| {
                // Every method is scored on the same samples, those inside the
                // reference whatever the time offset.
                let samples = scored
                    .reference
                    .interior(&scored.recording.time_s, TIME_OFFSET_MARGIN_S);
                transfer_row(label, installation, scored, samples, on)
            })
            .collect()
    }
}

/// The row of `installation` scored on `samples` of `scored`, calibrated on
/// `calibration`'s first `window_s` seconds.
pub(super) fn transfer_row(
    method: &str,
    installation: &Installation,
    scored: &Recording,
    samples: Range<usize>,
    (calibration, window_s): (&str, f64),
) -> Option<TransferRow> {
    let recording = &scored.recording;
    let rmse = score(
        installation,
        &recording.time_s,
        &recording.dvl_m_s,
        &scored.reference,
        samples,
    )?;
    let drift = drift_of(installation, recording);
    Some(TransferRow {
        method: method.to_string(),
        calibration: calibration.to_string(),
        window_s,
        scored: scored.name.clone(),
        rmse_cm_s: [100.0 * rmse.x_m_s, 100.0 * rmse.y_m_s, 100.0 * rmse.z_m_s],
        total_cm_s: 100.0 * rmse.total_m_s,
        drift_rms_pct: drift.map_or(f64::NAN, |d| d.rms_pct),
        drift_end_pct: drift.map_or(f64::NAN, |d| d.end_pct),
    })
}
