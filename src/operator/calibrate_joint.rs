//! `calibrate A.csv B.csv …`: one calibration over several recordings of the same
//! vehicle ([`crate::installation::estimate::joint`]), the vehicle's terms shared and each
//! recording's clock (and bias, where it is the dive's) its own. Beside it, each
//! recording fitted alone, and whether their terms agree with the joint ones within
//! their standard deviations (a χ² over the recordings); whether the joint fit's
//! residuals are at the specified noise (else the noise they show is what the standard
//! deviations use). Each recording is written corrected with its own clock, and the
//! installation saved where asked.
//! In: [`JointArgs`]. Out: a [`JointCalibration`], or the [`CalibrateError`] of the
//! recording at fault.

use crate::data::paired::{Loaded, PairedRecording, ReadCounts, Source};
use crate::evaluate::statistics::mean_std;
use crate::installation::estimate::between_dives::BetweenDives;
use crate::installation::estimate::bound::{DEFAULT_TOLERANCES, Noise, TermBound, bound};
use crate::installation::estimate::clock::{DEFAULT_SEARCH_S, fit_searched};
use crate::installation::estimate::fit::fit_about;
use crate::installation::estimate::joint::{JointFit, JointRecording, joint_fit, starts_from};
use crate::installation::frames::Reference;
use crate::installation::terms::names::{TermName, term_set};
use crate::operator::calibrate::{CalibrateError, Request, clear_of_inputs, named, refused};
use crate::operator::cost::{Cost, JOINT};
use crate::operator::inputs::{Reading, source};
use crate::operator::installation_file::{SavedInstallation, SavedSpread, SavedTerm};
use crate::results::ResultsError;
use crate::results::corrected::{Outputs, corrected_samples, stem, write};
use std::path::{Path, PathBuf};

/// What a joint `calibrate` is asked.
pub struct JointArgs<'a> {
    pub dvls: &'a [PathBuf],
    /// One per DVL file, or none where each DVL file holds its reference.
    pub references: &'a [PathBuf],
    pub columns: Option<&'a Path>,
    /// How to read the recordings beyond their columns (over the columns file).
    pub reading: Reading<'a>,
    pub terms: &'a [TermName],
    pub dive_terms: &'a [TermName],
    pub window_s: Option<f64>,
    pub dvl_noise_cm_s: f64,
    pub reference_noise_cm_s: f64,
    /// As single `calibrate`'s (checked the same, though no filter runs here).
    pub tolerance_pct: f64,
    pub out: &'a Path,
    pub save: Option<&'a Path>,
    /// How far from zero the first recording's clock is searched, s, and each other's
    /// from it ([`DEFAULT_SEARCH_S`] where `None`).
    pub search_s: Option<f64>,
}

impl JointArgs<'_> {
    /// What calibrating the recordings jointly will ask of this machine.
    pub fn cost(&self) -> Result<Cost, CalibrateError> {
        let files: Vec<(&Path, Option<&Path>)> = (self.dvls.iter().enumerate())
            .map(|(k, dvl)| (dvl.as_path(), self.references.get(k).map(PathBuf::as_path)))
            .collect();
        Cost::of(JOINT, &files).map_err(CalibrateError::Read)
    }

    /// What is asked beyond the files, checked as one recording's calibration is.
    fn request(&self) -> Request<'_> {
        Request {
            terms: self.terms,
            dive_terms: self.dive_terms,
            window_s: self.window_s,
            dvl_noise_cm_s: self.dvl_noise_cm_s,
            reference_noise_cm_s: self.reference_noise_cm_s,
            tolerance_pct: self.tolerance_pct,
            save: self.save,
            search_s: self.search_s,
        }
    }
}

/// How far one term's estimates from each recording alone lie from the joint one.
#[derive(Debug, Clone, PartialEq)]
pub struct Agreement {
    pub term: &'static str,
    /// Σ ((θ_k − θ) / σ_k)² over the recordings, and its p-value under χ²(K − 1).
    pub chi_square: f64,
    pub p_value: f64,
}

/// Everything a joint `calibrate` found and wrote.
pub struct JointCalibration {
    pub names: Vec<String>,
    /// How many samples each recording read, kept and left out.
    pub reads: Vec<ReadCounts>,
    pub joint: JointFit,
    /// Each recording alone: its fit's bound.
    pub alone: Vec<TermBound>,
    pub agreement: Vec<Agreement>,
    pub noise: Noise,
    pub written: Vec<PathBuf>,
}

/// The p-value under which the recordings' terms are said not to agree.
pub const AGREEMENT_P_VALUE: f64 = 1e-3;

/// The joint calibration of `args`.
pub fn calibrate_joint(args: &JointArgs) -> Result<JointCalibration, CalibrateError> {
    if !args.references.is_empty() && args.references.len() != args.dvls.len() {
        return Err(CalibrateError::References {
            dvls: args.dvls.len(),
            references: args.references.len(),
        });
    }
    refused(args.request())?;
    let noise = Noise {
        dvl_m_s: args.dvl_noise_cm_s / 100.0,
        reference_m_s: args.reference_noise_cm_s / 100.0,
    };
    let names = names(&args.dvls.iter().map(PathBuf::as_path).collect::<Vec<_>>());
    let outputs: Vec<Outputs> = names.iter().map(|s| Outputs::of(args.out, s)).collect();
    let inputs: Vec<Option<&Path>> = (args.dvls.iter().chain(args.references))
        .map(|p| Some(p.as_path()))
        .chain([args.columns])
        .collect();
    let corrected: Vec<&Path> = outputs.iter().flat_map(|o| o.all()).collect();
    clear_of_inputs(&inputs, &corrected, (args.save, false))?;
    args.cost()?.state()?;
    let sources = sources(args)?;
    let (loaded, shas) = load(args, &sources, &outputs)?;
    let recordings = read_all(args, loaded)?;
    let dives: Vec<(&Path, &str, &PairedRecording)> = (args.dvls.iter().zip(&shas))
        .zip(&recordings)
        .map(|((dvl, sha), (recording, _, _))| (dvl.as_path(), sha.as_str(), recording))
        .collect();
    each_recording_once(&dives)?;
    let calibrating: Vec<JointRecording> = recordings
        .iter()
        .map(|(recording, reference, window)| {
            let r: &PairedRecording = window.as_ref().unwrap_or(recording);
            JointRecording {
                time_s: &r.time_s,
                dvl_m_s: &r.dvl_m_s,
                reference,
            }
        })
        .collect();
    let (joint, alone) = fitted(args, &calibrating, noise)?;
    let mut written = Vec::new();
    for (k, (recording, reference, _)) in recordings.iter().enumerate() {
        let samples = corrected_samples(&joint.dives[k], recording, reference);
        written.extend(write(&outputs[k], &samples, &shas[k])?);
    }
    if let Some(path) = args.save {
        saved(args, &joint, shas)
            .write(path)
            .map_err(|source| ResultsError::Io {
                path: path.to_path_buf(),
                source,
            })?;
    }
    Ok(JointCalibration {
        reads: recordings
            .iter()
            .map(|(recording, ..)| recording.counts())
            .collect(),
        agreement: agreement(&joint, &alone),
        names,
        joint,
        alone,
        noise,
        written,
    })
}

/// Each recording's name in the outputs and the table: its DVL file's stem, numbered
/// by its place where two files share one (the same layout in several folders).
pub(crate) fn names(dvls: &[&Path]) -> Vec<String> {
    let stems: Vec<String> = dvls.iter().map(|d| stem(d)).collect();
    if crate::first_seen(stems.iter().map(String::as_str)).len() == stems.len() {
        return stems;
    }
    stems
        .iter()
        .enumerate()
        .map(|(k, s)| format!("{}-{s}", k + 1))
        .collect()
}

/// Each recording of `args`: its DVL's file beside its reference's, or the DVL's own.
fn sources(args: &JointArgs) -> Result<Vec<Source>, CalibrateError> {
    let source = |(k, dvl): (usize, &PathBuf)| {
        let reference = args.references.get(k).map(|r| r.as_path());
        source(dvl, reference, args.columns, args.reading).map_err(CalibrateError::Columns)
    };
    args.dvls.iter().enumerate().map(source).collect()
}

/// The files of each of `sources` read from disk and hashed, and each DVL file's
/// SHA-256; refused where `outputs` already there hold another recording's results.
fn load<'a>(
    args: &JointArgs,
    sources: &'a [Source],
    outputs: &[Outputs],
) -> Result<(Vec<Loaded<'a>>, Vec<String>), CalibrateError> {
    let loaded = sources
        .iter()
        .map(Source::load)
        .collect::<Result<Vec<Loaded>, _>>()?;
    let shas: Vec<String> = loaded.iter().map(|l| l.dvl_sha256().to_string()).collect();
    for ((dvl, ours), outputs) in args.dvls.iter().zip(&shas).zip(outputs) {
        outputs.not_another_recordings(dvl, ours)?;
    }
    Ok((loaded, shas))
}

/// Refuses two of `dives` (each its DVL file, that file's SHA-256 and its recording)
/// that are one recording: the same bytes, or the same samples written otherwise. A
/// joint calibration, against a reference or fixes, counts each recording once.
pub(super) fn each_recording_once(
    dives: &[(&Path, &str, &PairedRecording)],
) -> Result<(), CalibrateError> {
    for (k, (dvl, sha, recording)) in dives.iter().enumerate() {
        for (first, first_sha, earlier) in &dives[..k] {
            let (first, again) = (first.to_path_buf(), dvl.to_path_buf());
            if first_sha == sha {
                return Err(CalibrateError::Duplicate { first, again });
            }
            if earlier.same_samples(recording) {
                return Err(CalibrateError::SameSamples { first, again });
            }
        }
    }
    Ok(())
}

/// Each recording of `args`, parsed from the files `loaded` read, its reference, and
/// its window where one is asked.
fn read_all(
    args: &JointArgs,
    loaded: Vec<Loaded>,
) -> Result<Vec<(PairedRecording, Reference, Option<PairedRecording>)>, CalibrateError> {
    let mut recordings: Vec<(PairedRecording, Reference, Option<PairedRecording>)> = Vec::new();
    for loaded in loaded {
        let recording = loaded.parse()?.recording;
        let reference = Reference::new(&recording);
        let window = args.window_s.map(|w| recording.first_seconds(w));
        recordings.push((recording, reference, window));
    }
    Ok(recordings)
}

/// The joint fit of `calibrating`, from the first recording's fit alone and each
/// clock's search; beside it each recording fitted alone from its clock, for the
/// agreement.
fn fitted(
    args: &JointArgs,
    calibrating: &[JointRecording],
    noise: Noise,
) -> Result<(JointFit, Vec<TermBound>), CalibrateError> {
    let terms = term_set(args.terms);
    let fault = |k: usize, fault| CalibrateError::Fit {
        dvl: args.dvls[k].clone(),
        terms: named(args.terms),
        samples: calibrating[k].time_s.len(),
        fault,
    };
    let r = &calibrating[0];
    let first = fit_searched((r.time_s, r.dvl_m_s), r.reference, terms, args.search_s)
        .map_err(|f| fault(0, f))?;
    let search_s = args.search_s.unwrap_or(DEFAULT_SEARCH_S);
    let starts = starts_from(calibrating, first.installation, search_s);
    let mut alone = vec![bound(&first, noise, &DEFAULT_TOLERANCES)];
    for (k, r) in calibrating.iter().enumerate().skip(1) {
        let fitted = fit_about(r.time_s, r.dvl_m_s, r.reference, terms, starts[k])
            .map_err(|f| fault(k, f))?;
        alone.push(bound(&fitted, noise, &DEFAULT_TOLERANCES));
    }
    let dive = term_set(args.dive_terms);
    let joint = joint_fit(
        calibrating,
        &starts,
        (terms, dive),
        (noise, &DEFAULT_TOLERANCES),
    )
    .map_err(|f| fault(0, f))?;
    Ok((joint, alone))
}

/// Each vehicle term's recordings alone against the joint estimate.
fn agreement(joint: &JointFit, alone: &[TermBound]) -> Vec<Agreement> {
    (joint.bound.names.iter().enumerate())
        .map(|(k, &term)| {
            let mine: Vec<(f64, f64)> = alone
                .iter()
                .filter_map(|b| {
                    let i = b.names.iter().position(|n| *n == term)?;
                    Some((b.value[i], b.std[i]))
                })
                .collect();
            Agreement::of(term, joint.bound.value[k], &mine)
        })
        .collect()
}

impl Agreement {
    /// How far the recordings' own estimates of `term`, `alone` (value, standard
    /// deviation each), lie from its joint estimate `joint`.
    pub fn of(term: &'static str, joint: f64, alone: &[(f64, f64)]) -> Agreement {
        use statrs::distribution::{ChiSquared, ContinuousCDF};
        let chi_square: f64 = alone.iter().map(|(v, s)| ((v - joint) / s).powi(2)).sum();
        let freedom = (alone.len().max(2) - 1) as f64;
        let p_value = ChiSquared::new(freedom).map_or(f64::NAN, |d| 1.0 - d.cdf(chi_square));
        Agreement {
            term,
            chi_square,
            p_value,
        }
    }
}

/// The installation file of a joint calibration: the vehicle's terms with their bound
/// and, over three recordings or more, their spread between dives; each dive term at its
/// mean over the recordings, its standard deviation their spread (it is found again on
/// each dive).
fn saved(args: &JointArgs, joint: &JointFit, shas: Vec<String>) -> SavedInstallation {
    let every = term_set(args.terms);
    let names = every.parameter_names();
    let vehicle = &joint.bound;
    let per_dive: Vec<Vec<f64>> = joint
        .dives
        .iter()
        .map(|d| d.to_parameters(&every))
        .collect();
    let terms: Vec<SavedTerm> = names
        .iter()
        .enumerate()
        .map(
            |(k, name)| match vehicle.names.iter().position(|n| n == name) {
                Some(i) => SavedTerm {
                    name: name.to_string(),
                    value: vehicle.value[i],
                    std: vehicle.std[i],
                },
                None => {
                    let (mean, spread) = mean_std(per_dive.iter().map(|p| p[k]));
                    SavedTerm {
                        name: name.to_string(),
                        value: mean,
                        std: spread,
                    }
                }
            },
        )
        .collect();
    let correlation = correlation_over(&names, (&vehicle.names, &vehicle.correlation), |_| true);
    let residual = joint.residual_rms_m_s.iter().fold([0.0; 3], |sum, r| {
        [0, 1, 2].map(|k| sum[k] + r[k] * r[k] / joint.residual_rms_m_s.len() as f64)
    });
    let recording = args
        .dvls
        .iter()
        .map(|d| d.display().to_string())
        .collect::<Vec<_>>()
        .join(", ");
    SavedInstallation::of_terms(
        (terms, correlation),
        (args.terms, args.dive_terms),
        (recording, shas.join(", ")),
        (args.dvl_noise_cm_s, args.reference_noise_cm_s),
        residual.map(f64::sqrt),
    )
    .with_spread(
        joint.dives.len(),
        spreads(&joint.bound.names, &joint.between),
    )
}

/// The correlations of the vehicle's terms `names` (`correlation` among them) over every
/// parameter `every` an installation file saves, in its order: a parameter's with
/// itself 1, and 0 beside one not among `names` or not `kept` (by its place in `names`).
pub(crate) fn correlation_over(
    every: &[&str],
    (names, correlation): (&[&str], &[Vec<f64>]),
    kept: impl Fn(usize) -> bool,
) -> Vec<Vec<f64>> {
    let at = |name: &&str| names.iter().position(|n| n == name).filter(|&i| kept(i));
    (every.iter())
        .map(|a| {
            (every.iter())
                .map(|b| match (at(a), at(b)) {
                    (Some(i), Some(j)) => correlation[i][j],
                    _ if a == b => 1.0,
                    _ => 0.0,
                })
                .collect()
        })
        .collect()
}

/// The spread between dives of each vehicle term of `names` that has one in `between`,
/// as the installation file saves it.
pub(crate) fn spreads(names: &[&str], between: &[Option<BetweenDives>]) -> Vec<SavedSpread> {
    (names.iter().zip(between))
        .filter_map(|(name, between)| {
            let between = between.as_ref()?;
            let (low, high) = between.next_dive_95();
            let finite = [between.std, low, high].iter().all(|v| v.is_finite());
            finite.then(|| SavedSpread {
                name: name.to_string(),
                std: between.std,
                next_dive: [low, high],
            })
        })
        .collect()
}
