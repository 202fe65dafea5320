//! NMEA-0183 sentences as a recording's reference. The attitude is PASHR's (the
//! sentence of Ashtech, NovAtel SPAN and ArduPilot: its own UTC time of day, heading
//! true, roll and pitch in degrees, roll positive starboard down and pitch bow up, as
//! the body axes forward, starboard, down have them), each dated by the last RMC or
//! ZDA before it. Where a velocity is asked for (`--reference`, a surface vehicle's),
//! it is the ground velocity of each RMC (speed over ground in knots, course over
//! ground true), beside the PASHR of its time (within [`ATTITUDE_WITHIN_S`]: none is
//! interpolated), its down velocity zero: RMC gives none, and a vehicle at the surface
//! has none but its heave. Where only an attitude is asked for (`--attitude`, beside
//! position fixes), the reference is the PASHR sentences themselves.
//! Every sentence is counted once ([`SentencesRead`]): as a sample kept, as one that
//! served the samples (a date, an RMC's attitude), as left out by its reason (never
//! repaired), or as passed over; one without a checksum is read as written and counted
//! as unchecked besides.
//! In: an NMEA file's path and bytes. Out: the [`NmeaReference`]: its samples, the line
//! of each, and what was read.

use super::{NmeaError, checksum, date_time_s, on_the_day_of, with_checksum};
use std::path::Path;

/// A knot, m/s.
const KNOT_M_S: f64 = 1852.0 / 3600.0;

/// How far from an RMC's time a PASHR may be to give its attitude, s.
pub const ATTITUDE_WITHIN_S: f64 = 0.05;

/// What an NMEA file gave as a reference: the samples kept and what they are, the
/// sentences that served them (RMC or ZDA for the date; PASHR for an RMC's attitude),
/// the PASHR no RMC took (with a velocity asked for), those left out by reason, those
/// read without a checksum, and how many sentences of other types were passed over.
/// Every sentence is in one of `kept`, `served`, `not_taken`, `left_out` and
/// `passed_over`.
#[derive(Debug, Clone, PartialEq)]
pub struct SentencesRead {
    pub kept: usize,
    pub what: &'static str,
    pub served: usize,
    pub not_taken: usize,
    pub left_out: Vec<(&'static str, usize)>,
    pub unchecked: usize,
    pub passed_over: usize,
}

impl std::fmt::Display for SentencesRead {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let left_out: Vec<String> = (self.left_out.iter())
            .map(|(why, n)| format!("{n} {why}"))
            .collect();
        write!(
            f,
            "{} {}, read from NMEA sentences ({} more that dated them or gave their attitude{}; {} left out{}{}; {} without a checksum, so unchecked; {} other sentences passed over)",
            self.kept,
            self.what,
            self.served,
            match self.not_taken {
                0 => String::new(),
                n => format!(", {n} PASHR no RMC took"),
            },
            self.left_out.iter().map(|(_, n)| n).sum::<usize>(),
            if left_out.is_empty() { "" } else { ": " },
            left_out.join(", "),
            self.unchecked,
            self.passed_over,
        )
    }
}

/// Why a sentence gives no reference sample, nor serves one.
const LEFT_OUT: [&str; 7] = [
    "whose checksum fails or that do not parse",
    "PASHR before any RMC or ZDA gave the date",
    "PASHR with no true heading, roll or pitch",
    "stamped at or before the previous one",
    "RMC with no fix (status V) or no speed or course",
    "RMC with no PASHR within 0.05 s",
    "RMC or ZDA with no date or time",
];

/// A PASHR's attitude: its UTC time (s since 1970) and roll, pitch, heading in degrees.
type Attitude = (f64, [f64; 3]);

/// A reference read from NMEA sentences: each sample's UTC time (s since 1970), north,
/// east, down velocity (m/s; none where only an attitude was asked for), roll, pitch,
/// heading (degrees) and line; and what was read.
#[derive(Debug, Clone, PartialEq)]
pub struct NmeaReference {
    pub time_s: Vec<f64>,
    pub velocity_ned_m_s: Vec<[f64; 3]>,
    pub attitude_deg: Vec<[f64; 3]>,
    pub lines: Vec<u64>,
    pub read: SentencesRead,
}

/// The reference of the NMEA file `path` (its `bytes`): the ground velocity of its RMC
/// sentences beside its PASHR attitude where `with_velocity`, else its PASHR attitude
/// alone.
pub fn parse_reference(
    path: &Path,
    bytes: &[u8],
    with_velocity: bool,
) -> Result<NmeaReference, NmeaError> {
    let mut read = Reading {
        with_velocity,
        ..Reading::default()
    };
    for (k, text) in bytes.split(|&b| b == b'\n').enumerate() {
        read.take(k as u64 + 1, text);
    }
    let (time_s, velocity, attitude, lines, what) = match with_velocity {
        true => {
            let kept = read.velocities();
            let (time_s, rest): (Vec<f64>, Vec<_>) = kept
                .iter()
                .map(|(t, v, a, line)| (*t, (*v, *a, *line)))
                .unzip();
            let velocity = rest.iter().map(|r| r.0).collect();
            let attitude = rest.iter().map(|r| r.1).collect();
            let lines = rest.iter().map(|r| r.2).collect();
            (
                time_s,
                velocity,
                attitude,
                lines,
                "RMC ground velocities beside their PASHR attitude (the down velocity zero)",
            )
        }
        false => {
            let time_s = read.attitudes.iter().map(|a| a.0).collect();
            let attitude = read.attitudes.iter().map(|a| a.1).collect();
            (
                time_s,
                Vec::new(),
                attitude,
                read.attitude_lines.clone(),
                "PASHR attitudes",
            )
        }
    };
    let summary = SentencesRead {
        kept: lines.len(),
        what,
        served: read.served,
        not_taken: read.not_taken,
        left_out: (LEFT_OUT.into_iter().zip(read.counts))
            .filter(|&(_, n)| n > 0)
            .collect(),
        unchecked: read.unchecked,
        passed_over: read.passed_over,
    };
    if lines.is_empty() {
        return Err(NmeaError::NoReference {
            path: path.to_path_buf(),
            read: summary,
        });
    }
    Ok(NmeaReference {
        time_s,
        velocity_ned_m_s: velocity,
        attitude_deg: attitude,
        lines,
        read: summary,
    })
}

/// The sentences of a file as they are read, in order.
#[derive(Default)]
struct Reading {
    /// Whether the samples are RMC's ground velocities (else PASHR's attitudes).
    with_velocity: bool,
    /// The last RMC's or ZDA's date and time, s since 1970 UTC.
    dated_s: Option<f64>,
    attitudes: Vec<Attitude>,
    attitude_lines: Vec<u64>,
    /// Each RMC with a fix: its time, north and east velocity, m/s, and line.
    grounds: Vec<(f64, [f64; 2], u64)>,
    counts: [usize; 7],
    served: usize,
    /// With a velocity asked for, the PASHR no RMC took (a faster AHRS has many).
    not_taken: usize,
    unchecked: usize,
    passed_over: usize,
}

impl Reading {
    /// Reads the sentence `text` of line `line`.
    fn take(&mut self, line: u64, text: &[u8]) {
        let Ok(text) = std::str::from_utf8(text.trim_ascii()) else {
            self.counts[0] += 1;
            return;
        };
        if text.is_empty() {
            return;
        }
        let Some(sentence) = self.checked(text) else {
            self.counts[0] += 1;
            return;
        };
        match sentence.get(1..6) {
            Some("PASHR") => self.attitude(line, &sentence),
            Some(kind) if kind.ends_with("RMC") || kind.ends_with("ZDA") => {
                let dated_s = date_time_s(&sentence);
                self.dated_s = dated_s.or(self.dated_s);
                match dated_s {
                    None => self.counts[6] += 1,
                    Some(time_s) if self.with_velocity && kind.ends_with("RMC") => {
                        self.ground(line, &sentence, time_s)
                    }
                    Some(_) => self.served += 1,
                }
            }
            _ => self.passed_over += 1,
        }
    }

    /// The sentence with its checksum, where it holds; one written without a checksum
    /// is given one and counted as unchecked.
    fn checked(&mut self, text: &str) -> Option<String> {
        let body = text.strip_prefix('$')?;
        match body.split_once('*') {
            Some((body, sum)) => {
                (u8::from_str_radix(sum, 16).ok()? == checksum(body)).then(|| text.to_string())
            }
            None => {
                self.unchecked += 1;
                Some(with_checksum(body))
            }
        }
    }

    /// A PASHR: time of day, heading, `T`, roll, pitch, ...
    fn attitude(&mut self, line: u64, sentence: &str) {
        let Some(dated_s) = self.dated_s else {
            self.counts[1] += 1;
            return;
        };
        let fields: Vec<&str> = sentence.split(['*', ',']).collect();
        let number = |k: usize| fields.get(k).and_then(|f| f.parse::<f64>().ok());
        let time = fields
            .get(1)
            .and_then(|f| chrono::NaiveTime::parse_from_str(f, "%H%M%S%.f").ok());
        let (Some(time), Some(heading), Some("T"), Some(roll), Some(pitch)) = (
            time,
            number(2),
            fields.get(3).copied(),
            number(4),
            number(5),
        ) else {
            self.counts[2] += 1;
            return;
        };
        let time_s = on_the_day_of(dated_s, time);
        if self.attitudes.last().is_some_and(|last| time_s <= last.0) {
            self.counts[3] += 1;
            return;
        }
        self.attitudes.push((time_s, [roll, pitch, heading]));
        self.attitude_lines.push(line);
    }

    /// An RMC's ground velocity at `time_s`, where it has a fix, a speed and a course.
    fn ground(&mut self, line: u64, sentence: &str, time_s: f64) {
        let Ok(nmea::ParseResult::RMC(rmc)) = nmea::parse_str(sentence) else {
            self.counts[0] += 1;
            return;
        };
        let (Some(knots), Some(course_deg)) = (rmc.speed_over_ground, rmc.true_course) else {
            self.counts[4] += 1;
            return;
        };
        if rmc.status_of_fix == nmea::sentences::rmc::RmcStatusOfFix::Invalid {
            self.counts[4] += 1;
            return;
        }
        if self.grounds.last().is_some_and(|last| time_s <= last.0) {
            self.counts[3] += 1;
            return;
        }
        let speed_m_s = f64::from(knots) * KNOT_M_S;
        let (sin, cos) = f64::from(course_deg).to_radians().sin_cos();
        self.grounds
            .push((time_s, [speed_m_s * cos, speed_m_s * sin], line));
    }

    /// Each RMC's velocity (north, east, down zero) beside the PASHR of its time, and
    /// its line; those with none within [`ATTITUDE_WITHIN_S`] counted, and so are the
    /// PASHR that served an RMC and those that served none. (One whose north
    /// or east velocity is beyond any vehicle a DVL rides is refused by the recording's
    /// checks, naming its line.)
    fn velocities(&mut self) -> Vec<(f64, [f64; 3], [f64; 3], u64)> {
        let mut kept = Vec::new();
        let mut served = vec![false; self.attitudes.len()];
        for (time_s, [north, east], line) in std::mem::take(&mut self.grounds) {
            let next = self.attitudes.partition_point(|a| a.0 < time_s);
            let distance = |k: &usize| (self.attitudes[*k].0 - time_s).abs();
            let nearest = [next.wrapping_sub(1), next]
                .into_iter()
                .filter(|&k| k < self.attitudes.len())
                .min_by(|a, b| distance(a).total_cmp(&distance(b)));
            match nearest {
                Some(k) if distance(&k) <= ATTITUDE_WITHIN_S => {
                    served[k] = true;
                    kept.push((time_s, [north, east, 0.0], self.attitudes[k].1, line))
                }
                _ => self.counts[5] += 1,
            }
        }
        let used = served.iter().filter(|&&s| s).count();
        self.served += used;
        self.not_taken += served.len() - used;
        kept
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The documented PASHR example of the SPAN and RT300 manuals, and ArduPilot's
    /// sentence, read as their fields state: heading true, roll, pitch, in degrees.
    #[test]
    fn pashr_sentences_read_as_their_manuals_state() {
        let file = [
            with_checksum("GPZDA,085334.00,06,04,2017,00,00"),
            "$PASHR,085335.000,224.19,T,-01.26,+00.83,+00.00,0.101,0.113,0.267,1,0*06".into(),
            "$PASHR,085336.000,224.29,T,-01.20,+00.80,+00.00,0.101,0.113,0.267,1,0".into(),
            "$PASHR,085337.000,224.29,T,-01.20,+00.80,+00.00,0.101,0.113,0.267,1,0*00".into(),
            "$PASHR,085336.000,224.39,T,-01.20,+00.80,+00.00,0.101,0.113,0.267,1,0".into(),
        ]
        .join("\n");
        let read = parse_reference(Path::new("a.nmea"), file.as_bytes(), false).unwrap();
        let day_s = 1_491_436_800.0; // 2017-04-06 00:00 UTC
        assert_eq!(read.time_s, vec![day_s + 32_015.0, day_s + 32_016.0]);
        assert_eq!(read.attitude_deg[0], [-1.26, 0.83, 224.19]);
        assert!(read.velocity_ned_m_s.is_empty());
        assert_eq!(read.lines, vec![2, 3]);
        let read = read.read;
        assert_eq!(
            (read.left_out.clone(), read.unchecked, read.passed_over),
            (vec![(LEFT_OUT[0], 1), (LEFT_OUT[3], 1)], 2, 0)
        );
        assert_eq!(every_sentence(&read), 5);
        assert!(
            read.to_string().starts_with(
                "2 PASHR attitudes, read from NMEA sentences (1 more that dated them or gave their attitude; 2 left out: 1 whose checksum fails"
            ),
            "{read}"
        );
    }

    /// The sentences `read` accounts for: each is kept, served, left out or passed over.
    fn every_sentence(read: &SentencesRead) -> usize {
        let left_out: usize = read.left_out.iter().map(|(_, n)| n).sum();
        read.kept + read.served + read.not_taken + left_out + read.passed_over
    }

    /// Beside fixes, where the samples are PASHR's, an RMC only dates them: a valid one
    /// and a void one each serve, an undated one is left out, and none is a sample.
    #[test]
    fn for_an_attitude_alone_rmc_and_zda_only_date_the_pashr() {
        let file = [
            with_checksum("GPRMC,120000.00,A,4455.1,N,06659.2,W,3.0,090.0,060417,,,D"),
            with_checksum("PASHR,120000.00,030.00,T,+01.00,-02.00,+00.00,0.1,0.1,0.2,1,1"),
            with_checksum("GPRMC,120001.00,V,,,,,,,060417,,,N"),
            with_checksum("GPRMC,120002.00,A,4455.1,N,06659.2,W,3.0,090.0,,,,D"),
            with_checksum("PASHR,120002.00,030.00,T,+01.00,-02.00,+00.00,0.1,0.1,0.2,1,1"),
            with_checksum("GPGGA,120002.00,4455.1,N,06659.2,W,1,08,0.9,0.0,M,0.0,M,,"),
        ]
        .join("\n");
        let read = parse_reference(Path::new("a.nmea"), file.as_bytes(), false).unwrap();
        assert_eq!(read.lines, vec![2, 5]);
        let read = read.read;
        assert_eq!((read.kept, read.served, read.passed_over), (2, 2, 1));
        assert_eq!(read.left_out, vec![(LEFT_OUT[6], 1)]);
        assert_eq!(every_sentence(&read), 6);
    }

    /// An RMC's speed and course give north and east (down zero) beside the PASHR of
    /// its time; one with no attitude within 0.05 s, or no fix, is counted.
    #[test]
    fn rmc_ground_velocity_takes_the_attitude_of_its_time() {
        let rmc = |time: &str, status: &str, knots: &str, course: &str| {
            with_checksum(&format!(
                "GPRMC,{time},{status},4455.101083,N,06659.283834,W,{knots},{course},060417,,,D"
            ))
        };
        let pashr = |time: &str| {
            with_checksum(&format!(
                "PASHR,{time},030.00,T,+01.00,-02.00,+00.00,0.1,0.1,0.2,1,1"
            ))
        };
        let file = [
            rmc("120000.00", "A", "3.0", "090.0"),
            pashr("120000.00"),
            rmc("120001.00", "A", "2.0", "180.0"),
            pashr("120001.00"),
            rmc("120002.00", "A", "2.0", "180.0"),
            pashr("120002.20"),
            rmc("120003.00", "V", "", ""),
            pashr("120003.00"),
        ]
        .join("\n");
        let read = parse_reference(Path::new("g.nmea"), file.as_bytes(), true).unwrap();
        // Each RMC is dated by its own date; the third has no PASHR within 0.05 s.
        assert_eq!(read.lines, vec![1, 3]);
        let v = read.velocity_ned_m_s[0];
        assert!(
            v[0].abs() < 1e-6 && (v[1] - 3.0 * KNOT_M_S).abs() < 1e-6 && v[2] == 0.0,
            "{v:?}"
        );
        let v = read.velocity_ned_m_s[1];
        assert!(
            (v[0] + 2.0 * KNOT_M_S).abs() < 1e-6 && v[1].abs() < 1e-6,
            "{v:?}"
        );
        assert_eq!(read.attitude_deg[1], [1.0, -2.0, 30.0]);
        // Two PASHR served an RMC, two served none; the void RMC is left out.
        assert_eq!(read.read.left_out, vec![(LEFT_OUT[4], 1), (LEFT_OUT[5], 1)]);
        let counts = (read.read.served, read.read.not_taken);
        assert_eq!((counts, every_sentence(&read.read)), ((2, 2), 8));
        // No PASHR at all: nothing to keep, refused naming the file.
        let error = parse_reference(
            Path::new("g.nmea"),
            rmc("120000.00", "A", "1", "1").as_bytes(),
            true,
        )
        .unwrap_err();
        assert!(
            error.to_string().starts_with("g.nmea: no reference sample"),
            "{error}"
        );
    }
}
