//! `bench`: times the dataset generation, the Monte Carlo protocol and DCNet training
//! of a spec, and, given the PyTorch peer script, the same network in PyTorch in the
//! same arrangements, side by side: several models one per core, or one model over
//! several cores; with `--scaling`, on 1, 2, 4, … cores up to all of them; and where the
//! spec trains fewer models than there are cores, those models as `run` trains them, one
//! per core and then on all the cores. It prints the page faults and allocator calls of a
//! warm training step too.

use super::args::BenchArgs;
use super::{CliError, failure, input, load_spec};
use crate::count;
use crate::data::load_trajectories;
use crate::dataset::{self, DatasetSize, TrainingSet};
use crate::evaluate::run_protocol;
use crate::pipeline::training::first_loans;
use crate::spec::Spec;
use crate::train::{self, TrainError};
use crate::vocab::{ErrorModel, EstimatorKind};
use std::path::Path;
use std::time::Instant;

/// `bench`, as typed.
pub(super) fn bench_command(args: &BenchArgs) -> Result<(), CliError> {
    bench(
        &args.spec,
        args.repeat as usize,
        args.training_batches as usize,
        args.pytorch.as_deref(),
        args.scaling,
        &args.overrides.set,
    )
}

pub(super) fn bench(
    spec_path: &Path,
    repeat: usize,
    training_batches: usize,
    pytorch: Option<&Path>,
    scaling: bool,
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
    let hidden = crate::progress::Progress::hidden();
    let windows = DatasetSize::of(&spec, &trajectories).windows();
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
        "protocol: {} × {}, estimators {}, best {best:.3} s, median {median:.3} s over {}, {}",
        count(spec.calibration.monte_carlo_runs, "run"),
        count(spec.dvls.len(), "DVL"),
        kinds.join(", "),
        count(repeat, "run"),
        count(rayon::current_num_threads(), "thread")
    );
    bench_refusal(spec_path).map_err(failure)?;
    let set = dataset::generate(&spec, &trajectories, &hidden);
    print_step_counts(&spec, &set).map_err(failure)?;
    let cores = rayon::current_num_threads();
    let mut counts = if scaling {
        core_counts(cores)
    } else {
        vec![1, cores]
    };
    counts.dedup();
    let table = TrainingTable::measure(&spec, &set, training_batches, pytorch, repeat, &counts)?;
    table.print(&spec);
    Ok(())
}

/// Times refusing the spec at `spec_path` with 10³, 10⁴ and 10⁵ faults written in the
/// file, each its own fault placed on its line: invalid calibration window sizes (each
/// negative), and training trajectory names that are all different and none defined.
/// The times grow as the counts do: checking is linear in the number of faults.
fn bench_refusal(spec_path: &Path) -> std::io::Result<()> {
    let text = std::fs::read_to_string(spec_path)?;
    let folder = tempfile::tempdir()?;
    let path = folder
        .path()
        .join(spec_path.file_name().unwrap_or_default());
    let cases: [(&str, &str, fn(usize) -> String); 2] = [
        ("invalid window sizes", "window_sizes_s", |i| {
            format!("-{i}")
        }),
        ("unknown training trajectories", "trajectories", |i| {
            format!("\"unknown-{i}\"")
        }),
    ];
    for (what, key, value) in cases {
        for count in [1_000, 10_000, 100_000] {
            let values: Vec<String> = (1..=count).map(value).collect();
            let Some(bad) = with_first_value(&text, key, &values.join(", ")) else {
                println!("spec refusal: skipped, the spec writes no {key}");
                break;
            };
            std::fs::write(&path, bad)?;
            let clock = Instant::now();
            let faults = match crate::spec::load_experiment(&path, &[]) {
                Ok(_) => 0,
                Err(errors) => {
                    std::hint::black_box(errors.to_string());
                    errors.0.len()
                }
            };
            println!(
                "spec refusal: {count} {what}, {faults} faults, {:.3} s",
                clock.elapsed().as_secs_f64()
            );
        }
    }
    Ok(())
}

/// `text` with the first line that writes `key` writing `key = [values]` instead.
fn with_first_value(text: &str, key: &str, values: &str) -> Option<String> {
    let line = text.lines().position(|line| {
        line.trim_start()
            .strip_prefix(key)
            .is_some_and(|rest| rest.trim_start().starts_with('='))
    })?;
    let replaced = format!("{key} = [{values}]");
    let lines: Vec<&str> = text
        .lines()
        .enumerate()
        .map(|(i, l)| if i == line { replaced.as_str() } else { l })
        .collect();
    Some(lines.join("\n"))
}

/// How a tool trains on some cores: `models` models at once, each over `threads`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Arrangement {
    models: usize,
    threads: usize,
}

impl Arrangement {
    /// The arrangements of `cores`: one model per core, and one model over them all
    /// (the same on one core).
    fn on(cores: usize) -> Vec<Arrangement> {
        let mut all = vec![Arrangement {
            models: cores,
            threads: 1,
        }];
        if cores > 1 {
            all.push(Arrangement {
                models: 1,
                threads: cores,
            });
        }
        all
    }

    /// Each model's threads.
    fn threads_each(&self) -> Vec<usize> {
        vec![self.threads; self.models]
    }

    fn describe(&self) -> String {
        match (self.models, self.threads) {
            (1, 1) => "one model, one thread".to_string(),
            (models, 1) => format!("{models} models, one per core"),
            (1, threads) => format!("one model over {threads} threads"),
            (models, threads) => format!("{models} models over {threads} threads each"),
        }
    }
}

/// 1, 2, 4, … up to `cores`, and `cores` itself.
fn core_counts(cores: usize) -> Vec<usize> {
    let mut counts: Vec<usize> = std::iter::successors(Some(1), |n| Some(n * 2))
        .take_while(|&n| n < cores)
        .collect();
    counts.push(cores);
    counts
}

/// Training batches each model trains before it is timed, as the peer script does.
const WARM_UP_BATCHES: usize = 10;

/// A fresh model of the spec's last error model (EM5 by default) on its own pool of
/// threads, training the windows of its first epoch in order, batch by batch.
struct BenchModel<'a> {
    recipe: train::Recipe<'a>,
    data: train::PaperWindows<'a>,
    state: train::State,
    pool: rayon::ThreadPool,
    order: Vec<usize>,
    done: usize,
}

impl<'a> BenchModel<'a> {
    /// The model whose seeds are the spec's plus `seed_offset`, on `threads` threads.
    fn new(spec: &'a Spec, set: &'a TrainingSet, seed_offset: u64, threads: usize) -> Self {
        let error_model = *spec.error_models.last().unwrap_or(&ErrorModel::Em5);
        let mut recipe = train::Recipe::paper(spec, error_model);
        recipe.seed += seed_offset;
        let data = train::PaperWindows { set, error_model };
        let order = train::epoch_order(&recipe, &data, 0, 1);
        let state = train::State::of(&recipe, error_model, spec.dataset.window_samples, 0);
        Self {
            recipe,
            data,
            state,
            pool: train::pool(threads),
            order,
            done: 0,
        }
    }

    /// Trains the next `batches` batches (fewer where the epoch ends); returns their
    /// windows.
    fn train(&mut self, batches: usize) -> Result<usize, TrainError> {
        let batch = self.recipe.training.batch_size;
        let start = self.done.min(self.order.len());
        let windows = &self.order[start..(start + batches * batch).min(self.order.len())];
        let (recipe, data, state) = (&self.recipe, &self.data, &mut self.state);
        let hidden = crate::progress::Progress::hidden();
        self.pool
            .install(|| train::train_pass(recipe, data, state, 1, windows, &hidden))?;
        self.done = start + windows.len();
        Ok(windows.len())
    }
}

/// Training samples/s of the spec's model and batch size on its backend, one model at
/// once on each of `threads_each` threads: each model times its own batches after
/// [`WARM_UP_BATCHES`], and the rates are summed, as the peer script sums its processes'.
fn training_rate(
    spec: &Spec,
    set: &TrainingSet,
    batches: usize,
    threads_each: &[usize],
) -> Result<f64, TrainError> {
    let run_model = |seed_offset: u64, threads: usize| -> Result<f64, TrainError> {
        let mut model = BenchModel::new(spec, set, seed_offset, threads);
        model.train(WARM_UP_BATCHES)?;
        let clock = Instant::now();
        let windows = model.train(batches)?;
        Ok(windows as f64 / clock.elapsed().as_secs_f64())
    };
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0u64..)
            .zip(threads_each)
            .map(|(i, &threads)| scope.spawn(move || run_model(i, threads)))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a training thread panicked"))
            .sum()
    })
}

/// Prints the minor page faults and allocator calls of one warm training step, for one
/// model on one thread and over every thread.
fn print_step_counts(spec: &Spec, set: &TrainingSet) -> Result<(), TrainError> {
    let batch = spec.training.batch_size;
    let steps = 50.min(set.training_len() / batch / 2).max(1);
    let all = rayon::current_num_threads();
    let mut lines = Vec::new();
    for threads in if all > 1 { vec![1, all] } else { vec![1] } {
        let mut model = BenchModel::new(spec, set, 0, threads);
        model.train(steps)?;
        let faults = crate::memory::minor_page_faults();
        let (passed, calls) = crate::memory::count_allocations(|| model.train(steps));
        passed?;
        let faults = faults
            .zip(crate::memory::minor_page_faults())
            .map(|(a, b)| b - a);
        let per_step = |count: Option<u64>| {
            count.map_or("-".to_string(), |c| {
                format!("{:.1}", c as f64 / steps as f64)
            })
        };
        lines.push(format!(
            "{} minor page faults and {} allocator calls per step on {}",
            per_step(faults),
            per_step(calls),
            count(threads, "thread")
        ));
    }
    println!(
        "training step (batch {batch}), warm, mean over {steps} steps: {}",
        lines.join("; ")
    );
    Ok(())
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
    if spec.dataset.window_samples != 10
        || m.conv1d_kernel_size != 2
        || (w2, w3) != (w1 / 2, w1 / 4)
        || m.activation != crate::vocab::Activation::Tanh
        || m.dropout != 0.3
        || m.leaky_relu_slope != 0.05
    {
        return Err(format!(
            "--pytorch: the peer script builds windows of 10 samples, Conv1d kernels of 2, FC widths [w, w/2, w/4] with tanh, dropout 0.3 and LeakyReLU slope 0.05; the spec has {} samples, kernel {}, FC {:?} with {}, dropout {} and slope {}",
            spec.dataset.window_samples,
            m.conv1d_kernel_size,
            m.fc_widths,
            m.activation,
            m.dropout,
            m.leaky_relu_slope
        ));
    }
    Ok(())
}

/// The PyTorch peer `script`'s samples/s with the spec's sizes in `arrangement`: its
/// models in processes of their own.
fn peer_rate(
    spec: &Spec,
    script: &Path,
    batches: usize,
    arrangement: Arrangement,
) -> Result<f64, String> {
    let output = std::process::Command::new("python3")
        .arg(script)
        .args(["--processes", &arrangement.models.to_string()])
        .args(["--threads", &arrangement.threads.to_string()])
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
}

/// The median of `values` and their range, as a table cell: `36469 (33796-36924)`, or
/// the one value.
fn median_and_spread(values: &[f64], digits: usize) -> String {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    match sorted.len() {
        1 => format!("{median:.digits$}"),
        _ => format!(
            "{median:.digits$} ({:.digits$}-{:.digits$})",
            sorted[0],
            sorted[sorted.len() - 1]
        ),
    }
}

/// Training samples/s on each core count, in each arrangement, over paired runs: ours,
/// and with the peer script the peer's right after it in the same arrangement.
struct TrainingTable {
    /// Per core count, its arrangements.
    cells: Vec<(usize, Vec<Cell>)>,
    /// The spec's models as `run` trains them, where it trains some, fewer than the cores.
    run: Option<RunTraining>,
    runs: usize,
}

/// The spec's models trained at once as `run` trains them, on as many cores as models
/// (one each), then on all the cores (each on the threads `run` first lends it): what
/// training gains from the cores a run does not fill one model per core.
struct RunTraining {
    cores: usize,
    loans: Vec<usize>,
    /// Samples/s per run, one model per core.
    one_per_core: Vec<f64>,
    /// Samples/s per run, on all the cores.
    on_all: Vec<f64>,
}

impl RunTraining {
    fn measure(&mut self, spec: &Spec, set: &TrainingSet, batches: usize) -> Result<(), CliError> {
        let one_each = vec![1; self.loans.len()];
        let one_per_core = training_rate(spec, set, batches, &one_each).map_err(failure)?;
        self.one_per_core.push(one_per_core);
        let on_all = training_rate(spec, set, batches, &self.loans).map_err(failure)?;
        self.on_all.push(on_all);
        Ok(())
    }

    fn print(&self) {
        let models = self.loans.len();
        let ratios: Vec<f64> = self
            .on_all
            .iter()
            .zip(&self.one_per_core)
            .map(|(all, one)| all / one)
            .collect();
        let loans: Vec<String> = self.loans.iter().map(ToString::to_string).collect();
        println!(
            "training as `run` trains the spec's {} at once, samples/s in all: on {}, one model each, {}; on all {} cores, on {} threads, {}; {}× ({})",
            count(models, "model"),
            count(models, "core"),
            median_and_spread(&self.one_per_core, 0),
            self.cores,
            loans.join(", "),
            median_and_spread(&self.on_all, 0),
            median_and_spread(&ratios, 2),
            match ratios.len() {
                1 => "one paired run".to_string(),
                runs => format!("median of {runs} paired runs, range in brackets"),
            }
        );
    }
}

/// One arrangement's rates, one per run: ours and the peer's.
struct Cell {
    arrangement: Arrangement,
    ours: Vec<f64>,
    peers: Vec<f64>,
}

impl TrainingTable {
    fn measure(
        spec: &Spec,
        set: &TrainingSet,
        batches: usize,
        pytorch: Option<&Path>,
        runs: usize,
        counts: &[usize],
    ) -> Result<Self, CliError> {
        let mut cells: Vec<(usize, Vec<Cell>)> = counts
            .iter()
            .map(|&n| {
                let cells = Arrangement::on(n).into_iter().map(|arrangement| Cell {
                    arrangement,
                    ours: Vec::new(),
                    peers: Vec::new(),
                });
                (n, cells.collect())
            })
            .collect();
        let (models, cores) = (spec.model_count(), rayon::current_num_threads());
        let mut run = (1..cores).contains(&models).then(|| RunTraining {
            cores,
            loans: first_loans(cores, models),
            one_per_core: Vec::new(),
            on_all: Vec::new(),
        });
        for _ in 0..runs {
            if let Some(run) = &mut run {
                run.measure(spec, set, batches)?;
            }
            for cell in cells.iter_mut().flat_map(|(_, cells)| cells) {
                let arrangement = cell.arrangement;
                let ours = training_rate(spec, set, batches, &arrangement.threads_each())
                    .map_err(failure)?;
                cell.ours.push(ours);
                if let Some(script) = pytorch {
                    let peer = peer_rate(spec, script, batches, arrangement)
                        .map_err(|e| failure(anyhow::anyhow!(e)))?;
                    cell.peers.push(peer);
                }
            }
        }
        Ok(Self { cells, run, runs })
    }

    /// One row per core count and arrangement: samples/s in all and per model, median
    /// (range) over the runs, and with the peer its figures and the median of the paired
    /// ratios; then, per core count, each tool at its best arrangement.
    fn print(&self, spec: &Spec) {
        let with_peer = self
            .cells
            .iter()
            .any(|(_, cells)| cells.iter().any(|c| !c.peers.is_empty()));
        println!(
            "training: batch {}, {} conv channels, FC {:?}, {} backend; samples/s, median (range) of {}{}",
            spec.training.batch_size,
            spec.model.conv_channels,
            spec.model.fc_widths,
            spec.training.backend,
            count(self.runs, "run"),
            if with_peer {
                ", each ours then PyTorch's in the same arrangement (its models in processes of their own)"
            } else {
                ""
            }
        );
        let mut table = comfy_table::Table::new();
        table.load_preset(comfy_table::presets::ASCII_MARKDOWN);
        let mut header = vec!["cores", "arrangement", "dcnet-exp", "per model"];
        if with_peer {
            header.extend(["PyTorch", "per model", "ratio"]);
        }
        table.set_header(header);
        let per_model = |rates: &[f64], a: &Arrangement| {
            let each: Vec<f64> = rates.iter().map(|r| r / a.models as f64).collect();
            median_and_spread(&each, 0)
        };
        let mut best = Vec::new();
        for (cores, cells) in &self.cells {
            for Cell {
                arrangement,
                ours,
                peers,
            } in cells
            {
                let mut row = vec![
                    cores.to_string(),
                    arrangement.describe(),
                    median_and_spread(ours, 0),
                    per_model(ours, arrangement),
                ];
                if with_peer {
                    let ratios: Vec<f64> = ours.iter().zip(peers).map(|(o, p)| o / p).collect();
                    row.extend([
                        median_and_spread(peers, 0),
                        per_model(peers, arrangement),
                        median_and_spread(&ratios, 2),
                    ]);
                }
                table.add_row(row);
            }
            if with_peer {
                // Each run: each tool's best arrangement on these cores.
                let best_of = |pick: fn(&Cell) -> &Vec<f64>, run| {
                    cells.iter().map(|c| pick(c)[run]).fold(0.0, f64::max)
                };
                let ratios: Vec<f64> = (0..self.runs)
                    .map(|run| best_of(|c| &c.ours, run) / best_of(|c| &c.peers, run))
                    .collect();
                best.push(format!("{cores}: {}×", median_and_spread(&ratios, 2)));
            }
        }
        println!("{table}");
        if let Some(run) = &self.run {
            run.print();
        }
        if with_peer {
            println!(
                "each at its best arrangement, against PyTorch, by cores (median of {} paired runs, range in brackets): {}",
                self.runs,
                best.join(", ")
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::median_and_spread;

    #[test]
    fn a_cell_is_the_median_with_the_range_of_the_runs() {
        assert_eq!(
            median_and_spread(&[36469.0, 33796.0, 36924.0], 0),
            "36469 (33796-36924)"
        );
        assert_eq!(
            median_and_spread(&[1.56, 0.85, 1.32], 2),
            "1.32 (0.85-1.56)"
        );
        assert_eq!(median_and_spread(&[1.5], 2), "1.50");
    }
}
