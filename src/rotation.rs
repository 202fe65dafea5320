//! Rotations in three dimensions, beneath every stage: a 3×3 matrix, the rotations
//! about each axis, the body-to-NED rotation of an attitude (aerospace ZYX: yaw, then
//! pitch, then roll), and the products a recording's frames are turned with. Both a
//! recording's reader (a ROS 2 bag's frames) and the installation's model use them.
//! In: angles, matrices and vectors. Out: their products.

use crate::Vec3;

/// A 3×3 matrix, row by row.
pub type Mat3 = [[f64; 3]; 3];

/// Rx(φ): a right-handed rotation by `angle_rad` about x, `[[1,0,0],[0,c,−s],[0,s,c]]`.
pub fn rotation_x(angle_rad: f64) -> Mat3 {
    let (s, c) = angle_rad.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

/// Ry(θ): a right-handed rotation by `angle_rad` about y, `[[c,0,s],[0,1,0],[−s,0,c]]`.
pub fn rotation_y(angle_rad: f64) -> Mat3 {
    let (s, c) = angle_rad.sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

/// Rz(ψ): a right-handed rotation by `angle_rad` about z, `[[c,−s,0],[s,c,0],[0,0,1]]`.
pub fn rotation_z(angle_rad: f64) -> Mat3 {
    let (s, c) = angle_rad.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

/// C_b^n = Rz(ψ) · Ry(θ) · Rx(φ): rotates a body-frame vector into NED, for
/// `attitude_rad` = (roll φ, pitch θ, yaw ψ) in radians. Heading east (ψ = 90°), the
/// body's x axis points east: C_b^n · (1, 0, 0) = (0, 1, 0).
pub fn body_to_ned(attitude_rad: Vec3) -> Mat3 {
    let [roll, pitch, yaw] = attitude_rad;
    multiply(
        &multiply(&rotation_z(yaw), &rotation_y(pitch)),
        &rotation_x(roll),
    )
}

/// The product a · b.
pub fn multiply(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut out = [[0.0; 3]; 3];
    for (row, out_row) in out.iter_mut().enumerate() {
        for (column, value) in out_row.iter_mut().enumerate() {
            *value = (0..3).map(|k| a[row][k] * b[k][column]).sum();
        }
    }
    out
}

/// The transpose of a (for a rotation, its inverse).
pub fn transpose(a: &Mat3) -> Mat3 {
    let mut out = [[0.0; 3]; 3];
    for (row, out_row) in out.iter_mut().enumerate() {
        for (column, value) in out_row.iter_mut().enumerate() {
            *value = a[column][row];
        }
    }
    out
}

/// The product a · v.
pub fn apply(a: &Mat3, v: Vec3) -> Vec3 {
    [0, 1, 2].map(|row| a[row][0] * v[0] + a[row][1] * v[1] + a[row][2] * v[2])
}

/// The cross product a × b.
pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
