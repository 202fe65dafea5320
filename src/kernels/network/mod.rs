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

mod buffers;
mod inputs;
mod layers;

use buffers::{Workspace, resize};
use burn::backend::autodiff::checkpoint::base::Checkpointer;
use burn::backend::autodiff::checkpoint::strategy::NoCheckpointing;
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind};
use burn::backend::flex::FlexTensor;
use burn::backend::tensor::FloatTensor;
use burn::backend::{Autodiff, Flex};
use burn::tensor::{DType, Device, Tensor};
use inputs::Inputs;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
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

#[cfg(test)]
mod tests {
    use super::*;

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
