//! Closed-loop training of one DCNet per error model. In: the spec and the training
//! set. Out: the weights with the best validation loss, the per-epoch history, and why
//! training ended (every epoch, or `training.early_stopping`).
//!
//! The loss corrects each window's DVL velocity with the predicted terms and takes the
//! squared error against the ground truth in (cm/s)², summed over x, y, z and averaged
//! over samples and windows (docs/paper.md, "DCNet"). RMSProp updates the weights. Initial weights,
//! the order of the windows in every epoch and the dropout masks come from generators
//! seeded by (seed, error model, epoch, replicate), so a model does not depend on the
//! thread count or on the other models training beside it; replicate 0 (the only one
//! without `training.replicates`) draws from the streams of (seed, error model, epoch).

use crate::dataset::{INPUT_ROWS, TARGET_ROWS, TrainingSet};
use crate::kernels;
use crate::model::{
    BatchBuffers, Dcnet, NetworkIo, Settings, Windows, split_terms, term_columns, truth_cm_s,
};
use crate::progress::Progress;
use crate::rmsprop::RmsProp;
use crate::rng::task_rng;
use crate::spec::{ModelSpec, Spec, TrainingSpec};
use crate::vocab::{ErrorModel, StopReason};
use burn::module::Module;
use burn::tensor::{Device, Tensor};
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// How one model trained: its cache key, every epoch's losses, the epoch whose
/// weights it kept and why it stopped; the `.json` beside a stored model.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct TrainingHistory {
    pub key: String,
    pub error_model: ErrorModel,
    /// Which of `training.replicates` it is; absent for replicate 0, as before replicates.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub replicate: usize,
    pub best_epoch: usize,
    pub history: Vec<EpochRecord>,
    pub stop: StopReason,
}

/// One epoch of one model.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EpochRecord {
    pub epoch: usize,
    /// Mean closed-loop loss over the epoch's training windows, (cm/s)².
    pub train_loss: f64,
    /// Closed-loop loss on the validation windows after the epoch, (cm/s)².
    pub validation_loss: f64,
    pub seconds: f64,
    pub samples_per_s: f64,
}

#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    #[error(
        "DCNet {model}: the training loss became {loss} at epoch {epoch}, batch {batch}; training of {model} stopped (try a lower {learning_rate_key})"
    )]
    NonFinite {
        model: String,
        learning_rate_key: String,
        epoch: usize,
        batch: usize,
        loss: f32,
    },
    #[error("DCNet {model}: no training windows (is {validation_key} leaving none?)")]
    NoData {
        model: String,
        validation_key: String,
    },
}

/// What a training needs besides its windows: the network's sizes, the training
/// settings, the learning rate, and the name that seeds its random streams.
pub struct Recipe<'a> {
    pub seed: u64,
    pub model: &'a ModelSpec,
    pub training: &'a TrainingSpec,
    pub learning_rate: f64,
    /// Names the model in its random streams and its errors: the error model ("EM5")
    /// for the paper's.
    pub name: String,
    /// The spec keys an error names: the learning rate, and the validation share.
    pub learning_rate_key: String,
    pub validation_key: String,
}

impl<'a> Recipe<'a> {
    /// The paper's DCNet for `error_model`.
    pub fn paper(spec: &'a Spec, error_model: ErrorModel) -> Self {
        Recipe {
            seed: spec.seed,
            model: &spec.model,
            training: &spec.training,
            learning_rate: spec.training.learning_rate(error_model),
            name: error_model.to_string(),
            learning_rate_key: format!("training.learning_rate.{error_model}"),
            validation_key: "dataset.validation_fraction".to_string(),
        }
    }
}

/// Windows a DCNet trains on, and its closed-loop loss on some of them.
pub trait Windowed: Sync {
    fn len(&self) -> usize;
    fn is_validation(&self, window: usize) -> bool;
    /// The loss of `model` on windows `indices`, dropout masks drawn from `dropout_rng`
    /// when given (training).
    fn loss(
        &self,
        model: &Dcnet,
        indices: &[usize],
        settings: &Settings,
        device: &Device,
        dropout_rng: Option<&mut ChaCha8Rng>,
    ) -> Tensor<1>;
}

/// The paper's training set, for one error model.
pub struct PaperWindows<'a> {
    pub set: &'a TrainingSet,
    pub error_model: ErrorModel,
}

impl Windowed for PaperWindows<'_> {
    fn len(&self) -> usize {
        self.set.len()
    }

    fn is_validation(&self, window: usize) -> bool {
        self.set.is_validation[window]
    }

    fn loss(
        &self,
        model: &Dcnet,
        indices: &[usize],
        settings: &Settings,
        device: &Device,
        dropout_rng: Option<&mut ChaCha8Rng>,
    ) -> Tensor<1> {
        let (windows, truth) = batch_of(self.set, indices, settings, device);
        let terms = model.forward(&windows, settings, dropout_rng);
        closed_loop_loss(terms, self.error_model, windows.dvl_cm_s, truth)
    }
}

fn is_zero(value: &usize) -> bool {
    *value == 0
}

/// A trained model: the weights of its best validation epoch, on a plain (no autodiff)
/// device, ready for inference.
#[derive(Debug, Clone)]
pub struct Trained {
    pub error_model: ErrorModel,
    /// Which of `training.replicates` it is.
    pub replicate: usize,
    pub model: Dcnet,
    pub history: Vec<EpochRecord>,
    pub best_epoch: usize,
    pub stop: StopReason,
}

/// Training state that an epoch advances; a checkpoint saves exactly this.
pub struct State {
    /// Which of `training.replicates` this training is; it seeds the streams.
    pub replicate: usize,
    pub model: Dcnet,
    pub optimizer: RmsProp,
    pub best: Option<(usize, f64, Dcnet)>,
    pub history: Vec<EpochRecord>,
}

impl State {
    /// Fresh weights for replicate `replicate` of `error_model`, on the autodiff device
    /// of the spec's backend.
    pub fn new(spec: &Spec, error_model: ErrorModel, replicate: usize) -> Self {
        let recipe = Recipe::paper(spec, error_model);
        Self::of(&recipe, error_model, spec.dataset.window_samples, replicate)
    }

    /// Fresh weights of shape `io` on windows of `window` samples, for replicate
    /// `replicate` of `recipe`.
    pub fn of(recipe: &Recipe, io: impl Into<NetworkIo>, window: usize, replicate: usize) -> Self {
        let device = recipe.training.backend.device().autodiff();
        let mut rng = model_rng(recipe, "dcnet-init", replicate, None);
        let model = Dcnet::new(recipe.model, io, window, &device, &mut rng);
        Self {
            replicate,
            model,
            optimizer: optimizer(recipe.training),
            best: None,
            history: Vec::new(),
        }
    }

    pub fn next_epoch(&self) -> usize {
        self.history.len() + 1
    }

    /// Why training is over, or `None` while epochs remain.
    pub fn stop(&self, training: &TrainingSpec) -> Option<StopReason> {
        if self.history.len() >= training.epochs {
            return Some(StopReason::AllEpochs);
        }
        let rule = training.early_stopping?;
        (epochs_without_improvement(&self.history, rule.min_improvement) >= rule.patience)
            .then_some(StopReason::EarlyStopping)
    }

    /// The best weights and the history, once [`State::stop`] says why training ended.
    pub fn finish(self, error_model: ErrorModel, stop: StopReason) -> Trained {
        let (best_epoch, _, model) = self.best.expect("at least one epoch ran");
        Trained {
            error_model,
            replicate: self.replicate,
            model,
            history: self.history,
            best_epoch,
            stop,
        }
    }
}

pub fn optimizer(training: &TrainingSpec) -> RmsProp {
    RmsProp::new(
        training.rmsprop_alpha as f32,
        training.rmsprop_epsilon as f32,
    )
}

/// The closed-loop loss of `terms` `[batch, n]` on windows whose DVL velocity is
/// `dvl_cm_s` `[batch, time, 3]` and ground truth `truth_cm_s` `[batch, time, 3]`, in
/// (cm/s)².
pub fn closed_loop_loss(
    terms: Tensor<2>,
    error_model: ErrorModel,
    dvl_cm_s: Tensor<3>,
    truth_cm_s: Tensor<3>,
) -> Tensor<1> {
    if kernels::network::runs_on(&terms) {
        let columns = term_columns(error_model);
        return kernels::loss::closed_loop_loss(terms, columns, dvl_cm_s, truth_cm_s);
    }
    composed_closed_loop_loss(terms, error_model, dvl_cm_s, truth_cm_s)
}

/// [`closed_loop_loss`] composed of burn's operations.
fn composed_closed_loop_loss(
    terms: Tensor<2>,
    error_model: ErrorModel,
    dvl_cm_s: Tensor<3>,
    truth_cm_s: Tensor<3>,
) -> Tensor<1> {
    let [batch, time, axes] = dvl_cm_s.dims();
    let (scale_pct, bias_cm_s) = split_terms(terms, error_model);
    let per_window = |terms: Tensor<2>| -> Tensor<3> {
        terms.reshape([batch, 1, axes]).expand([batch, time, axes])
    };
    let corrected = (dvl_cm_s - per_window(bias_cm_s)) / (per_window(scale_pct) / 100.0 + 1.0);
    (corrected - truth_cm_s).square().sum() / (batch * time) as f64
}

/// Windows `indices` of `set`, ready for the network, and their ground truth.
fn batch_of<'a>(
    set: &'a TrainingSet,
    indices: &[usize],
    settings: &Settings,
    device: &Device,
) -> (Windows, Tensor<3>) {
    let w = set.window;
    // Each window's `rows × w` values of `values`, where they lie.
    let windows = |values: &'a [f32], rows: usize| -> Vec<&'a [f32]> {
        let size = rows * w;
        indices
            .iter()
            .map(|&i| &values[i * size..][..size])
            .collect()
    };
    BATCH_BUFFERS.with_borrow_mut(|buffers| {
        (
            Windows::of(
                &windows(&set.inputs, INPUT_ROWS),
                INPUT_ROWS,
                w,
                settings.kernel,
                device,
                buffers,
            ),
            truth_cm_s(&windows(&set.targets, TARGET_ROWS), w, device, buffers),
        )
    })
}

thread_local! {
    /// The buffers of the last batch this thread made: a model's steps run on one thread,
    /// so each step's batch reuses the last one's.
    static BATCH_BUFFERS: RefCell<BatchBuffers> = RefCell::default();
}

/// Mean closed-loop loss of `model` (plain device) over `indices` of `data`, in batches.
pub fn mean_loss(recipe: &Recipe, model: &Dcnet, data: &impl Windowed, indices: &[usize]) -> f64 {
    let device = recipe.training.backend.device();
    let settings = Settings::from(recipe.model);
    let mut total = 0.0;
    for chunk in indices.chunks(recipe.training.batch_size.max(1024)) {
        let loss: f32 = data
            .loss(model, chunk, &settings, &device, None)
            .into_scalar();
        total += f64::from(loss) * chunk.len() as f64;
    }
    total / indices.len().max(1) as f64
}

/// The generator of `stream` ("dcnet-init", "dcnet-shuffle", "dcnet-dropout") for
/// replicate `replicate` of `recipe`'s DCNet, at `epoch` where the stream has one.
/// Replicate 0 draws what a run without replicates draws.
fn model_rng(recipe: &Recipe, stream: &str, replicate: usize, epoch: Option<usize>) -> ChaCha8Rng {
    let mut parts: Vec<&dyn std::fmt::Display> = vec![&stream, &recipe.name];
    if let Some(epoch) = &epoch {
        parts.push(epoch);
    }
    if replicate > 0 {
        parts.extend([&"replicate" as &dyn std::fmt::Display, &replicate]);
    }
    task_rng(recipe.seed, &parts)
}

/// The training windows of `data` in the order epoch `epoch` of replicate `replicate`
/// visits them.
pub fn epoch_order(
    recipe: &Recipe,
    data: &impl Windowed,
    replicate: usize,
    epoch: usize,
) -> Vec<usize> {
    let mut order: Vec<usize> = (0..data.len())
        .filter(|&i| !data.is_validation(i))
        .collect();
    order.shuffle(&mut model_rng(
        recipe,
        "dcnet-shuffle",
        replicate,
        Some(epoch),
    ));
    order
}

/// One optimizer step per batch of `order`, as epoch `epoch` (which seeds the dropout
/// masks). Returns the sum of the batch losses weighted by batch size. `progress`
/// advances by each batch's samples.
pub fn train_pass(
    recipe: &Recipe,
    data: &impl Windowed,
    state: &mut State,
    epoch: usize,
    order: &[usize],
    progress: &Progress,
) -> Result<f64, TrainError> {
    let device = recipe.training.backend.device().autodiff();
    let settings = Settings::from(recipe.model);
    let mut dropout_rng = model_rng(recipe, "dcnet-dropout", state.replicate, Some(epoch));
    let mut loss_sum = 0.0;
    let model = with_pool_awake(|| {
        let mut model = state.model.clone();
        for (batch, indices) in order.chunks(recipe.training.batch_size).enumerate() {
            let loss = data.loss(&model, indices, &settings, &device, Some(&mut dropout_rng));
            let value: f32 = loss.clone().into_scalar();
            if !value.is_finite() {
                return Err(TrainError::NonFinite {
                    model: recipe.name.clone(),
                    learning_rate_key: recipe.learning_rate_key.clone(),
                    epoch,
                    batch: batch + 1,
                    loss: value,
                });
            }
            loss_sum += f64::from(value) * indices.len() as f64;
            progress.set_message(format!(
                "epoch {epoch}/{}, batch loss {value:.4} (cm/s)²",
                recipe.training.epochs
            ));
            let grads = loss.backward();
            model = state.optimizer.step(recipe.learning_rate, model, &grads);
            progress.inc(indices.len());
        }
        Ok(model)
    })?;
    state.model = model;
    Ok(loss_sum)
}

/// Runs the next epoch on `state`: training, then the validation loss, and keeps the
/// weights if they are the best so far.
pub fn run_epoch(
    recipe: &Recipe,
    data: &impl Windowed,
    state: &mut State,
    progress: &Progress,
) -> Result<(), TrainError> {
    let epoch = state.next_epoch();
    let clock = Instant::now();
    let order = epoch_order(recipe, data, state.replicate, epoch);
    if order.is_empty() {
        return Err(TrainError::NoData {
            model: recipe.name.clone(),
            validation_key: recipe.validation_key.clone(),
        });
    }
    let loss_sum = train_pass(recipe, data, state, epoch, &order, progress)?;
    let validation: Vec<usize> = (0..data.len()).filter(|&i| data.is_validation(i)).collect();
    let plain = state.model.valid();
    let validation_loss = if validation.is_empty() {
        f64::NAN
    } else {
        mean_loss(recipe, &plain, data, &validation)
    };
    let train_loss = loss_sum / order.len() as f64;
    let seconds = clock.elapsed().as_secs_f64();
    state.history.push(EpochRecord {
        epoch,
        train_loss,
        validation_loss,
        seconds,
        samples_per_s: order.len() as f64 / seconds,
    });
    // Without validation windows the training loss decides the best epoch.
    let score = if validation.is_empty() {
        train_loss
    } else {
        validation_loss
    };
    if state.best.as_ref().is_none_or(|(_, best, _)| score < *best) {
        state.best = Some((epoch, score, plain));
    }
    Ok(())
}

/// Epochs since the last epoch that counted as an improvement: one whose validation
/// loss fell more than `min_improvement` below that of the improvement before it (the
/// first epoch always counts), as Lightning's EarlyStopping counts. Without validation
/// windows (a NaN validation loss) the training loss stands in, as it does for the best
/// epoch.
pub fn epochs_without_improvement(history: &[EpochRecord], min_improvement: f64) -> usize {
    let mut best = f64::INFINITY;
    let mut since = 0;
    for record in history {
        let score = if record.validation_loss.is_nan() {
            record.train_loss
        } else {
            record.validation_loss
        };
        if score < best - min_improvement {
            best = score;
            since = 0;
        } else {
            since += 1;
        }
    }
    since
}

/// The seconds one training batch of `error_model` takes on one thread of this
/// machine, as `run` trains: the faster of two steps over a batch of windows at rest,
/// at a learning rate of zero (a step's time does not depend on the values, and a
/// learning rate that diverges is the training's to report, not the probe's).
pub fn seconds_per_batch(spec: &Spec, error_model: ErrorModel) -> Result<f64, TrainError> {
    let (batch, window) = (spec.training.batch_size, spec.dataset.window_samples);
    let set = TrainingSet {
        points: Vec::new(),
        window,
        windows_per_combination: batch,
        inputs: vec![0.0; batch * INPUT_ROWS * window],
        targets: vec![0.0; batch * TARGET_ROWS * window],
        is_validation: vec![false; batch],
    };
    let order: Vec<usize> = (0..batch).collect();
    let mut state = State::new(spec, error_model, 0);
    let hidden = Progress::hidden();
    let recipe = Recipe {
        learning_rate: 0.0,
        ..Recipe::paper(spec, error_model)
    };
    let data = PaperWindows {
        set: &set,
        error_model,
    };
    pool(1).install(|| {
        let mut fastest = f64::INFINITY;
        for epoch in 1..=2 {
            let clock = Instant::now();
            train_pass(&recipe, &data, &mut state, epoch, &order, &hidden)?;
            fastest = fastest.min(clock.elapsed().as_secs_f64());
        }
        Ok(fastest)
    })
}

/// A pool of `threads` threads for one training: the slices of its batches
/// ([`crate::kernels::network`]) run on them, and its bytes are the same on any number.
pub fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .build()
        .expect("a thread pool")
}

/// Runs `f` with the other threads of the current rayon pool kept awake: each runs the
/// pool's jobs as they come instead of going to sleep between them. A training step has
/// several parallel sections (the batch's windows, the slices forward and backward, their
/// gradients' sum, RMSProp's chunks) with serial work between them, and a rayon thread
/// that finds no work sleeps after a few dozen yields; waking it took tens of
/// microseconds on a virtual machine, at the start and the end of each section. The
/// threads stay busy while `f` runs, so call it only on a pool whose cores are the
/// model's own, from the thread that entered the pool (`install`), one call at a time.
/// Outside a pool, on a pool of one thread, and inside a job that a kept-awake thread
/// runs, `f` just runs.
///
/// A thread joins the helpers only before `f` starts ([`HelperGate`]): a helper's loop
/// holds its thread until `f` is done, so a thread that took it up while it waited in a
/// join on a job of `f` would never return to that join, and `f` would wait on it for
/// ever (a training hung so, once in three runs of the test suite).
pub fn with_pool_awake<R>(f: impl FnOnce() -> R) -> R {
    let Some(owner) = rayon::current_thread_index() else {
        return f();
    };
    let threads = rayon::current_num_threads();
    if threads == 1 || HELPING.get() {
        return f();
    }
    /// Ends the helpers' loops however `f` ends, a panic included.
    struct Done<'a>(&'a AtomicBool);
    impl Drop for Done<'_> {
        fn drop(&mut self) {
            self.0.store(true, Ordering::Release);
        }
    }
    let done = AtomicBool::new(false);
    let gate = HelperGate::default();
    rayon::in_place_scope(|scope| {
        // One job on every thread of the pool; the owner's returns at once.
        scope.spawn_broadcast(|_, context| {
            if context.index() == owner || !gate.enter() {
                return;
            }
            HELPING.set(true);
            let mut idle = Idle::default();
            while !done.load(Ordering::Acquire) {
                let worked = rayon::yield_now() == Some(rayon::Yield::Executed);
                match idle.after(worked, Instant::now()) {
                    Wait::None => {}
                    Wait::Spin => std::hint::spin_loop(),
                    Wait::Yield => std::thread::yield_now(),
                }
            }
            HELPING.set(false);
        });
        gate.close_when(threads - 1, Instant::now() + CHECK_IN);
        let _done = Done(&done);
        f()
    })
}

/// How long the owner of [`with_pool_awake`] waits for the pool's other threads to wake
/// and join the helpers before `f` starts: a thread wakes in tens of microseconds when
/// its core is free; one slower than this (its core busy elsewhere) sits this call out.
/// Once per epoch, it is nothing beside the epoch.
const CHECK_IN: Duration = Duration::from_millis(10);

/// The door through which threads join the helpers of [`with_pool_awake`], open until
/// `f` starts. The count of threads in and whether the door is closed share one word, so
/// that no thread comes in after it closes.
#[derive(Default)]
struct HelperGate(AtomicUsize);

impl HelperGate {
    const CLOSED: usize = 1 << (usize::BITS - 1);

    /// Comes in if the door is still open; false once `f` has started.
    fn enter(&self) -> bool {
        let open = |state: usize| (state & Self::CLOSED == 0).then_some(state + 1);
        self.0
            .fetch_update(Ordering::AcqRel, Ordering::Acquire, open)
            .is_ok()
    }

    /// Waits until `helpers` threads are in or `deadline` passes, then closes the door.
    fn close_when(&self, helpers: usize, deadline: Instant) {
        let mut idle = Idle::default();
        while self.0.load(Ordering::Acquire) < helpers && Instant::now() < deadline {
            match idle.after(false, Instant::now()) {
                Wait::Yield => std::thread::yield_now(),
                _ => std::hint::spin_loop(),
            }
        }
        self.0.fetch_or(Self::CLOSED, Ordering::AcqRel);
    }
}

/// How long a kept-awake thread finds no work before it offers its core to the
/// operating system's other threads between its looks for work: far longer than the
/// serial parts of a step (tens of microseconds), so that a training with cores of its
/// own keeps them, but short enough that where threads outnumber the cores (more
/// `--threads` than cores, or other programs busy) the thread that holds the step is not
/// kept off a core by one that waits for it.
const SPIN_BEFORE_YIELD: Duration = Duration::from_micros(200);

/// What a kept-awake thread does before it looks for work again.
#[derive(Debug, PartialEq, Eq)]
enum Wait {
    /// Look again at once: it has just run a job.
    None,
    /// Spin a moment: it has been idle less than [`SPIN_BEFORE_YIELD`].
    Spin,
    /// Offer its core to the operating system's other threads.
    Yield,
}

/// How long a kept-awake thread has found no work.
#[derive(Debug, Default)]
struct Idle {
    since: Option<Instant>,
}

impl Idle {
    /// The wait after a look for work at `now` that ran a job (`worked`) or found none.
    fn after(&mut self, worked: bool, now: Instant) -> Wait {
        if worked {
            self.since = None;
            return Wait::None;
        }
        let since = *self.since.get_or_insert(now);
        if now - since < SPIN_BEFORE_YIELD {
            Wait::Spin
        } else {
            Wait::Yield
        }
    }
}

thread_local! {
    /// Whether this thread is kept awake by [`with_pool_awake`] for another thread.
    static HELPING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::spec::quick_spec;

    /// The training set of `spec`.
    pub(crate) fn training_set(spec: &Spec) -> TrainingSet {
        let trajectories = crate::data::load_trajectories(spec).unwrap();
        crate::dataset::generate(spec, &trajectories, &Progress::hidden())
    }

    /// Runs `epochs` more epochs of `error_model` on `state`.
    pub(crate) fn run_epochs(
        spec: &Spec,
        set: &TrainingSet,
        error_model: ErrorModel,
        state: &mut State,
        epochs: usize,
    ) {
        let recipe = Recipe::paper(spec, error_model);
        let data = PaperWindows { set, error_model };
        for _ in 0..epochs {
            run_epoch(&recipe, &data, state, &Progress::hidden()).unwrap();
        }
    }
    use crate::estimators::Estimator;
    use burn::tensor::TensorData;

    /// With the pool kept awake, `f`'s parallel work runs on every thread of the pool and
    /// its result comes back; a panic in `f` comes out of it too, instead of leaving the
    /// helpers waiting; on one thread, and outside a pool, `f` just runs.
    #[test]
    fn a_pool_kept_awake_runs_the_work_and_lets_go_of_its_threads() {
        use rayon::prelude::*;
        let pool = pool(3);
        let threads = pool.install(|| {
            with_pool_awake(|| {
                let threads = (0..64).into_par_iter().map(|_| {
                    std::thread::sleep(std::time::Duration::from_millis(2));
                    rayon::current_thread_index()
                });
                threads.collect::<std::collections::BTreeSet<_>>()
            })
        });
        assert_eq!(threads.len(), 3, "threads used: {threads:?}");
        let panicked = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            pool.install(|| with_pool_awake(|| panic!("inside")))
        }));
        assert!(panicked.is_err());
        assert_eq!(pool.install(|| with_pool_awake(|| 7)), 7);
        assert_eq!(super::pool(1).install(|| with_pool_awake(|| 8)), 8);
        assert_eq!(with_pool_awake(|| 9), 9);
    }

    /// Every other thread of a pool of four is kept awake: the jobs of `f` that run on
    /// them run from the helpers' loop. (Helper jobs queued on the owner's deque were
    /// all taken by the first thread to wake, which left the others asleep.)
    #[test]
    fn every_other_thread_of_the_pool_is_kept_awake() {
        use rayon::prelude::*;
        let helped = pool(4).install(|| {
            with_pool_awake(|| {
                let deadline = Instant::now() + std::time::Duration::from_secs(20);
                let mut helped = std::collections::BTreeSet::new();
                while helped.len() < 3 && Instant::now() < deadline {
                    let jobs = (0..64).into_par_iter().map(|_| {
                        std::thread::sleep(std::time::Duration::from_micros(50));
                        (rayon::current_thread_index(), HELPING.get())
                    });
                    let jobs: Vec<_> = jobs.collect();
                    helped.extend(jobs.into_iter().filter(|job| job.1).map(|job| job.0));
                }
                helped
            })
        });
        assert_eq!(helped.len(), 3, "threads kept awake: {helped:?}");
    }

    /// Threads that are still busy with a job of `f` when the helpers' jobs come do not
    /// take one up in the middle of it: jobs of `f` that join jobs of their own, called
    /// thousands of times on a pool of two beside four threads that keep the cores busy,
    /// all come back. (Without the gate, a thread that became a helper inside such a join
    /// held it until `f` was done and `f` waited on it for ever: four runs of this test
    /// hung at rounds 1,305, 1,796, 3,530 and 5,932.)
    #[test]
    fn a_thread_busy_with_the_work_never_becomes_a_helper_in_the_middle_of_it() {
        use rayon::prelude::*;
        let (sender, receiver) = std::sync::mpsc::channel();
        /// Stops the busy threads however the test ends.
        struct Stop(std::sync::Arc<AtomicBool>);
        impl Drop for Stop {
            fn drop(&mut self) {
                self.0.store(true, Ordering::Relaxed);
            }
        }
        let stop = std::sync::Arc::new(AtomicBool::new(false));
        let _stop = Stop(stop.clone());
        for _ in 0..4 {
            let stop = stop.clone();
            std::thread::spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    std::hint::spin_loop()
                }
            });
        }
        std::thread::spawn(move || {
            let pool = pool(2);
            for round in 0..8_000_u64 {
                let sum = pool.install(|| {
                    with_pool_awake(|| {
                        (0..8_u64)
                            .into_par_iter()
                            .map(|i| {
                                let (a, b) = rayon::join(
                                    || (0..4_u64).into_par_iter().map(|j| i * j).sum::<u64>(),
                                    || (0..4_u64).into_par_iter().map(|j| i + j).sum::<u64>(),
                                );
                                a + b
                            })
                            .sum::<u64>()
                    })
                });
                sender.send((round, sum)).unwrap();
            }
        });
        for round in 0..8_000_u64 {
            let (done, sum) = receiver
                .recv_timeout(Duration::from_secs(60))
                .unwrap_or_else(|_| panic!("round {round} of the kept-awake pool never ended"));
            assert_eq!((done, sum), (round, 6 * 28 + 4 * 28 + 8 * 6));
        }
    }

    /// A kept-awake thread spins while it has been idle less than 200 µs, then offers its
    /// core between its looks for work, and spins again once it has run a job.
    #[test]
    fn an_idle_helper_spins_then_offers_its_core_until_it_works_again() {
        let start = Instant::now();
        let at = |us: u64| start + Duration::from_micros(us);
        let mut idle = Idle::default();
        assert_eq!(idle.after(true, at(0)), Wait::None);
        assert_eq!(idle.after(false, at(10)), Wait::Spin);
        assert_eq!(idle.after(false, at(209)), Wait::Spin, "idle since 10 µs");
        assert_eq!(idle.after(false, at(210)), Wait::Yield);
        assert_eq!(idle.after(false, at(5_000)), Wait::Yield);
        assert_eq!(idle.after(true, at(5_001)), Wait::None);
        assert_eq!(
            idle.after(false, at(5_100)),
            Wait::Spin,
            "idle anew since 5,100 µs"
        );
        assert_eq!(idle.after(false, at(5_300)), Wait::Yield);
    }

    /// On Flex the loss is one operation: its value and the terms' gradient are those of
    /// the loss composed of burn's operations, for every error model, on 7 windows of 5
    /// samples.
    #[test]
    fn the_loss_operation_matches_the_composed_loss() {
        use burn::tensor::TensorData;
        use rand::{RngExt, SeedableRng};
        let device = Device::flex().autodiff();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut random = |shape: Vec<usize>, spread: f32| {
            let count = shape.iter().product();
            let values: Vec<f32> = (0..count)
                .map(|_| rng.random_range(-spread..spread))
                .collect();
            TensorData::new(values, shape)
        };
        let dvl = Tensor::<3>::from_data(random(vec![7, 5, 3], 150.0), &device);
        let truth = dvl.clone() * 0.97 + Tensor::from_data(random(vec![7, 5, 3], 2.0), &device);
        for error_model in ErrorModel::ALL {
            let outputs = error_model.term_count();
            let terms = random(vec![7, outputs], 4.0);
            let loss_and_gradient = |fused: bool| {
                let terms = Tensor::<2>::from_data(terms.clone(), &device).require_grad();
                let (dvl, truth) = (dvl.clone(), truth.clone());
                let loss = if fused {
                    closed_loop_loss(terms.clone(), error_model, dvl, truth)
                } else {
                    composed_closed_loop_loss(terms.clone(), error_model, dvl, truth)
                };
                let gradient = terms.grad(&loss.backward()).expect("a gradient");
                let value: f32 = loss.into_scalar();
                (value, gradient.into_data().try_to_vec::<f32>().unwrap())
            };
            let ((fused, fused_gradient), (composed, composed_gradient)) =
                (loss_and_gradient(true), loss_and_gradient(false));
            assert!(
                (fused - composed).abs() <= 1e-5 * composed,
                "{error_model:?}: loss {fused} against {composed}"
            );
            let largest = composed_gradient.iter().fold(0f32, |m, g| m.max(g.abs()));
            assert!(
                largest > 0.0,
                "{error_model:?}: a zero gradient tests nothing"
            );
            for (i, (x, y)) in fused_gradient.iter().zip(&composed_gradient).enumerate() {
                assert!(
                    (x - y).abs() <= 1e-5 * largest,
                    "{error_model:?}, gradient {i}: {x} against {y}"
                );
            }
        }
    }

    #[test]
    fn closed_loop_loss_matches_a_hand_computed_value() {
        let device = Device::flex();
        // One window of two samples: x is 1 % too large, z carries a 0.7 cm/s bias.
        // [window, time, axis] in cm/s.
        let dvl = Tensor::<3>::from_data(
            TensorData::new(vec![101f32, 0.0, 0.7, 202.0, 0.0, 0.7], [1, 2, 3]),
            &device,
        );
        let truth = Tensor::<3>::from_data(
            TensorData::new(vec![100f32, 0.0, 0.0, 200.0, 0.0, 0.0], [1, 2, 3]),
            &device,
        );
        // EM4 removes a 0.5 cm/s z bias only: errors x 1 and 2 cm/s, z 0.2 cm/s.
        // Loss = mean over samples of the sum over axes = ((1 + 0.04) + (4 + 0.04)) / 2.
        let terms =
            Tensor::<2>::from_data(TensorData::new(vec![0.0f32, 0.0, 0.5], [1, 3]), &device);
        let loss: f32 =
            closed_loop_loss(terms, ErrorModel::Em4, dvl.clone(), truth.clone()).into_scalar();
        assert!((loss - 2.54).abs() < 1e-4, "loss {loss}");
        // EM5 with the true terms corrects exactly.
        let terms = Tensor::<2>::from_data(
            TensorData::new(vec![1.0f32, 1.0, 1.0, 0.0, 0.0, 0.7], [1, 6]),
            &device,
        );
        let loss: f32 = closed_loop_loss(terms, ErrorModel::Em5, dvl, truth).into_scalar();
        assert!(loss < 1e-6, "loss {loss}");
    }

    /// A training set with one error combination and no noise: the network has to
    /// learn constant terms, 1 % scale on every axis and the z bias of 0.7 cm/s beams.
    fn known_answer_spec() -> Spec {
        quick_spec(&[
            "grid.scale_pct.values=[1.0]",
            "grid.bias_cm_s.values=[0.7]",
            "grid.noise_cm_s.values=[0.0]",
            "sensors.gnss_noise_cm_s=0.0",
            "dataset.trajectories=[\"S1\", \"S2\", \"S3\"]",
            "model.dropout=0.0",
            "training.epochs=60",
            "training.batch_size=32",
            "training.learning_rate.EM5=1e-3",
        ])
    }

    #[test]
    fn training_learns_a_known_scale_and_bias() {
        let spec = known_answer_spec();
        let set = training_set(&spec);
        let mut state = State::new(&spec, ErrorModel::Em5, 0);
        run_epochs(
            &spec,
            &set,
            ErrorModel::Em5,
            &mut state,
            spec.training.epochs,
        );
        let trained = state.finish(ErrorModel::Em5, StopReason::AllEpochs);
        let estimator = crate::estimators::DcnetEstimator {
            model: trained.model,
            error_model: ErrorModel::Em5,
            window: spec.dataset.window_samples,
            settings: Settings::from(&spec.model),
            device: spec.training.backend.device(),
        };
        // Estimate on the (unseen) calibration trajectory, noise-free.
        let trajectories = crate::data::load_trajectories(&spec).unwrap();
        let truth = &trajectories[4].ground_truth;
        let geometry = crate::noise::BeamGeometry::janus_x(20.0);
        let errors = crate::vocab::SensorErrors::from_spec_units(1.0, 0.7, 0.0);
        let measured =
            crate::noise::measure_trajectory(&geometry, truth, &errors, 0.0, &mut task_rng(1, &[]));
        let correction = estimator.estimate(&measured.dvl[..100], &measured.gnss[..100]);
        let z_bias = 0.7 / 20f64.to_radians().cos();
        for axis in 0..3 {
            assert!(
                (correction.scale[axis] * 100.0 - 1.0).abs() < 0.15,
                "scale {:?} %",
                correction.scale.map(|k| k * 100.0)
            );
        }
        assert!(
            correction.bias_m_s[0].abs() * 100.0 < 0.15,
            "bias {:?}",
            correction.bias_m_s
        );
        assert!(
            correction.bias_m_s[1].abs() * 100.0 < 0.15,
            "bias {:?}",
            correction.bias_m_s
        );
        assert!(
            (correction.bias_m_s[2] * 100.0 - z_bias).abs() < 0.15,
            "bias {:?}",
            correction.bias_m_s
        );
    }

    /// The saved bytes of `model`'s weights.
    pub(crate) fn weights(model: &Dcnet) -> Vec<u8> {
        model.clone().into_record().into_bytes().unwrap().to_vec()
    }

    fn epoch(epoch: usize, validation_loss: f64) -> EpochRecord {
        EpochRecord {
            epoch,
            train_loss: 1.0,
            validation_loss,
            seconds: 0.0,
            samples_per_s: 0.0,
        }
    }

    #[test]
    fn early_stopping_counts_epochs_since_the_last_real_improvement() {
        let losses = [1.0, 0.8, 0.79, 0.85, 0.7, 0.75, 0.71, 0.69];
        let history: Vec<EpochRecord> = losses
            .iter()
            .enumerate()
            .map(|(i, &l)| epoch(i + 1, l))
            .collect();
        // Every fall counts without a minimum: 0.69 at epoch 8 is the last.
        assert_eq!(epochs_without_improvement(&history, 0.0), 0);
        // With 0.05 (cm/s)²: 0.8 (epoch 2) then 0.7 (epoch 5); 0.69 is too small a step.
        assert_eq!(epochs_without_improvement(&history, 0.05), 3);
        assert_eq!(epochs_without_improvement(&history[..4], 0.05), 2);
        assert_eq!(epochs_without_improvement(&[], 0.0), 0);

        let spec = quick_spec(&[
            "training.epochs=10",
            "training.early_stopping = { patience_epochs = 3, min_improvement = 0.05 }",
        ]);
        let mut state = State::new(&spec, ErrorModel::Em1, 0);
        state.history = history[..7].to_vec();
        assert_eq!(state.stop(&spec.training), None);
        state.history = history.clone();
        assert_eq!(state.stop(&spec.training), Some(StopReason::EarlyStopping));
        let plain = quick_spec(&["training.epochs=8"]);
        assert_eq!(state.stop(&plain.training), Some(StopReason::AllEpochs));
        let longer = quick_spec(&["training.epochs=9"]);
        assert_eq!(state.stop(&longer.training), None);
    }

    #[test]
    fn replicate_zero_draws_the_streams_of_a_run_without_replicates() {
        let spec = quick_spec(&["training.epochs=1"]);
        let em = ErrorModel::Em5;
        let legacy = Dcnet::new(
            &spec.model,
            em,
            spec.dataset.window_samples,
            &spec.training.backend.device().autodiff(),
            &mut task_rng(spec.seed, &[&"dcnet-init", &em]),
        );
        assert!(weights(&State::new(&spec, em, 0).model) == weights(&legacy));
        assert!(weights(&State::new(&spec, em, 1).model) != weights(&legacy));
        assert!(
            weights(&State::new(&spec, em, 1).model) != weights(&State::new(&spec, em, 2).model)
        );
        let set = training_set(&spec);
        let mut legacy_order: Vec<usize> =
            (0..set.len()).filter(|&i| !set.is_validation[i]).collect();
        legacy_order.shuffle(&mut task_rng(spec.seed, &[&"dcnet-shuffle", &em, &3]));
        let recipe = Recipe::paper(&spec, em);
        let data = PaperWindows {
            set: &set,
            error_model: em,
        };
        assert_eq!(epoch_order(&recipe, &data, 0, 3), legacy_order);
        assert_ne!(epoch_order(&recipe, &data, 1, 3), legacy_order);
    }

    #[test]
    fn one_two_and_three_threads_train_identical_weights() {
        let spec = quick_spec(&["training.epochs=2", "training.batch_size=256"]);
        let set = training_set(&spec);
        let train_with = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut state = State::new(&spec, ErrorModel::Em5, 0);
                run_epochs(&spec, &set, ErrorModel::Em5, &mut state, 2);
                (
                    weights(&state.model),
                    state
                        .history
                        .iter()
                        .map(|e| (e.train_loss, e.validation_loss))
                        .collect::<Vec<_>>(),
                )
            })
        };
        let (one, history_one) = train_with(1);
        for threads in [2, 3] {
            // Three threads share the 8 slices unevenly.
            let (other, history_other) = train_with(threads);
            assert!(
                one == other,
                "weights differ between 1 and {threads} threads"
            );
            assert_eq!(history_one, history_other);
        }
        // And training moved the weights away from their initial values.
        assert!(weights(&State::new(&spec, ErrorModel::Em5, 0).model) != one);
    }

    #[test]
    fn flex_and_ndarray_compute_the_same_training() {
        let history = |backend: &str| {
            let spec = quick_spec(&[
                "training.epochs=1",
                &format!("training.backend={backend:?}"),
            ]);
            let mut state = State::new(&spec, ErrorModel::Em2, 0);
            run_epochs(&spec, &training_set(&spec), ErrorModel::Em2, &mut state, 1);
            state.history[0].clone()
        };
        let (flex, ndarray) = (history("flex"), history("ndarray"));
        assert!(
            (flex.train_loss - ndarray.train_loss).abs() < 1e-4 * flex.train_loss,
            "{flex:?} vs {ndarray:?}"
        );
        assert!(
            (flex.validation_loss - ndarray.validation_loss).abs() < 1e-4 * flex.validation_loss,
            "{flex:?} vs {ndarray:?}"
        );
    }

    #[test]
    fn a_batch_is_timed_whatever_the_learning_rate() {
        // 1e30 turns EM5's loss to NaN at its second step in training.
        let spec = quick_spec(&["training.learning_rate.EM5=1e30"]);
        let seconds = seconds_per_batch(&spec, ErrorModel::Em5).expect("the probe learns nothing");
        assert!(seconds > 0.0 && seconds.is_finite(), "{seconds}");
    }

    #[test]
    fn a_non_finite_loss_stops_training_with_the_model_and_epoch() {
        let spec = quick_spec(&["training.learning_rate.EM3=1e30"]);
        let set = training_set(&spec);
        let mut state = State::new(&spec, ErrorModel::Em3, 0);
        let recipe = Recipe::paper(&spec, ErrorModel::Em3);
        let data = PaperWindows {
            set: &set,
            error_model: ErrorModel::Em3,
        };
        let error = (0..spec.training.epochs)
            .find_map(|_| run_epoch(&recipe, &data, &mut state, &Progress::hidden()).err())
            .expect("a learning rate of 1e30 diverges");
        let message = error.to_string();
        assert!(
            matches!(
                error,
                TrainError::NonFinite {
                    ref model,
                    epoch: 1,
                    ..
                } if model == "EM3"
            ),
            "{message}"
        );
        assert!(
            message.starts_with("DCNet EM3: the training loss became"),
            "{message}"
        );
    }
}
