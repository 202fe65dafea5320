//! DCNet (PAPER-NOTES, "DCNet"): a 1D head on `v_dvl − v_gnss`, a 2D head on the whole
//! 6×10 window, and a batch of four Linear layers that outputs the error model's terms.
//! In: a `[batch, 6, time]` window of DVL and GNSS-RTK velocity in m/s. Out: the terms,
//! scale in % and bias in cm/s (the spec's units, which keep the outputs near 1).
//!
//! Weights are drawn from a generator the caller seeds, and dropout masks too, so a
//! model does not depend on burn's process-wide random state or on which other models
//! train at the same time.

use crate::dataset::{INPUT_ROWS, TARGET_ROWS};
use crate::estimators::{Correction, ErrorModel};
use crate::spec::ModelSpec;
use burn::module::{Module, Param, ParamId};
use burn::nn::conv::{Conv1d, Conv1dConfig, Conv2d, Conv2dConfig};
use burn::nn::{Initializer, Linear, LinearConfig};
use burn::tensor::activation::{leaky_relu, tanh};
use burn::tensor::{Device, Tensor, TensorData};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use std::fmt;
use std::str::FromStr;

/// The activation of the FC batch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Activation {
    Tanh,
    LeakyRelu,
}

impl fmt::Display for Activation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Tanh => "tanh",
            Self::LeakyRelu => "leaky_relu",
        })
    }
}

impl FromStr for Activation {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "tanh" => Ok(Self::Tanh),
            "leaky_relu" => Ok(Self::LeakyRelu),
            _ => Err(format!(
                "unknown activation {s:?}; expected tanh or leaky_relu"
            )),
        }
    }
}

#[derive(Module, Debug)]
pub struct Dcnet {
    conv1d: Vec<Conv1d>,
    conv2d: Vec<Conv2d>,
    fc: Vec<Linear>,
}

/// What a forward pass needs besides the weights.
pub struct Settings {
    pub activation: Activation,
    pub leaky_relu_slope: f64,
    pub dropout: f64,
}

impl From<&ModelSpec> for Settings {
    fn from(spec: &ModelSpec) -> Self {
        Self {
            activation: spec.activation,
            leaky_relu_slope: spec.leaky_relu_slope,
            dropout: spec.dropout,
        }
    }
}

impl Dcnet {
    /// A freshly initialised DCNet for `error_model` on windows of `window` samples:
    /// every weight and bias uniform in ±1/√fan_in (PyTorch's default), drawn from `rng`.
    pub fn new(
        spec: &ModelSpec,
        error_model: ErrorModel,
        window: usize,
        device: &Device,
        rng: &mut ChaCha8Rng,
    ) -> Self {
        let params = &mut ParamSource { rng, next_id: 0 };
        let channels = spec.conv_channels;
        let kernel = spec.conv1d_kernel_size;
        let conv1d = vec![
            conv1d(TARGET_ROWS, channels, kernel, device, params),
            conv1d(channels, channels, kernel, device, params),
        ];
        let conv2d = vec![
            conv2d(1, channels, [3, 1], device, params),
            conv2d(channels, channels, [1, 1], device, params),
            conv2d(channels, channels, [1, 1], device, params),
        ];
        // 1D head: time shrinks by kernel − 1 per conv. 2D head: rows 6 → 3 → 2 → 1
        // (the first conv pairs row i with row i + 3), time shrinks by 1 per conv.
        let flat_1d = channels * (window - 2 * (kernel - 1));
        let flat_2d = channels * (window - 3);
        let [w1, w2, w3] = spec.fc_widths;
        let fc = vec![
            linear(flat_1d + flat_2d, w1, device, params),
            linear(w1, w2, device, params),
            linear(w2, w3, device, params),
            linear(w3, error_model.term_count(), device, params),
        ];
        Self { conv1d, conv2d, fc }
    }

    /// `[batch, 6, time]` windows → `[batch, terms]`. Dropout is applied when
    /// `dropout_rng` is given (training), with masks drawn from it.
    pub fn forward(
        &self,
        input: Tensor<3>,
        settings: &Settings,
        mut dropout_rng: Option<&mut ChaCha8Rng>,
    ) -> Tensor<2> {
        let [batch, rows, time] = input.dims();
        debug_assert_eq!(rows, INPUT_ROWS);
        let slope = settings.leaky_relu_slope;

        // 1D head on the DVL − GNSS difference, in cm/s: [batch, 3, time].
        let dvl = input.clone().slice([0..batch, 0..3, 0..time]);
        let gnss = input.clone().slice([0..batch, 3..6, 0..time]);
        let mut head_1d = (dvl - gnss) * 100.0;
        for conv in &self.conv1d {
            head_1d = leaky_relu(conv.forward(head_1d), slope);
        }
        let head_1d: Tensor<2> = head_1d.flatten(1, 2);

        // 2D head on the window as one channel: [batch, 1, 6, time].
        let mut head_2d: Tensor<4> = input.reshape([batch, 1, rows, time]);
        for conv in &self.conv2d {
            head_2d = leaky_relu(conv.forward(head_2d), slope);
        }
        let head_2d: Tensor<2> = head_2d.flatten(1, 3);

        let mut x = Tensor::cat(vec![head_1d, head_2d], 1);
        let last = self.fc.len() - 1;
        for linear in &self.fc[..last] {
            x = linear.forward(x);
            x = match settings.activation {
                Activation::Tanh => tanh(x),
                Activation::LeakyRelu => leaky_relu(x, slope),
            };
            if let Some(rng) = dropout_rng.as_deref_mut() {
                x = dropout(x, settings.dropout, rng);
            }
        }
        self.fc[last].forward(x)
    }
}

/// Zeroes each element with probability `p` and scales the rest by 1/(1 − p).
fn dropout(x: Tensor<2>, p: f64, rng: &mut ChaCha8Rng) -> Tensor<2> {
    if p == 0.0 {
        return x;
    }
    let [rows, cols] = x.dims();
    let keep = (1.0 / (1.0 - p)) as f32;
    let mask: Vec<f32> = (0..rows * cols)
        .map(|_| if rng.random::<f64>() < p { 0.0 } else { keep })
        .collect();
    let mask = Tensor::from_data(TensorData::new(mask, [rows, cols]), &x.device());
    x * mask
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

fn conv1d(
    channels_in: usize,
    channels_out: usize,
    kernel: usize,
    device: &Device,
    params: &mut ParamSource,
) -> Conv1d {
    let mut conv = Conv1dConfig::new(channels_in, channels_out, kernel)
        .with_initializer(Initializer::Zeros)
        .init(device);
    let bound = 1.0 / ((channels_in * kernel) as f64).sqrt();
    conv.weight = params.uniform([channels_out, channels_in, kernel], bound, device);
    conv.bias = Some(params.uniform([channels_out], bound, device));
    conv
}

/// A 2×2 convolution with the given (row, time) dilation.
fn conv2d(
    channels_in: usize,
    channels_out: usize,
    dilation: [usize; 2],
    device: &Device,
    params: &mut ParamSource,
) -> Conv2d {
    let mut conv = Conv2dConfig::new([channels_in, channels_out], [2, 2])
        .with_dilation(dilation)
        .with_initializer(Initializer::Zeros)
        .init(device);
    let bound = 1.0 / ((channels_in * 4) as f64).sqrt();
    conv.weight = params.uniform([channels_out, channels_in, 2, 2], bound, device);
    conv.bias = Some(params.uniform([channels_out], bound, device));
    conv
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
