//! The scale term S: the DVL reads (1 + s) times the true velocity, per axis in the
//! DVL's axes, or one s for all axes. Stored as a fraction, shown in %.

use crate::Vec3;
use crate::installation::terms::Linearisation;
use crate::installation::terms::kind::{KindOfTerm, ShownUnit, TermKind};

pub(super) const TERM: KindOfTerm = KindOfTerm {
    kind: TermKind::Scale,
    key: "scale",
    readable: "scale",
    one_name: Some("scale"),
    axis_names: Some(["scale_x", "scale_y", "scale_z"]),
    unit: ShownUnit::Percent,
    values: |installation| installation.scale,
    set: |installation, values| installation.scale = values,
    column,
};

/// ∂v_dvl/∂s: the rotated velocity, on its own axis for a scale per axis.
fn column(at: &Linearisation, axis: Option<usize>) -> Vec3 {
    match axis {
        None => at.rotated,
        Some(axis) => {
            let mut column = [0.0; 3];
            column[axis] = at.rotated[axis];
            column
        }
    }
}
