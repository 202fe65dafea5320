//! `calibrate`: one recording of a DVL beside a reference with attitude, calibrated by
//! one library call ([`crate::results::calibrate`]) and printed
//! ([`crate::report::operator::calibrate`]); and `correct`, its installation applied to
//! another dive ([`crate::results::correct`], printed by
//! [`crate::report::operator::correct`]). In: the parsed arguments. Out: what they
//! found on stdout, the files written named on stderr.

use super::{CliError, failure, input};
use crate::report::operator::calibrate::{calibration_text, joint_text};
use crate::report::operator::correct::correction_text;
use crate::results::calibrate::calibrate as calibrated;
use crate::results::calibrate_joint::{JointArgs, calibrate_joint as calibrated_jointly};
use crate::results::correct::{CorrectArgs, correct as corrected};

pub(super) use crate::results::calibrate::CalibrateArgs;

/// `calibrate`: the terms of one recording, their bound, how long the recording needed,
/// and the recording corrected.
pub(super) fn calibrate(args: &CalibrateArgs) -> Result<(), CliError> {
    let calibration = calibrated(args).map_err(|error| match error.is_input() {
        true => input(error),
        false => failure(error),
    })?;
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
    let correction = corrected(args).map_err(|error| match error.is_input() {
        true => input(error),
        false => failure(error),
    })?;
    print!("{}", correction_text(&correction));
    for path in &correction.written {
        eprintln!("corrected dive written to {}", path.display());
    }
    Ok(())
}

/// `calibrate A.csv B.csv …`: the vehicle's terms over every recording, each one's clock
/// its own, whether they agree, and each recording corrected.
pub(super) fn calibrate_joint(args: &JointArgs) -> Result<(), CliError> {
    let calibration = calibrated_jointly(args).map_err(|error| match error.is_input() {
        true => input(error),
        false => failure(error),
    })?;
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
