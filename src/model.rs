//! DCNet (docs/paper.md, "DCNet"): a 1D head on `v_dvl − v_gnss`, a 2D head on the whole
//! 6×10 window, and a batch of four Linear layers that outputs the error model's terms.
//! In: windows of DVL and GNSS-RTK velocity in m/s. Out: the terms, scale in % and bias
//! in cm/s (the spec's units, which keep the outputs near 1).
//!
//! Every convolution runs as one matrix product over its unfolded windows: activations
//! are rows of channels, one row per (window, time, row of the 2D head), and a layer
//! gathers each output's taps side by side ([`crate::kernels::unfold`]) and applies a
//! Linear layer. This is the same network as a stack of Conv1d and Conv2d, in far fewer
//! and larger operations; only the order of the first Linear layer's inputs differs
//! (time-major here, channel-major after burn's or PyTorch's convolutions).
//!
//! Weights are drawn from a generator the caller seeds, and dropout masks too, so a
//! model does not depend on burn's process-wide random state or on which other models
//! train at the same time.

use crate::dataset::{INPUT_ROWS, TARGET_ROWS};
use crate::kernels;
use crate::kernels::unfold::{GRID_TAPS, unfold_grid, unfold_time};
use crate::spec::ModelSpec;
use crate::vocab::{Activation, Correction, ErrorModel};
use burn::module::{Module, Param, ParamId};
use burn::nn::{Initializer, Linear, LinearConfig};
use burn::tensor::activation::{leaky_relu, tanh};
use burn::tensor::{Device, Tensor, TensorData};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// The three convolutions of the 2D head have 2×2 kernels, their taps in [`GRID_TAPS`]
/// order; the first pairs row i with row i + 3 (DVL with GNSS), the next two neighbouring
/// rows.
const KERNEL_2D: usize = GRID_TAPS.len();

/// The rows between the two taps of the first Conv2d: DVL row i and GNSS row i.
const FIRST_ROW_DILATION: usize = 3;

#[derive(Module, Debug)]
pub struct Dcnet {
    /// The two Conv1d of the 1D head, each over `kernel` time steps of its input.
    conv1d: Vec<Linear>,
    /// The three 2×2 Conv2d of the 2D head.
    conv2d: Vec<Linear>,
    fc: Vec<Linear>,
}

/// What a forward pass needs besides the weights.
pub struct Settings {
    pub activation: Activation,
    pub leaky_relu_slope: f64,
    pub dropout: f64,
    /// Time steps of a Conv1d kernel.
    pub kernel: usize,
}

impl From<&ModelSpec> for Settings {
    fn from(spec: &ModelSpec) -> Self {
        Self {
            activation: spec.activation,
            leaky_relu_slope: spec.leaky_relu_slope,
            dropout: spec.dropout,
            kernel: spec.conv1d_kernel_size,
        }
    }
}

/// One linear map of the network, `inputs` → `outputs`, applied at `positions` places
/// of a window (its time steps and rows for a convolution, once for a dense layer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayerShape {
    pub inputs: usize,
    pub outputs: usize,
    pub positions: usize,
}

impl LayerShape {
    pub fn parameters(&self) -> usize {
        (self.inputs + 1) * self.outputs
    }
}

/// What the network reads and writes besides the 2D head's 6 rows: the channels of the
/// 1D head's input (3: `v_dvl − v_gnss`; 6: and the body rate, for an installation) and
/// the terms it outputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NetworkIo {
    pub channels_1d: usize,
    pub outputs: usize,
}

impl From<ErrorModel> for NetworkIo {
    /// The paper's network for `error_model`.
    fn from(error_model: ErrorModel) -> Self {
        NetworkIo {
            channels_1d: 3,
            outputs: error_model.term_count(),
        }
    }
}

/// DCNet's layers on windows of `window` samples, in the order their weights are
/// drawn: the two Conv1d of the 1D head, the three Conv2d of the 2D head, the four
/// Linear. The 1D head's time shrinks by `kernel − 1` per conv; the 2D head's rows go
/// 6 → 3 → 2 → 1 (the first conv pairs row i with row i + 3) and its time shrinks by 1
/// per conv.
pub fn layer_shapes(spec: &ModelSpec, io: impl Into<NetworkIo>, window: usize) -> Vec<LayerShape> {
    let io = io.into();
    let channels = spec.conv_channels;
    let kernel = spec.conv1d_kernel_size;
    let shape = |inputs, outputs, positions| LayerShape {
        inputs,
        outputs,
        positions,
    };
    let steps_1d = [window + 1 - kernel, window + 2 - 2 * kernel];
    let flat_1d = channels * steps_1d[1];
    let flat_2d = channels * (window - 3);
    let [w1, w2, w3] = spec.fc_widths;
    vec![
        shape(io.channels_1d * kernel, channels, steps_1d[0]),
        shape(channels * kernel, channels, steps_1d[1]),
        shape(KERNEL_2D, channels, 3 * (window - 1)),
        shape(channels * KERNEL_2D, channels, 2 * (window - 2)),
        shape(channels * KERNEL_2D, channels, window - 3),
        shape(flat_1d + flat_2d, w1, 1),
        shape(w1, w2, 1),
        shape(w2, w3, 1),
        shape(w3, io.outputs, 1),
    ]
}

/// A batch of windows as the network and the loss take it. The first layer of each
/// head reads its unfolded input directly, built here on the CPU: it depends on the
/// data only, never on the weights.
pub struct Windows {
    pub count: usize,
    pub time: usize,
    /// `[count × (time − kernel + 1), channels × kernel]`: `v_dvl − v_gnss` in cm/s, then
    /// the body rate in deg/s where the windows hold it, at each tap of the first
    /// Conv1d, tap-major.
    head_1d: Tensor<2>,
    /// `[count × (time − 1) × 3, 4]`: the 2×2 taps of the first Conv2d, (row, time)-major.
    head_2d: Tensor<2>,
    /// `[count, time, 3]`: the DVL velocity in cm/s, which the loss corrects.
    pub dvl_cm_s: Tensor<3>,
    /// `[count, time, 3]`: the body rate in rad/s, where the windows hold it.
    pub rate_rad_s: Option<Tensor<3>>,
}

impl Windows {
    /// `inputs` `[count, rows, time]` row-major: DVL x, y, z then GNSS (or reference)
    /// x, y, z, in m/s, and with `rows` = 9 the body rate p, q, r in rad/s.
    pub fn new(inputs: &[f32], rows: usize, time: usize, kernel: usize, device: &Device) -> Self {
        let windows: Vec<&[f32]> = inputs.chunks_exact(rows * time).collect();
        Self::of(
            &windows,
            rows,
            time,
            kernel,
            device,
            &mut BatchBuffers::default(),
        )
    }

    /// [`Windows::new`] of windows that lie apart, each `[rows, time]` row-major: a
    /// batch read straight from a training set, into `buffers` (where a training step's
    /// batch is made each step, so that it writes no new buffer). Chunks of windows fill
    /// their rows in parallel.
    pub fn of(
        windows: &[&[f32]],
        rows: usize,
        time: usize,
        kernel: usize,
        device: &Device,
        buffers: &mut BatchBuffers,
    ) -> Self {
        assert!(rows == INPUT_ROWS || rows == INPUT_ROWS + 3, "6 or 9 rows");
        let with_rate = rows > INPUT_ROWS;
        let channels_1d = if with_rate { 6 } else { 3 };
        let count = windows.len();
        let steps_1d = time + 1 - kernel;
        let sizes = [
            steps_1d * channels_1d * kernel,
            (time - 1) * 3 * KERNEL_2D,
            time * 3,
        ];
        let head_1d = buffers
            .head_1d
            .values_mut([count * steps_1d, channels_1d * kernel].into());
        let head_2d = buffers
            .head_2d
            .values_mut([count * (time - 1) * 3, KERNEL_2D].into());
        let dvl = buffers.dvl.values_mut([count, time, 3].into());
        let task = |size: usize| size * WINDOWS_PER_TASK;
        head_1d
            .par_chunks_mut(task(sizes[0]))
            .zip(head_2d.par_chunks_mut(task(sizes[1])))
            .zip(dvl.par_chunks_mut(task(sizes[2])))
            .zip(windows.par_chunks(WINDOWS_PER_TASK))
            .for_each(|(((head_1d, head_2d), dvl), windows)| {
                windows.iter().for_each(|window| touch(window));
                let outputs = head_1d
                    .chunks_mut(sizes[0])
                    .zip(head_2d.chunks_mut(sizes[1]));
                let outputs = outputs.zip(dvl.chunks_mut(sizes[2]));
                for (((head_1d, head_2d), dvl), window) in outputs.zip(windows) {
                    head_1d_taps(window, time, kernel, with_rate, head_1d);
                    head_2d_taps(window, time, head_2d);
                    samples(window, time, 0, 100.0, dvl);
                }
            });
        let rate_rad_s = with_rate.then(|| {
            let rate = buffers.rate.values_mut([count, time, 3].into());
            for (rate, window) in rate.chunks_mut(time * 3).zip(windows) {
                samples(window, time, 6, 1.0, rate);
            }
            buffers.rate.tensor_on(device)
        });
        Self {
            count,
            time,
            head_1d: buffers.head_1d.tensor_on(device),
            head_2d: buffers.head_2d.tensor_on(device),
            dvl_cm_s: buffers.dvl.tensor_on(device),
            rate_rad_s,
        }
    }
}

/// The buffers a batch of [`Windows::of`] and its [`truth_cm_s`] are written to: each
/// reused from the last batch once its tensors are dropped.
#[derive(Debug, Default)]
pub struct BatchBuffers {
    head_1d: kernels::Reused,
    head_2d: kernels::Reused,
    dvl: kernels::Reused,
    rate: kernels::Reused,
    truth: kernels::Reused,
}

/// Windows filled per task of the pool in [`Windows::of`] and [`truth_cm_s`].
const WINDOWS_PER_TASK: usize = 16;

/// Reads one value in each cache line of `values`. A batch's windows lie at random in a
/// training set of hundreds of MB, and read one after the other each waits for memory
/// in turn; these reads do not depend on each other, so their waits overlap, and the
/// windows are in cache when they are read.
fn touch(values: &[f32]) {
    const PER_LINE: usize = 64 / std::mem::size_of::<f32>();
    for value in values.iter().step_by(PER_LINE).chain(values.last()) {
        std::hint::black_box(*value);
    }
}

/// Targets of each window `[3, time]` row-major in m/s → `[count, time, 3]` in cm/s, the
/// layout of [`Windows::dvl_cm_s`].
pub fn truth_cm_s(
    windows: &[&[f32]],
    time: usize,
    device: &Device,
    buffers: &mut BatchBuffers,
) -> Tensor<3> {
    let count = windows.len();
    let size = time * TARGET_ROWS;
    buffers
        .truth
        .values_mut([count, time, TARGET_ROWS].into())
        .par_chunks_mut(size * WINDOWS_PER_TASK)
        .zip(windows.par_chunks(WINDOWS_PER_TASK))
        .for_each(|(truth, windows)| {
            windows.iter().for_each(|window| touch(window));
            for (truth, targets) in truth.chunks_mut(size).zip(windows) {
                samples(targets, time, 0, 100.0, truth);
            }
        });
    buffers.truth.tensor_on(device)
}

/// The first Conv1d's taps of `window` (`[rows, time]` row-major, m/s and rad/s) into
/// `out`, `[time − kernel + 1, channels × kernel]`: `v_dvl − v_gnss` in cm/s, then the body
/// rate in deg/s `with_rate`, tap-major.
fn head_1d_taps(window: &[f32], time: usize, kernel: usize, with_rate: bool, out: &mut [f32]) {
    let value = |row: usize, t: usize| window[row * time + t];
    let mut out = out.iter_mut();
    for t in 0..time + 1 - kernel {
        for tap in 0..kernel {
            for axis in 0..3 {
                let difference = value(axis, t + tap) - value(axis + 3, t + tap);
                *out.next().expect("sized to the taps") = difference * 100.0;
            }
            if with_rate {
                for axis in 0..3 {
                    let rate = value(axis + 6, t + tap).to_degrees();
                    *out.next().expect("sized to the taps") = rate;
                }
            }
        }
    }
}

/// The first Conv2d's 2×2 taps of `window`'s six velocity rows into `out`,
/// `[(time − 1) × 3, 4]`, (row, time)-major, in m/s.
fn head_2d_taps(window: &[f32], time: usize, out: &mut [f32]) {
    let mut out = out.iter_mut();
    for t in 0..time - 1 {
        for row in 0..3 {
            for (row_tap, time_tap) in GRID_TAPS {
                let row = row + FIRST_ROW_DILATION * row_tap;
                *out.next().expect("sized to the taps") = window[row * time + t + time_tap];
            }
        }
    }
}

/// Rows `first..first + 3` of `window` (`[rows, time]` row-major) times `scale`, sample by
/// sample, into `out`, `[time, 3]`.
fn samples(window: &[f32], time: usize, first: usize, scale: f32, out: &mut [f32]) {
    for (t, sample) in out.chunks_exact_mut(3).enumerate() {
        for (axis, value) in sample.iter_mut().enumerate() {
            *value = window[(first + axis) * time + t] * scale;
        }
    }
}

impl Dcnet {
    /// A freshly initialised DCNet for `io` (an error model's, or an installation's) on
    /// windows of `window` samples: every weight and bias uniform in ±1/√fan_in
    /// (PyTorch's default), drawn from `rng`.
    pub fn new(
        spec: &ModelSpec,
        io: impl Into<NetworkIo>,
        window: usize,
        device: &Device,
        rng: &mut ChaCha8Rng,
    ) -> Self {
        let params = &mut ParamSource { rng, next_id: 0 };
        let mut layers = layer_shapes(spec, io, window)
            .into_iter()
            .map(|shape| linear(shape.inputs, shape.outputs, device, params));
        let mut take = |n: usize| layers.by_ref().take(n).collect::<Vec<_>>();
        let (conv1d, conv2d, fc) = (take(2), take(3), take(4));
        Self { conv1d, conv2d, fc }
    }

    /// `windows` → terms `[count, terms]`. Dropout is applied when `dropout_rng` is
    /// given (training), with masks drawn from it, layer by layer. On Flex the whole
    /// network is one operation over fixed slices of the batch
    /// ([`kernels::network`]); elsewhere it is composed of burn's operations.
    pub fn forward(
        &self,
        windows: &Windows,
        settings: &Settings,
        dropout_rng: Option<&mut ChaCha8Rng>,
    ) -> Tensor<2> {
        let dropout =
            dropout_rng
                .filter(|_| settings.dropout > 0.0)
                .map(|rng| kernels::network::Dropout {
                    p: settings.dropout,
                    seed: rng.random(),
                });
        if kernels::network::runs_on(&windows.head_1d) {
            let shape = kernels::network::NetworkShape {
                time: windows.time,
                kernel: settings.kernel,
                head_slope: settings.leaky_relu_slope as f32,
                fc_leaky_slope: match settings.activation {
                    Activation::Tanh => None,
                    Activation::LeakyRelu => Some(settings.leaky_relu_slope as f32),
                },
            };
            let layers = || self.conv1d.iter().chain(&self.conv2d).chain(&self.fc);
            let weights = layers().map(|layer| layer.weight.val()).collect();
            let biases = layers()
                .map(|layer| layer.bias.as_ref().expect("every layer has a bias").val())
                .collect();
            let (head_1d, head_2d) = (windows.head_1d.clone(), windows.head_2d.clone());
            return kernels::network::dcnet(weights, biases, head_1d, head_2d, dropout, shape);
        }
        self.composed(windows, settings, dropout)
    }

    /// [`Dcnet::forward`] composed of burn's operations, layer by layer.
    fn composed(
        &self,
        windows: &Windows,
        settings: &Settings,
        dropout: Option<kernels::network::Dropout>,
    ) -> Tensor<2> {
        let mut x = self.features(windows, settings);
        let last = self.fc.len() - 1;
        for (i, layer) in self.fc[..last].iter().enumerate() {
            x = match settings.activation {
                Activation::Tanh => tanh(layer.forward(x)),
                Activation::LeakyRelu => leaky_relu(layer.forward(x), settings.leaky_relu_slope),
            };
            if let Some(dropout) = dropout {
                let shape = x.dims();
                let mask = dropout.mask(i, shape[0], shape[1]);
                x = x * Tensor::from_data(TensorData::new(mask, shape), &windows.head_1d.device());
            }
        }
        self.fc[last].forward(x)
    }

    /// The two heads side by side, `[count, flat_1d + flat_2d]`, each flattened
    /// time-major (all channels of one time step, then the next).
    fn features(&self, windows: &Windows, settings: &Settings) -> Tensor<2> {
        let (count, time, kernel) = (windows.count, windows.time, settings.kernel);
        let slope = settings.leaky_relu_slope;
        let layer = |conv: &Linear, x: Tensor<2>| leaky_relu(conv.forward(x), slope);

        // 1D head: rows (window, time), then the second conv gathers `kernel` rows.
        let head_1d = layer(&self.conv1d[0], windows.head_1d.clone());
        let head_1d = layer(&self.conv1d[1], unfold_time(head_1d, count, kernel));

        // 2D head: rows (window, time, row); each conv gathers a 2×2 neighbourhood.
        let mut head_2d = layer(&self.conv2d[0], windows.head_2d.clone());
        let (mut steps, mut rows) = (time - 1, 3);
        for conv in &self.conv2d[1..] {
            head_2d = layer(conv, unfold_grid(head_2d, count, steps, rows));
            (steps, rows) = (steps - 1, rows - 1);
        }
        Tensor::cat(
            vec![
                head_1d.reshape([count as i32, -1]),
                head_2d.reshape([count as i32, -1]),
            ],
            1,
        )
    }
}

/// Terms `[batch, terms]` of `error_model` → per-axis scale (%) and bias (cm/s), each
/// `[batch, 3]`.
pub fn split_terms(terms: Tensor<2>, error_model: ErrorModel) -> (Tensor<2>, Tensor<2>) {
    let [batch, _] = terms.dims();
    let device = terms.device();
    let zeros = || Tensor::zeros([batch, 3], &device);
    match error_model {
        ErrorModel::Em1 => (terms.expand([batch, 3]), zeros()),
        ErrorModel::Em2 => (terms, zeros()),
        ErrorModel::Em3 => (zeros(), terms.expand([batch, 3])),
        ErrorModel::Em4 => (zeros(), terms),
        ErrorModel::Em5 => (
            terms.clone().slice([0..batch, 0..3]),
            terms.slice([0..batch, 3..6]),
        ),
    }
}

/// The columns of `error_model`'s terms that [`split_terms`] reads for each axis's scale
/// factor and bias.
pub fn term_columns(error_model: ErrorModel) -> kernels::loss::TermColumns {
    let (every, none) = ([0, 1, 2].map(Some), [None; 3]);
    let (scale_pct, bias_cm_s) = match error_model {
        ErrorModel::Em1 => ([Some(0); 3], none),
        ErrorModel::Em2 => (every, none),
        ErrorModel::Em3 => (none, [Some(0); 3]),
        ErrorModel::Em4 => (none, every),
        ErrorModel::Em5 => (every, [3, 4, 5].map(Some)),
    };
    kernels::loss::TermColumns {
        scale_pct,
        bias_cm_s,
    }
}

/// The correction that one row of network output stands for.
pub fn correction(terms: &[f32], error_model: ErrorModel) -> Correction {
    let t = |i: usize| f64::from(terms[i]) / 100.0;
    match error_model {
        ErrorModel::Em1 => Correction {
            scale: [t(0); 3],
            bias_m_s: [0.0; 3],
        },
        ErrorModel::Em2 => Correction {
            scale: [t(0), t(1), t(2)],
            bias_m_s: [0.0; 3],
        },
        ErrorModel::Em3 => Correction {
            scale: [0.0; 3],
            bias_m_s: [t(0); 3],
        },
        ErrorModel::Em4 => Correction {
            scale: [0.0; 3],
            bias_m_s: [t(0), t(1), t(2)],
        },
        ErrorModel::Em5 => Correction {
            scale: [t(0), t(1), t(2)],
            bias_m_s: [t(3), t(4), t(5)],
        },
    }
}

/// Draws the parameters of one model: uniform values from the model's generator, and
/// parameter ids numbered from 1 in creation order, so that saved weights and optimizer
/// state are the same bytes in every run.
struct ParamSource<'a> {
    rng: &'a mut ChaCha8Rng,
    next_id: u64,
}

impl ParamSource<'_> {
    /// Uniform values in ±`bound`.
    fn uniform<const D: usize>(
        &mut self,
        shape: [usize; D],
        bound: f64,
        device: &Device,
    ) -> Param<Tensor<D>> {
        let values: Vec<f32> = (0..shape.iter().product())
            .map(|_| self.rng.random_range(-bound..bound) as f32)
            .collect();
        let tensor = Tensor::from_data(TensorData::new(values, shape), device);
        let tensor = if device.is_autodiff() {
            tensor.require_grad()
        } else {
            tensor
        };
        self.next_id += 1;
        Param::initialized(ParamId::from(self.next_id), tensor)
    }
}

fn linear(d_input: usize, d_output: usize, device: &Device, params: &mut ParamSource) -> Linear {
    let mut linear = LinearConfig::new(d_input, d_output)
        .with_initializer(Initializer::Zeros)
        .init(device);
    let bound = 1.0 / (d_input as f64).sqrt();
    linear.weight = params.uniform([d_input, d_output], bound, device);
    linear.bias = Some(params.uniform([d_output], bound, device));
    linear
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::quick_spec;
    use burn::module::Param;
    use burn::nn::PaddingConfig2d;
    use burn::nn::conv::{Conv1dConfig, Conv2dConfig};
    use rand::SeedableRng;

    /// `linear`'s weight `[taps × c_in, c_out]` as a convolution kernel
    /// `[c_out, c_in, taps]`.
    fn kernel(linear: &Linear, taps: usize) -> Tensor<3> {
        let [rows, c_out] = linear.weight.val().dims();
        linear
            .weight
            .val()
            .reshape([taps, rows / taps, c_out])
            .permute([2, 1, 0])
    }

    /// The heads computed with burn's own Conv1d and Conv2d on the same weights agree
    /// with the unfolded matrix products.
    #[test]
    fn unfolded_heads_match_burns_convolutions() {
        let spec = quick_spec(&["model.conv1d_kernel_size=3"]);
        let device = Device::flex();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let window = spec.dataset.window_samples;
        let model = Dcnet::new(&spec.model, ErrorModel::Em5, window, &device, &mut rng);
        let settings = Settings::from(&spec.model);
        let (count, k, c) = (5, settings.kernel, spec.model.conv_channels);
        let inputs: Vec<f32> = (0..count * INPUT_ROWS * window)
            .map(|_| rng.random_range(-2.0..2.0))
            .collect();
        let windows = Windows::new(&inputs, INPUT_ROWS, window, k, &device);
        let ours: Vec<f32> = model
            .features(&windows, &settings)
            .into_data()
            .try_to_vec::<f32>()
            .unwrap();

        let slope = settings.leaky_relu_slope;
        let x = Tensor::<3>::from_data(
            TensorData::new(inputs, [count, INPUT_ROWS, window]),
            &device,
        );
        let diff = (x.clone().slice([0..count, 0..3, 0..window])
            - x.clone().slice([0..count, 3..6, 0..window]))
            * 100.0;
        let mut head_1d = diff;
        for (i, linear) in model.conv1d.iter().enumerate() {
            let mut conv = Conv1dConfig::new(if i == 0 { 3 } else { c }, c, k).init(&device);
            conv.weight = Param::from_tensor(kernel(linear, k));
            conv.bias = Some(Param::from_tensor(linear.bias.as_ref().unwrap().val()));
            head_1d = burn::tensor::activation::leaky_relu(conv.forward(head_1d), slope);
        }
        let mut head_2d: Tensor<4> = x.reshape([count, 1, INPUT_ROWS, window]);
        for (i, linear) in model.conv2d.iter().enumerate() {
            let c_in = if i == 0 { 1 } else { c };
            let mut conv = Conv2dConfig::new([c_in, c], [2, 2])
                .with_dilation([if i == 0 { 3 } else { 1 }, 1])
                .with_padding(PaddingConfig2d::Valid)
                .init(&device);
            let weight: Tensor<4> = kernel(linear, 4).reshape([c, c_in, 2, 2]);
            conv.weight = Param::from_tensor(weight);
            conv.bias = Some(Param::from_tensor(linear.bias.as_ref().unwrap().val()));
            head_2d = burn::tensor::activation::leaky_relu(conv.forward(head_2d), slope);
        }
        // Burn's layout is channel-major: [count, c, time] and [count, c, 1, time].
        let head_2d: Tensor<3> = head_2d.squeeze_dim(2);
        let theirs: Vec<f32> = Tensor::cat(
            vec![
                head_1d.swap_dims(1, 2).flatten::<2>(1, 2),
                head_2d.swap_dims(1, 2).flatten::<2>(1, 2),
            ],
            1,
        )
        .into_data()
        .try_to_vec::<f32>()
        .unwrap();
        assert_eq!(ours.len(), theirs.len());
        for (i, (a, b)) in ours.iter().zip(&theirs).enumerate() {
            assert!(
                (a - b).abs() <= 1e-4 * (1.0 + b.abs()),
                "feature {i}: {a} vs {b}"
            );
        }
    }

    /// The parameters' gradients of `sum(terms ⊙ weights)`, layer by layer, weight then
    /// bias, as f32 values.
    fn gradients(model: &Dcnet, terms: Tensor<2>, weights: Tensor<2>) -> Vec<Vec<f32>> {
        let grads = (terms * weights).sum().backward();
        let layers = model.conv1d.iter().chain(&model.conv2d).chain(&model.fc);
        layers
            .flat_map(|layer| {
                let bias = layer.bias.as_ref().unwrap();
                [
                    layer.weight.grad(&grads).unwrap().into_data(),
                    bias.grad(&grads).unwrap().into_data(),
                ]
            })
            .map(|data| data.try_to_vec::<f32>().unwrap())
            .collect()
    }

    /// The one-operation network on Flex against the same network composed of burn's
    /// operations, layer by layer: the terms and every parameter's gradient, with dropout,
    /// on a batch that the slices do not divide evenly and then on one of fewer windows
    /// than slices, for tanh and LeakyReLU Linear layers and a 1D head with the body rate.
    #[test]
    fn the_network_operation_matches_the_composed_layers() {
        for (overrides, rows, io) in [
            (vec![], INPUT_ROWS, NetworkIo::from(ErrorModel::Em5)),
            (
                vec![
                    "model.activation=\"leaky_relu\"",
                    "model.conv1d_kernel_size=3",
                ],
                INPUT_ROWS + 3,
                NetworkIo {
                    channels_1d: 6,
                    outputs: 4,
                },
            ),
        ] {
            let spec = quick_spec(&overrides);
            let device = Device::flex().autodiff();
            let mut rng = ChaCha8Rng::seed_from_u64(11);
            let window = spec.dataset.window_samples;
            let model = Dcnet::new(&spec.model, io, window, &device, &mut rng);
            let settings = Settings::from(&spec.model);
            assert!(settings.dropout > 0.0);
            // 5 windows after 37: fewer than the slices, on buffers a larger batch left.
            for count in [37, 5] {
                let inputs: Vec<f32> = (0..count * rows * window)
                    .map(|_| rng.random_range(-2.0..2.0))
                    .collect();
                let windows = Windows::new(&inputs, rows, window, settings.kernel, &device);
                let weights: Vec<f32> = (0..count * io.outputs)
                    .map(|_| rng.random_range(-1.0..1.0))
                    .collect();
                let weights =
                    Tensor::<2>::from_data(TensorData::new(weights, [count, io.outputs]), &device);
                let one_op =
                    model.forward(&windows, &settings, Some(&mut ChaCha8Rng::seed_from_u64(5)));
                let dropout = kernels::network::Dropout {
                    p: settings.dropout,
                    seed: ChaCha8Rng::seed_from_u64(5).random(),
                };
                let composed = model.composed(&windows, &settings, Some(dropout));
                let close = |a: &[f32], b: &[f32], what: &str| {
                    assert_eq!(a.len(), b.len(), "{what}");
                    let scale = b.iter().fold(0f32, |m, v| m.max(v.abs()));
                    for (i, (x, y)) in a.iter().zip(b).enumerate() {
                        assert!(
                            (x - y).abs() <= 1e-5 * (1.0 + scale),
                            "{what} {i}: {x} vs {y}"
                        );
                    }
                };
                let values = |t: &Tensor<2>| t.clone().into_data().try_to_vec::<f32>().unwrap();
                close(&values(&one_op), &values(&composed), "terms");
                let ours = gradients(&model, one_op, weights.clone());
                let theirs = gradients(&model, composed, weights);
                for (p, (a, b)) in ours.iter().zip(&theirs).enumerate() {
                    close(a, b, &format!("parameter {p}"));
                }
            }
        }
    }

    /// One model's terms and gradients are the same bits on one thread and on three.
    #[test]
    fn the_network_operation_gives_the_same_bits_on_any_thread_count() {
        let spec = quick_spec(&[]);
        let device = Device::flex().autodiff();
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let window = spec.dataset.window_samples;
        let model = Dcnet::new(&spec.model, ErrorModel::Em5, window, &device, &mut rng);
        let settings = Settings::from(&spec.model);
        let count = 203;
        let inputs: Vec<f32> = (0..count * INPUT_ROWS * window)
            .map(|_| rng.random_range(-2.0..2.0))
            .collect();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let windows = Windows::new(&inputs, INPUT_ROWS, window, settings.kernel, &device);
                let weights = Tensor::<2>::ones([count, 6], &device);
                let terms =
                    model.forward(&windows, &settings, Some(&mut ChaCha8Rng::seed_from_u64(1)));
                let bits = |v: Vec<f32>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                let mut all = vec![bits(terms.clone().into_data().try_to_vec::<f32>().unwrap())];
                all.extend(gradients(&model, terms, weights).into_iter().map(bits));
                all
            })
        };
        assert!(run(1) == run(3), "the bits depend on the thread count");
    }
}
