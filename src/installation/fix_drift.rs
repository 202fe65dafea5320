//! The dead reckoning's drift against position fixes, scored the way a blackout
//! verification scores it: the track of one piece (between losses of bottom lock) placed
//! at a span's start on the fixes there, and its error at the span's end against the
//! fixes there, as a share of the distance the dead reckoning travelled in between.
//! Each end is placed by the mean offset from the track of the fixes of the [`ANCHOR_S`]
//! beside it (outside a blackout, whose own fixes are withheld: before its start, after
//! its end; inside a piece: after its first fix, before its last), so that the fixes'
//! white noise is averaged over those fixes ([`SpanDrift::noise_floor_m`] says how much
//! of it is left); the span runs between the mean times of the two ends' fixes. A
//! blackout is one span ([`Reckoned::blackout_drift`]); a whole dive is each piece, the
//! errors summed over the distances ([`Reckoned::dive_drift`]), as [`Drift::end_pct`] sums them against a
//! reference's positions. The fixes are chosen by their stamps, the same whatever
//! latency a dead reckoning reads them with; each piece is reckoned once for both
//! ([`AgainstFixes::reckon`]).
//! In: an installation, the DVL's samples and pieces, an [`Attitude`], the [`Fixes`]
//! (their times on the attitude's clock) and the fixes' latency. Out: a [`SpanDrift`]
//! per span, each with its track placed on the fixes.
//!
//! [`Drift::end_pct`]: super::dead_reckoning::Drift::end_pct

use crate::Vec3;
use crate::data::fixes::Fixes;
use crate::installation::dead_reckoning::{Track, dead_reckon, interior, path_length_m};
use crate::installation::frames::Attitude;
use crate::installation::terms::Installation;
use std::ops::{Range, RangeInclusive};

/// How far from a span's end the fixes that place it lie, s: a USBL's ten fixes at
/// 1 Hz, over which a dead reckoning moves by a few millimetres.
pub const ANCHOR_S: f64 = 10.0;

/// A time span on the fixes' stamps, s: its start and its end.
pub type Span = (f64, f64);

/// The dead reckoning's drift over one span: placed at its start on the fixes there,
/// its error against the fixes at its end.
#[derive(Debug, Clone, PartialEq)]
pub struct SpanDrift {
    /// The mean times of the fixes that placed the start and the end, s.
    pub from_s: f64,
    pub to_s: f64,
    /// The track less the fixes at the end, north and east, m.
    pub error_ne_m: [f64; 2],
    /// How far the dead reckoning travelled horizontally from `from_s` to `to_s`, m.
    pub distance_m: f64,
    /// How many fixes placed the start and the end.
    pub anchored: (usize, usize),
    /// The track, placed on the fixes at the start: its times and north and east, m.
    pub track: PlacedTrack,
}

/// A dead-reckoned track placed on the fixes: times, s, and north and east, m.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlacedTrack {
    pub time_s: Vec<f64>,
    pub north_east_m: Vec<[f64; 2]>,
}

impl SpanDrift {
    /// The horizontal error at the end, m.
    pub fn error_m(&self) -> f64 {
        self.error_ne_m[0].hypot(self.error_ne_m[1])
    }

    /// The error at the end, % of the distance travelled.
    pub fn pct(&self) -> f64 {
        self.pct_of(self.distance_m)
    }

    /// The error at the end, % of `distance_m` (another dead reckoning's of the span).
    pub fn pct_of(&self, distance_m: f64) -> f64 {
        100.0 * self.error_m() / distance_m
    }

    /// The horizontal RMS error that white fixes of `fix_m` per axis leave alone, m:
    /// each end the mean of its fixes, per axis σ²(1/n₁ + 1/n₂), two axes.
    pub fn noise_floor_m(&self, fix_m: f64) -> f64 {
        let (a, b) = (self.anchored.0 as f64, self.anchored.1 as f64);
        fix_m * (2.0 * (1.0 / a + 1.0 / b)).sqrt()
    }
}

/// The dead reckoning's drift over a whole dive: a span per piece, from its first fix
/// to its last.
#[derive(Debug, Clone, PartialEq)]
pub struct DiveDrift {
    pub spans: Vec<SpanDrift>,
}

impl DiveDrift {
    /// The pieces' end errors summed over the distances they travelled, %.
    pub fn end_pct(&self) -> f64 {
        self.end_pct_of(self.distance_m())
    }

    /// The pieces' end errors summed, % of `distance_m` (another dead reckoning's).
    pub fn end_pct_of(&self, distance_m: f64) -> f64 {
        100.0 * self.error_m() / distance_m
    }

    /// The pieces' end errors summed, m.
    pub fn error_m(&self) -> f64 {
        self.spans.iter().map(SpanDrift::error_m).sum()
    }

    /// The distance travelled over every span, m.
    pub fn distance_m(&self) -> f64 {
        self.spans.iter().map(|s| s.distance_m).sum()
    }
}

/// What a dead reckoning is scored against: the DVL samples (stamps, velocities) and
/// their pieces, the attitude, the fixes, and the fixes' latency, s (a fix stamped t
/// gives the position at t − latency).
#[derive(Clone, Copy)]
pub struct AgainstFixes<'a> {
    pub dvl: (&'a [f64], &'a [Vec3]),
    pub pieces: &'a [Range<usize>],
    pub attitude: &'a Attitude,
    pub fixes: &'a Fixes,
    pub latency_s: f64,
}

/// The dead reckoning through one installation, scored against fixes: what it is scored
/// against, and each piece's track.
pub struct Reckoned<'a> {
    against: AgainstFixes<'a>,
    tracks: Vec<Track>,
}

impl<'a> AgainstFixes<'a> {
    /// Each piece's track through `installation`, cut to the samples whose stamp plus
    /// its clock reads the attitude.
    pub fn reckon(&self, installation: &Installation) -> Reckoned<'a> {
        let inside = interior(self.attitude, self.dvl.0, installation.time_offset_s);
        let tracks = (self.pieces.iter())
            .map(|piece| piece.start.max(inside.start)..piece.end.min(inside.end))
            .filter(|piece| piece.len() >= 2)
            .filter_map(|piece| {
                let dvl = (&self.dvl.0[piece.clone()], &self.dvl.1[piece]);
                dead_reckon(installation, dvl, self.attitude)
            })
            .collect();
        Reckoned {
            against: *self,
            tracks,
        }
    }

    /// The mean time (on the track's clock: the stamp less the latency) and the mean
    /// offset, north and east, of the fixes stamped within `stamps` from `track`, and
    /// how many; `None` where none lies on the track.
    fn anchor(&self, track: &Track, stamps: RangeInclusive<f64>) -> Option<(f64, [f64; 2], usize)> {
        let (mut time, mut offset, mut count) = (0.0, [0.0; 2], 0);
        let first = self.fixes.time_s.partition_point(|t| t < stamps.start());
        for j in first..self.fixes.len() {
            if self.fixes.time_s[j] > *stamps.end() {
                break;
            }
            let t = self.fixes.time_s[j] - self.latency_s;
            let Some(position) = track.at(t) else {
                continue;
            };
            let fix = self.fixes.north_east_m[j];
            time += t;
            offset = [0, 1].map(|k| offset[k] + fix[k] - position[k]);
            count += 1;
        }
        (count > 0).then(|| {
            let n = count as f64;
            (time / n, offset.map(|o| o / n), count)
        })
    }
}

impl Reckoned<'_> {
    /// The drift of the dead reckoning over the whole dive: each piece placed on its
    /// fixes of the [`ANCHOR_S`] after its first and scored on those of the [`ANCHOR_S`]
    /// before its last (a piece whose fixes span less than twice that is not scored);
    /// `None` where no piece is.
    pub fn dive_drift(&self) -> Option<DiveDrift> {
        let against = &self.against;
        let mut spans = Vec::new();
        for track in &self.tracks {
            let within =
                |t: f64| (track.time_s[0]..=track.time_s[track.time_s.len() - 1]).contains(&t);
            let stamps: Vec<f64> = (against.fixes.time_s.iter().copied())
                .filter(|&t| within(t - against.latency_s))
                .collect();
            let (Some(&first), Some(&last)) = (stamps.first(), stamps.last()) else {
                continue;
            };
            if last - first < 2.0 * ANCHOR_S {
                continue;
            }
            let ends = (first..=first + ANCHOR_S, last - ANCHOR_S..=last);
            if let Some(span) = span_drift(track, against, ends) {
                spans.push(span);
            }
        }
        (!spans.is_empty()).then_some(DiveDrift { spans })
    }

    /// The drift of the dead reckoning across the blackout `window` (on the fixes'
    /// stamps; its own fixes withheld from those scored against): placed on the fixes
    /// of the [`ANCHOR_S`] before its start, scored on those of the [`ANCHOR_S`] after its
    /// end; why not, in words, where it cannot be scored.
    pub fn blackout_drift(&self, window: Span) -> Result<SpanDrift, String> {
        let against = &self.against;
        let (from, to) = (window.0 - against.latency_s, window.1 - against.latency_s);
        let spans =
            |track: &&Track| track.time_s[0] <= from && to <= track.time_s[track.time_s.len() - 1];
        let track = self.tracks.iter().find(spans).ok_or_else(|| {
            "no piece of the DVL's record spans it (the DVL lost bottom lock within it, or it lies beyond the record)".to_string()
        })?;
        let ends = (
            window.0 - ANCHOR_S..=window.0,
            window.1..=window.1 + ANCHOR_S,
        );
        span_drift(track, against, ends).ok_or_else(|| {
            format!(
                "no fix within {ANCHOR_S} s before its start, or after its end, inside the DVL's record"
            )
        })
    }
}

/// `track` placed on the fixes stamped within the first of `ends`, scored on those
/// within the second; `None` where an end has no fix on the track, or the track does
/// not move between the two.
fn span_drift(
    track: &Track,
    against: &AgainstFixes,
    ends: (RangeInclusive<f64>, RangeInclusive<f64>),
) -> Option<SpanDrift> {
    let (from_s, start, before) = against.anchor(track, ends.0)?;
    let (to_s, end, after) = against.anchor(track, ends.1)?;
    let placed = |p: Vec3| [p[0] + start[0], p[1] + start[1]];
    // The track from `from_s` to `to_s`: its samples between, and both ends.
    let (from, to) = (track.at(from_s)?, track.at(to_s)?);
    let between =
        (track.time_s.iter().zip(&track.position_m)).filter(|(t, _)| from_s < **t && **t < to_s);
    let mut placed_track = PlacedTrack::default();
    for (t, p) in std::iter::once((from_s, from))
        .chain(between.map(|(t, p)| (*t, *p)))
        .chain(std::iter::once((to_s, to)))
    {
        placed_track.time_s.push(t);
        placed_track.north_east_m.push(placed(p));
    }
    let distance_m = path_length_m(&placed_track.north_east_m);
    (distance_m > 0.0).then(|| SpanDrift {
        from_s,
        to_s,
        // The track placed at the start less the fixes at the end: (p + s) − (p + e).
        error_ne_m: [start[0] - end[0], start[1] - end[1]],
        distance_m,
        anchored: (before, after),
        track: placed_track,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vehicle heading north-east at 1.5 m/s, level, for 600 s at 5 Hz; fixes each
    /// second on its true track.
    fn straight() -> (Attitude, Vec<f64>, Vec<Vec3>, Fixes) {
        let attitude_s: Vec<f64> = (0..=6000).map(|i| i as f64 / 10.0).collect();
        let heading = std::f64::consts::FRAC_PI_4;
        let angles = vec![[0.0, 0.0, heading]; attitude_s.len()];
        let time_s: Vec<f64> = (10..=2950).map(|i| i as f64 / 5.0).collect();
        let dvl = vec![[1.5, 0.0, 0.0]; time_s.len()];
        let fix_s: Vec<f64> = (3..=588).map(f64::from).collect();
        let fixes = Fixes {
            lines: (0..fix_s.len() as u64).collect(),
            north_east_m: (fix_s.iter())
                .map(|t| [1.5 * t * heading.cos(), 1.5 * t * heading.sin()])
                .collect(),
            time_s: fix_s,
            depth_m: None,
            noise_m: None,
        };
        (Attitude::new(&attitude_s, &angles), time_s, dvl, fixes)
    }

    /// A DVL reading 1 % fast drifts 1 % of the true distance, 1/1.01 % of its own,
    /// wherever it is placed; the true installation drifts none; a blackout's own fixes
    /// place neither end.
    #[test]
    fn a_scale_error_of_one_percent_drifts_one_percent_of_the_distance() {
        let (attitude, time_s, dvl, fixes) = straight();
        let fast: Vec<Vec3> = dvl.iter().map(|v| v.map(|c| 1.01 * c)).collect();
        let pieces = [0..time_s.len()];
        let against = |dvl| AgainstFixes {
            dvl: (&time_s, dvl),
            pieces: &pieces,
            attitude: &attitude,
            fixes: &fixes,
            latency_s: 0.0,
        };
        let none = Installation::default();
        let dive = against(&fast).reckon(&none).dive_drift().unwrap();
        let pct = 1.0 / 1.01;
        assert!((dive.end_pct() - pct).abs() < 1e-9, "{}", dive.end_pct());
        let window = (200.0, 500.0);
        let blackout = (against(&fast).reckon(&none))
            .blackout_drift(window)
            .unwrap();
        assert!((blackout.pct() - pct).abs() < 1e-9, "{}", blackout.pct());
        // The fixes 10 s before 200 s and after 500 s: 11 each, their mean times 195 s
        // and 505 s.
        assert_eq!(blackout.anchored, (11, 11));
        assert!((blackout.from_s - 195.0).abs() < 1e-9 && (blackout.to_s - 505.0).abs() < 1e-9);
        assert!((blackout.distance_m - 1.01 * 1.5 * 310.0).abs() < 1e-6);
        assert!((blackout.error_m() - 0.01 * 1.5 * 310.0).abs() < 1e-6);
        let truth = against(&dvl).reckon(&none).blackout_drift(window).unwrap();
        assert!(truth.error_m() < 1e-9, "{}", truth.error_m());
        assert!((truth.noise_floor_m(2.0) - 2.0 * (4.0f64 / 11.0).sqrt()).abs() < 1e-12);
    }

    /// A blackout across a loss of bottom lock, or past the fixes, is not scored.
    #[test]
    fn a_blackout_across_a_lost_lock_or_beyond_the_fixes_is_refused() {
        let (attitude, time_s, dvl, fixes) = straight();
        let pieces = [0..1000, 1000..time_s.len()];
        let against = AgainstFixes {
            dvl: (&time_s, &dvl),
            pieces: &pieces,
            attitude: &attitude,
            fixes: &fixes,
            latency_s: 0.0,
        };
        let reckoned = against.reckon(&Installation::default());
        assert!(reckoned.blackout_drift((150.0, 250.0)).is_err());
        assert!(reckoned.blackout_drift((210.0, 260.0)).is_ok());
        assert!(reckoned.blackout_drift((500.0, 588.5)).is_err());
        assert_eq!(reckoned.dive_drift().unwrap().spans.len(), 2);
    }

    /// A clock of seconds reads the attitude that far on: the samples are cut about it,
    /// so that a record that reaches the attitude's end is still reckoned whole.
    #[test]
    fn a_clock_of_seconds_still_reckons_the_record_to_the_attitudes_end() {
        let (attitude, _, _, fixes) = straight();
        let time_s: Vec<f64> = (10..=2990).map(|i| i as f64 / 5.0).collect();
        let dvl = vec![[1.5, 0.0, 0.0]; time_s.len()];
        let pieces = [0..time_s.len()];
        let against = AgainstFixes {
            dvl: (&time_s, &dvl),
            pieces: &pieces,
            attitude: &attitude,
            fixes: &fixes,
            latency_s: 0.0,
        };
        let late = Installation {
            time_offset_s: 5.0,
            ..Installation::default()
        };
        let dive = (against.reckon(&late).dive_drift()).expect("the piece reckoned");
        assert!(dive.error_m() < 1e-9, "{}", dive.error_m());
    }
}
