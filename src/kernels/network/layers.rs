//! The network's nine layers as the fused operation applies them: how many inputs,
//! outputs and positions each has, and its activation, applied forward and backward
//! in one pass with the bias and the dropout mask.
//! In: the network's shape and parameters. Out: [`Layer`]s.

use super::{LAYERS, NetworkShape, PARAMETERS};
use crate::kernels::activation::{leaky_relu_f32, tanh_f32};

/// How one layer is applied at each window: on `positions` rows of `inputs` values.
#[derive(Debug, Clone, Copy)]
pub(super) struct Layer {
    pub(super) inputs: usize,
    pub(super) outputs: usize,
    pub(super) positions: usize,
    pub(super) activation: Activation,
}

#[derive(Debug, Clone, Copy)]
pub(super) enum Activation {
    Identity,
    Tanh,
    Leaky(f32),
}

impl Activation {
    /// `values ← act(values + bias)`, row by row, at the CPU's widest vectors.
    pub(super) fn forward(self, values: &mut [f32], bias: &[f32]) {
        match self {
            Activation::Identity => add_bias_then(values, bias, |v| v),
            Activation::Tanh => add_bias_then(values, bias, tanh_f32),
            Activation::Leaky(slope) => {
                add_bias_then(values, bias, move |v| leaky_relu_f32(v, slope))
            }
        }
    }

    /// `grad ← act′ · grad ⊙ mask` in place, from the activation's output `activated`.
    pub(super) fn backward(self, grad: &mut [f32], activated: &[f32], mask: Option<&[f32]>) {
        match self {
            Activation::Identity => times_derivative(grad, activated, mask, |_, g| g),
            Activation::Tanh => times_derivative(grad, activated, mask, |y, g| g * (1.0 - y * y)),
            Activation::Leaky(slope) => {
                times_derivative(
                    grad,
                    activated,
                    mask,
                    move |y, g| {
                        if y <= 0.0 { g * slope } else { g }
                    },
                )
            }
        }
    }
}

per_instruction_set! {
    /// `values ← f(values + bias)`, row by row.
    fn add_bias_then<F: [Fn(f32) -> f32]>(values: &mut [f32], bias: &[f32], f: F) -> () {
        for row in values.chunks_exact_mut(bias.len()) {
            for (v, &b) in row.iter_mut().zip(bias) {
                *v = f(*v + b);
            }
        }
    }
}

per_instruction_set! {
    /// `grad ← f(y, grad · mask)` (or `f(y, grad)` without a mask), element by element.
    fn times_derivative<F: [Fn(f32, f32) -> f32]>(
        grad: &mut [f32],
        activated: &[f32],
        mask: Option<&[f32]>,
        f: F,
    ) -> () {
        match mask {
            Some(mask) => {
                for ((g, &y), &m) in grad.iter_mut().zip(activated).zip(mask) {
                    *g = f(y, *g * m);
                }
            }
            None => {
                for (g, &y) in grad.iter_mut().zip(activated) {
                    *g = f(y, *g);
                }
            }
        }
    }
}

per_instruction_set! {
    /// `sum ← f(sum, values)`, element by element.
    pub(super) fn combine<F: [Fn(f32, f32) -> f32]>(sum: &mut [f32], values: &[f32], f: F) -> () {
        for (s, &v) in sum.iter_mut().zip(values) {
            *s = f(*s, v);
        }
    }
}

/// The nine layers of a network with these parameters, in parameter order.
pub(super) fn layers(shape: &NetworkShape, params: &[&[f32]; PARAMETERS]) -> [Layer; LAYERS] {
    let (time, kernel) = (shape.time, shape.kernel);
    let head = Activation::Leaky(shape.head_slope);
    let fc = shape
        .fc_leaky_slope
        .map_or(Activation::Tanh, Activation::Leaky);
    let positions = [
        time + 1 - kernel,
        time + 2 - 2 * kernel,
        3 * (time - 1),
        2 * (time - 2),
        time - 3,
        1,
        1,
        1,
        1,
    ];
    let activations = [
        head,
        head,
        head,
        head,
        head,
        fc,
        fc,
        fc,
        Activation::Identity,
    ];
    std::array::from_fn(|i| {
        let outputs = params[2 * i + 1].len();
        Layer {
            inputs: params[2 * i].len() / outputs,
            outputs,
            positions: positions[i],
            activation: activations[i],
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The vectorised passes (AVX-512 or AVX2 where the CPU has them) give the bits of the
    /// scalar functions, over lengths whose vector loops and scalar tails both run.
    #[test]
    fn every_instruction_set_gives_the_same_bits() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let bias: Vec<f32> = (0..17).map(|_| rng.random_range(-1.0..1.0)).collect();
        let values: Vec<f32> = (0..17 * 59)
            .map(|_| rng.random_range(-12.0..12.0))
            .collect();
        for activation in [Activation::Tanh, Activation::Leaky(0.05)] {
            let mut vectorised = values.clone();
            activation.forward(&mut vectorised, &bias);
            let mut grad = values.clone();
            activation.backward(&mut grad, &vectorised, Some(&bias.repeat(59)));
            for (i, (x, &y)) in values.iter().zip(&vectorised).enumerate() {
                let z = x + bias[i % 17];
                let scalar = match activation {
                    Activation::Tanh => tanh_f32(z),
                    _ => leaky_relu_f32(z, 0.05),
                };
                assert_eq!(scalar.to_bits(), y.to_bits(), "{activation:?}({z})");
                let g = x * bias[i % 17];
                let derivative = match activation {
                    Activation::Tanh => g * (1.0 - y * y),
                    _ if y <= 0.0 => g * 0.05,
                    _ => g,
                };
                assert_eq!(
                    derivative.to_bits(),
                    grad[i].to_bits(),
                    "{activation:?}′ at {y}"
                );
            }
        }
    }
}
