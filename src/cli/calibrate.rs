//! `calibrate`: one recording of a DVL beside a reference with attitude, calibrated by
//! one library call ([`crate::operator::calibrate`]) and printed
//! ([`crate::report::operator::calibrate`]), held to `--accept`'s thresholds where asked
//! ([`crate::operator::acceptance`]); and `correct`, its installation applied to
//! another dive ([`crate::operator::correct`], printed by
//! [`crate::report::operator::correct`]), held to `--accept`'s drift there where asked;
//! either's report written with `--report`. In: the parsed arguments. Out: what they
//! found on stdout, the files written named on stderr (what each will cost, it says
//! itself before it starts: [`crate::operator::cost`]).

use super::args::{self, GivenFixes};
use super::{CliError, failure, input, stopped};
use crate::installation::estimate::clock::DEFAULT_SEARCH_S;
use crate::installation::estimate::fixes::default_fix_terms;
use crate::installation::terms::names::TermName;
use crate::operator::acceptance::{
    Acceptance, CALIBRATED_DRIFT, CARRIED_DRIFT, Thresholds, accept, accept_carried,
    reference_drift,
};
use crate::operator::calibrate::{CalibrateArgs, calibrate as calibrated};
use crate::operator::calibrate_fixes::{FixArgs, FixFiles, calibrate_fixes as calibrated_on_fixes};
use crate::operator::calibrate_fixes_joint::calibrate_fixes_joint as calibrated_on_fixes_jointly;
use crate::operator::calibrate_joint::{JointArgs, calibrate_joint as calibrated_jointly};
use crate::operator::correct::{CorrectArgs, correct as corrected};
use crate::operator::correct_fixes::{FixCorrectArgs, correct_fixes as corrected_on_fixes};
use crate::operator::fix_drifts::BlackoutAsked;
use crate::report::kit::plots::PlotError;
use crate::report::operator::acceptance::acceptance_text;
use crate::report::operator::calibrate::{calibration_text, joint_text};
use crate::report::operator::correct::{correction_text, fix_correction_text};
use crate::report::operator::figures::{calibration_figures, correction_figures};
use crate::report::operator::fix_figures::{fix_calibration_figures, fix_correction_figures};
use crate::report::operator::fixes::fixes_text;
use crate::report::operator::fixes_joint::joint_fixes_text;
use crate::report::operator::joint_figures::{joint_figures, joint_fix_figures};
use crate::report::operator::page::{HTML, write_report};
use std::path::Path;

/// `calibrate` as typed: one recording, or several calibrated jointly.
pub(super) fn calibrate_command(args: &args::CalibrateArgs) -> Result<(), CliError> {
    if args.dvl.len() == 1 && args.reference.len() > 1 {
        return Err(input(anyhow::anyhow!(
            "--reference: {} files for one DVL file: give one",
            args.reference.len()
        )));
    }
    if args.fix_latency && args.fix.fix_latency_s.is_some() {
        return Err(input(anyhow::anyhow!(
            "--fix-latency: estimates the fixes' latency, where --fix-latency-s gives it known: give one"
        )));
    }
    if let Some(typed) = (args.dvl.iter()).find(|dvl| thresholds_typed_apart(dvl)) {
        return Err(input(anyhow::anyhow!(
            "{}: not a DVL file but a threshold: give it after an equals sign, --accept={}",
            typed.display(),
            typed.display()
        )));
    }
    let given = (args.fix.given_per_dive(args.dvl.len())).map_err(|m| input(anyhow::anyhow!(m)))?;
    if args.dvl.len() > 1 {
        refuse_for_several(args)?;
    }
    let thresholds = thresholds(args.accept.as_deref())?;
    if let Some(given) = given {
        let rejected = calibrate_fixes(args, &given, thresholds)?;
        return rejection(rejected && args.fail_on_reject);
    }
    args::without_fixes(&[
        ("--depth-noise-m", args.depth_noise_m.is_some()),
        ("--fix-latency", args.fix_latency),
        ("--blackout-s", args.blackout_s.is_some()),
    ])
    .map_err(|m| input(anyhow::anyhow!(m)))?;
    let default_terms = ["lever_arm", "time_offset", "bias"].map(String::from);
    let terms = parse_terms(("--terms", args.terms.as_deref().unwrap_or(&default_terms)))?;
    let dive_terms = parse_terms(("--dive-terms", &args.dive_terms))?;
    if args.dvl.len() > 1 {
        let joint = JointArgs {
            dvls: &args.dvl,
            references: &args.reference,
            columns: args.columns.as_deref(),
            reading: args.reading.reading(),
            terms: &terms,
            dive_terms: &dive_terms,
            window_s: args.window_s,
            dvl_noise_cm_s: args.dvl_noise_cm_s,
            reference_noise_cm_s: args.reference_noise_cm_s(),
            tolerance_pct: args.tolerance_pct(),
            out: args.out(),
            save: args.save.as_deref(),
            search_s: args.search_s,
        };
        return calibrate_joint(&joint, args.report());
    }
    let one = CalibrateArgs {
        dvl: &args.dvl[0],
        reference: args.reference.first().map(std::path::PathBuf::as_path),
        columns: args.columns.as_deref(),
        reading: args.reading.reading(),
        terms: &terms,
        window_s: args.window_s,
        dvl_noise_cm_s: args.dvl_noise_cm_s,
        reference_noise_cm_s: args.reference_noise_cm_s(),
        tolerance_pct: args.tolerance_pct(),
        out: args.out(),
        save: args.save.as_deref(),
        dive_terms: &dive_terms,
        search_s: args.search_s,
    };
    let rejected = calibrate(&one, args.report(), thresholds)?;
    rejection(rejected && args.fail_on_reject)
}

/// `--accept`'s thresholds, where asked, parsed and named at fault.
fn thresholds(given: Option<&str>) -> Result<Option<Thresholds>, CliError> {
    (given.map(Thresholds::parse).transpose())
        .map_err(|message| input(anyhow::anyhow!("--accept: {message}")))
}

/// Whether `dvl`, named as a DVL file, is no file but `--accept`'s thresholds typed
/// after a space (`--accept scale_pct=1`), which the flag does not take.
fn thresholds_typed_apart(dvl: &Path) -> bool {
    let typed = dvl.to_string_lossy();
    !dvl.exists()
        && (typed.split(',')).all(|pair| {
            (pair.split_once('=')).is_some_and(|(key, _)| Thresholds::KEYS.contains(&key.trim()))
        })
}

/// Refuses what a joint calibration does not do yet: `--accept` and `--blackout-s`.
fn refuse_for_several(args: &args::CalibrateArgs) -> Result<(), CliError> {
    for (flag, asked) in [
        ("--accept", args.accept.is_some()),
        ("--blackout-s", args.blackout_s.is_some()),
    ] {
        if asked {
            return Err(input(anyhow::anyhow!(
                "{flag}: for one recording; not yet for several calibrated jointly"
            )));
        }
    }
    Ok(())
}

/// Exit status 3 where `--fail-on-reject` meets a calibration `--accept` rejected.
fn rejection(fail: bool) -> Result<(), CliError> {
    rejected_as(fail, "the calibration is rejected")
}

/// Exit status 3 where `fail`, saying that `what` (is rejected) by `--accept`.
fn rejected_as(fail: bool, what: &str) -> Result<(), CliError> {
    match fail {
        true => Err(CliError::Rejected(anyhow::anyhow!(
            "{what} by --accept (--fail-on-reject); every file was written"
        ))),
        false => Ok(()),
    }
}

/// `correct --accept`'s threshold: the drift alone, the terms' thresholds named as held
/// where the installation was calibrated.
fn carried_thresholds(given: Option<&str>) -> Result<Option<Thresholds>, CliError> {
    let keys = given.into_iter().flat_map(|g| g.split(','));
    let named = |pair: &str| pair.split('=').next().unwrap_or("").trim().to_string();
    let other = keys.map(named).find(|k| !k.is_empty() && k != "drift_pct");
    match other {
        Some(key) if Thresholds::KEYS.contains(&key.as_str()) => Err(input(anyhow::anyhow!(
            "--accept: {key}: the terms are held to their thresholds where the installation is calibrated (calibrate --accept); correct holds its dead reckoning on this dive to drift_pct"
        ))),
        Some(key) => Err(input(anyhow::anyhow!(
            "--accept: {key}: not a threshold; correct takes drift_pct"
        ))),
        None => thresholds(given),
    }
}

/// The acceptance of an installation carried to a dive whose dead reckoning there
/// drifted as `drift` says, where `thresholds` were asked; its text appended to
/// `printed`.
fn carried_acceptance(
    thresholds: Option<Thresholds>,
    drift: Result<crate::operator::acceptance::ScoredDrift, String>,
    printed: &mut String,
) -> Option<Acceptance> {
    let acceptance = accept_carried(drift, thresholds?);
    printed.push_str(&format!("\n{}", acceptance_text(&acceptance)));
    Some(acceptance)
}

/// `calibrate DVL.csv --fixes FIXES.csv --attitude ATTITUDE.csv --fix-noise-m σ`: the
/// terms the fixes show, printed, and saved where asked, held to `thresholds` and its
/// report written where asked; of several dives (one `given` each), the vehicle's terms
/// over them. Returns whether the thresholds reject it.
fn calibrate_fixes(
    args: &args::CalibrateArgs,
    given: &[GivenFixes],
    thresholds: Option<Thresholds>,
) -> Result<bool, CliError> {
    refuse_beside_fixes(
        &[
            ("--reference", !args.reference.is_empty()),
            ("--window-s", args.window_s.is_some()),
            ("--tolerance-pct", args.tolerance_pct.is_some()),
            (
                "--reference-noise-cm-s",
                args.reference_noise_cm_s.is_some(),
            ),
            ("--search-s", args.search_s.is_some()),
        ],
        (&args.reading, &given[0]),
        "a calibration against fixes, which runs no filter",
    )?;
    let terms = match &args.terms {
        Some(terms) => parse_terms(("--terms", terms))?,
        None => default_fix_terms(),
    };
    let dive_terms = parse_terms(("--dive-terms", &args.dive_terms))?;
    let blackout = (args.blackout_s.as_deref())
        .map(BlackoutAsked::parse)
        .transpose()
        .map_err(|message| input(anyhow::anyhow!("--blackout-s {message}")))?;
    let dives: Vec<FixArgs> = (args.dvl.iter().zip(given))
        .map(|(dvl, given)| FixArgs {
            files: fix_files(
                dvl,
                given,
                args.columns.as_deref(),
                &args.reading,
                &args.fix,
            ),
            terms: &terms,
            dive_terms: &dive_terms,
            fix_noise_m: args.fix.fix_noise_m,
            depth_noise_m: args.depth_noise_m,
            fix_latency: args.fix_latency,
            dvl_noise_cm_s: args.dvl_noise_cm_s,
            save: args.save.as_deref(),
            out: args.out(),
            blackout,
        })
        .collect();
    let [one] = &dives[..] else {
        calibrate_fixes_jointly(args, &dives)?;
        return Ok(false);
    };
    let calibration = calibrated_on_fixes(one).map_err(stopped)?;
    let mut printed = fixes_text(&calibration);
    let acceptance = thresholds.map(|thresholds| {
        let estimated = |k: usize| calibration.fit.estimated[k];
        let drift = calibration.drifts.scored();
        accept((&calibration.fit.bound, &estimated), drift, thresholds)
    });
    if let Some(acceptance) = &acceptance {
        printed.push_str(&format!("\n{}", acceptance_text(acceptance)));
    }
    print!("{printed}");
    written(&calibration.corrected, args.save.as_deref());
    if let Some(folder) = args.report() {
        let drawn = fix_calibration_figures(&calibration, &name_of(one.files.dvl));
        write_drawn(
            folder,
            &title("Calibration", one.files.dvl),
            &printed,
            drawn,
        )?;
    }
    Ok(acceptance.is_some_and(|a| a.rejected()))
}

/// Several `dives` against fixes calibrated jointly as one vehicle, printed, saved where
/// asked, and their report written where asked.
fn calibrate_fixes_jointly(args: &args::CalibrateArgs, dives: &[FixArgs]) -> Result<(), CliError> {
    let calibration = calibrated_on_fixes_jointly(dives).map_err(stopped)?;
    let printed = joint_fixes_text(&calibration);
    print!("{printed}");
    written(&calibration.written, args.save.as_deref());
    if let Some(folder) = args.report() {
        let title = format!("Joint calibration of {} dives with fixes", dives.len());
        write_drawn(folder, &title, &printed, joint_fix_figures(&calibration))?;
    }
    Ok(())
}

/// Says on stderr where the `corrected` recordings were written and where the
/// installation was `saved`, if it was.
fn written(corrected: &[std::path::PathBuf], saved: Option<&Path>) {
    for path in corrected {
        eprintln!("corrected recording written to {}", path.display());
    }
    if let Some(path) = saved {
        eprintln!(
            "installation saved to {} (apply it to another dive with `dcnet-exp correct`)",
            path.display()
        );
    }
}

/// The name a report gives the recording `dvl`: its file's stem.
fn name_of(dvl: &Path) -> String {
    (dvl.file_stem()).map_or("recording".into(), |s| s.to_string_lossy().into_owned())
}

/// A report's title: what was done (`Calibration`, `Correction`) of `dvl`.
fn title(done: &str, dvl: &Path) -> String {
    format!("{done} of {}", dvl.display())
}

/// The files of a fit to the fixes `given`, beside the DVL's file (or bag) `dvl`.
fn fix_files<'a>(
    dvl: &'a std::path::Path,
    given: &GivenFixes<'a>,
    columns: Option<&'a std::path::Path>,
    reading: &'a args::ReadingArgs,
    flags: &args::FixFlags,
) -> FixFiles<'a> {
    let (attitude, fixes, fix_topic) = match *given {
        GivenFixes::Files { fixes, attitude } => (attitude, fixes, None),
        GivenFixes::Topic(topic) => (dvl, dvl, Some(topic)),
    };
    FixFiles {
        dvl,
        attitude,
        fixes,
        fix_topic,
        columns,
        reading: reading.reading(),
        fix_latency_s: flags.fix_latency_s,
    }
}

/// Refuses the first of `flags` given, or, with fixes from files, of a bag's flags in
/// `reading`, saying that it does not apply to `command` (a command against fixes, and
/// what it does instead).
fn refuse_beside_fixes(
    flags: &[(&str, bool)],
    (reading, given): (&args::ReadingArgs, &GivenFixes),
    command: &str,
) -> Result<(), CliError> {
    if let Some((flag, _)) = flags.iter().find(|(_, given)| *given) {
        return Err(input(anyhow::anyhow!(
            "{flag}: does not apply to {command}"
        )));
    }
    if let GivenFixes::Topic(_) = given {
        return Ok(());
    }
    let bag = [
        ("--dvl-topic", reading.dvl_topic.is_some()),
        ("--reference-topic", reading.reference_topic.is_some()),
        ("--rate-topic", reading.rate_topic.is_some()),
        ("--stamps", reading.stamps.is_some()),
        ("--frame", reading.frame.is_some()),
    ];
    match bag.iter().find(|(_, given)| *given) {
        Some((flag, _)) => Err(input(anyhow::anyhow!(
            "{flag}: does not apply to {command} from --fixes, which reads CSV files (the DVL's, the attitude's and the fixes'); a bag's fixes are read with --fixes-topic"
        ))),
        None => Ok(()),
    }
}

/// `correct` as typed: against a velocity reference, or against fixes.
pub(super) fn correct_command(args: &args::CorrectArgs) -> Result<(), CliError> {
    let report = (args.report.as_ref()).map(|dir| dir.as_deref().unwrap_or(&args.out));
    let thresholds = carried_thresholds(args.accept.as_deref())?;
    let rejected = match args.fix.given().map_err(|m| input(anyhow::anyhow!(m)))? {
        Some(given) => correct_fixes(args, given, (report, thresholds))?,
        None => correct_velocity(args, (report, thresholds))?,
    };
    rejected_as(
        rejected && args.fail_on_reject,
        "the installation is rejected on this dive",
    )
}

/// `correct` against a velocity reference, its report written and its acceptance held
/// where asked; whether it is rejected.
fn correct_velocity(
    args: &args::CorrectArgs,
    asked: (Option<&Path>, Option<Thresholds>),
) -> Result<bool, CliError> {
    correct(
        &CorrectArgs {
            dvl: &args.dvl,
            reference: args.reference.as_deref(),
            columns: args.columns.as_deref(),
            reading: args.reading.reading(),
            installation: &args.installation,
            window_s: args.window_s.unwrap_or(DEFAULT_WINDOW_S),
            search_s: args.search_s.unwrap_or(DEFAULT_SEARCH_S),
            time_offset_s: args.time_offset_s,
            out: &args.out,
        },
        asked,
    )
}

/// The first seconds of a dive that find its clock again against a velocity reference.
const DEFAULT_WINDOW_S: f64 = 60.0;

/// `correct DVL.csv --installation FILE --fixes FIXES.csv --attitude ATTITUDE.csv
/// --fix-noise-m σ`: the installation carried, the clock found again from the fixes;
/// its report written and its acceptance held where asked; whether it is rejected.
fn correct_fixes(
    args: &args::CorrectArgs,
    given: GivenFixes,
    (report, thresholds): (Option<&Path>, Option<Thresholds>),
) -> Result<bool, CliError> {
    refuse_beside_fixes(
        &[
            ("--reference", args.reference.is_some()),
            ("--search-s", args.search_s.is_some()),
        ],
        (&args.reading, &given),
        "a correction against fixes, which scans the clock within ±3 s of the installation's",
    )?;
    let correction = corrected_on_fixes(&FixCorrectArgs {
        files: fix_files(
            &args.dvl,
            &given,
            args.columns.as_deref(),
            &args.reading,
            &args.fix,
        ),
        installation: &args.installation,
        fix_noise_m: args.fix.fix_noise_m,
        window_s: args.window_s,
        time_offset_s: args.time_offset_s,
        out: &args.out,
    })
    .map_err(stopped)?;
    let mut printed = fix_correction_text(&correction);
    let acceptance = carried_acceptance(thresholds, correction.drifts.carried(), &mut printed);
    print!("{printed}");
    for path in &correction.written {
        eprintln!("corrected dive written to {}", path.display());
    }
    if let Some(folder) = report {
        let drawn = fix_correction_figures(&correction, &name_of(&args.dvl));
        write_drawn(folder, &title("Correction", &args.dvl), &printed, drawn)?;
    }
    Ok(acceptance.is_some_and(|a| a.rejected()))
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
/// and the recording corrected; held to `thresholds` where asked, and its report
/// written to `report` where one is asked. Returns whether the thresholds reject it.
fn calibrate(
    args: &CalibrateArgs,
    report: Option<&Path>,
    thresholds: Option<Thresholds>,
) -> Result<bool, CliError> {
    let calibration = calibrated(args).map_err(stopped)?;
    let mut printed = calibration_text(&calibration);
    let acceptance = thresholds.map(|thresholds| {
        let drift = reference_drift(calibration.drift.as_ref(), CALIBRATED_DRIFT);
        accept((&calibration.bound, &|_| true), drift, thresholds)
    });
    if let Some(acceptance) = &acceptance {
        printed.push_str(&format!("\n{}", acceptance_text(acceptance)));
    }
    print!("{printed}");
    written(&calibration.corrected, args.save);
    eprintln!(
        "the filter's terms against time written to {}",
        calibration.terms_in_time.display()
    );
    if let Some(folder) = report {
        let drawn = calibration_figures(&calibration, &name_of(args.dvl));
        write_drawn(folder, &title("Calibration", args.dvl), &printed, drawn)?;
    }
    Ok(acceptance.is_some_and(|a| a.rejected()))
}

/// `correct`: the installation of `--installation` applied to the dive, its clock found
/// again, and how well it fits; its report written and its acceptance held where asked.
/// Returns whether the threshold rejects it.
fn correct(
    args: &CorrectArgs,
    (report, thresholds): (Option<&Path>, Option<Thresholds>),
) -> Result<bool, CliError> {
    let correction = corrected(args).map_err(stopped)?;
    let mut printed = correction_text(&correction);
    let drift = reference_drift(correction.drift.as_ref(), CARRIED_DRIFT);
    let acceptance = carried_acceptance(thresholds, drift, &mut printed);
    print!("{printed}");
    for path in &correction.written {
        eprintln!("corrected dive written to {}", path.display());
    }
    if let Some(folder) = report {
        let drawn = correction_figures(&correction, &name_of(args.dvl));
        write_drawn(folder, &title("Correction", args.dvl), &printed, drawn)?;
    }
    Ok(acceptance.is_some_and(|a| a.rejected()))
}

/// The report titled `title` of what was `printed` and `drawn`, written into `folder`.
fn write_drawn(
    folder: &Path,
    title: &str,
    printed: &str,
    drawn: crate::report::kit::plots::draw::PlotResult<
        Vec<(String, crate::report::kit::plots::canvas::Outcome)>,
    >,
) -> Result<(), CliError> {
    drawn
        .map_err(|source| PlotError::Draw {
            what: "report's",
            source,
        })
        .and_then(|drawn| write_report(folder, title, printed, drawn))
        .map_err(failure)?;
    eprintln!("report written to {}", folder.join(HTML).display());
    Ok(())
}

/// `calibrate A.csv B.csv …`: the vehicle's terms over every recording, each one's clock
/// its own, whether they agree, and each recording corrected; its report written to
/// `report` where one is asked.
fn calibrate_joint(args: &JointArgs, report: Option<&Path>) -> Result<(), CliError> {
    let calibration = calibrated_jointly(args).map_err(stopped)?;
    let printed = joint_text(&calibration);
    print!("{printed}");
    written(&calibration.written, args.save);
    if let Some(folder) = report {
        let title = format!("Joint calibration of {} recordings", args.dvls.len());
        write_drawn(folder, &title, &printed, joint_figures(&calibration))?;
    }
    Ok(())
}
