//! The subcommands: `run`, `plan`, `collect`, `plot`, `compare`, `validate`, `data
//! info`, `data fetch` and `bench`. Each reads a spec through
//! [`crate::spec::load_experiment`] (or results folders), hands the work to
//! [`crate::pipeline`] or the stage it names, and reports bad input (exit code 1) apart
//! from failures while running (exit code 2).

use crate::compare;
use crate::data::{fetch, load_trajectories};
use crate::dataset::{self, TrainingSet, window_starts};
use crate::evaluate::run_protocol;
use crate::pipeline::{Mode, Outcome, Plan, Shard, Task, execute};
use crate::plots::{self, Format, Metric};
use crate::report;
use crate::results::read::StoredRun;
use crate::spec::{Experiment, Origin, Spec, load, load_experiment};
use crate::sweep;
use crate::tables;
use crate::train::{self, TrainError};
use crate::vocab::{ErrorModel, EstimatorKind};
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, Parser)]
#[command(
    name = "dcnet-exp",
    version,
    about = "Reproduce and extend the DCNet DVL-calibration experiments"
)]
pub struct Cli {
    /// Worker threads [default: all cores, or RAYON_NUM_THREADS]; results do not depend on it
    #[arg(long, global = true)]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run an experiment, or every point of its sweep, doing only what is not done yet
    Run {
        #[command(flatten)]
        target: Target,
        #[command(flatten)]
        drawing: Drawing,
        /// Run only shard K of N (0 ≤ K < N) of the tasks and no results; `--shard N`
        /// takes K from SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX
        #[arg(long, value_name = "K/N")]
        shard: Option<String>,
        /// Recompute every task, cached or not
        #[arg(long)]
        force: bool,
    },
    /// List every task a run would do, each marked done or to do; changes nothing
    Plan {
        #[command(flatten)]
        target: Target,
        /// List only the tasks of shard K of N
        #[arg(long, value_name = "K/N")]
        shard: Option<String>,
    },
    /// Write the results of a sharded run once every shard has finished
    Collect {
        #[command(flatten)]
        target: Target,
        #[command(flatten)]
        drawing: Drawing,
    },
    /// Draw the figures and write report.md and report.tex from a results folder, re-running nothing
    Plot {
        /// A results folder written by `run`, such as results/paper, or a sweep's
        results: PathBuf,
        /// Figures go to OUT/<name>/
        #[arg(long, default_value = "plots")]
        out: PathBuf,
        /// Write each figure as PNG, SVG or both
        #[arg(long, value_enum, default_value_t = Format::Both)]
        format: Format,
        /// What a sweep's figures plot against each swept value
        #[arg(long, value_enum, default_value_t = Metric::EvaluationRmse)]
        metric: Metric,
    },
    /// Compare two results folders (or two sweep points) as Markdown: the spec keys that
    /// differ, every cell with A, B and B − A, differences beyond 2 standard errors marked
    Compare {
        /// The first results folder, such as results/quick or results/<sweep>/<point>
        #[arg(value_name = "A")]
        first: PathBuf,
        /// The second results folder
        #[arg(value_name = "B")]
        second: PathBuf,
        /// Also write the Markdown to FILE
        #[arg(long, value_name = "FILE", default_value = compare::DEFAULT_FILE)]
        out: PathBuf,
    },
    /// Check a spec (every point of its sweep) and its data files without running anything
    Validate {
        spec: PathBuf,
        #[command(flatten)]
        overrides: Overrides,
    },
    /// Inspect or download the data
    Data {
        #[command(subcommand)]
        command: DataCommand,
    },
    /// Time the dataset generation, the Monte Carlo protocol and DCNet training of a spec
    Bench {
        spec: PathBuf,
        /// Timed repetitions of each stage
        #[arg(long, default_value_t = 5)]
        repeat: usize,
        /// Training batches timed per model
        #[arg(long, default_value_t = 40)]
        training_batches: usize,
        /// The PyTorch peer script (torch_dcnet.py): times the same network in PyTorch
        /// in the same arrangements, side by side
        #[arg(long, value_name = "SCRIPT")]
        pytorch: Option<PathBuf>,
        #[command(flatten)]
        overrides: Overrides,
    },
}

/// The spec a command works on and where its results go.
#[derive(Debug, clap::Args)]
struct Target {
    spec: PathBuf,
    /// Results go to OUT/<name>/, the cache to OUT/.cache/
    #[arg(long, default_value = "results")]
    out: PathBuf,
    /// burn CPU backend for DCNet, overriding training.backend: flex or ndarray
    #[arg(long)]
    backend: Option<String>,
    #[command(flatten)]
    overrides: Overrides,
}

/// Where the figures of the results a command writes go.
#[derive(Debug, clap::Args)]
struct Drawing {
    /// Figures go to PLOTS/<name>/
    #[arg(long, default_value = "plots")]
    plots: PathBuf,
    /// Write the results and the reports but draw no figures
    #[arg(long)]
    no_plots: bool,
}

impl Drawing {
    fn folder(&self) -> Option<&Path> {
        (!self.no_plots).then_some(self.plots.as_path())
    }
}

#[derive(Debug, Subcommand)]
enum DataCommand {
    /// Trajectories, lengths, mean speeds, window counts and dataset size of a spec
    Info {
        spec: PathBuf,
        #[command(flatten)]
        overrides: Overrides,
    },
    /// Download the Snapir recordings (V.npy, V_test.npy) and check their SHA-256
    Fetch {
        /// Folder to write the files to
        #[arg(long, default_value = fetch::DEFAULT_DEST)]
        dest: PathBuf,
        /// Where the files are served (the BeamsNet repository by default)
        #[arg(long, default_value = fetch::DEFAULT_BASE_URL)]
        base_url: String,
    },
}

#[derive(Debug, clap::Args)]
struct Overrides {
    /// Override a spec key, e.g. --set calibration.monte_carlo_runs=50 (value read as TOML)
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
}

/// Why a command did not finish.
#[derive(Debug)]
pub enum CliError {
    /// Bad spec, data or arguments: exit code 1.
    Input(anyhow::Error),
    /// A failure while running: exit code 2.
    Failure(anyhow::Error),
}

impl CliError {
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Input(_) => 1,
            CliError::Failure(_) => 2,
        }
    }

    pub fn cause(&self) -> &anyhow::Error {
        match self {
            CliError::Input(e) | CliError::Failure(e) => e,
        }
    }

    pub fn into_cause(self) -> anyhow::Error {
        match self {
            CliError::Input(e) | CliError::Failure(e) => e,
        }
    }
}

fn input(error: impl Into<anyhow::Error>) -> CliError {
    CliError::Input(error.into())
}
fn failure(error: impl Into<anyhow::Error>) -> CliError {
    CliError::Failure(error.into())
}

pub fn main() -> Result<(), CliError> {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => {
            e.print().map_err(failure)?;
            return Ok(());
        }
        Err(e) => {
            let _ = e.print();
            std::process::exit(1);
        }
    };
    if let Some(threads) = cli.threads {
        if threads == 0 {
            return Err(input(anyhow::anyhow!("--threads must be at least 1")));
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global()
            .map_err(failure)?;
    }
    match cli.command {
        Command::Run {
            target,
            drawing,
            shard,
            force,
        } => run(&target, &drawing, shard.as_deref(), force),
        Command::Plan { target, shard } => plan(&target, shard.as_deref()),
        Command::Collect { target, drawing } => collect(&target, &drawing),
        Command::Plot {
            results,
            out,
            format,
            metric,
        } => plot(&results, Some(&out), format, metric),
        Command::Compare { first, second, out } => compare_folders(&first, &second, &out),
        Command::Validate { spec, overrides } => validate(&spec, &overrides.set),
        Command::Data {
            command: DataCommand::Info { spec, overrides },
        } => info(&spec, &overrides.set),
        Command::Data {
            command: DataCommand::Fetch { dest, base_url },
        } => fetch_data(&dest, &base_url),
        Command::Bench {
            spec,
            repeat,
            training_batches,
            pytorch,
            overrides,
        } => bench(
            &spec,
            repeat,
            training_batches,
            pytorch.as_deref(),
            &overrides.set,
        ),
    }
}

fn load_spec(path: &Path, set: &[String]) -> Result<Spec, CliError> {
    load(path, set).map_err(input)
}

fn load_target(target: &Target) -> Result<Experiment, CliError> {
    let mut set = target.overrides.set.clone();
    if let Some(backend) = &target.backend {
        set.push(format!("training.backend={backend:?}"));
    }
    load_experiment(&target.spec, &set).map_err(input)
}

fn parse_shard(shard: Option<&str>) -> Result<Option<Shard>, CliError> {
    shard
        .map(|text| Shard::parse(text, |variable| std::env::var(variable).ok()))
        .transpose()
        .map_err(|message| input(anyhow::anyhow!(message)))
}

fn run(
    target: &Target,
    drawing: &Drawing,
    shard: Option<&str>,
    force: bool,
) -> Result<(), CliError> {
    let experiment = load_target(target)?;
    let plan = Plan::new(&experiment, &target.out).map_err(input)?;
    let mode = match parse_shard(shard)? {
        Some(shard) => Mode::Shard { shard, force },
        None => Mode::All { force },
    };
    let to_do = plan.to_do(mode);
    let total = plan.tasks().len();
    let folder = target.out.join(&experiment.name);
    let whose = match mode {
        Mode::Shard { shard, .. } => format!("{} shard {shard}", experiment.name),
        _ => experiment.name.clone(),
    };
    if to_do.is_empty() {
        match mode {
            Mode::Shard { .. } => eprintln!("nothing to do: every task of {whose} is done"),
            _ => eprintln!(
                "nothing to do: every task of {whose} is done; the results in {} are current",
                folder.display()
            ),
        }
        return failed_models(plan.failures(mode));
    }
    eprintln!(
        "{whose}: {} to do ({total} in the plan)",
        tasks(to_do.len())
    );
    let outcome = execute(&plan, mode, &to_do).map_err(failure)?;
    if let Mode::Shard { shard, .. } = mode {
        eprintln!(
            "shard {shard}: {} done; once every shard has finished, `dcnet-exp collect {}` writes the results",
            tasks(outcome.done),
            target.spec.display()
        );
    } else {
        finish(&experiment, &outcome, drawing)?;
    }
    failed_models(plan.failures(mode))
}

/// "1 task", "31 tasks".
fn tasks(count: usize) -> String {
    if count == 1 {
        "1 task".into()
    } else {
        format!("{count} tasks")
    }
}

/// Lists the tasks of a run, shard or not, with their state.
fn plan(target: &Target, shard: Option<&str>) -> Result<(), CliError> {
    let experiment = load_target(target)?;
    let plan = Plan::new(&experiment, &target.out).map_err(input)?;
    let shard = parse_shard(shard)?;
    let mut table = comfy_table::Table::new();
    table.load_preset(comfy_table::presets::ASCII_MARKDOWN);
    let mut header = vec!["task", "key", "status"];
    if experiment.is_sweep() {
        header.insert(1, "point");
    }
    table.set_header(header);
    let mode = match shard {
        Some(shard) => Mode::Shard {
            shard,
            force: false,
        },
        None => Mode::All { force: false },
    };
    let to_do = plan.to_do(mode);
    let mut listed = 0;
    for task in plan.tasks() {
        let in_scope = match (shard, task) {
            (Some(shard), Task::Training(_) | Task::Block(_)) => plan.in_shard(task, shard),
            (Some(_), Task::Dataset(_)) => to_do.contains(&task),
            (Some(_), _) => false,
            (None, _) => true,
        };
        if !in_scope {
            continue;
        }
        listed += 1;
        let status = plan.status(task);
        let mut row = vec![
            plan.label(task),
            plan.key(task)
                .map(|k| k[..16].to_string())
                .unwrap_or_default(),
            status.to_string(),
        ];
        if experiment.is_sweep() {
            let point = plan
                .point_of(task)
                .map(|p| sweep::point_folder(&plan.spec(p).name).to_string())
                .unwrap_or_default();
            row.insert(1, point);
        }
        table.add_row(row);
    }
    println!("{table}");
    let scope = match shard {
        Some(shard) => format!("shard {shard} of {}", experiment.name),
        None => experiment.name.clone(),
    };
    println!(
        "{scope}: {}, {} to do; cache in {}",
        tasks(listed),
        to_do.len(),
        crate::cache::root(&target.out).display()
    );
    Ok(())
}

/// Writes the results of a sharded run from the cache the shards filled.
fn collect(target: &Target, drawing: &Drawing) -> Result<(), CliError> {
    let experiment = load_target(target)?;
    let plan = Plan::new(&experiment, &target.out).map_err(input)?;
    let outcome = execute(&plan, Mode::Collect, &plan.to_do(Mode::Collect)).map_err(failure)?;
    if outcome.done == 0 {
        eprintln!(
            "nothing to do: the results in {} are current",
            target.out.join(&experiment.name).display()
        );
    } else {
        finish(&experiment, &outcome, drawing)?;
    }
    failed_models(plan.failures(Mode::Collect))
}

/// Prints the tables of a single run, and draws the figures and writes the reports of
/// what was written.
fn finish(experiment: &Experiment, outcome: &Outcome, drawing: &Drawing) -> Result<(), CliError> {
    for folder in &outcome.written {
        if !experiment.is_sweep() {
            let stored = StoredRun::read(folder).map_err(failure)?;
            println!(
                "{}",
                tables::calibration_table(
                    &stored.calibration,
                    &stored.spec.calibration.trajectory,
                    stored.spec.calibration.monte_carlo_runs
                )
            );
            println!("{}", tables::evaluation_table(&stored.evaluation));
        }
        eprintln!("results written to {}", folder.display());
        plot_run(folder, drawing.folder(), Format::Both).map_err(|e| failure(e.into_cause()))?;
    }
    if let Some(folder) = &outcome.sweep {
        eprintln!(
            "sweep table written to {}",
            folder.join(sweep::TABLE).display()
        );
        plot_sweep(
            folder,
            drawing.folder(),
            Format::Both,
            Metric::EvaluationRmse,
        )
        .map_err(|e| failure(e.into_cause()))?;
    }
    Ok(())
}

/// Every model that failed to train, one per line, as an error; the results hold all
/// the others.
fn failed_models(failures: Vec<String>) -> Result<(), CliError> {
    if failures.is_empty() {
        return Ok(());
    }
    Err(failure(anyhow::anyhow!(
        "{}\nthe results leave these models out; --force trains them again",
        failures.join("\n")
    )))
}

/// Draws the figures of a results folder, a single run's or a sweep's, and writes the
/// reports.
fn plot(
    results: &Path,
    out: Option<&Path>,
    format: Format,
    metric: Metric,
) -> Result<(), CliError> {
    if !results.join(sweep::INDEX).is_file() {
        return plot_run(results, out, format);
    }
    let index = sweep::read_index(results).map_err(input)?;
    for point in &index.points {
        plot_run(&results.join(point), out, format)?;
    }
    plot_sweep(results, out, format, metric)
}

/// Reads the results folder back, draws its figures into `out/<name>/` (none when
/// `out` is `None`) and writes its report.
fn plot_run(results: &Path, out: Option<&Path>, format: Format) -> Result<(), CliError> {
    let stored = StoredRun::read(results).map_err(input)?;
    let figures = match out {
        Some(out) => {
            let folder = out.join(&stored.spec.name);
            let figures = plots::write_all(&stored, &folder, format).map_err(failure)?;
            report_figures(&figures, &folder);
            figures
        }
        None => Vec::new(),
    };
    let [markdown, tex] = report::write(&stored, &figures).map_err(failure)?;
    eprintln!(
        "report written to {} and {}",
        markdown.display(),
        tex.display()
    );
    Ok(())
}

/// Draws a sweep's figures into `out/<name>/`.
fn plot_sweep(
    results: &Path,
    out: Option<&Path>,
    format: Format,
    metric: Metric,
) -> Result<(), CliError> {
    let Some(out) = out else { return Ok(()) };
    let stored = sweep::read(results).map_err(input)?;
    let folder = out.join(&stored.index.name);
    let figures = plots::write_sweep(&stored, metric, &folder, format).map_err(failure)?;
    report_figures(&figures, &folder);
    Ok(())
}

fn report_figures(figures: &[plots::Written], folder: &Path) {
    for figure in figures {
        match &figure.caption {
            Ok(_) => eprintln!(
                "figure {}: {} files in {}",
                figure.stem,
                figure.files.len(),
                folder.display()
            ),
            Err(why) => eprintln!("figure {}: not drawn, {why}", figure.stem),
        }
    }
}

/// Prints the comparison of two results folders and writes it to `out`.
fn compare_folders(first: &Path, second: &Path, out: &Path) -> Result<(), CliError> {
    if out.is_dir() {
        return Err(input(anyhow::anyhow!(
            "--out {}: is a folder; name the file to write the comparison to",
            out.display()
        )));
    }
    let first = compare::read(first).map_err(input)?;
    let second = compare::read(second).map_err(input)?;
    let markdown = compare::render(&first, &second);
    print!("{markdown}");
    compare::write(out, &markdown).map_err(failure)?;
    eprintln!("comparison written to {}", out.display());
    Ok(())
}

fn validate(spec_path: &Path, set: &[String]) -> Result<(), CliError> {
    let experiment = load_experiment(spec_path, set).map_err(input)?;
    for point in &experiment.points {
        let spec = &point.spec;
        let trajectories = load_trajectories(spec).map_err(input)?;
        let windows =
            dataset::windows_per_combination(spec, &trajectories) * spec.grid.points().len();
        println!(
            "{}: ok ({} trajectories, {} training windows, {} DVLs, {} Monte Carlo runs)",
            if experiment.is_sweep() {
                format!("{} point {}", spec_path.display(), spec.name)
            } else {
                spec_path.display().to_string()
            },
            trajectories.len(),
            windows,
            spec.dvls.len(),
            spec.calibration.monte_carlo_runs
        );
    }
    Ok(())
}

fn info(spec_path: &Path, set: &[String]) -> Result<(), CliError> {
    let spec = load_spec(spec_path, set)?;
    let trajectories = load_trajectories(&spec).map_err(input)?;
    let mut table = comfy_table::Table::new();
    table.load_preset(comfy_table::presets::ASCII_MARKDOWN);
    table.set_header([
        "trajectory",
        "role",
        "source",
        "samples",
        "duration min",
        "mean speed m/s",
        "windows",
    ]);
    for (index, (source, trajectory)) in spec.trajectories.iter().zip(&trajectories).enumerate() {
        let roles = spec.roles(index);
        let origin = match &source.origin {
            Origin::File {
                path,
                samples: Some([start, end]),
                ..
            } => format!("{} [{start}, {end})", file_name(path)),
            Origin::File {
                path,
                samples: None,
                ..
            } => file_name(path),
            Origin::Synthetic { .. } => "synthetic".to_string(),
        };
        let len = trajectory.ground_truth.len();
        let windows = if roles.contains(&"train") {
            window_starts(len, spec.dataset.window, spec.dataset.stride)
                .count()
                .to_string()
        } else {
            String::new()
        };
        table.add_row(vec![
            trajectory.name.clone(),
            roles.join(", "),
            origin,
            len.to_string(),
            format!("{:.1}", len as f64 / spec.sample_rate_hz / 60.0),
            format!("{:.2}", trajectory.mean_speed_m_s()),
            windows,
        ]);
    }
    println!("{table}");
    let combinations = spec.grid.points().len();
    let per_combination = dataset::windows_per_combination(&spec, &trajectories);
    let windows = combinations * per_combination;
    let validation =
        combinations * (spec.dataset.validation_fraction * per_combination as f64).round() as usize;
    println!(
        "grid: {} scale × {} bias × {} noise = {combinations} combinations",
        spec.grid.scale_pct.len(),
        spec.grid.bias_cm_s.len(),
        spec.grid.noise_cm_s.len()
    );
    println!(
        "windows: {per_combination} per combination × {combinations} = {windows} ({} train, {validation} validation), {} s long every {} s",
        windows - validation,
        spec.dataset.window as f64 / spec.sample_rate_hz,
        spec.dataset.stride as f64 / spec.sample_rate_hz
    );
    if let Some(published) = spec.dataset.published_windows {
        println!(
            "published: {published} windows; this spec makes {:.3} of that",
            windows as f64 / published as f64
        );
    }
    println!(
        "dataset size: {} bytes (f32 inputs and targets, one split flag per window)",
        TrainingSet::size_bytes(windows, spec.dataset.window)
    );
    Ok(())
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn fetch_data(dest: &Path, base_url: &str) -> Result<(), CliError> {
    for outcome in fetch::fetch(base_url, dest).map_err(failure)? {
        match outcome {
            fetch::Outcome::Downloaded(path) => {
                eprintln!("downloaded {} (sha256 checked)", path.display())
            }
            fetch::Outcome::AlreadyPresent(path) => {
                eprintln!("{} is already there (sha256 checked)", path.display())
            }
        }
    }
    Ok(())
}

fn bench(
    spec_path: &Path,
    repeat: usize,
    training_batches: usize,
    pytorch: Option<&Path>,
    set: &[String],
) -> Result<(), CliError> {
    let spec = load_spec(spec_path, set)?;
    if let Some(script) = pytorch {
        pytorch_ready(&spec, script).map_err(|e| input(anyhow::anyhow!(e)))?;
    }
    let trajectories = load_trajectories(&spec).map_err(input)?;
    let repeat = repeat.max(1);
    let time = |f: &dyn Fn()| {
        let mut seconds: Vec<f64> = (0..repeat)
            .map(|_| {
                let clock = Instant::now();
                f();
                clock.elapsed().as_secs_f64()
            })
            .collect();
        seconds.sort_by(f64::total_cmp);
        (seconds[0], seconds[seconds.len() / 2])
    };
    let hidden = indicatif::ProgressBar::hidden();
    let windows = dataset::windows_per_combination(&spec, &trajectories) * spec.grid.points().len();
    let (best, median) = time(&|| {
        std::hint::black_box(dataset::generate(&spec, &trajectories, &hidden));
    });
    println!(
        "dataset generation: {windows} windows, best {best:.3} s, median {median:.3} s over {repeat} runs, {} threads ({:.0} windows/s)",
        rayon::current_num_threads(),
        windows as f64 / best
    );
    let kinds: Vec<String> = spec
        .kinds
        .iter()
        .filter(|k| **k != EstimatorKind::Dcnet)
        .map(ToString::to_string)
        .collect();
    let (best, median) = time(&|| {
        std::hint::black_box(run_protocol(&spec, &trajectories, &[], &hidden));
    });
    println!(
        "protocol: {} runs × {} DVLs, estimators {}, best {best:.3} s, median {median:.3} s over {repeat} runs, {} threads",
        spec.calibration.monte_carlo_runs,
        spec.dvls.len(),
        kinds.join(", "),
        rayon::current_num_threads()
    );
    let set = dataset::generate(&spec, &trajectories, &hidden);
    let ours = bench_training(&spec, &set, training_batches).map_err(failure)?;
    let peer = pytorch
        .map(|script| bench_pytorch(&spec, script, training_batches))
        .transpose()
        .map_err(|e| failure(anyhow::anyhow!(e)))?;
    print_training_bench(&spec, &ours, peer.as_ref());
    Ok(())
}

/// Training samples/s in the two arrangements both tools can take: one model on one
/// thread, and one model per core, all training at once (as `run` trains).
struct TrainingRates {
    one_thread: f64,
    one_per_core: f64,
}

/// The PyTorch peer's samples/s: its two arrangements of [`TrainingRates`], and one
/// process spreading one model over every core.
struct PeerRates {
    rates: TrainingRates,
    one_model_all_threads: f64,
}

/// Training samples/s of the spec's model and batch size on its backend, each model on
/// a pool of one thread, as `run` trains.
fn bench_training(
    spec: &Spec,
    set: &TrainingSet,
    batches: usize,
) -> Result<TrainingRates, TrainError> {
    let threads = rayon::current_num_threads();
    let error_model = *spec.error_models.last().unwrap_or(&ErrorModel::Em5);
    let hidden = indicatif::ProgressBar::hidden();
    let run_model = |seed_offset: u64| -> Result<usize, TrainError> {
        let mut spec = spec.clone();
        spec.seed += seed_offset;
        let order = train::epoch_order(&spec, set, error_model, 1);
        let order = &order[..order.len().min(batches * spec.training.batch_size)];
        let mut state = train::State::new(&spec, error_model);
        train::one_thread_pool().install(|| {
            train::train_pass(&spec, set, error_model, &mut state, 1, order, &hidden)
        })?;
        Ok(order.len())
    };
    let clock = Instant::now();
    let one_thread = run_model(0)? as f64 / clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let done = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads as u64)
            .map(|i| scope.spawn(move || run_model(i)))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a training thread panicked"))
            .sum::<Result<usize, _>>()
    })?;
    Ok(TrainingRates {
        one_thread,
        one_per_core: done as f64 / clock.elapsed().as_secs_f64(),
    })
}

/// Whether the PyTorch peer can run before anything is timed: the script is there,
/// python3 imports torch, and the spec has the only shapes the script builds.
fn pytorch_ready(spec: &Spec, script: &Path) -> Result<(), String> {
    if !script.is_file() {
        return Err(format!("--pytorch: {} is not a file", script.display()));
    }
    let import = std::process::Command::new("python3")
        .args(["-c", "import torch"])
        .output()
        .map_err(|e| format!("--pytorch: cannot run python3: {e}"))?;
    if !import.status.success() {
        return Err(format!(
            "--pytorch: python3 cannot import torch (pip install torch):\n{}",
            String::from_utf8_lossy(&import.stderr).trim_end()
        ));
    }
    let m = &spec.model;
    let [w1, w2, w3] = m.fc_widths;
    if spec.dataset.window != 10
        || m.conv1d_kernel_size != 2
        || (w2, w3) != (w1 / 2, w1 / 4)
        || m.activation != crate::vocab::Activation::Tanh
        || m.dropout != 0.3
        || m.leaky_relu_slope != 0.05
    {
        return Err(format!(
            "--pytorch: the peer script builds windows of 10 samples, Conv1d kernels of 2, FC widths [w, w/2, w/4] with tanh, dropout 0.3 and LeakyReLU slope 0.05; the spec has {} samples, kernel {}, FC {:?} with {}, dropout {} and slope {}",
            spec.dataset.window,
            m.conv1d_kernel_size,
            m.fc_widths,
            m.activation,
            m.dropout,
            m.leaky_relu_slope
        ));
    }
    Ok(())
}

/// Runs the PyTorch peer `script` with the spec's sizes in each arrangement.
fn bench_pytorch(spec: &Spec, script: &Path, batches: usize) -> Result<PeerRates, String> {
    let threads = rayon::current_num_threads();
    let run = |processes: usize, threads_each: usize| -> Result<f64, String> {
        let output = std::process::Command::new("python3")
            .arg(script)
            .args(["--processes", &processes.to_string()])
            .args(["--threads", &threads_each.to_string()])
            .args(["--batches", &batches.to_string()])
            .args(["--batch", &spec.training.batch_size.to_string()])
            .args(["--channels", &spec.model.conv_channels.to_string()])
            .args(["--width", &spec.model.fc_widths[0].to_string()])
            .output()
            .map_err(|e| format!("python3 {}: {e}", script.display()))?;
        let stdout = String::from_utf8_lossy(&output.stdout);
        if !output.status.success() {
            return Err(format!(
                "python3 {} failed ({}):\n{}{}",
                script.display(),
                output.status,
                stdout,
                String::from_utf8_lossy(&output.stderr)
            ));
        }
        stdout
            .lines()
            .find_map(|line| line.strip_prefix("pytorch: "))
            .and_then(|rest| rest.split_whitespace().next())
            .and_then(|rate| rate.parse().ok())
            .ok_or_else(|| {
                format!(
                    "python3 {} printed no samples/s:\n{}{}",
                    script.display(),
                    stdout,
                    String::from_utf8_lossy(&output.stderr)
                )
            })
    };
    Ok(PeerRates {
        rates: TrainingRates {
            one_thread: run(1, 1)?,
            one_per_core: run(threads, 1)?,
        },
        one_model_all_threads: run(1, threads)?,
    })
}

fn print_training_bench(spec: &Spec, ours: &TrainingRates, peer: Option<&PeerRates>) {
    let threads = rayon::current_num_threads();
    let backend = spec.training.backend;
    println!(
        "training: batch {}, {} conv channels, FC {:?}",
        spec.training.batch_size, spec.model.conv_channels, spec.model.fc_widths
    );
    let mut table = comfy_table::Table::new();
    table.load_preset(comfy_table::presets::ASCII_MARKDOWN);
    let rate = |r: f64| format!("{r:.0}");
    let mut header = vec![
        "arrangement".to_string(),
        format!("dcnet-exp ({backend}) samples/s"),
    ];
    let mut rows = vec![
        vec!["one model, one thread".to_string(), rate(ours.one_thread)],
        vec![
            format!("{threads} models, one per core"),
            rate(ours.one_per_core),
        ],
        vec![format!("one model over {threads} threads"), "-".to_string()],
    ];
    if let Some(peer) = peer {
        header.push("PyTorch samples/s".to_string());
        rows[0].push(rate(peer.rates.one_thread));
        rows[1].push(rate(peer.rates.one_per_core));
        rows[2].push(rate(peer.one_model_all_threads));
    }
    table.set_header(header);
    for row in rows {
        table.add_row(row);
    }
    println!("{table}");
    if let Some(peer) = peer {
        let best_peer = peer.rates.one_per_core.max(peer.one_model_all_threads);
        println!(
            "on all {threads} cores: dcnet-exp {:.0} samples/s, PyTorch at its best {best_peer:.0}: {:.2}×",
            ours.one_per_core,
            ours.one_per_core / best_peer
        );
    }
}
