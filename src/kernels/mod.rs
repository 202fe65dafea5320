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
        fn $name:ident<F: [$($bound:tt)*]>($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty $body:block
    ) => {
        $(#[$meta])*
        fn $name<F: $($bound)* + Copy>($($arg: $ty),*) -> $ret {
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
use burn::tensor::{Bytes, DType, Shape};

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
