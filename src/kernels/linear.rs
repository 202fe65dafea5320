//! A Linear layer with its activation and dropout mask as one backend operation: rows `x`
//! `[rows, inputs]`, a weight `[inputs, outputs]`, a bias `[outputs]` and optionally a mask
//! `[rows, outputs]` come in; `act(x·W + b) ⊙ mask` `[rows, outputs]` goes out.
//!
//! On Flex with f32 values the product is the `gemm` call Flex's matrix product makes, into
//! an aligned buffer of our own (Flex's product fills an unaligned one, then copies it), and
//! the bias, the activation and the mask follow in one pass over that buffer. Under autodiff
//! one backward node serves the three parents: the pre-activation gradient `g ⊙ mask ⊙ act′`
//! in one pass, then the input and weight gradients through the products burn's Linear
//! backward takes (`linear_x_backward`, `linear_weight_backward`: `g·Wᵀ`, `xᵀ·g`, the same
//! `gemm` calls) and the bias gradient through `linear_bias_backward`. Every float operation
//! is the one burn's Linear, the [`activation`](super::activation) kernels and a mask
//! multiplication perform, in the same order, so values and gradients are the same bits as
//! those composed operations (tested).
//! On any other backend or dtype the layer is those composed operations.

use super::activation::{leaky_relu_f32, tanh_f32};
use burn::backend::autodiff::checkpoint::base::Checkpointer;
use burn::backend::autodiff::checkpoint::strategy::CheckpointStrategy;
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind};
use burn::backend::flex::{FlexTensor, Layout};
use burn::backend::ops::ModuleOps;
use burn::backend::tensor::FloatTensor;
use burn::backend::{Autodiff, Backend, Dispatch, Flex, backend_extension};
use burn::nn::Linear;
use burn::tensor::{Bytes, DType, Device, Shape, Tensor};

/// The function a layer applies after its bias.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LayerActivation {
    /// None: the layer's output is `x·W + b`.
    Identity,
    Tanh,
    /// `x` where `x > 0`, `slope·x` elsewhere; `slope` ≥ 0.
    LeakyRelu {
        slope: f64,
    },
}

/// `activation(x·W + b)`, times `mask` elementwise when one is given, for rows `x`
/// `[rows, inputs]` and a Linear layer with a bias: one fused operation on Flex, burn's
/// Linear, the activation and a multiplication elsewhere. The parameters' gradients reach
/// `layer.weight` and `layer.bias` as through `layer.forward`.
pub fn linear(
    x: Tensor<2>,
    layer: &Linear,
    activation: LayerActivation,
    mask: Option<Tensor<2>>,
) -> Tensor<2> {
    if let LayerActivation::LeakyRelu { slope } = activation {
        assert!(slope >= 0.0, "linear: LeakyReLU slope {slope} is negative");
    }
    let bias = layer.bias.as_ref().map(|bias| bias.val());
    match bias {
        Some(bias) if fused(&x) => {
            let (x, weight, bias) = (
                x.into_dispatch(),
                layer.weight.val().into_dispatch(),
                bias.into_dispatch(),
            );
            Tensor::from_dispatch(match mask {
                None => <Dispatch as LinearBackend>::activated_linear(x, weight, bias, activation),
                Some(mask) => <Dispatch as LinearBackend>::masked_linear(
                    x,
                    weight,
                    bias,
                    activation,
                    mask.into_dispatch(),
                ),
            })
        }
        _ => composed(x, layer, activation, mask),
    }
}

/// Whether `x` takes the fused kernel: f32 values on Flex, with or without autodiff.
fn fused(x: &Tensor<2>) -> bool {
    x.dtype() == DType::F32 && x.device().inner() == Device::flex()
}

/// The layer as the network composed it before this kernel: burn's Linear, the activation
/// kernel, a multiplication by the mask.
fn composed(
    x: Tensor<2>,
    layer: &Linear,
    activation: LayerActivation,
    mask: Option<Tensor<2>>,
) -> Tensor<2> {
    let y = layer.forward(x);
    let y = match activation {
        LayerActivation::Identity => y,
        LayerActivation::Tanh => super::activation::tanh(y),
        LayerActivation::LeakyRelu { slope } => super::activation::leaky_relu(y, slope),
    };
    match mask {
        Some(mask) => y * mask,
        None => y,
    }
}

/// The fused layer as a backend operation. Implemented for Flex (forward) and for
/// `Autodiff<Flex>` (forward plus one hand-written backward); [`linear`] routes every other
/// backend to composed operations, so nothing else implements it.
#[backend_extension(Autodiff, Flex)]
pub trait LinearBackend: Backend {
    /// `activation(x·weight + bias)`: `x` `[rows, inputs]`, `weight` `[inputs, outputs]`,
    /// `bias` `[outputs]`.
    fn activated_linear(
        x: FloatTensor<Self>,
        weight: FloatTensor<Self>,
        bias: FloatTensor<Self>,
        activation: LayerActivation,
    ) -> FloatTensor<Self>;

    /// `activation(x·weight + bias) ⊙ mask`, `mask` `[rows, outputs]`.
    fn masked_linear(
        x: FloatTensor<Self>,
        weight: FloatTensor<Self>,
        bias: FloatTensor<Self>,
        activation: LayerActivation,
        mask: FloatTensor<Self>,
    ) -> FloatTensor<Self>;
}

impl LinearBackend for Flex {
    fn activated_linear(
        x: FlexTensor,
        weight: FlexTensor,
        bias: FlexTensor,
        activation: LayerActivation,
    ) -> FlexTensor {
        forward(x, weight, &bias, activation, None).0
    }

    fn masked_linear(
        x: FlexTensor,
        weight: FlexTensor,
        bias: FlexTensor,
        activation: LayerActivation,
        mask: FlexTensor,
    ) -> FlexTensor {
        let (_, masked) = forward(x, weight, &bias, activation, Some(&mask));
        masked.expect("a mask gives a masked output")
    }
}

impl<C: CheckpointStrategy> LinearBackend for Autodiff<Flex, C> {
    fn activated_linear(
        x: FloatTensor<Self>,
        weight: FloatTensor<Self>,
        bias: FloatTensor<Self>,
        activation: LayerActivation,
    ) -> FloatTensor<Self> {
        tracked_linear::<C>(x, weight, bias, activation, None)
    }

    fn masked_linear(
        x: FloatTensor<Self>,
        weight: FloatTensor<Self>,
        bias: FloatTensor<Self>,
        activation: LayerActivation,
        mask: FloatTensor<Self>,
    ) -> FloatTensor<Self> {
        tracked_linear::<C>(x, weight, bias, activation, Some(mask.into_primitive()))
    }
}

/// What the backward reads: the input (for the weight's gradient), the weight (for
/// the input's), the activation's output before the mask, and the mask.
#[derive(Debug, Clone)]
struct LinearState {
    x: Option<FlexTensor>,
    weight: Option<FlexTensor>,
    activated: FlexTensor,
    mask: Option<FlexTensor>,
}

/// Parents x, weight, bias. The pre-activation gradient g ⊙ mask ⊙ act′(y) in one
/// pass; then burn's Linear backward operations on it.
#[derive(Debug)]
struct LinearStep {
    activation: LayerActivation,
}

impl Backward<Flex, 3> for LinearStep {
    type State = LinearState;

    fn backward(
        self,
        ops: Ops<Self::State, 3>,
        grads: &mut Gradients,
        _checkpointer: &mut Checkpointer,
    ) {
        let [node_x, node_weight, node_bias] = ops.parents;
        let grad = grads.consume::<Flex>(&ops.node);
        let state = ops.state;
        let grad =
            pre_activation_grad(grad, &state.activated, state.mask.as_ref(), self.activation);
        if let Some(node) = node_x {
            // burn's linear_x_backward: g·Wᵀ, the transpose a view.
            let weight = state.weight.expect("the weight is kept for x's gradient");
            let input_grad = product(&grad, &weight.transpose(0, 1));
            grads.register::<Flex>(node.id, input_grad);
        }
        if let Some(node) = node_weight {
            // burn's linear_weight_backward on 2-D x: xᵀ·g, the transpose a view.
            let x = state.x.expect("x is kept for the weight's gradient");
            let weight_grad = product(&x.transpose(0, 1), &grad);
            grads.register::<Flex>(node.id, weight_grad);
        }
        if let Some(node) = node_bias {
            grads.register::<Flex>(
                node.id,
                <Flex as ModuleOps<Flex>>::linear_bias_backward(grad),
            );
        }
    }
}

/// The fused layer under autodiff: the forward of [`forward`], and one backward node whose
/// parents are `x`, `weight` and `bias`.
fn tracked_linear<C: CheckpointStrategy>(
    x: FloatTensor<Autodiff<Flex, C>>,
    weight: FloatTensor<Autodiff<Flex, C>>,
    bias: FloatTensor<Autodiff<Flex, C>>,
    activation: LayerActivation,
    mask: Option<FlexTensor>,
) -> FloatTensor<Autodiff<Flex, C>> {
    let x_tracked = x.is_tracked();
    let weight_tracked = weight.is_tracked();
    let step = LinearStep { activation };
    match step
        .prepare::<C>([x.node(), weight.node(), bias.node()])
        .compute_bound()
        .stateful()
    {
        OpsKind::Tracked(prep) => {
            // x is needed only for the weight's gradient, and the weight only for x's.
            let x = x.into_primitive();
            let weight = weight.into_primitive();
            let kept_x = weight_tracked.then(|| x.clone());
            let kept_weight = x_tracked.then(|| weight.clone());
            let (activated, masked) =
                forward(x, weight, bias.primitive(), activation, mask.as_ref());
            let output = masked.unwrap_or_else(|| activated.clone());
            let state = LinearState {
                x: kept_x,
                weight: kept_weight,
                activated,
                mask,
            };
            prep.finish(state, output)
        }
        OpsKind::UnTracked(prep) => {
            let (activated, masked) = forward(
                x.into_primitive(),
                weight.into_primitive(),
                bias.primitive(),
                activation,
                mask.as_ref(),
            );
            prep.finish(masked.unwrap_or(activated))
        }
    }
}

/// `activation(x·weight + bias)`, computed in place in the product's buffer, and, given a
/// mask, that times the mask in a fresh buffer written in the same pass.
fn forward(
    x: FlexTensor,
    weight: FlexTensor,
    bias: &FlexTensor,
    activation: LayerActivation,
    mask: Option<&FlexTensor>,
) -> (FlexTensor, Option<FlexTensor>) {
    let mut activated = product_values(&x, &weight);
    let shape = Shape::new([x.layout().shape()[0], weight.layout().shape()[1]]);
    let bias = values(bias);
    assert_eq!(bias.len(), shape[1], "fused linear: bias length");
    let mask = mask.map(values);
    let masked = match activation {
        LayerActivation::Identity => apply(&mut activated, &bias, mask.as_deref(), |v| v),
        LayerActivation::Tanh => apply(&mut activated, &bias, mask.as_deref(), tanh_f32),
        LayerActivation::LeakyRelu { slope } => {
            let slope = slope as f32;
            apply(&mut activated, &bias, mask.as_deref(), move |v| {
                leaky_relu_f32(v, slope)
            })
        }
    };
    let masked = masked.map(|values| f32_tensor(values, shape.clone()));
    (f32_tensor(activated, shape), masked)
}

/// Products of at least this many multiply-adds (`m·n·k`) run on the rayon pool: Flex's
/// threshold for its matrix product.
const PARALLEL_PRODUCT: usize = 192 * 192 * 192;

/// `lhs·rhs` of two 2-D f32 tensors of any strides as a contiguous `[m, n]` tensor on an
/// aligned buffer: the bits of Flex's `float_matmul`.
fn product(lhs: &FlexTensor, rhs: &FlexTensor) -> FlexTensor {
    let shape = Shape::new([lhs.layout().shape()[0], rhs.layout().shape()[1]]);
    f32_tensor(product_values(lhs, rhs), shape)
}

/// The values of `lhs·rhs` (`[m, k]·[k, n]`, any strides) in row-major order, by the very
/// `gemm` call Flex's 2-D matrix product makes (strides read from the layouts, `dst ←
/// 0·dst + 1·lhs·rhs` without reading `dst`, no conjugation, rayon from
/// [`PARALLEL_PRODUCT`] multiply-adds on) but into a zeroed `Vec` rather than Flex's
/// byte buffer, which is realigned by a copy.
fn product_values(lhs: &FlexTensor, rhs: &FlexTensor) -> Vec<f32> {
    let (lhs_layout, rhs_layout) = (lhs.layout(), rhs.layout());
    let (lhs_shape, rhs_shape) = (lhs_layout.shape(), rhs_layout.shape());
    assert!(
        lhs_shape.num_dims() == 2 && rhs_shape.num_dims() == 2,
        "fused linear: 2-D products only"
    );
    assert!(
        lhs.dtype() == DType::F32 && rhs.dtype() == DType::F32,
        "fused linear: f32 only"
    );
    let (m, k, n) = (lhs_shape[0], lhs_shape[1], rhs_shape[1]);
    assert_eq!(rhs_shape[0], k, "fused linear: inner dimensions");
    let (lhs_row, lhs_column) = (lhs_layout.strides()[0], lhs_layout.strides()[1]);
    let (rhs_row, rhs_column) = (rhs_layout.strides()[0], rhs_layout.strides()[1]);
    let lhs_start = lhs
        .storage::<f32>()
        .as_ptr()
        .wrapping_add(lhs_layout.start_offset());
    let rhs_start = rhs
        .storage::<f32>()
        .as_ptr()
        .wrapping_add(rhs_layout.start_offset());
    let parallelism = if m.saturating_mul(n).saturating_mul(k) >= PARALLEL_PRODUCT {
        gemm::Parallelism::Rayon(0)
    } else {
        gemm::Parallelism::None
    };
    let mut output = vec![0.0f32; m * n];
    // SAFETY: each layout addresses elements of its tensor's storage only (Flex's
    // invariant, which its own product relies on the same way), the storages outlive the
    // call, and `output` holds `m·n` elements at row stride `n`, column stride 1.
    unsafe {
        gemm::gemm(
            m,
            n,
            k,
            output.as_mut_ptr(),
            1,
            n as isize,
            false,
            lhs_start,
            lhs_column,
            lhs_row,
            rhs_start,
            rhs_column,
            rhs_row,
            0.0,
            1.0,
            false,
            false,
            false,
            parallelism,
        );
    }
    output
}

/// The gradient before the activation from the output's: `g ⊙ mask ⊙ act′(y)` with `y` the
/// activation's output (before the mask), as the mask's multiplication and the activation
/// kernel's backward compute it one after the other.
fn pre_activation_grad(
    grad: FlexTensor,
    activated: &FlexTensor,
    mask: Option<&FlexTensor>,
    activation: LayerActivation,
) -> FlexTensor {
    let shape = activated.layout().shape().clone();
    assert_eq!(
        &shape,
        grad.layout().shape(),
        "fused linear: gradient shape"
    );
    let grad_values = values(&grad);
    let mask_values = mask.map(values);
    let activated = values(activated);
    let mask = mask_values.as_deref();
    let output = match activation {
        LayerActivation::Identity => match mask {
            None => return grad,
            Some(_) => derivative(&grad_values, &activated, mask, |_, g| g),
        },
        LayerActivation::Tanh => {
            derivative(&grad_values, &activated, mask, |y, g| g * (1.0 - y * y))
        }
        LayerActivation::LeakyRelu { slope } => {
            let slope = slope as f32;
            derivative(&grad_values, &activated, mask, move |y, g| {
                if y <= 0.0 { g * slope } else { g }
            })
        }
    };
    f32_tensor(output, shape)
}

/// The tensor's f32 values in row-major order: its storage where that is one contiguous
/// run, a contiguous copy otherwise.
fn values(x: &FlexTensor) -> std::borrow::Cow<'_, [f32]> {
    assert_eq!(x.dtype(), DType::F32, "fused linear: f32 only");
    match x.as_slice::<f32>() {
        Some(values) => std::borrow::Cow::Borrowed(values),
        None => std::borrow::Cow::Owned(
            x.to_contiguous()
                .as_slice::<f32>()
                .expect("a contiguous copy is one run")
                .to_vec(),
        ),
    }
}

/// A contiguous f32 tensor on a `Vec`'s buffer (aligned, so burn never copies it).
fn f32_tensor(values: Vec<f32>, shape: Shape) -> FlexTensor {
    FlexTensor::new(
        Bytes::from_elems(values),
        Layout::contiguous(shape),
        DType::F32,
    )
}

per_instruction_set! {
    /// Row by row: `values ← f(values + bias)`, and with a mask a fresh `values · mask`, at
    /// the CPU's widest vectors (`per_instruction_set!`).
    fn apply<F: [Fn(f32) -> f32]>(
        values: &mut [f32],
        bias: &[f32],
        mask: Option<&[f32]>,
        f: F,
    ) -> Option<Vec<f32>> {
        let width = bias.len();
        match mask {
            None => {
                for row in values.chunks_exact_mut(width) {
                    for (v, &b) in row.iter_mut().zip(bias) {
                        *v = f(*v + b);
                    }
                }
                None
            }
            Some(mask) => {
                assert_eq!(mask.len(), values.len(), "fused linear: mask shape");
                let mut masked = Vec::with_capacity(values.len());
                let spare = &mut masked.spare_capacity_mut()[..values.len()];
                for ((row, mask_row), out_row) in values
                    .chunks_exact_mut(width)
                    .zip(mask.chunks_exact(width))
                    .zip(spare.chunks_exact_mut(width))
                {
                    for (((v, &b), &m), out) in row.iter_mut().zip(bias).zip(mask_row).zip(out_row)
                    {
                        let a = f(*v + b);
                        *v = a;
                        out.write(a * m);
                    }
                }
                // SAFETY: the loop has just written all values.len() elements.
                unsafe { masked.set_len(values.len()) };
                Some(masked)
            }
        }
    }
}

per_instruction_set! {
    /// `f(y, g · mask)` (or `f(y, g)` without a mask) over each element, into a fresh `Vec`;
    /// compiled for each instruction set like [`apply`].
    fn derivative<F: [Fn(f32, f32) -> f32]>(
        grad: &[f32],
        activated: &[f32],
        mask: Option<&[f32]>,
        f: F,
    ) -> Vec<f32> {
        let count = grad.len();
        assert_eq!(activated.len(), count, "fused linear: gradient shape");
        let mut output = Vec::with_capacity(count);
        let spare = &mut output.spare_capacity_mut()[..count];
        match mask {
            None => {
                for ((out, &g), &y) in spare.iter_mut().zip(grad).zip(activated) {
                    out.write(f(y, g));
                }
            }
            Some(mask) => {
                assert_eq!(mask.len(), count, "fused linear: mask shape");
                for (((out, &g), &y), &m) in spare.iter_mut().zip(grad).zip(activated).zip(mask) {
                    out.write(f(y, g * m));
                }
            }
        }
        // SAFETY: the loop has just written all `count` elements.
        unsafe { output.set_len(count) };
        output
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::module::Param;
    use burn::nn::LinearConfig;
    use burn::tensor::TensorData;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random<const D: usize>(
        shape: [usize; D],
        scale: f32,
        rng: &mut ChaCha8Rng,
        device: &Device,
    ) -> Tensor<D> {
        let count = shape.iter().product();
        let values: Vec<f32> = (0..count)
            .map(|_| rng.random_range(-scale..scale))
            .collect();
        Tensor::from_data(TensorData::new(values, shape), device)
    }

    fn bits<const D: usize>(x: Tensor<D>) -> Vec<u32> {
        x.into_data()
            .try_to_vec::<f32>()
            .unwrap()
            .iter()
            .map(|v| v.to_bits())
            .collect()
    }

    fn largest_difference(a: Tensor<2>, b: Tensor<2>) -> f32 {
        let a = a.into_data().try_to_vec::<f32>().unwrap();
        let b = b.into_data().try_to_vec::<f32>().unwrap();
        a.iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f32::max)
    }

    /// A tensor that requires its gradient on an autodiff device.
    fn tracked<const D: usize>(tensor: Tensor<D>) -> Tensor<D> {
        if tensor.device().is_autodiff() {
            tensor.require_grad()
        } else {
            tensor
        }
    }

    /// A Linear layer `[inputs, outputs]` with random weight and bias, tracked on an
    /// autodiff device.
    fn layer(inputs: usize, outputs: usize, rng: &mut ChaCha8Rng, device: &Device) -> Linear {
        let mut layer = LinearConfig::new(inputs, outputs).init(device);
        layer.weight = Param::from_tensor(tracked(random([inputs, outputs], 0.7, rng, device)));
        layer.bias = Some(Param::from_tensor(tracked(random(
            [outputs],
            0.7,
            rng,
            device,
        ))));
        layer
    }

    /// A dropout mask: 0 with probability ¼, 4/3 elsewhere.
    fn mask(shape: [usize; 2], rng: &mut ChaCha8Rng, device: &Device) -> Tensor<2> {
        let values: Vec<f32> = (0..shape[0] * shape[1])
            .map(|_| {
                if rng.random_range(0.0..1.0) < 0.25 {
                    0.0
                } else {
                    4.0 / 3.0
                }
            })
            .collect();
        Tensor::from_data(TensorData::new(values, shape), device)
    }

    type Layer = fn(Tensor<2>, &Linear, LayerActivation, Option<Tensor<2>>) -> Tensor<2>;

    const ACTIVATIONS: [LayerActivation; 4] = [
        LayerActivation::Identity,
        LayerActivation::Tanh,
        LayerActivation::LeakyRelu { slope: 0.05 },
        LayerActivation::LeakyRelu { slope: 0.0 },
    ];

    /// Forward and the three gradients, under loss = Σ w·layer(x), for the fused and the
    /// composed layer on the same random values of shape `[rows, inputs] → outputs`: the
    /// same bits (tolerance zero).
    fn assert_same_bits(
        [rows, inputs, outputs]: [usize; 3],
        activation: LayerActivation,
        with_mask: bool,
        rng: &mut ChaCha8Rng,
    ) {
        let device = Device::flex().autodiff();
        let x = random([rows, inputs], 2.0, rng, &device);
        assert!(fused(&x), "autodiff on Flex takes the fused kernel");
        let weights = random([rows, outputs], 1.0, rng, &device);
        let mask = with_mask.then(|| mask([rows, outputs], rng, &device));
        let layer = layer(inputs, outputs, rng, &device);
        let mut results = Vec::new();
        for run in [linear as Layer, composed] {
            let input = x.clone().detach().require_grad();
            let output = run(input.clone(), &layer, activation, mask.clone());
            let grads = (output.clone() * weights.clone()).sum().backward();
            let weight_grad = layer.weight.val().grad(&grads).unwrap();
            let bias_grad = layer.bias.as_ref().unwrap().val().grad(&grads).unwrap();
            results.push([
                bits(output),
                bits(input.grad(&grads).unwrap()),
                bits(weight_grad),
                bits(bias_grad),
            ]);
        }
        for (part, name) in ["output", "x gradient", "weight gradient", "bias gradient"]
            .iter()
            .enumerate()
        {
            assert_eq!(
                results[0][part], results[1][part],
                "{name}: [{rows}, {inputs}] → {outputs}, {activation:?}, mask {with_mask}"
            );
        }
    }

    /// Random shapes, every activation, with and without a mask: the same bits as burn's
    /// Linear, the activation and the mask.
    #[test]
    fn forward_and_gradients_are_the_bits_of_burns_linear_activation_and_mask() {
        let mut rng = ChaCha8Rng::seed_from_u64(27);
        for case in 0..24 {
            let shape = [
                rng.random_range(1..300),
                rng.random_range(1..70),
                rng.random_range(1..40),
            ];
            let activation = ACTIVATIONS[case % ACTIVATIONS.len()];
            assert_same_bits(shape, activation, case % 8 >= 4, &mut rng);
        }
    }

    /// Products past Flex's threshold for running on the rayon pool (forward and both
    /// gradient products: 2000·64·60 multiply-adds each), still the same bits.
    #[test]
    fn large_products_on_the_rayon_pool_are_the_same_bits() {
        let mut rng = ChaCha8Rng::seed_from_u64(270);
        assert!(2000 * 64 * 60 >= PARALLEL_PRODUCT);
        assert_same_bits([2000, 64, 60], LayerActivation::Tanh, true, &mut rng);
    }

    /// The composed reference itself against burn's own activations, so that the chain ends
    /// at burn: f32 tanh within 1e-6 of burn's, LeakyReLU exactly.
    #[test]
    fn composed_layer_matches_burns_linear_and_activations() {
        let device = Device::flex();
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let x = random([50, 13], 2.0, &mut rng, &device);
        let layer = layer(13, 9, &mut rng, &device);
        let plain = layer.forward(x.clone());
        let tanh = linear(x.clone(), &layer, LayerActivation::Tanh, None);
        let burn_tanh = burn::tensor::activation::tanh(plain.clone());
        let difference = largest_difference(tanh, burn_tanh);
        assert!(difference <= 1e-6, "tanh: {difference}");
        let leaky = linear(
            x.clone(),
            &layer,
            LayerActivation::LeakyRelu { slope: 0.1 },
            None,
        );
        let burn_leaky = burn::tensor::activation::leaky_relu(plain.clone(), 0.1);
        let difference = largest_difference(leaky, burn_leaky);
        assert!(difference <= 1e-6, "leaky: {difference}");
        assert_eq!(
            bits(linear(x, &layer, LayerActivation::Identity, None)),
            bits(plain)
        );
    }

    #[test]
    fn untracked_inputs_and_plain_flex_give_the_same_values() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let plain = Device::flex();
        let x = random([31, 17], 2.0, &mut rng, &plain);
        let mask = mask([31, 6], &mut rng, &plain);
        let layer = layer(17, 6, &mut rng, &plain);
        let want = bits(composed(
            x.clone(),
            &layer,
            LayerActivation::Tanh,
            Some(mask.clone()),
        ));
        let got = bits(linear(
            x.clone(),
            &layer,
            LayerActivation::Tanh,
            Some(mask.clone()),
        ));
        assert_eq!(got, want);
        // A transposed (non-contiguous) input.
        let transposed = random([17, 31], 2.0, &mut rng, &plain).transpose();
        assert_eq!(
            bits(linear(
                transposed.clone(),
                &layer,
                LayerActivation::Identity,
                None
            )),
            bits(composed(
                transposed,
                &layer,
                LayerActivation::Identity,
                None
            ))
        );
    }

    #[test]
    #[allow(deprecated)]
    fn other_backends_compose_burns_operations_unchanged() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let ndarray = Device::ndarray();
        for device in [ndarray.clone(), ndarray.autodiff()] {
            let x = random([6, 9], 3.0, &mut rng, &device);
            let layer = layer(9, 4, &mut rng, &device);
            let mask = mask([6, 4], &mut rng, &device);
            let activation = LayerActivation::LeakyRelu { slope: 0.05 };
            assert_eq!(
                bits(linear(x.clone(), &layer, activation, Some(mask.clone()))),
                bits(composed(x, &layer, activation, Some(mask)))
            );
        }
    }
}
