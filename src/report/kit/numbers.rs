//! How the report writes a number, wherever it shows one: a value with three
//! significant digits ([`three_digits`]: a figure's cut value, a tick between round
//! ones, a term in a comparison's or a bound's words) and the decimals that show a
//! standard deviation with two significant digits ([`decimals`]: a term beside its σ
//! in the tables). In: a number. Out: its text, or its count of decimals.

/// A value with three significant digits, or all of its integer digits.
pub fn three_digits(value: f64) -> String {
    if value != 0.0 && value.abs() < 1e-3 {
        return format!("{value:.2e}");
    }
    let magnitude = value.abs().log10().floor() as i32;
    let decimals = (2 - magnitude).max(0) as usize;
    format!("{value:.decimals$}")
}

/// The decimals that show `std` with two significant digits (0 to 4), and a value
/// beside it to the same place; 2 when it is not a positive number.
pub(crate) fn decimals(std: f64) -> usize {
    if !(std.is_finite() && std > 0.0) {
        return 2;
    }
    (1 - std.log10().floor() as i32).clamp(0, 4) as usize
}
