//! The misalignment δ: roll, pitch, yaw of the DVL's axes from the body's, three values
//! in radians, shown in degrees; R(δ) = (Rz(δ_z) · Ry(δ_y) · Rx(δ_x))ᵀ takes a body-frame
//! vector into the DVL's axes (the same ZYX form as C_n^b).

use crate::Vec3;
use crate::installation::frames::{
    Mat3, apply, body_to_ned, multiply, rotation_x, rotation_y, rotation_z, transpose,
};
use crate::installation::terms::Linearisation;
use crate::installation::terms::kind::{KindOfTerm, ShownUnit, TermKind};

pub(super) const TERM: KindOfTerm = KindOfTerm {
    kind: TermKind::Misalignment,
    key: "misalignment",
    readable: "misalignment",
    one_name: None,
    axis_names: Some([
        "misalignment_x_rad",
        "misalignment_y_rad",
        "misalignment_z_rad",
    ]),
    unit: ShownUnit::Degrees,
    values: |installation| installation.misalignment_rad,
    set: |installation, values| installation.misalignment_rad = values,
    column,
};

/// R(δ) = (Rz(δ_z) · Ry(δ_y) · Rx(δ_x))ᵀ: body axes into the DVL's axes.
pub(super) fn misalignment_matrix(misalignment_rad: Vec3) -> Mat3 {
    transpose(&body_to_ned(misalignment_rad))
}

/// ∂v_dvl/∂δ_axis: ∂R(δ)/∂δ_axis applied to the DVL point's velocity, scaled.
fn column(at: &Linearisation, axis: Option<usize>) -> Vec3 {
    let axis = axis.expect("a misalignment is per axis");
    let derivative = misalignment_derivative(at.installation.misalignment_rad, axis);
    at.scaled(apply(&derivative, at.point))
}

/// ∂R(δ)/∂δ_axis.
fn misalignment_derivative(misalignment_rad: Vec3, axis: usize) -> Mat3 {
    let [x, y, z] = misalignment_rad;
    let derivative = |angle: f64, which: usize| -> Mat3 {
        let (s, c) = angle.sin_cos();
        match which {
            0 => [[0.0, 0.0, 0.0], [0.0, -s, -c], [0.0, c, -s]],
            1 => [[-s, 0.0, c], [0.0, 0.0, 0.0], [-c, 0.0, -s]],
            _ => [[-s, -c, 0.0], [c, -s, 0.0], [0.0, 0.0, 0.0]],
        }
    };
    let (mut rx, mut ry, mut rz) = (rotation_x(x), rotation_y(y), rotation_z(z));
    match axis {
        0 => rx = derivative(x, 0),
        1 => ry = derivative(y, 1),
        _ => rz = derivative(z, 2),
    }
    transpose(&multiply(&multiply(&rz, &ry), &rx))
}
