//! `calibrate A.csv B.csv … --fixes FA --fixes FB … --attitude AA --attitude AB …`: the
//! dives of one vehicle with position fixes alone, calibrated as one vehicle. Each dive
//! is read and fitted alone, as `calibrate --fixes` fits it
//! ([`crate::operator::calibrate_fixes::fitted_dive`]); the vehicle's terms are the dives'
//! estimates weighed by their information, each term's spread between the dives beside
//! them ([`crate::installation::estimate::fix_joint`]); each dive's clock (and the
//! fixes' latency, where fitted) is fitted again with the vehicle's terms carried, and
//! the dive written corrected by them. The installation saved carries the spread
//! between dives to `correct`, as a joint velocity calibration's does.
//! In: one [`FixArgs`] per dive. Out: a [`JointFixCalibration`], or the
//! [`CalibrateError`] of the dive at fault; nothing is written unless every dive fitted.

use crate::data::paired::PairedRecording;
use crate::evaluate::statistics::mean_std;
use crate::installation::estimate::fix_joint::{FixVehicle, fix_vehicle};
use crate::installation::estimate::fixes::{FixFit, FixTerms, fit_fixes_around};
use crate::installation::frames::{Attitude, Reference};
use crate::installation::terms::names::term_set;
use crate::operator::calibrate::{CalibrateError, clear_of_inputs, named};
use crate::operator::calibrate_fixes::{
    FittedDive, FixArgs, FixCalibration, fitted_from, read_dive,
};
use crate::operator::calibrate_joint::{
    Agreement, correlation_over, each_recording_once, names, spreads,
};
use crate::operator::cost::{Cost, JOINT_FIXES};
use crate::operator::installation_file::{SavedInstallation, SavedTerm};
use crate::results::ResultsError;
use crate::results::corrected::{Outputs, corrected_samples, write};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// Everything a joint `calibrate` with fixes found and wrote.
pub struct JointFixCalibration {
    pub names: Vec<String>,
    /// Each dive read and fitted alone (nothing written of it).
    pub alone: Vec<FixCalibration>,
    pub vehicle: FixVehicle,
    /// Each vehicle term's dives alone against the vehicle's estimate.
    pub agreement: Vec<Agreement>,
    /// Each dive's clock (and the fixes' latency, where fitted) fitted again with the
    /// vehicle's terms carried: the installation each dive is written corrected by,
    /// and the fixes' residual it leaves.
    pub carried: Vec<FixFit>,
    pub written: Vec<PathBuf>,
}

/// The joint calibration of `dives` (one [`FixArgs`] each, alike but for their files).
pub fn calibrate_fixes_joint(dives: &[FixArgs]) -> Result<JointFixCalibration, CalibrateError> {
    let first = &dives[0];
    for dive in dives {
        crate::operator::calibrate_fixes::refused(dive)?;
    }
    let dvls: Vec<&Path> = dives.iter().map(|d| d.files.dvl).collect();
    let names = names(&dvls);
    let outputs: Vec<Outputs> = names.iter().map(|s| Outputs::of(first.out, s)).collect();
    let inputs: Vec<Option<&Path>> = dives.iter().flat_map(|d| d.files.inputs()).collect();
    let corrected: Vec<&Path> = outputs.iter().flat_map(|o| o.all()).collect();
    clear_of_inputs(&inputs, &corrected, (first.save, false))?;
    let rows = (dives.iter())
        .map(|d| d.files.rows())
        .collect::<Result<Vec<_>, _>>()
        .map_err(CalibrateError::Read)?;
    Cost::on(JOINT_FIXES, rows, crate::footprint::machine_memory() as f64).state()?;
    let readings = (dives.par_iter().zip(&outputs))
        .map(|(dive, outputs)| read_dive(dive, outputs))
        .collect::<Result<Vec<_>, _>>()?;
    let each: Vec<(&Path, &str, &PairedRecording)> = (dvls.iter().zip(&readings))
        .map(|(dvl, (reading, _))| {
            let read = &reading.read;
            (*dvl, read.dvl_sha256(), &read.recording)
        })
        .collect();
    each_recording_once(&each)?;
    let fitted = (dives.par_iter().zip(readings))
        .map(|(dive, reading)| fitted_from(dive, reading))
        .collect::<Result<Vec<FittedDive>, _>>()?;
    let fits: Vec<FixFit> = fitted.iter().map(|d| d.fit.clone()).collect();
    let dive_terms = term_set(first.dive_terms).parameter_names();
    let vehicle = fix_vehicle(&fits, &dive_terms);
    let carried = (dives.par_iter().zip(&fitted))
        .map(|(dive, fitted)| carried(dive, fitted, &vehicle))
        .collect::<Result<Vec<FixFit>, _>>()?;
    let mut written = Vec::new();
    for ((fitted, carried), outputs) in fitted.iter().zip(&carried).zip(&outputs) {
        let read = &fitted.reading.read;
        let recording = &read.recording;
        let samples =
            corrected_samples(&carried.installation, recording, &Reference::new(recording));
        written.extend(write(outputs, &samples, read.dvl_sha256()).map_err(CalibrateError::Write)?);
    }
    let shas: Vec<String> = (fitted.iter())
        .map(|d| d.reading.read.dvl_sha256().to_string())
        .collect();
    if let Some(path) = first.save {
        saved(dives, (&vehicle, &carried), shas)
            .write(path)
            .map_err(|source| {
                CalibrateError::Write(ResultsError::Io {
                    path: path.to_path_buf(),
                    source,
                })
            })?;
    }
    let agreement = (vehicle.names.iter().enumerate())
        .map(|(i, &term)| {
            let alone: Vec<(f64, f64)> = (0..vehicle.own.len())
                .filter_map(|k| vehicle.weighed(k, i))
                .collect();
            Agreement::of(term, vehicle.value[i], &alone)
        })
        .collect();
    let alone = (dives.iter().zip(fitted))
        .map(|(dive, fitted)| {
            let drifts = fitted.drifts(None);
            let latency_s = dive.files.fix_latency_s.unwrap_or(0.0);
            FixCalibration::of((fitted, drifts), latency_s, Vec::new())
        })
        .collect();
    Ok(JointFixCalibration {
        names,
        alone,
        vehicle,
        agreement,
        carried,
        written,
    })
}

/// The dive's own terms (its clock, and the fixes' latency where asked) fitted again to
/// its fixes with the vehicle's terms carried, from the clock its fit alone found.
fn carried(
    dive: &FixArgs,
    fitted: &FittedDive,
    vehicle: &FixVehicle,
) -> Result<FixFit, CalibrateError> {
    let recording = &fitted.reading.read.recording;
    let own_clock = fitted.fit.installation.time_offset_s;
    let terms = FixTerms {
        set: term_set(dive.dive_terms),
        fix_latency: dive.fix_latency,
    };
    let carried = vehicle.installation(&term_set(dive.terms), own_clock);
    let dvl = (&recording.time_s[..], &recording.dvl_m_s[..]);
    let attitude = Attitude::of(recording);
    let (fixes, noise) = (&fitted.reading.fixes, fitted.noise);
    fit_fixes_around(
        dvl,
        &recording.pieces(),
        &attitude,
        fixes,
        (terms, carried),
        noise,
    )
    .map_err(|fault| CalibrateError::FixFit {
        fixes: dive.files.fixes_named(),
        terms: named(dive.dive_terms),
        fault,
    })
}

/// The installation file of a joint calibration against fixes: the vehicle's terms with
/// their standard deviations and correlations and, over three dives or more, their
/// spread between dives; the dive's clock at its mean over the dives, its standard
/// deviation their spread (it is found again on each dive). A term no dive applied is
/// zero.
fn saved(
    dives: &[FixArgs],
    (vehicle, carried): (&FixVehicle, &[FixFit]),
    shas: Vec<String>,
) -> SavedInstallation {
    let first = &dives[0];
    let every = term_set(first.terms).parameter_names();
    let clocks: Vec<f64> = carried
        .iter()
        .map(|f| f.installation.time_offset_s)
        .collect();
    let terms: Vec<SavedTerm> = (every.iter())
        .map(|&name| {
            let (value, std) = match vehicle.names.iter().position(|n| *n == name) {
                Some(i) if vehicle.applied[i] => (vehicle.value[i], vehicle.std[i]),
                _ if name == "time_offset_s" => mean_std(clocks.iter().copied()),
                _ => (0.0, f64::INFINITY),
            };
            SavedTerm {
                name: name.to_string(),
                value,
                std,
            }
        })
        .collect();
    let correlation = correlation_over(&every, (&vehicle.names, &vehicle.correlation), |i| {
        vehicle.applied[i]
    });
    let recording = (dives.iter())
        .map(|d| d.files.dvl.display().to_string())
        .collect::<Vec<_>>()
        .join(", ");
    let noise_cm_s = first.dvl_noise_cm_s;
    let file = SavedInstallation::of_terms(
        (terms, correlation),
        (first.terms, first.dive_terms),
        (recording, shas.join(", ")),
        (noise_cm_s, 0.0),
        [noise_cm_s / 100.0; 3],
    )
    .of_fixes()
    .with_spread(dives.len(), spreads(&vehicle.names, &vehicle.between));
    // The clock saved is the dives' mean: the sum of clock and latency where any is.
    match carried.iter().any(FixFit::clock_is_the_sum) {
        true => file.with_time_offset_including_fix_latency(),
        false => file,
    }
}
