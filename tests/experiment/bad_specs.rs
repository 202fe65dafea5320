//! Bad input, one case per rule of the spec's checks: each `--set` that breaks a rule
//! is refused by `run` with exit 1, its first message naming the `--set` it came from, the
//! key and what is wrong, before anything runs; a few are written into the spec file
//! instead and named by its path, line and key. A results folder and cache computed
//! before are left as they were, byte for byte and modification time. Each refusal's
//! whole stderr is an insta snapshot in `tests/experiment/snapshots/`
//! (`experiment__bad_specs__<the --set, lowercase, other characters as _>.snap`,
//! `experiment__bad_specs__file_<key>.snap`), so a change of wording shows in review;
//! `INSTA_UPDATE=always cargo test --release --test experiment bad_specs::` rewrites
//! them after a deliberate change.

use crate::common;

use common::{
    assert_error_snapshot, dcnet, project, small_quick_run, snapshot, snapshot_name, stderr,
};
use std::collections::BTreeSet;

/// (`--set` assignment, the key the fault names, the start of its message).
const RULES: &[(&str, &str, &str)] = &[
    (
        "name=\"\"",
        "name",
        "\"\" must be non-empty, at most 200 characters,",
    ),
    (
        "name=\"a b\"",
        "name",
        "\"a b\" must be non-empty, at most 200",
    ),
    (
        "seed=-1",
        "seed",
        "invalid value: integer `-1`, expected u64",
    ),
    (
        "seed=18446744073709551615",
        "seed",
        "18446744073709551615 is larger than TOML's",
    ),
    (
        "data.sample_rate_hz=0",
        "data.sample_rate_hz",
        "0 must be a positive number",
    ),
    (
        "data.sample_rate_hz=5000",
        "data.sample_rate_hz",
        "5000 Hz is above 1000 Hz: faster than any DVL",
    ),
    (
        "data.ground_truth_window_samples=0",
        "data.ground_truth_window_samples",
        "0 must be at least 1",
    ),
    (
        "data.ground_truth_window_samples=100000",
        "data.ground_truth_window_samples",
        "100000 samples at 1 Hz: 100000 s is above 60 s:",
    ),
    (
        "data.trajectories=[]",
        "data.trajectories",
        "no trajectory is defined",
    ),
    (
        "data.trajectories[1].name=\"S1\"",
        "data.trajectories[1].name",
        "\"S1\" is defined twice",
    ),
    (
        "data.trajectories[0].synthetic_duration_s=0",
        "data.trajectories[0].synthetic_duration_s",
        "0 must be a positive whole number of samples",
    ),
    (
        "data.trajectories[0].synthetic_duration_s=1e12",
        "data.trajectories[0].synthetic_duration_s",
        "1000000000000 s is above 2592000 s: longer than",
    ),
    (
        "data.trajectories[0].samples=[0, 10]",
        "data.trajectories[0].samples",
        "is for file trajectories; a synthetic one has",
    ),
    (
        "data.trajectories[0].columns=[\"a\", \"b\", \"c\"]",
        "data.trajectories[0].columns",
        "is for .csv files; a synthetic trajectory has",
    ),
    (
        "data.trajectories[0].file=\"missing.npy\"",
        "data.trajectories[0].file",
        "give either file (with samples) or",
    ),
    (
        "data.synthetic.speed_m_s=[2, 1]",
        "data.synthetic.speed_m_s",
        "[2, 1] must be a range of positive numbers, low",
    ),
    (
        "data.synthetic.speed_m_s=[1, 100]",
        "data.synthetic.speed_m_s[1]",
        "100 m/s is above 10 m/s: faster than an AUV",
    ),
    (
        "data.synthetic.leg_duration_s=[0, 10]",
        "data.synthetic.leg_duration_s",
        "[0, 10] must be a range of positive numbers,",
    ),
    (
        "data.synthetic.turn_rate_deg_s=-1",
        "data.synthetic.turn_rate_deg_s",
        "-1 must be zero or positive",
    ),
    (
        "data.synthetic.turn_rate_deg_s=1000",
        "data.synthetic.turn_rate_deg_s",
        "1000 deg/s is above 180 deg/s: faster than an",
    ),
    (
        "data.synthetic.heave_amplitude_m_s=50",
        "data.synthetic.heave_amplitude_m_s",
        "50 m/s is above 10 m/s: faster than an AUV",
    ),
    (
        "data.synthetic.surface_s=1e9",
        "data.synthetic.surface_s",
        "1000000000 s is above 2592000 s: longer than a",
    ),
    (
        "data.synthetic.recording_noise_cm_s=1000",
        "data.synthetic.recording_noise_cm_s",
        "1000 cm/s is above 100 cm/s: a velocity error",
    ),
    (
        "sensors.beam_pitch_deg=90",
        "sensors.beam_pitch_deg",
        "90 must lie strictly between 0 and 90",
    ),
    (
        "sensors.gnss_noise_cm_s=-1",
        "sensors.gnss_noise_cm_s",
        "-1 must be zero or positive",
    ),
    (
        "sensors.gnss_noise_cm_s=500",
        "sensors.gnss_noise_cm_s",
        "500 cm/s is above 100 cm/s: a velocity error of",
    ),
    (
        "grid.scale_pct={values = []}",
        "grid.scale_pct",
        "is empty: the grid needs at least one value on",
    ),
    (
        "grid.scale_pct={values = [-100]}",
        "grid.scale_pct[0]",
        "-100 must be above -100 %",
    ),
    (
        "grid.scale_pct={values = [500]}",
        "grid.scale_pct[0]",
        "500 % is above 100 %: a scale factor error",
    ),
    (
        "grid.scale_pct={values = [1, 1]}",
        "grid.scale_pct.values[1]",
        "1 is listed twice: every combination with it",
    ),
    (
        "grid.scale_pct={start = 1, stop = 0, step = 0.1}",
        "grid.scale_pct",
        "start 1, stop 0, step 0.1: step must be",
    ),
    (
        "grid.scale_pct={start = 0, stop = 1, step = 0.3}",
        "grid.scale_pct",
        "stop 1 is not start 0 plus a whole number of",
    ),
    (
        "grid.scale_pct={start = 0, stop = 1}",
        "grid.scale_pct",
        "give either values = [...] or all of start,",
    ),
    (
        "grid.scale_pct={start = 0, stop = 100, step = 0.001}",
        "grid.scale_pct",
        "100001 values is above 10000 values: an axis",
    ),
    (
        "grid.scale_pct={values = [1.0], extra = 2}",
        "grid.scale_pct.extra",
        "unknown field `extra`, expected one of",
    ),
    (
        "grid.bias_cm_s={values = [200]}",
        "grid.bias_cm_s[0]",
        "200 cm/s is above 100 cm/s: a velocity error of",
    ),
    (
        "grid.noise_cm_s={values = [-0.1]}",
        "grid.noise_cm_s[0]",
        "-0.1 must be zero or positive",
    ),
    (
        "grid.noise_cm_s={values = [nan]}",
        "grid.noise_cm_s.values[0]",
        "NaN must be a finite number",
    ),
    (
        "dataset.trajectories=[]",
        "dataset.trajectories",
        "is empty: name at least one training trajectory",
    ),
    (
        "dataset.trajectories=[\"S1\", \"S1\"]",
        "dataset.trajectories[1]",
        "\"S1\" is listed twice",
    ),
    (
        "dataset.trajectories=[\"Nope\"]",
        "dataset.trajectories[0]",
        "unknown trajectory \"Nope\"; data.trajectories",
    ),
    (
        "dataset.window_s=0",
        "dataset.window_s",
        "0 must be a positive whole number of samples at",
    ),
    (
        "dataset.window_s=0.5",
        "dataset.window_s",
        "0.5 must be a positive whole number of samples",
    ),
    (
        "dataset.window_s=1000",
        "dataset.window_s",
        "1000 s is above 600 s: DCNet's windows are",
    ),
    (
        "dataset.window_s=3",
        "dataset.window_s",
        "3 samples are too few for the 2D head (at least",
    ),
    (
        "dataset.stride_s=-1",
        "dataset.stride_s",
        "-1 must be a positive whole number of samples",
    ),
    (
        "dataset.validation_fraction=0",
        "dataset.validation_fraction",
        "0 must be above 0 and below 1: training keeps",
    ),
    (
        "dataset.validation_fraction=0.001",
        "dataset.validation_fraction",
        "0.001 of 165 windows per combination leaves 0",
    ),
    ("dvl=[]", "dvl", "no DVL under test is defined"),
    (
        "dvl[1].name=\"DVL1\"",
        "dvl[1].name",
        "\"DVL1\" is defined twice",
    ),
    (
        "dvl[0].scale_pct=-100",
        "dvl[0].scale_pct",
        "-100 must be above -100 %",
    ),
    (
        "dvl[0].scale_pct=150",
        "dvl[0].scale_pct",
        "150 % is above 100 %: a scale factor error",
    ),
    (
        "dvl[0].bias_cm_s=inf",
        "dvl[0].bias_cm_s",
        "inf must be a finite number",
    ),
    (
        "dvl[0].bias_cm_s=-500",
        "dvl[0].bias_cm_s",
        "500 cm/s is above 100 cm/s: a velocity error of",
    ),
    (
        "dvl[0].noise_cm_s=-1",
        "dvl[0].noise_cm_s",
        "-1 must be zero or positive",
    ),
    (
        "dvl[0].noise_cm_s=1000",
        "dvl[0].noise_cm_s",
        "1000 cm/s is above 100 cm/s: a velocity error",
    ),
    (
        "calibration.trajectory=\"Nope\"",
        "calibration.trajectory",
        "unknown trajectory \"Nope\"; data.trajectories",
    ),
    (
        "calibration.window_sizes_s=[]",
        "calibration.window_sizes_s",
        "is empty: give at least one window size",
    ),
    (
        "calibration.window_sizes_s=[20, 20]",
        "calibration.window_sizes_s[1]",
        "20 s is calibration.window_sizes_s[0] again:",
    ),
    (
        "calibration.window_sizes_s=[0.5]",
        "calibration.window_sizes_s[0]",
        "0.5 must be a positive whole number of samples",
    ),
    (
        "calibration.window_sizes_s=[5000]",
        "calibration.window_sizes_s[0]",
        "5000 s is not shorter than SCal (200 s): no",
    ),
    (
        "calibration.window_sizes_s=[5]",
        "calibration.window_sizes_s[0]",
        "5 s is shorter than one DCNet window",
    ),
    (
        "calibration.monte_carlo_runs=0",
        "calibration.monte_carlo_runs",
        "0 must be at least 2",
    ),
    (
        "calibration.monte_carlo_runs=1",
        "calibration.monte_carlo_runs",
        "1 must be at least 2: the spread of the RMSE over runs",
    ),
    (
        "calibration.window_sizes_s=[11, 20]",
        "calibration.window_sizes_s[0]",
        "11 s holds 11 samples at 1 Hz: least squares needs at least 12 (2 per term of EM5's 6)",
    ),
    (
        "name=\"a/c\"",
        "name",
        "\"a/c\" must use only letters, digits, '-', '_' and '.' (it names the results folder; '/', '=' and ',' name the points of a sweep)",
    ),
    (
        "name=qs/monte_carlo_runs=10",
        "name",
        "\"qs/monte_carlo_runs=10\" must use only letters",
    ),
    (
        "grid.scale_pct=1",
        "grid.scale_pct",
        "invalid type: integer `1`, expected a table with `values`, or `start`, `stop` and `step`",
    ),
    (
        "calibration.monte_carlo_runs=1000000000",
        "calibration.monte_carlo_runs",
        "1000000000 runs is above 100000 runs: the paper",
    ),
    (
        "evaluation.trajectories=[]",
        "evaluation.trajectories",
        "is empty: name at least one test trajectory",
    ),
    (
        "evaluation.trajectories=[\"S3\", \"S3\"]",
        "evaluation.trajectories[1]",
        "\"S3\" is listed twice",
    ),
    (
        "evaluation.trajectories=[\"Nope\"]",
        "evaluation.trajectories[0]",
        "unknown trajectory \"Nope\"; data.trajectories",
    ),
    (
        "estimators.kinds=[\"magic\"]",
        "estimators.kinds[0]",
        "unknown estimator \"magic\"; expected one of baseline, least_squares, beam_wls, kalman, kalman_beam, dcnet, floor",
    ),
    (
        "estimators.kinds=[\"baseline\", \"baseline\"]",
        "estimators.kinds[1]",
        "\"baseline\" is listed twice",
    ),
    ("estimators.kinds=[]", "estimators.kinds", "is empty"),
    (
        "estimators.kinds=[\"baseline\", \"bound\"]",
        "estimators.kinds[1]",
        "the bound is no method to list: it is computed for every DVL",
    ),
    (
        "estimators.error_models=[\"EM9\"]",
        "estimators.error_models[0]",
        "unknown error model \"EM9\"; expected one of EM1,",
    ),
    (
        "model.conv_channels=0",
        "model.conv_channels",
        "0 must be at least 1",
    ),
    (
        "model.conv_channels=1000000",
        "model.conv_channels",
        "1000000 channels is above 4096 channels: the",
    ),
    (
        "model.conv1d_kernel_size=0",
        "model.conv1d_kernel_size",
        "0 must be at least 1 and leave the two Conv1d",
    ),
    (
        "model.conv1d_kernel_size=6",
        "model.conv1d_kernel_size",
        "6 must be at least 1 and leave the two Conv1d",
    ),
    (
        "model.fc_widths=[0, 64, 32]",
        "model.fc_widths[0]",
        "0 must be at least 1",
    ),
    (
        "model.fc_widths=[100000000, 64, 32]",
        "model.fc_widths[0]",
        "100000000 units is above 65536 units: the",
    ),
    (
        "model.fc_widths=[65536, 65536, 64]",
        "model.fc_widths[0]",
        "needs about",
    ),
    (
        "model.fc_widths=[1, 2]",
        "model.fc_widths",
        "invalid length 2, expected an array of length 3",
    ),
    (
        "model.activation=\"relu\"",
        "model.activation",
        "unknown activation \"relu\"; expected tanh or",
    ),
    (
        "model.leaky_relu_slope=-1",
        "model.leaky_relu_slope",
        "-1 must be zero or positive",
    ),
    (
        "model.dropout=1",
        "model.dropout",
        "1 must be at least 0 and below 1",
    ),
    (
        "model.bogus=1",
        "model.bogus",
        "unknown field `bogus`, expected one of",
    ),
    (
        "training.backend=\"cuda\"",
        "training.backend",
        "unknown backend \"cuda\"; expected flex or ndarray",
    ),
    (
        "training.epochs=0",
        "training.epochs",
        "0 must be at least 1",
    ),
    (
        "training.epochs=10000000",
        "training.epochs",
        "10000000 epochs is above 100000 epochs: the",
    ),
    (
        "training.batch_size=0",
        "training.batch_size",
        "0 must be at least 1",
    ),
    (
        "training.batch_size=100000000",
        "training.batch_size",
        "100000000 windows is above 1000000 windows: the",
    ),
    (
        "estimators.kinds=[\"baseline\", \"dcnet_ensemble\"]",
        "estimators.kinds[1]",
        "\"dcnet_ensemble\" is not listed: it runs beside",
    ),
    (
        "training.replicates=0",
        "training.replicates",
        "0 must be at least 1",
    ),
    (
        "training.replicates=101",
        "training.replicates",
        "101 replicates is above 100 replicates: at 100 the",
    ),
    (
        "training.replicates=1.5",
        "training.replicates",
        "invalid type: floating point `1.5`, expected usize",
    ),
    (
        "training.checkpoint_every_epochs=0",
        "training.checkpoint_every_epochs",
        "0 must be at least 1",
    ),
    (
        "training.learning_rate.EM2=0",
        "training.learning_rate.EM2",
        "0 must be a positive number",
    ),
    (
        "training.rmsprop_alpha=1",
        "training.rmsprop_alpha",
        "1 must lie strictly between 0 and 1",
    ),
    (
        "training.rmsprop_epsilon=0",
        "training.rmsprop_epsilon",
        "0 must be a positive number",
    ),
    (
        "training.early_stopping={patience_epochs = 0, min_improvement = 0}",
        "training.early_stopping.patience_epochs",
        "0 must be at least 1",
    ),
    (
        "training.early_stopping={patience_epochs = 3, min_improvement = -1}",
        "training.early_stopping.min_improvement",
        "-1 must be 0 or more (cm/s)²",
    ),
    (
        "report.published=\"nope.toml\"",
        "report.published",
        "cannot read it",
    ),
    (
        "report.tolerance_pct=-1",
        "report.tolerance_pct",
        "-1 must be zero or positive",
    ),
    (
        "report.velocity_trajectories=[\"S1\"]",
        "report.velocity_trajectories",
        "has 1 names: give two (a training and a test",
    ),
    (
        "report.velocity_trajectories=[\"S1\", \"Nope\"]",
        "report.velocity_trajectories[1]",
        "unknown trajectory \"Nope\"; data.trajectories",
    ),
    (
        "bogus.key=1",
        "bogus",
        "unknown field `bogus`, expected one of `name`,",
    ),
    ("sweep.values={}", "sweep.values", "names no key"),
    ("sweep.sample=0", "sweep.values", "missing field `values`"),
];

#[test]
fn every_rule_refuses_its_bad_value_at_its_key_and_loses_nothing() {
    let dir = project(false);
    let d = dir.path();
    small_quick_run(d, &["--no-plots"]);
    let before = snapshot(&d.join("results"));
    let mut refused = 0;
    let mut names = BTreeSet::new();
    for &(set, key, message) in RULES {
        let output = dcnet(d, &["run", "experiments/quick.toml", "--set", set]);
        let error = stderr(&output);
        assert_eq!(output.status.code(), Some(1), "--set {set}: {error}");
        let expected = format!("error: --set {set}: {key}: ");
        let first = error.lines().next().unwrap_or_default();
        assert!(
            first.starts_with(&expected) && first.contains(message),
            "--set {set}:\nexpected {expected:?} and {message:?}\n     got {error:?}"
        );
        let name = snapshot_name(set);
        assert!(names.insert(name.clone()), "two rules are named {name}");
        let command = format!("dcnet-exp run experiments/quick.toml --set {set}");
        assert_error_snapshot!(&name, &command, &error, d);
        refused += 1;
    }
    assert_eq!(refused, RULES.len());
    assert!(
        snapshot(&d.join("results")) == before,
        "a refused run changed results/"
    );
}

#[test]
fn a_fault_written_in_the_file_is_named_by_its_path_line_and_key() {
    let dir = project(false);
    let d = dir.path();
    let quick = std::fs::read_to_string(d.join("experiments/quick.toml")).unwrap();
    for (line, replacement, key, message) in [
        (
            "seed = 7",
            "seed = 18446744073709551615",
            "seed",
            "18446744073709551615 is larger than TOML's largest integer",
        ),
        (
            "monte_carlo_runs = 20",
            "monte_carlo_runs = 1000000000",
            "calibration.monte_carlo_runs",
            "1000000000 runs is above 100000 runs",
        ),
        (
            "window_s = 10.0",
            "window_s = 1000.0",
            "dataset.window_s",
            "1000 s is above 600 s",
        ),
        (
            "conv_channels = 16",
            "conv_channels = 0",
            "model.conv_channels",
            "0 must be at least 1",
        ),
        (
            "fc_widths = [128, 64, 32]",
            "fc_widths = [65536, 65536, 64]",
            "model.fc_widths[0]",
            "needs about",
        ),
    ] {
        let text = quick.replacen(line, replacement, 1);
        assert_ne!(text, quick, "{line} is in quick.toml");
        let number = text
            .lines()
            .position(|l| l.starts_with(replacement))
            .unwrap()
            + 1;
        let path = d.join("experiments/bad.toml");
        std::fs::write(&path, text).unwrap();
        let output = dcnet(d, &["run", "experiments/bad.toml"]);
        let error = stderr(&output);
        assert_eq!(output.status.code(), Some(1), "{replacement}: {error}");
        let expected = format!("error: experiments/bad.toml:{number}: {key}: {message}");
        assert!(
            error.starts_with(&expected),
            "expected {expected:?}\n     got {error:?}"
        );
        let command =
            format!("dcnet-exp run experiments/bad.toml, quick.toml with {replacement:?}");
        assert_error_snapshot!(&format!("file_{}", snapshot_name(key)), &command, &error, d);
        assert!(!d.join("results").exists(), "{replacement}: made results/");
    }
}

/// `dcnet-exp ARGS` in `cwd` under a limit of `megabytes` of address space, so that a
/// run that holds more than that fails instead of passing.
fn dcnet_within(cwd: &std::path::Path, megabytes: u64, args: &[&str]) -> std::process::Output {
    std::process::Command::new("sh")
        .current_dir(cwd)
        .arg("-c")
        .arg(format!(
            "ulimit -v {} && exec \"$0\" \"$@\"",
            megabytes * 1024
        ))
        .arg(env!("CARGO_BIN_EXE_dcnet-exp"))
        .args(args)
        .env_remove("DCNET_LOG_EVERY")
        .output()
        .expect("the binary runs")
}

/// Stderr's bounds whatever the number of faults: the first 20 messages, then how many
/// more, no line longer than a few hundred characters.
fn assert_bounded(error: &str, faults: usize) {
    let lines: Vec<&str> = error.lines().collect();
    assert_eq!(lines.len(), 21, "{error}");
    assert_eq!(
        lines[20],
        format!("error: … and {} more faults", faults - 20),
        "{error}"
    );
    assert!(
        lines.iter().all(|line| line.len() < 300),
        "a line repeats a long value: {error}"
    );
    assert!(error.len() < 21 * 300, "{} bytes of stderr", error.len());
}

#[test]
fn a_hundred_thousand_bad_values_in_the_file_give_a_short_answer_in_little_memory() {
    let dir = project(false);
    let d = dir.path();
    let quick = std::fs::read_to_string(d.join("experiments/quick.toml")).unwrap();
    let values: Vec<String> = (1..=100_000).map(|i| format!("-{i}")).collect();
    let line = "window_sizes_s = [20.0, 40.0, 60.0, 80.0, 100.0]";
    let text = quick.replacen(
        line,
        &format!("window_sizes_s = [{}]", values.join(", ")),
        1,
    );
    assert_ne!(text, quick, "{line} is in quick.toml");
    let number = text
        .lines()
        .position(|l| l.starts_with("window_sizes_s"))
        .unwrap()
        + 1;
    std::fs::write(d.join("experiments/many.toml"), text).unwrap();
    let output = dcnet_within(d, 1024, &["validate", "experiments/many.toml"]);
    let error = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{error}");
    assert!(
        error.starts_with(&format!(
            "error: experiments/many.toml:{number}: calibration.window_sizes_s[0]: -1 must be"
        )),
        "{error}"
    );
    assert_bounded(&error, 100_000);
}

/// Every name distinct and none defined, beside two thousand defined trajectories:
/// each name is looked up in constant time, and each message lists the first defined
/// names and how many there are, not all of them.
#[test]
fn a_hundred_thousand_unknown_trajectories_give_a_short_answer_in_little_memory() {
    let dir = project(false);
    let d = dir.path();
    let quick = std::fs::read_to_string(d.join("experiments/quick.toml")).unwrap();
    let names: Vec<String> = (1..=100_000).map(|i| format!("\"unknown-{i}\"")).collect();
    let line = "trajectories = [\"S1\", \"S2\"]";
    let defined: String = (0..2_000)
        .map(|i| format!("[[data.trajectories]]\nname = \"T{i}\"\nsynthetic_duration_s = 900\n\n"))
        .collect();
    let text = quick
        .replacen(line, &format!("trajectories = [{}]", names.join(", ")), 1)
        .replacen("[sensors]", &format!("{defined}[sensors]"), 1);
    assert_ne!(text, quick, "{line} is in quick.toml");
    std::fs::write(d.join("experiments/many.toml"), text).unwrap();
    let output = dcnet_within(d, 1024, &["validate", "experiments/many.toml"]);
    let error = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{error}");
    assert!(
        error.contains(": dataset.trajectories[0]: unknown trajectory \"unknown-1\"; data.trajectories defines S1, S2, S3, S4, SCal, T0, T1, T2, T3, T4, … (2005 in all)\n"),
        "{error}"
    );
    assert_bounded(&error, 100_000);
}

/// A spec of tens of megabytes is refused by its size before it is parsed, which
/// would take memory many times its size.
#[test]
fn a_spec_of_forty_megabytes_is_refused_by_its_size_in_little_memory() {
    let dir = project(false);
    let d = dir.path();
    let quick = std::fs::read_to_string(d.join("experiments/quick.toml")).unwrap();
    let values: Vec<String> = (0..6_000_000).map(|i| i.to_string()).collect();
    let text = quick.replacen(
        "sample_rate_hz = 1.0",
        &format!("sample_rate_hz = [{}]", values.join(",")),
        1,
    );
    std::fs::write(d.join("experiments/huge.toml"), text).unwrap();
    let output = dcnet_within(d, 512, &["validate", "experiments/huge.toml"]);
    let error = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{error}");
    assert!(
        error.starts_with(
            "error: experiments/huge.toml: cannot read the spec: it is larger than 4 MiB"
        ),
        "{error}"
    );
}

/// A string of a megabyte where a number goes is quoted by its start and length.
#[test]
fn a_long_string_in_the_file_is_shown_by_its_start_and_length() {
    let dir = project(false);
    let d = dir.path();
    let quick = std::fs::read_to_string(d.join("experiments/quick.toml")).unwrap();
    let long = "x".repeat(1 << 20);
    let text = quick.replacen(
        "sample_rate_hz = 1.0",
        &format!("sample_rate_hz = \"{long}\""),
        1,
    );
    std::fs::write(d.join("experiments/long.toml"), text).unwrap();
    let error = stderr(&dcnet(d, &["validate", "experiments/long.toml"]));
    assert_eq!(
        error,
        format!(
            "error: experiments/long.toml:7: data.sample_rate_hz: invalid type: string \"{}… (1048576 characters)\", expected f64\n",
            "x".repeat(30)
        )
    );
}

#[test]
fn a_long_set_value_is_shown_by_its_start_and_length() {
    let dir = project(false);
    let d = dir.path();
    let values: Vec<String> = (1..=15_000).map(|i| i.to_string()).collect();
    let set = format!("calibration.window_sizes_s=[{}]", values.join(","));
    let output = dcnet_within(
        d,
        1024,
        &["validate", "experiments/quick.toml", "--set", &set],
    );
    let error = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{error}");
    assert!(
        error.starts_with(
            "error: --set calibration.window_sizes_s=[1, 2, 3, … (15000 values)]: calibration.window_sizes_s["
        ),
        "{error}"
    );
    // Windows of 200 s and more are not shorter than SCal; 1–9 s are shorter than DCNet's.
    // 1–11 s hold fewer than 12 samples, least squares' least for EM5.
    assert_bounded(&error, 15_000 - 199 + 9 + 11);
}

#[test]
fn a_name_too_long_for_the_file_system_is_refused_by_validate() {
    let dir = project(false);
    let d = dir.path();
    let name = vec!["x".repeat(200); 25].join("/");
    let set = format!("name={name}");
    let output = dcnet(d, &["validate", "experiments/quick.toml", "--set", &set]);
    let error = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{error}");
    assert!(
        error.starts_with("error: --set name=xxxxxxxxxxxxxxxxxxxxxxxxxxxxxx… (5024 characters): name: \"xxxxxxxxxxxxxxxxxxxxxxxxxxxxxx… (5024 characters)\" must use only letters"),
        "{error}"
    );
    assert!(error.lines().all(|line| line.len() < 300), "{error}");
}

#[test]
fn a_spec_that_is_not_utf8_is_named_by_its_line_and_byte() {
    let dir = project(false);
    let d = dir.path();
    let mut bytes = std::fs::read(d.join("experiments/quick.toml")).unwrap();
    let at = bytes.windows(4).position(|w| w == b"seed").unwrap();
    let line = bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1;
    bytes[at + 1] = 0xff;
    std::fs::write(d.join("experiments/latin.toml"), bytes).unwrap();
    let output = dcnet(d, &["validate", "experiments/latin.toml"]);
    let error = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{error}");
    assert_eq!(
        error.trim_end(),
        format!(
            "error: experiments/latin.toml:{line}: cannot read the spec: it is not UTF-8: byte 0xff at offset {} (line {line}, column 2) starts no UTF-8 character; save the file as UTF-8",
            at + 1
        )
    );
}

#[test]
fn a_sweep_naming_no_key_is_placed_on_its_line() {
    let dir = project(false);
    let d = dir.path();
    let quick = std::fs::read_to_string(d.join("experiments/quick.toml")).unwrap();
    let text = format!("{quick}\n\n[sweep.values]\n");
    let line = text.lines().count();
    std::fs::write(d.join("experiments/empty-sweep.toml"), &text).unwrap();
    let output = dcnet(d, &["validate", "experiments/empty-sweep.toml"]);
    let error = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{error}");
    assert!(
        error.starts_with(&format!(
            "error: experiments/empty-sweep.toml:{line}: sweep.values: names no key"
        )),
        "{error}"
    );
}

#[test]
fn evaluating_on_the_calibration_trajectory_is_accepted_with_a_warning() {
    let dir = project(false);
    let d = dir.path();
    let set = "evaluation.trajectories=[\"S3\", \"SCal\"]";
    let output = dcnet(d, &["validate", "experiments/quick.toml", "--set", set]);
    let error = stderr(&output);
    assert_eq!(output.status.code(), Some(0), "{error}");
    assert!(
        error.starts_with(&format!("warning: --set {set}: evaluation.trajectories[1]: \"SCal\" is also calibration.trajectory: it is evaluated on the trajectory it was calibrated on")),
        "{error}"
    );
}

#[test]
fn training_on_a_test_or_the_calibration_trajectory_is_accepted_with_a_warning() {
    let dir = project(false);
    let d = dir.path();
    let evaluation = "evaluation.trajectories=[\"S1\", \"S3\"]";
    let dataset = "dataset.trajectories=[\"S1\", \"SCal\"]";
    let output = dcnet(
        d,
        &[
            "validate",
            "experiments/quick.toml",
            "--set",
            evaluation,
            "--set",
            dataset,
        ],
    );
    let error = stderr(&output);
    assert_eq!(output.status.code(), Some(0), "{error}");
    assert!(
        error.contains(&format!("warning: --set {dataset}: dataset.trajectories[0]: \"S1\" is also an evaluation trajectory: the networks have trained on the trajectory they are tested on")),
        "{error}"
    );
    assert!(
        error.contains(&format!("warning: --set {dataset}: dataset.trajectories[1]: \"SCal\" is also calibration.trajectory: the networks have trained on the trajectory they calibrate")),
        "{error}"
    );
    // The spec as written warns of nothing.
    let output = dcnet(d, &["validate", "experiments/quick.toml"]);
    assert!(!stderr(&output).contains("warning"), "{}", stderr(&output));
}
