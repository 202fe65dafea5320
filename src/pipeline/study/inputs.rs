//! What the points of an installation study read: every paired recording (each read
//! and its files hashed once, however many points name it, through
//! [`Recordings`]) and the DCNet models of each
//! paper spec the points apply (loaded once per spec). In: the experiment and the
//! output folder whose cache holds the models. Out: [`Inputs`], or the first recording
//! or model that cannot be had.

use crate::Vec3;
use crate::data::paired::Recordings;
use crate::estimators::{DcnetEstimator, Estimator};
use crate::installation::study::Recording;
use crate::installation::study::spec::StudySpec;
use crate::model::Settings;
use crate::pipeline::Plan;
use crate::pipeline::error::{DcnetSpecError, ExecuteError};
use crate::results::DataFile;
use crate::spec::Experiment;
use crate::vocab::{Correction, ErrorModel};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The DCNet models of one paper spec, each with its cache key.
pub struct DcnetModels(Vec<(DcnetEstimator, String)>);

impl DcnetModels {
    /// The models' cache keys, in error-model order.
    pub fn keys(&self) -> Vec<&str> {
        self.0.iter().map(|(_, key)| key.as_str()).collect()
    }

    /// The scale and bias the model of `error_model` estimates from a DVL window and
    /// the reference's body velocity on its stamps; `None` without such a model or
    /// where the window is shorter than the network's.
    pub fn estimate(
        &self,
        error_model: ErrorModel,
        dvl: &[Vec3],
        reference: &[Vec3],
    ) -> Option<Correction> {
        let (estimator, _) = self.0.iter().find(|(e, _)| e.error_model == error_model)?;
        (dvl.len() >= estimator.window).then(|| estimator.estimate(dvl, reference))
    }
}

/// What one point reads: its trajectories (indices into [`Inputs::recordings`]), the
/// files with their SHA-256, and its DCNet models (an index into [`Inputs::dcnets`]).
pub struct PointInputs {
    pub recordings: Vec<usize>,
    pub data_files: Vec<DataFile>,
    pub dcnets: Option<usize>,
}

/// Every recording and model the points of an experiment read.
pub struct Inputs {
    pub recordings: Vec<Recording>,
    pub dcnets: Vec<DcnetModels>,
    pub points: Vec<PointInputs>,
}

impl Inputs {
    pub fn read(experiment: &Experiment<StudySpec>, out: &Path) -> Result<Inputs, ExecuteError> {
        let mut read_once = Recordings::default();
        let mut recordings = Vec::new();
        // A recording per file read and name: the same files may be named otherwise in
        // another point.
        let mut recording_of: HashMap<(usize, &str), usize> = HashMap::new();
        let mut dcnets = Vec::new();
        let mut dcnets_of: HashMap<PathBuf, usize> = HashMap::new();
        let mut points = Vec::new();
        for point in &experiment.points {
            let spec = &point.spec;
            let mut point_recordings = Vec::new();
            let mut data_files = Vec::new();
            for (index, (name, source)) in spec.trajectories.iter().enumerate() {
                let read = read_once
                    .read(source)
                    .map_err(|error| ExecuteError::Recording {
                        index,
                        name: name.clone(),
                        error,
                    })?;
                let recording = read_once.get(read);
                let s = *recording_of.entry((read, name)).or_insert_with(|| {
                    recordings.push(Recording::new(name.clone(), recording.recording.clone()));
                    recordings.len() - 1
                });
                point_recordings.push(s);
                data_files.extend(recording.files.iter().map(|file| DataFile {
                    path: file.path.clone(),
                    sha256: file.sha256.clone(),
                }));
            }
            let point_dcnets = match &spec.dcnet_spec {
                None => None,
                Some(paper) => Some(match dcnets_of.get(paper) {
                    Some(&d) => d,
                    None => {
                        dcnets.push(dcnet_models(paper, out)?);
                        dcnets_of.insert(paper.clone(), dcnets.len() - 1);
                        dcnets.len() - 1
                    }
                }),
            };
            points.push(PointInputs {
                recordings: point_recordings,
                data_files,
                dcnets: point_dcnets,
            });
        }
        Ok(Inputs {
            recordings,
            dcnets,
            points,
        })
    }

    /// The trajectories of point `p`, in spec order.
    pub fn recordings_of(&self, p: usize) -> Vec<&Recording> {
        self.points[p]
            .recordings
            .iter()
            .map(|&s| &self.recordings[s])
            .collect()
    }

    /// The DCNet models point `p` applies, if any.
    pub fn dcnets_of(&self, p: usize) -> Option<&DcnetModels> {
        self.points[p].dcnets.map(|d| &self.dcnets[d])
    }
}

/// The paper spec's DCNet models (replicate 0 of each error model), set up to estimate,
/// each with its cache key.
fn dcnet_models(paper: &Path, out: &Path) -> Result<DcnetModels, ExecuteError> {
    let dcnet_error = |source: DcnetSpecError| ExecuteError::DcnetSpec {
        spec: paper.to_path_buf(),
        source,
    };
    let experiment = crate::spec::load_experiment(paper, &[]).map_err(|e| dcnet_error(e.into()))?;
    let plan = Plan::new(&experiment, out).map_err(|e| dcnet_error(e.into()))?;
    let spec = plan.spec(0);
    let mut models = Vec::new();
    for training in plan.trainings.iter().filter(|t| t.replicate == 0) {
        let trained = plan
            .models
            .load(spec, training.error_model, &training.key)
            .map_err(|e| dcnet_error(e.into()))?
            .ok_or_else(|| ExecuteError::DcnetMissing {
                spec: paper.to_path_buf(),
                out: out.to_path_buf(),
                error_model: training.error_model,
            })?;
        let estimator = DcnetEstimator {
            model: trained.model,
            error_model: training.error_model,
            window: spec.dataset.window_samples,
            settings: Settings::from(&spec.model),
            device: spec.training.backend.device(),
        };
        models.push((estimator, training.key.clone()));
    }
    Ok(DcnetModels(models))
}
