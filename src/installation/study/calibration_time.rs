//! How long each method needs to calibrate on each calibration trajectory of a study:
//! its held-out curve is the mean, over the trajectories it corrects, of their RMSE
//! with the terms from each calibration window; its calibration time the shortest
//! window after which that curve stays within the tolerance of its value at the
//! longest window (above or below it), the tolerance a fraction of that value's excess
//! over the specified noise (what no calibration removes), set beside its T_conv (the
//! window of lowest held-out RMSE). A window where it has no estimate (a fit that
//! failed) counts as not within; a method no better than no calibration on the same
//! trajectories has none. In: the study's held-out rows, the spec's tolerance and
//! noise. Out: one row per method and calibration trajectory.

use crate::evaluate::calibration_time::{calibration_time_index, tolerance_band};
use crate::first_seen;
use crate::installation::study::rows::{NO_CALIBRATION, StudyTimeRow, TransferRow};

/// Every method's calibration time on every calibration trajectory of `heldout`; the
/// RMSE that perfect terms leave (the specified noise, total over three axes) is
/// `floor_cm_s`.
pub fn calibration_times(
    heldout: &[TransferRow],
    tolerance: f64,
    floor_cm_s: f64,
) -> Vec<StudyTimeRow> {
    let pairs = first_seen(
        heldout
            .iter()
            .map(|r| (r.method.as_str(), r.calibration.as_str())),
    );
    // Every window of the study: a method with no row at one (a fit that failed) has
    // no value there, which counts as not within.
    let mut windows = first_seen(heldout.iter().map(|r| r.window_s));
    windows.sort_by(f64::total_cmp);
    let curve_of = |method: &str, calibration: &str| -> Vec<(f64, f64)> {
        let rows: Vec<&TransferRow> = heldout
            .iter()
            .filter(|r| r.method == method && r.calibration == calibration)
            .collect();
        windows
            .iter()
            .map(|&w| {
                let at: Vec<f64> = rows
                    .iter()
                    .filter(|r| r.window_s == w)
                    .map(|r| r.total_cm_s)
                    .collect();
                (w, at.iter().sum::<f64>() / at.len() as f64)
            })
            .collect()
    };
    // No calibration's RMSE at the longest window, once per calibration trajectory.
    let uncalibrated: std::collections::HashMap<&str, Option<f64>> =
        first_seen(pairs.iter().map(|&(_, calibration)| calibration))
            .into_iter()
            .map(|calibration| {
                let last = curve_of(NO_CALIBRATION, calibration)
                    .last()
                    .map(|&(_, rmse)| rmse);
                (calibration, last.filter(|rmse| rmse.is_finite()))
            })
            .collect();
    pairs
        .into_iter()
        .filter_map(|(method, calibration)| {
            let curve = curve_of(method, calibration);
            let uncalibrated = uncalibrated[calibration];
            let &(_, long) = curve.last()?;
            // The lowest finite mean, the first of equals.
            let t_conv = (0..curve.len())
                .filter(|&i| curve[i].1.is_finite())
                .reduce(|best, i| if curve[i].1 < curve[best].1 { i } else { best })?;
            // The band is of what calibration can change on these trajectories: from no
            // calibration's RMSE down to the noise (or the method's own value, where it
            // goes below the noise); a method no better than no calibration by more than
            // the band has no calibration time.
            let worst = uncalibrated.unwrap_or(long);
            let band = tolerance_band(tolerance, worst, floor_cm_s.min(long));
            let index = if long < worst - band || uncalibrated.is_none() {
                calibration_time_index(&curve, band)
            } else {
                None
            };
            Some(StudyTimeRow {
                method: method.to_string(),
                calibration: calibration.to_string(),
                t_conv_s: curve[t_conv].0,
                calibration_time_s: index.map(|i| curve[i].0),
                rmse_at_time_cm_s: index.map_or(f64::NAN, |i| curve[i].1),
                long_window_rmse_cm_s: long,
                tolerance_pct: 100.0 * tolerance,
                noise_floor_cm_s: floor_cm_s,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(method: &str, window_s: f64, scored: &str, total_cm_s: f64) -> TransferRow {
        TransferRow {
            method: method.into(),
            calibration: "T1".into(),
            window_s,
            scored: scored.into(),
            rmse_cm_s: [0.0; 3],
            total_cm_s,

            drift_rms_pct: f64::NAN,
            drift_end_pct: f64::NAN,
        }
    }

    #[test]
    fn the_curve_is_the_mean_over_the_scored_trajectories() {
        // Means: 20 s → 12, 50 s → 6.5, 100 s → 7, 400 s → 6.
        let rows = [
            row("fit", 400.0, "T2", 5.0),
            row("fit", 400.0, "T3", 7.0),
            row("fit", 20.0, "T2", 10.0),
            row("fit", 20.0, "T3", 14.0),
            row("fit", 50.0, "T2", 6.0),
            row("fit", 50.0, "T3", 7.0),
            row("fit", 100.0, "T2", 7.0),
            row("fit", 100.0, "T3", 7.0),
        ];
        let times = calibration_times(&rows, 0.1, 0.0);
        assert_eq!(times.len(), 1);
        // 7 is beyond 6.6, so the curve stays within 10 % only from 400 s; within 20 %
        // (4.8 to 7.2) from 50 s.
        assert_eq!(times[0].calibration_time_s, Some(400.0));
        assert_eq!(times[0].t_conv_s, 400.0);
        assert_eq!(times[0].long_window_rmse_cm_s, 6.0);
        assert_eq!(
            calibration_times(&rows, 0.2, 0.0)[0].calibration_time_s,
            Some(50.0)
        );
        // A failed fit at 100 s leaves the curve without a value there: within 20 % only
        // from 400 s.
        let failed: Vec<TransferRow> = rows
            .iter()
            .cloned()
            .chain([row("other", 100.0, "T2", 6.0)])
            .filter(|r| !(r.method == "fit" && r.window_s == 100.0))
            .collect();
        let fit = calibration_times(&failed, 0.2, 0.0);
        assert_eq!(fit[0].calibration_time_s, Some(400.0));
    }

    /// A method that does nothing had a calibration time at once (its flat curve "stays
    /// within" itself): no calibration and a method no better than it have none, and
    /// the band is of what calibration changes, from no calibration's 15 down to the
    /// noise's 3.
    #[test]
    fn a_method_that_does_nothing_has_no_calibration_time() {
        let mut rows = Vec::new();
        for (w, fit, flat) in [(20.0, 7.0, 14.9), (50.0, 5.5, 14.9), (400.0, 5.0, 14.9)] {
            rows.push(row(NO_CALIBRATION, w, "T2", 15.0));
            rows.push(row("fit", w, "T2", fit));
            rows.push(row("flat", w, "T2", flat));
        }
        let times = calibration_times(&rows, 0.1, 3.0);
        let time = |method: &str| {
            times
                .iter()
                .find(|t| t.method == method)
                .unwrap()
                .calibration_time_s
        };
        assert_eq!(time(NO_CALIBRATION), None);
        assert_eq!(time("flat"), None);
        // A band of 1.2 cm/s about 5: 5.5 at 50 s is within, 7 at 20 s is not.
        assert_eq!(time("fit"), Some(50.0));
    }
}
