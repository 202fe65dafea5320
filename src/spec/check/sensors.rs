//! Checks `[sensors]` and `[[dvl]]`. In: the beam pitch and the GNSS-RTK noise, and
//! each DVL under test with its error terms, as written (percent, cm/s). Out: the pitch
//! in degrees, the GNSS noise in m/s, and each DVL's [`SensorErrors`] as fractions and
//! m/s.
//!
//! [`SensorErrors`]: crate::vocab::SensorErrors

use super::{Faults, check_noise, check_scale, non_negative};
use crate::spec::{Dvl, file, ranges};
use crate::vocab::SensorErrors;

/// Checks `[sensors]`; returns the beam pitch in degrees and the GNSS noise in m/s.
pub(in crate::spec) fn check_sensors(
    sensors: file::SensorsFile,
    faults: &mut Faults,
) -> (f64, f64) {
    let file::SensorsFile {
        beam_pitch_deg,
        gnss_noise_cm_s,
    } = sensors;
    if !(beam_pitch_deg > 0.0 && beam_pitch_deg < 90.0) {
        faults.add(
            "sensors.beam_pitch_deg",
            format!("{beam_pitch_deg} must lie strictly between 0 and 90"),
        );
    }
    non_negative("sensors.gnss_noise_cm_s", gnss_noise_cm_s, faults);
    ranges::VELOCITY_ERROR_CM_S.check("sensors.gnss_noise_cm_s", gnss_noise_cm_s, faults);
    (beam_pitch_deg, gnss_noise_cm_s / 100.0)
}

/// Checks `[[dvl]]`: at least one, each named once, with error terms in range.
pub(in crate::spec) fn check_dvls(units: &[file::DvlFile], faults: &mut Faults) -> Vec<Dvl> {
    if units.is_empty() {
        faults.add("dvl", "no DVL under test is defined");
    }
    let mut dvls: Vec<Dvl> = Vec::new();
    let mut names = std::collections::HashSet::new();
    for (i, unit) in units.iter().enumerate() {
        let file::DvlFile {
            name,
            scale_pct,
            bias_cm_s,
            noise_cm_s,
        } = unit;
        let key = format!("dvl[{i}]");
        if !names.insert(name) {
            faults.add(format!("{key}.name"), format!("{name:?} is defined twice"));
        }
        check_scale(&format!("{key}.scale_pct"), *scale_pct, faults);
        if !bias_cm_s.is_finite() {
            faults.add(
                format!("{key}.bias_cm_s"),
                format!("{bias_cm_s} must be a finite number"),
            );
        }
        ranges::VELOCITY_ERROR_CM_S.check(&format!("{key}.bias_cm_s"), bias_cm_s.abs(), faults);
        check_noise(&format!("{key}.noise_cm_s"), *noise_cm_s, faults);
        dvls.push(Dvl {
            name: name.clone(),
            errors: SensorErrors::from_spec_units(*scale_pct, *bias_cm_s, *noise_cm_s),
        });
    }
    dvls
}

#[cfg(test)]
mod tests {
    use crate::spec::fixture::{quick_faults, quick_spec};

    #[test]
    fn error_terms_become_fractions_and_m_s() {
        let spec = quick_spec(&["dvl[0].scale_pct=2.5", "dvl[0].bias_cm_s=-3"]);
        assert_eq!(spec.gnss_noise_m_s, 0.005);
        assert_eq!(spec.dvls[0].errors.scale, 0.025);
        assert_eq!(spec.dvls[0].errors.bias_m_s, -0.03);
        assert_eq!(spec.dvls[0].errors.noise_m_s, 0.02);
    }

    #[test]
    fn a_pitch_of_90_degrees_and_a_name_twice_are_refused() {
        let set = "sensors.beam_pitch_deg=90";
        assert_eq!(
            quick_faults(&[set]),
            format!("--set {set}: sensors.beam_pitch_deg: 90 must lie strictly between 0 and 90")
        );
        let set = "dvl[1].name=DVL1";
        assert_eq!(
            quick_faults(&[set]),
            format!("--set {set}: dvl[1].name: \"DVL1\" is defined twice")
        );
    }
}
