//! `calibrate`: one recording of a DVL beside a reference with attitude. The fit of the
//! terms asked for prints them with their standard deviations and the terms the
//! recording cannot show; the Kalman filter over the same samples says how much of the
//! recording its terms needed ([`crate::installation::settling`]); the recording is
//! written corrected. In: the parsed arguments. Out: what is printed, the corrected
//! recording and the filter's terms against time.

use super::{CliError, failure, input};
use crate::data::paired::{self, PairedColumns, PairedFiles};
use crate::installation::bound::{Noise, TermBound, bound};
use crate::installation::filter::{FilterSettings, run_filter};
use crate::installation::fit::{Fit, TIME_OFFSET_MARGIN_S, fit};
use crate::installation::frames::Reference;
use crate::installation::protocol_filters::FilterRun;
use crate::installation::settling::{SettlingPoint, settling_curve, settling_time};
use crate::installation::spec::{ObservabilityFile, default_filter_settings};
use crate::installation::term_names::{TermName, term_list_faults, term_set};
use crate::installation::terms::{AxisRmse, Installation, TermSet, score};
use crate::report::installation::readable_term;
use crate::report::installation::readable_why;
use crate::spec::TomlFile;
use comfy_table::{Table, presets::ASCII_MARKDOWN};
use std::path::Path;

/// What `calibrate` is asked.
pub(super) struct CalibrateArgs<'a> {
    pub dvl: &'a Path,
    pub reference: Option<&'a Path>,
    pub columns: Option<&'a Path>,
    pub terms: &'a [TermName],
    pub window_s: Option<f64>,
    pub dvl_noise_cm_s: f64,
    pub reference_noise_cm_s: f64,
    /// How close to its value after every sample the filter's RMSE must stay, %.
    pub tolerance_pct: f64,
    pub out: &'a Path,
}

/// The columns of `path`'s `[columns]` table, or A-KIT's.
fn columns(path: Option<&Path>) -> Result<PairedColumns, CliError> {
    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct ColumnsFile {
        columns: PairedColumns,
    }
    match path {
        None => Ok(PairedColumns::akit()),
        Some(path) => TomlFile::<ColumnsFile>::read(path)
            .map(|file| file.value.columns)
            .map_err(|fault| input(anyhow::anyhow!("{fault}"))),
    }
}

/// The terms of a calibration with their standard deviations, the terms the window
/// cannot show and why, and the RMSE against the reference before and after.
fn printed_calibration(
    bound: &TermBound,
    fitted: &Fit,
    (scored, recorded): (usize, usize),
    before: Option<AxisRmse>,
    after: Option<AxisRmse>,
    noise: Noise,
) -> String {
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    table.set_header(["term", "estimate", "standard deviation", "seen"]);
    for (i, name) in bound.names.iter().enumerate() {
        let (readable, unit, factor) = readable_term(name);
        let seen = if bound.is_unseen(name) { "no" } else { "yes" };
        table.add_row([
            readable,
            format!("{:.4} {unit}", bound.value[i] * factor),
            format!("{:.4} {unit}", bound.std[i] * factor),
            seen.to_string(),
        ]);
    }
    let residual = fitted.residual_rms_m_s.map(|r| 100.0 * r);
    let assumed = 100.0 * (noise.dvl_m_s.powi(2) + noise.reference_m_s.powi(2)).sqrt();
    let mut text = format!(
        "calibrated on {} samples (those {TIME_OFFSET_MARGIN_S} s inside the reference)\n{table}\n",
        fitted.sample_count
    );
    text.push_str(&format!(
        "the standard deviations assume white noise of {assumed:.2} cm/s per axis; the fit leaves {:.2}, {:.2}, {:.2} cm/s (x, y, z): where the two differ, or the noise is not white, they are off by about as much\n",
        residual[0], residual[1], residual[2]
    ));
    for unseen in &bound.unseen {
        text.push_str(&format!(
            "not seen here: {}: {}\n",
            readable_term(unseen.term).0,
            readable_why(unseen.term, &unseen.why.to_string())
        ));
    }
    let rmse = |rmse: Option<AxisRmse>| match rmse {
        Some(r) => format!(
            "{:.2} cm/s (x {:.2}, y {:.2}, z {:.2})",
            100.0 * r.total_m_s,
            100.0 * r.x_m_s,
            100.0 * r.y_m_s,
            100.0 * r.z_m_s
        ),
        None => "no sample inside the reference".into(),
    };
    text.push_str(&format!(
        "RMSE against the reference, body frame, on the {scored} of {recorded} samples {TIME_OFFSET_MARGIN_S} s inside it: {} before, {} after",
        rmse(before),
        rmse(after)
    ));
    text
}

/// Why `args` cannot be taken, where it cannot: the first argument at fault, named.
fn refused(args: &CalibrateArgs) -> Option<String> {
    if let Some((_, message)) = term_list_faults(args.terms).first() {
        return Some(format!("--terms: {message}"));
    }
    if !(args.dvl_noise_cm_s.is_finite() && args.dvl_noise_cm_s > 0.0) {
        return Some(format!(
            "--dvl-noise-cm-s {}: give a positive number: the bound divides by it",
            args.dvl_noise_cm_s
        ));
    }
    if !(args.reference_noise_cm_s.is_finite() && args.reference_noise_cm_s >= 0.0) {
        return Some(format!(
            "--reference-noise-cm-s {}: give zero or a positive number",
            args.reference_noise_cm_s
        ));
    }
    if let Some(w) = args.window_s
        && !(w.is_finite() && w > 0.0)
    {
        return Some(format!("--window-s {w}: give a positive number of seconds"));
    }
    if !(args.tolerance_pct.is_finite() && args.tolerance_pct > 0.0) {
        return Some(format!(
            "--tolerance-pct {}: give a positive percentage",
            args.tolerance_pct
        ));
    }
    None
}

/// `calibrate`: the terms of one recording, their bound, how long the recording needed,
/// and the recording corrected.
pub(super) fn calibrate(args: &CalibrateArgs) -> Result<(), CliError> {
    if let Some(message) = refused(args) {
        return Err(input(anyhow::anyhow!(message)));
    }
    let files = PairedFiles {
        dvl: args.dvl.to_path_buf(),
        reference: args.reference.unwrap_or(args.dvl).to_path_buf(),
    };
    let recording = paired::read(&files, &columns(args.columns)?).map_err(input)?;
    let reference = Reference::new(&recording);
    let window = args.window_s.map(|w| recording.first_seconds(w));
    let calibrating = window.as_ref().unwrap_or(&recording);
    let terms = term_set(args.terms);
    let fitted = fit(
        &calibrating.time_s,
        &calibrating.dvl_m_s,
        &reference,
        terms,
    )
    .map_err(|error| {
        input(anyhow::anyhow!(
            "{}: calibrating {} on {} samples: {error}; a window too short for its terms, or terms it cannot tell apart (a scale and a bias at constant speed, say), fail this way: give a longer --window-s or fewer --terms",
            args.dvl.display(),
            args.terms.iter().map(|t| t.name()).collect::<Vec<_>>().join(", "),
            calibrating.time_s.len()
        ))
    })?;
    let tolerances = ObservabilityFile::default().tolerances();
    let noise = Noise {
        dvl_m_s: args.dvl_noise_cm_s / 100.0,
        reference_m_s: args.reference_noise_cm_s / 100.0,
    };
    let bounded = bound(&fitted, noise, &tolerances);
    let all = reference.interior(&recording.time_s, TIME_OFFSET_MARGIN_S);
    let all_samples = (all.len(), recording.time_s.len());
    let score_all = |installation: &Installation| {
        score(
            installation,
            &recording.time_s,
            &recording.dvl_m_s,
            &reference,
            all.clone(),
        )
    };
    let before = score_all(&Installation::default());
    let after = score_all(&fitted.installation);
    println!(
        "{}",
        printed_calibration(&bounded, &fitted, all_samples, before, after, noise)
    );
    let settings = default_filter();
    let filter = FilterRun {
        label: "Kalman filter".into(),
        terms,
        steps: run_filter(
            &calibrating.time_s,
            &calibrating.dvl_m_s,
            &reference,
            terms,
            &settings,
            noise,
        ),
    };
    let curve = settling_curve(&filter.steps, |installation| {
        score_all(installation).map_or(f64::NAN, |rmse| 100.0 * rmse.total_m_s)
    });
    println!(
        "\n{}",
        printed_settling(
            &curve,
            terms,
            &settings,
            args.tolerance_pct,
            args.window_s.is_some()
        )
    );
    let corrected = crate::results::corrected::corrected_samples(
        &fitted.installation,
        &recording.time_s,
        &recording.dvl_m_s,
        &reference,
    );
    let stem = args
        .dvl
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "recording".into());
    let written = crate::results::corrected::write(args.out, &stem, &corrected).map_err(failure)?;
    for path in written {
        eprintln!("corrected recording written to {}", path.display());
    }
    let points = filter.points(&stem);
    let path = crate::results::corrected::write_terms_in_time(args.out, &stem, &points)
        .map_err(failure)?;
    eprintln!(
        "the filter's terms against time written to {}",
        path.display()
    );
    Ok(())
}

/// The filter of an installation spec's `[calibration.kalman]` as it comes: wide priors
/// about zero, constant terms.
fn default_filter() -> FilterSettings {
    default_filter_settings()
}

/// The lengths the printed table shows: round ones below the recording's, the settling
/// time and the whole recording.
const SHOWN_LENGTHS_S: [f64; 9] = [5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0, 1000.0, 2000.0];

/// The filter's terms after a few lengths of the recording (of its first `window`
/// seconds where that was asked), each ± its standard deviation, and the RMSE they leave
/// on the whole recording; then how long the recording needed.
fn printed_settling(
    curve: &[SettlingPoint],
    terms: TermSet,
    settings: &FilterSettings,
    tolerance_pct: f64,
    window: bool,
) -> String {
    let Some(all) = curve.last() else {
        return "the Kalman filter took no sample: none lies inside the reference".into();
    };
    let settled = settling_time(curve, tolerance_pct / 100.0);
    let calibrated_on = if window { "window" } else { "all" };
    let mut shown: Vec<&SettlingPoint> = curve
        .iter()
        .filter(|p| {
            SHOWN_LENGTHS_S.contains(&p.length_s)
                || settled.is_some_and(|s| s.length_s == p.length_s)
        })
        .collect();
    if shown.last().is_none_or(|p| p.length_s != all.length_s) {
        shown.push(all);
    }
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    let mut header = vec!["after".to_string()];
    header.extend(shown.iter().map(|p| {
        if p.length_s == all.length_s {
            format!("{} s ({calibrated_on})", p.length_s)
        } else if settled.is_some_and(|s| s.length_s == p.length_s) {
            format!("{} s (settled)", p.length_s)
        } else {
            format!("{} s", p.length_s)
        }
    }));
    table.set_header(header);
    for (i, name) in terms.parameter_names().iter().enumerate() {
        let (readable, unit, factor) = readable_term(name);
        let mut row = vec![format!("{readable} ({unit})")];
        row.extend(shown.iter().map(|p| {
            let value = p.step.installation.to_parameters(&terms)[i];
            format!("{:.3} ± {:.3}", value * factor, p.step.std[i] * factor)
        }));
        table.add_row(row);
    }
    let mut rmse = vec!["RMSE on the recording (cm/s)".to_string()];
    rmse.extend(shown.iter().map(|p| format!("{:.2}", p.rmse_cm_s)));
    table.add_row(rmse);
    // Each prior once: the lever arm's three components share one.
    let mut prior: Vec<String> = Vec::new();
    for (&kind, name) in terms.parameter_kinds().iter().zip(terms.parameter_names()) {
        let (_, unit, factor) = readable_term(name);
        let std = format!("{} {unit}", settings.prior.of(kind) * factor);
        if !prior.contains(&std) {
            prior.push(std);
        }
    }
    let mut text = format!(
        "the Kalman filter over the same samples, its terms constant, starting at zero with standard deviations {}; its terms after each length, ± its standard deviation:\n{table}\n",
        prior.join(", ")
    );
    let of = if window {
        "of the window"
    } else {
        "of the recording"
    };
    text.push_str(&match settled {
        Some(point) => format!(
            "after {} s the filter's terms leave an RMSE on the whole recording within {tolerance_pct} % of the {:.2} cm/s they leave after all {} s {of}, and stay there: more of it moves the RMSE by less than {tolerance_pct} %, though a term whose ± is still wide then is not pinned down (scored on this recording, not on another dive)",
            point.length_s, all.rmse_cm_s, all.length_s
        ),
        None => format!(
            "the filter's terms after all {} s {of} leave no finite RMSE on the recording: the filter diverged",
            all.length_s
        ),
    });
    text
}
