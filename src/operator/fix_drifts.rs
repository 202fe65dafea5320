//! The dead reckoning of a calibration against fixes, scored as an operator scores it
//! ([`crate::installation::fix_drift`]): over the whole dive, with no terms and with
//! them; and where `--blackout-s START:LENGTH` asks for it, the vendors' blackout
//! verification: the fixes inside the window withheld from the fit, the dead reckoning
//! carried through it, its error at the window's end as a share of the distance
//! travelled in it. In: `--blackout-s` as typed, the dive read and fitted. Out: the
//! window and its fixes withheld ([`withhold`]), then the [`FixDrifts`].

use crate::data::fixes::Fixes;
use crate::data::paired::PairedRecording;
use crate::installation::estimate::fixes::{FIX_LATENCY, FixFit};
use crate::installation::fix_drift::{AgainstFixes, DiveDrift, Span, SpanDrift};
use crate::installation::frames::Attitude;
use crate::installation::terms::Installation;
use crate::operator::acceptance::{CARRIED_DRIFT, ScoredDrift};
use crate::operator::calibrate::CalibrateError;

/// A blackout as `--blackout-s START:LENGTH` asks for it: its start, s after the DVL's
/// first sample, and its length, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlackoutAsked {
    pub start_s: f64,
    pub length_s: f64,
}

impl BlackoutAsked {
    /// `START:LENGTH` as typed; a message naming the fault otherwise.
    pub fn parse(typed: &str) -> Result<BlackoutAsked, String> {
        let (start, length) = typed.split_once(':').ok_or_else(|| {
            format!("{typed}: give START:LENGTH, seconds after the DVL's first sample and seconds, e.g. 600:300")
        })?;
        let number = |what: &str, text: &str| {
            (text.trim().parse::<f64>().ok())
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("{typed}: its {what} {text:?} is not a number of seconds"))
        };
        let (start_s, length_s) = (number("start", start)?, number("length", length)?);
        if start_s < 0.0 || length_s <= 0.0 {
            return Err(format!(
                "{typed}: give a start of zero or more and a positive length"
            ));
        }
        Ok(BlackoutAsked { start_s, length_s })
    }
}

/// A blackout: as asked, its window on the fixes' clock, the fixes withheld from the fit
/// in it, and its drift with no terms and with them (or why it cannot be scored).
#[derive(Debug, Clone)]
pub struct Blackout {
    pub asked: BlackoutAsked,
    pub window: Span,
    pub withheld: Fixes,
    pub drift: Result<(SpanDrift, SpanDrift), String>,
}

/// The dead reckoning of a fit to fixes scored against them: the whole dive's, with no
/// terms and with them, and the blackout's where one was asked.
#[derive(Debug, Clone)]
pub struct FixDrifts {
    pub dive: Option<(DiveDrift, DiveDrift)>,
    pub blackout: Option<Blackout>,
}

/// The window `asked` of the DVL's record stamped `time_s` on the fixes' clock, its
/// fixes taken out of `fixes` (withheld from the fit) and returned; refused where the
/// window does not lie within the record.
pub fn withhold(
    (time_s, fixes): (&[f64], &mut Fixes),
    asked: BlackoutAsked,
) -> Result<(Span, Fixes), CalibrateError> {
    let (first, last) = (time_s[0], time_s[time_s.len() - 1]);
    let window = (
        first + asked.start_s,
        first + asked.start_s + asked.length_s,
    );
    if window.1 > last {
        return Err(CalibrateError::Blackout(format!(
            "{}:{}: ends {:.1} s after the DVL's first sample, beyond its record of {:.1} s",
            crate::Shown(asked.start_s),
            crate::Shown(asked.length_s),
            window.1 - first,
            last - first
        )));
    }
    let inside = |j: usize| window.0 < fixes.time_s[j] && fixes.time_s[j] < window.1;
    let withheld = fixes.select(inside);
    *fixes = fixes.select(|j| !inside(j));
    Ok((window, withheld))
}

/// The drifts of the dead reckoning of `recording` against the `fixes` `fit` was fitted
/// to, with no terms and with the fit's, and across `blackout` (the window and its
/// fixes withheld) where one was asked.
pub fn drifts(
    (recording, fixes, fit): (&PairedRecording, &Fixes, &FixFit),
    blackout: Option<(BlackoutAsked, Span, Fixes)>,
) -> FixDrifts {
    let (attitude, pieces) = (Attitude::of(recording), recording.pieces());
    let against = |latency_s| AgainstFixes {
        dvl: (&recording.time_s, &recording.dvl_m_s),
        pieces: &pieces,
        attitude: &attitude,
        fixes,
        latency_s,
    };
    let none = against(0.0).reckon(&Installation::default());
    let terms = against(fitted_latency_s(fit)).reckon(&fit.installation);
    let dive_drifts = none.dive_drift().zip(terms.dive_drift());
    let blackout = blackout.map(|(asked, window, withheld)| Blackout {
        asked,
        window,
        withheld,
        drift: (none.blackout_drift(window))
            .and_then(|before| Ok((before, terms.blackout_drift(window)?))),
    });
    FixDrifts {
        dive: dive_drifts,
        blackout,
    }
}

/// The fixes' latency `fit` estimated and applied, s; zero otherwise.
fn fitted_latency_s(fit: &FixFit) -> f64 {
    (fit.bound.names.iter())
        .position(|n| *n == FIX_LATENCY && fit.bound.is_applied(n))
        .map_or(0.0, |k| fit.bound.value[k])
}

/// Why a dive against fixes has no drift.
const NO_PIECE: &str = "no piece of the DVL's record holds fixes at both its ends";

impl FixDrifts {
    /// The drift the acceptance holds: the blackout's where one was asked, the whole
    /// dive's otherwise; or why there is none.
    pub fn scored(&self) -> Result<ScoredDrift, String> {
        match (&self.blackout, &self.dive) {
            (Some(blackout), _) => match &blackout.drift {
                Ok((_, after)) => Ok(ScoredDrift {
                    what: "dead-reckoning drift at the blackout's end, terms fitted without its fixes (% of the distance travelled in it)",
                    end_pct: after.pct(),
                }),
                Err(why) => Err(format!("the blackout cannot be scored: {why}")),
            },
            (None, Some((_, after))) => Ok(ScoredDrift {
                what: "dead-reckoning drift at the dive's end, terms applied, placed on the fixes at its start (% of the distance travelled; on the fixes fitted: give --blackout-s to withhold some)",
                end_pct: after.end_pct(),
            }),
            (None, None) => Err(NO_PIECE.into()),
        }
    }

    /// The drift the acceptance holds of an installation carried to a dive: the whole
    /// dive's with it; or why there is none.
    pub fn carried(&self) -> Result<ScoredDrift, String> {
        match &self.dive {
            Some((_, after)) => Ok(ScoredDrift {
                what: CARRIED_DRIFT,
                end_pct: after.end_pct(),
            }),
            None => Err(NO_PIECE.into()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_blackout_is_a_start_and_a_length_in_seconds() {
        assert_eq!(
            BlackoutAsked::parse("600:300"),
            Ok(BlackoutAsked {
                start_s: 600.0,
                length_s: 300.0
            })
        );
        assert!(
            BlackoutAsked::parse("600")
                .unwrap_err()
                .contains("START:LENGTH")
        );
        assert!(
            BlackoutAsked::parse("600:-5")
                .unwrap_err()
                .contains("positive length")
        );
        assert!(
            BlackoutAsked::parse("ten:300")
                .unwrap_err()
                .contains("start \"ten\"")
        );
    }
}
