//! A value axis that gives a crowded group of values room. Given a panel's values,
//! [`BrokenAxis::fit`] leaves out far values and values of rounding size as
//! [`Scale::fit_values`] does (each is drawn at the edge with its number), and then,
//! when the values left span less than a decade and fall in two groups with a wide
//! empty gap between them (most lines near 6 cm/s, one series near 6.4), breaks the
//! axis in that gap: each group gets its own linear [`Scale`] and a share of the panel
//! by how many values it holds, and the gap shrinks to a narrow band, drawn shaded,
//! through which the lines that cross it still run. Otherwise the axis is the one
//! [`Scale::fit`] chooses, linear or logarithmic. Like [`Scale`], a [`BrokenAxis`] is a
//! plotters coordinate that labels its own ticks.
//! In: a panel's values. Out: its axis.

use super::scale::{Scale, cut_above, pixel_at};
use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};
use std::ops::Range;

/// How many decades below the highest value the axis reaches at most (as
/// [`Scale::fit_values`]).
const MAX_DECADES: i32 = 4;
/// The axis breaks at a gap between values at least this share of their span.
const BREAK_GAP_SHARE: f64 = 0.25;
/// The share of the axis the band of the gap takes.
const GAP_BAND: f64 = 0.05;
/// Above a group with values cut above it, room for their marks: this share of the
/// group's span.
const CUT_HEADROOM: f64 = 0.25;
/// The least share of the axis either group takes.
const MIN_GROUP_SHARE: f64 = 0.2;

/// The part above the break of a [`BrokenAxis`].
#[derive(Debug, Clone, PartialEq)]
struct Upper {
    scale: Scale,
    /// Where along the axis (0 at its start, 1 at its end) the lower part ends.
    lower_end: f64,
    /// Where along the axis the upper part starts.
    upper_start: f64,
}

/// A value axis: one [`Scale`], or two with a break between them.
#[derive(Debug, Clone, PartialEq)]
pub struct BrokenAxis {
    lower: Scale,
    upper: Option<Upper>,
}

impl BrokenAxis {
    /// The axis for the `values` of a panel, leaving out at most `most` far values:
    /// broken when two groups of them lie far apart, as the module says.
    pub fn fit(values: &[f64], most: usize) -> BrokenAxis {
        let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
        let highest = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let floor = highest / 10f64.powi(MAX_DECADES);
        let near = |floor: f64| {
            finite
                .iter()
                .copied()
                .filter(move |v| highest <= 0.0 || *v < 0.0 || *v >= floor)
        };
        let cut = cut_above(&near(floor).collect::<Vec<_>>(), most).unwrap_or(f64::INFINITY);
        // Within reach of the highest value kept, not of the far ones cut.
        let kept_highest = near(floor)
            .filter(|v| *v <= cut)
            .fold(f64::NEG_INFINITY, f64::max);
        let floor = floor.min(kept_highest / 10f64.powi(MAX_DECADES));
        let mut kept: Vec<f64> = near(floor).filter(|v| *v <= cut).collect();
        kept.sort_by(f64::total_cmp);
        let whole = || {
            let (low, high) = (kept.first().copied(), kept.last().copied());
            BrokenAxis {
                lower: Scale::fit(
                    low.unwrap_or(f64::INFINITY),
                    high.unwrap_or(f64::NEG_INFINITY),
                ),
                upper: None,
            }
        };
        let (Some(&low), Some(&high)) = (kept.first(), kept.last()) else {
            return whole();
        };
        if kept.len() < 4 || (low > 0.0 && high / low >= 10.0) || high <= low {
            return whole();
        }
        // The widest gap between neighbouring values.
        let Some(at) = (1..kept.len())
            .max_by(|a, b| (kept[*a] - kept[*a - 1]).total_cmp(&(kept[*b] - kept[*b - 1])))
        else {
            return whole();
        };
        if kept[at] - kept[at - 1] < BREAK_GAP_SHARE * (high - low) {
            return whole();
        }
        let (below, above) = kept.split_at(at);
        let lower = Scale::fit(below[0], below[below.len() - 1]);
        let (first, last) = (above[0], above[above.len() - 1]);
        // Room above the group for the marks of the values cut above it.
        let headroom = if cut.is_finite() {
            CUT_HEADROOM * (last - first)
        } else {
            0.0
        };
        let upper = Scale::fit(first, last + headroom);
        if lower.range().end >= upper.range().start {
            return whole();
        }
        let share = (below.len() as f64 / kept.len() as f64)
            .clamp(MIN_GROUP_SHARE, 1.0 - MIN_GROUP_SHARE - GAP_BAND);
        BrokenAxis {
            lower,
            upper: Some(Upper {
                scale: upper,
                lower_end: share,
                upper_start: share + GAP_BAND,
            }),
        }
    }

    /// Whether the axis is logarithmic.
    pub fn is_log(&self) -> bool {
        self.upper.is_none() && self.lower.is_log()
    }

    /// The values of the gap's band, bottom to top, when the axis is broken.
    pub fn gap(&self) -> Option<Range<f64>> {
        let upper = self.upper.as_ref()?;
        Some(self.lower.range().end..upper.scale.range().start)
    }

    fn top(&self) -> &Scale {
        self.upper
            .as_ref()
            .map_or(&self.lower, |upper| &upper.scale)
    }

    /// Whether `value` lies beyond either end of the axis.
    pub fn is_cut(&self, value: f64) -> bool {
        value > self.top().range().end || self.is_below(value)
    }

    /// Whether `value` lies below the start of the axis.
    pub fn is_below(&self, value: f64) -> bool {
        self.lower.is_below(value)
    }

    /// Where `value` is drawn: itself, or the end of the axis it lies beyond.
    pub fn shown(&self, value: f64) -> f64 {
        value.clamp(self.lower.range().start, self.top().range().end)
    }

    /// The ticks, in ascending order, each with its label.
    fn ticks(&self) -> Vec<(f64, String)> {
        let parts = std::iter::once(&self.lower).chain(self.upper.as_ref().map(|u| &u.scale));
        parts
            .flat_map(|scale| scale.ticks().map(|t| (t, scale.label(t))))
            .collect()
    }

    /// Where `value` lies along the axis: 0 at its start, 1 at its end.
    pub fn fraction(&self, value: f64) -> f64 {
        let Some(upper) = &self.upper else {
            return self.lower.fraction(value);
        };
        let (gap_low, gap_high) = (self.lower.range().end, upper.scale.range().start);
        if value <= gap_low {
            self.lower.fraction(value) * upper.lower_end
        } else if value >= gap_high {
            upper.upper_start + upper.scale.fraction(value) * (1.0 - upper.upper_start)
        } else {
            let within = (value - gap_low) / (gap_high - gap_low);
            upper.lower_end + within * (upper.upper_start - upper.lower_end)
        }
    }
}

impl Ranged for BrokenAxis {
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
            self.ticks().into_iter().map(|(tick, _)| tick).collect()
        }
    }

    fn range(&self) -> Range<f64> {
        self.lower.range().start..self.top().range().end
    }
}

impl ValueFormatter<f64> for BrokenAxis {
    fn format_ext(&self, value: &f64) -> String {
        self.ticks()
            .into_iter()
            .find(|(tick, _)| tick == value)
            .map_or_else(|| self.top().label(*value), |(_, label)| label)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper's DVL1 with the model-based estimators: 40 values near 6 cm/s, least
    /// squares EM3 near 6.35 and EM5 far above.
    fn paper_dvl1() -> Vec<f64> {
        let near = (0..40).map(|i| 5.87 + 0.0625 * f64::from(i % 5) + 0.001 * f64::from(i));
        let em3 = [6.37, 6.34, 6.33, 6.31, 6.30];
        let em5 = [14.3, 11.7, 10.4, 9.0, 9.13];
        near.chain(em3).chain(em5).collect()
    }

    #[test]
    fn two_groups_far_apart_each_get_a_part_of_the_axis() {
        let axis = BrokenAxis::fit(&paper_dvl1(), 5);
        let upper = axis.upper.clone().expect("broken");
        // The far series is cut, the near group has the most room.
        assert!(axis.is_cut(14.3) && axis.is_cut(9.0) && !axis.is_cut(6.37));
        assert!(!axis.is_log());
        assert_eq!(upper.lower_end, 1.0 - MIN_GROUP_SHARE - GAP_BAND);
        let gap = axis.gap().unwrap();
        assert!(gap.start > 6.12 && gap.end < 6.30, "{gap:?}");
        // The parts meet the band, and values in the gap lie in it.
        assert!((axis.fraction(gap.start) - upper.lower_end).abs() < 1e-12);
        assert!((axis.fraction(gap.end) - upper.upper_start).abs() < 1e-12);
        let middle = axis.fraction((gap.start + gap.end) / 2.0);
        assert!(middle > upper.lower_end && middle < upper.upper_start);
        assert!(axis.fraction(5.9) < axis.fraction(6.1) && axis.fraction(6.37) <= 1.0);
        // Both parts are ticked and labelled.
        let ticks = axis.ticks();
        assert!(ticks.iter().any(|(t, _)| *t < 6.0) && ticks.iter().any(|(t, _)| *t > 6.25));
        assert_eq!(axis.format_ext(&6.0), "6.0");
        assert_eq!(axis.format_ext(&6.32), "6.32");
    }

    #[test]
    fn spread_values_or_decades_are_one_scale() {
        // The quick DVL1: no wide gap.
        let even: Vec<f64> = (0..30).map(|i| 5.8 + 0.03 * f64::from(i)).collect();
        let axis = BrokenAxis::fit(&even, 5);
        assert_eq!(
            axis,
            BrokenAxis {
                lower: Scale::fit(5.8, 5.8 + 0.03 * 29.0),
                upper: None
            }
        );
        // DVL2 spans decades: logarithmic, not broken.
        let axis = BrokenAxis::fit(&[0.058, 0.06, 0.09, 0.1, 0.5, 0.7, 2.1], 5);
        assert!(axis.is_log() && axis.gap().is_none());
    }

    #[test]
    fn small_values_near_the_kept_ones_stay_after_a_far_series_is_cut() {
        // A floor of 0.059 cm/s beside lines up to 1.25 and one series in the
        // thousands: the thousands are cut, and the floor is on the axis.
        let near = [0.059, 0.06, 0.09, 0.2, 0.7, 0.75, 1.2, 1.25];
        let mut values: Vec<f64> = near.iter().flat_map(|v| [*v; 5]).collect();
        values.extend([320.0, 622.0, 684.0, 1465.0, 1497.0]);
        let axis = BrokenAxis::fit(&values, 5);
        assert!(axis.is_cut(1497.0) && !axis.is_cut(0.059), "{axis:?}");
        assert!(axis.is_log());
        // Values of rounding size are still left below.
        let axis = BrokenAxis::fit(&[1e-12, 5.8, 5.9, 6.0, 6.1, 6.2], 1);
        assert!(axis.is_below(1e-12));
    }
}
