//! Acceptance of a calibration, the way the vendors' procedures accept one: the DVL's
//! misalignment under a limit (2° by default), its scale within one of 1 (0.95–1.05),
//! and the dead reckoning with the terms applied within a share of the distance
//! travelled at the recording's end (0.1 %, marginal to 0.2 %). An estimate is a claim
//! with an interval, so a term passes where its whole 95 % interval lies within the
//! limit, fails where the whole interval lies beyond, and is marginal where the limit
//! falls inside it. A check the calibration cannot make (the term not estimated, no
//! positions to dead-reckon against) is said so, and the calibration is then not
//! accepted. In: `--accept`'s thresholds, and a calibration's terms and drift. Out: an
//! [`Acceptance`], each check with its verdict.

use crate::installation::dead_reckoning::Drift;
use crate::installation::estimate::bound::{ReadNoise, TermBound};

/// The limits a calibration is held to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thresholds {
    /// The misalignment's angle, degrees.
    pub misalignment_deg: f64,
    /// The scale's distance from 1, %.
    pub scale_pct: f64,
    /// The dead reckoning's end error, % of the distance travelled: within it a pass,
    /// within twice it marginal.
    pub drift_pct: f64,
}

impl Default for Thresholds {
    fn default() -> Thresholds {
        Thresholds {
            misalignment_deg: 2.0,
            scale_pct: 5.0,
            drift_pct: 0.1,
        }
    }
}

impl Thresholds {
    /// The keys `--accept` takes, each a threshold.
    pub const KEYS: [&'static str; 3] = ["misalignment_deg", "scale_pct", "drift_pct"];

    /// The defaults with `given` (`key=value,…`, empty for none) set over them;
    /// a message naming the key or value at fault otherwise.
    pub fn parse(given: &str) -> Result<Thresholds, String> {
        let mut thresholds = Thresholds::default();
        for pair in given.split(',').filter(|pair| !pair.trim().is_empty()) {
            let (key, value) = pair.split_once('=').ok_or_else(|| {
                format!(
                    "{pair}: give key=value, a key among {}",
                    Self::KEYS.join(", ")
                )
            })?;
            let value: f64 = (value.trim().parse().ok())
                .filter(|v: &f64| v.is_finite() && *v > 0.0)
                .ok_or_else(|| format!("{key}={value}: not a positive number"))?;
            match key.trim() {
                "misalignment_deg" => thresholds.misalignment_deg = value,
                "scale_pct" => thresholds.scale_pct = value,
                "drift_pct" => thresholds.drift_pct = value,
                other => {
                    return Err(format!(
                        "{other}: not a threshold; the keys are {}",
                        Self::KEYS.join(", ")
                    ));
                }
            }
        }
        Ok(thresholds)
    }
}

/// A check's verdict, from best to worst.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Verdict {
    Pass,
    Marginal,
    /// The check could not be made.
    NotChecked,
    Fail,
}

impl Verdict {
    pub fn words(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Marginal => "marginal",
            Verdict::NotChecked => "not checked",
            Verdict::Fail => "fail",
        }
    }
}

/// One check: what it holds (in words, its unit's), the value and its 95 % half-width
/// (none for the drift), the limit and the verdict; or why it was not made.
#[derive(Debug, Clone, PartialEq)]
pub struct Check {
    /// Its name, and what it holds.
    pub name: &'static str,
    pub what: &'static str,
    pub unit: &'static str,
    pub value: f64,
    pub half_width_95: Option<f64>,
    pub limit: f64,
    /// Where a value beyond the limit is marginal up to a second one (the drift's).
    pub marginal_to: Option<f64>,
    pub verdict: Verdict,
    /// Why it was not made, where it was not.
    pub not_made: Option<String>,
}

/// The checks of a calibration and the verdict over them: the worst of theirs.
#[derive(Debug, Clone, PartialEq)]
pub struct Acceptance {
    pub thresholds: Thresholds,
    pub checks: Vec<Check>,
}

impl Acceptance {
    pub fn verdict(&self) -> Verdict {
        (self.checks.iter().map(|c| c.verdict).max()).unwrap_or(Verdict::NotChecked)
    }

    /// Whether the calibration is rejected: a check failed or could not be made.
    pub fn rejected(&self) -> bool {
        self.verdict() >= Verdict::NotChecked
    }
}

/// The checks of the terms `bound` and of the dead reckoning's `drift` (with no terms
/// and with them, where the reference records positions) against `thresholds`.
pub fn accept<N: ReadNoise>(
    bound: &TermBound<N>,
    drift: Option<&(Drift, Drift)>,
    thresholds: Thresholds,
) -> Acceptance {
    let checks = vec![
        misalignment(bound, thresholds.misalignment_deg),
        scale(bound, thresholds.scale_pct),
        drift_check(drift, thresholds.drift_pct),
    ];
    Acceptance { thresholds, checks }
}

/// The verdict on a magnitude `value` ± `half_width` against `limit`.
fn verdict_of(value: f64, half_width: f64, limit: f64) -> Verdict {
    if !half_width.is_finite() {
        Verdict::NotChecked
    } else if value + half_width <= limit {
        Verdict::Pass
    } else if value - half_width > limit {
        Verdict::Fail
    } else {
        Verdict::Marginal
    }
}

/// The misalignment's angle: the length of its rotation vector (roll, pitch, yaw; in
/// small angles the rotation's angle), its half-width by the estimates' covariance
/// along it.
fn misalignment<N: ReadNoise>(bound: &TermBound<N>, limit_deg: f64) -> Check {
    let axes: Vec<usize> = [
        "misalignment_x_rad",
        "misalignment_y_rad",
        "misalignment_z_rad",
    ]
    .iter()
    .filter_map(|name| bound.names.iter().position(|n| n == name))
    .collect();
    let mut check = Check {
        name: "misalignment",
        what: "misalignment (its angle)",
        unit: "°",
        value: f64::NAN,
        half_width_95: None,
        limit: limit_deg,
        marginal_to: None,
        verdict: Verdict::NotChecked,
        not_made: None,
    };
    if axes.is_empty() {
        check.not_made = Some("not estimated (add misalignment to --terms)".into());
        return check;
    }
    let angle = (axes.iter().map(|&k| bound.value[k].powi(2)).sum::<f64>()).sqrt();
    // Along the rotation vector where it has a direction; the largest axis's otherwise.
    let direction: Vec<f64> = match angle > 0.0 {
        true => axes.iter().map(|&k| bound.value[k] / angle).collect(),
        false => axes
            .iter()
            .map(|_| 1.0 / (axes.len() as f64).sqrt())
            .collect(),
    };
    let mut variance = 0.0;
    for (a, &i) in axes.iter().enumerate() {
        for (b, &j) in axes.iter().enumerate() {
            let correlation = if i == j { 1.0 } else { bound.correlation[i][j] };
            variance += direction[a] * direction[b] * correlation * bound.std[i] * bound.std[j];
        }
    }
    let half_width = bound.residual_noise.quantile_95() * variance.sqrt();
    check.value = angle.to_degrees();
    check.half_width_95 = Some(half_width.to_degrees());
    check.verdict = verdict_of(check.value, half_width.to_degrees(), limit_deg);
    if axes.len() < 3 {
        check.what = "misalignment (its angle over the axes estimated)";
    }
    check
}

/// The scale's distance from 1: one scale's, or the worst axis's of a scale per axis.
fn scale<N: ReadNoise>(bound: &TermBound<N>, limit_pct: f64) -> Check {
    let scales: Vec<usize> = ["scale", "scale_x", "scale_y", "scale_z"]
        .iter()
        .filter_map(|name| bound.names.iter().position(|n| n == name))
        .collect();
    let checks = scales.iter().map(|&k| {
        let (value, half_width) = (100.0 * bound.value[k].abs(), 100.0 * bound.half_width_95(k));
        Check {
            name: "scale",
            what: "scale (its distance from 1)",
            unit: "%",
            value,
            half_width_95: Some(half_width),
            limit: limit_pct,
            marginal_to: None,
            verdict: verdict_of(value, half_width, limit_pct),
            not_made: None,
        }
    });
    checks
        .max_by(|a, b| {
            (a.verdict, a.value)
                .partial_cmp(&(b.verdict, b.value))
                .unwrap()
        })
        .unwrap_or(Check {
            name: "scale",
            what: "scale (its distance from 1)",
            unit: "%",
            value: f64::NAN,
            half_width_95: None,
            limit: limit_pct,
            marginal_to: None,
            verdict: Verdict::NotChecked,
            not_made: Some("not estimated (add scale to --terms)".into()),
        })
}

/// The dead reckoning's end error with the terms applied, % of the distance: a pass
/// within the limit, marginal within twice it.
fn drift_check(drift: Option<&(Drift, Drift)>, limit_pct: f64) -> Check {
    let mut check = Check {
        name: "drift",
        what: "dead-reckoning drift at the end, terms applied (% of the distance travelled)",
        unit: "%",
        value: f64::NAN,
        half_width_95: None,
        limit: limit_pct,
        marginal_to: Some(2.0 * limit_pct),
        verdict: Verdict::NotChecked,
        not_made: None,
    };
    let Some((_, after)) = drift else {
        check.not_made = Some("the reference records no positions to dead-reckon against".into());
        return check;
    };
    check.value = after.end_pct.abs();
    check.verdict = if check.value <= limit_pct {
        Verdict::Pass
    } else if check.value <= 2.0 * limit_pct {
        // As `marginal_to` says.
        Verdict::Marginal
    } else {
        Verdict::Fail
    };
    check
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Inside, across and beyond the limit; an interval of no width where a term is not
    /// seen at all is no check.
    #[test]
    fn an_interval_within_across_or_beyond_its_limit_passes_is_marginal_or_fails() {
        assert_eq!(verdict_of(1.0, 0.5, 2.0), Verdict::Pass);
        assert_eq!(verdict_of(1.8, 0.5, 2.0), Verdict::Marginal);
        assert_eq!(verdict_of(2.6, 0.5, 2.0), Verdict::Fail);
        assert_eq!(verdict_of(1.0, f64::INFINITY, 2.0), Verdict::NotChecked);
        let acceptance = Acceptance {
            thresholds: Thresholds::default(),
            checks: vec![drift_check(None, 0.1)],
        };
        assert!(acceptance.rejected());
    }

    #[test]
    fn thresholds_are_set_over_the_defaults_by_key() {
        assert_eq!(Thresholds::parse(""), Ok(Thresholds::default()));
        let set = Thresholds::parse("scale_pct=1.5, drift_pct=0.2").unwrap();
        assert_eq!(
            (set.misalignment_deg, set.scale_pct, set.drift_pct),
            (2.0, 1.5, 0.2)
        );
        assert!(
            Thresholds::parse("scale_pct=-1")
                .unwrap_err()
                .contains("not a positive number")
        );
        assert!(
            Thresholds::parse("tilt=1")
                .unwrap_err()
                .starts_with("tilt: not a threshold")
        );
        assert!(
            Thresholds::parse("scale_pct")
                .unwrap_err()
                .contains("give key=value")
        );
    }
}
