//! Checks `[observability]`. In: the standard deviation past which each kind of term
//! counts as not seen, in the file's units. Out: the same table, each value finite and
//! above zero.

use crate::installation::study::spec::file::ObservabilityFile;
use crate::installation::terms::TermKind;
use crate::spec::check::Faults;

/// Checks `[observability]`: every tolerance finite and above zero.
pub(in crate::installation::study::spec) fn check_observability(
    observability: ObservabilityFile,
    faults: &mut Faults,
) -> ObservabilityFile {
    for kind in TermKind::ALL {
        let value = observability.of(kind);
        if !(value.is_finite() && value > 0.0) {
            faults.add(
                format!("observability.{}", kind.table().spec_key("")),
                format!(
                    "{value} must be a finite positive number: a term whose standard deviation is beyond it counts as not seen"
                ),
            );
        }
    }
    observability
}
