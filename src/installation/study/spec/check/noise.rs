//! Checks `[noise]`. In: the DVL's and the reference's white noise per axis, cm/s.
//! Out: both in m/s; the DVL's above zero (the bound divides by it), the reference's
//! zero or more.

use crate::installation::study::spec::file::NoiseFile;
use crate::spec::check::Faults;

/// Checks `[noise]`: the DVL's and the reference's noise, in m/s.
pub(in crate::installation::study::spec) fn check_noise(
    noise: NoiseFile,
    faults: &mut Faults,
) -> (f64, f64) {
    let NoiseFile {
        dvl_cm_s,
        reference_cm_s,
    } = noise;
    if !(dvl_cm_s.is_finite() && dvl_cm_s > 0.0) {
        faults.add(
            "noise.dvl_cm_s",
            format!("{dvl_cm_s} must be a finite positive number: the bound divides by it"),
        );
    }
    if !(reference_cm_s.is_finite() && reference_cm_s >= 0.0) {
        faults.add(
            "noise.reference_cm_s",
            format!("{reference_cm_s} must be zero or a finite positive number"),
        );
    }
    (dvl_cm_s / 100.0, reference_cm_s / 100.0)
}
