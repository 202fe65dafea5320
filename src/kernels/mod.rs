//! DCNet's hot operations as backend operations of their own, added to burn's Flex
//! backend through its backend extension, each with a backward written by hand. In:
//! tensors of the network's layers. Out: the values burn's own operations give (each
//! module's tests compare them, forward and gradient), in fewer and cheaper passes.
//! Backends without a kernel run burn's own operations instead.
//!
//! - [`activation`]: tanh and LeakyReLU, one pass each;
//! - [`linear`]: a Linear layer with its activation and dropout mask, one product and one
//!   pass forward, one backward node for input, weight and bias;
//! - [`unfold`]: the convolutions' taps side by side, and their gradient gathered back
//!   without a scatter.

pub mod activation;
pub mod linear;
pub mod unfold;
