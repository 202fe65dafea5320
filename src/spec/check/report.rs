//! Checks `[report]`. In: the published values' file, the tolerance, the trajectories
//! of the velocity figure, and the trajectories `[data]` gave. Out: the [`ReportSpec`]
//! with the published values read and checked, their path made absolute in the
//! resolved spec.
//!
//! [`ReportSpec`]: crate::spec::ReportSpec

use super::{Defined, Faults};
use crate::spec::published::Published;
use crate::spec::{ReportSpec, SpecFile, file};
use std::path::Path;

/// Checks `[report]`: the published values read, a tolerance not negative, and none or
/// two defined trajectories to draw the velocity of; `resolved` gets the absolute path.
pub(in crate::spec) fn check_report(
    report: file::ReportFile,
    spec_dir: &Path,
    sources: &Defined,
    resolved: &mut SpecFile,
    faults: &mut Faults,
) -> ReportSpec {
    let file::ReportFile {
        published,
        tolerance_pct,
        velocity_trajectories,
    } = report;
    let published = published.and_then(|file| {
        let path = spec_dir.join(file);
        resolved.report.published = Some(path.clone());
        Published::read(&path)
            .map_err(|errors| faults.add("report.published", errors.to_string()))
            .ok()
    });
    if !(tolerance_pct.is_finite() && tolerance_pct >= 0.0) {
        faults.add(
            "report.tolerance_pct",
            format!("{tolerance_pct} must be zero or positive"),
        );
    }
    if !matches!(velocity_trajectories.len(), 0 | 2) {
        faults.add(
            "report.velocity_trajectories",
            format!(
                "has {} names: give two (a training and a test trajectory), or none",
                velocity_trajectories.len()
            ),
        );
    }
    for (i, wanted) in velocity_trajectories.iter().enumerate() {
        sources.lookup(
            &format!("report.velocity_trajectories[{i}]"),
            wanted,
            faults,
        );
    }
    ReportSpec {
        published,
        tolerance_pct,
        velocity_trajectories,
    }
}

#[cfg(test)]
mod tests {
    use crate::spec::fixture::quick_faults;

    #[test]
    fn the_velocity_figure_takes_two_trajectories_or_none() {
        let set = "report.velocity_trajectories=[\"S1\"]";
        assert_eq!(
            quick_faults(&[set]),
            format!(
                "--set {set}: report.velocity_trajectories: has 1 names: give two (a training and a test trajectory), or none"
            )
        );
        let set = "report.tolerance_pct=-1";
        assert_eq!(
            quick_faults(&[set]),
            format!("--set {set}: report.tolerance_pct: -1 must be zero or positive")
        );
    }
}
