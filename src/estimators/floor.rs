//! The floor: corrects with the true terms of the noising settings, so what is left is
//! the beam noise alone. A bound for every method, not a method.

use super::Estimator;
use crate::Vec3;
use crate::noise::BeamGeometry;
use crate::vocab::Correction;
use crate::vocab::SensorErrors;

pub struct Floor(Correction);

impl Floor {
    /// The velocity-level terms of beam-level `errors`: the beam scale scales every axis,
    /// the shared beam bias becomes `b·(HᵀH)⁻¹Hᵀ1` (a pure z bias for a Janus DVL).
    pub fn new(errors: &SensorErrors, geometry: &BeamGeometry) -> Self {
        Self(Correction {
            scale: [errors.scale; 3],
            bias_m_s: geometry.shared_bias_velocity(errors.bias_m_s),
        })
    }
}

impl Estimator for Floor {
    fn estimate(&self, _dvl: &[Vec3], _gnss: &[Vec3]) -> Correction {
        self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::task_rng;

    #[test]
    fn true_terms_undo_noise_free_measurements_exactly() {
        let geometry = BeamGeometry::janus_x(20.0);
        let errors = SensorErrors::from_spec_units(1.0, 0.7, 0.0);
        let floor = Floor::new(&errors, &geometry).estimate(&[], &[]);
        let v = [1.4, 0.2, -0.1];
        let corrected = floor.apply(geometry.measure(v, &errors, &mut task_rng(0, &[])));
        assert!(
            (0..3).all(|a| (corrected[a] - v[a]).abs() < 1e-12),
            "{corrected:?}"
        );
    }
}
