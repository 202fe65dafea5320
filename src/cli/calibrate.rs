//! `calibrate`: one recording of a DVL beside a reference with attitude, calibrated by
//! one library call ([`crate::operator::calibrate`]) and printed
//! ([`crate::report::printed::calibrate`]); and `correct`, its installation applied to
//! another dive ([`crate::operator::correct`], printed by
//! [`crate::report::printed::correct`]). In: the parsed arguments. Out: what they
//! found on stdout, the files written named on stderr.

use super::{CliError, stopped};
use crate::operator::calibrate::calibrate as calibrated;
use crate::operator::calibrate_joint::{JointArgs, calibrate_joint as calibrated_jointly};
use crate::operator::correct::{CorrectArgs, correct as corrected};
use crate::report::printed::calibrate::{calibration_text, joint_text};
use crate::report::printed::correct::correction_text;

pub(super) use crate::operator::calibrate::CalibrateArgs;

/// `calibrate`: the terms of one recording, their bound, how long the recording needed,
/// and the recording corrected.
pub(super) fn calibrate(args: &CalibrateArgs) -> Result<(), CliError> {
    let calibration = calibrated(args).map_err(stopped)?;
    print!("{}", calibration_text(&calibration));
    for path in &calibration.corrected {
        eprintln!("corrected recording written to {}", path.display());
    }
    if let Some(path) = args.save {
        eprintln!(
            "installation saved to {} (apply it to another dive with `dcnet-exp correct`)",
            path.display()
        );
    }
    eprintln!(
        "the filter's terms against time written to {}",
        calibration.terms_in_time.display()
    );
    Ok(())
}

/// `correct`: the installation of `--installation` applied to the dive, its clock found
/// again, and how well it fits.
pub(super) fn correct(args: &CorrectArgs) -> Result<(), CliError> {
    let correction = corrected(args).map_err(stopped)?;
    print!("{}", correction_text(&correction));
    for path in &correction.written {
        eprintln!("corrected dive written to {}", path.display());
    }
    Ok(())
}

/// `calibrate A.csv B.csv …`: the vehicle's terms over every recording, each one's clock
/// its own, whether they agree, and each recording corrected.
pub(super) fn calibrate_joint(args: &JointArgs) -> Result<(), CliError> {
    let calibration = calibrated_jointly(args).map_err(stopped)?;
    print!("{}", joint_text(&calibration));
    for path in &calibration.written {
        eprintln!("corrected recording written to {}", path.display());
    }
    if let Some(path) = args.save {
        eprintln!(
            "installation saved to {} (apply it to another dive with `dcnet-exp correct`)",
            path.display()
        );
    }
    Ok(())
}
