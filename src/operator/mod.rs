//! The operator's commands on recordings named on the command line: [`calibrate`] one
//! recording (its [`residual`] sample by sample kept for its report), [`calibrate_joint`]
//! several at once, the [`installation_file`] that
//! `calibrate --save` writes (and, for a bag, the installation as ROS uses it:
//! [`ros`]), and [`correct`], which carries a saved installation to
//! the next dive and finds its clock again; [`calibrate_fixes`], a DVL calibrated
//! against position fixes and an attitude (its dead reckoning scored on them, and across
//! a blackout: [`fix_drifts`]), [`calibrate_fixes_joint`] several such dives
//! as one vehicle, and [`correct_fixes`], its installation
//! carried to the next such dive; what they share about their [`inputs`], and
//! what each will [`cost`] this machine; a calibration's [`acceptance`] against a
//! vendor's thresholds.
//! In: the command's arguments. Out: what each command prints, and the corrected
//! recordings written through [`crate::results::corrected`].

pub mod inputs;
pub mod cost;
pub mod calibrate;
pub mod residual;
pub mod acceptance;
pub mod installation_file;
pub mod ros;
pub mod correct;
pub mod calibrate_joint;
pub mod calibrate_fixes;
pub mod fix_drifts;
pub mod calibrate_fixes_joint;
pub mod correct_fixes;
