//! How the study's learned methods estimate, handed in by the pipeline that holds their
//! networks: the paper's DCNet (a scale and a bias from a DVL window and the reference's
//! body velocity) and `[learned]`'s models (the terms from samples of a calibration
//! recording). In: the pipeline's closures. Out: [`Estimators`].

use crate::Vec3;
use crate::installation::learned::spec::TrainingSource;
use crate::installation::study::recording::Recording;
use crate::installation::terms::Installation;
use crate::vocab::{Correction, ErrorModel};
use std::ops::Range;

/// How DCNet estimates a scale and a bias from a DVL window and the reference's body
/// velocity on its stamps, for an error model; `None` where it cannot (no model, or a
/// window shorter than the network's).
pub type DcnetEstimate<'a> = dyn Fn(ErrorModel, &[Vec3], &[Vec3]) -> Option<Correction> + Sync + 'a;

/// Which of `[learned]`'s models: what it trained on, which replicate, which fold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LearnedModel {
    pub source: TrainingSource,
    pub replicate: usize,
    pub fold: usize,
}

/// How one of `[learned]`'s models estimates the terms from samples of a calibration
/// recording; `None` where it cannot.
pub type LearnedEstimate<'a> =
    dyn Fn(LearnedModel, &Recording, Range<usize>) -> Option<Installation> + Sync + 'a;

/// The learned methods' estimators.
pub struct Estimators<'a> {
    pub dcnet: &'a DcnetEstimate<'a>,
    pub learned: &'a LearnedEstimate<'a>,
}
