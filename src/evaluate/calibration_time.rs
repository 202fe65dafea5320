//! How long to calibrate. In every Monte Carlo run, each method's terms from the first
//! n samples of the calibration trajectory correct that run's measurements of the test
//! trajectories, all of them pooled: the held-out RMSE against n, at every sample up
//! to the longest calibration window for the methods whose estimate is cheap, at the
//! calibration windows for DCNet. Its mean over runs is the method's held-out curve;
//! the bound's is the expected RMSE of an efficient estimator from the same samples.
//! (The calibration trajectory is never among the held-out data, even where a spec
//! tests on it too.) Read at the calibration windows, where every method has its curve:
//! a method's time to the bound is the shortest length after which it stays within the
//! tolerance of the bound's value at the longest window (a target common to every
//! method, which a method that converges to a worse value never reaches); its
//! calibration time the shortest length after which its curve stays within the
//! tolerance, of what calibration changes over the windows (from its RMSE at the
//! shortest down to the bound's at the longest), of its own value at the longest
//! window, set beside its T_conv: none for a method whose value there is further above
//! the bound's than the tolerance of the bound's own drop over the windows. In: per-run rows of
//! [`Phase::HeldOut`], the bound's curve, the calibration table. Out: the held-out
//! curves and the calibration-time table.

use super::rows::{CalibrationRow, CalibrationTimeRow, HeldOutRow, RunRow};
use super::statistics::mean_std;
use crate::Vec3;
use crate::bound::BoundRow;
use crate::first_seen;
use crate::vocab::{Correction, EstimatorKind, Phase};

/// The calibration lengths, in samples, at which a method's held-out curve is taken:
/// the calibration windows for DCNet, whose estimate is a network pass per window;
/// every sample up to the longest window for the others; none for the floor, which
/// does not calibrate.
pub fn curve_lengths(kind: EstimatorKind, windows: &[usize]) -> Vec<usize> {
    match kind {
        EstimatorKind::Dcnet | EstimatorKind::DcnetEnsemble => windows.to_vec(),
        EstimatorKind::Floor | EstimatorKind::Bound => Vec::new(),
        _ => (1..=windows.iter().copied().max().unwrap_or(0)).collect(),
    }
}

/// What scores any scale-and-bias correction on fixed samples in a few operations:
/// per axis, with e = d − t the DVL's error and t the truth, the count and the sums
/// of e, e², t, t² and e·t. The corrected error `(d − b)/(1 + k) − t` is
/// `(e − b − k·t)/(1 + k)`, whose square sums from them.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct HeldOutScore {
    count: f64,
    sums: [[f64; 5]; 3],
}

impl HeldOutScore {
    /// Adds the samples `dvl` of the truth `truth`.
    pub fn add(&mut self, dvl: &[Vec3], truth: &[Vec3]) {
        for (d, t) in dvl.iter().zip(truth) {
            self.count += 1.0;
            for (a, sums) in self.sums.iter_mut().enumerate() {
                let e = d[a] - t[a];
                for (sum, value) in sums.iter_mut().zip([e, e * e, t[a], t[a] * t[a], e * t[a]]) {
                    *sum += value;
                }
            }
        }
    }

    /// `sqrt(mean_t Σ_xyz (truth − corrected)²)` of the samples added, cm/s: what
    /// `protocol::rmse_cm_s` gives on them.
    pub fn rmse_cm_s(&self, correction: &Correction) -> f64 {
        let squares: f64 = (0..3)
            .map(|a| {
                let [e, ee, t, tt, et] = self.sums[a];
                let (k, b) = (correction.scale[a], correction.bias_m_s[a]);
                (ee + self.count * b * b + k * k * tt - 2.0 * b * e - 2.0 * k * et
                    + 2.0 * b * k * t)
                    / (1.0 + k).powi(2)
            })
            .sum();
        // Rounding may leave a tiny negative sum; a NaN term stays NaN.
        let squares = if squares < 0.0 { 0.0 } else { squares };
        100.0 * (squares / self.count).sqrt()
    }
}

/// The shortest length of `curve` (length, mean RMSE, in increasing length) from which
/// every later point is within `band_cm_s` of the last point's RMSE, above or below it;
/// its index. `None` when the last point is not finite.
pub fn calibration_time_index(curve: &[(f64, f64)], band_cm_s: f64) -> Option<usize> {
    let &(_, long) = curve.last()?;
    if !long.is_finite() {
        return None;
    }
    first_of_last_run(curve, |rmse| (rmse - long).abs() <= band_cm_s)
}

/// The band of a calibration time: `tolerance` (a fraction) of what calibration can
/// change, the RMSE from `worst` (with no calibration, where known) down to `floor`
/// (what no calibration removes: noise). A band of the whole RMSE let a method whose
/// curve sits on a high floor "settle" at once.
pub fn tolerance_band(tolerance: f64, worst_cm_s: f64, floor_cm_s: f64) -> f64 {
    tolerance * (worst_cm_s - floor_cm_s).max(0.0)
}

/// The shortest length of `curve` from which every later point is at most `limit`; its
/// index. `None` when the last point is beyond it (or not finite).
pub fn index_within(curve: &[(f64, f64)], limit: f64) -> Option<usize> {
    first_of_last_run(curve, |rmse| rmse <= limit)
}

/// The index from which every point of `curve` holds `inside`; `None` when the last
/// does not.
fn first_of_last_run(curve: &[(f64, f64)], inside: impl Fn(f64) -> bool) -> Option<usize> {
    let outside = curve.iter().rposition(|&(_, rmse)| !inside(rmse));
    match outside {
        None => Some(0),
        Some(i) if i + 1 < curve.len() => Some(i + 1),
        Some(_) => None,
    }
}

/// The held-out curve of every series of `runs` (replicates pooled with runs) and of
/// every DVL's bound (`bounds` of [`Phase::HeldOut`]), in that order.
pub fn held_out_curves(runs: &[RunRow], bounds: &[BoundRow]) -> Vec<HeldOutRow> {
    let held_out: Vec<&RunRow> = runs.iter().filter(|r| r.phase == Phase::HeldOut).collect();
    let series = first_seen(
        held_out
            .iter()
            .map(|r| (r.dvl.as_str(), r.estimator, r.error_model)),
    );
    let mut rows = Vec::new();
    for (dvl, estimator, error_model) in series {
        let of_series: Vec<&&RunRow> = held_out
            .iter()
            .filter(|r| r.dvl == dvl && r.estimator == estimator && r.error_model == error_model)
            .collect();
        let mut lengths = first_seen(of_series.iter().map(|r| r.window_s));
        lengths.sort_by(f64::total_cmp);
        for length_s in lengths {
            let (rmse_cm_s, rmse_std_cm_s) = mean_std(
                of_series
                    .iter()
                    .filter(|r| r.window_s == length_s)
                    .map(|r| r.rmse_cm_s),
            );
            rows.push(HeldOutRow {
                dvl: dvl.to_string(),
                estimator,
                error_model,
                length_s,
                rmse_cm_s,
                rmse_std_cm_s,
            });
        }
    }
    rows.extend(
        bounds
            .iter()
            .filter(|b| b.phase == Phase::HeldOut)
            .map(|b| HeldOutRow {
                dvl: b.dvl.clone(),
                estimator: EstimatorKind::Bound,
                error_model: None,
                length_s: b.window_s,
                rmse_cm_s: b.rmse_cm_s,
                rmse_std_cm_s: b.rmse_std_cm_s,
            }),
    );
    rows
}

/// The calibration time of every curve of `curves`, with the T_conv the calibration
/// table gives the same method; each DVL's curves are cut at its longest calibration
/// window, the same for every method.
pub fn calibration_times(
    curves: &[HeldOutRow],
    calibration: &[CalibrationRow],
    tolerance: f64,
) -> Vec<CalibrationTimeRow> {
    let series = first_seen(
        curves
            .iter()
            .map(|r| (r.dvl.as_str(), r.estimator, r.error_model)),
    );
    series
        .into_iter()
        .filter_map(|(dvl, estimator, error_model)| {
            // Read at the calibration windows, the lengths at which every method (DCNet,
            // whose estimate is a pass of the network per window, too) has its curve.
            let windows: Vec<f64> = calibration
                .iter()
                .filter(|r| r.dvl == dvl)
                .map(|r| r.window_s)
                .collect();
            let long_window_s = windows.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let curve: Vec<(f64, f64)> = curves
                .iter()
                .filter(|r| {
                    r.dvl == dvl
                        && r.estimator == estimator
                        && r.error_model == error_model
                        && windows.contains(&r.length_s)
                })
                .map(|r| (r.length_s, r.rmse_cm_s))
                .collect();
            let t_conv_s = calibration
                .iter()
                .find(|r| {
                    r.dvl == dvl
                        && r.estimator == estimator
                        && r.error_model == error_model
                        && r.is_t_conv
                })?
                .window_s;
            let &(long_s, long) = curve.last()?;
            let bound = bound_at(curves, dvl, long_window_s);
            // The protocol scores no uncorrected DVL: the band is of what calibration
            // changes over the windows, from the method's RMSE at the shortest (or the
            // longest, where higher) down to what the bound leaves at the longest.
            let floor = bound.map_or(0.0, |b| b.rmse_cm_s.min(long));
            let worst = curve[0].1.max(long);
            let index = calibration_time_index(&curve, tolerance_band(tolerance, worst, floor));
            let to_bound =
                bound.and_then(|b| index_within(&curve, b.rmse_cm_s * (1.0 + tolerance)));
            let shortest_s = windows.iter().copied().fold(f64::INFINITY, f64::min);
            let index = index
                .filter(|_| ends_at_the_bound(curves, dvl, (shortest_s, bound), long, tolerance));
            Some(CalibrationTimeRow {
                dvl: dvl.to_string(),
                estimator,
                error_model,
                t_conv_s,
                calibration_time_s: index.map(|i| curve[i].0),
                time_to_bound_s: to_bound.map(|i| curve[i].0),
                rmse_at_time_cm_s: index.map_or(f64::NAN, |i| curve[i].1),
                long_window_rmse_cm_s: long,
                long_window_s: long_s,
                tolerance_pct: 100.0 * tolerance,
            })
        })
        .collect()
}

/// Whether a method of `dvl` whose curve ends at `long` ends within `tolerance` of what
/// an efficient calibration changes over the windows (the bound's own drop from the
/// shortest window, `shortest_s`, to its value at the longest, `bound`: the same for
/// every method of the DVL, not the whole RMSE, floor included) above the bound; one
/// that does not has settled on a value worse than the data allow, and has no
/// calibration time. True where there is no bound.
fn ends_at_the_bound(
    curves: &[HeldOutRow],
    dvl: &str,
    (shortest_s, bound): (f64, Option<&HeldOutRow>),
    long: f64,
    tolerance: f64,
) -> bool {
    let Some(last) = bound else {
        return true;
    };
    let first = bound_at(curves, dvl, shortest_s).map_or(last.rmse_cm_s, |b| b.rmse_cm_s);
    long <= last.rmse_cm_s + tolerance_band(tolerance, first, last.rmse_cm_s)
}

/// The last point of `dvl`'s bound curve up to `length_s` (the longest window, where
/// every method's curve ends, or the shortest).
fn bound_at<'a>(curves: &'a [HeldOutRow], dvl: &str, length_s: f64) -> Option<&'a HeldOutRow> {
    curves
        .iter()
        .filter(|r| {
            r.dvl == dvl
                && r.estimator == EstimatorKind::Bound
                && r.length_s <= length_s
                && r.rmse_cm_s.is_finite()
        })
        .max_by(|a, b| a.length_s.total_cmp(&b.length_s))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::evaluate::rmse_cm_s;

    #[test]
    fn the_score_from_sums_is_the_rmse_of_the_samples() {
        let truth: Vec<Vec3> = (0..50)
            .map(|t| t as f64)
            .map(|t| {
                [
                    1.5 + 0.2 * (t / 7.0).sin(),
                    0.3 * (t / 5.0).cos(),
                    0.02 * t.sin(),
                ]
            })
            .collect();
        let dvl: Vec<Vec3> = truth
            .iter()
            .enumerate()
            .map(|(i, v)| {
                let wobble = 0.01 * ((i * 7919) % 13) as f64 / 13.0;
                [
                    1.01 * v[0] + wobble,
                    1.01 * v[1] - wobble,
                    1.01 * v[2] + 0.007,
                ]
            })
            .collect();
        let mut score = HeldOutScore::default();
        score.add(&dvl[..20], &truth[..20]);
        score.add(&dvl[20..], &truth[20..]);
        for correction in [
            Correction::NONE,
            Correction {
                scale: [0.01, 0.012, -0.003],
                bias_m_s: [0.001, -0.002, 0.007],
            },
        ] {
            let direct = rmse_cm_s(&correction, &dvl, &truth);
            assert!((score.rmse_cm_s(&correction) - direct).abs() < 1e-10 * direct);
        }
        let broken = Correction {
            scale: [f64::NAN; 3],
            bias_m_s: [0.0; 3],
        };
        assert!(
            score.rmse_cm_s(&broken).is_nan(),
            "a NaN term scores NaN, not 0"
        );
    }

    #[test]
    fn the_calibration_time_is_where_the_curve_stays_within_the_tolerance() {
        // Last point 1.0: within 10 % of it means from 0.9 to 1.1.
        let within = |curve: &[(f64, f64)], tolerance: f64| {
            calibration_time_index(curve, tolerance_band(tolerance, 1.0, 0.0))
        };
        let curve = [
            (1.0, 5.0),
            (2.0, 1.05),
            (3.0, 1.2),
            (4.0, 1.09),
            (5.0, 1.08),
            (6.0, 1.0),
        ];
        assert_eq!(within(&curve, 0.1), Some(3));
        assert_eq!(within(&curve, 0.25), Some(1));
        assert_eq!(within(&curve, 5.0), Some(0));
        // A curve that rises to its last value is within only once it is near it.
        let rising = [(1.0, 0.5), (2.0, 0.95), (3.0, 1.0)];
        assert_eq!(within(&rising, 0.1), Some(1));
        // A point that cannot be scored (NaN) is not within.
        let gap = [(1.0, 1.0), (2.0, f64::NAN), (3.0, 1.0)];
        assert_eq!(within(&gap, 0.1), Some(2));
        assert_eq!(within(&[(1.0, f64::INFINITY)], 0.1), None);
        // On a floor of 0.95 a tolerance of 10 % is of the 0.05 above it: within
        // 0.995 to 1.005, only at the last point.
        assert_eq!(
            calibration_time_index(&curve, tolerance_band(0.1, 1.0, 0.95)),
            Some(5)
        );
        // Against a common target: never, when the curve ends above it.
        assert_eq!(index_within(&curve, 0.95), None);
        assert_eq!(index_within(&curve, 1.2), Some(1));
    }
}
