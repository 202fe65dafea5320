//! What identifies a model in the [`super::ModelStore`] beside its key: one of the
//! paper's error models, or one of an installation study's `[learned]` models (its
//! training source, fold and replicate). The identity names the model's folder and the
//! start of its files' names, and how the log calls it; the key alone says which
//! inputs made it. In: an error model or a learned model. Out: names.

use crate::installation::study::LearnedModel;
use crate::vocab::ErrorModel;

/// Which model the store holds under a key.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelId {
    /// The paper's DCNet of an error model (its replicate is in its key).
    Paper(ErrorModel),
    /// A model of an installation study's `[learned]`.
    Learned(LearnedModel),
}

impl From<ErrorModel> for ModelId {
    fn from(error_model: ErrorModel) -> Self {
        ModelId::Paper(error_model)
    }
}

impl From<LearnedModel> for ModelId {
    fn from(model: LearnedModel) -> Self {
        ModelId::Learned(model)
    }
}

impl ModelId {
    /// The folder under the cache that holds the models of this kind: `models` for
    /// the paper's, `learned` for `[learned]`'s (where they were stored before they
    /// shared the store, so that stored models stay where runs find them).
    pub fn folder(self) -> &'static str {
        match self {
            ModelId::Paper(_) => "models",
            ModelId::Learned(_) => "learned",
        }
    }

    /// The start of its files' names, before `-<key>`: `EM5`, or
    /// `simulated-fold1-replicate1` (fold and replicate counted from 1).
    pub fn file_prefix(self) -> String {
        match self {
            ModelId::Paper(error_model) => error_model.to_string(),
            ModelId::Learned(model) => format!(
                "{}-fold{}-replicate{}",
                model.source.name(),
                model.fold + 1,
                model.replicate + 1
            ),
        }
    }
}

/// How the log names the model after "DCNet ": `EM5`, `installation simulated fold 1`,
/// `installation simulated fold 1 replicate 2`.
impl std::fmt::Display for ModelId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ModelId::Paper(error_model) => write!(f, "{error_model}"),
            ModelId::Learned(model) => {
                write!(
                    f,
                    "installation {} fold {}",
                    model.source.name(),
                    model.fold + 1
                )?;
                match model.replicate {
                    0 => Ok(()),
                    r => write!(f, " replicate {}", r + 1),
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::installation::learned::spec::TrainingSource;

    /// A learned model's files keep the names they had before the store was shared.
    #[test]
    fn a_learned_models_names_count_fold_and_replicate_from_one() {
        let id = ModelId::from(LearnedModel {
            source: TrainingSource::Vehicle,
            replicate: 1,
            fold: 2,
        });
        assert_eq!(id.folder(), "learned");
        assert_eq!(id.file_prefix(), "vehicle-fold3-replicate2");
        assert_eq!(id.to_string(), "installation vehicle fold 3 replicate 2");
        let paper = ModelId::from(ErrorModel::Em5);
        assert_eq!(
            (paper.folder(), paper.file_prefix()),
            ("models", "EM5".into())
        );
        assert_eq!(paper.to_string(), "EM5");
    }
}
