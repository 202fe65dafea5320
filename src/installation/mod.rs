//! The errors of a real DVL installation, calibrated against a reference with
//! attitude: the model `v_dvl(t) = (I + S) · R(δ) · [C_n^b(t+τ) · v_n(t+τ) + ω_b(t+τ) × l] + b`
//! with scale S, misalignment δ, lever arm l, time offset τ and bias b, each switched on
//! or off. By what a contributor adds, in data-flow order: [`frames`] puts the reference
//! in the body frame at any time (rotation, body rate); [`terms`] holds which terms are
//! estimated, their values and names, the model's prediction, the correction of a DVL
//! record and its score against the reference; [`dead_reckoning`] sums the corrected
//! velocity into a track and scores its drift against positions, [`fix_drift`] against
//! position fixes, over a blackout or a whole dive; [`estimate`] fits them, bounds them,
//! finds a dive's clock, fits several recordings jointly and runs the Kalman filter;
//! [`study`] is the installation study (`kind = "installation"`): its spec and the
//! held-out protocol that scores every method; [`learned`] the DCNets that learn an
//! installation (`[learned]`) from simulated installations over the real reference.
//! In: [`PairedRecording`](crate::data::paired::PairedRecording)s. Out: terms, their
//! bound, corrected records.

pub mod frames;
pub mod terms;
pub mod dead_reckoning;
pub mod fix_drift;
pub mod estimate;
pub mod study;
pub mod learned;
