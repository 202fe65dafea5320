//! The bias term b: added to every DVL sample, per axis in the DVL's axes, or one b
//! for all axes. Stored in m/s, shown in cm/s.

use crate::Vec3;
use crate::installation::terms::Linearisation;
use crate::installation::terms::kind::{KindOfTerm, ShownUnit, TermKind};

pub(super) const TERM: KindOfTerm = KindOfTerm {
    kind: TermKind::Bias,
    key: "bias",
    readable: "bias",
    one_name: Some("bias_m_s"),
    axis_names: Some(["bias_x_m_s", "bias_y_m_s", "bias_z_m_s"]),
    unit: ShownUnit::CentimetresPerSecond,
    values: |installation| installation.bias_m_s,
    set: |installation, values| installation.bias_m_s = values,
    column,
};

/// ∂v_dvl/∂b: one on its axis, or on every axis for one bias.
fn column(_: &Linearisation, axis: Option<usize>) -> Vec3 {
    match axis {
        None => [1.0; 3],
        Some(axis) => {
            let mut column = [0.0; 3];
            column[axis] = 1.0;
            column
        }
    }
}
