//! Checks `[model]`. In: DCNet's sizes, activation and dropout as written, and DCNet's
//! window in samples from `[dataset]`. Out: the [`ModelSpec`], sizes that fit the
//! window.
//!
//! [`ModelSpec`]: crate::spec::ModelSpec

use super::{Faults, non_negative};
use crate::spec::{ModelSpec, file, ranges};
use crate::vocab::Activation;

/// Checks `[model]`: sizes of at least 1 that fit the window, a known activation, a
/// dropout below 1.
pub(in crate::spec) fn check_model(
    model: file::ModelFile,
    window: Option<usize>,
    faults: &mut Faults,
) -> ModelSpec {
    let file::ModelFile {
        conv_channels,
        conv1d_kernel_size,
        fc_widths,
        activation,
        leaky_relu_slope,
        dropout,
    } = model;
    if conv_channels == 0 {
        faults.add("model.conv_channels", "0 must be at least 1");
    }
    ranges::CONV_CHANNELS.check("model.conv_channels", conv_channels as f64, faults);
    match window {
        Some(window) if conv1d_kernel_size == 0 || 2 * (conv1d_kernel_size - 1) >= window => faults.add(
            "model.conv1d_kernel_size",
            format!("{conv1d_kernel_size} must be at least 1 and leave the two Conv1d an output of a window of {window} samples"),
        ),
        Some(window) if window < 4 => faults.add("dataset.window_s", format!("{window} samples are too few for the 2D head (at least 4)")),
        _ => {}
    }
    for (i, width) in fc_widths.iter().enumerate() {
        if *width == 0 {
            faults.add(format!("model.fc_widths[{i}]"), "0 must be at least 1");
        }
        ranges::FC_WIDTH.check(&format!("model.fc_widths[{i}]"), *width as f64, faults);
    }
    let activation = activation.parse().unwrap_or_else(|message: String| {
        faults.add("model.activation", message);
        Activation::Tanh
    });
    non_negative("model.leaky_relu_slope", leaky_relu_slope, faults);
    if !(0.0..1.0).contains(&dropout) {
        faults.add(
            "model.dropout",
            format!("{dropout} must be at least 0 and below 1"),
        );
    }
    ModelSpec {
        conv_channels,
        conv1d_kernel_size,
        fc_widths,
        activation,
        leaky_relu_slope,
        dropout,
    }
}

#[cfg(test)]
mod tests {
    use crate::spec::fixture::quick_faults;

    #[test]
    fn the_kernel_leaves_the_convolutions_an_output() {
        // quick.toml's window is 10 samples: two Conv1d of kernel 6 leave none.
        let set = "model.conv1d_kernel_size=6";
        assert_eq!(
            quick_faults(&[set]),
            format!(
                "--set {set}: model.conv1d_kernel_size: 6 must be at least 1 and leave the two Conv1d an output of a window of 10 samples"
            )
        );
    }
}
