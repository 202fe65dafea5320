//! The paragraph after each terms table: where one installation model's estimates of a
//! term agree across the calibration trajectories within the bound's 95 % intervals,
//! where they do not, and where a term is not seen. In: the study's term rows of one
//! method. Out: the paragraph's text.

use crate::installation::study::rows::TermRow;
use crate::report::kit::numbers::decimals;
use crate::report::kit::readable::readable_term;

/// The z-value of a two-sided 95 % interval: estimates agree across calibration
/// trajectories when their spread is at most this many times the median bound.
const AGREEMENT_Z: f64 = 1.96;

/// One term's estimates across the calibration trajectories that see it.
#[derive(Debug, Clone, PartialEq)]
struct Agreement {
    name: String,
    unit: &'static str,
    /// How many calibration trajectories see it.
    seen: usize,
    /// The sample standard deviation of their estimates, in the readable unit.
    spread: f64,
    /// The median of their standard deviations.
    median_std: f64,
}

impl Agreement {
    fn of(term: &str, rows: &[&TermRow]) -> Agreement {
        let (name, unit, factor) = readable_term(term);
        let seen: Vec<&&TermRow> = rows
            .iter()
            .filter(|r| r.term == term && r.unseen.is_empty())
            .collect();
        let values: Vec<f64> = seen.iter().map(|r| factor * r.value).collect();
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let spread = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let mut stds: Vec<f64> = seen.iter().map(|r| factor * r.std).collect();
        stds.sort_by(f64::total_cmp);
        let median_std = match stds.len() {
            0 => f64::NAN,
            k if k % 2 == 1 => stds[k / 2],
            k => 0.5 * (stds[k / 2 - 1] + stds[k / 2]),
        };
        Agreement {
            name,
            unit,
            seen: values.len(),
            spread,
            median_std,
        }
    }

    fn agrees(&self) -> bool {
        self.spread <= AGREEMENT_Z * self.median_std
    }

    /// `lever arm x (spread 0.080 m, 8.0 × the median σ of 0.010 m, 11 trajectories)`.
    fn text(&self) -> String {
        let decimals = decimals(self.median_std);
        let unit = |value: f64| {
            if self.unit.is_empty() {
                format!("{value:.decimals$}")
            } else {
                format!("{value:.decimals$} {}", self.unit)
            }
        };
        format!(
            "{} (spread {}, {:.1} × the median σ of {}, {} trajectories)",
            self.name,
            unit(self.spread),
            self.spread / self.median_std,
            unit(self.median_std),
            self.seen
        )
    }
}

/// (d): which terms' estimates agree across the calibration trajectories within the
/// bound's 95 % intervals, which do not, and where terms are not seen.
pub(super) fn agreement(method: &str, rows: &[&TermRow]) -> String {
    let terms = crate::first_seen(rows.iter().map(|r| r.term.as_str()));
    let calibrations = crate::first_seen(rows.iter().map(|r| r.calibration.as_str()));
    let all: Vec<Agreement> = terms.iter().map(|t| Agreement::of(t, rows)).collect();
    let list = |items: Vec<String>| items.join(", ");
    let agree: Vec<String> = all
        .iter()
        .filter(|a| a.seen >= 2 && a.agrees())
        .map(Agreement::text)
        .collect();
    let disagree: Vec<String> = all
        .iter()
        .filter(|a| a.seen >= 2 && !a.agrees())
        .map(Agreement::text)
        .collect();
    let few: Vec<String> = all
        .iter()
        .filter(|a| a.seen < 2)
        .map(|a| a.name.clone())
        .collect();
    let mut text = format!(
        "Across the {} calibration trajectories, {method}'s estimates of a term agree within their intervals when the standard deviation of the estimates where the term is seen (the spread) is at most {AGREEMENT_Z} times the median of their standard deviations (σ, a fit's from the noise its residuals show, level and correlation in time, a Kalman filter's likewise, read as it runs).",
        calibrations.len()
    );
    text += &match agree.is_empty() {
        true => " No term's estimates agree.".to_string(),
        false => format!(" They agree for {}.", list(agree)),
    };
    if !disagree.is_empty() {
        text += &format!(" They do not for {}.", list(disagree));
    }
    if !few.is_empty() {
        text += &format!(
            " Seen on fewer than two trajectories, so not compared: {}.",
            list(few)
        );
    }
    let unseen: Vec<String> = terms
        .iter()
        .filter_map(|term| {
            let on: Vec<&str> = rows
                .iter()
                .filter(|r| r.term == *term && !r.unseen.is_empty())
                .map(|r| r.calibration.as_str())
                .collect();
            (!on.is_empty()).then(|| format!("{} on {}", readable_term(term).0, on.join(", ")))
        })
        .collect();
    if !unseen.is_empty() {
        text += &format!(" Not seen: {}.", unseen.join("; "));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::report::study::tests::small;

    #[test]
    fn the_paragraph_says_which_terms_agree_within_their_intervals() {
        let study = small();
        let rows: Vec<&TermRow> = study.terms.iter().collect();
        let lever = Agreement::of("lever_arm_x_m", &rows);
        // T1 and T2 only: spread of (-1.87, -1.89) is 0.01414, median σ 0.015.
        assert_eq!(lever.seen, 2);
        assert!((lever.spread - 0.02 / 2f64.sqrt()).abs() < 1e-12);
        assert!((lever.median_std - 0.015).abs() < 1e-12);
        assert!(lever.agrees());
        let paragraph = agreement("installation lever+offset", &rows);
        assert!(
            paragraph.contains(" They agree for lever arm x (spread 0.014 m, 0.9 × the median σ of 0.015 m, 2 trajectories)."),
            "{paragraph}"
        );
        assert!(
            paragraph.contains(" They do not for time offset (spread 0.524 s, 29.1 × the median σ of 0.018 s, 3 trajectories), bias y (spread 0.41 cm/s, 4.1 × the median σ of 0.10 cm/s, 3 trajectories)."),
            "{paragraph}"
        );
        assert!(
            paragraph.ends_with(" Not seen: lever arm x on T12."),
            "{paragraph}"
        );
    }
}
