//! Checks `[grid]`. In: each axis as written, a list of `values` or a `start`, `stop`
//! (inclusive) and `step`. Out: the [`Grid`], each axis expanded into its values (a
//! range rounded to 1e-9, so that 0.1 + 2 × 0.1 is 0.3), each value an error term in
//! its range, and not too many combinations.
//!
//! [`Grid`]: crate::spec::Grid

use super::{Faults, check_noise, check_scale};
use crate::spec::file::{self, AxisFile};
use crate::spec::{Grid, ranges};

/// Checks `[grid]`: each axis expanded, error terms in their ranges, and not too many
/// combinations.
pub(in crate::spec) fn check_grid(grid: file::GridFile, faults: &mut Faults) -> Grid {
    let file::GridFile {
        scale_pct,
        bias_cm_s,
        noise_cm_s,
    } = grid;
    let grid = Grid {
        scale_pct: expand_axis("grid.scale_pct", &scale_pct, faults),
        bias_cm_s: expand_axis("grid.bias_cm_s", &bias_cm_s, faults),
        noise_cm_s: expand_axis("grid.noise_cm_s", &noise_cm_s, faults),
    };
    // Values that are not finite numbers are reported by `expand_axis`.
    let finite = |values: &[f64]| -> Vec<(usize, f64)> {
        values
            .iter()
            .copied()
            .enumerate()
            .filter(|(_, v)| v.is_finite())
            .collect()
    };
    for (i, value) in finite(&grid.scale_pct) {
        check_scale(&format!("grid.scale_pct[{i}]"), value, faults);
    }
    for (i, value) in finite(&grid.bias_cm_s) {
        ranges::VELOCITY_ERROR_CM_S.check(&format!("grid.bias_cm_s[{i}]"), value.abs(), faults);
    }
    for (i, value) in finite(&grid.noise_cm_s) {
        check_noise(&format!("grid.noise_cm_s[{i}]"), value, faults);
    }
    let combinations = grid.scale_pct.len() * grid.bias_cm_s.len() * grid.noise_cm_s.len();
    ranges::GRID_COMBINATIONS.check("grid", combinations as f64, faults);
    grid
}

/// Expands `values` or `start`/`stop`/`step` into the list of grid values.
fn expand_axis(key: &str, axis: &AxisFile, faults: &mut Faults) -> Vec<f64> {
    let values = match axis {
        AxisFile {
            values: Some(values),
            start: None,
            stop: None,
            step: None,
        } => values.clone(),
        AxisFile {
            values: None,
            start: Some(start),
            stop: Some(stop),
            step: Some(step),
        } => match expand_range(key, *start, *stop, *step, faults) {
            Some(values) => values,
            None => return Vec::new(),
        },
        _ => {
            faults.add(
                key,
                "give either values = [...] or all of start, stop and step",
            );
            return Vec::new();
        }
    };
    if values.is_empty() {
        faults.add(
            key,
            "is empty: the grid needs at least one value on every axis",
        );
    }
    if let Some(why) = ranges::GRID_AXIS_VALUES.exceeded(values.len() as f64) {
        faults.add(key, why);
        return Vec::new();
    }
    // -0.0 is 0.0, as `==` has it.
    let mut listed = std::collections::HashSet::new();
    for (i, value) in values.iter().enumerate() {
        if !value.is_finite() {
            faults.add(
                format!("{key}.values[{i}]"),
                format!("{value} must be a finite number"),
            );
        } else if !listed.insert((value + 0.0).to_bits()) {
            faults.add(
                format!("{key}.values[{i}]"),
                format!(
                    "{value} is listed twice: every combination with it would be generated twice"
                ),
            );
        }
    }
    values
}

/// The values from `start` to `stop` (inclusive) every `step`, each rounded to 1e-9; a
/// fault at `key` when the range is empty, too fine, or not a whole number of steps.
fn expand_range(
    key: &str,
    start: f64,
    stop: f64,
    step: f64,
    faults: &mut Faults,
) -> Option<Vec<f64>> {
    if !(start.is_finite() && stop.is_finite() && step.is_finite() && step > 0.0 && stop >= start) {
        faults.add(key, format!("start {start}, stop {stop}, step {step}: step must be positive and stop at least start"));
        return None;
    }
    let steps = (stop - start) / step;
    // A quotient that overflows to infinity is too many values too.
    let count = (steps.round() + 1.0).min(f64::MAX);
    if let Some(why) = ranges::GRID_AXIS_VALUES.exceeded(count) {
        faults.add(key, why);
        return None;
    }
    if (steps - steps.round()).abs() > 1e-6 {
        faults.add(
            key,
            format!("stop {stop} is not start {start} plus a whole number of steps {step}"),
        );
        return None;
    }
    // Rounded to 1e-9 so that 0.1 + 2 × 0.1 prints and compares as 0.3.
    Some(
        (0..=steps.round() as usize)
            .map(|i| ((start + i as f64 * step) * 1e9).round() / 1e9)
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use crate::spec::fixture::{quick_faults, quick_spec};

    #[test]
    fn a_range_expands_to_its_values_rounded() {
        let spec = quick_spec(&["grid.scale_pct={start = 0.1, stop = 0.3, step = 0.1}"]);
        assert_eq!(spec.grid.scale_pct, [0.1, 0.2, 0.3]);
        let set = "grid.scale_pct={start = 0, stop = 1, step = 0.3}";
        assert_eq!(
            quick_faults(&[set]),
            format!(
                "--set {set}: grid.scale_pct: stop 1 is not start 0 plus a whole number of steps 0.3"
            )
        );
        let set = "grid.bias_cm_s={values = [1.0], step = 1.0}";
        assert_eq!(
            quick_faults(&[set]),
            format!(
                "--set {set}: grid.bias_cm_s: give either values = [...] or all of start, stop and step"
            )
        );
    }
}
