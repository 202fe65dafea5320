//! The figures of a sweep of installation studies, drawn from its table alone (each
//! point's own figures are drawn from the point's folder). In: a stored sweep of
//! studies. Out: the figure files written.

use crate::report::plots::figures::installation_sweep::installation_sweep;
use crate::report::plots::{Format, PlotError, Written, render, write_figures};
use crate::results::study_sweep::StoredStudySweep;
use std::path::Path;

/// Draws `installation_sweep` into `folder`.
pub fn draw(
    stored: &StoredStudySweep,
    folder: &Path,
    format: Format,
) -> Result<Vec<Written>, PlotError> {
    render::register_font();
    let drawn = installation_sweep(stored)
        .map(|outcome| vec![("installation_sweep".to_string(), outcome)])
        .map_err(|source| PlotError::Draw {
            what: "sweep of installation studies'",
            source,
        })?;
    write_figures(drawn, folder, format)
}
