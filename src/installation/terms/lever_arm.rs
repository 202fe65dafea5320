//! The lever arm l: the DVL's position from the reference point, body frame (x
//! forward, y starboard, z down), three values in metres; the DVL moves at v_b + ω_b × l.

use crate::Vec3;
use crate::installation::frames::{apply, cross};
use crate::installation::terms::Linearisation;
use crate::installation::terms::kind::{KindOfTerm, ShownUnit, TermKind};

pub(super) const TERM: KindOfTerm = KindOfTerm {
    kind: TermKind::LeverArm,
    key: "lever_arm",
    readable: "lever arm",
    one_name: None,
    axis_names: Some(["lever_arm_x_m", "lever_arm_y_m", "lever_arm_z_m"]),
    unit: ShownUnit::Metres,
    values: |installation| installation.lever_arm_m,
    set: |installation, values| installation.lever_arm_m = values,
    column,
};

/// ∂v_dvl/∂l_axis: ω_b × the axis's unit vector, through the misalignment and the scale.
fn column(at: &Linearisation, axis: Option<usize>) -> Vec3 {
    let axis = axis.expect("a lever arm is per axis");
    let mut unit = [0.0; 3];
    unit[axis] = 1.0;
    at.scaled(apply(&at.rotation, cross(at.at.rate_rad_s, unit)))
}
