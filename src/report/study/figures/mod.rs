//! The study's figures, drawn from its tables with the kit's drawing pieces, as a
//! paper run's are: the calibration × scored [`matrix`] of each method, held-out RMSE
//! against the window and the seconds of the clock ([`windows`]), one trajectory's
//! [`residual`] before and after, the first Kalman filter's terms against time
//! ([`kalman_terms`]), and with `[learned]` the held-out RMSE inside the folds; and a
//! sweep of studies' figure ([`sweep`]), held-out RMSE at each point, drawn from the
//! sweep's table. In: an [`StudyResults`], or a stored sweep of studies. Out:
//! the files written.

pub mod kalman_terms;
pub mod matrix;
pub mod residual;
pub mod sweep;
pub mod windows;

use crate::installation::study::rows::StudyResults;
use crate::report::kit::plots::canvas::Outcome;
use crate::report::kit::plots::draw::PlotResult;
use crate::report::kit::plots::{Format, PlotError, Written, render, write_figures};
use crate::results::study_sweep::StoredStudySweep;
use std::path::Path;

/// Draws the study's figures into `folder`, each file written atomically: the
/// calibration × scored matrix of each method, held-out RMSE against the window, and
/// one trajectory's residual before and after.
pub fn draw_all(
    study: &StudyResults,
    folder: &Path,
    format: Format,
) -> Result<Vec<Written>, PlotError> {
    render::register_font();
    let draw = || -> PlotResult<Vec<(String, Outcome)>> {
        let mut drawn = matrix::matrix(study)?;
        drawn.push(("installation_windows".into(), windows::windows(study)?));
        drawn.push(("installation_dive".into(), windows::dive(study)?));
        drawn.push(("installation_residual".into(), residual::residual(study)?));
        drawn.push((
            "installation_kalman_terms".into(),
            kalman_terms::kalman_terms(study)?,
        ));
        if !study.folds.is_empty() {
            drawn.push(("installation_folds".into(), windows::folds(study)?));
        }
        Ok(drawn)
    };
    let drawn = draw().map_err(|source| PlotError::Draw {
        what: "installation study's",
        source,
    })?;
    write_figures(drawn, folder, format)
}

/// Draws the figure of a sweep of studies into `folder` (each point's own figures are
/// drawn from the point's folder by [`draw_all`]).
pub fn draw_sweep(
    stored: &StoredStudySweep,
    folder: &Path,
    format: Format,
) -> Result<Vec<Written>, PlotError> {
    render::register_font();
    let drawn = sweep::sweep(stored)
        .map(|outcome| vec![("installation_sweep".to_string(), outcome)])
        .map_err(|source| PlotError::Draw {
            what: "sweep of installation studies'",
            source,
        })?;
    write_figures(drawn, folder, format)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::installation::study::method::Method;
    use crate::installation::study::rows::{
        FilterPoint, NO_CALIBRATION, SummaryRow, TermRow, TracePoint, TransferRow,
    };

    /// A deterministic jitter in -1..1 from `seed`.
    fn jitter(seed: u64) -> f64 {
        let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03;
        x ^= x >> 31;
        x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x ^= x >> 27;
        (x % 20_001) as f64 / 10_000.0 - 1.0
    }

    /// A study resembling the A-KIT one: 13 trajectories, three windows, no
    /// calibration, least squares EM1 to EM5 and two installation models.
    pub(crate) fn akit_like() -> StudyResults {
        let none = [
            20.0, 13.4, 11.8, 23.1, 13.3, 10.9, 11.3, 24.2, 24.4, 14.5, 22.9, 2.9, 3.1,
        ];
        let ratio = [
            0.33, 0.337, 0.33, 0.34, 0.529, 0.473, 0.332, 0.342, 0.313, 0.343, 0.421, 0.505, 0.549,
        ];
        let names: Vec<String> = (1..=13).map(|i| format!("T{i}")).collect();
        let mut methods: Vec<String> = vec![NO_CALIBRATION.into()];
        methods.extend((1..=5).map(|k| format!("least squares EM{k}")));
        methods.extend([
            "installation lever+offset".to_string(),
            "installation lever+offset+bias".to_string(),
        ]);
        let windows = [100.0, 200.0, 400.0];
        let mut heldout = Vec::new();
        let mut seed = 0;
        for &window_s in &windows {
            for (c, calibration) in names.iter().enumerate() {
                for (m, method) in methods.iter().enumerate() {
                    for (s, scored) in names.iter().enumerate() {
                        if s == c {
                            continue;
                        }
                        seed += 1;
                        let factor = match m {
                            0 => 1.0,
                            1..=5 => 1.0 + 0.02 * m as f64 + 0.05 * jitter(seed),
                            _ => {
                                let short = 400.0 / window_s;
                                (ratio[c] * (1.0 + 0.1 * (short - 1.0)) - 0.01 * (m - 6) as f64)
                                    * (1.0 + 0.3 * jitter(seed))
                            }
                        };
                        let total = none[s] * factor;
                        let share = [0.37, 0.82, 0.33];
                        let norm = share.iter().map(|v: &f64| v * v).sum::<f64>().sqrt();
                        heldout.push(TransferRow {
                            method: method.clone(),
                            calibration: calibration.clone(),
                            window_s,
                            scored: scored.clone(),
                            rmse_cm_s: share.map(|v| v / norm * total),
                            total_cm_s: total,
                            drift_rms_pct: f64::NAN,
                            drift_end_pct: f64::NAN,
                        });
                    }
                }
            }
        }
        let mut summary = Vec::new();
        for &window_s in &windows {
            let per_calibration = |method: &str| -> Vec<f64> {
                names
                    .iter()
                    .map(|c| {
                        let scores: Vec<f64> = heldout
                            .iter()
                            .filter(|r| {
                                r.method == method && r.window_s == window_s && r.calibration == *c
                            })
                            .map(|r| r.total_cm_s)
                            .collect();
                        scores.iter().sum::<f64>() / scores.len() as f64
                    })
                    .collect()
            };
            let (reference, _) = crate::evaluate::mean_ci95(&per_calibration(NO_CALIBRATION));
            for method in &methods {
                let (mean, ci) = crate::evaluate::mean_ci95(&per_calibration(method));
                summary.push(SummaryRow {
                    method: method.clone(),
                    window_s,
                    mean_cm_s: mean,
                    ci95_cm_s: ci,
                    ratio: mean / reference,
                    calibrations: 13,
                });
            }
        }
        // The clock found again from the first 30, 60 and 120 s of each trajectory, and
        // a joint fit's.
        for (k, dive_s) in [30.0, 60.0, 120.0].into_iter().enumerate() {
            for (method, mean) in [
                (NO_CALIBRATION, 14.0),
                ("installation lever+offset+bias", 4.1),
                ("installation lever+offset+bias, joint", 3.5),
            ] {
                summary.push(SummaryRow {
                    method: Method::parse(method).refound(dive_s).to_string(),
                    window_s: 400.0,
                    mean_cm_s: mean * (1.0 - 0.02 * k as f64),
                    ci95_cm_s: 0.6,
                    ratio: mean / 15.0,
                    calibrations: 13,
                });
            }
        }
        let mut terms = Vec::new();
        for &window_s in &windows {
            for method in &methods[6..] {
                for (c, calibration) in names.iter().enumerate() {
                    let straight = c >= 11;
                    let cluster_b = [4, 5, 10, 11].contains(&c);
                    seed += 1;
                    let mut push = |term: &str, value: f64, std: f64, unseen: &str| {
                        terms.push(TermRow {
                            method: method.clone(),
                            calibration: calibration.clone(),
                            window_s,
                            term: term.into(),
                            value,
                            std,
                            bound_std: std,
                            unseen: unseen.into(),
                            asked: String::new(),
                            between_dives_std: f64::NAN,
                            next_dive_low: f64::NAN,
                            next_dive_high: f64::NAN,
                        })
                    };
                    let lever_std = if straight { 0.36 } else { 0.013 };
                    let why = if straight {
                        "standard deviation 0.36 m, beyond 0.1 m"
                    } else {
                        ""
                    };
                    push("lever_arm_x_m", -1.9 + 0.08 * jitter(seed), lever_std, why);
                    push(
                        "lever_arm_y_m",
                        -0.03 + 0.03 * jitter(seed + 1),
                        lever_std,
                        why,
                    );
                    push("lever_arm_z_m", 0.5 + 0.3 * jitter(seed + 2), 0.06, "");
                    let tau = if cluster_b { 0.58 } else { 1.46 };
                    push("time_offset_s", tau + 0.03 * jitter(seed + 3), 0.009, "");
                    if method.ends_with("bias") {
                        for (axis, b) in ["x", "y", "z"].iter().zip([0.005, 0.006, -0.003]) {
                            push(
                                &format!("bias_{axis}_m_s"),
                                b + 0.002 * jitter(seed + 4),
                                0.001,
                                "",
                            );
                        }
                    }
                }
            }
        }
        let trace = (0..399u32)
            .map(|i| {
                let time_s = f64::from(i) * 400.0 / 399.0;
                let turn = (time_s / 40.0 * std::f64::consts::TAU).sin();
                let yaw_rate_deg_s = 15.0 * turn.powi(3);
                let noise = |k: u64| 1.5 * jitter(10_000 + 3 * i as u64 + k);
                TracePoint {
                    trajectory: "T1".into(),
                    method: "installation lever+offset+bias".into(),
                    calibration: "T2".into(),
                    time_s,
                    before_cm_s: [
                        3.0 * turn.abs() + noise(0),
                        -1.64 * yaw_rate_deg_s.to_radians() * 100.0 + noise(1),
                        1.0 + noise(2),
                    ],
                    after_cm_s: [noise(0), 0.5 * noise(1), noise(2)],
                    yaw_rate_deg_s,
                }
            })
            .collect();
        StudyResults {
            heldout,
            terms,
            summary,
            trace,
            failures: Vec::new(),
            folds: Vec::new(),
            // A filter settling on T1 (well seen) and T2 (poorly seen).
            filtered: ["T1", "T2"]
                .into_iter()
                .flat_map(|calibration| {
                    let spread = if calibration == "T1" { 0.05 } else { 0.5 };
                    (1..=100).flat_map(move |i| {
                        let t = f64::from(i);
                        [
                            ("lever_arm_x_m", -1.9, spread),
                            ("time_offset_s", 1.2, 0.02),
                        ]
                        .map(|(term, value, scale)| FilterPoint {
                            method: "Kalman filter lever+offset".into(),
                            calibration: calibration.into(),
                            time_s: t,
                            term: term.into(),
                            value: value + scale * (t / 7.0).sin() / t.sqrt(),
                            std: scale / t.sqrt(),
                            bound_std: 0.8 * scale / t.sqrt(),
                        })
                    })
                })
                .collect(),
            calibration_time: Vec::new(),
            recordings: Vec::new(),
        }
    }

    #[test]
    fn the_figures_of_a_study_are_written_with_their_captions() {
        // Set DCNET_INSTALLATION_FIGURES to a folder to keep the figures and look at them.
        let kept = std::env::var_os("DCNET_INSTALLATION_FIGURES").map(std::path::PathBuf::from);
        let temporary = tempfile::tempdir().unwrap();
        let folder = kept.as_deref().unwrap_or(temporary.path());
        let written = draw_all(&akit_like(), folder, Format::Png).unwrap();
        let stems: Vec<&str> = written.iter().map(|w| w.stem.as_str()).collect();
        assert_eq!(
            stems,
            [
                "installation_matrix_no_calibration",
                "installation_matrix_least_squares_em1",
                "installation_matrix_least_squares_em2",
                "installation_matrix_least_squares_em3",
                "installation_matrix_least_squares_em4",
                "installation_matrix_least_squares_em5",
                "installation_matrix_installation_lever_offset",
                "installation_matrix_installation_lever_offset_bias",
                "installation_windows",
                "installation_dive",
                "installation_residual",
                "installation_kalman_terms",
            ]
        );
        for figure in &written {
            assert!(
                matches!(figure.caption, crate::report::kit::plots::Caption::Drawn(_)),
                "{figure:?}"
            );
            assert_eq!(figure.files.len(), 1);
            assert!(figure.files[0].is_file());
        }
        let empty = StudyResults::default();
        let written = draw_all(&empty, temporary.path(), Format::Png).unwrap();
        assert!(written.iter().all(|w| w.files.is_empty()), "{written:?}");
        assert_eq!(crate::report::study::markdown(&empty).lines().count(), 4);
    }
}
