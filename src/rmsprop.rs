//! RMSProp as DCNet trains with it (PyTorch's RMSprop with its defaults: no momentum,
//! not centred). In: a model and the gradients of its loss. Out: the model one step on,
//! each parameter's running mean of squared gradients kept here between steps.
//!
//! Per value, with g the gradient, a = `training.rmsprop_alpha` and ε its epsilon:
//! `s ← a·s + (1 − a)·g²`, then `w ← w − lr·g/(√s + ε)`, in one pass over the parameter
//! and its mean, from s = 0 (so the first step is burn's `RmsProp`, whose state starts
//! at (1 − a)·g²; tested against it). burn's optimizer takes the same step in about seven
//! tensor operations a parameter, each a fresh buffer: here one pass reads the weights and
//! the gradient where they lie and writes the new weights and the mean.

use burn::backend::Flex;
use burn::module::{Module, ModuleMapper, Param};
use burn::tensor::{Device, Gradients, Shape, Tensor, TensorData};
use rayon::prelude::*;

/// The optimizer of one model: its settings and each parameter's mean of squared
/// gradients, in the order [`Module::map`] visits the parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct RmsProp {
    alpha: f32,
    epsilon: f32,
    square_avg: Vec<Vec<f32>>,
}

impl RmsProp {
    /// A fresh optimizer: every mean at zero.
    pub fn new(alpha: f32, epsilon: f32) -> Self {
        Self {
            alpha,
            epsilon,
            square_avg: Vec::new(),
        }
    }

    /// `model` after one step of `learning_rate` along `grads`; a parameter without a
    /// gradient stays as it is.
    pub fn step<M: Module>(&mut self, learning_rate: f64, model: M, grads: &Gradients) -> M {
        model.map(&mut Step {
            optimizer: self,
            learning_rate: learning_rate as f32,
            grads,
            next: 0,
        })
    }

    /// The means, as a checkpoint saves them.
    pub fn to_bytes(&self) -> Vec<u8> {
        rmp_serde::to_vec(&self.square_avg).expect("a list of f32 lists serialises")
    }

    /// This optimizer with the means of `bytes`, as [`RmsProp::to_bytes`] saved them.
    pub fn with_bytes(self, bytes: &[u8]) -> Result<Self, String> {
        let square_avg = rmp_serde::from_slice(bytes).map_err(|e| e.to_string())?;
        Ok(Self { square_avg, ..self })
    }
}

/// Values of a parameter updated per task of the pool.
const VALUES_PER_TASK: usize = 8192;

/// One step over a module's parameters, in visiting order.
struct Step<'a> {
    optimizer: &'a mut RmsProp,
    learning_rate: f32,
    grads: &'a Gradients,
    next: usize,
}

impl ModuleMapper for Step<'_> {
    fn map_float<const D: usize>(&mut self, param: Param<Tensor<D>>) -> Param<Tensor<D>> {
        let index = self.next;
        self.next += 1;
        let (id, tensor, mapper) = param.consume();
        let Some(grad) = tensor.grad(self.grads) else {
            return Param::from_mapped_value(id, tensor, mapper);
        };
        let (device, shape) = (tensor.device(), tensor.shape());
        let tracked = device.is_autodiff();
        let means = &mut self.optimizer.square_avg;
        if means.len() == index {
            means.push(vec![0.0; shape.num_elements()]);
        }
        let mean = &mut means[index];
        assert_eq!(
            mean.len(),
            shape.num_elements(),
            "RMSProp: parameter {index} changed size"
        );
        let (alpha, epsilon, lr) = (
            self.optimizer.alpha,
            self.optimizer.epsilon,
            self.learning_rate,
        );
        let updated = with_values(tensor.inner(), |weights| {
            with_values(grad, |grad| {
                let mut updated = vec![0.0; weights.len()];
                // Chunks of values in parallel, on the model's pool.
                let chunks = updated.par_chunks_mut(VALUES_PER_TASK);
                let chunks = chunks.zip(weights.par_chunks(VALUES_PER_TASK));
                let chunks = chunks.zip(grad.par_chunks(VALUES_PER_TASK));
                chunks.zip(mean.par_chunks_mut(VALUES_PER_TASK)).for_each(
                    |(((updated, weights), grad), mean)| {
                        step_values(weights, grad, mean, updated, |w, g, s| {
                            *s = *s * alpha + g * g * (1.0 - alpha);
                            w - g / (s.sqrt() + epsilon) * lr
                        });
                    },
                );
                updated
            })
        });
        let updated = on_device(updated, shape, &device);
        let updated = if tracked {
            Tensor::from_inner(updated).require_grad()
        } else {
            updated
        };
        Param::from_mapped_value(id, updated, mapper)
    }
}

crate::kernels::per_instruction_set! {
    /// `updated ← step(weights, grad, mean)` value by value, `step` updating the mean.
    fn step_values<F: [Fn(f32, f32, &mut f32) -> f32]>(
        weights: &[f32],
        grad: &[f32],
        mean: &mut [f32],
        updated: &mut [f32],
        step: F,
    ) -> () {
        let n = updated.len();
        let (weights, grad, mean) = (&weights[..n], &grad[..n], &mut mean[..n]);
        for i in 0..n {
            updated[i] = step(weights[i], grad[i], &mut mean[i]);
        }
    }
}

/// `f` of `tensor`'s f32 values: read where they lie on Flex, copied out elsewhere.
fn with_values<const D: usize, R>(tensor: Tensor<D>, f: impl FnOnce(&[f32]) -> R) -> R {
    if let Ok(primitive) = tensor.clone().try_into_primitive::<Flex>()
        && let Some(values) = primitive.as_slice::<f32>()
    {
        return f(values);
    }
    f(&tensor
        .into_data()
        .try_into_vec::<f32>()
        .expect("f32 tensors"))
}

/// `values` as a tensor of `shape` on the plain (no autodiff) backend of `device`: on
/// Flex, on their own buffer with no copy.
fn on_device<const D: usize>(values: Vec<f32>, shape: Shape, device: &Device) -> Tensor<D> {
    let inner = device.clone().inner();
    if inner == Device::flex() {
        return Tensor::from_primitive::<Flex>(crate::kernels::f32_tensor(values, shape));
    }
    Tensor::from_data(TensorData::new(values, shape), &inner)
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::nn::{Linear, LinearConfig};
    use burn::optim::{GradientsParams, RmsPropConfig};
    use burn::tensor::Device;

    fn weights(layer: &Linear) -> Vec<f32> {
        let mut values = layer.weight.val().into_data().try_to_vec::<f32>().unwrap();
        values.extend(
            layer
                .bias
                .as_ref()
                .unwrap()
                .val()
                .into_data()
                .try_to_vec::<f32>()
                .unwrap(),
        );
        values
    }

    /// Five steps of ours and of burn's RMSProp (no momentum, not centred) on the same
    /// layer and losses give the same weights, and a saved optimizer resumes the same.
    #[test]
    fn steps_match_burns_rmsprop_and_resume_from_bytes() {
        let device = Device::flex().autodiff();
        let layer = LinearConfig::new(7, 3).init(&device);
        let x = Tensor::<2>::from_data(
            TensorData::new((0..35).map(|i| (i as f32 * 0.37).sin()).collect(), [5, 7]),
            &device,
        );
        let loss = |layer: &Linear| (layer.forward(x.clone()) - 0.5).powi_scalar(2).sum();
        let (alpha, epsilon, lr) = (0.99, 1e-8, 5e-3);
        let mut theirs_optimizer = RmsPropConfig::new()
            .with_alpha(alpha)
            .with_epsilon(epsilon)
            .with_momentum(0.0)
            .init();
        let (mut ours, mut theirs) = (layer.clone(), layer);
        let mut optimizer = RmsProp::new(alpha, epsilon);
        for step in 0..5 {
            if step == 3 {
                optimizer = RmsProp::new(alpha, epsilon)
                    .with_bytes(&optimizer.to_bytes())
                    .unwrap();
            }
            ours = optimizer.step(lr, ours.clone(), &loss(&ours).backward());
            let grads = GradientsParams::from_grads(loss(&theirs).backward(), &theirs);
            theirs = theirs_optimizer.step(lr, theirs, grads);
            let (a, b) = (weights(&ours), weights(&theirs));
            for (i, (x, y)) in a.iter().zip(&b).enumerate() {
                assert!(
                    (x - y).abs() <= 1e-6 * (1.0 + y.abs()),
                    "step {step}, value {i}: {x} vs {y}"
                );
            }
        }
        assert_ne!(
            weights(&ours),
            weights(&LinearConfig::new(7, 3).init(&device))
        );
    }
}
