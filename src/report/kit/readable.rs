//! Error terms in units people read, for every table, figure and printed line that
//! shows them: a term's stored name (`lever_arm_x_m`, `bias_x_m_s`,
//! `misalignment_x_rad`, `scale_x`) to a name without its unit suffix, the unit shown
//! and the factor from the stored value ([`readable_term`], from the terms' own table),
//! and why the bound finds a term not seen, in that unit ([`readable_why`]). In: a
//! term's name (and the bound's reason). Out: text. It imports only the kit's number
//! format ([`super::numbers`]) and the terms' table, so the report's tables, its figures and the printed
//! tables of every room all stand above it.

use crate::installation::terms::TermKind;
use crate::report::kit::numbers::three_digits;

/// A term's name for people and its unit, and the factor from the stored value (SI,
/// radians, a fraction for a scale) to that unit, as its kind's row gives them
/// ([`TermKind::of_parameter`]): `lever_arm_x_m` → ("lever arm x", "m", 1),
/// `bias_x_m_s` → ("bias x", "cm/s", 100), `misalignment_x_rad` → degrees, `scale_x` →
/// %. A name no kind gives (the fixes' latency, `fix_latency_s`) is shown with its
/// suffix `_s` or `_m` read as its unit, or else as it is, with no unit.
pub fn readable_term(term: &str) -> (String, &'static str, f64) {
    if let Some((kind, axis)) = TermKind::of_parameter(term) {
        return (
            kind.readable_name(axis),
            kind.unit.symbol(),
            kind.unit.factor(),
        );
    }
    for (suffix, unit) in [("_s", "s"), ("_m", "m")] {
        if let Some(name) = term.strip_suffix(suffix) {
            return (name.replace('_', " "), unit, 1.0);
        }
    }
    (term.replace('_', " "), "", 1.0)
}

/// A value of a reason in its table unit: three significant digits, trailing zeros
/// dropped (0.136, 0.1, 1.02).
fn reason_number(value: f64) -> String {
    let text = three_digits(value);
    if text.contains('.') && !text.contains('e') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// Why a term is not seen, as the bound stored it ("standard deviation 1.361e-1 above
/// its tolerance 1.000e-1; correlated -0.969 with bias_y_m_s"), in the term's table
/// unit and with the other terms' names for people ("standard deviation 0.136 m above
/// its tolerance 0.1 m, correlated -0.969 with bias y"). A reason of another form is
/// kept as it is.
pub fn readable_why(term: &str, why: &str) -> String {
    let (_, unit, factor) = readable_term(term);
    let name = |other: &str| readable_term(other).0;
    let reason = |reason: &str| -> Option<String> {
        if let Some(rest) = reason.strip_prefix("standard deviation ") {
            let (std, tolerance) = rest.split_once(" above its tolerance ")?;
            let [std, tolerance] = [std, tolerance].map(|v| v.trim().parse::<f64>().ok());
            return Some(format!(
                "standard deviation {} {unit} above its tolerance {} {unit}",
                reason_number(factor * std?),
                reason_number(factor * tolerance?)
            ));
        }
        if let Some(rest) = reason.strip_prefix("correlated ") {
            let (correlation, other) = rest.split_once(" with ")?;
            return Some(format!("correlated {correlation} with {}", name(other)));
        }
        let others = reason.strip_prefix("flat together with ")?;
        let others: Vec<String> = others.split(", ").map(name).collect();
        Some(format!("flat together with {}", others.join(", ")))
    };
    why.split("; ")
        .map(|part| reason(part).unwrap_or_else(|| part.to_string()))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::readable_term as readable;
    use super::*;

    #[test]
    fn why_a_term_is_not_seen_reads_in_its_table_unit() {
        assert_eq!(
            readable_why(
                "lever_arm_z_m",
                "standard deviation 1.361e-1 above its tolerance 1.000e-1"
            ),
            "standard deviation 0.136 m above its tolerance 0.1 m"
        );
        assert_eq!(
            readable_why(
                "lever_arm_x_m",
                "standard deviation 4.081e-1 above its tolerance 1.000e-1; correlated -0.969 with bias_y_m_s"
            ),
            "standard deviation 0.408 m above its tolerance 0.1 m, correlated -0.969 with bias y"
        );
        assert_eq!(
            readable_why(
                "bias_z_m_s",
                "standard deviation 1.019e-2 above its tolerance 1.000e-2"
            ),
            "standard deviation 1.02 cm/s above its tolerance 1 cm/s"
        );
        assert_eq!(
            readable_why(
                "misalignment_x_rad",
                "standard deviation 9.734e-3 above its tolerance 8.727e-3"
            ),
            "standard deviation 0.558 deg above its tolerance 0.5 deg"
        );
        assert_eq!(
            readable_why("scale", "correlated -0.970 with bias_x_m_s"),
            "correlated -0.970 with bias x"
        );
        assert_eq!(
            readable_why("time_offset_s", "flat together with lever_arm_x_m, scale"),
            "flat together with lever arm x, scale"
        );
        assert_eq!(
            readable_why("time_offset_s", "the residuals do not depend on it"),
            "the residuals do not depend on it"
        );
    }

    #[test]
    fn terms_read_in_their_units() {
        assert_eq!(readable("lever_arm_x_m"), ("lever arm x".into(), "m", 1.0));
        assert_eq!(readable("bias_x_m_s"), ("bias x".into(), "cm/s", 100.0));
        assert_eq!(readable("time_offset_s"), ("time offset".into(), "s", 1.0));
        assert_eq!(readable("scale_x"), ("scale x".into(), "%", 100.0));
        assert_eq!(readable("scale"), ("scale".into(), "%", 100.0));
        let (name, unit, factor) = readable("misalignment_z_rad");
        assert_eq!((name.as_str(), unit), ("misalignment z", "deg"));
        assert!((factor * std::f64::consts::PI - 180.0).abs() < 1e-12);
    }
}
