//! The operation's forward and backward over the slices of a batch: each slice's
//! layers in order into its own buffers, then the slices' parameter gradients summed in
//! slice order, so a model's bytes do not depend on the thread count.
//! In: the parameters, the heads' inputs and the dropout. Out: the terms, and every
//! parameter's gradient.

use super::buffers::{
    Operand, SUM_CHUNK, SliceBuffers, Workspace, fold_grid, fold_time, product, resize,
    unfold_grid, unfold_time,
};
use super::layers::{Layer, combine, layers};
use super::{Dropout, LAYERS, NetworkShape, PARAMETERS, slice_windows};
use crate::kernels::{Reused, f32_tensor, values};
use burn::backend::TensorMetadata;
use burn::backend::flex::FlexTensor;
use burn::tensor::DType;
use burn::tensor::Shape;
use rayon::prelude::*;

/// The operation's tensors, contiguous, with the layers they make.
#[derive(Debug)]
pub(super) struct Inputs {
    pub(super) params: Vec<FlexTensor>,
    pub(super) head_1d: FlexTensor,
    pub(super) head_2d: FlexTensor,
    pub(super) dropout: Option<Dropout>,
    pub(super) layers: [Layer; LAYERS],
    pub(super) windows: usize,
    pub(super) shape: NetworkShape,
}

impl Inputs {
    pub(super) fn new(
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

    pub(super) fn param(&self, i: usize) -> &[f32] {
        values(&self.params[i])
    }

    /// The windows of slice `s`.
    pub(super) fn slice_windows(&self, s: usize) -> std::ops::Range<usize> {
        slice_windows(self.windows, s)
    }

    /// The terms `[windows, outputs]`, each slice's activations left in `workspace`.
    pub(super) fn forward(&self, workspace: &mut Workspace) -> FlexTensor {
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
    pub(super) fn slice_inputs(&self, slice: usize) -> (std::ops::Range<usize>, &[f32], &[f32]) {
        let windows = slice_windows(self.windows, slice);
        let rows = |input, layer: usize| {
            let per_window = self.layers[layer].positions * self.layers[layer].inputs;
            &values(input)[windows.start * per_window..windows.end * per_window]
        };
        let head_1d = rows(&self.head_1d, 0);
        let head_2d = rows(&self.head_2d, 2);
        (windows, head_1d, head_2d)
    }

    pub(super) fn slice_forward(&self, slice: usize, buffers: &mut SliceBuffers) {
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
    pub(super) fn layer_forward(
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
    pub(super) fn param_size(&self, p: usize) -> usize {
        let layer = self.layers[p / 2];
        if p.is_multiple_of(2) {
            layer.inputs * layer.outputs
        } else {
            layer.outputs
        }
    }

    /// `grads`, one slice's parameter gradients, cut into each layer's weight and bias.
    pub(super) fn layer_parts<'a>(
        &self,
        grads: &'a mut [f32],
    ) -> [(&'a mut [f32], &'a mut [f32]); LAYERS] {
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
    pub(super) fn backward(&self, grad: &[f32], workspace: &mut Workspace) -> Vec<FlexTensor> {
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
    pub(super) fn slice_backward(&self, slice: usize, grad: &[f32], buffers: &mut SliceBuffers) {
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
            self.input_grad(5, g5, count, features_grad);
            split_features_grad(features_grad, count, [&activated[1], &activated[4]], g1, g4);
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
    pub(super) fn products_beside<R: Send>(
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
    pub(super) fn param_grads(
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
    pub(super) fn input_grad(
        &self,
        i: usize,
        grad: &[f32],
        count: usize,
        grad_input: &mut Vec<f32>,
    ) {
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

/// The features' gradient split back into the two heads' outputs' (`g1`, `g4`), each
/// window's row the 1D head's values then the 2D head's, as long as the heads'
/// activations `heads`.
fn split_features_grad(
    features_grad: &[f32],
    count: usize,
    heads: [&[f32]; 2],
    g1: &mut Vec<f32>,
    g4: &mut Vec<f32>,
) {
    let (flat_1d, flat_2d) = (heads[0].len() / count, heads[1].len() / count);
    resize(g1, heads[0].len());
    resize(g4, heads[1].len());
    for w in 0..count {
        let row = &features_grad[w * (flat_1d + flat_2d)..][..flat_1d + flat_2d];
        g1[w * flat_1d..][..flat_1d].copy_from_slice(&row[..flat_1d]);
        g4[w * flat_2d..][..flat_2d].copy_from_slice(&row[flat_1d..]);
    }
}
