//! The whole DCNet, both heads and the four Linear layers, as one backend operation over
//! fixed slices of the batch. In: the network's 18 parameters, the two heads' unfolded
//! inputs and the dropout's seed. Out: the terms `[windows, outputs]`; backward, the
//! gradient of every parameter.
//!
//! The batch is cut into [`SLICES`] runs of consecutive windows, as even as the count
//! allows, whatever the number of threads. Each slice runs forward and backward on its own
//! buffers, on whichever core of the rayon pool is free, and the slices' parameter
//! gradients are summed in slice order; so a model's sums are taken in the same order on
//! one core or sixteen, and its bytes do not depend on the thread count.
//!
//! The buffers of a step (activations, their gradients, each slice's parameter gradients)
//! live in a [`Workspace`] that the thread running the step keeps between steps: once the
//! largest batch has been seen, a step allocates nothing but the tensors burn hands back
//! (the terms and one gradient per parameter). Every layer is a `gemm` product into a buffer
//! followed by one pass for the bias, the activation and the mask, in the layer order of
//! the network composed of burn's operations (the model's tests compare the two).

use super::activation::{leaky_relu_f32, tanh_f32};
use super::unfold::GRID_TAPS;
use super::{Reused, f32_tensor, values};
use burn::backend::autodiff::checkpoint::base::Checkpointer;
use burn::backend::autodiff::checkpoint::strategy::NoCheckpointing;
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind};
use burn::backend::flex::FlexTensor;
use burn::backend::tensor::FloatTensor;
use burn::backend::{Autodiff, Flex, TensorMetadata};
use burn::tensor::{DType, Device, Shape, Tensor};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::cell::RefCell;
use std::sync::{Arc, Mutex};

/// The slices a batch is cut into: a constant of the training code, since the order of
/// the gradient sums, and so a trained model's bytes, follow from it.
pub const SLICES: usize = 8;

/// The parameters: a weight `[inputs, outputs]` and a bias `[outputs]` for each layer.
pub const PARAMETERS: usize = 2 * LAYERS;

/// Two Conv1d, three Conv2d, four Linear.
const LAYERS: usize = 9;

/// What the operation needs to know besides the tensors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NetworkShape {
    /// Samples per window.
    pub time: usize,
    /// Time steps of a Conv1d kernel.
    pub kernel: usize,
    /// The heads' LeakyReLU slope (≥ 0).
    pub head_slope: f32,
    /// The first three Linear layers' activation: tanh, or LeakyReLU with this slope.
    pub fc_leaky_slope: Option<f32>,
}

/// Dropout on the first three Linear layers' outputs: each value dropped with probability
/// `p`, the others scaled by 1/(1 − p). The masks are drawn from `seed`, one stream per
/// layer and slice ([`Dropout::slice_mask`]), so each slice draws its own in parallel and
/// the batch's masks do not depend on the thread count either.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dropout {
    pub p: f64,
    pub seed: u64,
}

impl Dropout {
    /// The mask of Linear layer `layer` (0, 1 or 2) over `windows` windows of slice `slice`,
    /// `width` values each, into `out`: one 32-bit draw per value, dropped when below
    /// p·2³².
    fn slice_mask(
        &self,
        layer: usize,
        slice: usize,
        windows: usize,
        width: usize,
        out: &mut Vec<f32>,
    ) {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream((layer * SLICES + slice) as u64);
        let keep = (1.0 / (1.0 - self.p)) as f32;
        let threshold = (self.p * 2f64.powi(32)) as u64;
        resize(out, windows * width);
        let mut draws = [0u32; 64];
        for chunk in out.chunks_mut(draws.len()) {
            let draws = &mut draws[..chunk.len()];
            rng.fill(draws);
            for (value, &draw) in chunk.iter_mut().zip(draws.iter()) {
                *value = if u64::from(draw) < threshold {
                    0.0
                } else {
                    keep
                };
            }
        }
    }

    /// The mask `[windows, width]` of Linear layer `layer` over a batch of `windows`: its
    /// slices' masks one after the other, as the operation draws them.
    pub fn mask(&self, layer: usize, windows: usize, width: usize) -> Vec<f32> {
        let mut mask = Vec::with_capacity(windows * width);
        let mut part = Vec::new();
        for slice in 0..SLICES {
            self.slice_mask(
                layer,
                slice,
                slice_windows(windows, slice).len(),
                width,
                &mut part,
            );
            mask.extend_from_slice(&part);
        }
        mask
    }
}

/// The windows of slice `slice` of a batch of `windows`: consecutive, the first
/// `windows % SLICES` slices one more than the others.
fn slice_windows(windows: usize, slice: usize) -> std::ops::Range<usize> {
    let (base, extra) = (windows / SLICES, windows % SLICES);
    let start = slice * base + slice.min(extra);
    start..start + base + usize::from(slice < extra)
}

/// How one layer is applied at each window: on `positions` rows of `inputs` values.
#[derive(Debug, Clone, Copy)]
struct Layer {
    inputs: usize,
    outputs: usize,
    positions: usize,
    activation: Activation,
}

#[derive(Debug, Clone, Copy)]
enum Activation {
    Identity,
    Tanh,
    Leaky(f32),
}

impl Activation {
    /// `values ← act(values + bias)`, row by row, at the CPU's widest vectors.
    fn forward(self, values: &mut [f32], bias: &[f32]) {
        match self {
            Activation::Identity => add_bias_then(values, bias, |v| v),
            Activation::Tanh => add_bias_then(values, bias, tanh_f32),
            Activation::Leaky(slope) => {
                add_bias_then(values, bias, move |v| leaky_relu_f32(v, slope))
            }
        }
    }

    /// `grad ← act′ · grad ⊙ mask` in place, from the activation's output `activated`.
    fn backward(self, grad: &mut [f32], activated: &[f32], mask: Option<&[f32]>) {
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
    fn combine<F: [Fn(f32, f32) -> f32]>(sum: &mut [f32], values: &[f32], f: F) -> () {
        for (s, &v) in sum.iter_mut().zip(values) {
            *s = f(*s, v);
        }
    }
}

/// The nine layers of a network with these parameters, in parameter order.
fn layers(shape: &NetworkShape, params: &[&[f32]; PARAMETERS]) -> [Layer; LAYERS] {
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

/// Whether the operation runs on `x`'s device and dtype: f32 on Flex, with or without
/// autodiff.
pub fn runs_on(x: &Tensor<2>) -> bool {
    x.dtype() == DType::F32 && x.device().inner() == Device::flex()
}

/// The terms `[windows, outputs]` of the windows whose heads' inputs are `head_1d`
/// `[windows × (time − kernel + 1), channels × kernel]` and `head_2d`
/// `[windows × (time − 1) × 3, 4]`, for the layers' `weights` `[inputs, outputs]` and
/// `biases` `[outputs]` in layer order, with `dropout` where training applies it. On an autodiff device, one
/// backward node gives every parameter's gradient.
pub fn dcnet(
    weights: Vec<Tensor<2>>,
    biases: Vec<Tensor<1>>,
    head_1d: Tensor<2>,
    head_2d: Tensor<2>,
    dropout: Option<Dropout>,
    shape: NetworkShape,
) -> Tensor<2> {
    assert!(runs_on(&head_1d), "dcnet: f32 tensors on Flex only");
    if head_1d.device().is_autodiff() {
        type Tracked = Autodiff<Flex>;
        let tracked = |t: Tensor<2>| {
            t.try_into_primitive::<Tracked>()
                .expect("on Autodiff<Flex>")
        };
        let params: Vec<_> = weights
            .into_iter()
            .zip(biases)
            .flat_map(|(w, b)| {
                let b = b
                    .try_into_primitive::<Tracked>()
                    .expect("on Autodiff<Flex>");
                [tracked(w), b]
            })
            .collect();
        // Data, not parameters: their values only.
        let plain = |t: Tensor<2>| tracked(t).into_primitive();
        let terms = tracked_dcnet(params, plain(head_1d), plain(head_2d), dropout, shape);
        Tensor::from_primitive::<Tracked>(terms)
    } else {
        let plain = |t: Tensor<2>| t.try_into_primitive::<Flex>().expect("on Flex");
        let params = weights
            .into_iter()
            .zip(biases)
            .flat_map(|(w, b)| [plain(w), b.try_into_primitive::<Flex>().expect("on Flex")])
            .collect();
        let inputs = Inputs::new(params, plain(head_1d), plain(head_2d), dropout, shape);
        let mut workspace = Workspace::take();
        let terms = inputs.forward(&mut workspace);
        Workspace::give_back(workspace);
        Tensor::from_primitive::<Flex>(terms)
    }
}

/// The forward under autodiff, with one backward node whose parents are `params`.
fn tracked_dcnet(
    params: Vec<FloatTensor<Autodiff<Flex>>>,
    head_1d: FlexTensor,
    head_2d: FlexTensor,
    dropout: Option<Dropout>,
    shape: NetworkShape,
) -> FloatTensor<Autodiff<Flex>> {
    let nodes: [_; PARAMETERS] = std::array::from_fn(|i| params[i].node());
    let params = params.into_iter().map(|p| p.into_primitive()).collect();
    let inputs = Inputs::new(params, head_1d, head_2d, dropout, shape);
    let mut workspace = Workspace::take();
    let terms = inputs.forward(&mut workspace);
    match NetworkStep
        .prepare::<NoCheckpointing>(nodes)
        .compute_bound()
        .stateful()
    {
        OpsKind::Tracked(prep) => {
            let state = NetworkState {
                inputs: Arc::new(inputs),
                workspace: Arc::new(Mutex::new(Some(workspace))),
            };
            prep.finish(state, terms)
        }
        OpsKind::UnTracked(prep) => {
            Workspace::give_back(workspace);
            prep.finish(terms)
        }
    }
}

/// The one backward node: its parents are the parameters.
#[derive(Debug)]
struct NetworkStep;

/// What the backward reads: the forward's inputs and the workspace holding its activations.
#[derive(Debug, Clone)]
struct NetworkState {
    inputs: Arc<Inputs>,
    workspace: Arc<Mutex<Option<Box<Workspace>>>>,
}

impl Backward<Flex, PARAMETERS> for NetworkStep {
    type State = NetworkState;

    fn backward(
        self,
        ops: Ops<Self::State, PARAMETERS>,
        grads: &mut Gradients,
        _checkpointer: &mut Checkpointer,
    ) {
        let grad = grads.consume::<Flex>(&ops.node).to_contiguous();
        let grad = grad.as_slice::<f32>().expect("contiguous f32");
        let mut workspace = ops
            .state
            .workspace
            .lock()
            .expect("no backward panicked")
            .take()
            .expect("one backward per forward");
        let param_grads = ops.state.inputs.backward(grad, &mut workspace);
        Workspace::give_back(workspace);
        for (node, grad) in ops.parents.into_iter().zip(param_grads) {
            if let Some(node) = node {
                grads.register::<Flex>(node.id, grad);
            }
        }
    }
}

/// The operation's tensors, contiguous, with the layers they make.
#[derive(Debug)]
struct Inputs {
    params: Vec<FlexTensor>,
    head_1d: FlexTensor,
    head_2d: FlexTensor,
    dropout: Option<Dropout>,
    layers: [Layer; LAYERS],
    windows: usize,
    shape: NetworkShape,
}

impl Inputs {
    fn new(
        params: Vec<FlexTensor>,
        head_1d: FlexTensor,
        head_2d: FlexTensor,
        dropout: Option<Dropout>,
        shape: NetworkShape,
    ) -> Self {
        assert_eq!(params.len(), PARAMETERS, "dcnet: parameter count");
        let contiguous = |t: FlexTensor| {
            assert_eq!(t.dtype(), DType::F32, "dcnet: f32 only");
            t.to_contiguous()
        };
        let params: Vec<FlexTensor> = params.into_iter().map(contiguous).collect();
        let (head_1d, head_2d) = (contiguous(head_1d), contiguous(head_2d));
        let layers = layers(&shape, &std::array::from_fn(|i| values(&params[i])));
        let windows = head_1d.shape()[0] / layers[0].positions;
        assert_eq!(
            head_2d.shape()[0],
            windows * layers[2].positions,
            "dcnet: the heads' windows"
        );
        Self {
            params,
            head_1d,
            head_2d,
            dropout,
            layers,
            windows,
            shape,
        }
    }

    fn param(&self, i: usize) -> &[f32] {
        values(&self.params[i])
    }

    /// The windows of slice `s`.
    fn slice_windows(&self, s: usize) -> std::ops::Range<usize> {
        slice_windows(self.windows, s)
    }

    /// The terms `[windows, outputs]`, each slice's activations left in `workspace`.
    fn forward(&self, workspace: &mut Workspace) -> FlexTensor {
        workspace
            .slices
            .par_iter_mut()
            .enumerate()
            .for_each(|(s, buffers)| {
                if !self.slice_windows(s).is_empty() {
                    self.slice_forward(s, buffers);
                }
            });
        // An empty slice (a batch of fewer windows than slices) keeps an older step's
        // buffers, so each slice gives its own windows' rows only.
        let outputs = self.layers[LAYERS - 1].outputs;
        let mut terms = Vec::with_capacity(self.windows * outputs);
        for (s, buffers) in workspace.slices.iter().enumerate() {
            let rows = self.slice_windows(s).len() * outputs;
            terms.extend_from_slice(&buffers.activated[LAYERS - 1][..rows]);
        }
        assert_eq!(
            terms.len(),
            self.windows * outputs,
            "dcnet: one row of terms a window"
        );
        f32_tensor(terms, Shape::new([self.windows, outputs]))
    }

    /// Slice `slice`'s windows, and the rows of the two heads' inputs that they read.
    fn slice_inputs(&self, slice: usize) -> (std::ops::Range<usize>, &[f32], &[f32]) {
        let windows = slice_windows(self.windows, slice);
        let rows = |input, layer: usize| {
            let per_window = self.layers[layer].positions * self.layers[layer].inputs;
            &values(input)[windows.start * per_window..windows.end * per_window]
        };
        let head_1d = rows(&self.head_1d, 0);
        let head_2d = rows(&self.head_2d, 2);
        (windows, head_1d, head_2d)
    }

    fn slice_forward(&self, slice: usize, buffers: &mut SliceBuffers) {
        let (windows, head_1d, head_2d) = self.slice_inputs(slice);
        let count = windows.len();
        let rows = |layer: usize| self.layers[layer].positions;
        let SliceBuffers {
            activated,
            masks,
            masked,
            unfolded,
            features,
            ..
        } = buffers;
        let (time, kernel) = (self.shape.time, self.shape.kernel);
        if let Some(dropout) = &self.dropout {
            for (i, mask) in masks.iter_mut().enumerate() {
                dropout.slice_mask(i, slice, count, self.layers[5 + i].outputs, mask);
            }
        }
        let mask = |i: usize| self.dropout.is_some().then(|| &masks[i][..]);

        // 1D head.
        self.layer_forward(0, head_1d, count, &mut activated[0], None, None);
        unfold_time(&activated[0], count, rows(0), kernel, &mut unfolded[0]);
        self.layer_forward(1, &unfolded[0], count, &mut activated[1], None, None);
        // 2D head.
        self.layer_forward(2, head_2d, count, &mut activated[2], None, None);
        unfold_grid(&activated[2], count, time - 1, 3, &mut unfolded[1]);
        self.layer_forward(3, &unfolded[1], count, &mut activated[3], None, None);
        unfold_grid(&activated[3], count, time - 2, 2, &mut unfolded[2]);
        self.layer_forward(4, &unfolded[2], count, &mut activated[4], None, None);
        // The heads side by side, each window's rows time-major.
        let (flat_1d, flat_2d) = (activated[1].len() / count, activated[4].len() / count);
        features.clear();
        for w in 0..count {
            features.extend_from_slice(&activated[1][w * flat_1d..][..flat_1d]);
            features.extend_from_slice(&activated[4][w * flat_2d..][..flat_2d]);
        }
        // The Linear layers: each reads the previous one's masked output.
        let [_, _, _, _, _, a5, a6, a7, a8] = activated;
        let [m5, m6, m7] = masked;
        let dropped = self.dropout.is_some();
        self.layer_forward(5, features, count, a5, mask(0), Some(m5));
        let x6 = if dropped { &*m5 } else { &*a5 };
        self.layer_forward(6, x6, count, a6, mask(1), Some(m6));
        let x7 = if dropped { &*m6 } else { &*a6 };
        self.layer_forward(7, x7, count, a7, mask(2), Some(m7));
        let x8 = if dropped { &*m7 } else { &*a7 };
        self.layer_forward(8, x8, count, a8, None, None);
    }

    /// Layer `i` on `x` (`count` windows): `activated ← act(x·W + b)`, and with a mask
    /// `masked ← activated ⊙ mask`.
    fn layer_forward(
        &self,
        i: usize,
        x: &[f32],
        count: usize,
        activated: &mut Vec<f32>,
        mask: Option<&[f32]>,
        masked: Option<&mut Vec<f32>>,
    ) {
        let layer = self.layers[i];
        let rows = count * layer.positions;
        resize(activated, rows * layer.outputs);
        product(
            activated,
            [rows, layer.outputs, layer.inputs],
            Operand::plain(x, layer.inputs),
            Operand::plain(self.param(2 * i), layer.outputs),
        );
        layer.activation.forward(activated, self.param(2 * i + 1));
        if let (Some(mask), Some(masked)) = (mask, masked) {
            resize(masked, activated.len());
            for ((out, &a), &m) in masked.iter_mut().zip(activated.iter()).zip(mask) {
                *out = a * m;
            }
        }
    }

    /// The number of values of parameter `p`.
    fn param_size(&self, p: usize) -> usize {
        let layer = self.layers[p / 2];
        if p.is_multiple_of(2) {
            layer.inputs * layer.outputs
        } else {
            layer.outputs
        }
    }

    /// `grads`, one slice's parameter gradients, cut into each layer's weight and bias.
    fn layer_parts<'a>(&self, grads: &'a mut [f32]) -> [(&'a mut [f32], &'a mut [f32]); LAYERS] {
        let mut parts: [(&mut [f32], &mut [f32]); LAYERS] = Default::default();
        let mut rest = grads;
        for (i, (weight, bias)) in parts.iter_mut().enumerate() {
            let (w, tail) = std::mem::take(&mut rest).split_at_mut(self.param_size(2 * i));
            let (b, tail) = tail.split_at_mut(self.param_size(2 * i + 1));
            (*weight, *bias, rest) = (w, b, tail);
        }
        parts
    }

    /// The parameters' gradients in parameter order, from the terms' `grad` `[windows,
    /// outputs]`: each slice's, summed in slice order, on the workspace's buffers.
    fn backward(&self, grad: &[f32], workspace: &mut Workspace) -> Vec<FlexTensor> {
        let total: usize = (0..PARAMETERS).map(|p| self.param_size(p)).sum();
        let outputs = self.layers[LAYERS - 1].outputs;
        workspace
            .slices
            .par_iter_mut()
            .enumerate()
            .for_each(|(s, buffers)| {
                let windows = self.slice_windows(s);
                resize(&mut buffers.param_grads, total);
                if windows.is_empty() {
                    buffers.param_grads.fill(0.0);
                } else {
                    let grad = &grad[windows.start * outputs..][..windows.len() * outputs];
                    self.slice_backward(s, grad, buffers);
                }
            });
        // Each value's sum over the slices, in slice order, into its parameter's own
        // buffer; chunks of values in parallel.
        let Workspace { slices, grads } = workspace;
        let mut sums: Vec<&mut [f32]> = grads
            .iter_mut()
            .zip(&self.params)
            .map(|(grad, param)| grad.values_mut(param.shape()))
            .collect();
        let starts = (0..PARAMETERS).scan(0, |start, p| {
            let this = *start;
            *start += self.param_size(p);
            Some(this)
        });
        let starts: Vec<usize> = starts.collect();
        sums.par_iter_mut()
            .zip(starts)
            .flat_map(|(grad, start)| {
                let chunks = grad.par_chunks_mut(SUM_CHUNK).enumerate();
                chunks.map(move |(c, chunk)| (start + c * SUM_CHUNK, chunk))
            })
            .for_each(|(start, chunk)| {
                let range = start..start + chunk.len();
                chunk.copy_from_slice(&slices[0].param_grads[range.clone()]);
                for buffers in &slices[1..] {
                    combine(chunk, &buffers.param_grads[range.clone()], |a, b| a + b);
                }
            });
        grads.iter().map(Reused::tensor).collect()
    }

    /// Slice `slice`'s backward from the gradient of its terms `grad`: each layer's
    /// pre-activation gradient in `buffers.grads`, the parameters' gradients in
    /// `buffers.param_grads`. Past the small Linear layers, each layer's products run beside
    /// the rest of the backward, and the two heads beside each other, so that the pool's
    /// other threads can take over part of a slice when they have none left to start.
    fn slice_backward(&self, slice: usize, grad: &[f32], buffers: &mut SliceBuffers) {
        let (windows, head_1d, head_2d) = self.slice_inputs(slice);
        let count = windows.len();
        let SliceBuffers {
            activated,
            masks,
            masked,
            unfolded,
            features,
            grads,
            features_grad,
            folded: [folded_1d, folded_2d],
            param_grads,
        } = buffers;
        let (activated, unfolded, features) = (&*activated, &*unfolded, &*features);
        let mut parts = self.layer_parts(param_grads);
        // `grad ← act′ · grad ⊙ mask`: the gradient of layer `i`'s (masked) output made
        // its pre-activation gradient.
        let pre_activation = |i: usize, grad: &mut [f32]| {
            let mask = (5..8).contains(&i) && self.dropout.is_some();
            let mask = mask.then(|| &masks[i - 5][..]);
            self.layers[i]
                .activation
                .backward(grad, &activated[i], mask);
        };
        // Linear 4, 3 and 2, whose products are small, one after the other.
        resize(&mut grads[LAYERS - 1], grad.len());
        grads[LAYERS - 1].copy_from_slice(grad);
        for i in (6..LAYERS).rev() {
            let (below, from_i) = grads.split_at_mut(i);
            pre_activation(i, &mut from_i[0]);
            let input = if self.dropout.is_some() {
                &masked[i - 6]
            } else {
                &activated[i - 1]
            };
            self.param_grads(i, input, count, &from_i[0], std::mem::take(&mut parts[i]));
            self.input_grad(i, &from_i[0], count, &mut below[i - 1]);
        }
        let [g0, g1, g2, g3, g4, g5, ..] = grads;
        let [p0, p1, p2, p3, p4, p5, ..] = parts;
        let (time, kernel) = (self.shape.time, self.shape.kernel);
        pre_activation(5, g5);
        self.products_beside(5, features, count, g5, p5, |g5| {
            // The features' gradient split back into the two heads' outputs'.
            self.input_grad(5, g5, count, features_grad);
            let (flat_1d, flat_2d) = (activated[1].len() / count, activated[4].len() / count);
            resize(g1, activated[1].len());
            resize(g4, activated[4].len());
            for w in 0..count {
                let row = &features_grad[w * (flat_1d + flat_2d)..][..flat_1d + flat_2d];
                g1[w * flat_1d..][..flat_1d].copy_from_slice(&row[..flat_1d]);
                g4[w * flat_2d..][..flat_2d].copy_from_slice(&row[flat_1d..]);
            }
            // 2D head: layers 4, 3 and 2, each input's gradient folded back into the
            // output's of the layer before.
            let head_2d_backward = || {
                pre_activation(4, g4);
                self.products_beside(4, &unfolded[2], count, g4, p4, |g4| {
                    self.input_grad(4, g4, count, folded_2d);
                    fold_grid(folded_2d, count, time - 2, 2, g3);
                    pre_activation(3, g3);
                    self.products_beside(3, &unfolded[1], count, g3, p3, |g3| {
                        self.input_grad(3, g3, count, folded_2d);
                        fold_grid(folded_2d, count, time - 1, 3, g2);
                        pre_activation(2, g2);
                        self.param_grads(2, head_2d, count, g2, p2);
                    })
                })
            };
            // 1D head: layers 1 and 0, folded back the same way.
            let head_1d_backward = || {
                pre_activation(1, g1);
                self.products_beside(1, &unfolded[0], count, g1, p1, |g1| {
                    self.input_grad(1, g1, count, folded_1d);
                    fold_time(folded_1d, count, self.layers[0].positions, kernel, g0);
                    pre_activation(0, g0);
                    self.param_grads(0, head_1d, count, g0, p0);
                })
            };
            rayon::join(head_2d_backward, head_1d_backward);
        });
    }

    /// Layer `i`'s parameters' gradients from its input `x` and its pre-activation
    /// gradient `grad`, beside `rest`, the backward further down, which reads `grad` too.
    /// This thread computes the products; `rest` is offered to the pool's other threads
    /// (and run here after the products if none takes it).
    #[allow(clippy::too_many_arguments)]
    fn products_beside<R: Send>(
        &self,
        i: usize,
        x: &[f32],
        count: usize,
        grad: &[f32],
        param: (&mut [f32], &mut [f32]),
        rest: impl FnOnce(&[f32]) -> R + Send,
    ) -> R {
        rayon::join(|| self.param_grads(i, x, count, grad, param), || rest(grad)).1
    }

    /// Layer `i`'s weight gradient `xᵀ·g` and bias gradient (column sums of `g`), from its
    /// input `x` (`count` windows) and its pre-activation gradient `grad`.
    fn param_grads(
        &self,
        i: usize,
        x: &[f32],
        count: usize,
        grad: &[f32],
        (weight_grad, bias_grad): (&mut [f32], &mut [f32]),
    ) {
        let layer = self.layers[i];
        product(
            weight_grad,
            [layer.inputs, layer.outputs, count * layer.positions],
            Operand::transposed(x, layer.inputs),
            Operand::plain(grad, layer.outputs),
        );
        bias_grad.fill(0.0);
        for row in grad.chunks_exact(layer.outputs) {
            for (b, &g) in bias_grad.iter_mut().zip(row) {
                *b += g;
            }
        }
    }

    /// Layer `i`'s input gradient `g·Wᵀ` into `grad_input`, from its pre-activation
    /// gradient `grad` (`count` windows).
    fn input_grad(&self, i: usize, grad: &[f32], count: usize, grad_input: &mut Vec<f32>) {
        let layer = self.layers[i];
        let rows = count * layer.positions;
        resize(grad_input, rows * layer.inputs);
        product(
            grad_input,
            [rows, layer.inputs, layer.outputs],
            Operand::plain(grad, layer.outputs),
            Operand::transposed(self.param(2 * i), layer.outputs),
        );
    }
}

/// A step's buffers: one set per slice.
#[derive(Debug)]
struct Workspace {
    slices: Vec<SliceBuffers>,
    /// Each parameter's gradient, the slices' summed.
    grads: [Reused; PARAMETERS],
}

/// Values of a parameter summed over the slices per task of the pool.
const SUM_CHUNK: usize = 4096;

/// One slice's activations and gradients, grown to the largest slice seen and reused.
#[derive(Debug, Default)]
struct SliceBuffers {
    /// Each layer's output after its activation, before its mask.
    activated: [Vec<f32>; LAYERS],
    /// The dropout masks of the first three Linear layers.
    masks: [Vec<f32>; 3],
    /// The first three Linear layers' outputs times their masks.
    masked: [Vec<f32>; 3],
    /// The inputs of Conv1d 2 and Conv2d 2 and 3: their input's taps side by side.
    unfolded: [Vec<f32>; 3],
    /// The two heads side by side, the first Linear layer's input.
    features: Vec<f32>,
    /// Each layer's pre-activation gradient.
    grads: [Vec<f32>; LAYERS],
    /// The gradient of the features.
    features_grad: Vec<f32>,
    /// The gradient of the 1D and the 2D head's unfolded inputs, before folding.
    folded: [Vec<f32>; 2],
    /// Every parameter's gradient from this slice, in parameter order.
    param_grads: Vec<f32>,
}

thread_local! {
    /// The workspace this thread's last step gave back.
    static SPARE: RefCell<Option<Box<Workspace>>> = const { RefCell::new(None) };
}

impl Workspace {
    /// This thread's workspace, or a new one.
    fn take() -> Box<Workspace> {
        SPARE
            .with(|spare| spare.borrow_mut().take())
            .unwrap_or_else(|| {
                Box::new(Workspace {
                    slices: (0..SLICES).map(|_| SliceBuffers::default()).collect(),
                    grads: Default::default(),
                })
            })
    }

    /// Keeps `workspace` for this thread's next step.
    fn give_back(workspace: Box<Workspace>) {
        SPARE.with(|spare| *spare.borrow_mut() = Some(workspace));
    }
}

/// `buffer`'s length set to `len` (reallocating only to grow past its capacity); its
/// values are overwritten by the caller.
fn resize(buffer: &mut Vec<f32>, len: usize) {
    buffer.resize(len, 0.0);
}

/// A matrix operand of [`product`]: its values and its row and column strides.
struct Operand<'a> {
    values: &'a [f32],
    row_stride: isize,
    column_stride: isize,
}

impl<'a> Operand<'a> {
    /// `values` as a row-major matrix of `columns` columns.
    fn plain(values: &'a [f32], columns: usize) -> Self {
        Self {
            values,
            row_stride: columns as isize,
            column_stride: 1,
        }
    }

    /// The transpose of `values` read as a row-major matrix of `columns` columns.
    fn transposed(values: &'a [f32], columns: usize) -> Self {
        Self {
            values,
            row_stride: 1,
            column_stride: columns as isize,
        }
    }
}

/// `output ← lhs·rhs` for `[m, k]·[k, n]` given as `[m, n, k]`, on this thread.
fn product(output: &mut [f32], [m, n, k]: [usize; 3], lhs: Operand, rhs: Operand) {
    assert!(output.len() == m * n, "dcnet: product output size");
    assert!(
        lhs.values.len() >= m * k && rhs.values.len() >= k * n,
        "dcnet: product operands"
    );
    if m == 0 || n == 0 {
        return;
    }
    // SAFETY: the operands hold [m, k] and [k, n] at their strides (checked above for the
    // row-major and transposed layouts, the only ones built), and `output` holds [m, n]
    // row-major; gemm neither reads `output` (read_dst false) nor keeps any pointer.
    unsafe {
        gemm::gemm(
            m,
            n,
            k,
            output.as_mut_ptr(),
            1,
            n as isize,
            false,
            lhs.values.as_ptr(),
            lhs.column_stride,
            lhs.row_stride,
            rhs.values.as_ptr(),
            rhs.column_stride,
            rhs.row_stride,
            0.0,
            1.0,
            false,
            false,
            false,
            gemm::Parallelism::None,
        );
    }
}

/// Rows (window, time) of `x` → `[windows × (steps − kernel + 1), kernel × channels]`:
/// output (w, t) holds input rows (w, t), …, (w, t + kernel − 1).
fn unfold_time(x: &[f32], windows: usize, steps: usize, kernel: usize, out: &mut Vec<f32>) {
    let channels = x.len() / (windows * steps);
    let (outputs, width) = (steps + 1 - kernel, kernel * channels);
    out.clear();
    for w in 0..windows {
        for t in 0..outputs {
            out.extend_from_slice(&x[(w * steps + t) * channels..][..width]);
        }
    }
}

/// The gradient of [`unfold_time`]: input row (w, s) sums the blocks that read it, in
/// increasing output order.
fn fold_time(grad: &[f32], windows: usize, steps: usize, kernel: usize, out: &mut Vec<f32>) {
    let outputs = steps + 1 - kernel;
    let channels = grad.len() / (windows * outputs * kernel);
    let width = kernel * channels;
    resize(out, windows * steps * channels);
    out.fill(0.0);
    for w in 0..windows {
        for s in 0..steps {
            let row = &mut out[(w * steps + s) * channels..][..channels];
            for t in s.saturating_sub(kernel - 1)..=s.min(outputs - 1) {
                add(
                    row,
                    &grad[(w * outputs + t) * width + (s - t) * channels..][..channels],
                );
            }
        }
    }
}

/// Rows (window, time, row) of `x` → one row per 2×2 neighbourhood, in [`GRID_TAPS`] order.
fn unfold_grid(x: &[f32], windows: usize, steps: usize, rows: usize, out: &mut Vec<f32>) {
    let channels = x.len() / (windows * steps * rows);
    out.clear();
    for w in 0..windows {
        for t in 0..steps - 1 {
            for r in 0..rows - 1 {
                for (row_tap, time_tap) in GRID_TAPS {
                    let start = ((w * steps + t + time_tap) * rows + r + row_tap) * channels;
                    out.extend_from_slice(&x[start..start + channels]);
                }
            }
        }
    }
}

/// The gradient of [`unfold_grid`]: input row (w, s, q) sums the blocks that read it, in
/// increasing (t, r) order.
fn fold_grid(grad: &[f32], windows: usize, steps: usize, rows: usize, out: &mut Vec<f32>) {
    let width = grad.len() / (windows * (steps - 1) * (rows - 1));
    let channels = width / GRID_TAPS.len();
    resize(out, windows * steps * rows * channels);
    out.fill(0.0);
    for w in 0..windows {
        for s in 0..steps {
            for q in 0..rows {
                let row = &mut out[((w * steps + s) * rows + q) * channels..][..channels];
                for t in s.saturating_sub(1)..=s.min(steps - 2) {
                    for r in q.saturating_sub(1)..=q.min(rows - 2) {
                        let tap = GRID_TAPS
                            .iter()
                            .position(|&offsets| offsets == (q - r, s - t))
                            .expect("every offset of a 2×2 neighbourhood is a tap");
                        let output = (w * (steps - 1) + t) * (rows - 1) + r;
                        add(row, &grad[output * width + tap * channels..][..channels]);
                    }
                }
            }
        }
    }
}

/// `row += block`, element by element.
fn add(row: &mut [f32], block: &[f32]) {
    for (sum, value) in row.iter_mut().zip(block) {
        *sum += value;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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

    /// The slices cover the batch in order, as even as the count allows, and the batch's
    /// mask is its slices' masks one after the other.
    #[test]
    fn slices_cover_the_batch_and_the_mask_follows_them() {
        for windows in [0, 1, 7, 8, 9, 203] {
            let ranges: Vec<_> = (0..SLICES).map(|s| slice_windows(windows, s)).collect();
            assert_eq!(ranges[0].start, 0);
            assert_eq!(ranges[SLICES - 1].end, windows);
            for pair in ranges.windows(2) {
                assert_eq!(pair[0].end, pair[1].start);
                assert!(pair[0].len() >= pair[1].len() && pair[0].len() <= pair[1].len() + 1);
            }
        }
        let dropout = Dropout { p: 0.3, seed: 9 };
        let mask = dropout.mask(1, 203, 5);
        let mut part = Vec::new();
        dropout.slice_mask(1, 3, slice_windows(203, 3).len(), 5, &mut part);
        assert_eq!(
            mask[slice_windows(203, 3).start * 5..][..part.len()],
            part[..]
        );
        let dropped = mask.iter().filter(|&&m| m == 0.0).count() as f64 / mask.len() as f64;
        assert!((dropped - 0.3).abs() < 0.05, "{dropped} dropped");
        assert!(mask.iter().all(|&m| m == 0.0 || m == (1.0f64 / 0.7) as f32));
    }
}
