//! `run`, `plan` and `collect`: an experiment's plan, shown or done, whole or one
//! shard at a time, and what a run wrote, printed and drawn.

use super::args::RunArgs;
use super::args::{Drawing, Target};
use super::plot::{plot_run, plot_sweep};
use super::{CliError, about, failure, input, load_target, training_seconds};
use crate::pipeline::{Executed, Mode, Plan, Planned, Shard, Task, execute, owner, tidy_models};
use crate::report::kit::plots::Format;
use crate::report::paper::printed;
use crate::report::paper::sweep::Metric;
use crate::results::read::StoredRun;
use crate::results::sweep;
use crate::spec::Experiment;

/// `run`: the spec's kind runs it, all of it or one shard.
pub(super) fn run_command(args: &RunArgs) -> Result<(), CliError> {
    let force = args.force;
    let mode = match parse_shard(args.shard.as_deref())? {
        Some(shard) => Mode::Shard { shard, force },
        None => Mode::All { force },
    };
    if let (Mode::All { .. }, Some(plots)) = (&mode, args.drawing.folder()) {
        writable(plots)?;
    }
    super::kind_of(&args.target.spec)?.run(&args.target, &args.drawing, mode)
}

/// Refuses a `--plots` folder that cannot be written, before the run rather than after
/// it: the deepest of its folders that exists takes a file (made and removed at once),
/// and none of its parts is a file.
fn writable(plots: &std::path::Path) -> Result<(), CliError> {
    let refused = |why: String| {
        input(anyhow::anyhow!(
            "--plots {}: {why}; give a folder that can be written, or --no-plots",
            plots.display()
        ))
    };
    let deepest = crate::files::deepest_folder(plots)
        .map_err(|file| refused(format!("{} is not a folder", file.display())))?;
    tempfile::tempfile_in(deepest)
        .map(drop)
        .map_err(|e| refused(format!("{} cannot be written ({e})", deepest.display())))
}

/// `--shard K/N` as typed, or from the variables it names.
pub(super) fn parse_shard(shard: Option<&str>) -> Result<Option<Shard>, CliError> {
    shard
        .map(|text| Shard::parse(text, |variable| std::env::var(variable).ok()))
        .transpose()
        .map_err(|message| input(anyhow::anyhow!(message)))
}

/// `run` of a paper spec: every task left, or one shard's share.
pub(super) fn run(target: &Target, drawing: &Drawing, mode: Mode) -> Result<(), CliError> {
    let experiment = load_target(target)?;
    let plan = planned(&experiment, target)?;
    tidy_models(&plan).map_err(failure)?;
    let to_do = plan.to_do(mode);
    check_owners(&plan, &to_do, mode.force())?;
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
    say_how_long(&plan, &to_do)?;
    let executed = execute(
        &Planned::Paper {
            plan: &plan,
            to_do: &to_do,
        },
        mode,
    )
    .map_err(failure)?;
    if let Mode::Shard { shard, .. } = mode {
        eprintln!(
            "shard {shard}: {} done; once every shard has finished, `{}` writes the results",
            tasks(executed.done),
            target.command("collect")
        );
    } else {
        finish(&experiment, &executed, drawing)?;
    }
    failed_models(plan.failures(mode))
}

/// The plan of `experiment`, whose results folders record the spec file they come
/// from.
fn planned<'a>(experiment: &'a Experiment, target: &Target) -> Result<Plan<'a>, CliError> {
    let mut plan = Plan::new(experiment, &target.out).map_err(input)?;
    plan.spec_file = owner::recorded(&target.spec, &target.out);
    Ok(plan)
}

/// Refuses, before anything is computed, to write a results folder that another spec
/// wrote, unless `force`.
fn check_owners(plan: &Plan, to_do: &[Task], force: bool) -> Result<(), CliError> {
    for task in to_do {
        if let Task::Results(p) = *task {
            owner::check(&owner::Writer::point(plan, p, force)).map_err(input)?;
        }
    }
    Ok(())
}

/// Trainings that take longer than this are announced with how long they take.
const LONG_TRAINING_S: f64 = 600.0;

/// Says how long the trainings of `to_do` will take, when that is long.
fn say_how_long(plan: &Plan, to_do: &[Task]) -> Result<(), CliError> {
    let trainings: Vec<_> = to_do
        .iter()
        .filter_map(|task| match task {
            Task::Training(t) => Some(plan.trainings[*t].point),
            _ => None,
        })
        .map(|p| {
            let lengths = plan.trajectories[p]
                .iter()
                .map(|t| t.ground_truth.len())
                .collect();
            (plan.spec(p), lengths)
        })
        .collect();
    if trainings.is_empty() {
        return Ok(());
    }
    let seconds = training_seconds(&trainings)?;
    if seconds > LONG_TRAINING_S {
        eprintln!(
            "training {} will take about {} on {} (from one batch timed here)",
            crate::count(trainings.len(), "model"),
            about(seconds),
            crate::count(rayon::current_num_threads(), "thread")
        );
    }
    Ok(())
}

/// "1 task", "31 tasks".
fn tasks(count: usize) -> String {
    if count == 1 {
        "1 task".into()
    } else {
        format!("{count} tasks")
    }
}

/// Lists the tasks of a paper spec's run, shard or not, with their state.
pub(super) fn plan(target: &Target, shard: Option<Shard>) -> Result<(), CliError> {
    let experiment = load_target(target)?;
    let plan = Plan::new(&experiment, &target.out).map_err(input)?;
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
        crate::pipeline::cache::root(&target.out).display()
    );
    Ok(())
}

/// Writes the results of a sharded run from the cache the shards filled.
pub(super) fn collect(target: &Target, drawing: &Drawing) -> Result<(), CliError> {
    let experiment = load_target(target)?;
    let plan = planned(&experiment, target)?;
    let to_do = plan.to_do(Mode::Collect);
    check_owners(&plan, &to_do, false)?;
    let executed = execute(
        &Planned::Paper {
            plan: &plan,
            to_do: &to_do,
        },
        Mode::Collect,
    )
    .map_err(failure)?;
    if executed.done == 0 {
        eprintln!(
            "nothing to do: the results in {} are current",
            target.out.join(&experiment.name).display()
        );
    } else {
        finish(&experiment, &executed, drawing)?;
    }
    failed_models(plan.failures(Mode::Collect))
}

/// Prints the tables of a single run, and draws the figures and writes the reports of
/// what was written.
fn finish(experiment: &Experiment, executed: &Executed, drawing: &Drawing) -> Result<(), CliError> {
    for folder in &executed.written {
        if !experiment.is_sweep() {
            let stored = StoredRun::read(folder).map_err(failure)?;
            println!(
                "{}",
                printed::calibration_table(
                    &stored.calibration,
                    &stored.spec.calibration.trajectory,
                    stored.spec.calibration.monte_carlo_runs
                )
            );
            println!("{}", printed::evaluation_table(&stored.evaluation));
        }
        eprintln!("results written to {}", folder.display());
        plot_run(folder, drawing.folder(), Format::Both).map_err(|e| failure(e.into_cause()))?;
    }
    if let Some(folder) = &executed.sweep {
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
