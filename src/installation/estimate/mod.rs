//! The terms estimated from a paired recording, in data-flow order: [`fit`] fits the
//! selected terms by nonlinear least squares, then under [`robust`]'s loss; [`residual_noise`] reads the noise its
//! residuals show; [`bound`] gives their standard deviations and the Fisher bound, and
//! the terms a recording cannot show; [`missing`] the terms left out that the residuals
//! still ask for; [`clock`] finds a dive's clock again with the rest carried; [`joint`]
//! fits several recordings at once, and [`between_dives`] reads from it how far the
//! vehicle's terms move between dives; [`fixes`] fits the terms to position fixes
//! through the dead reckoning (the problem in `fix_problem`, solved through `fix_solve`,
//! what it is asked and its refusals in `fix_terms`) under the noise [`fix_noise`]
//! whitens, for a vehicle with no velocity reference; [`filter`] estimates the terms sample by sample
//! (an extended Kalman filter) with the noise [`filter_noise`] reads as it runs; and
//! [`settling`] says how much of a recording the filter needed.
//! In: a [`Reference`](crate::installation::frames::Reference) and DVL samples. Out:
//! terms with their standard deviations.

pub mod fit;
pub mod robust;
pub mod residual_noise;
pub mod bound;
pub mod missing;
pub mod clock;
pub mod joint;
pub mod between_dives;
pub mod fix_noise;
pub mod fixes;
pub mod fix_joint;
mod fix_terms;
mod fix_problem;
mod fix_solve;
pub mod filter_noise;
pub mod filter;
pub mod settling;
