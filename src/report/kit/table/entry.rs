//! One cell of a report's tables ([`Entry`]), written by the Markdown and the LaTeX
//! rendering each with its own signs ([`Signs`]), and the characters LaTeX sets in math
//! mode. In: a number a report picks from its results. Out: the text of the cell.

use super::{Cell, RmseValue, Signs};
use crate::report::kit::numbers::decimals;

/// One cell, written by each rendering with its own signs.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Entry {
    Text(String),
    /// A mean RMSE and the half-width of its 95 % interval, cm/s.
    Rmse {
        mean_cm_s: f64,
        ci95_cm_s: f64,
    },
    Ratio(f64),
    /// A mean RMSE with its interval, and its ratio to no calibration in brackets.
    RmseRatio {
        mean_cm_s: f64,
        ci95_cm_s: f64,
        ratio: f64,
    },
    /// A number in a readable unit, three decimals.
    Value(f64),
    /// A mean paired difference, cm/s, its 95 % interval, and on how many of `of` pairs
    /// the first was lower.
    Difference {
        mean_cm_s: f64,
        ci95_cm_s: f64,
        lower: usize,
        of: usize,
    },
    /// A term in its readable unit, its standard deviation, whether it is seen.
    Term {
        value: f64,
        std: f64,
        seen: bool,
    },
    /// An RMSE of the paper's layout, beside its published value where there is one.
    Published(Cell),
    Missing,
}

impl Entry {
    pub(crate) fn text(&self, signs: &Signs) -> String {
        match self {
            Entry::Text(text) => text.clone(),
            Entry::Rmse {
                mean_cm_s,
                ci95_cm_s,
            } => RmseValue {
                rmse_cm_s: *mean_cm_s,
                ci_cm_s: Some(*ci95_cm_s),
                detail: None,
            }
            .text(signs),
            Entry::Ratio(ratio) => format!("{ratio:.2}"),
            Entry::RmseRatio {
                mean_cm_s,
                ci95_cm_s,
                ratio,
            } => {
                let rmse = Entry::Rmse {
                    mean_cm_s: *mean_cm_s,
                    ci95_cm_s: *ci95_cm_s,
                };
                format!("{} ({ratio:.2})", rmse.text(signs))
            }
            Entry::Difference {
                mean_cm_s,
                ci95_cm_s,
                lower,
                of,
            } => {
                let mean = format!("{mean_cm_s:+.2}").replace('-', signs.minus);
                format!(
                    "{mean}{}{ci95_cm_s:.2} (lower on {lower} of {of})",
                    signs.plus_minus
                )
            }
            Entry::Value(value) => {
                let text = format!("{value:.3}");
                match text.strip_prefix('-') {
                    Some(magnitude) => format!("{}{magnitude}", signs.minus),
                    None => text,
                }
            }
            Entry::Term { value, std, seen } => {
                let decimals = decimals(*std);
                let value = format!("{value:.decimals$}");
                let value = match value.strip_prefix('-') {
                    Some(magnitude) => format!("{}{magnitude}", signs.minus),
                    None => value,
                };
                let std = if std.is_finite() {
                    format!("{std:.decimals$}")
                } else {
                    "∞".into()
                };
                let unseen = if *seen { "" } else { " (not seen)" };
                format!("{value}{}{std}{unseen}", signs.plus_minus)
            }
            Entry::Published(cell) => cell.ours.text(signs),
            Entry::Missing => "—".into(),
        }
    }
}

/// The characters of our text and of the bound's reasons that LaTeX sets in math mode
/// (or that its default font would set as other glyphs: `<` and `>`), and how.
const MATH: [(char, &str); 16] = [
    ('±', "$\\pm$"),
    ('σ', "$\\sigma$"),
    ('τ', "$\\tau$"),
    ('δ', "$\\delta$"),
    ('ω', "$\\omega$"),
    ('ρ', "$\\rho$"),
    ('×', "$\\times$"),
    ('∞', "$\\infty$"),
    ('−', "$-$"),
    ('≥', "$\\geq$"),
    ('≤', "$\\leq$"),
    ('>', "$>$"),
    ('<', "$<$"),
    ('°', "$^\\circ$"),
    ('→', "$\\to$"),
    ('|', "$|$"),
];

/// `text` with the characters of [`MATH`] written as LaTeX sets them.
pub(crate) fn symbols(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match MATH.iter().find(|(m, _)| *m == c) {
            Some((_, latex)) => out.push_str(latex),
            None => out.push(c),
        }
    }
    out
}
