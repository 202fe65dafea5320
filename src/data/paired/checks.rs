//! The plausibility checks of a paired recording, whatever its format: time stamps
//! that go back or repeat in either stream, roll or pitch out of range, a velocity
//! beyond a vehicle's, a body rate or an attitude jump beyond a vehicle's turn, a DVL
//! and a reference that never overlap in time, fewer than [`MIN_SAMPLES`] valid DVL
//! samples. The DVL's samples it did not measure (lost bottom lock: no velocity, the
//! invalid marker, 0, 0, 0, or its validity flag down) are left out, each with its
//! reason, never repaired. They run on the samples a format read, and name where a
//! faulty sample came from through a [`Locator`] (a CSV file's line today).
//! In: the [`Unchecked`] samples and their [`Locator`]. Out: the [`PairedRecording`],
//! angles in radians, or the first fault as a [`PairedError`].

use super::{
    GAP_MARGIN_S, GapLimit, INVALID_MARKER_M_S, LeftOut, LeftOutWhy, MAX_BODY_RATE_RAD_S,
    MAX_DVL_SPEED_M_S, MIN_KEPT_SHARE, MIN_SAMPLES, PairedColumns, PairedError, PairedRecording,
    REFERENCE_GAP_INTERVALS, default_gap_limit_s, sample_interval,
};
use crate::Vec3;
use crate::data::local_plane::off_the_globe;
use crate::data::nmea::reference::SentencesRead;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// The samples as a format gives them, before any check: the DVL's and the
/// reference's, each on its own time stamps (their counts may differ), the angles (and
/// the rate) in the unit recorded.
#[derive(Debug, Clone, PartialEq)]
pub struct Unchecked {
    pub dvl_time_s: Vec<f64>,
    /// The DVL's body-frame velocity, m/s; NaN where it has none.
    pub dvl_m_s: Vec<Vec3>,
    /// Why the recording states a DVL sample is not a measurement, per sample, where it
    /// states it: a validity flag down, or what a DVL's own log says of the ping.
    pub dvl_stated: Option<Vec<Option<LeftOutWhy>>>,
    pub reference_time_s: Vec<f64>,
    /// The reference's north, east, down velocity, m/s.
    pub velocity_ned_m_s: Vec<Vec3>,
    /// Roll, pitch, yaw, in degrees where `angles_in_degrees`, radians otherwise.
    pub attitude: Vec<Vec3>,
    /// The body angular rate, in deg/s where `angles_in_degrees`, rad/s otherwise.
    pub rate: Option<Vec<Vec3>>,
    pub angles_in_degrees: bool,
    /// The reference's position where it records one, and whether it is latitude and
    /// longitude (in the angles' unit) rather than north and east in metres.
    pub position: Option<(Vec<[f64; 2]>, bool)>,
    /// What an NMEA reference gave, and left out ([`crate::data::nmea::reference`]).
    pub reference_read: Option<SentencesRead>,
}

impl Unchecked {
    /// The factor from the recorded angle unit to radians.
    fn to_rad(&self) -> f64 {
        if self.angles_in_degrees {
            1f64.to_radians()
        } else {
            1.0
        }
    }

    /// Why the DVL sample `row` is left out, if it is: its validity flag down, no
    /// velocity, the invalid marker on an axis, or exactly 0, 0, 0 (unless zero is a
    /// valid reading here).
    fn invalid(&self, row: usize, zero_is_valid: bool) -> Option<LeftOutWhy> {
        let velocity = self.dvl_m_s[row];
        if let Some(why) = self.dvl_stated.as_ref().and_then(|stated| stated[row]) {
            Some(why)
        } else if velocity.iter().any(|v| v.is_nan()) {
            Some(LeftOutWhy::NoVelocity)
        } else if velocity.contains(&INVALID_MARKER_M_S) {
            Some(LeftOutWhy::Marker)
        } else if !zero_is_valid && velocity == [0.0; 3] {
            Some(LeftOutWhy::AllZero)
        } else {
            None
        }
    }

    /// The recording, angles (and the rate) in radians: the DVL's valid samples on its
    /// stamps, the reference on its own, and the DVL's invalid samples left out, each
    /// with its stamp, its line and why.
    fn into_recording(self, at: &Locator) -> PairedRecording {
        let to_rad = self.to_rad();
        let (mut time_s, mut dvl_m_s, mut left_out) = (Vec::new(), Vec::new(), Vec::new());
        let longest_gap_s = REFERENCE_GAP_INTERVALS * sample_interval(&self.reference_time_s);
        for row in 0..self.dvl_time_s.len() {
            let stamp = self.dvl_time_s[row];
            let why = self.invalid(row, at.names.zero_is_valid).or_else(|| {
                beside_a_gap(&self.reference_time_s, longest_gap_s, stamp)
                    .then_some(LeftOutWhy::ReferenceGap)
            });
            match why {
                Some(why) => left_out.push(LeftOut {
                    time_s: stamp,
                    line: at.dvl_lines[row],
                    why,
                }),
                None => {
                    time_s.push(stamp);
                    dvl_m_s.push(self.dvl_m_s[row]);
                }
            }
        }
        let scaled = |values: Vec<Vec3>| -> Vec<Vec3> {
            values
                .into_iter()
                .map(|[a, b, c]| [a * to_rad, b * to_rad, c * to_rad])
                .collect()
        };
        let position_ne_m = self.position.map(|(values, geographic)| {
            if !geographic {
                return values;
            }
            let radians: Vec<[f64; 2]> = values.iter().map(|p| p.map(|v| v * to_rad)).collect();
            crate::data::local_plane::north_east_m(radians[0], &radians)
        });
        PairedRecording {
            time_s,
            dvl_m_s,
            left_out,
            position_ne_m,
            reference_time_s: self.reference_time_s,
            velocity_ned_m_s: self.velocity_ned_m_s,
            attitude_rad: scaled(self.attitude),
            rate_rad_s: self.rate.map(scaled),
            gap_limit_s: (at.names.gap_limit_s)
                .map_or_else(|| default_gap_limit_s(&self.dvl_time_s), |limit| limit.0),
            reference_read: self.reference_read,
        }
    }
}

/// Whether `stamp_s` lies within [`GAP_MARGIN_S`] of a gap longer than `longest_s`
/// in the reference stamped `reference_s`.
fn beside_a_gap(reference_s: &[f64], longest_s: f64, stamp_s: f64) -> bool {
    // The reference samples up to GAP_MARGIN_S either side of the stamp.
    let first = reference_s.partition_point(|&t| t < stamp_s - GAP_MARGIN_S);
    let last = reference_s.partition_point(|&t| t <= stamp_s + GAP_MARGIN_S);
    let (from, to) = (first.saturating_sub(1), (last + 1).min(reference_s.len()));
    reference_s[from..to].windows(2).any(|pair| {
        pair[1] - pair[0] > longest_s
            && pair[0] < stamp_s + GAP_MARGIN_S
            && pair[1] > stamp_s - GAP_MARGIN_S
    })
}

/// Where each sample came from: the DVL's file and the reference's (one path when one
/// file holds both), each sample's line there (a CSV file's line, the header line 1;
/// another format would give its message's place), and the name each quantity has
/// there.
#[derive(Debug, Clone, PartialEq)]
pub struct Locator {
    pub dvl: PathBuf,
    pub reference: PathBuf,
    pub dvl_lines: Vec<u64>,
    pub reference_lines: Vec<u64>,
    pub names: PairedColumns,
}

/// Checks `samples`, each fault placed by `at`, and gives the recording they make.
pub fn check(samples: Unchecked, at: &Locator) -> Result<PairedRecording, PairedError> {
    if let Some(GapLimit(limit_s)) = at.names.gap_limit_s
        && !(limit_s > 0.0 && limit_s.is_finite())
    {
        return Err(PairedError::GapLimit {
            path: at.dvl.clone(),
            limit_s,
        });
    }
    let time = &at.names.time;
    check_increasing(&at.dvl, time, &samples.dvl_time_s, &at.dvl_lines)?;
    // In one file the reference's stamps are the DVL's, already checked.
    check_increasing(
        &at.reference,
        time,
        &samples.reference_time_s,
        &at.reference_lines,
    )?;
    check_attitude(&samples, at)?;
    check_on_the_globe(&samples, at)?;
    check_reference_motion(&samples, at)?;
    for (path, samples) in [
        (&at.dvl, samples.dvl_time_s.len()),
        (&at.reference, samples.reference_time_s.len()),
    ] {
        if samples < MIN_SAMPLES {
            return Err(PairedError::TooShort {
                path: path.clone(),
                samples,
            });
        }
    }
    check_overlap(&samples, at)?;
    check_dvl_speed(&samples, at)?;
    let recording = samples.into_recording(at);
    let counts = recording.counts();
    if counts.kept < MIN_SAMPLES {
        return Err(PairedError::TooFewValid {
            path: at.dvl.clone(),
            counts,
        });
    }
    if (counts.kept as f64) < MIN_KEPT_SHARE * counts.read() as f64 {
        return Err(PairedError::MostlyLeftOut {
            path: at.dvl.clone(),
            counts,
        });
    }
    Ok(recording)
}

/// Every time stamp of `time_s` after the one before it.
fn check_increasing(
    path: &Path,
    column: &str,
    time_s: &[f64],
    lines: &[u64],
) -> Result<(), PairedError> {
    for row in 1..time_s.len() {
        let (previous_s, now_s) = (time_s[row - 1], time_s[row]);
        if now_s <= previous_s {
            return Err(PairedError::TimeNotIncreasing {
                path: path.to_path_buf(),
                line: lines[row],
                column: column.to_string(),
                time_s: now_s,
                previous_line: lines[row - 1],
                previous_s,
            });
        }
    }
    Ok(())
}

/// Roll and pitch within their ranges, [-π, π] and [-π/2, π/2] in radians, or the same
/// in degrees; yaw may run on beyond a turn (an unwrapped heading), its jumps are
/// checked with the reference's motion.
fn check_attitude(samples: &Unchecked, at: &Locator) -> Result<(), PairedError> {
    let degrees = samples.angles_in_degrees;
    for (row, angles) in samples.attitude.iter().enumerate() {
        for (angle, &value) in angles[..2].iter().enumerate() {
            let bound = if degrees {
                [180.0, 90.0, 360.0][angle]
            } else {
                [PI, PI / 2.0, 2.0 * PI][angle]
            };
            if value.abs() > bound {
                return Err(PairedError::AttitudeOutOfRange {
                    path: at.reference.clone(),
                    line: at.reference_lines[row],
                    column: at.names.attitude[angle].clone(),
                    angle,
                    value,
                    degrees,
                });
            }
        }
    }
    Ok(())
}

/// A latitude within ±90° and a longitude within −180° to 360°, where the position is
/// geographic ([`off_the_globe`]).
fn check_on_the_globe(samples: &Unchecked, at: &Locator) -> Result<(), PairedError> {
    let (Some((values, true)), Some((names, _))) = (&samples.position, at.names.position()) else {
        return Ok(());
    };
    match off_the_globe(values, samples.angles_in_degrees) {
        Some((row, axis)) => Err(PairedError::OffTheGlobe {
            path: at.reference.clone(),
            line: at.reference_lines[row],
            column: names[axis].clone(),
            value: values[row][axis],
            degrees: samples.angles_in_degrees,
            longitude: axis == 1,
        }),
        None => Ok(()),
    }
}

/// The reference's velocity within [`MAX_DVL_SPEED_M_S`], its recorded body rate
/// within [`MAX_BODY_RATE_RAD_S`], and its attitude turning no faster than that between
/// two samples (each angle's change taken the short way round).
fn check_reference_motion(samples: &Unchecked, at: &Locator) -> Result<(), PairedError> {
    let to_rad = samples.to_rad();
    let path = || at.reference.clone();
    for row in 0..samples.reference_time_s.len() {
        let line = at.reference_lines[row];
        for axis in 0..3 {
            // An attitude alone has no velocity.
            let value = samples.velocity_ned_m_s.get(row).map_or(0.0, |v| v[axis]);
            if value.abs() > MAX_DVL_SPEED_M_S {
                return Err(PairedError::ReferenceOutOfRange {
                    path: path(),
                    line,
                    column: at.names.velocity_ned[axis].clone(),
                    value,
                });
            }
            if let (Some(rate), Some(names)) = (&samples.rate, &at.names.rate)
                && (rate[row][axis] * to_rad).abs() > MAX_BODY_RATE_RAD_S
            {
                return Err(PairedError::RateOutOfRange {
                    path: path(),
                    line,
                    column: names[axis].clone(),
                    value: rate[row][axis],
                });
            }
        }
        if row > 0 {
            check_turn(samples, at, row)?;
        }
    }
    Ok(())
}

/// The attitude of sample `row` against the one before it: no angle turning faster
/// than [`MAX_BODY_RATE_RAD_S`] between them, taken the short way round.
fn check_turn(samples: &Unchecked, at: &Locator, row: usize) -> Result<(), PairedError> {
    let to_rad = samples.to_rad();
    let time_s = &samples.reference_time_s;
    let dt_s = time_s[row] - time_s[row - 1];
    let (now, before) = (samples.attitude[row], samples.attitude[row - 1]);
    for axis in 0..3 {
        let (value, previous) = (now[axis], before[axis]);
        let change = ((value - previous) * to_rad + PI).rem_euclid(2.0 * PI) - PI;
        let rate_rad_s = change.abs() / dt_s;
        if rate_rad_s > MAX_BODY_RATE_RAD_S {
            return Err(PairedError::AttitudeJump {
                path: at.reference.clone(),
                line: at.reference_lines[row],
                previous_line: at.reference_lines[row - 1],
                column: at.names.attitude[axis].clone(),
                value,
                previous,
                dt_s,
                rate_rad_s,
                degrees: samples.angles_in_degrees,
            });
        }
    }
    Ok(())
}

/// The DVL's stamps and the reference's overlapping in time: each stream is on its own
/// clock and at its own rate, but a DVL whose samples all lie outside the reference's
/// span has nothing to be calibrated against.
fn check_overlap(samples: &Unchecked, at: &Locator) -> Result<(), PairedError> {
    let (dvl, reference) = (&samples.dvl_time_s, &samples.reference_time_s);
    let span = |time: &[f64]| (time[0], time[time.len() - 1]);
    let (dvl_span, reference_span) = (span(dvl), span(reference));
    if dvl_span.1 < reference_span.0 || reference_span.1 < dvl_span.0 {
        return Err(PairedError::NoOverlap {
            dvl: at.dvl.clone(),
            dvl_span_s: dvl_span,
            reference: at.reference.clone(),
            reference_span_s: reference_span,
        });
    }
    Ok(())
}

/// Every DVL velocity component within [`MAX_DVL_SPEED_M_S`], but for the invalid
/// marker and a missing velocity, which leave their sample out.
fn check_dvl_speed(samples: &Unchecked, at: &Locator) -> Result<(), PairedError> {
    for (row, velocity) in samples.dvl_m_s.iter().enumerate() {
        for (axis, &value) in velocity.iter().enumerate() {
            if value.abs() > MAX_DVL_SPEED_M_S && value != INVALID_MARKER_M_S {
                return Err(PairedError::DvlOutOfRange {
                    path: at.dvl.clone(),
                    line: at.dvl_lines[row],
                    column: at.names.dvl[axis].clone(),
                    value,
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three samples of a recording in no file, placed at made-up lines.
    fn samples() -> (Unchecked, Locator) {
        let samples = Unchecked {
            dvl_time_s: vec![0.0, 1.0, 2.0],
            dvl_m_s: vec![[1.0, 0.0, 0.0]; 3],
            dvl_stated: None,
            reference_time_s: vec![0.0, 1.0, 2.0],
            velocity_ned_m_s: vec![[1.0, 0.0, 0.0]; 3],
            attitude: vec![[0.0, 0.0, 90.0], [0.0, 0.0, 100.0], [0.0, 0.0, 110.0]],
            rate: None,
            angles_in_degrees: true,
            position: None,
            reference_read: None,
        };
        let names = |names: [&str; 3]| names.map(String::from);
        let at = Locator {
            dvl: "message.bag".into(),
            reference: "message.bag".into(),
            dvl_lines: vec![10, 20, 30],
            reference_lines: vec![11, 21, 31],
            names: PairedColumns {
                time: "stamp".into(),
                dvl: names(["vx", "vy", "vz"]),
                velocity_ned: names(["n", "e", "d"]),
                attitude: names(["roll", "pitch", "heading"]),
                rate: None,
                angles_in_degrees: true,
                valid: None,
                zero_is_valid: false,
                gap_limit_s: None,
                latitude_longitude: None,
                north_east: None,
            },
        };
        (samples, at)
    }

    /// The checks place a fault through the locator alone, whatever the samples came
    /// from; angles come out in radians.
    #[test]
    fn a_fault_is_placed_by_the_locator_and_angles_come_out_in_radians() {
        let (good, at) = samples();
        let recording = check(good.clone(), &at).unwrap();
        assert_eq!(recording.attitude_rad[1][2], 100.0 * 1f64.to_radians());
        assert_eq!(recording.time_s, good.dvl_time_s);
        let mut fast = good.clone();
        fast.dvl_m_s[2][1] = 25.0;
        assert_eq!(
            check(fast, &at).unwrap_err().to_string(),
            "message.bag:30: vy: 25 m/s is beyond 20 m/s, faster than any vehicle a DVL rides: another vendor's bad-velocity marker or a unit other than m/s; mark the sample invalid (an empty cell, or the validity column) or give the velocity in m/s"
        );
        let mut back = good;
        back.reference_time_s[2] = 0.5;
        assert_eq!(
            check(back, &at).unwrap_err().to_string(),
            "message.bag:31: stamp: 0.5 s follows 1 s of line 21: time stamps must increase"
        );
    }
}
