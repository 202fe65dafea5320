//! NMEA-0183 GGA sentences (a GNSS's, or a USBL's) as position fixes, each parsed and
//! its checksum checked by the `nmea` crate. A GGA gives a time of day: its date is
//! that of the stamp it was recorded beside (a DVL log's ping), a day earlier or later
//! where the time of day has wrapped at midnight between them. Sentences of other
//! types are passed over; a GGA left out is counted by its reason (a checksum that
//! fails, no fix, no position, a time that does not follow the previous fix's), never
//! repaired. A GGA without a checksum (a recorder may strip it: WinRiver does) is read
//! as written and counted as unchecked.
//! The recorder's clock may run on another time zone, and drift: the median of each
//! fix's time less its stamp says how far behind the GNSS's it runs, and places the
//! fixes on it ([`LoggedFixes::on_the_recorders_clock`]); what remains of the clocks'
//! difference is the calibration's time offset to find.
//! An NMEA file of its own (a GNSS's or a USBL's log) is read a line at a time, each GGA
//! dated by the last RMC or ZDA before it ([`read_nmea_fixes`]).
//! In: the sentences, each with the stamp it was recorded beside (s since 1970 UTC) and
//! its place, or an NMEA file. Out: [`LoggedFixes`]: the fixes, north and east of the
//! first, and the counts of those left out.

pub mod reference;

use crate::data::local_plane::north_east_m;
use crate::data::position_fixes::Fixes;
use crate::files::SourceFile;
use crate::files::read_lines;
use std::path::{Path, PathBuf};

/// Why an NMEA file gives no fixes.
#[derive(Debug, thiserror::Error)]
pub enum NmeaError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: no reference sample among its sentences: {read}", path.display())]
    NoReference {
        path: PathBuf,
        read: reference::SentencesRead,
    },
    #[error("{}: no GGA sentence with a fix and a date among its {sentences} sentences ({undated} GGA before any RMC or ZDA gave the date)", path.display())]
    NoFixes {
        path: PathBuf,
        sentences: usize,
        undated: usize,
    },
}

/// Whether the file at `path` is NMEA: its first character, past white space, is `$`.
pub fn is_nmea(path: &Path) -> bool {
    use std::io::Read;
    let mut first = Vec::with_capacity(256);
    let Ok(file) = std::fs::File::open(path) else {
        return false;
    };
    file.take(256).read_to_end(&mut first).is_ok() && holds_nmea(&first)
}

/// Whether `bytes` (a file's, or its start) are NMEA: their first character, past white
/// space, is `$`.
pub fn holds_nmea(bytes: &[u8]) -> bool {
    bytes.trim_ascii_start().starts_with(b"$")
}

/// The GGA fixes of the NMEA file at `path` (a GNSS's or a USBL's log, a sentence a
/// line), each dated by the last RMC or ZDA before it (a GGA before any is counted as
/// undated), on UTC in seconds since 1970; the file with its SHA-256; and how many GGA
/// were undated. Read a line at a time.
pub fn read_nmea_fixes(path: &Path) -> Result<(LoggedFixes, SourceFile, usize), NmeaError> {
    let io = |source| NmeaError::Io {
        path: path.to_path_buf(),
        source,
    };
    let (mut dated_s, mut undated, mut sentences, mut lines) = (None, 0, Vec::new(), 0);
    let sha256 = read_lines(path, io, |line, text| {
        lines = line;
        let Ok(sentence) = std::str::from_utf8(text.trim_ascii()) else {
            return Ok(());
        };
        match sentence.get(3..6) {
            Some("RMC" | "ZDA") => dated_s = date_time_s(sentence).or(dated_s),
            Some("GGA") => match dated_s {
                Some(stamp_s) => sentences.push((stamp_s, line, sentence.to_string())),
                None => undated += 1,
            },
            _ => {}
        }
        Ok(())
    })?;
    let Some(fixes) = gga_fixes(&sentences) else {
        return Err(NmeaError::NoFixes {
            path: path.to_path_buf(),
            sentences: lines as usize,
            undated,
        });
    };
    let file = SourceFile {
        path: path.to_path_buf(),
        sha256,
    };
    Ok((fixes, file, undated))
}

/// The UTC date and time an RMC or ZDA sentence gives, s since 1970 (`None` where it
/// gives none or fails its checksum).
fn date_time_s(sentence: &str) -> Option<f64> {
    let (date, time) = match nmea::parse_str(sentence).ok()? {
        nmea::ParseResult::RMC(rmc) => (rmc.fix_date?, rmc.fix_time?),
        nmea::ParseResult::ZDA(zda) => (zda.utc_date()?, zda.utc_time?),
        _ => return None,
    };
    Some(date.and_time(time).and_utc().timestamp_micros() as f64 * 1e-6)
}

/// Half a day, s: a time of day further than this from its sentence's stamp has
/// wrapped at midnight.
const HALF_DAY_S: f64 = 43_200.0;

/// The fixes a recorder logged beside a DVL's pings (GGA sentences, VmDAS's navigation
/// blocks), and those left out, by reason.
#[derive(Debug, Clone, PartialEq)]
pub struct LoggedFixes {
    pub fixes: Fixes,
    /// The first fix's latitude and longitude, degrees: where north and east are from.
    pub origin_deg: [f64; 2],
    pub left_out: Vec<(&'static str, usize)>,
    /// How many sentences of other types were passed over (GGA), or blocks repeating
    /// the fix before, read once (VmDAS).
    pub others: usize,
    /// How many GGA sentences came without a checksum, so unchecked (none but GGA).
    pub without_checksum: usize,
    /// The median of each fix's time less the stamp it was recorded beside, s: how far
    /// the recorder's clock runs behind the GNSS's (its time zone, its drift, and the
    /// sentence's wait for the next ping).
    pub recorder_behind_s: f64,
}

/// A fix a recorder logged beside a ping: the ping's stamp (s on the recorder's clock)
/// and place, the fix's own time (s since 1970 UTC), its latitude and longitude (°).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoggedFix {
    pub stamp_s: f64,
    pub place: u64,
    pub time_s: f64,
    pub position_deg: [f64; 2],
}

impl LoggedFixes {
    /// `fixes` (each later than the one before), north and east of the first, with
    /// those `left_out` by reason; `None` where there is none.
    pub fn new(
        fixes: &[LoggedFix],
        left_out: Vec<(&'static str, usize)>,
        (others, without_checksum): (usize, usize),
    ) -> Option<LoggedFixes> {
        let origin_deg = fixes.first()?.position_deg;
        let radians: Vec<[f64; 2]> = (fixes.iter())
            .map(|fix| fix.position_deg.map(f64::to_radians))
            .collect();
        let behind_s: Vec<f64> = fixes.iter().map(|fix| fix.time_s - fix.stamp_s).collect();
        Some(LoggedFixes {
            fixes: Fixes {
                lines: fixes.iter().map(|fix| fix.place).collect(),
                time_s: fixes.iter().map(|fix| fix.time_s).collect(),
                north_east_m: north_east_m(radians[0], &radians),
                depth_m: None,
                noise_m: None,
            },
            origin_deg,
            left_out: left_out.into_iter().filter(|&(_, n)| n > 0).collect(),
            others,
            without_checksum,
            recorder_behind_s: crate::median(&behind_s),
        })
    }

    /// The fixes placed on the recorder's clock: each moved by
    /// [`LoggedFixes::recorder_behind_s`].
    pub fn on_the_recorders_clock(mut self) -> Fixes {
        for t in &mut self.fixes.time_s {
            *t -= self.recorder_behind_s;
        }
        self.fixes
    }
}

/// Why a GGA sentence gives no fix.
const LEFT_OUT: [&str; 4] = [
    "a GGA whose checksum fails or that does not parse",
    "a GGA with no fix (quality 0)",
    "a GGA with no position or time",
    "a GGA stamped at or before the previous fix",
];

/// The fixes of `sentences` (each the stamp it was recorded beside, its place, the
/// sentence); `None` where no GGA gives a fix.
pub fn gga_fixes(sentences: &[(f64, u64, String)]) -> Option<LoggedFixes> {
    let mut counts = [0usize; 4];
    let (mut others, mut without_checksum) = (0, 0);
    let mut fixes: Vec<LoggedFix> = Vec::new();
    for (stamp_s, place, sentence) in sentences {
        if !is_gga(sentence) {
            others += 1;
            continue;
        }
        // A recorder may strip the checksum (WinRiver writes GGA so): such a sentence is
        // read as written, its checksum computed for the parser, and counted.
        let checked = match sentence.contains('*') {
            true => std::borrow::Cow::Borrowed(sentence.as_str()),
            false => {
                without_checksum += 1;
                std::borrow::Cow::Owned(with_checksum(&sentence[1..]))
            }
        };
        let gga = match nmea::parse_str(&checked) {
            Ok(nmea::ParseResult::GGA(gga)) => gga,
            _ => {
                counts[0] += 1;
                continue;
            }
        };
        if matches!(gga.fix_type, None | Some(nmea::sentences::FixType::Invalid)) {
            counts[1] += 1;
            continue;
        }
        let (Some(time), Some(latitude), Some(longitude)) =
            (gga.fix_time, gga.latitude, gga.longitude)
        else {
            counts[2] += 1;
            continue;
        };
        let fix_s = on_the_day_of(*stamp_s, time);
        if fixes.last().is_some_and(|last| fix_s <= last.time_s) {
            counts[3] += 1;
            continue;
        }
        fixes.push(LoggedFix {
            stamp_s: *stamp_s,
            place: *place,
            time_s: fix_s,
            position_deg: [latitude, longitude],
        });
    }
    let left_out = LEFT_OUT.into_iter().zip(counts).collect();
    LoggedFixes::new(&fixes, left_out, (others, without_checksum))
}

/// The sentence of `body` (what lies between `$` and `*`) with its checksum.
fn with_checksum(body: &str) -> String {
    format!("${body}*{:02X}", checksum(body))
}

/// NMEA's checksum of `body` (what lies between `$` and `*`): its bytes XORed.
fn checksum(body: &str) -> u8 {
    body.bytes().fold(0u8, |sum, b| sum ^ b)
}

/// Whether `sentence` is a GGA of any talker (`$GPGGA`, `$GNGGA`, ...).
pub fn is_gga(sentence: &str) -> bool {
    sentence.get(3..6) == Some("GGA")
}

/// The time of day `time` on the day of `stamp_s` (s since 1970 UTC), moved a day
/// where that puts it more than half a day from the stamp.
fn on_the_day_of(stamp_s: f64, time: chrono::NaiveTime) -> f64 {
    use chrono::Timelike;
    let midnight_s = (stamp_s / 86_400.0).floor() * 86_400.0;
    let of_day_s =
        f64::from(time.num_seconds_from_midnight()) + f64::from(time.nanosecond()) * 1e-9;
    let fix_s = midnight_s + of_day_s;
    if fix_s - stamp_s > HALF_DAY_S {
        fix_s - 86_400.0
    } else if stamp_s - fix_s > HALF_DAY_S {
        fix_s + 86_400.0
    } else {
        fix_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fixes across midnight take the next day; a bad checksum, no fix and a repeated
    /// time are each counted; other sentences passed over.
    #[test]
    fn gga_sentences_give_fixes_on_their_days_and_count_those_left_out() {
        let day_s = 1_491_436_800.0; // 2017-04-06 00:00 UTC
        let gga = |time: &str, quality: u8| {
            with_checksum(&format!(
                "GPGGA,{time},4455.101083,N,06659.283834,W,{quality},8,1.0,5.1,M,-28.1,M,,"
            ))
        };
        let mut bad = gga("235959.50", 2);
        bad.replace_range(10..11, "8");
        let sentences = vec![
            (day_s + 86_399.0, 1, gga("235959.00", 2)),
            (day_s + 86_399.6, 2, bad),
            (day_s + 86_400.4, 3, gga("000000.50", 2)),
            (day_s + 86_400.5, 4, gga("000000.50", 2)),
            (day_s + 86_401.0, 5, gga("000001.00", 0)),
            (
                day_s + 86_401.0,
                6,
                with_checksum("GPVTG,115.5,T,95.2,M,0.07,N,0.13,K,D"),
            ),
        ];
        let read = gga_fixes(&sentences).unwrap();
        assert_eq!(read.fixes.time_s, vec![day_s + 86_399.0, day_s + 86_400.5]);
        assert_eq!(read.fixes.lines, vec![1, 3]);
        assert_eq!((read.others, read.without_checksum), (1, 0));
        assert_eq!(
            read.left_out,
            vec![(LEFT_OUT[0], 1), (LEFT_OUT[1], 1), (LEFT_OUT[3], 1)]
        );
        assert!((read.origin_deg[0] - (44.0 + 55.101083 / 60.0)).abs() < 1e-9);
        assert!((read.origin_deg[1] + (66.0 + 59.283834 / 60.0)).abs() < 1e-9);
        // A time of day before midnight beside a stamp after it is the day before.
        let late = gga_fixes(&[(day_s + 10.0, 1, gga("235955.00", 2))]).unwrap();
        assert_eq!(late.fixes.time_s, vec![day_s - 5.0]);
        // WinRiver's GGA, its checksum stripped, is read and counted as unchecked.
        let stripped =
            "$GPGGA,202401.30,4455.101083,N,06659.283834,W,2,8,1.0,5.1,M,-28.1,M,6.2,0135";
        let read = gga_fixes(&[(day_s + 73_441.0, 1, stripped.to_string())]).unwrap();
        assert_eq!((read.fixes.len(), read.without_checksum), (1, 1));
        assert!((read.fixes.time_s[0] - (day_s + 73_441.3)).abs() < 1e-6);
        assert!((read.recorder_behind_s - 0.3).abs() < 1e-6);
        assert!((read.on_the_recorders_clock().time_s[0] - (day_s + 73_441.0)).abs() < 1e-6);
        assert_eq!(gga_fixes(&sentences[4..]), None);
    }
}
