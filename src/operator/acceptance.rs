//! Acceptance of a calibration, the way the vendors' procedures accept one: the DVL's
//! misalignment under a limit (2° by default), its scale within one of 1 (0.95–1.05),
//! and the dead reckoning with the terms applied within a share of the distance
//! travelled (0.1 %, marginal to 0.2 %): at a blackout's end where one was asked (the
//! fixes inside it withheld from the fit), at the recording's end otherwise. An estimate is a claim
//! with an interval, so a term passes where its whole 95 % interval lies within the
//! limit, fails where the whole interval lies beyond, and is marginal where the limit
//! falls inside it. A check the calibration cannot make (the term not estimated, no
//! positions to dead-reckon against) is said so, and the calibration is then not
//! accepted. An installation carried to the next dive (`correct --accept`) is held to
//! its dead reckoning's drift there, which its calibration did not see: the vendors'
//! verification run. In: `--accept`'s thresholds, and a calibration's terms and drift
//! or a carried installation's drift. Out: an [`Acceptance`], each check with its
//! verdict.

use crate::installation::dead_reckoning::Reckoning;
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
        let mut seen = Vec::new();
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
            if seen.contains(&key.trim()) {
                return Err(format!("{}: given twice", key.trim()));
            }
            seen.push(key.trim());
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

impl Check {
    /// A check not yet made: its name, what it holds, its unit and limit.
    fn unmade(name: &'static str, what: &'static str, unit: &'static str, limit: f64) -> Check {
        Check {
            name,
            what,
            unit,
            value: f64::NAN,
            half_width_95: None,
            limit,
            marginal_to: None,
            verdict: Verdict::NotChecked,
            not_made: None,
        }
    }
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

/// A dead reckoning's drift with the terms applied, as the acceptance holds it: what it
/// is, in words, and its error at the end, % of the distance travelled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScoredDrift {
    pub what: &'static str,
    pub end_pct: f64,
}

/// What the drift of a calibration against a velocity reference is, in words.
pub const CALIBRATED_DRIFT: &str =
    "dead-reckoning drift at the end, terms applied (% of the distance travelled)";

/// What the drift of an installation carried to a dive is, in words.
pub const CARRIED_DRIFT: &str = "dead-reckoning drift at the dive's end, the installation carried to it (% of the distance travelled; held out from its calibration)";

/// The drift the acceptance holds against a velocity reference: the dead reckoning's
/// with the terms applied, against the reference's positions where it records them;
/// `what` it is, in words.
pub fn reference_drift(
    drift: Option<&(Reckoning, Reckoning)>,
    what: &'static str,
) -> Result<ScoredDrift, String> {
    match drift {
        Some((_, after)) => Ok(ScoredDrift {
            what,
            end_pct: after.drift.end_pct,
        }),
        None => Err("no dead reckoning against the reference's positions (it records none, or no piece could be scored)".into()),
    }
}

/// The checks of the terms `bound` (those `estimated`: a fit to horizontal fixes does
/// not estimate roll and pitch) and of the dead reckoning's `drift` (or why there is
/// none) against `thresholds`.
pub fn accept<N: ReadNoise>(
    (bound, estimated): (&TermBound<N>, &dyn Fn(usize) -> bool),
    drift: Result<ScoredDrift, String>,
    thresholds: Thresholds,
) -> Acceptance {
    let checks = vec![
        misalignment((bound, estimated), thresholds.misalignment_deg),
        scale(bound, thresholds.scale_pct),
        drift_check(drift, thresholds.drift_pct),
    ];
    Acceptance { thresholds, checks }
}

/// The check of an installation carried to a dive: its dead reckoning's `drift` there
/// (or why there is none) against `thresholds`' drift; its terms were held to theirs
/// where they were calibrated.
pub fn accept_carried(drift: Result<ScoredDrift, String>, thresholds: Thresholds) -> Acceptance {
    let checks = vec![drift_check(drift, thresholds.drift_pct)];
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
/// small angles the rotation's angle), its half-width that of the estimates' worst-known
/// direction (t times the square root of their covariance's largest eigenvalue): the
/// angle moves by no more than the vector does, and a roll the recording barely shows
/// widens it however tight the yaw.
fn misalignment<N: ReadNoise>(
    (bound, estimated): (&TermBound<N>, &dyn Fn(usize) -> bool),
    limit_deg: f64,
) -> Check {
    let axes: Vec<usize> = [
        "misalignment_x_rad",
        "misalignment_y_rad",
        "misalignment_z_rad",
    ]
    .iter()
    .filter_map(|name| bound.names.iter().position(|n| n == name))
    .filter(|&k| estimated(k))
    .collect();
    let what = match axes.len() {
        3 => "misalignment (its angle)",
        1 if bound.names[axes[0]] == "misalignment_z_rad" => {
            "misalignment (its yaw: horizontal fixes do not feel roll and pitch)"
        }
        _ => "misalignment (its angle over the axes estimated)",
    };
    let mut check = Check::unmade("misalignment", what, "°", limit_deg);
    if axes.is_empty() {
        check.not_made = Some("not estimated (add misalignment to --terms)".into());
        return check;
    }
    let covariance = nalgebra::DMatrix::from_fn(axes.len(), axes.len(), |a, b| {
        let (i, j) = (axes[a], axes[b]);
        let correlation = if i == j { 1.0 } else { bound.correlation[i][j] };
        correlation * bound.std[i] * bound.std[j]
    });
    let widest = match covariance.iter().all(|c| c.is_finite()) {
        true => covariance.symmetric_eigenvalues().max().max(0.0).sqrt(),
        false => f64::INFINITY,
    };
    let angle = (axes.iter().map(|&k| bound.value[k].powi(2)).sum::<f64>()).sqrt();
    let half_width = (bound.residual_noise.quantile_95() * widest).to_degrees();
    check.value = angle.to_degrees();
    check.half_width_95 = Some(half_width);
    check.verdict = verdict_of(check.value, half_width, limit_deg);
    if check.verdict == Verdict::NotChecked {
        check.not_made = Some(
            "an axis the recording does not show (its standard deviation is not finite)".into(),
        );
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
        let verdict = verdict_of(value, half_width, limit_pct);
        Check {
            name: "scale",
            what: match bound.names[k] {
                "scale_x" => "scale x, the worst axis (its distance from 1)",
                "scale_y" => "scale y, the worst axis (its distance from 1)",
                "scale_z" => "scale z, the worst axis (its distance from 1)",
                _ => "scale (its distance from 1)",
            },
            unit: "%",
            value,
            half_width_95: Some(half_width),
            limit: limit_pct,
            marginal_to: None,
            verdict,
            not_made: (verdict == Verdict::NotChecked).then(|| {
                "the recording does not show it (its standard deviation is not finite)".into()
            }),
        }
    });
    checks
        .max_by(|a, b| {
            (a.verdict, a.value)
                .partial_cmp(&(b.verdict, b.value))
                .unwrap()
        })
        .unwrap_or(Check {
            not_made: Some("not estimated (add scale to --terms)".into()),
            ..Check::unmade("scale", "scale (its distance from 1)", "%", limit_pct)
        })
}

/// The dead reckoning's end error with the terms applied, % of the distance, as
/// `drift` says what it is (or why there is none); a pass within the limit, marginal
/// within twice it.
fn drift_check(drift: Result<ScoredDrift, String>, limit_pct: f64) -> Check {
    let what = (drift.as_ref()).map_or("dead-reckoning drift (% of the distance travelled)", |d| {
        d.what
    });
    let mut check = Check {
        marginal_to: Some(2.0 * limit_pct),
        ..Check::unmade("drift", what, "%", limit_pct)
    };
    let drift = match drift {
        Ok(drift) => drift,
        Err(why) => {
            check.not_made = Some(why);
            return check;
        }
    };
    check.value = drift.end_pct.abs();
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

    /// Inside, across and beyond the limit; an interval without bound (a term not seen at
    /// all) is no check.
    #[test]
    fn an_interval_within_across_or_beyond_its_limit_passes_is_marginal_or_fails() {
        assert_eq!(verdict_of(1.0, 0.5, 2.0), Verdict::Pass);
        assert_eq!(verdict_of(1.8, 0.5, 2.0), Verdict::Marginal);
        assert_eq!(verdict_of(2.6, 0.5, 2.0), Verdict::Fail);
        assert_eq!(verdict_of(1.0, f64::INFINITY, 2.0), Verdict::NotChecked);
        let acceptance = Acceptance {
            thresholds: Thresholds::default(),
            checks: vec![drift_check(Err("no positions".into()), 0.1)],
        };
        assert!(acceptance.rejected());
    }

    /// The dead reckoning's end drift: within the limit a pass, within twice it marginal,
    /// beyond a fail.
    #[test]
    fn the_drift_passes_within_its_limit_and_is_marginal_within_twice_it() {
        let drift = |end_pct: f64| {
            let what = "drift";
            drift_check(Ok(ScoredDrift { what, end_pct }), 0.1).verdict
        };
        assert_eq!(drift(0.08), Verdict::Pass);
        assert_eq!(drift(-0.15), Verdict::Marginal);
        assert_eq!(drift(0.3), Verdict::Fail);
    }

    /// Degrees of freedom enough for t to be 1.96.
    struct Known;
    impl ReadNoise for Known {
        fn freedom(&self) -> f64 {
            1e9
        }
    }

    /// The misalignment's terms at `value` (rad) with standard deviations `std` (rad)
    /// and the roll–yaw correlation `rho`.
    fn misaligned(value: [f64; 3], std: [f64; 3], rho: f64) -> TermBound<Known> {
        let mut correlation = vec![vec![0.0; 3]; 3];
        for k in 0..3 {
            correlation[k][k] = 1.0;
        }
        (correlation[0][2], correlation[2][0]) = (rho, rho);
        TermBound {
            names: vec![
                "misalignment_x_rad",
                "misalignment_y_rad",
                "misalignment_z_rad",
            ],
            value: value.to_vec(),
            std: std.to_vec(),
            bound_std: std.to_vec(),
            correlation,
            unseen: Vec::new(),
            applied: vec![true; 3],
            residual_noise: Known,
        }
    }

    /// Known answers: the angle is the rotation vector's length; its half-width 1.96
    /// times the largest standard deviation where they are uncorrelated (a roll barely
    /// shown widens the angle's interval however tight the yaw), and that of the
    /// covariance's largest eigenvalue where roll and yaw are correlated.
    #[test]
    fn the_misalignments_interval_covers_its_worst_known_direction() {
        let deg = f64::to_radians;
        let all = |_| true;
        let check = misalignment(
            (
                &misaligned(
                    [deg(0.1), 0.0, deg(1.0)],
                    [deg(2.0), deg(0.05), deg(0.05)],
                    0.0,
                ),
                &all,
            ),
            2.0,
        );
        assert!((check.value - 0.1f64.hypot(1.0)).abs() < 1e-9, "{check:?}");
        let half_width = check.half_width_95.unwrap();
        assert!((half_width - 1.959_964 * 2.0).abs() < 1e-4, "{check:?}");
        assert_eq!(check.verdict, Verdict::Marginal);
        // Roll and yaw of 1° each, correlated 0.5: the largest eigenvalue of
        // [[1, 0.5], [0.5, 1]] (deg²) is 1.5.
        let check = misalignment(
            (
                &misaligned([0.0, 0.0, deg(0.2)], [deg(1.0), deg(0.1), deg(1.0)], 0.5),
                &all,
            ),
            5.0,
        );
        assert!(
            (check.half_width_95.unwrap() - 1.959_964 * 1.5f64.sqrt()).abs() < 1e-4,
            "{check:?}"
        );
        assert_eq!(check.verdict, Verdict::Pass);
        let tilted = misaligned([deg(3.0), 0.0, deg(4.0)], [deg(0.1); 3], 0.0);
        let check = misalignment((&tilted, &all), 2.0);
        assert!((check.value - 5.0).abs() < 1e-9);
        assert_eq!(check.verdict, Verdict::Fail);
        // The yaw alone, where roll and pitch were not estimated (horizontal fixes).
        let yaw = misalignment((&tilted, &|k| k == 2), 2.0);
        assert!((yaw.value - 4.0).abs() < 1e-9 && yaw.what.contains("its yaw"));
        let unseen = misaligned([0.0; 3], [f64::INFINITY, 0.1, 0.1], 0.0);
        let unseen = misalignment((&unseen, &all), 2.0);
        assert_eq!(unseen.verdict, Verdict::NotChecked);
        assert!(unseen.not_made.is_some());
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
