//! Checks `[calibration]`. In: the calibration windows, the paper's methods by name,
//! the named term sets of `[[calibration.models]]`, `[calibration.kalman]` and the
//! calibration time's tolerance, as written. Out: the windows in increasing order, the
//! methods in the order the tables show them (the paper's, then each term set's fit,
//! then its Kalman filter), whether "dcnet" is listed, the filter's settings and the
//! tolerance as a fraction.

use crate::data::fixes::FixSimulation;
use crate::installation::estimate::clock::ClockSearch;
use crate::installation::estimate::filter::FilterSettings;
use crate::installation::study::spec::DiveSpec;
use crate::installation::study::spec::Model;
use crate::installation::study::spec::check::check_terms;
use crate::installation::study::spec::check::kalman::check_kalman;
use crate::installation::study::spec::file::{
    DiveFile, FixesFile, StudyCalibrationFile, TermSetFile,
};
use crate::installation::terms::names::{TermName, term_set};
use crate::spec::check::Faults;
use crate::vocab::ErrorModel;
use std::collections::HashSet;

/// `[calibration]`, checked.
pub(in crate::installation::study::spec) struct CheckedCalibration {
    /// In increasing order.
    pub windows_s: Vec<f64>,
    /// The paper's methods, then the fit of each term set, then their filters; DCNet's
    /// come after, from `[dcnet]`.
    pub methods: Vec<Model>,
    /// Whether "dcnet" is among the methods.
    pub wants_dcnet: bool,
    pub filter: FilterSettings,
    /// A fraction (0.1 for 10 %).
    pub time_tolerance: f64,
    pub dive: Option<DiveSpec>,
}

/// Checks `[calibration]`: windows, methods, models and the filter's table.
pub(in crate::installation::study::spec) fn check_calibration(
    calibration: StudyCalibrationFile,
    faults: &mut Faults,
) -> CheckedCalibration {
    let StudyCalibrationFile {
        window_s,
        methods: names,
        models,
        kalman,
        time_tolerance_pct,
        dive,
        fixes,
    } = calibration;
    let windows_s = check_windows("calibration.window_s", &window_s, faults);
    let (mut methods, wants_dcnet) = check_methods(&names, faults);
    check_models(&models, faults);
    methods.extend(models.iter().map(|model| Model::Installation {
        name: model.name.clone(),
        terms: model.terms.clone(),
    }));
    let model_names: Vec<&str> = models.iter().map(|m| m.name.as_str()).collect();
    let filtered = kalman.models.clone();
    let filter = check_kalman(kalman, &model_names, faults);
    for name in &filtered {
        if let Some(model) = models.iter().find(|m| &m.name == name) {
            methods.push(Model::Filter {
                name: model.name.clone(),
                terms: model.terms.clone(),
            });
        }
    }
    if let Some(fixes) = fixes {
        methods.push(check_fixes(fixes, faults));
    }
    if !(time_tolerance_pct.is_finite() && time_tolerance_pct > 0.0) {
        faults.add(
            "calibration.time_tolerance_pct",
            format!("{time_tolerance_pct} must be a finite number above zero"),
        );
    }
    CheckedCalibration {
        windows_s,
        methods,
        wants_dcnet,
        filter,
        time_tolerance: time_tolerance_pct / 100.0,
        dive: dive.map(|dive| check_dive(dive, faults)),
    }
}

/// `[calibration.fixes]`: an interval and a noise above zero, a share of outliers in
/// [0, 1) and their distance zero or more.
fn check_fixes(fixes: FixesFile, faults: &mut Faults) -> Model {
    let FixesFile {
        interval_s,
        noise_m,
        outlier_share,
        outlier_m,
        seed,
    } = fixes;
    let positive = |v: f64| v.is_finite() && v > 0.0;
    if !positive(interval_s) {
        faults.add(
            "calibration.fixes.interval_s",
            format!("{interval_s} must be a number of seconds above zero"),
        );
    }
    if !positive(noise_m) {
        faults.add(
            "calibration.fixes.noise_m",
            format!(
                "{noise_m} must be a number of metres above zero: the fit weighs the fixes by it"
            ),
        );
    }
    if !(0.0..1.0).contains(&outlier_share) {
        faults.add(
            "calibration.fixes.outlier_share",
            format!("{outlier_share} must be a share of the fixes, at least 0 and below 1"),
        );
    }
    if !(outlier_m.is_finite() && outlier_m >= 0.0) {
        faults.add(
            "calibration.fixes.outlier_m",
            format!("{outlier_m} must be a number of metres, zero or more"),
        );
    }
    Model::Fixes {
        simulation: FixSimulation {
            interval_s,
            noise_m,
            outlier_share,
            outlier_m,
        },
        seed,
    }
}

/// `[calibration.dive]`: the time offset among its terms, the rest a bias; its windows
/// as the calibration's; a search range above zero and within an hour.
fn check_dive(dive: DiveFile, faults: &mut Faults) -> DiveSpec {
    let DiveFile {
        terms,
        window_s,
        search_s,
    } = dive;
    check_terms("calibration.dive.terms", &terms, faults);
    if !terms.contains(&TermName::TimeOffset) {
        faults.add(
            "calibration.dive.terms",
            "must hold \"time_offset\": the clock is what a dive sets again",
        );
    }
    for (j, term) in terms.iter().enumerate() {
        if !term.may_be_the_dives() {
            faults.add(
                format!("calibration.dive.terms[{j}]"),
                format!("{:?} belongs to the vehicle, not the dive: a dive's terms are \"time_offset\", and \"bias\" or \"bias_scalar\"", term.name()),
            );
        }
    }
    let windows_s = check_windows("calibration.dive.window_s", &window_s, faults);
    if !(search_s.is_finite() && search_s > 0.0 && search_s <= 3600.0) {
        faults.add(
            "calibration.dive.search_s",
            format!("{search_s} must be a number of seconds above zero and at most 3600"),
        );
    }
    DiveSpec {
        search: ClockSearch {
            dive_terms: term_set(&terms),
            search_s,
        },
        windows_s,
    }
}

/// A list of windows at `key`: at least one, each finite, positive and listed once; in
/// increasing order.
fn check_windows(key: &str, window_s: &[f64], faults: &mut Faults) -> Vec<f64> {
    if window_s.is_empty() {
        faults.add(key, "is empty: give at least one window, in seconds (one at least a trajectory's length takes all of it)");
    }
    let mut windows_s = Vec::new();
    for (i, &w) in window_s.iter().enumerate() {
        if !(w.is_finite() && w > 0.0) {
            faults.add(
                format!("{key}[{i}]"),
                format!("{w} must be a finite positive number of seconds"),
            );
        } else if windows_s.contains(&w) {
            faults.add(format!("{key}[{i}]"), format!("{w} is listed twice"));
        } else {
            windows_s.push(w);
        }
    }
    windows_s.sort_by(f64::total_cmp);
    windows_s
}

/// `calibration.methods`: the paper's methods, each listed once, and whether "dcnet"
/// is among them.
fn check_methods(names: &[String], faults: &mut Faults) -> (Vec<Model>, bool) {
    let mut methods = Vec::new();
    let mut listed = HashSet::new();
    let mut wants_dcnet = false;
    for (i, method) in names.iter().enumerate() {
        let key = format!("calibration.methods[{i}]");
        if !listed.insert(method.as_str()) {
            faults.add(key, format!("{method:?} is listed twice"));
            continue;
        }
        match method.as_str() {
            "baseline" => methods.push(Model::Baseline),
            "dcnet" => wants_dcnet = true,
            other => match other.parse::<ErrorModel>() {
                Ok(model) => methods.push(Model::LeastSquares(model)),
                Err(_) => faults.add(
                    key,
                    format!(
                        "{other:?} is not a method: give \"baseline\", \"EM1\" to \"EM5\" (the paper's least squares) or \"dcnet\"; term sets of the installation model go in [[calibration.models]]"
                    ),
                ),
            },
        }
    }
    (methods, wants_dcnet)
}

/// `[[calibration.models]]`: each name defined once, each list of terms sound.
fn check_models(models: &[TermSetFile], faults: &mut Faults) {
    let mut names = HashSet::new();
    for (i, model) in models.iter().enumerate() {
        let TermSetFile { name, terms } = model;
        let key = format!("calibration.models[{i}]");
        if !names.insert(name.as_str()) {
            faults.add(format!("{key}.name"), format!("{name:?} is defined twice"));
        }
        check_terms(&format!("{key}.terms"), terms, faults);
    }
}
