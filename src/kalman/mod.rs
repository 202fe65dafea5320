//! Recursive calibration: a Kalman filter whose state is the error terms, updated
//! sample by sample as the vehicle sails, with the standard deviation of every term at
//! every sample. [`filter`] holds the filter (extended where a term enters
//! nonlinearly) and the batch least squares it equals with no random walk;
//! [`scale_bias`] the paper's EM1 to EM5 and the beam model as its measurements. The
//! installation model's filter, whose time offset and misalignment enter nonlinearly,
//! is `installation::filter`. In: a prior and samples. Out: estimates with their
//! standard deviations against time.

pub mod filter;
pub mod scale_bias;

pub use filter::{Filter, Measurement, Prior, batch_least_squares};
pub use scale_bias::ScaleBiasModel;
