//! Least squares: the closed-form fit of `v_dvl = (1 + k)·v_gnss + b` with the error
//! model's structure. EM1 and EM2 fit a scale through the origin (one for all axes, or
//! one per axis), EM3 and EM4 a bias (one for all axes, or one per axis), EM5 a line per
//! axis. GNSS-RTK noise sits in the regressor, so the EM5 slope is attenuated when the
//! window barely varies in speed: that is the textbook errors-in-variables bias.

use super::Estimator;
use crate::Vec3;
use crate::vocab::{Correction, ErrorModel};

pub struct LeastSquares(pub ErrorModel);

/// Below this variance (m²/s²) the GNSS velocity of an axis is taken as constant and
/// EM5 falls back to a pure bias on that axis.
const MIN_VARIANCE: f64 = 1e-12;

impl Estimator for LeastSquares {
    fn estimate(&self, dvl: &[Vec3], gnss: &[Vec3]) -> Correction {
        let n = dvl.len().min(gnss.len()).max(1) as f64;
        let sum = |f: &dyn Fn(Vec3, Vec3) -> f64| {
            dvl.iter().zip(gnss).map(|(d, g)| f(*d, *g)).sum::<f64>()
        };
        let cross: Vec3 = std::array::from_fn(|a| sum(&|d, g| d[a] * g[a]));
        let square: Vec3 = std::array::from_fn(|a| sum(&|_, g| g[a] * g[a]));
        let mean_dvl: Vec3 = std::array::from_fn(|a| sum(&|d, _| d[a]) / n);
        let mean_gnss: Vec3 = std::array::from_fn(|a| sum(&|_, g| g[a]) / n);
        let ratio = |num: f64, den: f64| if den > 0.0 { num / den - 1.0 } else { 0.0 };
        match self.0 {
            ErrorModel::Em1 => {
                let k = ratio(cross.iter().sum(), square.iter().sum());
                Correction {
                    scale: [k; 3],
                    bias_m_s: [0.0; 3],
                }
            }
            ErrorModel::Em2 => Correction {
                scale: std::array::from_fn(|a| ratio(cross[a], square[a])),
                bias_m_s: [0.0; 3],
            },
            ErrorModel::Em3 => {
                let b = (0..3).map(|a| mean_dvl[a] - mean_gnss[a]).sum::<f64>() / 3.0;
                Correction {
                    scale: [0.0; 3],
                    bias_m_s: [b; 3],
                }
            }
            ErrorModel::Em4 => Correction {
                scale: [0.0; 3],
                bias_m_s: std::array::from_fn(|a| mean_dvl[a] - mean_gnss[a]),
            },
            ErrorModel::Em5 => {
                let mut scale = [0.0; 3];
                let mut bias_m_s = [0.0; 3];
                for a in 0..3 {
                    let covariance = cross[a] / n - mean_dvl[a] * mean_gnss[a];
                    let variance = square[a] / n - mean_gnss[a] * mean_gnss[a];
                    let slope = if variance > MIN_VARIANCE {
                        covariance / variance
                    } else {
                        1.0
                    };
                    scale[a] = slope - 1.0;
                    bias_m_s[a] = mean_dvl[a] - slope * mean_gnss[a];
                }
                Correction { scale, bias_m_s }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Noise-free windows with varying velocity: `dvl = (1 + k)·v + b` exactly.
    fn window(k: Vec3, b: Vec3) -> (Vec<Vec3>, Vec<Vec3>) {
        let gnss: Vec<Vec3> = (0..40)
            .map(|t| t as f64)
            .map(|t| [1.0 + 0.02 * t, 0.3 * (t / 5.0).sin(), 0.1 * (t / 7.0).cos()])
            .collect();
        let dvl = gnss
            .iter()
            .map(|g| std::array::from_fn(|a| (1.0 + k[a]) * g[a] + b[a]))
            .collect();
        (dvl, gnss)
    }

    fn assert_close(actual: Vec3, expected: Vec3) {
        assert!(
            (0..3).all(|a| (actual[a] - expected[a]).abs() < 1e-9),
            "{actual:?} != {expected:?}"
        );
    }

    #[test]
    fn recovers_known_terms_from_noise_free_data_for_every_error_model() {
        let cases = [
            (ErrorModel::Em1, [0.012; 3], [0.0; 3]),
            (ErrorModel::Em2, [0.01, -0.02, 0.03], [0.0; 3]),
            (ErrorModel::Em3, [0.0; 3], [0.007; 3]),
            (ErrorModel::Em4, [0.0; 3], [0.001, -0.004, 0.0075]),
            (
                ErrorModel::Em5,
                [0.01, 0.015, -0.01],
                [0.002, -0.003, 0.0075],
            ),
        ];
        for (model, k, b) in cases {
            let (dvl, gnss) = window(k, b);
            let correction = LeastSquares(model).estimate(&dvl, &gnss);
            assert_close(correction.scale, k);
            assert_close(correction.bias_m_s, b);
        }
    }

    #[test]
    fn em5_falls_back_to_a_bias_on_a_constant_axis() {
        let gnss = vec![[1.0, 0.0, 0.0]; 10];
        let dvl = vec![[1.01, 0.0, 0.0075]; 10];
        let correction = LeastSquares(ErrorModel::Em5).estimate(&dvl, &gnss);
        assert_close(correction.scale, [0.0; 3]);
        assert_close(correction.bias_m_s, [0.01, 0.0, 0.0075]);
    }
}
