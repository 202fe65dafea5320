//! The DCNet's activations, tanh and LeakyReLU, as fused one-pass kernels: a `Tensor` comes
//! in, a `Tensor` of the same shape goes out. On Flex with f32 values each runs as one loop
//! that LLVM vectorises, writing a fresh aligned buffer; under autodiff its backward is one
//! more such loop over the saved output (tanh: grad·(1 − y²); LeakyReLU: grad·(y > 0 ? 1 :
//! slope), which needs a slope ≥ 0). On any other backend or dtype the same functions compose
//! burn's own operations, exactly as the model did before these kernels.
//!
//! tanh is computed without libm and without branches: |x| below atanh(½) by an odd
//! polynomial (a least-squares fit), above it as 1 − 2/(e^{2|x|} + 1) with e^{2|x|} from a
//! Cody–Waite range reduction and a degree-7 polynomial, the sign copied back last. Both
//! halves are plain f32 multiplies, adds and one division (no fused multiply-add), so the
//! result is the same bits whatever vector width the loop runs at. Its error is under 2 ulps
//! of f64 tanh (1.50 at most over every 13th f32 below 20; exactly ±1 from 9.02 on, ±0 and
//! NaN kept).

use burn::backend::autodiff::checkpoint::base::Checkpointer;
use burn::backend::autodiff::checkpoint::strategy::CheckpointStrategy;
use burn::backend::autodiff::grads::Gradients;
use burn::backend::autodiff::ops::{Backward, Ops, OpsKind};
use burn::backend::flex::{FlexTensor, Layout};
use burn::backend::tensor::FloatTensor;
use burn::backend::{Autodiff, Backend, Dispatch, Flex, backend_extension};
use burn::tensor::activation::{relu, sigmoid};
use burn::tensor::{Bytes, DType, Device, Tensor};

/// tanh, elementwise: one fused pass on Flex, `2σ(2x) − 1` elsewhere.
pub fn tanh<const D: usize>(x: Tensor<D>) -> Tensor<D> {
    if fused(&x) {
        Tensor::from_dispatch(<Dispatch as ActivationBackend>::tanh(x.into_dispatch()))
    } else {
        composed_tanh(x)
    }
}

/// LeakyReLU, elementwise: `x` where `x > 0`, `slope·x` elsewhere; one fused pass on Flex,
/// `(1 − slope)·relu(x) + slope·x` elsewhere. `slope` must be ≥ 0 (the spec checks it): the
/// backward reads the sign of `x` from the output.
pub fn leaky_relu<const D: usize>(x: Tensor<D>, slope: f64) -> Tensor<D> {
    assert!(slope >= 0.0, "leaky_relu: slope {slope} is negative");
    if fused(&x) {
        Tensor::from_dispatch(<Dispatch as ActivationBackend>::leaky_relu(
            x.into_dispatch(),
            slope,
        ))
    } else {
        composed_leaky_relu(x, slope)
    }
}

/// Whether `x` takes the fused kernels: f32 values on Flex, with or without autodiff.
fn fused<const D: usize>(x: &Tensor<D>) -> bool {
    x.dtype() == DType::F32 && x.device().inner() == Device::flex()
}

/// tanh as `2σ(2x) − 1`: on burn's CPU backends this trains faster than their own tanh
/// (libm's `tanhf`, computed again in backward).
fn composed_tanh<const D: usize>(x: Tensor<D>) -> Tensor<D> {
    sigmoid(x * 2.0) * 2.0 - 1.0
}

/// LeakyReLU as `(1 − slope)·relu(x) + slope·x`: burn's fused relu instead of a mask.
fn composed_leaky_relu<const D: usize>(x: Tensor<D>, slope: f64) -> Tensor<D> {
    relu(x.clone()) * (1.0 - slope) + x * slope
}

/// The activations as backend operations. Implemented for Flex (the forward kernels) and for
/// `Autodiff<Flex>` (forward kernels plus hand-written backward); the `Tensor` functions above
/// route every other backend to composed operations, so nothing else implements it.
#[backend_extension(Autodiff, Flex)]
pub trait ActivationBackend: Backend {
    /// tanh of each element.
    fn tanh(x: FloatTensor<Self>) -> FloatTensor<Self>;
    /// `x` where `x > 0`, `slope·x` elsewhere (`slope` ≥ 0).
    fn leaky_relu(x: FloatTensor<Self>, slope: f64) -> FloatTensor<Self>;
}

impl ActivationBackend for Flex {
    fn tanh(x: FlexTensor) -> FlexTensor {
        unary(&x, tanh_f32)
    }

    fn leaky_relu(x: FlexTensor, slope: f64) -> FlexTensor {
        let slope = slope as f32;
        unary(&x, move |v| leaky_relu_f32(v, slope))
    }
}

impl<C: CheckpointStrategy> ActivationBackend for Autodiff<Flex, C> {
    fn tanh(x: FloatTensor<Self>) -> FloatTensor<Self> {
        /// Saves the output y; the input's gradient is grad·(1 − y²).
        #[derive(Debug)]
        struct TanhBackward;

        impl Backward<Flex, 1> for TanhBackward {
            type State = FlexTensor;

            fn backward(
                self,
                ops: Ops<Self::State, 1>,
                grads: &mut Gradients,
                _checkpointer: &mut Checkpointer,
            ) {
                let [parent] = ops.parents;
                let grad = grads.consume::<Flex>(&ops.node);
                if let Some(parent) = parent {
                    let input_grad = binary(&ops.state, &grad, |y, g| g * (1.0 - y * y));
                    grads.register::<Flex>(parent.id, input_grad);
                }
            }
        }

        match TanhBackward
            .prepare::<C>([x.node()])
            .compute_bound()
            .stateful()
        {
            OpsKind::Tracked(prep) => {
                let output = unary(x.primitive(), tanh_f32);
                prep.finish(output.clone(), output)
            }
            OpsKind::UnTracked(prep) => prep.finish(unary(x.primitive(), tanh_f32)),
        }
    }

    fn leaky_relu(x: FloatTensor<Self>, slope: f64) -> FloatTensor<Self> {
        /// Saves the output y, whose sign is the input's (slope ≥ 0); the input's gradient is
        /// grad where y > 0 (or NaN, as burn's relu keeps it) and slope·grad elsewhere. The
        /// output is what the next layer saves anyway, so no extra tensor is kept alive.
        #[derive(Debug)]
        struct LeakyReluBackward {
            slope: f32,
        }

        impl Backward<Flex, 1> for LeakyReluBackward {
            type State = FlexTensor;

            fn backward(
                self,
                ops: Ops<Self::State, 1>,
                grads: &mut Gradients,
                _checkpointer: &mut Checkpointer,
            ) {
                let [parent] = ops.parents;
                let grad = grads.consume::<Flex>(&ops.node);
                if let Some(parent) = parent {
                    let slope = self.slope;
                    let input_grad =
                        binary(
                            &ops.state,
                            &grad,
                            move |y, g| if y <= 0.0 { g * slope } else { g },
                        );
                    grads.register::<Flex>(parent.id, input_grad);
                }
            }
        }

        let slope = slope as f32;
        let forward = move |v| leaky_relu_f32(v, slope);
        let step = LeakyReluBackward { slope };
        match step.prepare::<C>([x.node()]).compute_bound().stateful() {
            OpsKind::Tracked(prep) => {
                let output = unary(x.primitive(), forward);
                prep.finish(output.clone(), output)
            }
            OpsKind::UnTracked(prep) => prep.finish(unary(x.primitive(), forward)),
        }
    }
}

/// LeakyReLU of one value; NaN stays NaN and −0 stays −0.
#[inline(always)]
pub(super) fn leaky_relu_f32(x: f32, slope: f32) -> f32 {
    if x <= 0.0 { x * slope } else { x }
}

/// atanh(½): below it the polynomial, above it the exponential form (whose result is then ≥ ½,
/// so the subtraction 1 − q loses nothing).
const TANH_POLYNOMIAL_LIMIT: f32 = 0.549_306_15;
/// Beyond this |x|, tanh(x) rounds to ±1 in f32 (from about 9.01 on); clamping here keeps
/// e^{2|x|} finite.
const TANH_SATURATION: f32 = 9.1;
/// tanh(a) = a + a³·P(a²) on [0, atanh(½)]: a weighted least-squares fit on Chebyshev nodes
/// for relative error, 0.76 ulp at most evaluated in f32.
const TANH_ODD: [f32; 5] = [
    -0.333_333_16,
    0.133_325_71,
    -0.053_851_098,
    0.021_067_651,
    -0.006_269_626_8,
];
/// 1.5·2²³: adding it rounds a float in ±2²² to an integer, which its low mantissa bits hold.
const ROUNDING_SHIFT: f32 = 12_582_912.0;
/// ln 2 split so that n·LN2_HIGH is exact for the n here (|n| < 2⁹).
const LN2_HIGH: f32 = 0.693_359_4;
const LN2_LOW: f32 = -2.121_944_4e-4;
/// e^r ≈ 1 + r + r²·Q(r) on |r| ≤ ln2/2 (Cephes' `expf` coefficients).
const EXP_TAIL: [f32; 6] = [
    5.000_000_1e-1,
    1.666_666_5e-1,
    4.166_579_6e-2,
    8.333_452e-3,
    1.398_2e-3,
    1.987_569_1e-4,
];

/// tanh of one f32, branch-free so that a loop over it vectorises. Keeps ±0, sends ±∞ to ±1
/// and NaN to NaN.
#[inline(always)]
pub(super) fn tanh_f32(x: f32) -> f32 {
    let a = f32::from_bits(x.to_bits() & 0x7fff_ffff);

    // Small |x|: the odd polynomial (exact for subnormals, where a² underflows to 0).
    let s = a * a;
    let mut p = TANH_ODD[4];
    p = p * s + TANH_ODD[3];
    p = p * s + TANH_ODD[2];
    p = p * s + TANH_ODD[1];
    p = p * s + TANH_ODD[0];
    let small = a + a * (s * p);

    // Large |x|: 1 − 2/(e^z + 1) with z = 2|x| = n·ln2 + r. NaN compares false and flows
    // through r into the result.
    let z = 2.0
        * if a > TANH_SATURATION {
            TANH_SATURATION
        } else {
            a
        };
    let shifted = z * core::f32::consts::LOG2_E + ROUNDING_SHIFT;
    let n = shifted - ROUNDING_SHIFT;
    let r = (z - n * LN2_HIGH) - n * LN2_LOW;
    let mut q = EXP_TAIL[5];
    q = q * r + EXP_TAIL[4];
    q = q * r + EXP_TAIL[3];
    q = q * r + EXP_TAIL[2];
    q = q * r + EXP_TAIL[1];
    q = q * r + EXP_TAIL[0];
    let exp_r = 1.0 + r + r * r * q;
    // 2ⁿ from n's bits: 0 ≤ n ≤ 27 here, so the exponent field n + 127 is in range.
    let exponent = shifted
        .to_bits()
        .wrapping_sub(ROUNDING_SHIFT.to_bits())
        .wrapping_add(127)
        << 23;
    let exp_z = exp_r * f32::from_bits(exponent);
    let large = 1.0 - 2.0 / (exp_z + 1.0);

    let magnitude = if a < TANH_POLYNOMIAL_LIMIT {
        small
    } else {
        large
    };
    f32::from_bits(magnitude.to_bits() | (x.to_bits() & 0x8000_0000))
}

/// Applies `f` to every element of an f32 Flex tensor, into a fresh contiguous tensor whose
/// buffer is a `Vec<f32>` (aligned, so burn never copies it to realign).
fn unary(x: &FlexTensor, f: impl Fn(f32) -> f32 + Copy) -> FlexTensor {
    let shape = x.layout().shape().clone();
    let output = with_values(x, |values| map_unary(values, f));
    FlexTensor::new(
        Bytes::from_elems(output),
        Layout::contiguous(shape),
        DType::F32,
    )
}

/// Applies `f` to every pair of elements of two f32 Flex tensors of one shape, into a fresh
/// contiguous tensor of that shape.
fn binary(x: &FlexTensor, y: &FlexTensor, f: impl Fn(f32, f32) -> f32 + Copy) -> FlexTensor {
    let shape = x.layout().shape().clone();
    assert_eq!(
        &shape,
        y.layout().shape(),
        "fused activation: shapes differ"
    );
    let output = with_values(x, |left| with_values(y, |right| map_binary(left, right, f)));
    FlexTensor::new(
        Bytes::from_elems(output),
        Layout::contiguous(shape),
        DType::F32,
    )
}

/// Calls `f` with the tensor's f32 values in row-major order: its storage where that is one
/// contiguous run, a contiguous copy otherwise.
fn with_values<R>(x: &FlexTensor, f: impl FnOnce(&[f32]) -> R) -> R {
    assert_eq!(x.dtype(), DType::F32, "fused activation: f32 only");
    match x.as_slice::<f32>() {
        Some(values) => f(values),
        None => {
            let copy = x.to_contiguous();
            f(copy
                .as_slice::<f32>()
                .expect("a contiguous copy is one run"))
        }
    }
}

per_instruction_set! {
    /// `f` over each element, into a fresh `Vec`, at the CPU's widest vectors
    /// (`per_instruction_set!`).
    fn map_unary<F: [Fn(f32) -> f32]>(x: &[f32], f: F) -> Vec<f32> {
        // A plain loop rather than `collect`, whose out-of-line `from_iter` would run
        // outside the instruction-set copies below.
        let mut output = Vec::with_capacity(x.len());
        for (slot, &v) in output.spare_capacity_mut().iter_mut().zip(x) {
            slot.write(f(v));
        }
        // SAFETY: the loop has just written all x.len() elements.
        unsafe { output.set_len(x.len()) };
        output
    }
}

per_instruction_set! {
    /// `f` over each pair of elements of two slices of one length, into a fresh `Vec`; compiled
    /// for each instruction set like [`map_unary`].
    fn map_binary<F: [Fn(f32, f32) -> f32]>(x: &[f32], y: &[f32], f: F) -> Vec<f32> {
        assert_eq!(x.len(), y.len(), "fused activation: lengths differ");
        let mut output = Vec::with_capacity(x.len());
        for ((slot, &u), &v) in output.spare_capacity_mut().iter_mut().zip(x).zip(y) {
            slot.write(f(u, v));
        }
        // SAFETY: the loop has just written all x.len() (= y.len()) elements.
        unsafe { output.set_len(x.len()) };
        output
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The distance from `value` to `reference` in units of the f32 spacing at `reference`.
    fn ulps(value: f32, reference: f64) -> f64 {
        let magnitude = reference.abs();
        let spacing = if magnitude < f64::from(f32::MIN_POSITIVE) {
            2f64.powi(-149)
        } else {
            2f64.powi(magnitude.log2().floor() as i32 - 23)
        };
        (f64::from(value) - reference).abs() / spacing
    }

    #[test]
    fn tanh_is_within_two_ulps_of_f64_tanh_below_twenty() {
        // Every 13th f32 bit pattern from +0 to 20 (subnormals included): 0.09 × 10⁹ values.
        let mut worst = (0.0f64, 0.0f32);
        let mut bits = 0u32;
        while bits <= 20f32.to_bits() {
            let x = f32::from_bits(bits);
            let error = ulps(tanh_f32(x), f64::from(x).tanh());
            if error > worst.0 {
                worst = (error, x);
            }
            // tanh is odd, to the bit.
            assert_eq!(tanh_f32(-x).to_bits(), (-tanh_f32(x)).to_bits(), "x = {x}");
            bits += 13;
        }
        eprintln!("tanh: {} ulps at most, at x = {}", worst.0, worst.1);
        assert!(worst.0 < 2.0, "{} ulps at x = {}", worst.0, worst.1);
        // Measured: 1.50 ulps at most (x = 0.5521, just above the switch to the exponential
        // form); a lost Cody–Waite term or a wrong coefficient gives many.
        assert!(
            worst.0 > 0.5,
            "a correctly rounded result everywhere is implausible"
        );
    }

    #[test]
    fn tanh_keeps_zeros_saturates_and_propagates_nan() {
        assert_eq!(tanh_f32(0.0).to_bits(), 0.0f32.to_bits());
        assert_eq!(tanh_f32(-0.0).to_bits(), (-0.0f32).to_bits());
        let tiny = f32::from_bits(1);
        assert_eq!(tanh_f32(tiny), tiny);
        assert_eq!(tanh_f32(-tiny), -tiny);
        for x in [
            9.02f32,
            9.1,
            10.0,
            20.0,
            88.8,
            1e30,
            f32::MAX,
            f32::INFINITY,
        ] {
            assert_eq!(tanh_f32(x), 1.0, "tanh({x})");
            assert_eq!(tanh_f32(-x), -1.0, "tanh(-{x})");
        }
        // Just below saturation, the largest f32 below 1.
        assert_eq!(tanh_f32(8.9), 1.0 - f32::EPSILON / 2.0);
        assert!(tanh_f32(f32::NAN).is_nan());
        assert!(tanh_f32(-f32::NAN).is_nan());
    }

    #[test]
    fn every_instruction_set_gives_the_same_bits() {
        // 1000 values so that the vector loops and their scalar tails both run.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let values: Vec<f32> = (0..1003).map(|_| rng.random_range(-12.0..12.0)).collect();
        let vectorised = map_unary(&values, tanh_f32);
        for (x, y) in values.iter().zip(&vectorised) {
            assert_eq!(tanh_f32(*x).to_bits(), y.to_bits(), "tanh({x})");
        }
    }

    /// A tensor of the given shape, values normal-ish with scale `scale`.
    fn random<const D: usize>(
        shape: [usize; D],
        scale: f32,
        rng: &mut ChaCha8Rng,
        device: &Device,
    ) -> Tensor<D> {
        let count = shape.iter().product();
        let values: Vec<f32> = (0..count)
            .map(|_| (0..4).map(|_| rng.random_range(-scale..scale)).sum::<f32>())
            .collect();
        Tensor::from_data(burn::tensor::TensorData::new(values, shape), device)
    }

    fn values<const D: usize>(x: Tensor<D>) -> Vec<f32> {
        x.into_data().try_to_vec::<f32>().unwrap()
    }

    fn random_shape(rng: &mut ChaCha8Rng) -> [usize; 3] {
        [
            rng.random_range(1..6),
            rng.random_range(1..40),
            rng.random_range(1..40),
        ]
    }

    /// The fused function's forward and input gradient against the composed one's, under
    /// loss = Σ w·f(x) with random w, on Flex with autodiff, over 20 random shapes. Returns
    /// the largest forward difference divided by (|reference| + `floor`) and the largest
    /// gradient difference divided by |w| (the gradient is w·f′(x), with |f′| ≤ 1).
    fn compare(
        fused: impl Fn(Tensor<3>) -> Tensor<3>,
        composed: impl Fn(Tensor<3>) -> Tensor<3>,
        floor: f32,
        seed: u64,
    ) -> (f32, f32) {
        let device = Device::flex().autodiff();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (mut forward, mut backward) = (0.0f32, 0.0f32);
        for _ in 0..20 {
            let shape = random_shape(&mut rng);
            let x = random(shape, 1.5, &mut rng, &device);
            let weights = random(shape, 1.0, &mut rng, &device);
            let mut outputs = Vec::new();
            let mut gradients = Vec::new();
            for f in [&fused as &dyn Fn(Tensor<3>) -> Tensor<3>, &composed] {
                let input = x.clone().detach().require_grad();
                let output = f(input.clone());
                let grads = (output.clone() * weights.clone()).sum().backward();
                outputs.push(values(output));
                gradients.push(values(input.grad(&grads).unwrap()));
            }
            let scales: Vec<f32> = outputs[1].iter().map(|v| v.abs() + floor).collect();
            let largest = |got: &[f32], want: &[f32], scales: &[f32]| {
                (0..got.len())
                    .map(|i| (got[i] - want[i]).abs() / scales[i])
                    .fold(0.0f32, f32::max)
            };
            forward = forward.max(largest(&outputs[0], &outputs[1], &scales));
            let weights: Vec<f32> = values(weights).iter().map(|w| w.abs()).collect();
            backward = backward.max(largest(&gradients[0], &gradients[1], &weights));
        }
        (forward, backward)
    }

    #[test]
    fn tanh_and_its_gradient_match_burns_composed_tanh() {
        // The forward relative to |reference| + 1: the composed 2σ(2x) − 1 rounds at the scale
        // of 1, so it loses its relative accuracy near 0. The derivatives 1 − y² and 4σ(1 − σ)
        // are each a few f32 roundings of 1 from the true one.
        let (forward, backward) = compare(tanh, composed_tanh, 1.0, 11);
        eprintln!("tanh: forward {forward:e}, gradient {backward:e}");
        assert!(forward <= 4.0 * f32::EPSILON, "forward: {forward}");
        assert!(backward <= 4.0 * f32::EPSILON, "gradient: {backward}");
    }

    #[test]
    fn leaky_relu_and_its_gradient_match_burns_composed_leaky_relu() {
        for (seed, slope) in [(5, 0.05), (6, 0.0), (7, 0.3)] {
            let (forward, backward) = compare(
                |x| leaky_relu(x, slope),
                |x| composed_leaky_relu(x, slope),
                0.0,
                seed,
            );
            // x·(1 − s) + x·s is x within two roundings; so is (1 − s)·g + s·g.
            assert!(
                forward <= 2.0 * f32::EPSILON,
                "slope {slope}: forward {forward}"
            );
            assert!(
                backward <= 2.0 * f32::EPSILON,
                "slope {slope}: gradient {backward}"
            );
        }
    }

    #[test]
    fn fused_kernels_read_non_contiguous_inputs() {
        let device = Device::flex();
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let x = random([7, 5], 2.0, &mut rng, &device);
        let transposed = x.clone().transpose();
        let from_copy = values(tanh(Tensor::<2>::from_data(
            transposed.clone().into_data(),
            &device,
        )));
        assert_eq!(values(tanh(transposed.clone())), from_copy);
        let leaky = values(leaky_relu(transposed.clone(), 0.1));
        let want: Vec<f32> = values(transposed)
            .iter()
            .map(|&v| if v > 0.0 { v } else { 0.1 * v })
            .collect();
        assert_eq!(leaky, want);
    }

    #[test]
    fn other_backends_compose_burns_operations_unchanged() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        #[allow(deprecated)]
        let ndarray = Device::ndarray();
        for device in [ndarray.clone(), ndarray.autodiff()] {
            let x = random([6, 9], 3.0, &mut rng, &device);
            assert_eq!(values(tanh(x.clone())), values(composed_tanh(x.clone())));
            assert_eq!(
                values(leaky_relu(x.clone(), 0.05)),
                values(composed_leaky_relu(x, 0.05))
            );
        }
    }
}
