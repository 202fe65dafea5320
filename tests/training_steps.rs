//! A warm training step touches no fresh memory and allocates nothing per window: after a
//! warm-up, most rounds of 100 steps take no minor page fault at all, on one thread or
//! two, and the allocator calls of a step (about 870, burn's tensors and autodiff nodes
//! and the matrix products' scratch) do not grow with the batch. Counts, not times; this
//! file is its own test binary, so nothing else runs while it counts.

use dcnet_exp::memory::{
    CountingAllocator, count_allocations, keep_freed_memory, minor_page_faults,
};
use dcnet_exp::progress::Progress;
use dcnet_exp::train::{self, PaperWindows, Recipe, State};
use dcnet_exp::vocab::ErrorModel;

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

const STEPS_PER_ROUND: usize = 100;

/// The quick spec's EM5 model trained at `batch` on `threads` threads: 100 steps of
/// warm-up, then `rounds` rounds of [`STEPS_PER_ROUND`] steps over the same windows.
/// Returns each round's minor page faults and the allocator calls per step of the last.
fn rounds(batch: usize, threads: usize, rounds: usize) -> (Vec<u64>, f64) {
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let overrides = [
        format!("training.batch_size={batch}"),
        "dataset.stride_s=1.0".into(),
        r#"dataset.trajectories=["S1", "S2", "S3", "S4"]"#.into(),
    ];
    let spec = dcnet_exp::spec::load(&repo.join("experiments/quick.toml"), &overrides)
        .expect("the quick spec loads");
    let trajectories = dcnet_exp::data::load_trajectories(&spec).expect("synthetic trajectories");
    let set = dcnet_exp::dataset::generate(&spec, &trajectories, &Progress::hidden());
    let em = ErrorModel::Em5;
    let recipe = Recipe::paper(&spec, em);
    let data = PaperWindows {
        set: &set,
        error_model: em,
    };
    let order = train::epoch_order(&recipe, &data, 0, 1);
    assert!(
        order.len() >= 2 * STEPS_PER_ROUND * batch,
        "{} windows",
        order.len()
    );
    let (warm_up, round) = order.split_at(STEPS_PER_ROUND * batch);
    let round = &round[..STEPS_PER_ROUND * batch];
    let mut state = State::new(&spec, em, 0);
    let hidden = Progress::hidden();
    let pool = train::pool(threads);
    let mut pass = |windows: &[usize]| {
        pool.install(|| train::train_pass(&recipe, &data, &mut state, 1, windows, &hidden))
            .expect("training runs")
    };
    pass(warm_up);
    let mut faults = Vec::new();
    for _ in 0..rounds {
        let before = minor_page_faults().expect("getrusage counts page faults here");
        pass(round);
        faults.push(minor_page_faults().unwrap() - before);
    }
    let (_, calls) = count_allocations(|| pass(round));
    let calls = calls.expect("the counting allocator is installed");
    (faults, calls as f64 / STEPS_PER_ROUND as f64)
}

#[test]
fn a_warm_training_step_takes_no_page_fault_and_allocates_nothing_per_window() {
    keep_freed_memory();
    for threads in [1, 2] {
        let (mut faults, _) = rounds(128, threads, 9);
        let total: u64 = faults.iter().sum();
        faults.sort();
        assert_eq!(
            faults[faults.len() / 2],
            0,
            "page faults by round on {threads} threads: {faults:?}"
        );
        let per_step = total as f64 / (faults.len() * STEPS_PER_ROUND) as f64;
        assert!(
            per_step < 0.2,
            "{per_step} page faults per warm step on {threads} threads"
        );
    }
    // Below six windows a slice, the matrix products' own scratch depends on the size.
    let (_, small) = rounds(48, 1, 0);
    let (_, large) = rounds(64, 1, 0);
    assert!(small > 0.0, "the counter counts");
    assert!(
        (small - large).abs() < 1.0,
        "allocator calls per step: {small} at a batch of 48, {large} at 64"
    );
}
