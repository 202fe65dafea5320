//! The subcommands: `run`, `plan`, `collect`, `plot`, `compare`, `validate`, `data
//! info`, `data fetch` and `bench`. Each reads a spec through
//! [`crate::spec::load_experiment`] (or results folders), hands the work to
//! [`crate::pipeline`] or the stage it names, and reports bad input (exit code 1) apart
//! from failures while running (exit code 2) and a calibration rejected where asked
//! (exit code 3). In: the command line. Out: what the
//! stages write, and what they did on stderr.
//!
//! `args` declares the command line; `run` runs, plans and collects experiments;
//! `plot` draws and compares results folders; `inspect` checks specs and fetches
//! data; `bench` times the stages.

mod args;
mod bench;
mod calibrate;
mod inspect;
mod plot;
mod run;
mod study;

pub use args::Cli;

use crate::count;
use crate::data;
use crate::data::paired::dvl_log;
use crate::footprint::{self, Footprint};
use crate::pipeline::{Mode, Shard};
use crate::spec::{Experiment, Spec, SpecErrors, TrajectorySource, load, load_experiment};
use crate::vocab::ErrorModel;
use args::{Command, DataCommand, Drawing, Target};
use clap::Parser;
use std::path::Path;

/// Why a command did not finish.
#[derive(Debug)]
pub enum CliError {
    /// Bad spec, data or arguments: exit code 1.
    Input(anyhow::Error),
    /// A failure while running: exit code 2.
    Failure(anyhow::Error),
    /// A calibration computed and written, and rejected by `--accept` where
    /// `--fail-on-reject` asks: exit code 3.
    Rejected(anyhow::Error),
}

impl CliError {
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Input(_) => 1,
            CliError::Failure(_) => 2,
            CliError::Rejected(_) => 3,
        }
    }

    pub fn cause(&self) -> &anyhow::Error {
        match self {
            CliError::Input(e) | CliError::Failure(e) | CliError::Rejected(e) => e,
        }
    }

    pub fn into_cause(self) -> anyhow::Error {
        match self {
            CliError::Input(e) | CliError::Failure(e) | CliError::Rejected(e) => e,
        }
    }
}

fn input(error: impl Into<anyhow::Error>) -> CliError {
    CliError::Input(error.into())
}
fn failure(error: impl Into<anyhow::Error>) -> CliError {
    CliError::Failure(error.into())
}

/// An error that tells a fault in what was given from a failure while running.
trait Fault: Into<anyhow::Error> {
    fn is_input(&self) -> bool;
}

impl Fault for crate::pipeline::ExecuteError {
    fn is_input(&self) -> bool {
        crate::pipeline::ExecuteError::is_input(self)
    }
}

impl Fault for crate::operator::calibrate::CalibrateError {
    fn is_input(&self) -> bool {
        crate::operator::calibrate::CalibrateError::is_input(self)
    }
}

impl Fault for crate::operator::correct::CorrectError {
    fn is_input(&self) -> bool {
        crate::operator::correct::CorrectError::is_input(self)
    }
}

/// A command that stopped: bad input (exit 1), or a failure while running (exit 2).
fn stopped(error: impl Fault) -> CliError {
    match error.is_input() {
        true => input(error),
        false => failure(error),
    }
}

/// The variable that gives `--log-every` when the flag is not typed.
const LOG_EVERY_VARIABLE: &str = "DCNET_LOG_EVERY";

/// Refuses environment variables that stand for a flag the user did not type, naming
/// the variable: a `DCNET_LOG_EVERY` that is not a number (clap would name the
/// `--log-every` flag), a `RAYON_NUM_THREADS` that is not a count of threads (rayon
/// would ignore it and use every core).
fn check_flag_variables() -> Result<(), CliError> {
    refuse_variable(
        (LOG_EVERY_VARIABLE, "--log-every"),
        |value| value.parse::<f64>().is_ok(),
        &format!("not a number of seconds; give 0 to {MAX_LOG_EVERY_S}"),
    )?;
    refuse_variable(
        ("RAYON_NUM_THREADS", "--threads"),
        |value| value.parse::<usize>().is_ok_and(|n| n <= MAX_THREADS),
        &format!("not a number of threads; give 1 to {MAX_THREADS} (0: every core)"),
    )
}

/// Refuses `variable`'s value where `accepts` does not, saying `expected`; a typed
/// `flag` wins over the variable.
fn refuse_variable(
    (variable, flag): (&str, &str),
    accepts: fn(&str) -> bool,
    expected: &str,
) -> Result<(), CliError> {
    let typed = std::env::args_os().any(|arg| arg.to_string_lossy().starts_with(flag));
    match std::env::var_os(variable) {
        Some(value) if !typed && !accepts(&value.to_string_lossy()) => Err(input(anyhow::anyhow!(
            "{variable}={}: {expected}",
            value.to_string_lossy()
        ))),
        _ => Ok(()),
    }
}

/// `--threads` and `--log-every`, checked and set for the whole process.
fn apply_global_flags(threads: Option<usize>, log_every: Option<f64>) -> Result<(), CliError> {
    if let Some(threads) = threads {
        if !(1..=MAX_THREADS).contains(&threads) {
            return Err(input(anyhow::anyhow!(
                "--threads {threads}: give 1 to {MAX_THREADS}"
            )));
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
            .map_err(failure)?;
        let cores = std::thread::available_parallelism().map(|n| n.get());
        if let Ok(cores) = cores
            && threads > cores
        {
            eprintln!(
                "warning: --threads {threads} is more than the {cores} cores this process may \
                 use: threads that wait for each other then share cores, and training runs \
                 slower than on {cores}"
            );
        }
    }
    if threads.is_none() && std::env::var_os("RAYON_NUM_THREADS").is_some_and(|v| v == "0") {
        eprintln!(
            "RAYON_NUM_THREADS=0: every core, {} threads",
            rayon::current_num_threads()
        );
    }
    if let Some(seconds) = log_every {
        if !(0.0..=MAX_LOG_EVERY_S).contains(&seconds) {
            return Err(input(anyhow::anyhow!(
                "--log-every {seconds} (or DCNET_LOG_EVERY): give 0 to {MAX_LOG_EVERY_S} seconds"
            )));
        }
        crate::progress::set_log_every(std::time::Duration::from_secs_f64(seconds));
    }
    Ok(())
}

/// Parses the command line, then hands each command to the module that does it, one
/// line a command.
pub fn main() -> Result<(), CliError> {
    check_flag_variables()?;
    let Some(cli) = parsed()? else {
        return Ok(());
    };
    apply_global_flags(cli.threads, cli.log_every)?;
    match cli.command {
        Command::Run(args) => run::run_command(&args),
        Command::Plan(args) => {
            kind_of(&args.target.spec)?.plan(&args.target, run::parse_shard(args.shard.as_deref())?)
        }
        Command::Collect(args) => kind_of(&args.target.spec)?.collect(&args.target, &args.drawing),
        Command::Plot(args) => plot::plot(&args.results, Some(&args.out), args.format, args.metric),
        Command::Compare(args) => plot::compare_folders(&args.first, &args.second, &args.out),
        Command::Validate(args) => kind_of(&args.spec)?.validate(&args.spec, &args.overrides.set),
        Command::Calibrate(args) => calibrate::calibrate_command(&args),
        Command::Correct(args) => calibrate::correct_command(&args),
        Command::Data { command } => data_command(command),
        Command::Bench(args) => bench::bench_command(&args),
    }
}

/// The command line, or `None` where clap printed what was asked (`--help`,
/// `--version`); a command line clap refuses ends the process with exit code 1.
fn parsed() -> Result<Option<Cli>, CliError> {
    match Cli::try_parse() {
        Ok(cli) => Ok(Some(cli)),
        Err(e) if !e.use_stderr() => {
            e.print().map_err(failure)?;
            Ok(None)
        }
        Err(e) => {
            let _ = e.print();
            std::process::exit(1);
        }
    }
}

/// `data info` and `data fetch`.
fn data_command(command: DataCommand) -> Result<(), CliError> {
    match command {
        DataCommand::Info { spec, .. } if crate::data::paired::bag::is_bag(&spec) => {
            inspect::bag_info(&spec)
        }
        DataCommand::Info {
            spec, dvl_format, ..
        } if let Some(format) =
            (dvl_format.map(args::DvlFormatArg::format)).or_else(|| dvl_log::format_of(&spec)) =>
        {
            inspect::log_info(&spec, format)
        }
        DataCommand::Info {
            spec, overrides, ..
        } => inspect::info(&spec, &overrides.set),
        DataCommand::Fetch {
            dataset,
            dest,
            base_url,
        } => inspect::fetch_data(
            dataset,
            dest.as_deref().unwrap_or(Path::new(dataset.default_dest())),
            base_url.as_deref().unwrap_or(dataset.default_base_url()),
        ),
    }
}

/// Says, for each figure, where its files went or why it was not drawn.
fn report_figures(figures: &[crate::report::kit::plots::Written], folder: &Path) {
    for figure in figures {
        match &figure.caption {
            crate::report::kit::plots::Caption::Drawn(_) => eprintln!(
                "figure {}: {} in {}",
                figure.stem,
                count(figure.files.len(), "file"),
                folder.display()
            ),
            crate::report::kit::plots::Caption::NotApplicable(why) => {
                eprintln!("figure {}: not drawn, {why}", figure.stem)
            }
        }
    }
}

/// The commands that take a spec, as one kind of spec does them: the paper's
/// experiment or the study of a real installation. The spec's `kind` is read once, by
/// [`kind_of`], and the command handed to its kind.
trait SpecKind {
    fn run(&self, target: &Target, drawing: &Drawing, mode: Mode) -> Result<(), CliError>;
    fn plan(&self, target: &Target, shard: Option<Shard>) -> Result<(), CliError>;
    fn collect(&self, target: &Target, drawing: &Drawing) -> Result<(), CliError>;
    fn validate(&self, spec: &Path, set: &[String]) -> Result<(), CliError>;
    /// The spec as the paper's, for `data info` and `bench`, which only it has.
    fn paper_spec(&self, spec: &Path, set: &[String]) -> Result<Spec, CliError>;
}

/// A spec without `kind`: the paper's experiment, or a sweep of it.
struct PaperKind;

impl SpecKind for PaperKind {
    fn run(&self, target: &Target, drawing: &Drawing, mode: Mode) -> Result<(), CliError> {
        run::run(target, drawing, mode)
    }
    fn plan(&self, target: &Target, shard: Option<Shard>) -> Result<(), CliError> {
        run::plan(target, shard)
    }
    fn collect(&self, target: &Target, drawing: &Drawing) -> Result<(), CliError> {
        run::collect(target, drawing)
    }
    fn validate(&self, spec: &Path, set: &[String]) -> Result<(), CliError> {
        inspect::validate(spec, set)
    }
    fn paper_spec(&self, spec: &Path, set: &[String]) -> Result<Spec, CliError> {
        load(spec, set).map_err(input)
    }
}

/// A spec with `kind = "installation"`: a study of a real installation, or a sweep of it.
struct StudyKind;

impl SpecKind for StudyKind {
    fn run(&self, target: &Target, drawing: &Drawing, mode: Mode) -> Result<(), CliError> {
        study::run(target, drawing, mode)
    }
    fn plan(&self, target: &Target, shard: Option<Shard>) -> Result<(), CliError> {
        study::plan(target, shard)
    }
    fn collect(&self, target: &Target, drawing: &Drawing) -> Result<(), CliError> {
        study::collect(target, drawing)
    }
    fn validate(&self, spec: &Path, set: &[String]) -> Result<(), CliError> {
        study::validate(spec, set)
    }
    fn paper_spec(&self, spec: &Path, _set: &[String]) -> Result<Spec, CliError> {
        Err(input(anyhow::anyhow!(
            "{}: an installation study has no training data to inspect nor training to bench: `dcnet-exp validate` checks it, `dcnet-exp run` runs it",
            spec.display()
        )))
    }
}

/// The kind of the spec at `path`, from its `kind` key; another kind is refused.
fn kind_of(path: &Path) -> Result<&'static dyn SpecKind, CliError> {
    use crate::installation::study::spec::KIND;
    match crate::spec::declared_kind(path).map_err(input)? {
        None => Ok(&PaperKind),
        Some(kind) if kind == KIND => Ok(&StudyKind),
        Some(kind) => Err(input(anyhow::anyhow!(
            "{}: kind: {kind:?} is not a kind of spec: leave it out for the paper's experiments, or give {KIND:?} for a study of a real installation",
            path.display()
        ))),
    }
}

/// The paper spec at `path` with `set`, for the commands that only a paper spec has
/// (its training data, its training bench).
fn load_spec(path: &Path, set: &[String]) -> Result<Spec, CliError> {
    kind_of(path)?.paper_spec(path, set)
}

/// The longest interval `--log-every` may ask for: a day.
const MAX_LOG_EVERY_S: f64 = 86_400.0;

/// The most worker threads `--threads` may ask for.
const MAX_THREADS: usize = 1024;

/// The experiment a command works on: its spec with `--set`, and `--backend` checked
/// as itself before it overrides `training.backend`; OUT, when it exists, must be a
/// folder.
fn load_target(target: &Target) -> Result<Experiment, CliError> {
    let mut set = target.overrides.set.clone();
    if let Some(backend) = &target.backend {
        backend
            .parse::<crate::vocab::Backend>()
            .map_err(|message| input(anyhow::anyhow!("--backend {backend}: {message}")))?;
        set.push(format!("training.backend={backend:?}"));
    }
    if target.out.exists() && !target.out.is_dir() {
        return Err(input(anyhow::anyhow!(
            "--out {}: is a file; results go into a folder",
            target.out.display()
        )));
    }
    let experiment = load_experiment(&target.spec, &set).map_err(input)?;
    footprints(&experiment)?;
    Ok(experiment)
}

/// About how many seconds `trainings` take on this machine's threads, each given by
/// its spec and its trajectories' lengths, from one batch timed per model shape.
fn training_seconds(trainings: &[(&Spec, Vec<usize>)]) -> Result<f64, CliError> {
    let threads = rayon::current_num_threads();
    let mut timed: Vec<(String, f64)> = Vec::new();
    let mut seconds = 0.0;
    for (spec, lengths) in trainings {
        let shape = format!(
            "{:?} {} {} {}",
            spec.model,
            spec.training.backend,
            spec.training.batch_size,
            spec.dataset.window_samples
        );
        let per_batch = match timed.iter().find(|(s, _)| *s == shape) {
            Some(&(_, per_batch)) => per_batch,
            None => {
                let per_batch =
                    crate::train::seconds_per_batch(spec, ErrorModel::Em5).map_err(failure)?;
                timed.push((shape, per_batch));
                per_batch
            }
        };
        seconds += footprint::training_seconds(spec, lengths, 1, 1, per_batch);
    }
    Ok(seconds / threads.clamp(1, trainings.len().max(1)) as f64)
}

/// A duration as a person reads it, to the second below an hour and to the minute
/// above: `4m 12s`, `2h 10m`.
fn about(seconds: f64) -> String {
    let whole = if seconds < 3600.0 {
        seconds.round()
    } else {
        (seconds / 60.0).round() * 60.0
    };
    humantime::format_duration(std::time::Duration::from_secs_f64(whole)).to_string()
}

/// Refuses a point of `experiment` (named `point` in a sweep) whose `footprint` is
/// beyond this machine's `memory`: bad input, placed at the key of its largest part.
fn beyond_memory<S>(
    experiment: &Experiment<S>,
    point: &str,
    footprint: &Footprint,
    memory: u64,
) -> Result<(), CliError> {
    let Some((key, message)) = footprint.refusal(memory) else {
        return Ok(());
    };
    let message = match experiment.is_sweep() {
        true => format!("point {point}: {message}"),
        false => message,
    };
    Err(input(SpecErrors::from(experiment.fault(&key, message))))
}

/// What each point of `experiment` asks of this machine, and its trajectories'
/// lengths, known before anything is allocated; a point beyond this machine's memory is bad input, placed at the key of
/// its largest part.
/// The spec's warnings are printed here, once per command that loads a spec.
fn footprints(experiment: &Experiment) -> Result<Vec<(Footprint, Vec<usize>)>, CliError> {
    for warning in experiment.warnings() {
        eprintln!("warning: {warning}");
    }
    let memory = footprint::machine_memory();
    let threads = rayon::current_num_threads();
    let mut known: Option<(&[TrajectorySource], Vec<usize>)> = None;
    let mut footprints = Vec::new();
    for point in &experiment.points {
        let spec = &point.spec;
        let lengths = match &known {
            Some((sources, lengths)) if *sources == &spec.trajectories[..] => lengths.clone(),
            _ => data::lengths(spec).map_err(input)?,
        };
        let footprint = Footprint::of(spec, &lengths, threads);
        beyond_memory(experiment, &spec.name, &footprint, memory)?;
        known = Some((&spec.trajectories, lengths.clone()));
        footprints.push((footprint, lengths));
    }
    Ok(footprints)
}
