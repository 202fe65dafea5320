//! DCNet's hot operations as backend operations of their own, added to burn's Flex
//! backend through its backend extension, each with a backward written by hand. In:
//! tensors of the network's layers. Out: the same values that burn's own operations give
//! (each module's tests compare them, forward and gradient), in fewer and cheaper passes.
//! Backends without a kernel run burn's own operations instead.

pub mod unfold;
