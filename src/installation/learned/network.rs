//! DCNet for an installation: the network reads the DVL, the reference's body velocity
//! and the body rate ([`simulate`](crate::installation::learned::simulate)'s windows) and outputs the terms of a
//! [`TermSet`] in units that keep them near 1 (scale in %, misalignment in degrees,
//! lever arm in m, time offset in s, bias in cm/s). The closed-loop loss is the paper's,
//! for any selection of terms: each window's DVL corrected with the predicted terms,
//! squared error against the reference in (cm/s)², averaged over samples.
//! In: windows and a term set. Out: tensors for the network, the loss, the terms as an
//! [`Installation`].
//!
//! The loss reads the reference and the body rate at t + τ by linear interpolation
//! between the window's samples, as [`Reference::at`](crate::installation::frames::Reference::at)
//! does, written as a sum of the samples around t weighted by hat functions of τ, so that
//! it is differentiable in τ (|τ| up to [`REFERENCE_MARGIN`] sample intervals). It
//! linearises the misalignment's rotation as `I + [δ]×` (for 2°, the neglected part is
//! 0.06 % of the speed). The terms it outputs are applied with the exact model
//! ([`Installation::correct`]).

use crate::installation::learned::simulate::{
    INPUT_ROWS, InstallationWindows, REFERENCE_MARGIN, TARGET_ROWS,
};
use crate::installation::terms::{Installation, PerAxis, TermKind, TermSet};
use crate::model::{NetworkIo, Windows};
use burn::tensor::{Device, Tensor, TensorData};

/// The network's shape for `terms`: the body rate beside `v_dvl − v_ref` in its 1D head,
/// one output per parameter.
pub fn network_io(terms: &TermSet) -> NetworkIo {
    NetworkIo {
        channels_1d: 6,
        outputs: terms.parameter_count(),
    }
}

/// The factor from a term's SI value to the network's unit, the unit it is shown in.
fn network_unit(kind: TermKind) -> f64 {
    kind.table().unit.factor()
}

/// The installation of one window's outputs, in [`TermSet::parameter_names`] order.
pub fn installation_of(terms: &TermSet, outputs: &[f32]) -> Installation {
    let parameters: Vec<f64> = terms
        .parameter_kinds()
        .into_iter()
        .zip(outputs)
        .map(|(kind, &value)| f64::from(value) / network_unit(kind))
        .collect();
    Installation::from_parameters(terms, &parameters)
}

/// The outputs that stand for `installation`: the inverse of [`installation_of`].
pub fn outputs_of(terms: &TermSet, installation: &Installation) -> Vec<f32> {
    terms
        .parameter_kinds()
        .into_iter()
        .zip(installation.to_parameters(terms))
        .map(|(kind, value)| (value * network_unit(kind)) as f32)
        .collect()
}

/// A batch as the network and the loss take it.
pub struct WindowBatch {
    pub windows: Windows,
    /// `[count, time + 2 · REFERENCE_MARGIN, 3]`: the reference's body velocity, cm/s,
    /// from [`REFERENCE_MARGIN`] samples before the window to as many after it.
    pub reference_cm_s: Tensor<3>,
    /// `[count, time + 2 · REFERENCE_MARGIN, 3]`: the body rate, rad/s, likewise.
    pub rate_rad_s: Tensor<3>,
    /// The interval between two samples, s.
    pub step_s: f64,
}

/// The windows `indices` of `set`.
pub fn batch_of(
    set: &InstallationWindows,
    indices: &[usize],
    kernel: usize,
    device: &Device,
) -> WindowBatch {
    let w = set.window;
    let span = w + 2 * REFERENCE_MARGIN;
    let mut inputs = Vec::with_capacity(indices.len() * INPUT_ROWS * w);
    let mut reference = Vec::with_capacity(indices.len() * 3 * span);
    let mut rate = Vec::with_capacity(indices.len() * 3 * span);
    for &i in indices {
        inputs.extend_from_slice(&set.inputs[i * INPUT_ROWS * w..][..INPUT_ROWS * w]);
        let target = &set.targets[i * TARGET_ROWS * span..][..TARGET_ROWS * span];
        for t in 0..span {
            for axis in 0..3 {
                reference.push(target[axis * span + t] * 100.0);
                rate.push(target[(3 + axis) * span + t]);
            }
        }
    }
    let count = indices.len();
    let tensor =
        |values: Vec<f32>| Tensor::from_data(TensorData::new(values, [count, span, 3]), device);
    WindowBatch {
        windows: Windows::new(&inputs, INPUT_ROWS, w, kernel, device),
        reference_cm_s: tensor(reference),
        rate_rad_s: tensor(rate),
        step_s: set.step_s,
    }
}

/// `values` `[count, time + 2 · REFERENCE_MARGIN, 3]` at each sample of the window
/// shifted by `shift` `[count, time, 3]` sample intervals: Σ_s hat(shift − s) · values
/// at s samples from it, hat(x) = max(0, 1 − |x|), linear interpolation.
fn shifted(values: &Tensor<3>, shift: &Tensor<3>, time: usize) -> Tensor<3> {
    let margin = REFERENCE_MARGIN as i64;
    let mut sum: Option<Tensor<3>> = None;
    for s in -margin..=margin {
        let weight = (-(shift.clone() - s as f64).abs() + 1.0).clamp_min(0.0);
        let term = weight * values.clone().narrow(1, (margin + s) as usize, time);
        sum = Some(match sum {
            None => term,
            Some(sum) => sum + term,
        });
    }
    sum.expect("at least one shift")
}

/// `a × b` along the last axis of `[batch, time, 3]` tensors.
fn cross(a: Tensor<3>, b: Tensor<3>) -> Tensor<3> {
    let part = |t: &Tensor<3>, k: usize| t.clone().narrow(2, k, 1);
    Tensor::cat(
        vec![
            part(&a, 1) * part(&b, 2) - part(&a, 2) * part(&b, 1),
            part(&a, 2) * part(&b, 0) - part(&a, 0) * part(&b, 2),
            part(&a, 0) * part(&b, 1) - part(&a, 1) * part(&b, 0),
        ],
        2,
    )
}

/// The closed-loop loss, (cm/s)², of `outputs` `[batch, parameters]` (network units,
/// `terms`' order) on `batch`.
pub fn closed_loop_loss(outputs: Tensor<2>, terms: &TermSet, batch: &WindowBatch) -> Tensor<1> {
    let [count, time, _] = batch.windows.dvl_cm_s.dims();
    let mut next = 0;
    // The next `n` outputs, each window's value repeated over its samples, `[count,
    // time, 3]`; a single value stands for all three axes.
    let mut take = |n: usize| -> Tensor<3> {
        let columns = outputs.clone().narrow(1, next, n);
        next += n;
        let columns = if n == 1 {
            columns.expand([count, 3])
        } else {
            columns
        };
        columns.reshape([count, 1, 3]).expand([count, time, 3])
    };
    let per_axis = |p: PerAxis| match p {
        PerAxis::Off => 0,
        PerAxis::Scalar => 1,
        PerAxis::PerAxis => 3,
    };
    let scale_pct = (terms.scale != PerAxis::Off).then(|| take(per_axis(terms.scale)));
    let misalignment_deg = terms.misalignment.then(|| take(3));
    let lever_arm_m = terms.lever_arm.then(|| take(3));
    let time_offset_s = terms.time_offset.then(|| take(1));
    let bias_cm_s = (terms.bias != PerAxis::Off).then(|| take(per_axis(terms.bias)));

    let (reference_cm_s, rate_rad_s) = match &time_offset_s {
        Some(tau) => {
            let shift = tau.clone() / batch.step_s;
            (
                shifted(&batch.reference_cm_s, &shift, time),
                shifted(&batch.rate_rad_s, &shift, time),
            )
        }
        None => (
            batch
                .reference_cm_s
                .clone()
                .narrow(1, REFERENCE_MARGIN, time),
            batch.rate_rad_s.clone().narrow(1, REFERENCE_MARGIN, time),
        ),
    };
    let mut corrected = batch.windows.dvl_cm_s.clone();
    if let Some(bias) = bias_cm_s {
        corrected = corrected - bias;
    }
    if let Some(scale) = scale_pct {
        corrected = corrected / (scale / 100.0 + 1.0);
    }
    if let Some(angles) = misalignment_deg {
        corrected = corrected.clone() + cross(angles * (std::f64::consts::PI / 180.0), corrected);
    }
    if let Some(lever) = lever_arm_m {
        corrected = corrected - cross(rate_rad_s, lever) * 100.0;
    }
    let target = reference_cm_s;
    (corrected - target).square().sum() / (count * time) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::installation::frames::cross as cross3;
    use crate::installation::learned::simulate::simulated_windows;
    use crate::installation::learned::spec::SimulationGrid;
    use crate::installation::study::Recording;
    use crate::model::{Dcnet, Settings};
    use crate::spec::ModelSpec;
    use crate::vocab::Activation;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn device() -> Device {
        Device::flex()
    }

    fn recordings() -> Vec<Recording> {
        vec![
            crate::installation::learned::simulate::tests::weaving("A", 120, 0.0),
            crate::installation::learned::simulate::tests::weaving("B", 120, 2.0),
        ]
    }

    fn one(values: &[f64]) -> SimulationGrid {
        SimulationGrid {
            lever_arm_x_m: vec![values[0]],
            lever_arm_y_m: vec![values[1]],
            lever_arm_z_m: vec![values[2]],
            time_offset_s: vec![values[3]],
            misalignment_z_deg: vec![values[4]],
            scale_pct: vec![values[5]],
            bias_cm_s: vec![values[6]],
        }
    }

    fn loss_of(set: &InstallationWindows, terms: &TermSet, installation: &Installation) -> f64 {
        let indices: Vec<usize> = (0..set.len()).collect();
        let batch = batch_of(set, &indices, 2, &device());
        let outputs = outputs_of(terms, installation);
        let outputs = Tensor::from_data(
            TensorData::new(
                outputs.repeat(indices.len()),
                [indices.len(), terms.parameter_count()],
            ),
            &device(),
        );
        f64::from(closed_loop_loss(outputs, terms, &batch).into_scalar::<f32>())
    }

    #[test]
    fn outputs_and_installations_convert_both_ways_in_network_units() {
        let installation = Installation {
            scale: [0.01, 0.02, -0.01],
            misalignment_rad: [0.0, 0.01, 0.02],
            lever_arm_m: [-1.9, 0.0, 0.8],
            time_offset_s: 1.4,
            bias_m_s: [0.005, 0.0, -0.002],
        };
        let outputs = outputs_of(&TermSet::EVERY, &installation);
        assert_eq!(outputs[0], 1.0);
        assert!((outputs[4] - 0.5729578).abs() < 1e-6, "{outputs:?}");
        assert_eq!(outputs[6], -1.9);
        assert_eq!(outputs[9], 1.4);
        assert_eq!(outputs[10], 0.5);
        let back = installation_of(&TermSet::EVERY, &outputs);
        for (a, b) in back
            .to_parameters(&TermSet::EVERY)
            .iter()
            .zip(installation.to_parameters(&TermSet::EVERY))
        {
            assert!((a - b).abs() < 1e-6 * b.abs().max(1.0));
        }
    }

    /// Without a misalignment the loss is exact: zero at the terms that simulated a
    /// noise-free DVL, time offset included, and above zero at any other.
    #[test]
    fn the_loss_vanishes_at_the_true_terms_of_a_noise_free_dvl() {
        let recordings = recordings();
        let recordings: Vec<&Recording> = recordings.iter().collect();
        let truth = [-1.9, 0.1, 0.7, 1.4, 0.0, 1.5, 0.8];
        let set = simulated_windows(&recordings, &one(&truth), 0.0, 10, 4, 3);
        let terms = TermSet {
            scale: PerAxis::Scalar,
            lever_arm: true,
            time_offset: true,
            bias: PerAxis::Scalar,
            ..TermSet::NONE
        };
        let installation = set_installation(&truth);
        let at_truth = loss_of(&set, &terms, &installation);
        assert!(at_truth < 1e-6, "{at_truth}");
        let mut off = installation;
        off.lever_arm_m[0] += 0.1;
        // ω_z up to about 0.2 rad/s: 0.1 m of lever arm is up to 2 cm/s in y.
        assert!(loss_of(&set, &terms, &off) > 0.1);
    }

    fn set_installation(values: &[f64]) -> Installation {
        one(values).installations()[0]
    }

    /// The loss is the mean over samples of the squared error of the correction with the
    /// misalignment linearised, against the reference interpolated at t + τ, computed
    /// here in f64 from the windows' rows.
    #[test]
    fn the_loss_is_the_linearised_correction_error_computed_by_hand() {
        let recordings = recordings();
        let recordings: Vec<&Recording> = recordings.iter().collect();
        let simulated = [-1.9, 0.0, 0.6, 1.4, 2.0, -1.0, 0.5];
        let set = simulated_windows(&recordings, &one(&simulated), 0.02, 10, 7, 5);
        let guess = Installation {
            scale: [0.004, 0.006, -0.002],
            misalignment_rad: [0.01, -0.02, 0.03],
            lever_arm_m: [-1.5, 0.2, 0.3],
            time_offset_s: 1.1,
            bias_m_s: [0.004, -0.001, 0.002],
        };
        let mut expected = 0.0;
        let w = set.window;
        let span = w + 2 * REFERENCE_MARGIN;
        let shift = guess.time_offset_s / set.step_s;
        let hat = |x: f64| (1.0 - x.abs()).max(0.0);
        for i in 0..set.len() {
            let input = |r: usize, t: usize| f64::from(set.inputs[(i * INPUT_ROWS + r) * w + t]);
            // Row r of the reference at window sample t shifted by τ.
            let at_tau = |r: usize, t: usize| {
                (0..span)
                    .map(|j| {
                        let offset = j as f64 - (t + REFERENCE_MARGIN) as f64;
                        hat(shift - offset)
                            * f64::from(set.targets[(i * TARGET_ROWS + r) * span + j])
                    })
                    .sum::<f64>()
            };
            for t in 0..w {
                let dvl = [0, 1, 2].map(|k| input(k, t) * 100.0);
                let rate = [0, 1, 2].map(|k| at_tau(3 + k, t));
                let unscaled = [0, 1, 2]
                    .map(|k| (dvl[k] - guess.bias_m_s[k] * 100.0) / (1.0 + guess.scale[k]));
                let turned = cross3(guess.misalignment_rad, unscaled);
                let turning = cross3(rate, guess.lever_arm_m);
                for k in 0..3 {
                    let corrected = unscaled[k] + turned[k] - turning[k] * 100.0;
                    expected += (corrected - at_tau(k, t) * 100.0).powi(2);
                }
            }
        }
        expected /= (set.len() * w) as f64;
        let found = loss_of(&set, &TermSet::EVERY, &guess);
        assert!(
            (found - expected).abs() < 1e-4 * expected,
            "{found} against {expected}"
        );
    }

    /// The terms, as free parameters, descend the loss to the installation that
    /// simulated a noise-free DVL.
    #[test]
    fn descending_the_loss_over_the_terms_finds_the_simulated_installation() {
        let recordings = recordings();
        let recordings: Vec<&Recording> = recordings.iter().collect();
        let simulated = [-1.9, 0.0, 0.6, 1.4, 0.0, 0.0, 0.0];
        let set = simulated_windows(&recordings, &one(&simulated), 0.0, 10, 2, 9);
        let terms = TermSet {
            lever_arm: true,
            time_offset: true,
            ..TermSet::NONE
        };
        let indices: Vec<usize> = (0..set.len()).collect();
        let device = Device::flex().autodiff();
        let batch = batch_of(&set, &indices, 2, &device);
        // Adam's steps, by hand: the terms' curvatures differ by orders of magnitude.
        let (mut found, mut mean, mut square) = (vec![0.0f32; 4], [0.0f32; 4], [0.0f32; 4]);
        for step_count in 1..=1500 {
            let parameters =
                Tensor::<2>::from_data(TensorData::new(found.clone(), [1, 4]), &device)
                    .require_grad();
            let outputs = parameters.clone().expand([indices.len(), 4]);
            let grads = closed_loop_loss(outputs, &terms, &batch).backward();
            let gradient: Vec<f32> = parameters
                .grad(&grads)
                .unwrap()
                .into_data()
                .try_to_vec()
                .unwrap();
            for (k, g) in gradient.into_iter().enumerate() {
                mean[k] = 0.9 * mean[k] + 0.1 * g;
                square[k] = 0.999 * square[k] + 0.001 * g * g;
                let unbiased_mean = mean[k] / (1.0 - 0.9f32.powi(step_count));
                let unbiased_square = square[k] / (1.0 - 0.999f32.powi(step_count));
                found[k] -= 0.01 * unbiased_mean / (unbiased_square.sqrt() + 1e-8);
            }
        }
        let expected = [-1.9f32, 0.0, 0.6, 1.4];
        for (f, e) in found.iter().zip(expected) {
            assert!((f - e).abs() < 0.01, "{found:?} against {expected:?}");
        }
    }

    #[test]
    fn a_dcnet_for_an_installation_reads_the_body_rate_and_outputs_its_terms() {
        let recordings = recordings();
        let recordings: Vec<&Recording> = recordings.iter().collect();
        let set = simulated_windows(
            &recordings,
            &one(&[-1.9, 0.0, 0.6, 1.4, 1.0, 1.0, 0.5]),
            0.02,
            10,
            5,
            1,
        );
        let spec = ModelSpec {
            conv_channels: 4,
            conv1d_kernel_size: 2,
            fc_widths: [16, 8, 4],
            activation: Activation::Tanh,
            leaky_relu_slope: 0.05,
            dropout: 0.0,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let model = Dcnet::new(&spec, network_io(&TermSet::EVERY), 10, &device(), &mut rng);
        let indices: Vec<usize> = (0..set.len()).collect();
        let batch = batch_of(&set, &indices, spec.conv1d_kernel_size, &device());
        let settings = Settings::from(&spec);
        let outputs = model.forward(&batch.windows, &settings, None);
        assert_eq!(outputs.dims(), [set.len(), 13]);
        let loss: f32 = closed_loop_loss(outputs, &TermSet::EVERY, &batch).into_scalar();
        assert!(loss.is_finite() && loss > 0.0);
    }
}
