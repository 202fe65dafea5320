//! How long one recording needs to calibrate, the question an operator with a single
//! recording asks: the installation's Kalman filter runs over it, and the terms it holds
//! after each whole second (at most [`MAX_LENGTHS`] of them, spread in ratio over a long
//! recording, so the cost stays linear in its length) are scored on every sample of the
//! recording. The settling
//! time is the shortest length after which that score stays within a tolerance of its
//! value after the last sample, the rule of a study's calibration time; it is scored on
//! the recording that calibrates, since there is no other. In: the filter's steps and
//! how to score an installation. Out: the curve and the settling time.

use crate::evaluate::calibration_time::{calibration_time_index, tolerance_band};
use crate::installation::estimate::filter::FilterStep;
use crate::installation::terms::Installation;

/// The filter after the samples of the first `length_s` seconds (its step, copied, so a
/// curve outlives the filter's run), and the RMSE its terms leave on the whole recording.
#[derive(Debug, Clone, PartialEq)]
pub struct SettlingPoint {
    pub length_s: f64,
    pub step: FilterStep,
    pub rmse_cm_s: f64,
}

/// The most lengths a curve scores. Each is scored on every sample, so a curve costs
/// at most this many scorings of the recording: linear in its length.
pub const MAX_LENGTHS: usize = 400;

/// The lengths a curve scores, whole seconds up to `longest`: every one where there are
/// at most [`MAX_LENGTHS`], or else that many spread evenly in ratio from 1 s to
/// `longest` (each a fixed fraction longer than the one before, as a settling time is
/// read), the longest always among them.
pub fn curve_lengths(longest: usize) -> Vec<usize> {
    if longest <= MAX_LENGTHS {
        return (1..=longest).collect();
    }
    let step = (longest as f64).ln() / (MAX_LENGTHS - 1) as f64;
    let mut lengths: Vec<usize> = (0..MAX_LENGTHS)
        .map(|i| ((i as f64 * step).exp().round() as usize).clamp(1, longest))
        .collect();
    lengths.dedup();
    if lengths.last() != Some(&longest) {
        lengths.push(longest);
    }
    lengths
}

/// The filter's state after 1, 2, 3, … s of the recording ([`curve_lengths`]), up to
/// the length that holds every step, each with `score_cm_s` of its terms (NaN where
/// there is no score). A length holds the steps whose time from the first sample is
/// below it, as a study's window of that length does.
pub fn settling_curve(
    steps: &[FilterStep],
    score_cm_s: impl Fn(&Installation) -> f64,
) -> Vec<SettlingPoint> {
    let Some(last) = steps.last() else {
        return Vec::new();
    };
    let longest = last.time_s.floor() as usize + 1;
    let mut taken = 0;
    curve_lengths(longest)
        .into_iter()
        .filter_map(|seconds| {
            let length_s = seconds as f64;
            taken += steps[taken..]
                .iter()
                .take_while(|s| s.time_s < length_s)
                .count();
            let step = steps[..taken].last()?;
            Some((length_s, step))
        })
        .map(|(length_s, step)| SettlingPoint {
            length_s,
            step: step.clone(),
            rmse_cm_s: score_cm_s(&step.installation),
        })
        .collect()
}

/// The shortest length of `curve` after which its RMSE stays within `tolerance` (a
/// fraction) of what calibration changes on the recording, from `before_cm_s` (no
/// calibration) down to `floor_cm_s` (the batch fit's), of its last value; `None`
/// when the last value is not finite.
pub fn settling_time(
    curve: &[SettlingPoint],
    tolerance: f64,
    (before_cm_s, floor_cm_s): (f64, f64),
) -> Option<&SettlingPoint> {
    let points: Vec<(f64, f64)> = curve.iter().map(|p| (p.length_s, p.rmse_cm_s)).collect();
    let band = tolerance_band(tolerance, before_cm_s, floor_cm_s);
    calibration_time_index(&points, band).map(|i| &curve[i])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::installation::estimate::bound::Noise;
    use crate::installation::estimate::filter::run_filter;
    use crate::installation::estimate::filter::tests::{settings, weaving_segment};
    use crate::installation::estimate::fit::{TIME_OFFSET_MARGIN_S, fit};
    use crate::installation::terms::names::{TermName, term_set};
    use crate::installation::terms::score;

    /// A ten-hour recording at 1 Hz is scored at most [`MAX_LENGTHS`] times, where it
    /// was once scored after every second (36,000 times its 36,000 samples); a short
    /// one after every second still.
    #[test]
    fn a_long_recording_is_scored_a_bounded_number_of_times() {
        let steps: Vec<FilterStep> = (0..36_000).map(|i| step(i as f64, 0.0)).collect();
        let scorings = std::cell::Cell::new(0);
        let curve = settling_curve(&steps, |_| {
            scorings.set(scorings.get() + 1);
            1.0
        });
        assert!(scorings.get() <= MAX_LENGTHS, "{}", scorings.get());
        assert_eq!(scorings.get(), curve.len());
        assert_eq!(curve.last().unwrap().length_s, 36_000.0);
        let lengths: Vec<f64> = curve.iter().map(|p| p.length_s).collect();
        assert!(lengths.windows(2).all(|w| w[0] < w[1]));
        // Each length at most 3 % and a second longer than the one before.
        assert!(
            lengths.windows(2).all(|w| w[1] <= w[0] * 1.03 + 1.0),
            "{lengths:?}"
        );
        assert_eq!(curve_lengths(400), (1..=400).collect::<Vec<_>>());
    }

    fn step(time_s: f64, lever_x: f64) -> FilterStep {
        let mut installation = Installation::default();
        installation.lever_arm_m[0] = lever_x;
        FilterStep {
            sample: 0,
            time_s,
            installation,
            std: Vec::new(),
            bound_std: Vec::new(),
            gated: false,
        }
    }

    #[test]
    fn each_length_holds_the_steps_below_it_and_the_last_holds_them_all() {
        // Samples at 0, 0.5, 1.0, 2.5 s: 1 s holds two, 2 s three, 3 s all four.
        let steps = [
            step(0.0, 1.0),
            step(0.5, 2.0),
            step(1.0, 3.0),
            step(2.5, 4.0),
        ];
        let curve = settling_curve(&steps, |i| i.lever_arm_m[0]);
        let seen: Vec<(f64, f64)> = curve.iter().map(|p| (p.length_s, p.rmse_cm_s)).collect();
        assert_eq!(seen, [(1.0, 2.0), (2.0, 3.0), (3.0, 4.0)]);
        assert!(settling_curve(&[], |_| 0.0).is_empty());
    }

    #[test]
    fn the_settling_time_is_where_the_curve_stays_within_the_tolerance_of_its_end() {
        // RMSE 30, 12, 9.5, 11.5, 10 after 1 to 5 s, 20 before calibration and 0 after
        // the fit: the band is 9 % or 16 % of 20. Within 1.8 of the last from 3 s;
        // within 3.2 from 2 s.
        let steps: Vec<FilterStep> = [30.0, 12.0, 9.5, 11.5, 10.0]
            .iter()
            .enumerate()
            .map(|(i, &rmse)| step(i as f64, rmse))
            .collect();
        let curve = settling_curve(&steps, |i| i.lever_arm_m[0]);
        assert_eq!(
            settling_time(&curve, 0.09, (20.0, 0.0)).unwrap().length_s,
            3.0
        );
        assert_eq!(
            settling_time(&curve, 0.16, (20.0, 0.0)).unwrap().length_s,
            2.0
        );
        // With the fit at 9: a band of 1.1, within from 5 s only.
        assert_eq!(
            settling_time(&curve, 0.10, (20.0, 9.0)).unwrap().length_s,
            5.0
        );
        let unscored = settling_curve(&steps, |_| f64::NAN);
        assert!(settling_time(&unscored, 0.10, (20.0, 0.0)).is_none());
    }

    /// On a simulated recording the filter's last terms score as the fit of every sample
    /// does, and the curve settles before its end.
    #[test]
    fn a_simulated_recording_settles_to_the_fits_score() {
        let truth = Installation {
            lever_arm_m: [0.8, -0.3, 0.5],
            time_offset_s: 0.2,
            bias_m_s: [0.02, -0.01, 0.015],
            ..Installation::default()
        };
        let (time_s, dvl, reference) = weaving_segment(&truth, 0.02, 4);
        let noise = Noise {
            dvl_m_s: 0.02,
            reference_m_s: 0.0,
        };
        let terms = term_set(&[TermName::LeverArm, TermName::TimeOffset, TermName::Bias]);
        let steps = run_filter(&time_s, &dvl, &reference, terms, &settings(), noise);
        let all = reference.interior(&time_s, TIME_OFFSET_MARGIN_S);
        let rmse = |installation: &Installation| {
            score(installation, &time_s, &dvl, &reference, all.clone())
                .map_or(f64::NAN, |r| 100.0 * r.total_m_s)
        };
        let curve = settling_curve(&steps, rmse);
        let fitted = fit(&time_s, &dvl, &reference, terms).unwrap();
        let end = curve.last().unwrap().rmse_cm_s;
        let best = rmse(&fitted.installation);
        assert!((end - best).abs() < 0.01 * best, "{end} against {best}");
        let before = rmse(&Installation::default());
        let settled = settling_time(&curve, 0.10, (before, best)).unwrap();
        assert!(settled.length_s < 200.0, "{}", settled.length_s);
        assert!(curve[0].rmse_cm_s > 1.1 * end, "{}", curve[0].rmse_cm_s);
    }
}
