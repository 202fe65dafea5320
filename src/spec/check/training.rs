//! Checks `[training]`. In: the backend, epochs, batch size, learning rates (one, or
//! one per error model), RMSProp's settings, checkpoints, early stopping and
//! replicates, as written. Out: the [`TrainingSpec`].
//!
//! [`TrainingSpec`]: crate::spec::TrainingSpec

use super::Faults;
use crate::spec::{EarlyStopping, TrainingSpec, file, ranges};
use crate::vocab::{Backend, ErrorModel};

/// Checks `[training]`: a known backend, counts of at least 1, RMSProp's settings in
/// range, and the learning rates and early stopping.
pub(in crate::spec) fn check_training(
    training: file::TrainingFile,
    faults: &mut Faults,
) -> TrainingSpec {
    let file::TrainingFile {
        backend,
        epochs,
        batch_size,
        learning_rate,
        rmsprop_alpha,
        rmsprop_epsilon,
        checkpoint_every_epochs,
        early_stopping,
        replicates,
    } = training;
    let backend = backend.parse().unwrap_or_else(|message: String| {
        faults.add("training.backend", message);
        Backend::Flex
    });
    for (key, value) in [
        ("training.epochs", epochs),
        ("training.batch_size", batch_size),
        ("training.checkpoint_every_epochs", checkpoint_every_epochs),
        ("training.replicates", replicates),
    ] {
        if value == 0 {
            faults.add(key, "0 must be at least 1");
        }
    }
    ranges::EPOCHS.check("training.epochs", epochs as f64, faults);
    ranges::BATCH_SIZE.check("training.batch_size", batch_size as f64, faults);
    ranges::REPLICATES.check("training.replicates", replicates as f64, faults);
    let learning_rates = check_learning_rates(learning_rate, faults);
    if !(rmsprop_alpha > 0.0 && rmsprop_alpha < 1.0) {
        faults.add(
            "training.rmsprop_alpha",
            format!("{rmsprop_alpha} must lie strictly between 0 and 1"),
        );
    }
    if !(rmsprop_epsilon.is_finite() && rmsprop_epsilon > 0.0) {
        faults.add(
            "training.rmsprop_epsilon",
            format!("{rmsprop_epsilon} must be a positive number"),
        );
    }
    let early_stopping = early_stopping.map(|file| check_early_stopping(file, faults));
    TrainingSpec {
        backend,
        epochs,
        batch_size,
        learning_rates,
        rmsprop_alpha,
        rmsprop_epsilon,
        checkpoint_every_epochs,
        early_stopping,
        replicates,
    }
}

/// Checks `training.learning_rate`: a positive number per error model, in
/// `ErrorModel` order.
fn check_learning_rates(learning_rate: file::LearningRatesFile, faults: &mut Faults) -> [f64; 5] {
    let file::LearningRatesFile {
        em1,
        em2,
        em3,
        em4,
        em5,
    } = learning_rate;
    let learning_rates = [em1, em2, em3, em4, em5];
    for (model, rate) in ErrorModel::ALL.iter().zip(learning_rates) {
        let key = format!("training.learning_rate.{model}");
        if !(rate.is_finite() && rate > 0.0) {
            faults.add(&key, format!("{rate} must be a positive number"));
        }
    }
    learning_rates
}

/// Checks `[training.early_stopping]`: a patience of at least 1 epoch, an improvement
/// not negative.
fn check_early_stopping(
    early_stopping: file::EarlyStoppingFile,
    faults: &mut Faults,
) -> EarlyStopping {
    let file::EarlyStoppingFile {
        patience_epochs,
        min_improvement,
    } = early_stopping;
    if patience_epochs == 0 {
        faults.add(
            "training.early_stopping.patience_epochs",
            "0 must be at least 1",
        );
    }
    if !(min_improvement.is_finite() && min_improvement >= 0.0) {
        faults.add(
            "training.early_stopping.min_improvement",
            format!("{min_improvement} must be 0 or more (cm/s)²"),
        );
    }
    EarlyStopping {
        patience: patience_epochs,
        min_improvement,
    }
}

#[cfg(test)]
mod tests {
    use crate::spec::fixture::{quick_faults, quick_spec};
    use crate::vocab::ErrorModel;

    #[test]
    fn learning_rates_and_early_stopping_are_checked_at_their_keys() {
        let spec = quick_spec(&["training.learning_rate.EM3=2e-3"]);
        assert_eq!(spec.training.learning_rate(ErrorModel::Em3), 2e-3);
        assert_eq!(spec.training.learning_rate(ErrorModel::Em5), 5e-4);
        let set = "training.learning_rate.EM3=0";
        assert_eq!(
            quick_faults(&[set]),
            format!("--set {set}: training.learning_rate.EM3: 0 must be a positive number")
        );
        let set = "training.early_stopping={patience_epochs = 0}";
        assert_eq!(
            quick_faults(&[set]),
            format!("--set {set}: training.early_stopping.patience_epochs: 0 must be at least 1")
        );
    }
}
