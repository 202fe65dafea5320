//! The commands of an installation study: `run`, `validate` and `plot` of a spec with
//! `kind = "installation"`, and `calibrate`, which calibrates one recording of a DVL
//! beside a reference, prints the terms with their standard deviations and the terms it
//! cannot see, and writes the recording corrected.
//! In: the parsed arguments. Out: the results folder or the corrected recording, and
//! what is printed.

use super::args::{Drawing, Target};
use super::{CliError, failure, input};
use crate::data::paired::{self, PairedColumns, PairedFiles};
use crate::installation::bound::{Noise, Tolerances, bound};
use crate::installation::fit::fit;
use crate::installation::frames::Reference;
use crate::installation::spec::{self as study_spec, ObservabilityFile, TermName};
use crate::installation::study::term_set;
use crate::installation::terms::score;
use crate::pipeline::installation::{Outcome, run_study};
use crate::report::plots::Format;
use crate::spec::TomlFile;
use std::path::{Path, PathBuf};

/// `run` of an installation spec.
pub(super) fn run(target: &Target, drawing: &Drawing, force: bool) -> Result<(), CliError> {
    let spec = study_spec::load(&target.spec, &target.overrides.set).map_err(input)?;
    match run_study(&spec, &target.out, force).map_err(input)? {
        Outcome::Current(folder) => {
            eprintln!("nothing to do: the results in {} are current", folder.display());
        }
        Outcome::Written { folder, study } => {
            println!("{}", crate::report::installation::printed(&study));
            if let Some(plots) = drawing.folder() {
                draw(&study, &plots.join(&spec.name))?;
            }
            eprintln!("results written to {}", folder.display());
        }
    }
    Ok(())
}

/// `plot` of an installation study's results folder: its figures and reports again.
pub(super) fn plot(results: &Path, out: &Path) -> Result<(), CliError> {
    let study = crate::results::installation::read_study(results).map_err(input)?;
    let name = results.file_name().map(PathBuf::from).unwrap_or_default();
    draw(&study, &out.join(name))
}

fn draw(study: &crate::installation::rows::Study, folder: &Path) -> Result<(), CliError> {
    let drawn = crate::report::plots::figures::installation::draw_all(study, folder, Format::Both)
        .map_err(failure)?;
    for (figure, caption) in drawn {
        eprintln!("{figure}: {caption}");
    }
    Ok(())
}

/// `validate` of an installation spec: its faults, or what it would compute.
pub(super) fn validate(path: &Path, set: &[String]) -> Result<(), CliError> {
    let spec = study_spec::load(path, set).map_err(input)?;
    println!(
        "{}: ok (an installation study: {} trajectories, {} windows, {} methods)",
        path.display(),
        spec.trajectories.len(),
        spec.windows_s.len(),
        spec.methods.len() + 1
    );
    Ok(())
}

/// What `calibrate` is asked.
pub(super) struct CalibrateArgs<'a> {
    pub dvl: &'a Path,
    pub reference: Option<&'a Path>,
    pub columns: Option<&'a Path>,
    pub terms: &'a [TermName],
    pub window_s: Option<f64>,
    pub dvl_noise_cm_s: f64,
    pub reference_noise_cm_s: f64,
    pub out: &'a Path,
}

/// The columns of `path`'s `[columns]` table, or A-KIT's.
fn columns(path: Option<&Path>) -> Result<PairedColumns, CliError> {
    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct ColumnsFile {
        columns: PairedColumns,
    }
    match path {
        None => Ok(PairedColumns::akit()),
        Some(path) => TomlFile::<ColumnsFile>::read(path)
            .map(|file| file.value.columns)
            .map_err(|fault| input(anyhow::anyhow!("{fault}"))),
    }
}

/// `calibrate`: the terms of one recording, their bound, and the recording corrected.
pub(super) fn calibrate(args: &CalibrateArgs) -> Result<(), CliError> {
    let files = PairedFiles {
        dvl: args.dvl.to_path_buf(),
        reference: args.reference.unwrap_or(args.dvl).to_path_buf(),
    };
    let recording = paired::read(&files, &columns(args.columns)?).map_err(input)?;
    let reference = Reference::new(&recording);
    let start = recording.time_s[0];
    let end = match args.window_s {
        Some(w) => recording.time_s.partition_point(|&t| t - start < w),
        None => recording.time_s.len(),
    };
    let terms = term_set(args.terms);
    let fitted = fit(
        &recording.time_s[..end],
        &recording.dvl_m_s[..end],
        &reference,
        terms,
    )
    .map_err(input)?;
    let defaults = ObservabilityFile::default();
    let tolerances = Tolerances {
        scale: defaults.scale_pct / 100.0,
        misalignment_rad: defaults.misalignment_deg.to_radians(),
        lever_arm_m: defaults.lever_arm_m,
        time_offset_s: defaults.time_offset_s,
        bias_m_s: defaults.bias_cm_s / 100.0,
        max_correlation: defaults.max_correlation,
    };
    let noise = Noise {
        dvl_m_s: args.dvl_noise_cm_s / 100.0,
        reference_m_s: args.reference_noise_cm_s / 100.0,
    };
    let bounded = bound(&fitted, noise, &tolerances);
    let all = 0..recording.time_s.len();
    let before = score(
        &Default::default(),
        &recording.time_s,
        &recording.dvl_m_s,
        &reference,
        all.clone(),
    );
    let after = score(
        &fitted.installation,
        &recording.time_s,
        &recording.dvl_m_s,
        &reference,
        all,
    );
    println!(
        "{}",
        crate::report::installation::calibration_printed(&bounded, end, &before, &after)
    );
    let corrected = crate::installation::terms::corrected_record(
        &fitted.installation,
        &recording.time_s,
        &recording.dvl_m_s,
        &reference,
    );
    let stem = args
        .dvl
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "recording".into());
    let written = crate::results::corrected::write(args.out, &stem, &corrected).map_err(failure)?;
    for path in written {
        eprintln!("corrected recording written to {}", path.display());
    }
    Ok(())
}
