//! Fused operations on burn's `Flex` CPU backend, added through burn's backend extension:
//! each takes and returns `Tensor`s like burn's own operations, runs one pass over f32
//! storage on Flex (with a hand-written backward under autodiff), and falls back to burn's
//! composed operations on every other backend.

pub mod activation;
