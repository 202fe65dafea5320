//! The time offset τ: the DVL sample stamped t measured the motion of the reference at
//! t + τ. One value, in seconds.

use crate::Vec3;
use crate::installation::frames::{apply, cross};
use crate::installation::terms::Linearisation;
use crate::installation::terms::kind::{KindOfTerm, ShownUnit, TermKind};

pub(super) const TERM: KindOfTerm = KindOfTerm {
    kind: TermKind::TimeOffset,
    key: "time_offset",
    readable: "time offset",
    one_name: Some("time_offset_s"),
    axis_names: None,
    unit: ShownUnit::Seconds,
    values: |installation| [installation.time_offset_s, 0.0, 0.0],
    set: |installation, values| installation.time_offset_s = values[0],
    column,
};

/// ∂v_dvl/∂τ: the DVL point's velocity's rate of change (the reference's slope, with the
/// lever arm's turning), through the misalignment and the scale.
fn column(at: &Linearisation, _: Option<usize>) -> Vec3 {
    let turning = cross(at.slope.rate_rad_s, at.installation.lever_arm_m);
    let change = [0, 1, 2].map(|k| at.slope.velocity_body_m_s[k] + turning[k]);
    at.scaled(apply(&at.rotation, change))
}
