//! The training scheduler: datasets generated a few at a time, and the models that
//! train on them interleaved epoch by epoch over the cores, each epoch on a pool of the
//! cores lent to its worker (a model's bytes do not depend on how many). The paper's
//! models train here ([`train`]); an installation study's `[learned]` models go through
//! the same [`in_batches`] and [`interleave_epochs`] (`pipeline/installation/learned.rs`).

pub mod job;

use crate::dataset::{self, TrainingSet};
use crate::kernels::network::SLICES;
use crate::pipeline::cache::{Blueprint, StoredModel};
use crate::pipeline::plan::Plan;
use crate::pipeline::{ExecuteError, Executed};
use crate::progress::Progress;
use crate::results::StageSeconds;
use crate::train;
use crate::vocab::{ErrorModel, StopReason};
use job::{ModelTask, Provenance, TrainingJob, TrainingJobError};
use std::time::Instant;

/// Trains the models `trainings` asks for; a model whose training fails is recorded as
/// failed in the store, and the others go on. Datasets are generated a few at a time
/// ([`dataset_batches`]), and the models of those datasets then train together, epoch
/// by epoch ([`interleave_epochs`]); only those datasets are held in memory.
pub(super) fn train(
    plan: &Plan,
    trainings: &[usize],
    force: bool,
    stages: &mut StageSeconds,
    executed: &mut Executed,
) -> Result<(), ExecuteError> {
    for batch in dataset_batches(plan, trainings) {
        let sets: Vec<(usize, TrainingSet)> = batch
            .iter()
            .map(|&(d, _)| (d, generate_dataset(plan, d, stages)))
            .collect();
        executed.done += sets.len();
        let set_of = |t: usize| {
            let dataset = plan.trainings[t].dataset;
            &sets
                .iter()
                .find(|(d, _)| *d == dataset)
                .expect("generated")
                .1
        };
        let mine: Vec<usize> = batch.iter().flat_map(|(_, m)| m.iter().copied()).collect();
        let clock = Instant::now();
        let bars = indicatif::MultiProgress::new();
        let announce = |t: usize, ended: &Ended| eprintln!("{}", describe(plan, t, ended));
        let results = interleave_epochs(&mine, announce, |t| {
            let training = &plan.trainings[t];
            let spec = plan.spec(training.point);
            let set = set_of(t);
            let samples_per_epoch = set.training_len();
            let progress = Progress::new(
                task_name(training.error_model, &training.key),
                spec.training.epochs * samples_per_epoch,
                "samples",
            )
            .shown_in(&bars);
            let task = ModelTask {
                blueprint: Blueprint::paper(spec, training.error_model),
                id: training.error_model.into(),
                replicate: training.replicate,
                key: &training.key,
                store: &plan.models,
            };
            let job = TrainingJob::start(&task, force).map_err(TrainingJobError::from);
            let data = train::PaperWindows {
                set,
                error_model: training.error_model,
            };
            let run =
                move |job: TrainingJob, progress: &Progress| job.epoch(&task, &data, progress);
            if let Ok(job) = &job {
                progress.set_position(job.epochs_done() * samples_per_epoch);
            }
            (job, run, progress)
        });
        stages.training += clock.elapsed().as_secs_f64();
        record(plan, results, executed)?;
    }
    Ok(())
}

/// The datasets that `trainings` need, in groups that train together: each group has
/// just enough models that every thread has one to train. A group lists each dataset
/// with its trainings.
fn dataset_batches(plan: &Plan, trainings: &[usize]) -> Vec<Vec<(usize, Vec<usize>)>> {
    in_batches((0..plan.datasets.len()).map(|d| {
        let mine: Vec<usize> = trainings
            .iter()
            .copied()
            .filter(|&t| plan.trainings[t].dataset == d)
            .collect();
        (d, mine)
    }))
}

/// `sets`, each a training set with the models that train on it, in groups that train
/// together: each group has just enough models that every thread has one to train,
/// so that no more sets are in memory than the threads need. Sets without models are
/// left out.
pub(crate) fn in_batches<D>(
    sets: impl IntoIterator<Item = (D, Vec<usize>)>,
) -> Vec<Vec<(D, Vec<usize>)>> {
    let mut batches: Vec<Vec<(D, Vec<usize>)>> = vec![Vec::new()];
    for (set, mine) in sets {
        if mine.is_empty() {
            continue;
        }
        let last = batches.last_mut().expect("never empty");
        if last.iter().map(|(_, m)| m.len()).sum::<usize>() >= rayon::current_num_threads() {
            batches.push(vec![(set, mine)]);
        } else {
            last.push((set, mine));
        }
    }
    batches.retain(|batch| !batch.is_empty());
    batches
}

/// Counts the trained models and stores the failures; a storage error is returned once
/// every other training's end is recorded.
fn record(
    plan: &Plan,
    ended: Vec<(usize, Ended)>,
    executed: &mut Executed,
) -> Result<(), ExecuteError> {
    let mut storage_error = None;
    for (t, result) in ended {
        match result {
            Ok(_) => executed.done += 1,
            Err(TrainingJobError::Store(error)) => {
                storage_error.get_or_insert(error);
            }
            Err(error) => {
                let training = &plan.trainings[t];
                plan.models.save_failure(
                    training.error_model,
                    &training.key,
                    &error.to_string(),
                )?;
            }
        }
    }
    match storage_error {
        Some(error) => Err(error.into()),
        None => Ok(()),
    }
}

/// How the log names a training: its error model and the start of its key.
fn task_name(error_model: ErrorModel, key: &str) -> String {
    format!("DCNet {error_model} {}", &key[..16])
}

/// The line that says how training `t` ended: where its model came from and its best
/// validation loss, or the error that ended it.
fn describe(plan: &Plan, t: usize, ended: &Ended) -> String {
    let training = &plan.trainings[t];
    let task = task_name(training.error_model, &training.key);
    let (model, provenance) = match ended {
        Ok((model, provenance)) => (model, provenance),
        Err(error) => return format!("{task}: failed: {error}"),
    };
    let best = &model.history[model.best_epoch - 1];
    let how = match provenance {
        Provenance::Trained => "trained".to_string(),
        Provenance::Resumed(epoch) => format!("resumed from the checkpoint of epoch {epoch}"),
        Provenance::Reused => "reused".to_string(),
    };
    let stopped = match model.stop {
        StopReason::AllEpochs => "",
        StopReason::EarlyStopping => ", stopped early",
    };
    format!(
        "{task}: {how}; best validation loss {:.4} (cm/s)² at epoch {} of {}{stopped}",
        best.validation_loss,
        model.best_epoch,
        model.history.len()
    )
}

/// How one training ended: its model and where it came from, or the error that ended it.
pub(crate) type Ended = Result<(Box<StoredModel>, Provenance), TrainingJobError>;

/// One training's next epoch: its job in, the job one epoch on out.
type EpochStep<'a> =
    Box<dyn Fn(TrainingJob, &Progress) -> Result<TrainingJob, TrainingJobError> + Send + Sync + 'a>;

/// Runs every training of `ids` to its end, epoch by epoch, on
/// `rayon::current_num_threads()` cores. `start` gives each id its job, the
/// step that trains one epoch, and its progress bar. A worker takes the training at
/// the head of the queue, trains its next epoch and puts it back at the tail, so that
/// the models advance together. There are as many workers as trainings, up to one per
/// core, and each epoch runs on a [`train::pool`] of the cores [`Cores`] lends the
/// worker for it: one thread where trainings outnumber cores, several where they do not
/// (five models on 16 cores: 4, 3, 3, 3 and 3); the cores of a training that has ended
/// go to the others as each starts its next epoch. A model computes the same bytes
/// whichever worker, and however many threads, train it.
/// `announce` is told of each training as it ends. Returns each id's trained model or
/// the error that ended it.
pub(crate) fn interleave_epochs<'a, F, S>(
    ids: &[usize],
    announce: impl Fn(usize, &Ended) + Sync,
    start: S,
) -> Vec<(usize, Ended)>
where
    S: Fn(usize) -> (Result<TrainingJob, TrainingJobError>, F, Progress),
    F: Fn(TrainingJob, &Progress) -> Result<TrainingJob, TrainingJobError> + Send + Sync + 'a,
{
    let queue = std::sync::Mutex::new(std::collections::VecDeque::new());
    let finished = std::sync::Mutex::new(Vec::new());
    // A running training goes to the tail of the queue; an ended one is finished.
    let place = |id,
                 stepped: Result<TrainingJob, TrainingJobError>,
                 step: EpochStep<'a>,
                 progress: Progress| {
        let ended = match stepped {
            Ok(TrainingJob::Done(trained, provenance)) => Ok((trained, provenance)),
            Ok(running) => {
                let mut queue = queue.lock().expect("no worker panics");
                queue.push_back((id, running, step, progress));
                return;
            }
            Err(error) => Err(error),
        };
        progress.finish();
        announce(id, &ended);
        finished.lock().expect("no worker panics").push((id, ended));
    };
    for &id in ids {
        let (job, step, progress) = start(id);
        place(id, job, Box::new(step), progress);
    }
    let trainings = queue.lock().expect("no worker panics").len();
    let lender = Cores::new(rayon::current_num_threads(), trainings);
    std::thread::scope(|scope| {
        for _ in 0..lender.workers() {
            let (queue, place, lender) = (&queue, &place, &lender);
            scope.spawn(move || {
                // The pool of the last loan, kept while the loans stay that size.
                let mut pool: Option<rayon::ThreadPool> = None;
                // The queue only shrinks while this worker is away: every training
                // not in it is held by a worker that will carry on with it.
                loop {
                    let next = queue.lock().expect("no worker panics").pop_front();
                    let Some((id, job, step, progress)) = next else {
                        lender.leave();
                        break;
                    };
                    let threads = lender.lend();
                    if pool
                        .as_ref()
                        .is_none_or(|p| p.current_num_threads() != threads)
                    {
                        pool = Some(train::pool(threads));
                    }
                    let pool = pool.as_ref().expect("made for this loan");
                    let stepped = pool.install(|| step(job, &progress));
                    lender.repay(threads);
                    place(id, stepped, step, progress);
                }
            });
        }
    });
    let mut finished = finished.into_inner().expect("no worker panics");
    finished.sort_by_key(|(id, _)| *id);
    finished
}

/// The threads of the first epochs of `trainings` trainings on `cores` cores, one per
/// worker, as [`interleave_epochs`] lends them (`bench` times a run's arrangement with them).
pub(crate) fn first_loans(cores: usize, trainings: usize) -> Vec<usize> {
    let lender = Cores::new(cores, trainings);
    (0..lender.workers()).map(|_| lender.lend()).collect()
}

/// The cores lent to the workers of [`interleave_epochs`], one epoch at a time. A
/// worker waiting for its next epoch is lent its share of the free cores (shared among
/// the waiting workers), at most its share of all of them (shared among the workers
/// still training) and no more than a batch has slices (a slice runs on one thread),
/// and at least one: the loans never add up to more than the cores, and the cores a
/// worker gives back, or leaves behind when its trainings have ended, go to the next
/// workers to start an epoch.
#[derive(Debug)]
struct Cores {
    cores: usize,
    loans: std::sync::Mutex<Loans>,
}

/// Where the cores are: free, or lent to the workers not waiting.
#[derive(Debug)]
struct Loans {
    free: usize,
    /// Workers between two epochs (each will take at least one core, or leave).
    waiting: usize,
    /// Workers that have not left.
    workers: usize,
}

impl Cores {
    /// The workers of `trainings` trainings on `cores` cores (at least one): as many as
    /// trainings, up to one per core, and at least one; all waiting.
    fn new(cores: usize, trainings: usize) -> Self {
        assert!(cores >= 1, "at least one core");
        let workers = cores.min(trainings).max(1);
        let loans = Loans {
            free: cores,
            waiting: workers,
            workers,
        };
        Self {
            cores,
            loans: std::sync::Mutex::new(loans),
        }
    }

    /// The workers that have not left.
    fn workers(&self) -> usize {
        self.loans.lock().expect("no worker panics").workers
    }

    /// The threads of a waiting worker's next epoch. The free cores never fall below the
    /// waiting workers: `⌈free / waiting⌉ ≤ free − (waiting − 1)`.
    fn lend(&self) -> usize {
        let mut loans = self.loans.lock().expect("no worker panics");
        let share_of_free = loans.free.div_ceil(loans.waiting);
        let share = self.cores.div_ceil(loans.workers).min(SLICES);
        let threads = share_of_free.min(share);
        loans.free -= threads;
        loans.waiting -= 1;
        debug_assert!(threads >= 1 && loans.free >= loans.waiting);
        threads
    }

    /// `threads` cores back from a worker's epoch; it waits for its next.
    fn repay(&self, threads: usize) {
        let mut loans = self.loans.lock().expect("no worker panics");
        loans.free += threads;
        loans.waiting += 1;
    }

    /// A waiting worker finds no training left and leaves.
    fn leave(&self) {
        let mut loans = self.loans.lock().expect("no worker panics");
        loans.waiting -= 1;
        loans.workers -= 1;
    }
}

/// Generates dataset `d` from the spec of its first point.
fn generate_dataset(plan: &Plan, d: usize, stages: &mut StageSeconds) -> TrainingSet {
    let dataset = &plan.datasets[d];
    let spec = plan.spec(dataset.point);
    let clock = Instant::now();
    let task = format!("dataset {}", &dataset.key[..16]);
    let progress = Progress::new(task.clone(), spec.grid.points().len(), "combinations");
    let set = dataset::generate(spec, &plan.trajectories[dataset.point], &progress);
    progress.finish();
    stages.dataset += clock.elapsed().as_secs_f64();
    eprintln!(
        "{task}: {} combinations × {} windows = {} windows ({} validation), {:.1} MB, in {:.2} s",
        set.points.len(),
        set.windows_per_combination,
        set.len(),
        set.validation_len(),
        TrainingSet::size_bytes(set.len() as f64, set.window as f64) / 1e6,
        clock.elapsed().as_secs_f64()
    );
    set
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    #[test]
    fn five_models_on_16_cores_get_4_3_3_3_3_and_the_cores_of_one_that_ends() {
        assert_eq!(first_loans(16, 5), [4, 3, 3, 3, 3]);
        assert_eq!(first_loans(2, 5), [1, 1]);
        let lender = Cores::new(16, 5);
        let first: Vec<usize> = (0..5).map(|_| lender.lend()).collect();
        assert_eq!(first, [4, 3, 3, 3, 3]);
        // The first model ends: its worker gives its cores back and leaves.
        lender.repay(4);
        lender.leave();
        // The other four, at their next epochs, take a quarter of the cores each.
        let next: Vec<usize> = (0..4)
            .map(|_| {
                lender.repay(3);
                lender.lend()
            })
            .collect();
        assert_eq!(next, [4, 4, 4, 4]);
        // The last model left trains on as many cores as a batch has slices.
        for _ in 0..3 {
            lender.repay(4);
            lender.leave();
        }
        lender.repay(4);
        assert_eq!(lender.lend(), SLICES);
    }

    /// Workers that start, end and leave in a random order: a loan is never empty, the
    /// loans never exceed the cores, and once every worker has started an epoch since
    /// the last one left, no core is idle that a worker could use.
    #[test]
    fn loans_never_exceed_the_cores_and_leave_none_idle() {
        #[derive(Clone, Copy, PartialEq)]
        enum Worker {
            Waiting,
            Training(usize),
            Left,
        }
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(40);
        for _ in 0..500 {
            let cores = rng.random_range(1..=3 * SLICES);
            let mut workers = vec![Worker::Waiting; rng.random_range(1..=cores)];
            let lender = Cores::new(cores, workers.len());
            let mut started_since_a_leave = vec![false; workers.len()];
            for _ in 0..200 {
                let w = rng.random_range(0..workers.len());
                match workers[w] {
                    Worker::Waiting if rng.random_bool(0.05) => {
                        lender.leave();
                        workers[w] = Worker::Left;
                        started_since_a_leave.fill(false);
                    }
                    Worker::Waiting => {
                        let threads = lender.lend();
                        assert!(threads >= 1);
                        workers[w] = Worker::Training(threads);
                        started_since_a_leave[w] = true;
                    }
                    Worker::Training(threads) => {
                        lender.repay(threads);
                        workers[w] = Worker::Waiting;
                    }
                    Worker::Left => continue,
                }
                let lent: usize = workers
                    .iter()
                    .map(|w| match w {
                        Worker::Training(threads) => *threads,
                        _ => 0,
                    })
                    .sum();
                assert!(lent <= cores, "{lent} threads lent on {cores} cores");
                let all_started =
                    workers
                        .iter()
                        .zip(&started_since_a_leave)
                        .all(|(worker, &started)| {
                            *worker == Worker::Left || (started && *worker != Worker::Waiting)
                        });
                let training = workers.iter().filter(|w| **w != Worker::Left).count();
                if all_started && training > 0 {
                    let usable = cores.min(training * SLICES);
                    assert_eq!(lent, usable, "every worker training, yet cores idle");
                }
            }
        }
    }
}
