//! Checks `[observability]`. In: the standard deviation past which each kind of term
//! counts as not seen, in the file's units. Out: the same table, each value finite and
//! above zero.

use crate::installation::study::spec::file::ObservabilityFile;
use crate::spec::check::Faults;

/// Checks `[observability]`: every tolerance finite and above zero.
pub(in crate::installation::study::spec) fn check_observability(
    observability: ObservabilityFile,
    faults: &mut Faults,
) -> ObservabilityFile {
    let ObservabilityFile {
        scale_pct,
        misalignment_deg,
        lever_arm_m,
        time_offset_s,
        bias_cm_s,
    } = observability;
    for (key, value) in [
        ("scale_pct", scale_pct),
        ("misalignment_deg", misalignment_deg),
        ("lever_arm_m", lever_arm_m),
        ("time_offset_s", time_offset_s),
        ("bias_cm_s", bias_cm_s),
    ] {
        if !(value.is_finite() && value > 0.0) {
            faults.add(
                format!("observability.{key}"),
                format!(
                    "{value} must be a finite positive number: a term whose standard deviation is beyond it counts as not seen"
                ),
            );
        }
    }
    ObservabilityFile {
        scale_pct,
        misalignment_deg,
        lever_arm_m,
        time_offset_s,
        bias_cm_s,
    }
}
