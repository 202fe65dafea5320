//! Numeric axes that read at any range. Given the values a panel shows, [`Scale::fit`]
//! chooses a linear axis when they span less than a decade and a logarithmic one
//! otherwise, with at least [`MIN_TICKS`] labelled ticks at round numbers;
//! [`Scale::fit_values`] also ends the axis below one value, or one series, lying far
//! above all the others ([`cut_above`]), and above values more than `MAX_DECADES`
//! below the highest (a floor of 10⁻¹² cm/s when a DVL has no noise), so that the
//! others keep the panel, and the figure draws such a value at the edge with its
//! number written on it ([`three_digits`]). A [`Scale`] is a plotters coordinate:
//! charts use it as an axis directly, and it labels its own ticks.
//! In: a panel's values. Out: its axis and ticks.

use crate::report::kit::numbers::three_digits;
use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};
use std::ops::Range;

/// The fewest labelled ticks an axis shows.
pub const MIN_TICKS: usize = 3;

/// Values are cut when the axis without them would be at most this share of the axis
/// with them: the others would be squashed into that share of the panel.
const OUTLIER_SHARE: f64 = 0.25;

/// How many decades below a panel's highest value its axis reaches at most: values
/// further below, such as an RMSE of rounding size, are drawn at the lower edge.
const MAX_DECADES: i32 = 4;

/// A numeric axis: its range, whether it is logarithmic, and its ticks with labels.
#[derive(Debug, Clone, PartialEq)]
pub struct Scale {
    range: Range<f64>,
    log: bool,
    ticks: Vec<(f64, String)>,
}

impl Scale {
    /// A linear axis over `range` exactly, ticked at the multiples of the largest step
    /// of 1, 2 or 5 times a power of ten that gives [`MIN_TICKS`] ticks in it.
    pub fn linear(range: Range<f64>) -> Scale {
        let (low, high) = (range.start, range.end);
        let span = high - low;
        let mut exponent = (span.abs().max(1e-300)).log10().ceil() as i32;
        let ticks = loop {
            let candidates = [5, 2, 1].map(|mantissa| linear_ticks(low, high, mantissa, exponent));
            if let Some(ticks) = candidates.into_iter().find(|t| t.len() >= MIN_TICKS) {
                break ticks;
            }
            if exponent < -300 {
                break Vec::new();
            }
            exponent -= 1;
        };
        Scale {
            range,
            log: false,
            ticks,
        }
    }

    /// A logarithmic axis over `range`, which spans a decade or more, ticked at the
    /// powers of ten when [`MIN_TICKS`] of them lie in it, and otherwise at 1, 2 and 5
    /// times them: any decade holds three of 1, 2, 5, 10, 20, 50, …
    /// An axis of things rather than a quantity: thing `i` at `i`, labelled `names[i]`.
    pub fn named(names: &[String]) -> Scale {
        Scale {
            range: -0.5..names.len() as f64 - 0.5,
            log: false,
            ticks: names
                .iter()
                .enumerate()
                .map(|(i, name)| (i as f64, name.clone()))
                .collect(),
        }
    }

    fn logarithmic(range: Range<f64>) -> Scale {
        let decades = log_ticks(range.start, range.end, &[1]);
        let ticks = if decades.len() >= MIN_TICKS {
            decades
        } else {
            log_ticks(range.start, range.end, &[1, 2, 5])
        };
        Scale {
            range,
            log: true,
            ticks,
        }
    }

    /// An axis for the values `low..=high` of a panel, with room around them:
    /// logarithmic when they are all positive and span a decade or more, linear
    /// otherwise (never below 0 for values that are not). No finite values: 0 to 1.
    pub fn fit(low: f64, high: f64) -> Scale {
        let (low, high) = if !(low.is_finite() && high.is_finite()) {
            (0.0, 1.0)
        } else if high > low {
            (low, high)
        } else {
            // One value: a span of a tenth of it, or of 1 around 0.
            let half = if low == 0.0 { 0.5 } else { 0.05 * low.abs() };
            (low - half, high + half)
        };
        if low > 0.0 && high / low >= 10.0 {
            return Scale::logarithmic(low / 1.3..high * 1.3);
        }
        let pad = 0.06 * (high - low);
        let start = if low >= 0.0 {
            (low - pad).max(0.0)
        } else {
            low - pad
        };
        Scale::linear(start..high + pad)
    }

    /// An axis for the values of a panel, as [`Scale::fit`] makes it, ending below at
    /// most `most` far values ([`cut_above`]): draw each value at [`Scale::shown`], and
    /// mark those that [`Scale::is_cut`] with their number.
    /// Values more than `MAX_DECADES` below the highest are left below the axis.
    pub fn fit_values(values: &[f64], most: usize) -> Scale {
        let highest = values
            .iter()
            .filter(|v| v.is_finite())
            .fold(f64::NEG_INFINITY, |high, v| high.max(*v));
        let floor = highest / 10f64.powi(MAX_DECADES);
        let near: Vec<f64> = values
            .iter()
            .copied()
            .filter(|v| v.is_finite() && (highest <= 0.0 || *v < 0.0 || *v >= floor))
            .collect();
        let cut = cut_above(&near, most).unwrap_or(f64::INFINITY);
        let (low, high) = near
            .iter()
            .filter(|v| **v <= cut)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(*v), hi.max(*v))
            });
        Scale::fit(low, high)
    }

    /// Whether the axis is logarithmic.
    pub fn is_log(&self) -> bool {
        self.log
    }

    /// Whether `value` lies beyond either end of the axis.
    pub fn is_cut(&self, value: f64) -> bool {
        value > self.range.end || self.is_below(value)
    }

    /// Whether `value` lies below the start of the axis.
    pub fn is_below(&self, value: f64) -> bool {
        value < self.range.start
    }

    /// Where `value` is drawn: itself, or the end of the axis it lies beyond.
    pub fn shown(&self, value: f64) -> f64 {
        value.clamp(self.range.start, self.range.end)
    }

    /// The ticks, in ascending order.
    pub fn ticks(&self) -> impl Iterator<Item = f64> + '_ {
        self.ticks.iter().map(|(value, _)| *value)
    }

    /// The label of tick `value` (of any other value, its three significant digits).
    pub fn label(&self, value: f64) -> String {
        self.ticks
            .iter()
            .find(|(tick, _)| *tick == value)
            .map_or_else(|| three_digits(value), |(_, label)| label.clone())
    }

    /// Where `value` lies along the axis: 0 at its start, 1 at its end.
    pub fn fraction(&self, value: f64) -> f64 {
        let Range { start, end } = self.range;
        if self.log {
            let value = value.max(f64::MIN_POSITIVE);
            (value / start).ln() / (end / start).ln()
        } else {
            (value - start) / (end - start)
        }
    }
}

/// The multiples of `mantissa` × 10^`exponent` within `low..=high`, labelled with the
/// decimals the step needs. Each is computed as an integer over a power of ten, so it
/// is the double nearest its decimal value (6.2, not 6.200000000000001).
fn linear_ticks(low: f64, high: f64, mantissa: i64, exponent: i32) -> Vec<(f64, String)> {
    let scale = 10f64.powi(exponent.abs());
    let of = |units: i64| {
        if exponent >= 0 {
            units as f64 * scale
        } else {
            units as f64 / scale
        }
    };
    let step = of(mantissa);
    let slack = 1e-9 * (high - low).abs();
    let first = ((low - slack) / step).ceil() as i64;
    let last = ((high + slack) / step).floor() as i64;
    if last - first > 1000 {
        return Vec::new();
    }
    let decimals = (-exponent).max(0) as usize;
    (first..=last)
        .map(|k| {
            let value = of(k * mantissa);
            let value = if value == 0.0 { 0.0 } else { value };
            (value, format!("{value:.decimals$}"))
        })
        .collect()
}

/// `mantissas` times each power of ten, within `low..=high`, each labelled with its
/// one significant digit.
fn log_ticks(low: f64, high: f64, mantissas: &[u32]) -> Vec<(f64, String)> {
    let slack = 1e-9;
    let first = (low * (1.0 - slack)).log10().floor() as i32;
    let last = (high * (1.0 + slack)).log10().floor() as i32;
    let mut ticks = Vec::new();
    for exponent in first..=last {
        let scale = 10f64.powi(exponent.abs());
        for &mantissa in mantissas {
            let value = if exponent >= 0 {
                f64::from(mantissa) * scale
            } else {
                f64::from(mantissa) / scale
            };
            if value >= low * (1.0 - slack) && value <= high * (1.0 + slack) {
                let decimals = (-exponent).max(0) as usize;
                ticks.push((value, format!("{value:.decimals$}")));
            }
        }
    }
    ticks
}

/// The largest value a panel's axis should hold when a few values lie far above the
/// rest: the fewest of the highest values, at most `most` (one value, or one series of
/// a line figure) and at most a sixth of them, whose removal leaves the others within
/// a quarter of the span of all, measured on a log scale when the values span a decade
/// or more, as the axis will be. `None` when no values are that far, or fewer than
/// three are given.
pub fn cut_above(values: &[f64], most: usize) -> Option<f64> {
    let mut sorted: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    let count = sorted.len();
    if count < 3 {
        return None;
    }
    let (low, highest) = (sorted[0], sorted[count - 1]);
    let log = low > 0.0 && highest / low >= 10.0;
    let distance = |value: f64| {
        if log { (value / low).ln() } else { value - low }
    };
    let all = distance(highest);
    if all <= 0.0 {
        return None;
    }
    (1..=most.min(count / 6).max(1))
        .map(|cut| sorted[count - 1 - cut])
        .find(|kept| distance(*kept) <= OUTLIER_SHARE * all)
}

/// The pixel at `fraction` of the way from `limit.0` to `limit.1`, as every axis of
/// these figures maps a value (far values clamped, so they stay drawable).
pub fn pixel_at(fraction: f64, limit: (i32, i32)) -> i32 {
    let length = f64::from(limit.1 - limit.0);
    let position = (fraction * length).clamp(-1e6, 1e6);
    limit.0 + (position + 1e-3).floor() as i32
}

impl Ranged for Scale {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        pixel_at(self.fraction(*value), limit)
    }

    /// The ticks, as the bold mesh lines; no light lines.
    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks().collect()
        }
    }

    fn range(&self) -> Range<f64> {
        self.range.clone()
    }
}

impl ValueFormatter<f64> for Scale {
    fn format_ext(&self, value: &f64) -> String {
        self.label(*value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ticks(scale: &Scale) -> Vec<f64> {
        scale.ticks().collect()
    }

    fn labels(scale: &Scale) -> Vec<String> {
        scale.ticks().map(|t| scale.label(t)).collect()
    }

    #[test]
    fn narrow_ranges_get_round_linear_ticks() {
        let scale = Scale::linear(5.8..6.4);
        assert!(!scale.log);
        assert_eq!(ticks(&scale), [5.8, 6.0, 6.2, 6.4]);
        assert_eq!(labels(&scale), ["5.8", "6.0", "6.2", "6.4"]);

        let scale = Scale::linear(0.05..0.09);
        assert_eq!(ticks(&scale), [0.05, 0.06, 0.07, 0.08, 0.09]);
        assert_eq!(labels(&scale), ["0.05", "0.06", "0.07", "0.08", "0.09"]);

        // The step is the largest that still gives three ticks: 10, not 5 or 20.
        assert_eq!(ticks(&Scale::linear(0.0..25.0)), [0.0, 10.0, 20.0]);
        assert_eq!(ticks(&Scale::linear(-100.0..45.0)), [-100.0, -50.0, 0.0]);
        let rate = Scale::linear(0.0005..0.002);
        assert_eq!(labels(&rate), ["0.0005", "0.0010", "0.0015", "0.0020"]);
    }

    #[test]
    fn a_narrow_panel_of_data_is_linear_and_a_wide_one_logarithmic() {
        // The DVL1 Monte Carlo spread: all near 6.
        let scale = Scale::fit(5.8, 6.4);
        assert!(!scale.log);
        assert_eq!(ticks(&scale), [5.8, 6.0, 6.2, 6.4]);
        let scale = Scale::fit(0.05, 0.09);
        assert!(!scale.log);
        assert_eq!(ticks(&scale), [0.05, 0.06, 0.07, 0.08, 0.09]);
        // DVL2 calibration, 0.06 to 2.1 cm/s: log, labelled at 1, 2 and 5.
        let scale = Scale::fit(0.06, 2.1);
        assert!(scale.log);
        assert_eq!(ticks(&scale), [0.05, 0.1, 0.2, 0.5, 1.0, 2.0]);
        assert_eq!(labels(&scale), ["0.05", "0.1", "0.2", "0.5", "1", "2"]);
        // Four decades of loss: powers of ten suffice.
        let scale = Scale::fit(0.01, 200.0);
        assert_eq!(ticks(&scale), [0.01, 0.1, 1.0, 10.0, 100.0]);
        // A decade that starts just above a power of ten still holds three ticks.
        assert_eq!(ticks(&Scale::logarithmic(1.01..10.1)), [2.0, 5.0, 10.0]);
        // Values from 0 get no negative axis; no values get 0 to 1.
        assert_eq!(ticks(&Scale::fit(0.0, 0.5)), [0.0, 0.2, 0.4]);
        assert_eq!(
            ticks(&Scale::fit(f64::INFINITY, f64::NEG_INFINITY)),
            [0.0, 0.5, 1.0]
        );
        // A single value gets a span around it.
        assert_eq!(ticks(&Scale::fit(6.0, 6.0)), [5.8, 6.0, 6.2]);
        for (low, high) in [
            (5.8, 6.4),
            (0.05, 0.09),
            (1e-4, 2e-3),
            (-3.0, 1e4),
            (0.7, 0.71),
        ] {
            let scale = Scale::fit(low, high);
            assert!(
                scale.ticks().count() >= MIN_TICKS,
                "{low}..{high}: {scale:?}"
            );
        }
    }

    #[test]
    fn positions_along_the_axis() {
        let scale = Scale::linear(2.0..6.0);
        assert_eq!(scale.fraction(3.0), 0.25);
        assert_eq!(scale.map(&3.0, (0, 400)), 100);
        // A y axis runs from the bottom pixel up.
        assert_eq!(scale.map(&3.0, (400, 0)), 300);
        let scale = Scale::logarithmic(0.1..1000.0);
        assert!((scale.fraction(10.0) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn only_far_values_are_cut() {
        // Least squares EM5 at 20 s beside eleven lines near 6 cm/s.
        let values = [5.9, 6.0, 6.1, 6.3, 7.0, 25.0];
        assert_eq!(cut_above(&values, 1), Some(7.0));
        // A steady spread is not cut.
        assert_eq!(cut_above(&[5.9, 6.0, 6.1, 6.3, 7.0, 8.0], 1), None);
        // Spanning decades, distance is measured in decades: 0.06 to 2.1 is no outlier,
        // 0.06 to 0.1 beside 50 is.
        assert_eq!(cut_above(&[0.06, 0.07, 0.74, 2.1], 1), None);
        assert_eq!(cut_above(&[0.06, 0.07, 0.1, 50.0], 1), Some(0.1));
        assert_eq!(cut_above(&[1.0, 100.0], 1), None);
        // One series of five windows far above 25 values near 6 (least squares EM5 on
        // the paper's DVL1): cut when five may be, not when one may, and never more
        // than a sixth of the values.
        let near: Vec<f64> = (0..25).map(|i| 5.9 + 0.02 * f64::from(i)).collect();
        let far = [9.0, 9.1, 10.4, 11.7, 14.3];
        let mut paper = [near.clone(), far.to_vec()].concat();
        assert_eq!(cut_above(&paper, 5), Some(near[24]));
        assert_eq!(cut_above(&paper, 1), None);
        paper.drain(..12);
        assert_eq!(cut_above(&paper, 5), None);

        let scale = Scale::fit_values(&values, 1);
        assert!(!scale.log);
        assert_eq!(ticks(&scale), [6.0, 6.5, 7.0]);
        assert!(scale.is_cut(25.0) && !scale.is_cut(7.0));
        assert_eq!(scale.shown(25.0), scale.range().end);
        assert_eq!(scale.shown(6.3), 6.3);
    }

    #[test]
    fn values_of_rounding_size_are_left_below_the_axis() {
        // A DVL without noise: its floor is 1e-12 cm/s beside a panel near 6 cm/s, and
        // least squares EM5 far above.
        let values = [
            1e-12, 2e-12, 5.8, 5.9, 6.0, 6.1, 6.2, 6.3, 6.4, 6.4, 6.3, 31.9,
        ];
        let scale = Scale::fit_values(&values, 1);
        assert!(!scale.log);
        assert_eq!(ticks(&scale), [5.8, 6.0, 6.2, 6.4]);
        assert!(scale.is_cut(1e-12) && scale.is_below(1e-12) && scale.is_cut(31.9));
        assert!(!scale.is_below(31.9) && !scale.is_cut(5.8));
        assert_eq!(scale.shown(1e-12), scale.range().start);
        // Within four decades of the highest value, nothing is left out: a log axis.
        let scale = Scale::fit_values(&[0.001, 0.01, 0.1, 1.0, 5.0], 1);
        assert!(scale.log && !scale.is_cut(0.001));
        assert_eq!(labels(&scale), ["0.001", "0.01", "0.1", "1"]);
        assert_eq!(three_digits(1.234e-12), "1.23e-12");
    }
}
