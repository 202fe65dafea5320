//! `calibrate`: one recording of a DVL beside a reference with attitude, calibrated by
//! one library call ([`crate::results::calibrate`]) and printed
//! ([`crate::report::printed::calibrate`]). In: the parsed arguments. Out: the fit and
//! the filter's settling on stdout, the files written named on stderr.

use super::{CliError, failure, input};
use crate::report::printed::calibrate::calibration_text;
use crate::results::calibrate::calibrate as calibrated;

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
    eprintln!(
        "the filter's terms against time written to {}",
        calibration.terms_in_time.display()
    );
    Ok(())
}
