//! The DCNet ensemble: the `training.replicates` DCNets of one error model, each
//! estimating the terms of the calibration window as [`super::DcnetEstimator`] does,
//! and the mean of their terms (scale and bias, term by term) as the estimate.

use super::Estimator;
use crate::Vec3;
use crate::vocab::Correction;

pub struct Ensemble {
    pub members: Vec<Box<dyn Estimator>>,
}

impl Estimator for Ensemble {
    fn estimate(&self, dvl: &[Vec3], gnss: &[Vec3]) -> Correction {
        let corrections: Vec<Correction> = self
            .members
            .iter()
            .map(|member| member.estimate(dvl, gnss))
            .collect();
        Correction::mean(&corrections)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An estimator that always returns the same terms.
    struct Fixed(Correction);

    impl Estimator for Fixed {
        fn estimate(&self, _: &[Vec3], _: &[Vec3]) -> Correction {
            self.0
        }
    }

    fn ensemble(corrections: &[Correction]) -> Correction {
        let members = corrections
            .iter()
            .map(|&c| Box::new(Fixed(c)) as Box<dyn Estimator>)
            .collect();
        Ensemble { members }.estimate(&[[1.0; 3]], &[[1.0; 3]])
    }

    #[test]
    fn an_ensemble_of_identical_members_is_that_member() {
        let one = Correction {
            scale: [0.01, -0.02, 0.003],
            bias_m_s: [0.007, 0.0, -0.001],
        };
        // Equal up to the rounding of summing three terms and dividing by 3.
        let mean = ensemble(&[one, one, one]);
        for axis in 0..3 {
            assert!((mean.scale[axis] - one.scale[axis]).abs() < 1e-17);
            assert!((mean.bias_m_s[axis] - one.bias_m_s[axis]).abs() < 1e-17);
        }
        assert_eq!(ensemble(&[one]), one);
    }

    #[test]
    fn an_ensemble_averages_each_term() {
        let a = Correction {
            scale: [0.01, 0.02, 0.03],
            bias_m_s: [0.001, 0.002, 0.003],
        };
        let b = Correction {
            scale: [0.03, 0.0, -0.03],
            bias_m_s: [0.003, -0.002, 0.009],
        };
        let mean = ensemble(&[a, b]);
        let expected = Correction {
            scale: [0.02, 0.01, 0.0],
            bias_m_s: [0.002, 0.0, 0.006],
        };
        for axis in 0..3 {
            assert!((mean.scale[axis] - expected.scale[axis]).abs() < 1e-15);
            assert!((mean.bias_m_s[axis] - expected.bias_m_s[axis]).abs() < 1e-15);
        }
        // The mean of the terms, not of the corrected velocities: (v − b̄) ⊘ (1 + k̄).
        let v = [1.0, 1.0, 1.0];
        assert!((mean.apply(v)[0] - (1.0 - 0.002) / 1.02).abs() < 1e-12);
    }
}
