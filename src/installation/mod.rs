//! The errors of a real DVL installation, calibrated against a reference with
//! attitude: the model `v_dvl(t) = (I + S) · R(δ) · [C_n^b(t+τ) · v_n(t+τ) + ω_b(t+τ) × l] + b`
//! with scale S, misalignment δ, lever arm l, time offset τ and bias b, each switched on
//! or off. In data-flow order: [`frames`] puts the reference in the body frame at any
//! time (rotation, body rate); [`terms`] holds which terms are estimated, their values,
//! the model's prediction, the correction of a DVL record and its score against the
//! reference; [`fit`] estimates the selected terms by nonlinear least squares
//! (Levenberg–Marquardt from a scan over τ, on a fixed interior mask); [`residual_noise`]
//! reads the noise its residuals show (level and correlation in time); [`bound`] gives
//! the terms' standard deviations, from that noise and from the specified one (the
//! Fisher bound), their correlations and the terms a segment cannot show; [`filter`] estimates them sample by sample (an extended Kalman filter)
//! with the bound of the samples so far; [`study`] scores every method held out (its
//! filters' passes in [`protocol_filters`]), and [`calibration_time`] finds how long each
//! needs; [`settling`] finds it for a single recording (`calibrate`). With `[learned]`
//! ([`learned_spec`]): [`simulate`] makes DVLs of simulated installations over the real
//! reference, [`network`] is the DCNet that outputs the terms and its loss, [`learned`]
//! gives each fold its training windows and reads the terms a trained model finds. The
//! spec's names of the terms are [`term_names`]; `[calibration.kalman]`, the filter's
//! settings, is [`filter_spec`].
//! In: [`PairedRecording`](crate::data::paired::PairedRecording)s. Out: terms, their
//! bound, corrected records.

pub mod term_names;
pub mod learned_spec;
pub mod filter_spec;
pub mod spec;
pub mod frames;
pub mod terms;
pub mod fit;
pub mod residual_noise;
pub mod bound;
pub mod missing;
pub mod clock;
pub mod joint;
pub mod filter_noise;
pub mod filter;
pub mod rows;
pub mod protocol;
pub mod protocol_filters;
pub mod calibration_time;
pub mod settling;
pub mod simulate;
pub mod network;
pub mod learned;
