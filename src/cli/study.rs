//! The commands of an installation study: `run` (whole or one shard), `plan`,
//! `collect`, `validate` and `plot` of a spec with `kind = "installation"` (a study, or
//! a sweep of them). In: the parsed arguments. Out: the results folder and what is
//! printed.

use crate::cli::args::{Drawing, Target};
use crate::cli::{CliError, failure, input, stopped};
use crate::count;
use crate::data::paired::Recordings;
use crate::files::Seal;
use crate::installation::study::rows::StudyResults;
use crate::installation::study::spec as study_spec;
use crate::installation::study::spec::StudySpec;
use crate::pipeline::{ExecuteError, Executed, Mode, Planned, Shard, StudyPlan, execute};
use crate::report::kit::plots::Format;
use crate::results::study_sweep::{self, StoredStudySweep};
use crate::spec::Experiment;
use comfy_table::{Table, presets::ASCII_MARKDOWN};
use std::path::{Path, PathBuf};

/// The experiment of an installation spec: the study, or the points of its sweep.
fn load(path: &Path, set: &[String]) -> Result<Experiment<StudySpec>, CliError> {
    study_spec::load_experiment(path, set).map_err(input)
}

/// The experiment a command works on; OUT, when it exists, must be a folder.
fn load_target(target: &Target) -> Result<Experiment<StudySpec>, CliError> {
    if target.out.exists() && !target.out.is_dir() {
        return Err(input(anyhow::anyhow!(
            "--out {}: is a file; results go into a folder",
            target.out.display()
        )));
    }
    load(&target.spec, &target.overrides.set)
}

/// `run` of an installation spec: every point not current, or one shard of its
/// calibrations.
pub(super) fn run(target: &Target, drawing: &Drawing, mode: Mode) -> Result<(), CliError> {
    let experiment = load_target(target)?;
    let plan = StudyPlan::new(&experiment, &target.spec, &target.out).map_err(input)?;
    let mut lengths = Vec::new();
    for (p, point) in experiment.points.iter().enumerate() {
        let recordings: Vec<(&str, &[f64])> = (plan.inputs.recordings_of(p).into_iter())
            .map(|r| (r.name.as_str(), r.recording.time_s.as_slice()))
            .collect();
        within_the_recordings(&experiment, &point.spec, &recordings)?;
        lengths.push(recordings.iter().map(|(_, time_s)| time_s.len()).collect());
    }
    learned_memory(&experiment, lengths)?;
    let Mode::Shard { shard, .. } = mode else {
        let executed = execute(&Planned::Study(&plan), mode).map_err(stopped)?;
        return finish(&plan, &executed, drawing);
    };
    let in_shard = (0..plan.units.len())
        .filter(|&u| plan.in_shard(u, shard))
        .count();
    if in_shard == 0 {
        eprintln!(
            "nothing to do: shard {shard} has no calibrations ({} has {}, shared round the {} shards)",
            experiment.name,
            count(plan.units.len(), "calibration"),
            shard.count
        );
        return Ok(());
    }
    let executed = execute(&Planned::Study(&plan), mode).map_err(stopped)?;
    if executed.done == 0 {
        eprintln!(
            "nothing to do: every calibration of {} shard {shard} is in the cache",
            experiment.name
        );
    } else {
        eprintln!(
            "shard {shard}: {} done; once every shard has finished, `{}` writes the results",
            count(executed.done, "calibration"),
            target.command("collect")
        );
    }
    Ok(())
}

/// `collect` of an installation spec: every point's folder from the calibrations its
/// shards stored.
pub(super) fn collect(target: &Target, drawing: &Drawing) -> Result<(), CliError> {
    let experiment = load_target(target)?;
    let plan = StudyPlan::new(&experiment, &target.spec, &target.out).map_err(input)?;
    let executed =
        execute(&Planned::Study(&plan), Mode::Collect).map_err(|error| match error {
            ExecuteError::NotCollected { .. } => input(anyhow::anyhow!(
                "{error}: run the shards that compute them (`{} --shard K/N`), or `{}`, which computes what is missing",
                target.command("run"),
                target.command("run")
            )),
            other => stopped(other),
        })?;
    finish(&plan, &executed, drawing)
}

/// `plan` of an installation spec: its calibrations (one shard's, with `--shard`), each
/// with its key and whether the cache holds it.
pub(super) fn plan(target: &Target, shard: Option<Shard>) -> Result<(), CliError> {
    let experiment = load_target(target)?;
    let plan = StudyPlan::new(&experiment, &target.spec, &target.out).map_err(input)?;
    let models = plan.learned_rows(shard);
    if !models.is_empty() {
        let mut table = Table::new();
        table.load_preset(ASCII_MARKDOWN);
        table.set_header(["learned model", "key", "status"]);
        for row in &models {
            table.add_row([&row.label, &row.key[..16], &row.status.to_string()]);
        }
        println!("{table}");
    }
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    table.set_header(["calibration", "key", "status"]);
    let mut listed = 0;
    let mut to_do = 0;
    for (u, unit) in plan.units.iter().enumerate() {
        if shard.is_some_and(|shard| !plan.in_shard(u, shard)) {
            continue;
        }
        let status = match plan.status(u) {
            Seal::Intact => "done",
            Seal::Absent => "to do",
            Seal::Damaged(_) => "to do (damaged)",
        };
        listed += 1;
        to_do += usize::from(status != "done");
        table.add_row([
            plan.label(u),
            unit.key[..16].to_string(),
            status.to_string(),
        ]);
    }
    println!("{table}");
    let scope = match shard {
        Some(shard) => format!("shard {shard} of {}", experiment.name),
        None => experiment.name.clone(),
    };
    let models = match models.len() {
        0 => String::new(),
        n => {
            let to_do = models.iter().filter(|m| !m.status.is_settled()).count();
            format!("{}, {to_do} to do; ", count(n, "learned model"))
        }
    };
    println!(
        "{scope}: {models}{}, {to_do} to do; cache in {}",
        count(listed, "calibration"),
        plan.store.folder.display()
    );
    Ok(())
}

/// Says what a run or collect did, prints the headline of a single study or the table
/// of a sweep, and draws the figures of what was written.
fn finish(plan: &StudyPlan, executed: &Executed, drawing: &Drawing) -> Result<(), CliError> {
    if executed.sweep.is_none() && executed.written.is_empty() {
        let folder = plan.out.join(&plan.experiment.name);
        eprintln!(
            "nothing to do: the results in {} are current",
            folder.display()
        );
        return Ok(());
    }
    for folder in &executed.written {
        let results = crate::results::study::read_study(folder).map_err(failure)?;
        if !plan.experiment.is_sweep() {
            println!("{}", crate::report::study::printed::headline(&results));
        }
        report(folder, &results, drawing.folder(), Format::Both)?;
        eprintln!("results written to {}", folder.display());
    }
    if let Some(folder) = &executed.sweep {
        let stored = study_sweep::read(folder).map_err(input)?;
        println!("{}", crate::report::study::printed::sweep_table(&stored));
        if let Some(plots) = drawing.folder() {
            draw_sweep(&stored, &plots.join(&plan.experiment.name), Format::Both)?;
        }
        eprintln!(
            "sweep table written to {}",
            folder.join(crate::results::sweep::TABLE).display()
        );
    }
    Ok(())
}

/// `plot` of an installation study's results folder, or of a sweep of them: figures
/// and reports again, from the tables alone.
pub(super) fn plot(results: &Path, out: &Path, format: Format) -> Result<(), CliError> {
    if !results.join(crate::results::sweep::INDEX).is_file() {
        return plot_study(results, out, format);
    }
    let stored = study_sweep::read(results).map_err(input)?;
    for point in &stored.index.points {
        plot_study(&results.join(point), out, format)?;
    }
    let name = results.file_name().map(PathBuf::from).unwrap_or_default();
    draw_sweep(&stored, &out.join(&name), format)
}

/// Reads one study's folder back and reports it again, its figures drawn into `out`.
fn plot_study(results: &Path, out: &Path, format: Format) -> Result<(), CliError> {
    let study = crate::results::study::read_checked(results).map_err(input)?;
    report(results, &study, Some(out), format)?;
    eprintln!("report written to {}", results.join("report.md").display());
    Ok(())
}

/// Draws the figures of the study in `folder` into `<plots>/<its name>` (none without
/// `plots`), then writes its reports and seals them with its manifest and figures, as
/// a paper run's are. Its name, which keys the LaTeX labels, is its manifest's: a sweep
/// point's is `<sweep>/<point>`.
fn report(
    folder: &Path,
    study: &StudyResults,
    plots: Option<&Path>,
    format: Format,
) -> Result<(), CliError> {
    let name = crate::results::read::manifest(folder).ok().map_or_else(
        || {
            folder
                .file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned()
        },
        |manifest| manifest.name,
    );
    let figures = match plots {
        Some(plots) => draw(study, &plots.join(&name), format)?,
        None => Vec::new(),
    };
    let reported = crate::report::Reported::Study {
        study,
        name: &name,
        folder,
        figures: &figures,
    };
    crate::report::write(&reported)
        .map_err(|e| failure(anyhow::Error::new(e).context(folder.display().to_string())))?;
    Ok(())
}

fn draw(
    study: &StudyResults,
    folder: &Path,
    format: Format,
) -> Result<Vec<crate::report::kit::plots::Written>, CliError> {
    let drawn = crate::report::study::draw_all(study, folder, format).map_err(failure)?;
    super::report_figures(&drawn, folder);
    Ok(drawn)
}

fn draw_sweep(stored: &StoredStudySweep, folder: &Path, format: Format) -> Result<(), CliError> {
    let drawn = crate::report::study::draw_sweep(stored, folder, format).map_err(failure)?;
    super::report_figures(&drawn, folder);
    Ok(())
}

/// The memory of the largest point's `[learned]` training, whose trajectories are
/// `lengths` samples long; bad input, placed at the key of its largest part, where it
/// is beyond this machine's.
fn learned_memory(
    experiment: &Experiment<StudySpec>,
    lengths: Vec<Vec<usize>>,
) -> Result<Option<crate::footprint::Bytes>, CliError> {
    let memory = crate::footprint::machine_memory();
    let threads = rayon::current_num_threads();
    let mut largest: Option<f64> = None;
    for (point, lengths) in experiment.points.iter().zip(lengths) {
        let Some(footprint) = crate::footprint::learned(&point.spec, &lengths, threads) else {
            continue;
        };
        crate::cli::beyond_memory(experiment, &point.spec.name, &footprint, memory)?;
        largest = Some(largest.unwrap_or(0.0).max(footprint.bytes()));
    }
    Ok(largest.map(crate::footprint::Bytes))
}

/// Refuses, at its key, what `spec` (a point of `experiment`) asks that its recordings
/// (each trajectory's name and time stamps) cannot give: a `[learned]` window or time
/// offset beyond them, a `[calibration.dive]` window that no trajectory outlasts.
fn within_the_recordings(
    experiment: &Experiment<StudySpec>,
    spec: &StudySpec,
    recordings: &[(&str, &[f64])],
) -> Result<(), CliError> {
    let learned = (spec.learned.as_ref())
        .and_then(|l| crate::installation::learned::beyond_the_recordings(l, recordings));
    let dive = (spec.dive.as_ref())
        .and_then(|d| crate::installation::study::dive::beyond_the_recordings(d, recordings));
    match learned.or(dive) {
        Some((key, message)) => {
            let fault = experiment.fault(&key, message);
            Err(input(crate::spec::SpecErrors::from(fault)))
        }
        None => Ok(()),
    }
}

/// `validate` of an installation spec: its faults (its recordings read and checked),
/// or what it would compute.
pub(super) fn validate(path: &Path, set: &[String]) -> Result<(), CliError> {
    let experiment = load(path, set)?;
    let mut read = Recordings::default();
    let mut lengths = Vec::new();
    for point in &experiment.points {
        let spec = &point.spec;
        let mut times = Vec::new();
        for (name, source) in &spec.trajectories {
            times.push((name.as_str(), read.read(source).map_err(input)?));
        }
        let recordings: Vec<(&str, &[f64])> = times
            .iter()
            .map(|&(name, at)| (name, read.get(at).recording.time_s.as_slice()))
            .collect();
        within_the_recordings(&experiment, spec, &recordings)?;
        lengths.push(recordings.iter().map(|(_, time_s)| time_s.len()).collect());
    }
    if let Some(memory) = learned_memory(&experiment, lengths)? {
        println!("[learned] training needs at most about {memory} of memory at its peak");
    }
    let spec = &experiment.points[0].spec;
    let points = match experiment.points.len() {
        1 => String::new(),
        n => format!(
            "{n} points of a sweep over {}; the first: ",
            experiment.swept.join(", ")
        ),
    };
    println!(
        "{}: ok (an installation study: {points}{}, {}, {})",
        path.display(),
        count(spec.trajectories.len(), "trajectory").replace("trajectorys", "trajectories"),
        count(spec.windows_s.len(), "window"),
        count(spec.methods.len() + 1, "method")
    );
    Ok(())
}
