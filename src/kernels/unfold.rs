//! The taps of DCNet's convolutions laid side by side, for the network composed of burn's
//! operations (on `ndarray`, and as the reference the network operation is tested
//! against). In: activations `[positions, channels]`, one row per (window, time) for the
//! 1D head or per (window, time, row) for the 2D head. Out: one row per output position
//! holding the channel blocks of the input rows it reads, ready for one matrix product:
//! burn's `select` on the list of those rows, whose backward adds each block back.

use burn::tensor::{Int, Tensor, TensorData};

/// The 2×2 neighbourhood of a grid output at (time t, row r): the input rows at
/// (t + time offset, r + row offset), as (row offset, time offset), in the order their
/// channel blocks sit in the output row.
pub const GRID_TAPS: [(usize, usize); 4] = [(0, 0), (0, 1), (1, 0), (1, 1)];

/// Rows (window, time) of `x` `[windows × steps, channels]` → `[windows × (steps − kernel
/// + 1), kernel × channels]`: output (w, t) holds input rows (w, t), …, (w, t + kernel − 1).
pub fn unfold_time(x: Tensor<2>, windows: usize, kernel: usize) -> Tensor<2> {
    let [positions, channels] = x.dims();
    let steps = positions / windows;
    let mut taps = Vec::with_capacity(windows * (steps + 1 - kernel) * kernel);
    for w in 0..windows {
        for t in 0..steps + 1 - kernel {
            taps.extend((0..kernel).map(|k| (w * steps + t + k) as i64));
        }
    }
    select(x, taps, kernel * channels)
}

/// Rows (window, time, row) of `x` `[windows × steps × rows, channels]` → `[windows ×
/// (steps − 1) × (rows − 1), 4 × channels]`: output (w, t, r) holds the rows of its 2×2
/// neighbourhood in [`GRID_TAPS`] order.
pub fn unfold_grid(x: Tensor<2>, windows: usize, steps: usize, rows: usize) -> Tensor<2> {
    let channels = x.dims()[1];
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
    select(x, taps, GRID_TAPS.len() * channels)
}

/// The rows `taps` of `x`, `width / channels` of them side by side in each output row.
fn select(x: Tensor<2>, taps: Vec<i64>, width: usize) -> Tensor<2> {
    let count = taps.len();
    let taps = Tensor::<1, Int>::from_data(TensorData::new(taps, [count]), &x.device());
    let channels = x.dims()[1];
    x.select(0, taps).reshape([count * channels / width, width])
}

#[cfg(test)]
mod tests {
    use super::*;
    use burn::tensor::Device;

    fn values(x: Tensor<2>) -> Vec<f32> {
        x.into_data().try_to_vec::<f32>().unwrap()
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
