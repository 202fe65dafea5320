//! The Kalman filter on a vector of error terms θ: constant in time, or wandering as a
//! random walk of the spec's strength, and measured sample by sample through
//! `y = h(θ) + r`, r ~ N(0, R) with R diagonal. The update is the extended filter's
//! (the innovation `y − h(θ̂)` and the Jacobian H at the current estimate), which is the
//! plain filter where h is linear; the covariance is updated in Joseph form, which
//! stays symmetric and positive over thousands of samples. With no random walk the
//! filter's estimate after n samples is the batch least squares over those samples with
//! the prior as n + 1st measurement ([`batch_least_squares`], the known answer its
//! tests hold it to). In: a prior, then measurements. Out: the estimate and covariance
//! after each.

use nalgebra::{DMatrix, DVector};

/// The state of the filter: the estimate of the terms and its covariance.
#[derive(Debug, Clone)]
pub struct Filter {
    pub estimate: DVector<f64>,
    pub covariance: DMatrix<f64>,
    /// The random walk's variance per second, per term.
    walk_variance_per_s: DVector<f64>,
}

/// The prior of the terms: mean and standard deviation, term by term, and the random
/// walk (standard deviation per √s) each may take between samples.
#[derive(Debug, Clone, PartialEq)]
pub struct Prior {
    pub mean: Vec<f64>,
    pub std: Vec<f64>,
    pub walk_per_sqrt_s: Vec<f64>,
}

/// One sample's measurement: `rows` of H (one per measured component, each over every
/// term), the innovation `y − h(θ̂)` and the noise variance of each component.
#[derive(Debug, Clone, PartialEq)]
pub struct Measurement {
    pub rows: Vec<Vec<f64>>,
    pub innovation: Vec<f64>,
    pub noise_variance: Vec<f64>,
}

impl Filter {
    /// The filter before any measurement: the prior.
    ///
    /// # Panics
    /// When the prior's three lists differ in length.
    pub fn new(prior: &Prior) -> Self {
        let n = prior.mean.len();
        assert!(prior.std.len() == n && prior.walk_per_sqrt_s.len() == n);
        Filter {
            estimate: DVector::from_column_slice(&prior.mean),
            covariance: DMatrix::from_diagonal(&DVector::from_iterator(
                n,
                prior.std.iter().map(|s| s * s),
            )),
            walk_variance_per_s: DVector::from_iterator(
                n,
                prior.walk_per_sqrt_s.iter().map(|w| w * w),
            ),
        }
    }

    /// Lets `elapsed_s` seconds pass: each term's variance grows by its random walk's.
    pub fn predict(&mut self, elapsed_s: f64) {
        for (i, variance) in self.walk_variance_per_s.iter().enumerate() {
            self.covariance[(i, i)] += variance * elapsed_s.max(0.0);
        }
    }

    /// Takes in one sample's measurement.
    pub fn update(&mut self, measurement: &Measurement) {
        self.update_about(measurement, &self.estimate.clone());
    }

    /// Takes in one sample's measurement of a nonlinear h by the iterated extended
    /// filter: `measure(θ)` linearises h at θ (its Jacobian and `y − h(θ)`), and the
    /// update is taken again about each new estimate, `iterations` times in all (Gauss–
    /// Newton on the sample and the prior). Where h is linear every pass gives the plain
    /// update.
    pub fn update_iterated(&mut self, iterations: usize, measure: impl Fn(&[f64]) -> Measurement) {
        let prior = self.clone();
        let mut about = self.estimate.clone();
        for _ in 0..iterations.max(1) {
            *self = prior.clone();
            self.update_about(&measure(about.as_slice()), &about);
            about = self.estimate.clone();
        }
    }

    /// The update with `measurement` linearised about `about`: its innovation
    /// `y − h(about)` moved to the current estimate, `− H·(θ̂ − about)`. With R
    /// diagonal, the components are taken in one at a time, which is the joint update
    /// and needs no matrix inverse: a component that neither its noise nor the terms'
    /// uncertainty can move (`hPhᵀ + r = 0`) tells nothing and is passed over.
    pub fn update_about(&mut self, measurement: &Measurement, about: &DVector<f64>) {
        let n = self.estimate.len();
        for (r, row) in measurement.rows.iter().enumerate() {
            let h = DVector::from_column_slice(row);
            let noise = measurement.noise_variance[r];
            let ph = &self.covariance * &h;
            let spread = h.dot(&ph) + noise;
            if !(spread > 0.0) {
                continue;
            }
            let gain = ph / spread;
            let innovation = measurement.innovation[r] - h.dot(&(&self.estimate - about));
            self.estimate += &gain * innovation;
            let keep = DMatrix::identity(n, n) - &gain * h.transpose();
            self.covariance =
                &keep * &self.covariance * keep.transpose() + &gain * gain.transpose() * noise;
        }
    }

    /// The standard deviation of each term.
    pub fn std(&self) -> Vec<f64> {
        self.covariance
            .diagonal()
            .iter()
            .map(|v| v.sqrt())
            .collect()
    }
}

/// The batch least squares of linear measurements (innovations taken about zero terms,
/// so `innovation` is y) with `prior` as one more: `(P₀⁻¹ + Σ HᵀR⁻¹H)⁻¹ (P₀⁻¹θ₀ +
/// Σ HᵀR⁻¹y)` and that covariance. What a filter with no random walk gives.
pub fn batch_least_squares(
    prior: &Prior,
    measurements: &[Measurement],
) -> (DVector<f64>, DMatrix<f64>) {
    let n = prior.mean.len();
    let mut information = DMatrix::from_diagonal(&DVector::from_iterator(
        n,
        prior.std.iter().map(|s| 1.0 / (s * s)),
    ));
    let mut projection = DVector::from_iterator(
        n,
        (0..n).map(|i| prior.mean[i] / (prior.std[i] * prior.std[i])),
    );
    for measurement in measurements {
        for (r, row) in measurement.rows.iter().enumerate() {
            let weight = 1.0 / measurement.noise_variance[r];
            for a in 0..n {
                projection[a] += weight * row[a] * measurement.innovation[r];
                for b in 0..n {
                    information[(a, b)] += weight * row[a] * row[b];
                }
            }
        }
    }
    let covariance = information
        .try_inverse()
        .expect("a prior makes the information invertible");
    (&covariance * projection, covariance)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    /// Three terms, two measured components a sample, rows that change with time.
    fn measurements(count: usize) -> Vec<Measurement> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let truth = [0.3, -1.2, 0.05];
        (0..count)
            .map(|t| {
                let t = t as f64;
                let rows = vec![
                    vec![1.0 + (t / 9.0).sin(), 0.2, 0.0],
                    vec![0.0, (t / 4.0).cos(), 1.0],
                ];
                let noise_variance: Vec<f64> = vec![0.04, 0.09];
                let innovation = rows
                    .iter()
                    .zip(&noise_variance)
                    .map(|(row, variance)| {
                        let noise: f64 = StandardNormal.sample(&mut rng);
                        row.iter().zip(truth).map(|(h, x)| h * x).sum::<f64>()
                            + variance.sqrt() * noise
                    })
                    .collect();
                Measurement {
                    rows,
                    innovation,
                    noise_variance,
                }
            })
            .collect()
    }

    /// The known answer: with no random walk, the filter after n samples holds the
    /// batch least squares of those n samples with its prior, estimate and covariance,
    /// at every n.
    #[test]
    fn without_a_random_walk_the_filter_is_the_batch_least_squares_at_every_sample() {
        let prior = Prior {
            mean: vec![0.1, 0.0, -0.2],
            std: vec![0.5, 2.0, 0.1],
            walk_per_sqrt_s: vec![0.0; 3],
        };
        let all = measurements(300);
        let mut filter = Filter::new(&prior);
        for n in 1..=all.len() {
            let measurement = &all[n - 1];
            // Innovation about the current estimate, as a filter takes it.
            let predicted: Vec<f64> = measurement
                .rows
                .iter()
                .map(|row| {
                    row.iter()
                        .zip(filter.estimate.iter())
                        .map(|(h, x)| h * x)
                        .sum()
                })
                .collect();
            filter.predict(1.0);
            filter.update(&Measurement {
                innovation: measurement
                    .innovation
                    .iter()
                    .zip(predicted)
                    .map(|(y, p)| y - p)
                    .collect(),
                ..measurement.clone()
            });
            let (estimate, covariance) = batch_least_squares(&prior, &all[..n]);
            for i in 0..3 {
                assert!(
                    (filter.estimate[i] - estimate[i]).abs() < 1e-12,
                    "sample {n}, term {i}: {} vs {}",
                    filter.estimate[i],
                    estimate[i]
                );
                for j in 0..3 {
                    assert!((filter.covariance[(i, j)] - covariance[(i, j)]).abs() < 1e-14);
                }
            }
        }
    }

    #[test]
    fn a_random_walk_widens_the_covariance_by_its_variance_per_second() {
        let mut filter = Filter::new(&Prior {
            mean: vec![0.0, 0.0],
            std: vec![1.0, 2.0],
            walk_per_sqrt_s: vec![0.1, 0.0],
        });
        filter.predict(4.0);
        assert!((filter.covariance[(0, 0)] - 1.04).abs() < 1e-15);
        assert_eq!(filter.covariance[(1, 1)], 4.0);
    }
}
