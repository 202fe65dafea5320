//! The scale-and-bias models as the filter measures them: the paper's EM1 to EM5 and
//! the DVL's beam model. Each sample of DVL velocity d and GNSS-RTK velocity g gives,
//! per axis a, the measurement `d_a − g_a = k_a·g_a + b_a + r_a`, linear in the terms:
//! EM1 one scale for every axis, EM2 a scale per axis, EM3 one bias, EM4 a bias per
//! axis, EM5 a scale and a bias per axis (scales first), and the beam model the beam
//! scale s and the shared beam bias seen on z, β (`k = s` on every axis, `b = β·e_z`,
//! the form `bound` states). The noise of axis a is the DVL's velocity noise there plus
//! the GNSS-RTK noise. In: a model, the DVL's noise, samples. Out: the filter's
//! measurements, and the terms as a [`Correction`].

use super::filter::{Filter, Measurement, Prior};
use crate::Vec3;
use crate::noise::BeamGeometry;
use crate::spec::TermSettings;
use crate::vocab::{Correction, ErrorModel, SensorErrors};

/// A model the filter estimates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScaleBiasModel {
    Paper(ErrorModel),
    /// The beam model: (s, β).
    Beam,
}

/// Which term of the correction a parameter is: a scale on some axes, or a bias.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Term {
    Scale(&'static [usize]),
    Bias(&'static [usize]),
}

const ALL: &[usize] = &[0, 1, 2];
const AXES: [&[usize]; 3] = [&[0], &[1], &[2]];

impl ScaleBiasModel {
    fn terms(self) -> Vec<Term> {
        match self {
            Self::Paper(ErrorModel::Em1) => vec![Term::Scale(ALL)],
            Self::Paper(ErrorModel::Em2) => AXES.map(Term::Scale).to_vec(),
            Self::Paper(ErrorModel::Em3) => vec![Term::Bias(ALL)],
            Self::Paper(ErrorModel::Em4) => AXES.map(Term::Bias).to_vec(),
            Self::Paper(ErrorModel::Em5) => AXES
                .map(Term::Scale)
                .into_iter()
                .chain(AXES.map(Term::Bias))
                .collect(),
            Self::Beam => vec![Term::Scale(ALL), Term::Bias(AXES[2])],
        }
    }

    /// The terms' names, in the order of the state, as `terms_in_time.parquet` stores
    /// them: `scale`, `scale_x`, `bias_m_s`, `bias_z_m_s`, …
    pub fn term_names(self) -> Vec<&'static str> {
        self.terms()
            .into_iter()
            .map(|term| match term {
                Term::Scale(ALL) => "scale",
                Term::Bias(ALL) => "bias_m_s",
                Term::Scale(axes) => ["scale_x", "scale_y", "scale_z"][axes[0]],
                Term::Bias(axes) => ["bias_x_m_s", "bias_y_m_s", "bias_z_m_s"][axes[0]],
            })
            .collect()
    }

    /// The prior: zero terms with standard deviations `std`, and random walks `walk`.
    pub fn prior(self, std: TermSettings, walk: TermSettings) -> Prior {
        let of = |term: &Term, of: TermSettings| match term {
            Term::Scale(_) => of.scale,
            Term::Bias(_) => of.bias_m_s,
        };
        let terms = self.terms();
        Prior {
            mean: vec![0.0; terms.len()],
            std: terms.iter().map(|t| of(t, std)).collect(),
            walk_per_sqrt_s: terms.iter().map(|t| of(t, walk)).collect(),
        }
    }

    /// The measurement of one sample about the terms `estimate`.
    pub fn measurement(self, dvl: Vec3, gnss: Vec3, estimate: &[f64], noise: Vec3) -> Measurement {
        let terms = self.terms();
        let rows: Vec<Vec<f64>> = (0..3)
            .map(|a| {
                terms
                    .iter()
                    .map(|term| match term {
                        Term::Scale(axes) if axes.contains(&a) => gnss[a],
                        Term::Bias(axes) if axes.contains(&a) => 1.0,
                        _ => 0.0,
                    })
                    .collect()
            })
            .collect();
        let innovation = (0..3)
            .map(|a| {
                let predicted: f64 = rows[a].iter().zip(estimate).map(|(h, x)| h * x).sum();
                dvl[a] - gnss[a] - predicted
            })
            .collect();
        Measurement {
            rows,
            innovation,
            noise_variance: noise.to_vec(),
        }
    }

    /// The terms as a correction of the DVL.
    pub fn correction(self, estimate: &[f64]) -> Correction {
        let mut correction = Correction::NONE;
        for (term, value) in self.terms().into_iter().zip(estimate) {
            match term {
                Term::Scale(axes) => axes.iter().for_each(|&a| correction.scale[a] = *value),
                Term::Bias(axes) => axes.iter().for_each(|&a| correction.bias_m_s[a] = *value),
            }
        }
        correction
    }

    /// The true terms of a simulated DVL with `errors` in this model's form, when the
    /// model can hold them exactly (EM3 cannot hold a scale, EM1 a bias).
    pub fn true_terms(self, errors: &SensorErrors, geometry: &BeamGeometry) -> Option<Vec<f64>> {
        let truth = Correction {
            scale: [errors.scale; 3],
            bias_m_s: geometry.shared_bias_velocity(errors.bias_m_s),
        };
        let terms: Vec<f64> = self
            .terms()
            .into_iter()
            .map(|term| match term {
                Term::Scale(axes) => truth.scale[axes[0]],
                Term::Bias(axes) => truth.bias_m_s[axes[axes.len() - 1]],
            })
            .collect();
        let held = self.correction(&terms);
        let same = |a: Vec3, b: Vec3| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-12);
        (same(held.scale, truth.scale) && same(held.bias_m_s, truth.bias_m_s)).then_some(terms)
    }
}

/// The noise variance per axis of `d − g`: the DVL's velocity noise through the beam
/// geometry plus the GNSS-RTK noise.
pub fn axis_noise(errors: &SensorErrors, geometry: &BeamGeometry, gnss_noise_m_s: f64) -> Vec3 {
    geometry
        .velocity_noise_variances(errors.noise_m_s)
        .map(|v| v + gnss_noise_m_s.powi(2))
}

/// The filter run over every sample, one second apart at `sample_rate_hz`: the
/// estimate and the standard deviations after each sample.
pub fn run(
    model: ScaleBiasModel,
    prior: &Prior,
    noise: Vec3,
    sample_period_s: f64,
    dvl: &[Vec3],
    gnss: &[Vec3],
) -> Vec<(Vec<f64>, Vec<f64>)> {
    let mut filter = Filter::new(prior);
    dvl.iter()
        .zip(gnss)
        .map(|(&d, &g)| {
            filter.predict(sample_period_s);
            let measurement = model.measurement(d, g, filter.estimate.as_slice(), noise);
            filter.update(&measurement);
            (filter.estimate.as_slice().to_vec(), filter.std())
        })
        .collect()
}

/// The Cramér–Rao bound of the model's terms from a batch of the first n samples, for
/// every n: the standard deviations of the inverse of `Σ HᵀR⁻¹H` with H taken at the
/// true velocity `truth`. Infinite while the samples cannot tell the terms apart.
pub fn bound_history(model: ScaleBiasModel, truth: &[Vec3], noise: Vec3) -> Vec<Vec<f64>> {
    let n = model.terms().len();
    let mut information = nalgebra::DMatrix::<f64>::zeros(n, n);
    truth
        .iter()
        .map(|&v| {
            let measurement = model.measurement(v, v, &vec![0.0; n], noise);
            for (row, variance) in measurement.rows.iter().zip(noise) {
                for a in 0..n {
                    for b in 0..n {
                        information[(a, b)] += row[a] * row[b] / variance;
                    }
                }
            }
            match information.clone().try_inverse() {
                Some(covariance) if covariance.diagonal().iter().all(|v| *v > 0.0) => {
                    covariance.diagonal().iter().map(|v| v.sqrt()).collect()
                }
                _ => vec![f64::INFINITY; n],
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimators::{Estimator, LeastSquares};
    use crate::noise::measure_trajectory;
    use crate::rng::task_rng;

    fn truth(n: usize) -> Vec<Vec3> {
        (0..n)
            .map(|t| t as f64)
            .map(|t| {
                [
                    1.5 + 0.4 * (t / 13.0).sin(),
                    0.3 * (t / 7.0).cos(),
                    0.1 * (t / 5.0).sin(),
                ]
            })
            .collect()
    }

    /// Constant terms: no random walk.
    const STILL: TermSettings = TermSettings {
        scale: 0.0,
        bias_m_s: 0.0,
    };

    fn every_model() -> Vec<ScaleBiasModel> {
        ErrorModel::ALL
            .map(ScaleBiasModel::Paper)
            .into_iter()
            .chain([ScaleBiasModel::Beam])
            .collect()
    }

    /// With a prior too wide to matter, the filter over a window is the paper's closed-
    /// form least squares of the same model (per-axis models), to 1e-8.
    #[test]
    fn a_diffuse_prior_gives_the_papers_least_squares() {
        let geometry = BeamGeometry::janus_x(20.0);
        let errors = SensorErrors::from_spec_units(1.0, 0.7, 2.0);
        let mut rng = task_rng(3, &[]);
        let measured = measure_trajectory(&geometry, &truth(80), &errors, 0.005, &mut rng);
        // Wide enough to weigh nothing at 1e-8, narrow enough to keep the digits.
        let wide = TermSettings {
            scale: 1e4,
            bias_m_s: 1e4,
        };
        for model in [ErrorModel::Em2, ErrorModel::Em4, ErrorModel::Em5] {
            let filtered = ScaleBiasModel::Paper(model);
            // Per-axis models: the weights of the axes do not matter.
            let history = run(
                filtered,
                &filtered.prior(wide, STILL),
                [1.0; 3],
                1.0,
                &measured.dvl,
                &measured.gnss,
            );
            let estimate = filtered.correction(&history.last().unwrap().0);
            let closed = LeastSquares(model).estimate(&measured.dvl, &measured.gnss);
            for a in 0..3 {
                assert!(
                    (estimate.scale[a] - closed.scale[a]).abs() < 1e-8,
                    "{model}: {estimate:?} vs {closed:?}"
                );
                assert!(
                    (estimate.bias_m_s[a] - closed.bias_m_s[a]).abs() < 1e-8,
                    "{model}"
                );
            }
        }
    }

    /// With a flat prior, the filter's standard deviations are the bound of the same
    /// samples when the regressor is the truth: on noise-free GNSS-RTK samples they meet.
    #[test]
    fn with_a_flat_prior_the_filters_spread_is_the_bound() {
        let geometry = BeamGeometry::janus_x(20.0);
        let errors = SensorErrors::from_spec_units(1.0, 0.7, 2.0);
        let truth = truth(50);
        let mut rng = task_rng(5, &[]);
        let measured = measure_trajectory(&geometry, &truth, &errors, 0.0, &mut rng);
        let noise = axis_noise(&errors, &geometry, 0.0);
        let flat = TermSettings {
            scale: 1e2,
            bias_m_s: 1e2,
        };
        let model = ScaleBiasModel::Beam;
        let history = run(
            model,
            &model.prior(flat, STILL),
            noise,
            1.0,
            &measured.dvl,
            &measured.gnss,
        );
        let bound = bound_history(model, &truth, noise);
        let standing = bound_history(model, &[[0.0; 3]; 5], noise);
        assert!(standing[4][0].is_infinite(), "no motion, no scale");
        for n in [10, 49] {
            for (filtered, bound) in history[n].1.iter().zip(&bound[n]) {
                assert!(
                    (filtered / bound - 1.0).abs() < 1e-6,
                    "{n}: {filtered} vs {bound}"
                );
            }
        }
    }

    /// Noise-free samples of a DVL the model holds, the filter told there is no noise
    /// at all: every model that can hold the truth recovers it, and the others say
    /// they cannot.
    #[test]
    fn noise_free_samples_give_the_true_terms_of_every_model_that_holds_them() {
        let geometry = BeamGeometry::janus_x(20.0);
        let wide = TermSettings {
            scale: 1e3,
            bias_m_s: 1e3,
        };
        for (scale_pct, bias_cm_s) in [(1.0, 0.7), (1.0, 0.0), (0.0, 0.7)] {
            let errors = SensorErrors::from_spec_units(scale_pct, bias_cm_s, 0.0);
            let mut rng = task_rng(4, &[]);
            let measured = measure_trajectory(&geometry, &truth(60), &errors, 0.0, &mut rng);
            for model in every_model() {
                let history = run(
                    model,
                    &model.prior(wide, STILL),
                    [0.0; 3],
                    1.0,
                    &measured.dvl,
                    &measured.gnss,
                );
                let estimate = &history.last().unwrap().0;
                match model.true_terms(&errors, &geometry) {
                    Some(terms) => {
                        for (e, t) in estimate.iter().zip(&terms) {
                            assert!(
                                (e - t).abs() < 1e-7,
                                "{model:?} {scale_pct} {bias_cm_s}: {estimate:?} vs {terms:?}"
                            );
                        }
                    }
                    None => assert!(
                        matches!(
                            (model, scale_pct > 0.0, bias_cm_s > 0.0),
                            (
                                ScaleBiasModel::Paper(ErrorModel::Em1 | ErrorModel::Em2),
                                _,
                                true
                            ) | (
                                ScaleBiasModel::Paper(ErrorModel::Em3 | ErrorModel::Em4),
                                true,
                                _
                            ) | (ScaleBiasModel::Paper(ErrorModel::Em3), _, true)
                        ),
                        "{model:?} should hold {scale_pct} % and {bias_cm_s} cm/s"
                    ),
                }
            }
        }
    }
}
