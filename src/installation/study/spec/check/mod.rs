//! The checks of an installation spec, one file a section, in the shape of the paper's
//! [`crate::spec::check`]. In: a section of the [`StudyFile`] as read from TOML,
//! destructured whole so that a new key cannot skip its check, and what earlier
//! sections gave (the count of trajectories, the models' names). Out: the section's
//! checked values, and every fault as its key path and message in the paper's
//! [`Faults`]. [`StudyFile`]'s check calls them in the order of the file:
//! [`recordings`], [`noise`], [`calibration`] (with [`kalman`], `[calibration.kalman]`),
//! [`dcnet`], [`learned`], [`observability`].
//!
//! This file holds what the sections share: the faults of a list of terms at its key.
//!
//! [`StudyFile`]: crate::installation::study::spec::StudyFile

pub mod recordings;
pub mod noise;
pub mod kalman;
pub mod calibration;
pub mod dcnet;
pub mod learned;
pub mod observability;

use crate::installation::terms::names::{TermName, term_list_faults};
use crate::spec::check::Faults;

/// Adds the faults of the list of terms at `key` (`learned.terms`): the list's own at
/// `key`, a term's at `key[j]`.
fn check_terms(key: &str, terms: &[TermName], faults: &mut Faults) {
    for (at, message) in term_list_faults(terms) {
        match at {
            Some(j) => faults.add(format!("{key}[{j}]"), message),
            None => faults.add(key, message),
        }
    }
}
