//! The subcommands: `run`, `validate`, `data info`, `data fetch` and `bench`. Each
//! reads a spec through [`crate::spec::load`], runs the stages it needs, and reports
//! bad input (exit code 1) apart from failures while running (exit code 2).

use crate::checkpoint::{ModelStore, Provenance, train_cached};
use crate::data::{fetch, load_trajectories};
use crate::dataset::{self, TrainingSet, window_starts};
use crate::estimators::{ErrorModel, EstimatorKind};
use crate::evaluate::run_protocol;
use crate::plots::{self, Format};
use crate::progress::bar;
use crate::report;
use crate::results::read::StoredRun;
use crate::results::{self, Manifest, StageSeconds};
use crate::spec::{Origin, Spec, load};
use crate::tables;
use crate::train::{self, Backend, TrainError, Trained};
use anyhow::Context;
use clap::{Parser, Subcommand};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::{Instant, SystemTime};

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
    /// Run an experiment: dataset, Monte Carlo calibration and evaluation, results
    Run {
        spec: PathBuf,
        /// Results go to OUT/<name>/
        #[arg(long, default_value = "results")]
        out: PathBuf,
        /// burn CPU backend for DCNet, overriding training.backend: flex or ndarray
        #[arg(long)]
        backend: Option<String>,
        /// Figures go to PLOTS/<name>/
        #[arg(long, default_value = "plots")]
        plots: PathBuf,
        /// Write the results and report.md but draw no figures
        #[arg(long)]
        no_plots: bool,
        #[command(flatten)]
        overrides: Overrides,
    },
    /// Draw the figures and write report.md from a results folder, re-running nothing
    Plot {
        /// A results folder written by `run`, such as results/paper
        results: PathBuf,
        /// Figures go to OUT/<name>/
        #[arg(long, default_value = "plots")]
        out: PathBuf,
        /// Write each figure as PNG, SVG or both
        #[arg(long, value_enum, default_value_t = Format::Both)]
        format: Format,
    },
    /// Check a spec and its data files without running anything
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
    /// Time the dataset generation and the Monte Carlo protocol of a spec
    Bench {
        spec: PathBuf,
        /// Timed repetitions of each stage
        #[arg(long, default_value_t = 5)]
        repeat: usize,
        /// Training batches timed per model and backend
        #[arg(long, default_value_t = 40)]
        training_batches: usize,
        #[command(flatten)]
        overrides: Overrides,
    },
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
            spec,
            out,
            backend,
            plots,
            no_plots,
            mut overrides,
        } => {
            if let Some(backend) = backend {
                overrides.set.push(format!("training.backend={backend:?}"));
            }
            let plots = (!no_plots).then_some(plots.as_path());
            run(&spec, &out, plots, &overrides.set)
        }
        Command::Plot {
            results,
            out,
            format,
        } => plot(&results, Some(&out), format),
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
            overrides,
        } => bench(&spec, repeat, training_batches, &overrides.set),
    }
}

fn load_spec(path: &Path, set: &[String]) -> Result<Spec, CliError> {
    load(path, set).map_err(input)
}

fn run(spec_path: &Path, out: &Path, plots: Option<&Path>, set: &[String]) -> Result<(), CliError> {
    let started_at = SystemTime::now();
    let spec = load_spec(spec_path, set)?;
    let mut stages = StageSeconds::default();
    let clock = Instant::now();
    let trajectories = load_trajectories(&spec).map_err(input)?;
    stages.load = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let progress = bar(spec.grid.points().len(), "dataset");
    let training = dataset::generate(&spec, &trajectories, &progress);
    progress.finish_and_clear();
    stages.dataset = clock.elapsed().as_secs_f64();
    eprintln!(
        "dataset: {} combinations × {} windows = {} windows ({} validation), {:.1} MB, in {:.2} s",
        training.points.len(),
        training.windows_per_combination,
        training.len(),
        training.validation_len(),
        TrainingSet::size_bytes(training.len(), training.window) as f64 / 1e6,
        stages.dataset
    );

    let clock = Instant::now();
    let folder = out.join(&spec.name);
    let (dcnets, failures) = train_all(&spec, &training, &ModelStore::new(folder.join("models")));
    stages.training = clock.elapsed().as_secs_f64();

    let clock = Instant::now();
    let progress = bar(
        2 * spec.dvls.len() * spec.calibration.monte_carlo_runs,
        "monte carlo",
    );
    let result = run_protocol(&spec, &trajectories, &dcnets, &progress);
    progress.finish_and_clear();
    stages.protocol = clock.elapsed().as_secs_f64();

    let manifest = Manifest {
        name: spec.name.clone(),
        spec_sha256: fetch::sha256_hex(spec.resolved_toml().as_bytes()),
        git_commit: env!("DCNET_GIT_COMMIT").to_string(),
        crate_version: env!("CARGO_PKG_VERSION").to_string(),
        started_at: humantime::format_rfc3339_seconds(started_at).to_string(),
        finished_at: humantime::format_rfc3339_seconds(SystemTime::now()).to_string(),
        threads: rayon::current_num_threads(),
        backend: spec.training.backend.to_string(),
        host: gethostname::gethostname().to_string_lossy().into_owned(),
        data_files: data_files(&spec).map_err(failure)?,
        stage_seconds: stages,
    };
    results::write_run(&folder, &spec, &trajectories, &result, &dcnets, &manifest)
        .map_err(failure)?;
    let calibration_name = &trajectories[spec.calibration.trajectory].name;
    println!(
        "{}",
        tables::calibration_table(
            &result.calibration,
            calibration_name,
            spec.calibration.monte_carlo_runs
        )
    );
    println!("{}", tables::evaluation_table(&result.evaluation));
    eprintln!("results written to {}", folder.display());
    plot(&folder, plots, Format::Both).map_err(|e| failure(e.into_cause()))?;
    if failures.is_empty() {
        return Ok(());
    }
    // Every failed model, one per line; the results above hold all the others.
    let messages: Vec<String> = failures.iter().map(ToString::to_string).collect();
    Err(failure(anyhow::anyhow!(messages.join("\n"))))
}

/// Reads the results folder back, draws its figures into `out/<name>/` (none when
/// `out` is `None`) and writes its report.
fn plot(results: &Path, out: Option<&Path>, format: Format) -> Result<(), CliError> {
    let stored = StoredRun::read(results).map_err(input)?;
    let figures = match out {
        Some(out) => {
            let folder = out.join(&stored.spec.name);
            let figures = plots::write_all(&stored, &folder, format).map_err(failure)?;
            for figure in &figures {
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
            figures
        }
        None => Vec::new(),
    };
    let report = report::write(&stored, &figures).map_err(failure)?;
    eprintln!("report written to {}", report.display());
    Ok(())
}

/// Trains one DCNet per error model of the spec, concurrently; a model that fails is
/// reported and left out, the others go on.
fn train_all(
    spec: &Spec,
    set: &TrainingSet,
    store: &ModelStore,
) -> (Vec<Trained>, Vec<TrainError>) {
    if !spec.kinds.contains(&EstimatorKind::Dcnet) {
        return (Vec::new(), Vec::new());
    }
    let bars = indicatif::MultiProgress::new();
    let outcomes: Vec<Result<(Trained, Provenance), TrainError>> = spec
        .error_models
        .par_iter()
        .map(|&error_model| {
            let progress = bars.add(bar(
                spec.training.epochs * train::batches_per_epoch(spec, set),
                "DCNet",
            ));
            progress.set_message(format!("DCNet {error_model}"));
            let outcome = train_cached(spec, set, error_model, store, &progress);
            progress.finish_and_clear();
            outcome
        })
        .collect();
    let mut trained = Vec::new();
    let mut failures = Vec::new();
    for outcome in outcomes {
        match outcome {
            Ok((model, provenance)) => {
                let best = &model.history[model.best_epoch - 1];
                let how = match provenance {
                    Provenance::Trained => "trained".to_string(),
                    Provenance::Resumed(epoch) => {
                        format!("resumed from the checkpoint of epoch {epoch}")
                    }
                    Provenance::Reused => format!("reused from {}", store.folder.display()),
                };
                eprintln!(
                    "DCNet {}: {how}; best validation loss {:.4} (cm/s)² at epoch {} of {}",
                    model.error_model,
                    best.validation_loss,
                    model.best_epoch,
                    model.history.len()
                );
                trained.push(model);
            }
            Err(error) => failures.push(error),
        }
    }
    (trained, failures)
}

/// The `.npy` files the spec reads, with their SHA-256.
fn data_files(spec: &Spec) -> anyhow::Result<Vec<results::DataFile>> {
    let mut files: Vec<results::DataFile> = Vec::new();
    for source in &spec.trajectories {
        if let Origin::File { path, .. } = &source.origin {
            if !files.iter().any(|f| &f.path == path) {
                let bytes =
                    std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
                files.push(results::DataFile {
                    path: path.clone(),
                    sha256: fetch::sha256_hex(&bytes),
                });
            }
        }
    }
    Ok(files)
}

fn validate(spec_path: &Path, set: &[String]) -> Result<(), CliError> {
    let spec = load_spec(spec_path, set)?;
    let trajectories = load_trajectories(&spec).map_err(input)?;
    let windows = dataset::windows_per_combination(&spec, &trajectories) * spec.grid.points().len();
    println!(
        "{}: ok ({} trajectories, {} training windows, {} DVLs, {} Monte Carlo runs)",
        spec_path.display(),
        trajectories.len(),
        windows,
        spec.dvls.len(),
        spec.calibration.monte_carlo_runs
    );
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
            } => format!("{} [{start}, {end})", file_name(path)),
            Origin::File {
                path,
                samples: None,
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
    set: &[String],
) -> Result<(), CliError> {
    let spec = load_spec(spec_path, set)?;
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
    bench_training(
        &spec,
        &dataset::generate(&spec, &trajectories, &hidden),
        training_batches,
    )
    .map_err(failure)
}

/// Training samples/s of the spec's model and batch size on each backend: one model on
/// one thread, and one model per thread training at once (as `run` trains the error
/// models side by side).
fn bench_training(spec: &Spec, set: &TrainingSet, batches: usize) -> Result<(), TrainError> {
    let threads = rayon::current_num_threads();
    let error_model = *spec.error_models.last().unwrap_or(&ErrorModel::Em5);
    let hidden = indicatif::ProgressBar::hidden();
    let samples = |order: &[usize]| order.len().min(batches * spec.training.batch_size);
    let run_model = |spec: &Spec, seed_offset: u64| -> Result<usize, TrainError> {
        let mut spec = spec.clone();
        spec.seed += seed_offset;
        let order = train::epoch_order(&spec, set, error_model, 1);
        let order = &order[..samples(&order)];
        let mut state = train::State::new(&spec, error_model);
        train::train_pass(&spec, set, error_model, &mut state, 1, order, &hidden)?;
        Ok(order.len())
    };
    for backend in [Backend::Flex, Backend::NdArray] {
        let mut spec = spec.clone();
        spec.training.backend = backend;
        let one_thread = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("a pool of one thread");
        let clock = Instant::now();
        let done = one_thread.install(|| run_model(&spec, 0))?;
        let single = done as f64 / clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        let done: usize = (0..threads as u64)
            .into_par_iter()
            .map(|i| run_model(&spec, i))
            .sum::<Result<usize, _>>()?;
        let together = done as f64 / clock.elapsed().as_secs_f64();
        println!(
            "training {error_model} on {backend}: {single:.0} samples/s with one model on one thread, {together:.0} samples/s with {threads} models on {threads} threads (batch {}, {} conv channels, FC {:?})",
            spec.training.batch_size, spec.model.conv_channels, spec.model.fc_widths
        );
    }
    Ok(())
}
