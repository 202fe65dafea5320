//! What a results folder holds, told from its files alone: nothing, a single run of the
//! paper's experiment, a sweep of them, an installation study, or a sweep of studies.
//! The one place that tells a folder's kind, for `plot`, `compare` and the owner
//! check. In: a folder. Out: [`Held`].

use super::{MANIFEST, SPEC, study::HELDOUT, sweep};
use std::path::Path;

/// What a results folder holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Held {
    Nothing,
    Single,
    Sweep,
    Study,
    StudySweep,
}

impl Held {
    pub fn of(folder: &Path) -> Held {
        if folder.join(HELDOUT).is_file() || is_study_spec(folder) {
            Held::Study
        } else if folder.join(sweep::INDEX).is_file() {
            match sweep::read_index(folder) {
                Ok(index) if index.kind == crate::installation::study::spec::KIND => {
                    Held::StudySweep
                }
                _ => Held::Sweep,
            }
        } else if folder.join(MANIFEST).is_file() {
            Held::Single
        } else {
            Held::Nothing
        }
    }

    /// Whether the folder holds an installation study or a sweep of them.
    pub fn is_study(self) -> bool {
        matches!(self, Held::Study | Held::StudySweep)
    }

    pub fn words(self) -> &'static str {
        match self {
            Held::Nothing => "nothing",
            Held::Single => "the results of a single run",
            Held::Sweep => "the points of a sweep",
            Held::Study => "the results of an installation study",
            Held::StudySweep => "the points of a sweep of installation studies",
        }
    }
}

/// Whether `folder`'s resolved spec is an installation study's (its `kind`), so that a
/// study whose tables are damaged or missing is still told as one.
fn is_study_spec(folder: &Path) -> bool {
    crate::spec::declared_kind(&folder.join(SPEC))
        .ok()
        .flatten()
        .is_some_and(|kind| kind == crate::installation::study::spec::KIND)
}
