//! `calibrate`: one recording of a DVL beside a reference with attitude, calibrated by
//! one library call ([`crate::operator::calibrate`]) and printed
//! ([`crate::report::operator::calibrate`]); and `correct`, its installation applied to
//! another dive ([`crate::operator::correct`], printed by
//! [`crate::report::operator::correct`]). In: the parsed arguments. Out: what they
//! found on stdout, the files written named on stderr (what each will cost, it says
//! itself before it starts: [`crate::operator::cost`]).

use super::args;
use super::{CliError, input, stopped};
use crate::installation::terms::names::TermName;
use crate::operator::calibrate::{CalibrateArgs, calibrate as calibrated};
use crate::operator::calibrate_joint::{JointArgs, calibrate_joint as calibrated_jointly};
use crate::operator::correct::{CorrectArgs, correct as corrected};
use crate::report::operator::calibrate::{calibration_text, joint_text};
use crate::report::operator::correct::correction_text;

/// `calibrate` as typed: one recording, or several calibrated jointly.
pub(super) fn calibrate_command(args: &args::CalibrateArgs) -> Result<(), CliError> {
    if args.dvl.len() == 1 && args.reference.len() > 1 {
        return Err(input(anyhow::anyhow!(
            "--reference: {} files for one DVL file: give one",
            args.reference.len()
        )));
    }
    let terms = parse_terms(("--terms", &args.terms))?;
    let dive_terms = parse_terms(("--dive-terms", &args.dive_terms))?;
    if args.dvl.len() > 1 {
        return calibrate_joint(&JointArgs {
            dvls: &args.dvl,
            references: &args.reference,
            columns: args.columns.as_deref(),
            reading: args.reading.reading(),
            terms: &terms,
            dive_terms: &dive_terms,
            window_s: args.window_s,
            dvl_noise_cm_s: args.dvl_noise_cm_s,
            reference_noise_cm_s: args.reference_noise_cm_s,
            tolerance_pct: args.tolerance_pct,
            out: &args.out,
            save: args.save.as_deref(),
        });
    }
    calibrate(&CalibrateArgs {
        dvl: &args.dvl[0],
        reference: args.reference.first().map(std::path::PathBuf::as_path),
        columns: args.columns.as_deref(),
        reading: args.reading.reading(),
        terms: &terms,
        window_s: args.window_s,
        dvl_noise_cm_s: args.dvl_noise_cm_s,
        reference_noise_cm_s: args.reference_noise_cm_s,
        tolerance_pct: args.tolerance_pct,
        out: &args.out,
        save: args.save.as_deref(),
        dive_terms: &dive_terms,
    })
}

/// `correct` as typed.
pub(super) fn correct_command(args: &args::CorrectArgs) -> Result<(), CliError> {
    correct(&CorrectArgs {
        dvl: &args.dvl,
        reference: args.reference.as_deref(),
        columns: args.columns.as_deref(),
        reading: args.reading.reading(),
        installation: &args.installation,
        window_s: args.window_s,
        search_s: args.search_s,
        time_offset_s: args.time_offset_s,
        out: &args.out,
    })
}

/// `--terms` (or `--dive-terms`) as typed, each a term's name.
fn parse_terms((flag, terms): (&str, &[String])) -> Result<Vec<TermName>, CliError> {
    terms
        .iter()
        .map(|term| {
            term.parse()
                .map_err(|message| input(anyhow::anyhow!("{flag} {term}: {message}")))
        })
        .collect()
}

/// `calibrate`: the terms of one recording, their bound, how long the recording needed,
/// and the recording corrected.
fn calibrate(args: &CalibrateArgs) -> Result<(), CliError> {
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
fn correct(args: &CorrectArgs) -> Result<(), CliError> {
    let correction = corrected(args).map_err(stopped)?;
    print!("{}", correction_text(&correction));
    for path in &correction.written {
        eprintln!("corrected dive written to {}", path.display());
    }
    Ok(())
}

/// `calibrate A.csv B.csv …`: the vehicle's terms over every recording, each one's clock
/// its own, whether they agree, and each recording corrected.
fn calibrate_joint(args: &JointArgs) -> Result<(), CliError> {
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
