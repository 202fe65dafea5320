//! The content-addressed store every run shares, `OUT/.cache/`. A dataset, a trained
//! model and a Monte Carlo block are each keyed by the SHA-256 of exactly the inputs
//! that determine them (the relevant settings of the resolved spec, the SHA-256 of the
//! data files, the code version), so a run reuses whatever another run, sweep point or
//! shard already computed, and a changed setting recomputes only what depends on it.
//! In: the spec and its data files. Out: the keys, and the two stores.
//!
//! Every stored file is sealed ([`crate::files::write_sealed`]): a `.sha256` beside it
//! names its key and its SHA-256, checked whenever it is read. A file that fails its
//! seal (a flipped byte, a truncation, another entry copied over it, a write cut
//! short) is never used: `plan` shows its task as `to do (damaged)`, and a run moves it
//! into `damaged/`, says so once, and computes it again.
//!
//! - Datasets are keyed but not stored: the paper's 203 MB generate in 0.26 s, while an
//!   fsynced write of them takes 1 s and reading them back would save at most 0.1 s.
//!   The points of a sweep that share a dataset share it in memory, and a run whose
//!   models are all stored generates none.
//! - Models live in `models/` (the paper's) and `learned/` (an installation study's
//!   `[learned]`), both in one [`ModelStore`] that tells them apart by their
//!   [`ModelId`], with their [`checkpoints`] while they train.
//! - Monte Carlo blocks (one estimator on one DVL, every run) live in `monte_carlo/`
//!   ([`BlockStore`]) as Parquet files of their per-run rows.
//! - The calibrations of installation studies (one calibration trajectory, every window
//!   and method, scored on every other trajectory) live in `installation/`
//!   ([`CalibrationStore`]).

pub mod blocks;
pub mod calibrations;
pub mod checkpoints;
pub mod identity;
pub mod models;

pub use blocks::BlockStore;
pub use calibrations::CalibrationStore;
pub use identity::ModelId;
pub use models::{Blueprint, ModelStore, ModelStoreError, StoredModel};

use crate::files::sha256_hex;
use crate::results;
use crate::spec::{FileFormat, Origin, Spec};
use crate::vocab::{ErrorModel, EstimatorKind};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Bumped whenever the dataset generation changes its bytes.
const DATASET_CODE_VERSION: u32 = 1;
/// Bumped whenever training changes in a way that changes the weights.
const TRAINING_CODE_VERSION: u32 = 6;
/// Bumped whenever the protocol or an estimator changes its numbers (2: the held-out
/// rows of the calibration time).
const PROTOCOL_CODE_VERSION: u32 = 2;
/// Bumped whenever an installation study's calibration changes its numbers (2: the
/// Kalman filters' terms against time; 3: standard deviations from the residuals'
/// noise beside the bound's; 4: the terms left out that the residuals still follow;
/// 5: the Kalman filter's standard deviations from the noise its residuals show, and
/// its run up to the longest window only; 6: the rows with the dive's clock found
/// again; 7: the noise's level counting what the fit absorbs, standard deviations no
/// longer widened, a joint fit's spread between dives).
const INSTALLATION_CODE_VERSION: u32 = 8;
/// Bumped whenever the tables put together from an installation study's calibrations
/// change (2: the calibration time's band of what calibration can change).
const INSTALLATION_TABLES_CODE_VERSION: u32 = 3;
/// Bumped whenever the tables put together from the blocks change (2: the bound rows
/// and the efficiency column; 3: the held-out curves and the calibration time; 4: the
/// calibration time read at the calibration windows, its band of the excess over the
/// bound; 5: no calibration time for a method that ends further above the bound than
/// the tolerance of the bound's own drop over the windows).
const TABLES_CODE_VERSION: u32 = 5;

/// The folder of the cache under a results folder.
pub const FOLDER: &str = ".cache";

/// The SHA-256 of every data file the specs read, computed once.
#[derive(Debug, Clone, Default)]
pub struct DataHashes(BTreeMap<PathBuf, String>);

impl DataHashes {
    pub fn of<'a>(specs: impl IntoIterator<Item = &'a Spec>) -> std::io::Result<Self> {
        let mut hashes = BTreeMap::new();
        for spec in specs {
            for source in &spec.trajectories {
                if let Origin::File { path, .. } = &source.origin
                    && !hashes.contains_key(path)
                {
                    let bytes = std::fs::read(path).map_err(|e| {
                        std::io::Error::new(e.kind(), format!("{}: {e}", path.display()))
                    })?;
                    hashes.insert(path.clone(), sha256_hex(&bytes));
                }
            }
        }
        Ok(Self(hashes))
    }

    /// The files `spec` reads, with their SHA-256, for the manifest.
    pub fn files_of(&self, spec: &Spec) -> Vec<results::DataFile> {
        let mut files: Vec<results::DataFile> = Vec::new();
        for source in &spec.trajectories {
            if let Origin::File { path, .. } = &source.origin
                && !files.iter().any(|f| &f.path == path)
            {
                files.push(results::DataFile {
                    path: path.clone(),
                    sha256: self.0[path].clone(),
                });
            }
        }
        files
    }

    /// A trajectory as a key sees it: its name and where its samples come from (a
    /// `.csv` file's with its velocity columns).
    fn source(&self, spec: &Spec, index: usize) -> (String, String) {
        let source = &spec.trajectories[index];
        let origin = match &source.origin {
            Origin::File {
                path,
                format,
                samples,
            } => {
                // A `.npy` file's key is as it was before `.csv` files were read.
                let columns = match format {
                    FileFormat::Npy => String::new(),
                    FileFormat::Csv { columns } => format!(" columns {columns:?}"),
                };
                format!("sha256 {}{columns} samples {samples:?}", self.0[path])
            }
            Origin::Synthetic { samples } => {
                format!("synthetic {samples} {:?}", spec.resolved.data.synthetic)
            }
        };
        (source.name.clone(), origin)
    }
}

/// The key of calibration trajectory `calibration` of an installation study: the study's
/// resolved spec without its `name` (a sweep point and a single run of the same
/// settings share it), the calibration time's tolerance and the recordings' paths, the SHA-256 of every recording it reads (each calibration is
/// scored on all of them), the keys of the DCNet models it applies, and the code
/// version.
pub fn calibration_key(
    resolved_toml: &str,
    data_sha256: &[&str],
    dcnet_keys: &[&str],
    calibration: usize,
) -> String {
    let mut settings: toml::Table = toml::from_str(resolved_toml).expect("a resolved spec is TOML");
    settings.remove("name");
    // The report's tolerance changes no calibration.
    if let Some(toml::Value::Table(calibration)) = settings.get_mut("calibration") {
        calibration.remove("time_tolerance_pct");
    }
    // The recordings count by their bytes (`data_sha256`), not where they lie: the same
    // recordings at another path are the same calibration.
    if let Some(toml::Value::Table(recordings)) = settings.get_mut("recordings")
        && let Some(toml::Value::Array(trajectories)) = recordings.get_mut("trajectories")
    {
        for trajectory in trajectories
            .iter_mut()
            .filter_map(toml::Value::as_table_mut)
        {
            trajectory.remove("dvl");
            trajectory.remove("reference");
        }
    }
    hash(&(
        "installation calibration",
        INSTALLATION_CODE_VERSION,
        toml::to_string(&settings).expect("a TOML table serializes"),
        data_sha256,
        dcnet_keys,
        calibration,
    ))
}

/// The key of one of `[learned]`'s models: its `[learned]` table, the DVL noise, the
/// trajectories' names (they seed the simulated noise) and columns, the recordings'
/// SHA-256, its fold, source and replicate, and the training code.
pub fn learned_key(
    resolved_toml: &str,
    data_sha256: &[&str],
    model: &crate::installation::study::LearnedModel,
) -> String {
    let mut settings: toml::Table = toml::from_str(resolved_toml).expect("a resolved spec is TOML");
    // A replicate's model is the same however many replicates there are.
    if let Some(training) = settings
        .get_mut("learned")
        .and_then(|learned| learned.get_mut("training"))
        .and_then(toml::Value::as_table_mut)
    {
        training.remove("replicates");
    }
    let at = |path: &[&str]| {
        let mut value = settings.get(path[0]);
        for key in &path[1..] {
            value = value.and_then(|v| v.get(key));
        }
        value.map(|v| v.to_string()).unwrap_or_default()
    };
    let names: Vec<String> = settings
        .get("recordings")
        .and_then(|r| r.get("trajectories"))
        .and_then(toml::Value::as_array)
        .map(|list| {
            list.iter()
                .map(|t| t.get("name").map(|n| n.to_string()).unwrap_or_default())
                .collect()
        })
        .unwrap_or_default();
    hash(&(
        "learned installation model",
        TRAINING_CODE_VERSION,
        env!("CARGO_PKG_VERSION"),
        at(&["learned"]),
        at(&["noise", "dvl_cm_s"]),
        names,
        at(&["recordings", "columns"]),
        data_sha256,
        model.fold,
        model.source.name(),
        model.replicate,
    ))
}

/// The SHA-256, in hex, of `inputs` as JSON.
pub(crate) fn hash(inputs: &impl Serialize) -> String {
    sha256_hex(
        serde_json::to_string(inputs)
            .expect("key inputs serialize")
            .as_bytes(),
    )
}

/// The key of the training set: what the windows are cut from and how.
pub fn dataset_key(spec: &Spec, hashes: &DataHashes) -> String {
    let r = &spec.resolved;
    hash(&(
        ("dataset", DATASET_CODE_VERSION, env!("CARGO_PKG_VERSION")),
        spec.seed,
        (r.data.sample_rate_hz, r.data.ground_truth_window_samples),
        &r.sensors,
        &r.grid,
        (
            r.dataset.window_s,
            r.dataset.stride_s,
            r.dataset.validation_fraction,
        ),
        spec.dataset
            .trajectories
            .iter()
            .map(|&t| hashes.source(spec, t))
            .collect::<Vec<_>>(),
    ))
}

/// The key of replicate `replicate` of `error_model`'s trained DCNet; replicate 0
/// keeps the key of a run without replicates.
pub fn model_key(
    spec: &Spec,
    error_model: ErrorModel,
    replicate: usize,
    dataset_key: &str,
) -> String {
    let r = &spec.resolved;
    let key = hash(&(
        ("model", TRAINING_CODE_VERSION, env!("CARGO_PKG_VERSION")),
        dataset_key,
        error_model.to_string(),
        spec.seed,
        &r.model,
        &r.training.backend,
        (spec.training.epochs, spec.training.batch_size),
        spec.training.learning_rate(error_model),
        (spec.training.rmsprop_alpha, spec.training.rmsprop_epsilon),
        &r.training.early_stopping,
    ));
    if replicate == 0 {
        return key;
    }
    hash(&(key, "replicate", replicate))
}

/// The key of a results folder: its resolved spec and the blocks it is put together
/// from.
pub fn results_key(spec: &Spec, block_keys: &[&str]) -> String {
    hash(&(
        ("results", TABLES_CODE_VERSION),
        spec.resolved_toml(),
        block_keys,
    ))
}

/// The key of an installation study's results folder: its resolved spec and the keys
/// of the calibrations it is put together from (which name its recordings and models).
pub fn study_results_key(resolved_toml: &str, calibration_keys: &[&str]) -> String {
    hash(&(
        ("installation results", INSTALLATION_TABLES_CODE_VERSION),
        resolved_toml,
        calibration_keys,
    ))
}

/// The key of one estimator's Monte Carlo block on the DVL at `dvl`; `model_keys` are
/// the keys of the DCNets it runs (one for DCNet, each replicate's for the ensemble).
pub fn block_key(
    spec: &Spec,
    hashes: &DataHashes,
    dvl: usize,
    estimator: EstimatorKind,
    error_model: Option<ErrorModel>,
    model_keys: &[&str],
) -> String {
    let r = &spec.resolved;
    let model_key = match model_keys {
        [] => None,
        [one] => Some(one.to_string()),
        many => Some(hash(&many)),
    };
    hash(&(
        (
            "monte_carlo",
            PROTOCOL_CODE_VERSION,
            env!("CARGO_PKG_VERSION"),
        ),
        spec.seed,
        &r.dvl[dvl],
        &r.sensors,
        (r.data.sample_rate_hz, r.data.ground_truth_window_samples),
        hashes.source(spec, spec.calibration.trajectory),
        (
            &r.calibration.window_sizes_s,
            r.calibration.monte_carlo_runs,
        ),
        spec.evaluation
            .iter()
            .map(|&t| hashes.source(spec, t))
            .collect::<Vec<_>>(),
        (estimator.to_string(), error_model.map(|m| m.to_string())),
        model_key,
        matches!(estimator, EstimatorKind::Kalman | EstimatorKind::KalmanBeam)
            .then_some(&r.estimators.kalman),
    ))
}

/// The cache under the results folder `out`.
pub fn root(out: &Path) -> PathBuf {
    out.join(FOLDER)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::installation::learned::spec::TrainingSource;
    use crate::installation::study::LearnedModel;

    /// A replicate's model is the same however many replicates there are, and another
    /// replicate, fold or setting of `[learned]` is another model.
    #[test]
    fn a_learned_models_key_leaves_out_the_replicate_count_only() {
        let spec = |replicates: usize, folds: usize| {
            format!(
                "name = \"a\"\n[noise]\ndvl_cm_s = 2.0\n[learned]\nfolds = {folds}\n[learned.training]\nepochs = 3\nreplicates = {replicates}\n"
            )
        };
        let model = |replicate, fold| LearnedModel {
            source: TrainingSource::Simulated,
            replicate,
            fold,
        };
        let key = |text: &str, m| learned_key(text, &["abc"], &m);
        assert_eq!(key(&spec(2, 2), model(1, 0)), key(&spec(3, 2), model(1, 0)));
        assert_ne!(key(&spec(2, 2), model(1, 0)), key(&spec(2, 2), model(0, 0)));
        assert_ne!(key(&spec(2, 2), model(1, 0)), key(&spec(2, 2), model(1, 1)));
        assert_ne!(key(&spec(2, 2), model(1, 0)), key(&spec(2, 3), model(1, 0)));
        // The trajectories' names seed the simulated noise; the reference's noise is
        // not used in training.
        let named = |name: &str| {
            format!(
                "{}[recordings]\n[[recordings.trajectories]]\nname = \"{name}\"\n",
                spec(2, 2)
            )
        };
        assert_ne!(
            key(&named("T1"), model(1, 0)),
            key(&named("T2"), model(1, 0))
        );
        let reference_noise =
            spec(2, 2).replace("dvl_cm_s = 2.0", "dvl_cm_s = 2.0\nreference_cm_s = 0.5");
        assert_eq!(
            key(&spec(2, 2), model(1, 0)),
            key(&reference_noise, model(1, 0))
        );
    }
}
