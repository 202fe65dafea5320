//! The taps of DCNet's convolutions laid side by side, as one backend operation each way.
//! In: activations `[positions, channels]`, one row per (window, time) for the 1D head or
//! per (window, time, row) for the 2D head. Out: one row per output position holding the
//! channel blocks of the input rows it reads, ready for one matrix product; backward, the
//! gradient of each input row, the sum of the gradient blocks that read it.
//!
//! On Flex both directions are plain loops over the pattern: the forward copies contiguous
//! channel blocks, the backward sums for each input row the blocks that read it, with no
//! index tensor and no scatter. They add in the order of burn's `select` backward (a
//! scatter-add over the index list), so the gradients are the same bytes. Autodiff
//! registers the backward by hand; any other backend (NdArray) runs `select` on an index
//! list, as the network did before these kernels.

// burn-ndarray is deprecated in burn 0.22; it stays selectable for comparison
// (`training.backend = "ndarray"`), so its extension routing and fallback stay here.
#![allow(deprecated)]

use burn::backend::autodiff::checkpoint::{base::Checkpointer, strategy::CheckpointStrategy};
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind, unary};
use burn::backend::flex::{FlexTensor, Layout};
use burn::backend::tensor::{FloatTensor, IntTensor};
use burn::backend::{
    Autodiff, Backend, Dispatch, Flex, NdArray, TensorMetadata, backend_extension,
};
use burn::tensor::{Bytes, DType, IndexingUpdateOp, Shape, Tensor, TensorData};

/// The 2×2 neighbourhood of a grid output at (time t, row r): the input rows at
/// (t + time offset, r + row offset), as (row offset, time offset), in the order their
/// channel blocks sit in the output row.
pub const GRID_TAPS: [(usize, usize); 4] = [(0, 0), (0, 1), (1, 0), (1, 1)];

/// Rows (window, time) of `x` `[windows × steps, channels]` → `[windows × (steps − kernel
/// + 1), kernel × channels]`: output (w, t) holds input rows (w, t), …, (w, t + kernel − 1).
pub fn unfold_time(x: Tensor<2>, windows: usize, kernel: usize) -> Tensor<2> {
    Tensor::from_dispatch(<Dispatch as UnfoldBackend>::unfold_time(
        x.into_dispatch(),
        windows,
        kernel,
    ))
}

/// Rows (window, time, row) of `x` `[windows × steps × rows, channels]` → `[windows ×
/// (steps − 1) × (rows − 1), 4 × channels]`: output (w, t, r) holds the rows of its 2×2
/// neighbourhood in [`GRID_TAPS`] order.
pub fn unfold_grid(x: Tensor<2>, windows: usize, steps: usize, rows: usize) -> Tensor<2> {
    Tensor::from_dispatch(<Dispatch as UnfoldBackend>::unfold_grid(
        x.into_dispatch(),
        windows,
        steps,
        rows,
    ))
}

/// The two unfolds and their gradients. The default bodies gather with `select` on an
/// index list and scatter-add back, as burn's own `select` and its backward do.
#[backend_extension(Autodiff, Flex, NdArray)]
pub trait UnfoldBackend: Backend {
    /// See [`unfold_time`].
    fn unfold_time(x: FloatTensor<Self>, windows: usize, kernel: usize) -> FloatTensor<Self> {
        select_time::<Self>(x, windows, kernel)
    }

    /// The gradient of [`unfold_time`] with respect to its input `[windows × steps,
    /// channels]`, from the gradient of its output.
    fn unfold_time_backward(
        grad: FloatTensor<Self>,
        windows: usize,
        steps: usize,
        kernel: usize,
    ) -> FloatTensor<Self> {
        select_time_backward::<Self>(grad, windows, steps, kernel)
    }

    /// See [`unfold_grid`].
    fn unfold_grid(
        x: FloatTensor<Self>,
        windows: usize,
        steps: usize,
        rows: usize,
    ) -> FloatTensor<Self> {
        select_grid::<Self>(x, windows, steps, rows)
    }

    /// The gradient of [`unfold_grid`] with respect to its input `[windows × steps × rows,
    /// channels]`, from the gradient of its output.
    fn unfold_grid_backward(
        grad: FloatTensor<Self>,
        windows: usize,
        steps: usize,
        rows: usize,
    ) -> FloatTensor<Self> {
        select_grid_backward::<Self>(grad, windows, steps, rows)
    }
}

impl UnfoldBackend for NdArray {}

impl UnfoldBackend for Flex {
    fn unfold_time(x: FlexTensor, windows: usize, kernel: usize) -> FlexTensor {
        let [positions, channels] = dims(&x);
        let steps = positions / windows;
        let x = x.to_contiguous();
        let Some(rows) = x.as_slice::<f32>() else {
            return select_time::<Flex>(x, windows, kernel);
        };
        let values = time_forward(rows, channels, windows, steps, kernel);
        let outputs = windows * (steps + 1 - kernel);
        f32_tensor(values, [outputs, kernel * channels])
    }

    fn unfold_time_backward(
        grad: FlexTensor,
        windows: usize,
        steps: usize,
        kernel: usize,
    ) -> FlexTensor {
        let channels = dims(&grad)[1] / kernel;
        let grad = grad.to_contiguous();
        let Some(blocks) = grad.as_slice::<f32>() else {
            return select_time_backward::<Flex>(grad, windows, steps, kernel);
        };
        let values = time_backward(blocks, channels, windows, steps, kernel);
        f32_tensor(values, [windows * steps, channels])
    }

    fn unfold_grid(x: FlexTensor, windows: usize, steps: usize, rows: usize) -> FlexTensor {
        let channels = dims(&x)[1];
        let x = x.to_contiguous();
        let Some(input) = x.as_slice::<f32>() else {
            return select_grid::<Flex>(x, windows, steps, rows);
        };
        let values = grid_forward(input, channels, windows, steps, rows);
        let outputs = windows * (steps - 1) * (rows - 1);
        f32_tensor(values, [outputs, GRID_TAPS.len() * channels])
    }

    fn unfold_grid_backward(
        grad: FlexTensor,
        windows: usize,
        steps: usize,
        rows: usize,
    ) -> FlexTensor {
        let channels = dims(&grad)[1] / GRID_TAPS.len();
        let grad = grad.to_contiguous();
        let Some(blocks) = grad.as_slice::<f32>() else {
            return select_grid_backward::<Flex>(grad, windows, steps, rows);
        };
        let values = grid_backward(blocks, channels, windows, steps, rows);
        f32_tensor(values, [windows * steps * rows, channels])
    }
}

impl<B: UnfoldBackend, C: CheckpointStrategy> UnfoldBackend for Autodiff<B, C> {
    fn unfold_time(x: FloatTensor<Self>, windows: usize, kernel: usize) -> FloatTensor<Self> {
        #[derive(Debug)]
        struct UnfoldTime;

        impl<B: UnfoldBackend> Backward<B, 1> for UnfoldTime {
            /// (windows, steps, kernel)
            type State = (usize, usize, usize);

            fn backward(
                self,
                ops: Ops<Self::State, 1>,
                grads: &mut Gradients,
                _checkpointer: &mut Checkpointer,
            ) {
                let (windows, steps, kernel) = ops.state;
                unary::<B, _>(ops.parents, ops.node, grads, |grad| {
                    B::unfold_time_backward(grad, windows, steps, kernel)
                });
            }
        }

        let (x, node) = x.into_parts();
        let steps = dims(&x)[0] / windows;
        match UnfoldTime.prepare::<C>([node]).compute_bound().stateful() {
            OpsKind::Tracked(prep) => {
                prep.finish((windows, steps, kernel), B::unfold_time(x, windows, kernel))
            }
            OpsKind::UnTracked(prep) => prep.finish(B::unfold_time(x, windows, kernel)),
        }
    }

    fn unfold_grid(
        x: FloatTensor<Self>,
        windows: usize,
        steps: usize,
        rows: usize,
    ) -> FloatTensor<Self> {
        #[derive(Debug)]
        struct UnfoldGrid;

        impl<B: UnfoldBackend> Backward<B, 1> for UnfoldGrid {
            /// (windows, steps, rows)
            type State = (usize, usize, usize);

            fn backward(
                self,
                ops: Ops<Self::State, 1>,
                grads: &mut Gradients,
                _checkpointer: &mut Checkpointer,
            ) {
                let (windows, steps, rows) = ops.state;
                unary::<B, _>(ops.parents, ops.node, grads, |grad| {
                    B::unfold_grid_backward(grad, windows, steps, rows)
                });
            }
        }

        let (x, node) = x.into_parts();
        match UnfoldGrid.prepare::<C>([node]).compute_bound().stateful() {
            OpsKind::Tracked(prep) => prep.finish(
                (windows, steps, rows),
                B::unfold_grid(x, windows, steps, rows),
            ),
            OpsKind::UnTracked(prep) => prep.finish(B::unfold_grid(x, windows, steps, rows)),
        }
    }
}

/// Output (w, t) of [`unfold_time`] from `input` `[windows × steps, channels]`: its
/// `kernel` input rows are consecutive, so each output row is one copy.
fn time_forward(
    input: &[f32],
    channels: usize,
    windows: usize,
    steps: usize,
    kernel: usize,
) -> Vec<f32> {
    assert_eq!(
        input.len(),
        windows * steps * channels,
        "unfold_time: input shape"
    );
    let (outputs, width) = (steps + 1 - kernel, kernel * channels);
    let mut values = Vec::with_capacity(windows * outputs * width);
    for w in 0..windows {
        for t in 0..outputs {
            let start = (w * steps + t) * channels;
            values.extend_from_slice(&input[start..start + width]);
        }
    }
    values
}

/// The gradient of [`time_forward`]: input row (w, s) is read by outputs (w, t) at tap
/// s − t, summed over t in increasing order.
fn time_backward(
    grad: &[f32],
    channels: usize,
    windows: usize,
    steps: usize,
    kernel: usize,
) -> Vec<f32> {
    let (outputs, width) = (steps + 1 - kernel, kernel * channels);
    assert_eq!(
        grad.len(),
        windows * outputs * width,
        "unfold_time: gradient shape"
    );
    let mut values = vec![0.0f32; windows * steps * channels];
    for w in 0..windows {
        for s in 0..steps {
            let row = &mut values[(w * steps + s) * channels..][..channels];
            for t in s.saturating_sub(kernel - 1)..=s.min(outputs - 1) {
                let block = &grad[(w * outputs + t) * width + (s - t) * channels..][..channels];
                add(row, block);
            }
        }
    }
    values
}

/// Output (w, t, r) of [`unfold_grid`] from `input` `[windows × steps × rows, channels]`.
fn grid_forward(
    input: &[f32],
    channels: usize,
    windows: usize,
    steps: usize,
    rows: usize,
) -> Vec<f32> {
    assert_eq!(
        input.len(),
        windows * steps * rows * channels,
        "unfold_grid: input shape"
    );
    let outputs = windows * (steps - 1) * (rows - 1);
    let mut values = Vec::with_capacity(outputs * GRID_TAPS.len() * channels);
    for w in 0..windows {
        for t in 0..steps - 1 {
            for r in 0..rows - 1 {
                for (row_tap, time_tap) in GRID_TAPS {
                    let start = ((w * steps + t + time_tap) * rows + r + row_tap) * channels;
                    values.extend_from_slice(&input[start..start + channels]);
                }
            }
        }
    }
    values
}

/// The gradient of [`grid_forward`]: input row (w, s, q) is read by outputs (w, t, r)
/// with t ∈ {s − 1, s} and r ∈ {q − 1, q}, summed in increasing (t, r) order.
fn grid_backward(
    grad: &[f32],
    channels: usize,
    windows: usize,
    steps: usize,
    rows: usize,
) -> Vec<f32> {
    let width = GRID_TAPS.len() * channels;
    assert_eq!(
        grad.len(),
        windows * (steps - 1) * (rows - 1) * width,
        "unfold_grid: gradient shape"
    );
    let mut values = vec![0.0f32; windows * steps * rows * channels];
    for w in 0..windows {
        for s in 0..steps {
            for q in 0..rows {
                let row = &mut values[((w * steps + s) * rows + q) * channels..][..channels];
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
    values
}

/// `row += block`, element by element.
fn add(row: &mut [f32], block: &[f32]) {
    for (sum, value) in row.iter_mut().zip(block) {
        *sum += value;
    }
}

/// An f32 tensor on Flex that owns `values`, aligned, so Flex does not copy it.
fn f32_tensor<const D: usize>(values: Vec<f32>, shape: [usize; D]) -> FlexTensor {
    FlexTensor::new(
        Bytes::from_elems(values),
        Layout::contiguous(Shape::new(shape)),
        DType::F32,
    )
}

fn dims<T: TensorMetadata>(x: &T) -> [usize; 2] {
    let shape = x.shape();
    assert_eq!(
        shape.num_dims(),
        2,
        "unfold: activations are [positions, channels]"
    );
    [shape[0], shape[1]]
}

/// The input row of each block of [`unfold_time`]'s output, in output order.
fn time_taps(windows: usize, steps: usize, kernel: usize) -> TensorData {
    let outputs = steps + 1 - kernel;
    let mut taps = Vec::with_capacity(windows * outputs * kernel);
    for w in 0..windows {
        for t in 0..outputs {
            taps.extend((0..kernel).map(|k| (w * steps + t + k) as i64));
        }
    }
    let count = taps.len();
    TensorData::new(taps, [count])
}

/// The input row of each block of [`unfold_grid`]'s output, in output order.
fn grid_taps(windows: usize, steps: usize, rows: usize) -> TensorData {
    let mut taps = Vec::with_capacity(windows * (steps - 1) * (rows - 1) * GRID_TAPS.len());
    for w in 0..windows {
        for t in 0..steps - 1 {
            for r in 0..rows - 1 {
                for (row_tap, time_tap) in GRID_TAPS {
                    taps.push(((w * steps + t + time_tap) * rows + r + row_tap) as i64);
                }
            }
        }
    }
    let count = taps.len();
    TensorData::new(taps, [count])
}

/// [`unfold_time`] as `select` over [`time_taps`].
fn select_time<B: Backend>(x: FloatTensor<B>, windows: usize, kernel: usize) -> FloatTensor<B> {
    let [positions, channels] = dims(&x);
    let steps = positions / windows;
    let taps = B::int_from_data(time_taps(windows, steps, kernel), &x.device());
    let outputs = windows * (steps + 1 - kernel);
    B::float_reshape(
        B::float_select(x, 0, taps),
        Shape::new([outputs, kernel * channels]),
    )
}

/// [`unfold_grid`] as `select` over [`grid_taps`].
fn select_grid<B: Backend>(
    x: FloatTensor<B>,
    windows: usize,
    steps: usize,
    rows: usize,
) -> FloatTensor<B> {
    let channels = dims(&x)[1];
    let taps = B::int_from_data(grid_taps(windows, steps, rows), &x.device());
    let outputs = windows * (steps - 1) * (rows - 1);
    B::float_reshape(
        B::float_select(x, 0, taps),
        Shape::new([outputs, GRID_TAPS.len() * channels]),
    )
}

/// [`select_time`]'s backward, as burn's `select` backward computes it.
fn select_time_backward<B: Backend>(
    grad: FloatTensor<B>,
    windows: usize,
    steps: usize,
    kernel: usize,
) -> FloatTensor<B> {
    let channels = dims(&grad)[1] / kernel;
    let taps = B::int_from_data(time_taps(windows, steps, kernel), &grad.device());
    scatter_add::<B>(grad, taps, windows * steps, channels)
}

/// [`select_grid`]'s backward, as burn's `select` backward computes it.
fn select_grid_backward<B: Backend>(
    grad: FloatTensor<B>,
    windows: usize,
    steps: usize,
    rows: usize,
) -> FloatTensor<B> {
    let channels = dims(&grad)[1] / GRID_TAPS.len();
    let taps = B::int_from_data(grid_taps(windows, steps, rows), &grad.device());
    scatter_add::<B>(grad, taps, windows * steps * rows, channels)
}

/// `select`'s backward: the gradient blocks `grad` `[outputs, taps per output × channels]`
/// added into zeros `[rows, channels]` at the rows `taps` lists, in list order.
fn scatter_add<B: Backend>(
    grad: FloatTensor<B>,
    taps: IntTensor<B>,
    rows: usize,
    channels: usize,
) -> FloatTensor<B> {
    let blocks = taps.shape()[0];
    let dtype = grad.dtype().into();
    let device = grad.device();
    let grad = B::float_reshape(grad, Shape::new([blocks, channels]));
    let zeros = B::float_zeros(Shape::new([rows, channels]), &device, dtype);
    B::float_select_assign(zeros, 0, taps, grad, IndexingUpdateOp::Add)
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::tensor::{Device, Int};
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn values(x: Tensor<2>) -> Vec<f32> {
        x.into_data().try_to_vec::<f32>().unwrap()
    }

    fn bits(values: &[f32]) -> Vec<u32> {
        values.iter().map(|v| v.to_bits()).collect()
    }

    fn random(rng: &mut ChaCha8Rng, shape: [usize; 2], device: &Device) -> Tensor<2> {
        let values: Vec<f32> = (0..shape[0] * shape[1])
            .map(|_| rng.random_range(-2.0..2.0))
            .collect();
        Tensor::from_data(TensorData::new(values, shape), device)
    }

    /// The index lists the network gathered with before these kernels, written out
    /// independently of [`time_taps`] and [`GRID_TAPS`]: 1D output (w, t) reads rows
    /// (w, t + k); 2D output (w, t, r) reads (t, r), (t + 1, r), (t, r + 1), (t + 1, r + 1).
    fn reference_taps(windows: usize, steps: usize, pattern: Pattern) -> Vec<i64> {
        let mut taps = Vec::new();
        for w in 0..windows {
            match pattern {
                Pattern::Time { kernel } => {
                    for t in 0..steps + 1 - kernel {
                        taps.extend((0..kernel).map(|k| (w * steps + t + k) as i64));
                    }
                }
                Pattern::Grid { rows } => {
                    let row = |t: usize, r: usize| ((w * steps + t) * rows + r) as i64;
                    for t in 0..steps - 1 {
                        for r in 0..rows - 1 {
                            taps.extend([
                                row(t, r),
                                row(t + 1, r),
                                row(t, r + 1),
                                row(t + 1, r + 1),
                            ]);
                        }
                    }
                }
            }
        }
        taps
    }

    #[derive(Debug, Clone, Copy)]
    enum Pattern {
        Time { kernel: usize },
        Grid { rows: usize },
    }

    /// Ours and burn's `select` on `x` `[positions, channels]`: the outputs, and the
    /// gradients of `sum(output · weights)` with respect to `x`, each as values.
    fn both(
        x: Tensor<2>,
        weights: Tensor<2>,
        windows: usize,
        steps: usize,
        pattern: Pattern,
    ) -> [(Vec<f32>, Option<Vec<f32>>); 2] {
        let device = x.device();
        let taps = reference_taps(windows, steps, pattern);
        let taps =
            Tensor::<1, Int>::from_data(TensorData::new(taps.clone(), [taps.len()]), &device);
        let outputs = weights.dims()[0];
        let run = |y: Tensor<2>, x: &Tensor<2>| {
            let gradient = device.is_autodiff().then(|| {
                let grads = (y.clone() * weights.clone()).sum().backward();
                values(x.grad(&grads).unwrap())
            });
            (values(y), gradient)
        };
        let x = if device.is_autodiff() {
            x.require_grad()
        } else {
            x
        };
        let ours = match pattern {
            Pattern::Time { kernel } => unfold_time(x.clone(), windows, kernel),
            Pattern::Grid { rows } => unfold_grid(x.clone(), windows, steps, rows),
        };
        let ours = run(ours, &x);
        let x = x.detach();
        let x = if device.is_autodiff() {
            x.require_grad()
        } else {
            x
        };
        let theirs = x.clone().select(0, taps).reshape([outputs as i32, -1]);
        [ours, run(theirs, &x)]
    }

    /// Random shapes, kernels 1 to 4, rows 2 to 6: the same bytes as `select` forward,
    /// and backward too (the gradient blocks are added in `select`'s scatter order).
    fn matches_select_on(device: &Device) {
        let mut rng = ChaCha8Rng::seed_from_u64(27);
        for case in 0..40 {
            let windows = rng.random_range(1..5);
            let channels = rng.random_range(1..10);
            let (pattern, steps, outputs, width) = if case % 2 == 0 {
                let kernel = rng.random_range(1..=4);
                let steps = rng.random_range(kernel..kernel + 9);
                let outputs = windows * (steps + 1 - kernel);
                (Pattern::Time { kernel }, steps, outputs, kernel * channels)
            } else {
                let (steps, rows) = (rng.random_range(2..10), rng.random_range(2..=6));
                let outputs = windows * (steps - 1) * (rows - 1);
                (Pattern::Grid { rows }, steps, outputs, 4 * channels)
            };
            let positions = match pattern {
                Pattern::Time { .. } => windows * steps,
                Pattern::Grid { rows } => windows * steps * rows,
            };
            let x = random(&mut rng, [positions, channels], device);
            let weights = random(&mut rng, [outputs, width], device);
            let [ours, theirs] = both(x, weights, windows, steps, pattern);
            let label =
                format!("{pattern:?}, {windows} windows, {steps} steps, {channels} channels");
            assert_eq!(bits(&ours.0), bits(&theirs.0), "forward: {label}");
            assert_eq!(ours.1.is_some(), device.is_autodiff());
            assert_eq!(
                ours.1.as_deref().map(bits),
                theirs.1.as_deref().map(bits),
                "gradient: {label}"
            );
        }
    }

    #[test]
    fn flex_matches_select() {
        matches_select_on(&Device::flex());
        matches_select_on(&Device::flex().autodiff());
    }

    #[test]
    fn ndarray_matches_select() {
        matches_select_on(&Device::ndarray());
        matches_select_on(&Device::ndarray().autodiff());
    }

    /// One window of three steps, one channel, kernel 2: outputs [1, 2] and [2, 3]; the
    /// middle step is read twice, so its gradient under `sum` is 2.
    #[test]
    fn time_known_answer() {
        let device = Device::flex().autodiff();
        let x = Tensor::<2>::from_data(TensorData::new(vec![1.0f32, 2.0, 3.0], [3, 1]), &device)
            .require_grad();
        let y = unfold_time(x.clone(), 1, 2);
        assert_eq!(y.dims(), [2, 2]);
        assert_eq!(values(y.clone()), [1.0, 2.0, 2.0, 3.0]);
        let grads = y.sum().backward();
        assert_eq!(values(x.grad(&grads).unwrap()), [1.0, 2.0, 1.0]);
    }

    /// One window of 2 steps × 3 rows, one channel, x(t, r) = 10t + r: the two outputs
    /// read (0, r), (1, r), (0, r + 1), (1, r + 1); under `sum` the middle row is read
    /// twice at each step.
    #[test]
    fn grid_known_answer() {
        let device = Device::flex().autodiff();
        let x = Tensor::<2>::from_data(
            TensorData::new(vec![0.0f32, 1.0, 2.0, 10.0, 11.0, 12.0], [6, 1]),
            &device,
        )
        .require_grad();
        let y = unfold_grid(x.clone(), 1, 2, 3);
        assert_eq!(y.dims(), [2, 4]);
        assert_eq!(
            values(y.clone()),
            [0.0, 10.0, 1.0, 11.0, 1.0, 11.0, 2.0, 12.0]
        );
        let grads = y.sum().backward();
        assert_eq!(
            values(x.grad(&grads).unwrap()),
            [1.0, 2.0, 1.0, 1.0, 2.0, 1.0]
        );
    }
}
