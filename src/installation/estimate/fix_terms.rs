//! What a fit to position fixes is asked and why it refuses: the terms it estimates
//! ([`FixTerms`], the fixes' latency [`FIX_LATENCY`] among them where asked), their
//! tolerances ([`FIX_TOLERANCES`]), the noise it is given ([`FixNoise`]) and its
//! refusals ([`FixFitError`]). In: nothing. Out: the types the fit and its callers share.

use crate::installation::estimate::bound::Tolerances;
use crate::installation::estimate::fit::TIME_OFFSET_MARGIN_S;
use crate::installation::terms::{PerKind, TermSet};

/// The tolerance of each term fitted to fixes: beyond it a term is said to be seen
/// poorly (and still applied, with its standard deviation). Fixes of metres place a
/// scale and a yaw well (they grow with the distance travelled), a lever arm and a
/// clock only as well as the turns show them; a lever arm within half a metre and a
/// clock within half a second move a dead reckoning by less than the fixes' noise.
pub const FIX_TOLERANCES: Tolerances = PerKind {
    scale: 0.005,
    misalignment_rad: 0.5 * (std::f64::consts::PI / 180.0),
    lever_arm_m: 0.5,
    time_offset_s: 0.5,
    bias_m_s: 0.01,
};

/// The name of the fixes' latency among a fit's parameters: how late each fix is
/// stamped after the position it gives, on the attitude's clock, s (a USBL's acoustic
/// travel and processing). Not a term of the DVL's installation: the fixes' own.
pub const FIX_LATENCY: &str = "fix_latency_s";

/// What a fit to fixes estimates: the DVL's terms, and whether the fixes' latency too.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixTerms {
    pub set: TermSet,
    pub fix_latency: bool,
}

impl From<TermSet> for FixTerms {
    /// The DVL's terms alone, the fixes taken as stamped when they were taken.
    fn from(set: TermSet) -> FixTerms {
        FixTerms {
            set,
            fix_latency: false,
        }
    }
}

/// The noise of a fit to fixes: a fix's per horizontal axis and in depth, m, and the
/// DVL's white noise per axis, m/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixNoise {
    pub fix_m: f64,
    pub depth_m: f64,
    pub dvl_m_s: f64,
}

/// Why the terms cannot be fitted to the fixes.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FixFitError {
    #[error(
        "no fix lies within a piece of the DVL record ({fixes} fixes from {:.1} to {:.1} s, the DVL's {pieces} piece(s) from {:.1} to {:.1} s on its clock, each less {margin_s} s at its ends (the clock's search, and the latency's where it is fitted), about a time offset of {} s): the fixes do not overlap the DVL; give fixes of the same dive, on the attitude's clock", fix_span_s.0, fix_span_s.1, dvl_span_s.0, dvl_span_s.1, crate::ThreeFigures(*centre_s)
    )]
    NoOverlap {
        fixes: usize,
        fix_span_s: (f64, f64),
        pieces: usize,
        dvl_span_s: (f64, f64),
        centre_s: f64,
        margin_s: f64,
    },
    #[error(
        "{} within the DVL's pieces, {outliers} of them outliers left out, give {residuals} residuals for {parameters} parameters (the terms and a start position per piece): a fit needs more; give more fixes, or fewer terms",
        match fitted { 1 => "1 fix".to_string(), n => format!("{n} fixes") }
    )]
    TooFewFixes {
        fitted: usize,
        outliers: usize,
        residuals: usize,
        parameters: usize,
    },
    #[error(
        "{outliers} of the {within} fixes within the DVL's pieces lie beyond the robust fit's reach of the dead reckoning: more than a quarter are outliers, so the fixes do not show the installation (fixes on another clock than the attitude's, more than the ±{TIME_OFFSET_MARGIN_S} s a fit searches apart, leave most of them so: put them on one clock)"
    )]
    Outliers { outliers: usize, within: usize },
    #[error(
        "the attitude does not cover the DVL's samples at the time offset {time_offset_s:.3} s: give the attitude of the whole dive"
    )]
    NoAttitude { time_offset_s: f64 },
    #[error(
        "the time offset that fits the fixes best, {time_offset_s:.2} s, lies at the edge of the ±{TIME_OFFSET_MARGIN_S} s a fit to fixes searches, and nothing fitted at the edge is the installation: the clocks may lie further apart than that (or the fixes and the attitude on different clocks): put the DVL, the attitude and the fixes on one clock to within {TIME_OFFSET_MARGIN_S} s; or the fixes do not place the clock at all (fixes of metres over a dive of minutes, or one steady turn, which ties a clock to the yaw): calibrate on a longer dive with more varied turns, or where the clocks are known to agree, leave time_offset out of --terms (correct: give the clock with --time-offset-s)"
    )]
    ClockAtScanEdge { time_offset_s: f64 },
    #[error(
        "the fixes' latency that fits them best, {latency_s:.2} s, lies at the edge of the ±{TIME_OFFSET_MARGIN_S} s a fit allows it, and nothing fitted at the edge is the installation: the fixes may be stamped on another clock than the attitude's (put them on one clock to within {TIME_OFFSET_MARGIN_S} s), or they do not place a latency at all (a straight run at one speed shifts the track as its start does, and fixes of metres tell a latency from the DVL's clock only through the attitude read at that clock): give the latency where it is known with --fix-latency-s, or calibrate on a dive with turns and changes of speed"
    )]
    LatencyAtScanEdge { latency_s: f64 },
    #[error(
        "the terms fitted leave the fixes further from the dead reckoning than no terms do (whitened sum of squares {with:.1} against {without:.1}): the fit found no installation the fixes show; the fixes may be on another clock, another vehicle's, or in another frame"
    )]
    WorseThanNone { with: f64, without: f64 },
    #[error("the fit to the fixes did not converge: {termination}")]
    NotConverged { termination: String },
}
