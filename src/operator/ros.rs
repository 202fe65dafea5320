//! The installation as ROS uses it, for a recording read from a bag: the terms in the
//! bag's body frame's own axes (REP-103's forward-left-up unless it says otherwise),
//! the DVL's frame placed in the body's as a URDF joint and as the arguments of
//! `static_transform_publisher`, and the DVL's velocity covariance from the fit's
//! residual noise, as a `TwistWithCovarianceStamped` carries it to robot_localization.
//! In: the frames the bag was read in and the installation found. Out: a
//! [`RosInstallation`] and its texts.

use crate::Vec3;
use crate::data::paired::bag::euler_zyx;
use crate::data::paired::bag::{Axes, BagFrames};
use crate::installation::estimate::bound::TermBound;
use crate::installation::terms::Installation;
use crate::operator::installation_file::SavedMount;
use crate::rotation::{Mat3, apply, body_to_ned, multiply};
use std::path::{Path, PathBuf};

/// The DVL's frame in the body's, as found, and its velocity covariance.
#[derive(Debug, Clone, PartialEq)]
pub struct RosInstallation {
    pub body: String,
    pub dvl_frame: String,
    /// Where the DVL's frame's origin is in the body frame, m, and the rotation that
    /// takes a vector in the DVL's frame into the body's.
    pub translation_m: Vec3,
    pub rotation: Mat3,
    /// The DVL's velocity covariance in the body frame's axes, (m/s)², row-major.
    pub covariance: [[f64; 3]; 3],
    /// The mount `/tf_static` gave, which the misalignment found is a turn from.
    pub tf_static: SavedMount,
}

impl RosInstallation {
    /// The DVL's frame of `frames` placed by `installation`: its misalignment turns the
    /// mount `/tf_static` gave, its lever arm (where `lever_arm_found`) replaces the
    /// mount's translation; `residual_rms_m_s` per axis gives the covariance.
    pub fn of(
        frames: &BagFrames,
        installation: &Installation,
        lever_arm_found: bool,
        residual_rms_m_s: Vec3,
    ) -> RosInstallation {
        let axes = frames.axes.to_frd();
        let misalignment = body_to_ned(installation.misalignment_rad);
        let rotation = multiply(
            &multiply(&multiply(&axes, &misalignment), &axes),
            &frames.mount.rotation,
        );
        let translation_m = match lever_arm_found {
            true => apply(&axes, installation.lever_arm_m),
            false => frames.mount.translation_m,
        };
        let mut covariance = [[0.0; 3]; 3];
        for k in 0..3 {
            covariance[k][k] = residual_rms_m_s[k].powi(2);
        }
        RosInstallation {
            body: frames.body.clone(),
            dvl_frame: frames.dvl_frame.clone(),
            translation_m,
            rotation,
            covariance,
            tf_static: SavedMount {
                body: frames.body.clone(),
                dvl_frame: frames.dvl_frame.clone(),
                rpy_rad: euler_zyx(&frames.mount.rotation),
            },
        }
    }

    /// The DVL's frame as a fixed URDF joint.
    pub fn urdf(&self) -> String {
        let [x, y, z] = self.translation_m;
        let [roll, pitch, yaw] = euler_zyx(&self.rotation);
        format!(
            "<!-- The DVL's mounting found by dcnet-exp calibrate; its velocity covariance, (m/s)^2, row-major: {} -->\n<joint name=\"{}_joint\" type=\"fixed\">\n  <parent link=\"{}\"/>\n  <child link=\"{}\"/>\n  <origin xyz=\"{x:.4} {y:.4} {z:.4}\" rpy=\"{roll:.6} {pitch:.6} {yaw:.6}\"/>\n</joint>\n",
            self.covariance_row_major(),
            self.dvl_frame,
            self.body,
            self.dvl_frame
        )
    }

    /// The command that publishes the DVL's frame as a static transform.
    pub fn static_transform_publisher(&self) -> String {
        let [x, y, z] = self.translation_m;
        let [roll, pitch, yaw] = euler_zyx(&self.rotation);
        format!(
            "ros2 run tf2_ros static_transform_publisher --x {x:.4} --y {y:.4} --z {z:.4} --roll {roll:.6} --pitch {pitch:.6} --yaw {yaw:.6} --frame-id {} --child-frame-id {}",
            self.body, self.dvl_frame
        )
    }

    /// The covariance's nine values, row-major, as a message's field lists them.
    fn covariance_row_major(&self) -> String {
        let values: Vec<String> = self
            .covariance
            .iter()
            .flatten()
            .map(|v| format!("{v:.3e}"))
            .collect();
        format!("[{}]", values.join(", "))
    }

    /// The files `--save FILE` writes beside FILE: `FILE.urdf` and `FILE.ros.txt`.
    pub fn paths(save: &Path) -> [PathBuf; 2] {
        [save.with_extension("urdf"), save.with_extension("ros.txt")]
    }

    /// Writes the URDF joint and the ROS text beside the installation file `save`.
    pub fn write(&self, save: &Path) -> std::io::Result<[PathBuf; 2]> {
        let [urdf, text] = Self::paths(save);
        crate::files::write_atomic(&urdf, self.urdf().as_bytes())?;
        let ros = format!(
            "# The DVL's mounting found by dcnet-exp calibrate, {} to {}, lever arm in metres, angles in radians.\n{}\n# The DVL's velocity covariance in {}'s axes, (m/s)^2, row-major (the linear block of a TwistWithCovarianceStamped):\n{}\n",
            self.body,
            self.dvl_frame,
            self.static_transform_publisher(),
            self.body,
            self.covariance_row_major()
        );
        crate::files::write_atomic(&text, ros.as_bytes())?;
        Ok([urdf, text])
    }
}

/// A term's value in the body frame's `axes`: a lever arm's, a misalignment's or a
/// bias's y and z are negated in forward-left-up; every other term reads the same.
pub fn in_body_axes(name: &str, value: f64, axes: Axes) -> f64 {
    let per_axis = ["lever_arm_", "misalignment_", "bias_"]
        .iter()
        .any(|p| name.starts_with(p));
    let flipped = name.contains("_y_") || name.contains("_z_");
    match (axes, per_axis && flipped) {
        (Axes::ForwardLeftUp, true) => -value,
        _ => value,
    }
}

/// The terms of `bound` in the body frame's axes: name, estimate and standard
/// deviation each.
pub fn body_axes_terms(bound: &TermBound, axes: Axes) -> Vec<(String, f64, f64)> {
    (bound.names.iter().enumerate())
        .map(|(k, name)| {
            (
                name.to_string(),
                in_body_axes(name, bound.value[k], axes),
                bound.std[k],
            )
        })
        .collect()
}
