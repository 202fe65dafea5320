//! The summaries of a study's held-out rows: per method and window, the mean over
//! calibration trajectories of each one's mean held-out RMSE, its 95 % interval and its
//! ratio to no calibration's; with `[learned]`, the same on the pairs inside each fold
//! and inside any, every method on the same pairs. In: the held-out rows, the windows,
//! the folds. Out: [`SummaryRow`]s and [`FoldSummaryRow`]s.

use crate::evaluate::statistics::{mean_ci95, mean_std};
use crate::installation::study::rows::{FoldSummaryRow, NO_CALIBRATION, SummaryRow, TransferRow};

/// [`summarize`] on the pairs whose calibration and scored trajectories share a fold,
/// and at each window only those every method scored there (a fit that failed, or a
/// window too short for a network, leaves the pair out for every method): fold by fold
/// ("1", "2", …), then over every fold ("all"), every method on the same pairs.
pub fn summarize_folds(
    heldout: &[TransferRow],
    windows_s: &[f64],
    folds: usize,
    fold_of: impl Fn(&str) -> usize,
) -> Vec<FoldSummaryRow> {
    let mut inside = Vec::new();
    for &window_s in windows_s {
        let rows: Vec<&TransferRow> = heldout
            .iter()
            .filter(|r| r.window_s == window_s && fold_of(&r.calibration) == fold_of(&r.scored))
            .collect();
        let methods = crate::first_seen(rows.iter().map(|r| r.method.as_str()));
        let pairs = |method: &str| -> Vec<(&str, &str)> {
            rows.iter()
                .filter(|r| r.method == method)
                .map(|r| (r.calibration.as_str(), r.scored.as_str()))
                .collect()
        };
        let every: Vec<Vec<(&str, &str)>> = methods.iter().map(|m| pairs(m)).collect();
        inside.extend(
            rows.iter()
                .filter(|r| {
                    let pair = (r.calibration.as_str(), r.scored.as_str());
                    every.iter().all(|p| p.contains(&pair))
                })
                .map(|r| (*r).clone()),
        );
    }
    let mut rows = Vec::new();
    for fold in 0..folds {
        let of_fold: Vec<TransferRow> = inside
            .iter()
            .filter(|r| fold_of(&r.calibration) == fold)
            .cloned()
            .collect();
        rows.extend(
            summarize(&of_fold, windows_s)
                .into_iter()
                .map(|summary| FoldSummaryRow {
                    fold: (fold + 1).to_string(),
                    summary,
                }),
        );
    }
    rows.extend(
        summarize(&inside, windows_s)
            .into_iter()
            .map(|summary| FoldSummaryRow {
                fold: "all".to_string(),
                summary,
            }),
    );
    rows
}

/// Per method and window: the mean over calibration trajectories of each one's mean
/// held-out RMSE, its 95 % interval, and its ratio to no calibration's.
pub fn summarize(heldout: &[TransferRow], windows_s: &[f64]) -> Vec<SummaryRow> {
    let methods = crate::first_seen(heldout.iter().map(|r| r.method.as_str()));
    let per_calibration = |method: &str, window_s: f64| -> Vec<f64> {
        let calibrations = crate::first_seen(
            heldout
                .iter()
                .filter(|r| r.method == method && r.window_s == window_s)
                .map(|r| r.calibration.as_str()),
        );
        calibrations
            .iter()
            .map(|c| {
                let scores: Vec<f64> = heldout
                    .iter()
                    .filter(|r| r.method == method && r.window_s == window_s && r.calibration == *c)
                    .map(|r| r.total_cm_s)
                    .collect();
                scores.iter().sum::<f64>() / scores.len() as f64
            })
            .collect()
    };
    let mut rows = Vec::new();
    for &window_s in windows_s {
        let (none, _) = mean_std(per_calibration(NO_CALIBRATION, window_s).into_iter());
        for method in &methods {
            let values = per_calibration(method, window_s);
            if values.is_empty() {
                continue;
            }
            // One calibration trajectory bounds nothing: its interval is unbounded.
            let (mean, ci95) = match values.len() {
                1 => (values[0], f64::INFINITY),
                _ => mean_ci95(&values),
            };
            rows.push(SummaryRow {
                method: method.to_string(),
                window_s,
                mean_cm_s: mean,
                ci95_cm_s: ci95,
                ratio: mean / none,
                calibrations: values.len(),
            });
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(method: &str, calibration: &str, scored: &str, total_cm_s: f64) -> TransferRow {
        TransferRow {
            method: method.into(),
            calibration: calibration.into(),
            window_s: 100.0,
            scored: scored.into(),
            rmse_cm_s: [total_cm_s, 0.0, 0.0],
            total_cm_s,

            drift_rms_pct: f64::NAN,
            drift_end_pct: f64::NAN,
        }
    }

    /// Inside the folds, every method is averaged over the same pairs: those inside a
    /// fold that every method scored.
    #[test]
    fn the_fold_summary_keeps_the_pairs_inside_a_fold_that_every_method_scored() {
        // Folds: A, C | B, D. The fit failed on C → A; the cross-fold pairs are out.
        let heldout = vec![
            row(NO_CALIBRATION, "A", "C", 10.0),
            row(NO_CALIBRATION, "C", "A", 20.0),
            row(NO_CALIBRATION, "A", "B", 99.0),
            row(NO_CALIBRATION, "B", "D", 12.0),
            row(NO_CALIBRATION, "D", "B", 14.0),
            row("fit", "A", "C", 4.0),
            row("fit", "A", "B", 99.0),
            row("fit", "B", "D", 6.0),
            row("fit", "D", "B", 8.0),
            row("learned", "A", "C", 5.0),
            row("learned", "C", "A", 7.0),
            row("learned", "B", "D", 3.0),
            row("learned", "D", "B", 5.0),
        ];
        let fold_of = |name: &str| usize::from(name == "B" || name == "D");
        let rows = summarize_folds(&heldout, &[100.0], 2, fold_of);
        let mean = |fold: &str, method: &str| {
            let r = rows
                .iter()
                .find(|r| r.fold == fold && r.summary.method == method)
                .unwrap();
            (r.summary.mean_cm_s, r.summary.calibrations)
        };
        // Fold 1 keeps only A → C; fold 2 both pairs.
        assert_eq!(mean("1", NO_CALIBRATION), (10.0, 1));
        assert_eq!(mean("1", "learned"), (5.0, 1));
        assert_eq!(mean("2", "fit"), (7.0, 2));
        // Over all folds: A 5, B 3, D 5.
        assert_eq!(mean("all", "learned"), ((5.0 + 3.0 + 5.0) / 3.0, 3));
        assert_eq!(mean("all", NO_CALIBRATION), (12.0, 3));
    }
}
