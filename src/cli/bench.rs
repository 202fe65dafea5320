//! `bench`: times the dataset generation, the Monte Carlo protocol and DCNet training
//! of a spec, and, given the PyTorch peer script, the same network in PyTorch in the
//! same arrangements, side by side.

use super::{CliError, failure, input, load_spec};
use crate::data::load_trajectories;
use crate::dataset::{self, DatasetSize, TrainingSet};
use crate::evaluate::run_protocol;
use crate::spec::Spec;
use crate::train::{self, TrainError};
use crate::vocab::{ErrorModel, EstimatorKind};
use std::path::Path;
use std::time::Instant;

pub(super) fn bench(
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
        "protocol: {} runs × {} DVLs, estimators {}, best {best:.3} s, median {median:.3} s over {repeat} runs, {} threads",
        spec.calibration.monte_carlo_runs,
        spec.dvls.len(),
        kinds.join(", "),
        rayon::current_num_threads()
    );
    bench_refusal(spec_path).map_err(failure)?;
    let set = dataset::generate(&spec, &trajectories, &hidden);
    // Paired runs: ours then the peer in each, so that both see the machine as it is
    // at that moment; the table gives the median of each and its spread.
    let mut ours = Vec::new();
    let mut peers = Vec::new();
    for _ in 0..repeat {
        ours.push(bench_training(&spec, &set, training_batches).map_err(failure)?);
        if let Some(script) = pytorch {
            peers.push(
                bench_pytorch(&spec, script, training_batches)
                    .map_err(|e| failure(anyhow::anyhow!(e)))?,
            );
        }
    }
    print_training_bench(&spec, &ours, &peers);
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
    let hidden = crate::progress::Progress::hidden();
    let run_model = |seed_offset: u64| -> Result<usize, TrainError> {
        let mut spec = spec.clone();
        spec.seed += seed_offset;
        let recipe = train::Recipe::paper(&spec, error_model);
        let data = train::PaperWindows { set, error_model };
        let order = train::epoch_order(&recipe, &data, 0, 1);
        let order = &order[..order.len().min(batches * spec.training.batch_size)];
        let mut state = train::State::new(&spec, error_model, 0);
        train::one_thread_pool()
            .install(|| train::train_pass(&recipe, &data, &mut state, 1, order, &hidden))?;
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

/// The training table: each arrangement's median samples/s over the paired runs with
/// its range, and, with the peer, the median of the paired ratios on all cores.
fn print_training_bench(spec: &Spec, ours: &[TrainingRates], peers: &[PeerRates]) {
    let threads = rayon::current_num_threads();
    let backend = spec.training.backend;
    println!(
        "training: batch {}, {} conv channels, FC {:?}; median (range) of {} run{}{}",
        spec.training.batch_size,
        spec.model.conv_channels,
        spec.model.fc_widths,
        ours.len(),
        if ours.len() == 1 { "" } else { "s" },
        if peers.is_empty() {
            ""
        } else {
            ", each ours then PyTorch's"
        }
    );
    let mut table = comfy_table::Table::new();
    table.load_preset(comfy_table::presets::ASCII_MARKDOWN);
    let rates = |f: &dyn Fn(&TrainingRates) -> f64| {
        median_and_spread(&ours.iter().map(f).collect::<Vec<_>>(), 0)
    };
    let peer_rates = |f: &dyn Fn(&PeerRates) -> f64| {
        median_and_spread(&peers.iter().map(f).collect::<Vec<_>>(), 0)
    };
    let mut header = vec![
        "arrangement".to_string(),
        format!("dcnet-exp ({backend}) samples/s"),
    ];
    let mut rows = vec![
        vec![
            "one model, one thread".to_string(),
            rates(&|r| r.one_thread),
        ],
        vec![
            format!("{threads} models, one per core"),
            rates(&|r| r.one_per_core),
        ],
        vec![format!("one model over {threads} threads"), "-".to_string()],
    ];
    if !peers.is_empty() {
        header.extend(["PyTorch samples/s".to_string(), "ratio".to_string()]);
        let ratio = |f: &dyn Fn(&TrainingRates, &PeerRates) -> f64| {
            median_and_spread(
                &ours
                    .iter()
                    .zip(peers)
                    .map(|(o, p)| f(o, p))
                    .collect::<Vec<_>>(),
                2,
            )
        };
        rows[0].extend([
            peer_rates(&|p| p.rates.one_thread),
            ratio(&|o, p| o.one_thread / p.rates.one_thread),
        ]);
        rows[1].extend([
            peer_rates(&|p| p.rates.one_per_core),
            ratio(&|o, p| o.one_per_core / p.rates.one_per_core),
        ]);
        rows[2].extend([peer_rates(&|p| p.one_model_all_threads), "-".to_string()]);
    }
    table.set_header(header);
    for row in rows {
        table.add_row(row);
    }
    println!("{table}");
    if !peers.is_empty() {
        let ratios: Vec<f64> = ours
            .iter()
            .zip(peers)
            .map(|(o, p)| o.one_per_core / p.rates.one_per_core.max(p.one_model_all_threads))
            .collect();
        println!(
            "on all {threads} cores, against PyTorch at its best arrangement: {}× (median of {} paired runs, range in brackets)",
            median_and_spread(&ratios, 2),
            ratios.len()
        );
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
