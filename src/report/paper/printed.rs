//! The tables a paper run prints at its end, in the paper's layout: error models
//! across, DVLs and estimators down, `mean ± std (T_conv)` cells. In: a run's
//! calibration and evaluation rows. Out: text.

use crate::evaluate::{CalibrationRow, EvaluationRow};
use crate::first_seen;
use crate::vocab::ErrorModel;
use comfy_table::{Table, presets::ASCII_MARKDOWN};

/// Calibration at T_conv: one row per DVL and estimator, one column per error model
/// (the first column holds the estimators that take none: the baseline and the floor).
pub fn calibration_table(
    rows: &[CalibrationRow],
    calibration_trajectory: &str,
    runs: usize,
) -> String {
    let models = models_in(rows.iter().map(|r| r.error_model));
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    let mut header = vec![
        "DVL".to_string(),
        "estimator".to_string(),
        "no error model".to_string(),
    ];
    header.extend(models.iter().map(ToString::to_string));
    table.set_header(header);
    let keys = first_seen(
        rows.iter()
            .filter(|r| r.is_t_conv)
            .map(|r| (r.dvl.as_str(), r.estimator)),
    );
    for (dvl, estimator) in keys {
        let mut cells = vec![dvl.to_string(), estimator.label().to_string()];
        for model in std::iter::once(None).chain(models.iter().copied().map(Some)) {
            let cell = rows
                .iter()
                .find(|r| {
                    r.is_t_conv
                        && r.dvl == dvl
                        && r.estimator == estimator
                        && r.error_model == model
                })
                .map(|r| {
                    format!(
                        "{:.2} ± {:.2} ({})",
                        r.rmse_cm_s, r.rmse_std_cm_s, r.window_s
                    )
                })
                .unwrap_or_default();
            cells.push(cell);
        }
        table.add_row(cells);
    }
    format!(
        "Calibration on {calibration_trajectory}: RMSE in cm/s at T_conv, mean ± std over {runs} runs (T_conv in s)\n{table}\n"
    )
}

/// Evaluation with the T_conv terms: one row per DVL, estimator and error model, one
/// column per test trajectory, with the improvement over the baseline.
pub fn evaluation_table(rows: &[EvaluationRow]) -> String {
    let trajectories = first_seen(rows.iter().map(|r| r.trajectory.as_str()));
    let keys = first_seen(
        rows.iter()
            .map(|r| (r.dvl.as_str(), r.estimator, r.error_model)),
    );
    let mut table = Table::new();
    table.load_preset(ASCII_MARKDOWN);
    let mut header = vec![
        "DVL".to_string(),
        "estimator".to_string(),
        "EM".to_string(),
        "T_conv s".to_string(),
    ];
    header.extend(trajectories.iter().map(ToString::to_string));
    table.set_header(header);
    for (dvl, estimator, model) in keys {
        let matching: Vec<&EvaluationRow> = rows
            .iter()
            .filter(|r| r.dvl == dvl && r.estimator == estimator && r.error_model == model)
            .collect();
        let mut cells = vec![
            dvl.to_string(),
            estimator.label().to_string(),
            model.map(|m| m.to_string()).unwrap_or_else(|| "-".into()),
            matching
                .first()
                .map(|r| r.t_conv_s.to_string())
                .unwrap_or_default(),
        ];
        for trajectory in &trajectories {
            let cell = matching
                .iter()
                .find(|r| r.trajectory == *trajectory)
                .map(|r| match r.improvement_pct {
                    Some(pct) if r.estimator != crate::vocab::EstimatorKind::Baseline => {
                        format!("{:.2} ± {:.2} ({pct:+.0} %)", r.rmse_cm_s, r.rmse_std_cm_s)
                    }
                    _ => format!("{:.2} ± {:.2}", r.rmse_cm_s, r.rmse_std_cm_s),
                })
                .unwrap_or_default();
            cells.push(cell);
        }
        table.add_row(cells);
    }
    format!(
        "Evaluation: RMSE in cm/s with the T_conv terms, mean ± std (improvement over the baseline)\n{table}\n"
    )
}

/// The error models among `models`, in order.
pub(crate) fn models_in(models: impl Iterator<Item = Option<ErrorModel>>) -> Vec<ErrorModel> {
    let mut found: Vec<ErrorModel> = models.flatten().collect();
    found.sort();
    found.dedup();
    found
}
