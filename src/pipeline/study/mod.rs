//! An installation study as a run, whole, one shard at a time, or collected: each
//! point of the spec (one, or one per point of its `[sweep]`) is calibrated on every
//! trajectory in turn, and each calibration (one trajectory, every window and method,
//! scored on every other trajectory) is stored in the cache under its key as it
//! finishes, so an interrupted run resumes where it stopped, `--shard K/N` computes
//! every N-th calibration, and `collect` puts the points together from the cache. A
//! point whose results folder is current and intact is not computed again; a folder
//! another spec file wrote is refused unless `--force`.
//! In: the experiment of an [`StudySpec`] and the output folder. Out: each
//! point's results folder, a sweep's table and index, or why not.
//!
//! - this file plans the calibrations and runs them: [`StudyPlan`];
//! - [`inputs`] reads the recordings and DCNet models the points use, each once;
//! - [`folder`] writes a point's results folder, manifest last;
//! - the sweep's table and index are written by [`crate::results::study_sweep`].

pub mod folder;
pub mod inputs;
pub mod learned;

use crate::files::{Seal, sha256_hex};
use crate::installation::study::rows::{RecordingRow, StudyResults};
use crate::installation::study::spec::StudySpec;
use crate::installation::study::{self, Calibrated};
use crate::pipeline::cache::{self, CalibrationStore};
use crate::pipeline::{ExecuteError, Executed, Mode, Shard, owner};
use crate::results::{self, Manifest, RunRecord, StageSeconds};
use crate::spec::Experiment;
use crate::vocab::ErrorModel;
use inputs::Inputs;
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::{Instant, SystemTime};

/// One calibration: trajectory `calibration` of point `point`, stored under `key`.
#[derive(Debug, Clone)]
pub struct Unit {
    pub point: usize,
    pub calibration: usize,
    pub key: String,
}

/// A study's plan: its points, what they read, and their calibrations with their keys.
pub struct StudyPlan<'a> {
    pub experiment: &'a Experiment<StudySpec>,
    pub out: PathBuf,
    /// The spec file as a manifest records it (see [`owner::recorded`]).
    pub spec_file: PathBuf,
    pub recorded_spec_file: String,
    pub inputs: Inputs,
    /// Point by point, each point's trajectories in spec order.
    pub units: Vec<Unit>,
    /// Each point's models of `[learned]`, by key.
    learned: Vec<Vec<learned::LearnedKey>>,
    pub store: CalibrationStore,
    /// Each point's results key: what its folder is current for.
    results_keys: Vec<String>,
    load_s: f64,
    started_at: SystemTime,
}

impl<'a> StudyPlan<'a> {
    /// Reads what the points of `experiment`, from `spec_file`, use, and keys their
    /// calibrations.
    pub fn new(
        experiment: &'a Experiment<StudySpec>,
        spec_file: &Path,
        out: &Path,
    ) -> Result<Self, ExecuteError> {
        let started_at = SystemTime::now();
        let clock = Instant::now();
        let inputs = Inputs::read(experiment, out)?;
        let mut units = Vec::new();
        let mut results_keys = Vec::new();
        let mut learned_keys = Vec::new();
        for (p, point) in experiment.points.iter().enumerate() {
            let spec = &point.spec;
            let data: Vec<&str> = inputs.points[p]
                .data_files
                .iter()
                .map(|f| f.sha256.as_str())
                .collect();
            let point_learned = learned::keys(spec, &data);
            let mut dcnets = inputs.dcnets_of(p).map(|d| d.keys()).unwrap_or_default();
            dcnets.extend(point_learned.iter().map(|k| k.key.as_str()));
            for calibration in 0..spec.trajectories.len() {
                units.push(Unit {
                    point: p,
                    calibration,
                    key: cache::calibration_key(&spec.resolved_toml, &data, &dcnets, calibration),
                });
            }
            let calibrations: Vec<&str> = units[units.len() - spec.trajectories.len()..]
                .iter()
                .map(|unit| unit.key.as_str())
                .collect();
            results_keys.push(cache::study_results_key(&spec.resolved_toml, &calibrations));
            learned_keys.push(point_learned);
        }
        Ok(StudyPlan {
            experiment,
            out: out.to_path_buf(),
            spec_file: spec_file.to_path_buf(),
            recorded_spec_file: owner::recorded(spec_file, out).unwrap_or_default(),
            inputs,
            units,
            learned: learned_keys,
            store: CalibrationStore::new(out),
            results_keys,
            load_s: clock.elapsed().as_secs_f64(),
            started_at,
        })
    }

    pub fn spec(&self, p: usize) -> &StudySpec {
        &self.experiment.points[p].spec
    }

    /// Point `p`'s results folder (`<out>/<name>/<point>` in a sweep).
    pub fn folder(&self, p: usize) -> PathBuf {
        self.out.join(&self.spec(p).name)
    }

    /// Unit `u` as a person names it: its trajectory, after its point in a sweep.
    pub fn label(&self, u: usize) -> String {
        let unit = &self.units[u];
        let trajectory = &self.spec(unit.point).trajectories[unit.calibration].0;
        if self.experiment.is_sweep() {
            let point = crate::results::sweep::point_folder(&self.spec(unit.point).name);
            format!("{point}: {trajectory}")
        } else {
            trajectory.clone()
        }
    }

    pub fn in_shard(&self, u: usize, shard: Shard) -> bool {
        u % shard.count == shard.index
    }

    /// Whether unit `u` is in the cache, intact.
    pub fn status(&self, u: usize) -> Seal {
        self.store.integrity(&self.units[u].key)
    }

    /// Whether point `p`'s folder holds its results, intact.
    pub fn is_current(&self, p: usize) -> bool {
        folder::is_current(&self.folder(p), &self.results_keys[p])
    }

    /// Does what `mode` asks: one shard's calibrations into the cache, or every point
    /// whose folder is not current (all with `force`) put together and written, from
    /// the cache and, but for `collect`, what it lacks computed here.
    pub fn execute(&self, mode: Mode) -> Result<Executed, ExecuteError> {
        let clock = Instant::now();
        let force = match mode {
            Mode::Shard { shard, .. } => return self.execute_shard(shard),
            Mode::All { force } => force,
            Mode::Collect => false,
        };
        self.check_owners(force)?;
        let stale: Vec<usize> = (0..self.experiment.points.len())
            .filter(|&p| force || !self.is_current(p))
            .collect();
        let (calibrated, computed) = self.calibrations(&stale, force, mode == Mode::Collect)?;
        let protocol_s = clock.elapsed().as_secs_f64();
        let (results, mut unfitted) = self.assemble(&stale, calibrated);
        let mut written = Vec::new();
        for (p, results) in results {
            folder::write_folder(
                self.spec(p),
                &self.folder(p),
                &results,
                self.manifest(p, protocol_s),
            )?;
            written.push((p, results));
        }
        if !unfitted.is_empty() {
            if !self.experiment.is_sweep() {
                return Err(unfitted.remove(0));
            }
            return Err(ExecuteError::Unfitted {
                errors: unfitted.iter().map(ToString::to_string).collect(),
                written: written.len(),
            });
        }
        let sweep = self.write_sweep(&written)?;
        Ok(Executed {
            done: computed,
            written: written.iter().map(|(p, _)| self.folder(*p)).collect(),
            sweep,
        })
    }

    /// Computes the calibrations of `shard` that the cache lacks, and writes nothing.
    fn execute_shard(&self, shard: Shard) -> Result<Executed, ExecuteError> {
        let to_do: Vec<usize> = (0..self.units.len())
            .filter(|&u| self.in_shard(u, shard) && self.status(u) != Seal::Intact)
            .collect();
        self.compute(&to_do)?;
        Ok(Executed {
            done: to_do.len(),
            ..Executed::default()
        })
    }

    /// Every calibration of the points `stale`, from the cache or computed (all of them
    /// with `force`; none, for `collect`, which refuses when the cache lacks one), and
    /// how many were computed.
    fn calibrations(
        &self,
        stale: &[usize],
        force: bool,
        collect: bool,
    ) -> Result<(HashMap<usize, Calibrated>, usize), ExecuteError> {
        let needed: Vec<usize> = (0..self.units.len())
            .filter(|&u| stale.contains(&self.units[u].point))
            .collect();
        let missing: Vec<usize> = needed
            .iter()
            .copied()
            .filter(|&u| force || self.status(u) != Seal::Intact)
            .collect();
        if collect && !missing.is_empty() {
            return Err(ExecuteError::NotCollected {
                out: self.out.clone(),
                missing: missing.iter().take(5).map(|&u| self.label(u)).collect(),
                missing_count: missing.len(),
                total: needed.len(),
            });
        }
        let mut calibrated = self.compute(&missing)?;
        for &u in &needed {
            if let std::collections::hash_map::Entry::Vacant(entry) = calibrated.entry(u) {
                let stored = match self.store.load(&self.units[u].key)? {
                    Some(stored) => stored,
                    // Damaged since it was looked at: computed again.
                    None => self.compute(&[u])?.remove(&u).expect("computed"),
                };
                entry.insert(stored);
            }
        }
        Ok((calibrated, missing.len()))
    }

    /// The results of each point of `stale` put together from its calibrations, and
    /// the refusals of those in which a method fitted at no window.
    fn assemble(
        &self,
        stale: &[usize],
        mut calibrated: HashMap<usize, Calibrated>,
    ) -> (Vec<(usize, StudyResults)>, Vec<ExecuteError>) {
        let mut assembled = Vec::new();
        let mut unfitted = Vec::new();
        for &p in stale {
            let parts = (0..self.units.len())
                .filter(|&u| self.units[u].point == p)
                .map(|u| {
                    calibrated
                        .remove(&u)
                        .expect("every needed calibration is here")
                });
            let (mut results, estimates) = study::assemble(self.spec(p), parts.collect());
            let point = match self.experiment.is_sweep() {
                true => format!("point {}: ", self.spec(p).name),
                false => String::new(),
            };
            if let Err(error) = folder::no_window_without_a_fit(self.spec(p), &results, &point) {
                unfitted.push(error);
                continue;
            }
            let recordings = self.inputs.recordings_of(p);
            results.trace = folder::trace(&results, &estimates, &recordings);
            results.recordings = (recordings.iter())
                .map(|r| RecordingRow::of(&r.name, &r.recording.counts()))
                .collect();
            assembled.push((p, results));
        }
        (assembled, unfitted)
    }

    /// Computes units `to_do` in parallel, each stored in the cache as it finishes (a
    /// damaged entry set aside first, and said).
    fn compute(&self, to_do: &[usize]) -> Result<HashMap<usize, Calibrated>, ExecuteError> {
        for &u in to_do {
            if let Some(said) = self.store.set_aside_damaged(&self.units[u].key)? {
                eprintln!("{said}");
            }
        }
        let mut learned_models = HashMap::new();
        for point in crate::first_seen(to_do.iter().map(|&u| self.units[u].point)) {
            let spec = self.spec(point);
            let recordings = self.inputs.recordings_of(point);
            let models =
                learned::train_or_load(spec, &recordings, &self.learned[point], &self.out)?;
            learned_models.insert(point, models);
        }
        to_do
            .par_iter()
            .map(|&u| {
                let unit = &self.units[u];
                let spec = self.spec(unit.point);
                let models = self.inputs.dcnets_of(unit.point);
                let dcnet = |model: ErrorModel, dvl: &[crate::Vec3], reference: &[crate::Vec3]| {
                    models.and_then(|m| m.estimate(model, dvl, reference))
                };
                let learned_models = &learned_models[&unit.point];
                let learned = |which, recording: &study::Recording, range| {
                    let model = learned_models.model(which)?;
                    let learned = spec.learned.as_ref()?;
                    crate::installation::learned::estimate(
                        model,
                        learned,
                        recording,
                        range,
                        &learned.training.backend.device(),
                    )
                };
                let recordings = self.inputs.recordings_of(unit.point);
                let calibrated = study::calibrate_on(
                    spec,
                    &recordings,
                    unit.calibration,
                    &study::Estimators {
                        dcnet: &dcnet,
                        learned: &learned,
                    },
                );
                self.store.save(&unit.key, &calibrated)?;
                Ok((u, calibrated))
            })
            .collect()
    }

    /// Refuses, before anything is computed, folders another spec file or another kind
    /// of run wrote (unless `force`, for the first).
    fn check_owners(&self, force: bool) -> Result<(), ExecuteError> {
        if self.experiment.is_sweep() {
            owner::check(&owner::Writer {
                folder: &self.out.join(&self.experiment.name),
                out: &self.out,
                spec_file: &self.recorded_spec_file,
                name: &self.experiment.name,
                spec_sha256: String::new(),
                writing: owner::Writing::StudySweep,
                force,
            })?;
        }
        for p in 0..self.experiment.points.len() {
            let spec = self.spec(p);
            owner::check(&owner::Writer {
                folder: &self.folder(p),
                out: &self.out,
                spec_file: &self.recorded_spec_file,
                name: &spec.name,
                spec_sha256: sha256_hex(spec.resolved_toml.as_bytes()),
                writing: owner::Writing::Study,
                force,
            })?;
        }
        Ok(())
    }

    /// The manifest of point `p`'s folder, but for its files and finishing time.
    fn manifest(&self, p: usize, protocol_s: f64) -> Manifest {
        let spec = self.spec(p);
        Manifest::of_run(RunRecord {
            name: spec.name.clone(),
            resolved_toml: &spec.resolved_toml,
            started_at: self.started_at,
            backend: String::new(),
            data_files: self.inputs.points[p].data_files.clone(),
            stage_seconds: StageSeconds {
                load: self.load_s,
                protocol: protocol_s,
                ..StageSeconds::default()
            },
            results_key: self.results_keys[p].clone(),
            spec_file: self.recorded_spec_file.clone(),
        })
    }

    /// A sweep's table and index, written when a point was written or the index is not
    /// that of the points' results; `None` for a single study or a current sweep.
    fn write_sweep(
        &self,
        written: &[(usize, StudyResults)],
    ) -> Result<Option<PathBuf>, ExecuteError> {
        if !self.experiment.is_sweep() {
            return Ok(None);
        }
        let folder = self.out.join(&self.experiment.name);
        if written.is_empty() && results::study_sweep::is_current(&folder, &self.results_keys) {
            return Ok(None);
        }
        let mut summaries = Vec::new();
        for p in 0..self.experiment.points.len() {
            let summary = match written.iter().find(|(w, _)| *w == p) {
                Some((_, results)) => results.summary.clone(),
                None => results::study::read_study(&self.folder(p))?.summary,
            };
            summaries.push((p, summary));
        }
        results::study_sweep::write(&folder, self.experiment, &summaries, &self.results_keys)?;
        Ok(Some(folder))
    }
}
