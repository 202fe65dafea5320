//! Dead reckoning: the DVL's velocity, corrected by an installation and turned into NED
//! by the attitude, summed over time into a track; and the operator's score of a
//! calibration, the track's drift from the reference's positions as a percentage of
//! the distance travelled.
//! In: an installation, a piece of DVL samples, an [`Attitude`]. Out: a [`Track`] of
//! the reference point; against the reference's positions, a [`Reckoning`]: each piece
//! placed on them, and the [`Drift`].
//!
//! The DVL sample stamped t measured at t + τ; corrected, u = R(δ)ᵀ(I + S)⁻¹(v − b) is
//! the velocity of the DVL's own point in body axes. The DVL's point moves at C_b^n u,
//! summed by the trapezoidal rule between two samples of a piece; the reference point
//! (where the fixes or the reference's positions are) lies at p_DVL − C_b^n l. The
//! lever arm's part is thereby exact: the ω × l the velocity correction removes
//! integrates to C_b^n l.

use crate::Vec3;
use crate::data::interpolate::Between;
use crate::data::paired::{GAP_MARGIN_S, PairedRecording};
use crate::installation::frames::{Attitude, Mat3, apply};
use crate::installation::terms::Installation;
use std::ops::Range;
use std::sync::{Arc, Mutex};

/// The reference point's track of one piece: at each DVL sample's t + τ, its position,
/// metres north, east and down of the DVL's point at the piece's first sample.
#[derive(Debug, Clone, PartialEq)]
pub struct Track {
    pub time_s: Vec<f64>,
    pub position_m: Vec<Vec3>,
}

impl Track {
    /// The position at `time_s`, linearly interpolated between two samples (exact at
    /// one); `None` outside the track.
    pub fn at(&self, time_s: f64) -> Option<Vec3> {
        Between::locate(&self.time_s, time_s, f64::INFINITY).map(|at| at.of(&self.position_m))
    }
}

/// The track of the DVL samples `dvl` (stamps and velocities of one piece) through
/// `installation`, with `attitude` read at each stamp plus the time offset; `None`
/// where the attitude is not read at one of them.
pub fn dead_reckon(
    installation: &Installation,
    dvl: (&[f64], &[Vec3]),
    attitude: &Attitude,
) -> Option<Track> {
    let body_to_ned = attitude_along(dvl.0, installation.time_offset_s, attitude)?;
    Some(dead_reckon_along(installation, dvl, &body_to_ned))
}

/// C_b^n at each of the stamps `time_s` plus `time_offset_s`, what a dead reckoning
/// reads of the attitude; `None` where it is not read at one of them. A fit that moves
/// every term but the clock reads the same, once.
pub fn attitude_along(
    time_s: &[f64],
    time_offset_s: f64,
    attitude: &Attitude,
) -> Option<Vec<Mat3>> {
    (time_s.iter())
        .map(|&stamp| attitude.body_to_ned_at(stamp + time_offset_s))
        .collect()
}

/// The attitude a fit's dead reckonings read along each piece of a DVL record (C_b^n
/// at each sample's stamp plus the clock, [`attitude_along`]), kept for the last
/// [`Self::KEPT`] clocks: a Jacobian's columns other than the clock's, and every step
/// of a scan's trial at one clock, read it at the same times, and reading it
/// (interpolating and turning angles into a matrix) was three quarters of a fit to
/// fixes' time.
#[derive(Default)]
pub struct AttitudeRead {
    /// The clock's bits, and the attitude along each piece.
    kept: Mutex<Vec<(u64, AttitudeAlong)>>,
}

/// C_b^n at each DVL sample of each piece, shared by the fits that read it.
pub type AttitudeAlong = Arc<Vec<Vec<Mat3>>>;

impl AttitudeRead {
    /// The clock, and the clock moved either way by a Jacobian's step.
    const KEPT: usize = 3;

    /// The attitude along each of `pieces` of the DVL's stamps `time_s` at
    /// `time_offset_s`, read where it is not kept; `None` where it is not read at one
    /// of them.
    pub fn along(
        &self,
        (time_s, pieces): (&[f64], &[Range<usize>]),
        time_offset_s: f64,
        attitude: &Attitude,
    ) -> Option<AttitudeAlong> {
        let bits = time_offset_s.to_bits();
        let mut kept = self.kept.lock().expect("the attitude read, not poisoned");
        if let Some(k) = kept.iter().position(|(b, _)| *b == bits) {
            let found = kept.remove(k);
            kept.push(found.clone());
            return Some(found.1);
        }
        // The oldest let go first: no more than KEPT are ever held.
        if kept.len() == Self::KEPT {
            kept.remove(0);
        }
        let along: Option<Vec<Vec<Mat3>>> = (pieces.iter())
            .map(|piece| attitude_along(&time_s[piece.clone()], time_offset_s, attitude))
            .collect();
        let along = Arc::new(along?);
        kept.push((bits, along.clone()));
        Some(along)
    }
}

/// [`dead_reckon`] with the attitude read already: `body_to_ned[i]` at stamp i plus
/// the installation's time offset ([`attitude_along`]).
pub fn dead_reckon_along(
    installation: &Installation,
    (time_s, dvl_m_s): (&[f64], &[Vec3]),
    body_to_ned: &[Mat3],
) -> Track {
    let mut track = Track {
        time_s: Vec::with_capacity(time_s.len()),
        position_m: Vec::with_capacity(time_s.len()),
    };
    let (mut dvl_point, mut previous) = ([0.0; 3], None::<(f64, Vec3)>);
    for ((&stamp, &dvl), body_to_ned) in time_s.iter().zip(dvl_m_s).zip(body_to_ned) {
        let t = stamp + installation.time_offset_s;
        let velocity = apply(body_to_ned, installation.correct(dvl, [0.0; 3]));
        if let Some((before_s, before)) = previous {
            let dt = t - before_s;
            dvl_point = [0, 1, 2].map(|k| dvl_point[k] + 0.5 * dt * (before[k] + velocity[k]));
        }
        let lever = apply(body_to_ned, installation.lever_arm_m);
        track.time_s.push(t);
        track
            .position_m
            .push([0, 1, 2].map(|k| dvl_point[k] - lever[k]));
        previous = Some((t, velocity));
    }
    track
}

/// A dead reckoning's horizontal error against the reference's positions, as a share
/// of the distance travelled: over every sample of every piece, the RMS of the error
/// over its piece's distance, and the error at each piece's end over its distance
/// (pieces summed), both in %; the distance, m, and the samples scored.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drift {
    pub rms_pct: f64,
    pub end_pct: f64,
    pub distance_m: f64,
    pub samples: usize,
}

impl Drift {
    /// The pieces' end errors summed over `distance_m` instead of their own distance, %:
    /// a dead reckoning on another clock, over the distance the one it is set beside
    /// travelled.
    pub fn end_pct_of(&self, distance_m: f64) -> f64 {
        self.end_pct * self.distance_m / distance_m
    }
}

/// The reference's horizontal positions on their stamps, read at any time.
pub struct Positions<'a> {
    pub time_s: &'a [f64],
    pub north_east_m: &'a [[f64; 2]],
}

impl Positions<'_> {
    /// The position at `time_s`, linearly interpolated; `None` outside.
    pub fn at(&self, time_s: f64) -> Option<[f64; 2]> {
        Between::locate(self.time_s, time_s, f64::INFINITY).map(|at| at.of(self.north_east_m))
    }
}

/// One piece's dead reckoning in plan view, placed on the reference's position at its
/// first sample, beside the reference's positions at the same times: north and east, m.
#[derive(Debug, Clone, PartialEq)]
pub struct PlacedPiece {
    pub reckoned_ne_m: Vec<[f64; 2]>,
    pub reference_ne_m: Vec<[f64; 2]>,
}

impl PlacedPiece {
    /// The horizontal error of the dead reckoning at each sample, m.
    pub fn errors_m(&self) -> impl Iterator<Item = f64> + '_ {
        (self.reckoned_ne_m.iter().zip(&self.reference_ne_m))
            .map(|(p, r)| (p[0] - r[0]).hypot(p[1] - r[1]))
    }

    /// The horizontal error at the piece's end, m.
    pub fn end_error_m(&self) -> f64 {
        self.errors_m().last().unwrap_or(0.0)
    }

    /// How far the reference travelled along the piece, horizontally, m.
    pub fn travelled_m(&self) -> f64 {
        path_length_m(&self.reference_ne_m)
    }
}

/// A dead reckoning scored against the reference's positions: its [`Drift`], and the
/// pieces it is the drift of.
#[derive(Debug, Clone, PartialEq)]
pub struct Reckoning {
    pub drift: Drift,
    pub pieces: Vec<PlacedPiece>,
}

/// The horizontal length of the path through `points` (north and east first), m.
pub fn path_length_m<P: AsRef<[f64]>>(points: &[P]) -> f64 {
    (points.windows(2))
        .map(|pair| {
            let (a, b) = (pair[0].as_ref(), pair[1].as_ref());
            (b[0] - a[0]).hypot(b[1] - a[1])
        })
        .sum()
}

/// The dead reckonings of `installations` over the `pieces` of the DVL record `dvl`
/// against `positions`, each piece started at the reference's position (at the first
/// sample's t + τ, each on its own clock): `None` where no piece could be scored (the
/// attitude or the positions not read over it, or a vehicle that did not move). Every
/// installation is scored on the same samples and pieces: those whose t lies inside
/// the attitude within ±[`GAP_MARGIN_S`] (so that any τ within it reads the attitude,
/// and methods compared are scored alike) and whose t + τ does for each installation's
/// clock (a clock found seconds away, which `correct` searches for), a piece left out
/// for all where one of them cannot reckon it.
pub fn reckon_alike<const N: usize>(
    installations: [&Installation; N],
    (time_s, dvl_m_s): (&[f64], &[Vec3]),
    pieces: &[Range<usize>],
    attitude: &Attitude,
    positions: &Positions,
) -> Option<[Reckoning; N]> {
    let inside = (installations.iter()).fold(interior(attitude, time_s, 0.0), |inside, i| {
        let read = within(attitude, time_s, (i.time_offset_s, 0.0));
        inside.start.max(read.start)..inside.end.min(read.end)
    });
    let mut placed: [Vec<PlacedPiece>; N] = std::array::from_fn(|_| Vec::new());
    for piece in pieces {
        let piece = piece.start.max(inside.start)..piece.end.min(inside.end);
        let dvl = (&time_s[piece.clone()], &dvl_m_s[piece]);
        let each: Option<Vec<PlacedPiece>> = (installations.iter())
            .map(|installation| place(&dead_reckon(installation, dvl, attitude)?, positions))
            .collect();
        for (k, piece) in each.into_iter().flatten().enumerate() {
            placed[k].push(piece);
        }
    }
    let reckonings = placed.map(|pieces| {
        let drift = drift_over(&pieces);
        drift.map(|drift| Reckoning { drift, pieces })
    });
    reckonings
        .into_iter()
        .collect::<Option<Vec<_>>>()?
        .try_into()
        .ok()
}

/// `track` placed on `positions` at its first sample, beside them at each of its
/// samples; `None` where the positions are not read at one of them, or the reference
/// did not move.
fn place(track: &Track, positions: &Positions) -> Option<PlacedPiece> {
    let reference: Vec<[f64; 2]> = (track.time_s.iter())
        .map(|&t| positions.at(t))
        .collect::<Option<_>>()?;
    if reference.len() < 2 || path_length_m(&reference) <= 0.0 {
        return None;
    }
    let start = [0, 1].map(|k| reference[0][k] - track.position_m[0][k]);
    Some(PlacedPiece {
        reckoned_ne_m: (track.position_m.iter())
            .map(|p| [p[0] + start[0], p[1] + start[1]])
            .collect(),
        reference_ne_m: reference,
    })
}

/// The drift of the placed `pieces`: over every sample, the RMS of the error over its
/// piece's distance, and the pieces' end errors summed over their distances; `None`
/// with no piece.
fn drift_over(pieces: &[PlacedPiece]) -> Option<Drift> {
    let (mut squares, mut samples, mut end_error_m, mut distance_m) = (0.0, 0, 0.0, 0.0);
    for piece in pieces {
        let travelled = piece.travelled_m();
        squares += piece
            .errors_m()
            .map(|e| (e / travelled).powi(2))
            .sum::<f64>();
        samples += piece.reckoned_ne_m.len();
        end_error_m += piece.end_error_m();
        distance_m += travelled;
    }
    (samples > 0).then(|| Drift {
        rms_pct: 100.0 * (squares / samples as f64).sqrt(),
        end_pct: 100.0 * end_error_m / distance_m,
        distance_m,
        samples,
    })
}

/// The dead reckonings of `installations` over `recording` against its reference's
/// positions, where it records them, scored alike ([`reckon_alike`]).
pub fn reckonings_of<const N: usize>(
    installations: [&Installation; N],
    recording: &PairedRecording,
) -> Option<[Reckoning; N]> {
    let positions = Positions {
        time_s: &recording.reference_time_s,
        north_east_m: recording.position_ne_m.as_deref()?,
    };
    reckon_alike(
        installations,
        (&recording.time_s, &recording.dvl_m_s),
        &recording.pieces(),
        &Attitude::of(recording),
        &positions,
    )
}

/// The drift of `installation` over `recording` against its reference's positions
/// ([`reckonings_of`]).
pub fn drift_of(installation: &Installation, recording: &PairedRecording) -> Option<Drift> {
    reckonings_of([installation], recording).map(|[r]| r.drift)
}

/// The samples stamped `time_s` whose t + τ lies inside `attitude`'s span for every τ
/// within [`GAP_MARGIN_S`] of `centre_s` (empty where none does).
pub fn interior(attitude: &Attitude, time_s: &[f64], centre_s: f64) -> Range<usize> {
    within(attitude, time_s, (centre_s, GAP_MARGIN_S))
}

/// The samples stamped `time_s` whose t + τ lies inside `attitude`'s span for every τ
/// within `margin_s` of `centre_s` (empty where none does).
fn within(attitude: &Attitude, time_s: &[f64], (centre_s, margin_s): (f64, f64)) -> Range<usize> {
    let (Some(&first), Some(&last)) = (attitude.time_s.first(), attitude.time_s.last()) else {
        return 0..0;
    };
    let start = time_s.partition_point(|&t| t + centre_s - margin_s < first);
    let end = time_s.partition_point(|&t| t + centre_s + margin_s <= last);
    start..end.max(start)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A turning attitude at 10 Hz over 60 s, and a DVL at 2 Hz in two pieces.
    fn turning() -> (Attitude, Vec<f64>, Vec<Vec3>, Vec<Range<usize>>) {
        let attitude_s: Vec<f64> = (0..=600).map(|i| i as f64 / 10.0).collect();
        let angles: Vec<Vec3> = (attitude_s.iter())
            .map(|t| [0.02 * t.sin(), -0.01, 0.05 * t])
            .collect();
        let time_s: Vec<f64> = (4..=110).map(|i| i as f64 / 2.0).collect();
        let dvl = (time_s.iter()).map(|t| [1.5, 0.1 * t.cos(), 0.0]).collect();
        let pieces = vec![0..50, 50..time_s.len()];
        (Attitude::new(&attitude_s, &angles), time_s, dvl, pieces)
    }

    /// A circle at 1.5 m/s turning 0.05 rad/s, the DVL 1 % fast: with no terms, each
    /// position is 1.01 times its displacement from the start, so the end error is 1 %
    /// of the chord, 2R sin(ωT/2), over the arc ωRT travelled (0.665 % over 60 s), the
    /// end placed there; with the scale applied, under 0.001 % (the sampling's own).
    #[test]
    fn a_fast_dvl_drifts_its_share_of_the_chord_over_the_arc() {
        let (speed, rate) = (1.5, 0.05);
        let radius = speed / rate;
        let on_circle = |t: f64| [radius * (rate * t).sin(), radius * (1.0 - (rate * t).cos())];
        let reference_s: Vec<f64> = (0..=700).map(|i| i as f64 / 10.0).collect();
        let angles: Vec<Vec3> = reference_s.iter().map(|t| [0.0, 0.0, rate * t]).collect();
        let attitude = Attitude::new(&reference_s, &angles);
        let north_east: Vec<[f64; 2]> = reference_s.iter().map(|&t| on_circle(t)).collect();
        let positions = Positions {
            time_s: &reference_s,
            north_east_m: &north_east,
        };
        let time_s: Vec<f64> = (50..=650).map(|i| i as f64 / 10.0).collect();
        let dvl: Vec<Vec3> = vec![[1.01 * speed, 0.0, 0.0]; time_s.len()];
        let pieces = [0..time_s.len()];
        let reckon = |installation: &Installation| {
            let [reckoning] = reckon_alike(
                [installation],
                (&time_s, &dvl),
                &pieces,
                &attitude,
                &positions,
            )
            .unwrap();
            reckoning
        };
        let none = reckon(&Installation::default());
        let arc_m = speed * 60.0;
        let chord_m = 2.0 * radius * (rate * 60.0 / 2.0).sin();
        assert!(
            (none.drift.distance_m - arc_m).abs() < 1e-3,
            "{:?}",
            none.drift
        );
        assert!(
            (none.drift.end_pct - chord_m / arc_m).abs() < 1e-3,
            "{:?}",
            none.drift
        );
        assert_eq!(none.drift.samples, time_s.len());
        let piece = &none.pieces[0];
        assert_eq!(piece.reference_ne_m[0], piece.reckoned_ne_m[0]);
        let start = on_circle(5.0);
        let end = on_circle(65.0);
        let last = piece.reckoned_ne_m[time_s.len() - 1];
        let expected = [0, 1].map(|k| start[k] + 1.01 * (end[k] - start[k]));
        assert!(
            (last[0] - expected[0]).hypot(last[1] - expected[1]) < 1e-3,
            "{last:?}"
        );
        let scaled = Installation {
            scale: [0.01; 3],
            ..Installation::default()
        };
        let fitted = reckon(&scaled).drift;
        assert!(fitted.end_pct < 1e-3 && fitted.rms_pct < 1e-3, "{fitted:?}");
    }

    #[test]
    fn the_attitude_kept_gives_the_tracks_read_afresh_at_every_clock() {
        let (attitude, time_s, dvl, pieces) = turning();
        let read = AttitudeRead::default();
        // Four clocks, the first again after the fourth evicted it, then the last kept.
        for time_offset_s in [0.3, 0.301, 0.299, -1.0, 0.3, -1.0] {
            let installation = Installation {
                scale: [0.01; 3],
                misalignment_rad: [0.0, 0.0, 0.02],
                lever_arm_m: [0.8, -0.5, 0.1],
                time_offset_s,
                bias_m_s: [0.0; 3],
            };
            let along = read
                .along((&time_s, &pieces), time_offset_s, &attitude)
                .unwrap();
            for (piece, body_to_ned) in pieces.iter().zip(along.iter()) {
                let dvl = (&time_s[piece.clone()], &dvl[piece.clone()]);
                let afresh = dead_reckon(&installation, dvl, &attitude).unwrap();
                assert_eq!(dead_reckon_along(&installation, dvl, body_to_ned), afresh);
            }
            assert!(read.kept.lock().unwrap().len() <= AttitudeRead::KEPT);
        }
        // A clock that reads past the attitude's end reads nothing, and keeps nothing.
        assert!(read.along((&time_s, &pieces), 10.0, &attitude).is_none());
        assert!(
            !read
                .kept
                .lock()
                .unwrap()
                .iter()
                .any(|(b, _)| *b == 10f64.to_bits())
        );
    }
}
