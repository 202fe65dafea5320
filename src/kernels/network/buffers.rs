//! The buffers a step reuses ([`Workspace`], one [`SliceBuffers`] per slice, kept by
//! the thread between steps) and the arithmetic they are filled by: the `gemm` product
//! of two operands, and the unfolding of the heads' inputs into the convolutions' taps
//! and its gradient.
//! In: slices of `f32`. Out: the same buffers, filled.

use super::{LAYERS, PARAMETERS, SLICES};
use crate::kernels::Reused;
use crate::kernels::unfold::GRID_TAPS;
use std::cell::RefCell;

/// A step's buffers: one set per slice.
#[derive(Debug)]
pub(super) struct Workspace {
    pub(super) slices: Vec<SliceBuffers>,
    /// Each parameter's gradient, the slices' summed.
    pub(super) grads: [Reused; PARAMETERS],
}

/// Values of a parameter summed over the slices per task of the pool.
pub(super) const SUM_CHUNK: usize = 4096;

/// One slice's activations and gradients, grown to the largest slice seen and reused.
#[derive(Debug, Default)]
pub(super) struct SliceBuffers {
    /// Each layer's output after its activation, before its mask.
    pub(super) activated: [Vec<f32>; LAYERS],
    /// The dropout masks of the first three Linear layers.
    pub(super) masks: [Vec<f32>; 3],
    /// The first three Linear layers' outputs times their masks.
    pub(super) masked: [Vec<f32>; 3],
    /// The inputs of Conv1d 2 and Conv2d 2 and 3: their input's taps side by side.
    pub(super) unfolded: [Vec<f32>; 3],
    /// The two heads side by side, the first Linear layer's input.
    pub(super) features: Vec<f32>,
    /// Each layer's pre-activation gradient.
    pub(super) grads: [Vec<f32>; LAYERS],
    /// The gradient of the features.
    pub(super) features_grad: Vec<f32>,
    /// The gradient of the 1D and the 2D head's unfolded inputs, before folding.
    pub(super) folded: [Vec<f32>; 2],
    /// Every parameter's gradient from this slice, in parameter order.
    pub(super) param_grads: Vec<f32>,
}

thread_local! {
    /// The workspace this thread's last step gave back.
    static SPARE: RefCell<Option<Box<Workspace>>> = const { RefCell::new(None) };
}

impl Workspace {
    /// This thread's workspace, or a new one.
    pub(super) fn take() -> Box<Workspace> {
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
    pub(super) fn give_back(workspace: Box<Workspace>) {
        SPARE.with(|spare| *spare.borrow_mut() = Some(workspace));
    }
}

/// `buffer`'s length set to `len` (reallocating only to grow past its capacity); its
/// values are overwritten by the caller.
pub(super) fn resize(buffer: &mut Vec<f32>, len: usize) {
    buffer.resize(len, 0.0);
}

/// A matrix operand of [`product`]: its values and its row and column strides.
pub(super) struct Operand<'a> {
    pub(super) values: &'a [f32],
    pub(super) row_stride: isize,
    pub(super) column_stride: isize,
}

impl<'a> Operand<'a> {
    /// `values` as a row-major matrix of `columns` columns.
    pub(super) fn plain(values: &'a [f32], columns: usize) -> Self {
        Self {
            values,
            row_stride: columns as isize,
            column_stride: 1,
        }
    }

    /// The transpose of `values` read as a row-major matrix of `columns` columns.
    pub(super) fn transposed(values: &'a [f32], columns: usize) -> Self {
        Self {
            values,
            row_stride: 1,
            column_stride: columns as isize,
        }
    }
}

/// `output ← lhs·rhs` for `[m, k]·[k, n]` given as `[m, n, k]`, on this thread.
pub(super) fn product(output: &mut [f32], [m, n, k]: [usize; 3], lhs: Operand, rhs: Operand) {
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
pub(super) fn unfold_time(
    x: &[f32],
    windows: usize,
    steps: usize,
    kernel: usize,
    out: &mut Vec<f32>,
) {
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
pub(super) fn fold_time(
    grad: &[f32],
    windows: usize,
    steps: usize,
    kernel: usize,
    out: &mut Vec<f32>,
) {
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
pub(super) fn unfold_grid(
    x: &[f32],
    windows: usize,
    steps: usize,
    rows: usize,
    out: &mut Vec<f32>,
) {
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
pub(super) fn fold_grid(
    grad: &[f32],
    windows: usize,
    steps: usize,
    rows: usize,
    out: &mut Vec<f32>,
) {
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
pub(super) fn add(row: &mut [f32], block: &[f32]) {
    for (sum, value) in row.iter_mut().zip(block) {
        *sum += value;
    }
}
