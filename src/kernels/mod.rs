//! DCNet on burn's Flex backend as one operation of its own ([`network`]): both heads and
//! the four Linear layers, forward and a backward written by hand, over fixed slices of
//! the batch that run on the model's cores. In: the network's parameters and windows.
//! Out: its terms, and every parameter's gradient; the same values as the network
//! composed of burn's operations (`model`'s tests compare the two). The paper's loss on
//! those terms is one operation too ([`loss`]).
//!
//! - [`network`]: the operation, its slices, buffers and dropout;
//! - [`loss`]: the paper's closed-loop loss as one operation, forward and backward;
//! - [`activation`]: tanh and LeakyReLU on one value, tanh without libm;
//! - [`unfold`]: the convolutions' taps side by side as burn's `select`, for the composed
//!   network.

/// A loop function compiled three times, for baseline x86-64 (SSE2, 4 lanes), AVX2 (8) and
/// AVX-512 (16), the widest the CPU has chosen at run time. The crate targets baseline
/// x86-64, so without this LLVM would vectorise the loop at 4 lanes only. Write the
/// function as usual with its closure parameter `F`'s bound in brackets; its body becomes
/// an `#[inline(always)]` function that each copy inlines. No fused multiply-add is enabled
/// in any copy, so every copy computes the same bits.
macro_rules! per_instruction_set {
    (
        $(#[$meta:meta])*
        $vis:vis fn $name:ident<F: [$($bound:tt)*]>($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty $body:block
    ) => {
        $(#[$meta])*
        $vis fn $name<F: $($bound)* + Copy>($($arg: $ty),*) -> $ret {
            #[inline(always)]
            fn body<F: $($bound)*>($($arg: $ty),*) -> $ret $body
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx512f")]
                fn avx512<F: $($bound)*>($($arg: $ty),*) -> $ret {
                    body($($arg),*)
                }
                #[target_feature(enable = "avx2")]
                fn avx2<F: $($bound)*>($($arg: $ty),*) -> $ret {
                    body($($arg),*)
                }
                if std::arch::is_x86_feature_detected!("avx512f") {
                    // SAFETY: the CPU has just been found to support AVX-512F.
                    return unsafe { avx512($($arg),*) };
                }
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: the CPU has just been found to support AVX2.
                    return unsafe { avx2($($arg),*) };
                }
            }
            body($($arg),*)
        }
    };
}
pub(crate) use per_instruction_set;

/// The widest vector instructions the matrix products (the `gemm` crate, with its AVX-512
/// micro-kernels enabled) use on this machine. Their blocking over the inner dimension
/// follows the vector width, so products, and the models trained with them, differ in
/// their last bits between machines that differ here; on one machine they are the same
/// bytes at any thread count.
pub fn instruction_set() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            return "x86-64 AVX-512";
        }
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            return "x86-64 AVX2+FMA";
        }
        return "x86-64 baseline";
    }
    #[allow(unreachable_code)]
    std::env::consts::ARCH
}

pub mod activation;
pub mod loss;
pub mod network;
pub mod unfold;

use burn::backend::flex::{FlexTensor, Layout};
use burn::backend::{Flex, TensorMetadata};
use burn::tensor::{Bytes, DType, Device, Shape, Tensor};

/// The values of a contiguous f32 tensor.
fn values(x: &FlexTensor) -> &[f32] {
    x.as_slice::<f32>()
        .expect("kernels: contiguous f32 tensors")
}

/// A contiguous f32 tensor owning `values`.
pub(crate) fn f32_tensor(values: Vec<f32>, shape: Shape) -> FlexTensor {
    FlexTensor::new(
        Bytes::from_elems(values),
        Layout::contiguous(shape),
        DType::F32,
    )
}

/// A tensor that a kernel writes anew at each step and hands to burn, on one buffer kept
/// from step to step: its values are written in place once burn has dropped the last
/// step's tensor (the usual case), and on a fresh buffer while it still holds it.
#[derive(Debug, Default)]
pub(crate) struct Reused(Option<FlexTensor>);

impl Reused {
    /// The values of a tensor of `shape`, for the caller to overwrite, every one.
    pub(crate) fn values_mut(&mut self, shape: Shape) -> &mut [f32] {
        let reusable = self.0.as_mut().is_some_and(|tensor| {
            tensor.shape() == shape && tensor.try_storage_mut::<f32>().is_some()
        });
        if !reusable {
            self.0 = Some(f32_tensor(vec![0.0; shape.num_elements()], shape));
        }
        let tensor = self.0.as_mut().expect("a tensor was just made");
        tensor
            .try_storage_mut::<f32>()
            .expect("a tensor held here alone")
    }

    /// The tensor of the values last written, sharing their buffer.
    pub(crate) fn tensor(&self) -> FlexTensor {
        self.0.clone().expect("values written first")
    }

    /// [`Reused::tensor`] on `device`: on Flex (with or without autodiff) sharing the
    /// buffer, elsewhere a copy.
    pub(crate) fn tensor_on<const D: usize>(&self, device: &Device) -> Tensor<D> {
        let tensor = self.tensor();
        let inner = device.clone().inner();
        if inner != Device::flex() {
            return Tensor::from_data(tensor.into_data(), device);
        }
        let tensor = Tensor::from_primitive::<Flex>(tensor);
        if device.is_autodiff() {
            Tensor::from_inner(tensor)
        } else {
            tensor
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A buffer is written again in place once its last tensor is dropped, and never
    /// while a tensor still reads it: that one keeps its values.
    #[test]
    fn a_reused_buffer_is_rewritten_only_once_its_tensor_is_dropped() {
        let shape = || Shape::new([2, 3]);
        let mut reused = Reused::default();
        reused.values_mut(shape()).fill(1.0);
        let first = reused.tensor();
        let address = values(&first).as_ptr();
        drop(first);
        reused.values_mut(shape()).fill(2.0);
        let second = reused.tensor();
        assert_eq!(
            values(&second).as_ptr(),
            address,
            "the dropped buffer is reused"
        );
        reused.values_mut(shape()).fill(3.0);
        assert_eq!(values(&second), [2.0; 6], "a held tensor keeps its values");
        assert_ne!(values(&reused.tensor()).as_ptr(), address);
        assert_eq!(values(&reused.tensor()), [3.0; 6]);
        let other = reused.values_mut(Shape::new([4])).len();
        assert_eq!(other, 4, "another shape gets a buffer of its own size");
    }
}
