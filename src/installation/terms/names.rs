//! The terms of the installation model as a spec and the command line name them
//! (`lever_arm`, `time_offset`, `bias`, …): the names, what is wrong with a list of them,
//! and the [`TermSet`] a list stands for. In: names as written. Out: a checked list and
//! its term set.

use crate::installation::terms::{PerAxis, TermSet};
use std::collections::HashSet;

/// One term of the installation model, as a spec names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TermName {
    /// One scale for all axes.
    Scale,
    ScalePerAxis,
    Misalignment,
    LeverArm,
    TimeOffset,
    /// One bias per axis.
    Bias,
    /// One bias for all axes.
    BiasScalar,
}

impl TermName {
    pub const ALL: [TermName; 7] = [
        TermName::Scale,
        TermName::ScalePerAxis,
        TermName::Misalignment,
        TermName::LeverArm,
        TermName::TimeOffset,
        TermName::Bias,
        TermName::BiasScalar,
    ];

    /// The term's name in a spec and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            TermName::Scale => "scale",
            TermName::ScalePerAxis => "scale_per_axis",
            TermName::Misalignment => "misalignment",
            TermName::LeverArm => "lever_arm",
            TermName::TimeOffset => "time_offset",
            TermName::Bias => "bias",
            TermName::BiasScalar => "bias_scalar",
        }
    }

    /// Whether the term may be a dive's, found again on each dive (the clock, and the
    /// bias), rather than the vehicle's, carried from one dive to the next.
    pub fn may_be_the_dives(self) -> bool {
        matches!(
            self,
            TermName::TimeOffset | TermName::Bias | TermName::BiasScalar
        )
    }
}

impl std::str::FromStr for TermName {
    type Err = String;

    fn from_str(name: &str) -> Result<Self, String> {
        TermName::ALL
            .into_iter()
            .find(|term| term.name() == name)
            .ok_or_else(|| {
                let names: Vec<&str> = TermName::ALL.iter().map(|term| term.name()).collect();
                format!("{name:?} is not a term: give {}", names.join(", "))
            })
    }
}

/// What is wrong with a list of terms, each with the index it is at (`None` for the
/// list): empty, a term listed twice, or a term with its per-axis form.
pub fn term_list_faults(terms: &[TermName]) -> Vec<(Option<usize>, String)> {
    let mut faults = Vec::new();
    if terms.is_empty() {
        faults.push((None, "is empty: name at least one term (scale, scale_per_axis, misalignment, lever_arm, time_offset, bias, bias_scalar)".to_string()));
    }
    let has = |term| terms.contains(&term);
    if has(TermName::Scale) && has(TermName::ScalePerAxis) {
        faults.push((None, "lists scale and scale_per_axis: give one".to_string()));
    }
    if has(TermName::Bias) && has(TermName::BiasScalar) {
        faults.push((None, "lists bias and bias_scalar: give one".to_string()));
    }
    let mut seen = HashSet::new();
    for (j, term) in terms.iter().enumerate() {
        if !seen.insert(term) {
            faults.push((Some(j), format!("{:?} is listed twice", term.name())));
        }
    }
    faults
}

/// The terms of a spec's term names.
pub fn term_set(terms: &[TermName]) -> TermSet {
    let has = |term| terms.contains(&term);
    let either = |one, per_axis| match (has(one), has(per_axis)) {
        (_, true) => PerAxis::PerAxis,
        (true, false) => PerAxis::Scalar,
        (false, false) => PerAxis::Off,
    };
    TermSet {
        scale: either(TermName::Scale, TermName::ScalePerAxis),
        misalignment: has(TermName::Misalignment),
        lever_arm: has(TermName::LeverArm),
        time_offset: has(TermName::TimeOffset),
        bias: either(TermName::BiasScalar, TermName::Bias),
    }
}
