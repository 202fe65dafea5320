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
use burn::tensor::{Device, Gradients, Tensor, TensorData};
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
        let tracked = tensor.device().is_autodiff();
        let size = tensor.shape().num_elements();
        let means = &mut self.optimizer.square_avg;
        if means.len() == index {
            means.push(vec![0.0; size]);
        }
        let mean = &mut means[index];
        assert_eq!(mean.len(), size, "RMSProp: parameter {index} changed size");
        let (alpha, epsilon, lr) = (
            self.optimizer.alpha,
            self.optimizer.epsilon,
            self.learning_rate,
        );
        let updated = with_values(grad, |grad| {
            updated(tensor.inner(), |weights| {
                // Chunks of values in parallel, on the model's pool.
                let chunks = weights.par_chunks_mut(VALUES_PER_TASK);
                let chunks = chunks.zip(grad.par_chunks(VALUES_PER_TASK));
                chunks.zip(mean.par_chunks_mut(VALUES_PER_TASK)).for_each(
                    |((weights, grad), mean)| {
                        step_values(weights, grad, mean, |w, g, s| {
                            *s = *s * alpha + g * g * (1.0 - alpha);
                            w - g / (s.sqrt() + epsilon) * lr
                        });
                    },
                );
            })
        });
        let updated = if tracked {
            Tensor::from_inner(updated).require_grad()
        } else {
            updated
        };
        Param::from_mapped_value(id, updated, mapper)
    }
}

crate::kernels::per_instruction_set! {
    /// `weights ← step(weights, grad, mean)` value by value, `step` updating the mean.
    fn step_values<F: [Fn(f32, f32, &mut f32) -> f32]>(
        weights: &mut [f32],
        grad: &[f32],
        mean: &mut [f32],
        step: F,
    ) -> () {
        let n = weights.len();
        let (grad, mean) = (&grad[..n], &mut mean[..n]);
        for i in 0..n {
            weights[i] = step(weights[i], grad[i], &mut mean[i]);
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

/// `tensor` (on a plain device) after `f` has changed its f32 values: in place on Flex
/// where nothing else holds its buffer, as with a model's weights between steps, so that
/// a step writes no new buffer; else on a copy, and the other holders keep the old values.
fn updated<const D: usize>(tensor: Tensor<D>, f: impl FnOnce(&mut [f32])) -> Tensor<D> {
    let (device, shape) = (tensor.device(), tensor.shape());
    let data = if device == Device::flex() {
        let mut primitive = tensor
            .try_into_primitive::<Flex>()
            .expect("a tensor on Flex");
        let whole = primitive
            .as_slice::<f32>()
            .is_some_and(|values| values.len() == primitive.storage::<f32>().len());
        if whole && let Some(values) = primitive.try_storage_mut::<f32>() {
            f(values);
            return Tensor::from_primitive::<Flex>(primitive);
        }
        primitive.into_data()
    } else {
        tensor.into_data()
    };
    let mut values = data.try_into_vec::<f32>().expect("f32 tensors");
    f(&mut values);
    Tensor::from_data(TensorData::new(values, shape), &device)
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::nn::{Linear, LinearConfig};
    use burn::optim::{GradientsParams, RmsPropConfig};

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

    /// A Linear layer of 7 inputs and 3 outputs on Flex with autodiff, and its squared
    /// error from 0.5 on a fixed batch of 5 rows.
    fn layer_and_loss() -> (Linear, impl Fn(&Linear) -> Tensor<1>) {
        let device = Device::flex().autodiff();
        let layer = LinearConfig::new(7, 3).init(&device);
        let x = Tensor::<2>::from_data(
            TensorData::new((0..35).map(|i| (i as f32 * 0.37).sin()).collect(), [5, 7]),
            &device,
        );
        let loss = move |layer: &Linear| (layer.forward(x.clone()) - 0.5).powi_scalar(2).sum();
        (layer, loss)
    }

    /// The address of `layer`'s weight values.
    fn weight_address(layer: &Linear) -> usize {
        let weight = layer.weight.val().inner();
        let weight = weight.try_into_primitive::<Flex>().unwrap();
        weight.as_slice::<f32>().unwrap().as_ptr() as usize
    }

    /// A step writes the new weights over the old where nothing else holds them; where a
    /// clone of the model still does, it writes them to a copy, the same values, and the
    /// clone keeps its own.
    #[test]
    fn a_step_writes_in_place_unless_the_weights_are_shared() {
        let (layer, loss) = layer_and_loss();
        let grads = loss(&layer).backward();
        let step = |layer: Linear| RmsProp::new(0.99, 1e-8).step(5e-3, layer, &grads);
        let (before, address) = (weights(&layer), weight_address(&layer));
        let kept = layer.clone();
        let on_copy = step(layer.clone());
        assert_eq!(weights(&kept), before, "the clone keeps its weights");
        assert_ne!(weight_address(&on_copy), address);
        drop(kept);
        let in_place = step(layer);
        assert_eq!(weight_address(&in_place), address, "stepped in place");
        assert_eq!(weights(&in_place), weights(&on_copy));
        assert_ne!(weights(&in_place), before);
    }

    /// Five steps of ours and of burn's RMSProp (no momentum, not centred) on the same
    /// layer and losses give the same weights, and a saved optimizer resumes the same.
    #[test]
    fn steps_match_burns_rmsprop_and_resume_from_bytes() {
        let (layer, loss) = layer_and_loss();
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
            weights(&LinearConfig::new(7, 3).init(&Device::flex().autodiff()))
        );
    }
}
