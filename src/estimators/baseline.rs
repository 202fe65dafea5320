//! The paper's baseline (eq. 9-10): a scalar scale `k_t = |v_dvl,t| / |v_gnss,t| − 1`
//! averaged over the calibration window, corrected as `v / (1 + k)`.

use super::Estimator;
use crate::Vec3;
use crate::data::norm;
use crate::vocab::Correction;

pub struct Baseline;

impl Estimator for Baseline {
    fn estimate(&self, dvl: &[Vec3], gnss: &[Vec3]) -> Correction {
        let ratios: Vec<f64> = dvl
            .iter()
            .zip(gnss)
            .filter(|(_, g)| norm(**g) > 0.0)
            .map(|(d, g)| norm(*d) / norm(*g) - 1.0)
            .collect();
        let k = if ratios.is_empty() {
            0.0
        } else {
            ratios.iter().sum::<f64>() / ratios.len() as f64
        };
        Correction {
            scale: [k; 3],
            bias_m_s: [0.0; 3],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_known_scale() {
        let gnss: Vec<Vec3> = (0..50)
            .map(|t| [1.0 + 0.01 * t as f64, -0.3, 0.05])
            .collect();
        let dvl: Vec<Vec3> = gnss.iter().map(|g| g.map(|x| 1.013 * x)).collect();
        let correction = Baseline.estimate(&dvl, &gnss);
        for k in correction.scale {
            assert!((k - 0.013).abs() < 1e-12, "k = {k}");
        }
        assert_eq!(correction.bias_m_s, [0.0; 3]);
        let corrected = correction.apply(dvl[7]);
        assert!((0..3).all(|a| (corrected[a] - gnss[7][a]).abs() < 1e-12));
    }
}
