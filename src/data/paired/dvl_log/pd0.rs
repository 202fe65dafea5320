//! Teledyne RDI's PD0 binary log, ensemble by ensemble: each ensemble starts with the
//! bytes 0x7F 0x7F, states its length, lists the offsets of its data types (walked, not
//! assumed: the fixed leader's length differs between firmware versions) and ends with a
//! checksum. Read here: the fixed leader (the frame the velocities are in, the beam
//! angle and pattern, the heading alignment EA, where the attitude came from, EZ), the
//! variable leader (the ensemble's clock and attitude) and bottom track (four
//! velocities in mm/s, −32768 for none, each beam's correlation, evaluation amplitude,
//! percent good and range), the NMEA sentences WinRiver writes as text (IDs
//! 0x2101–0x2104) and the last GNSS fix VmDAS writes in its navigation block (ID
//! 0x2000). Every other data type is counted by its ID and not read.
//! The file is streamed: a long log is never held whole.
//! An ensemble whose checksum fails is counted and not read, and so are a navigation
//! block too short to hold its fix and a last ensemble the file ends inside (a log cut as the recorder stopped: its length points past
//! the file); an offset that overlaps another or leaves its ensemble, or an ensemble
//! without its leaders, is refused, naming the byte.
//! In: a file's path. Out: each [`Ensemble`] handed to a visitor, then a [`Pd0Survey`]
//! with the file's SHA-256.

use super::LogError;
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

/// The two bytes every ensemble starts with.
const MAGIC: [u8; 2] = [0x7F, 0x7F];
/// The data-type IDs read.
const FIXED_LEADER: u16 = 0x0000;
const VARIABLE_LEADER: u16 = 0x0080;
pub const BOTTOM_TRACK: u16 = 0x0600;
/// WinRiver's blocks of NMEA sentences as text.
const NMEA_TEXT: std::ops::RangeInclusive<u16> = 0x2101..=0x2104;
/// VmDAS's navigation block, and the bytes read of it (to its flags).
const VMDAS_NAVIGATION: u16 = 0x2000;
const VMDAS_NAVIGATION_READ: usize = 48;
/// Degrees per unit of a binary angle of 32 bits.
const DEG_PER_BAM32: f64 = 180.0 / 2_147_483_648.0;
/// Bottom track's marker of a beam (or an axis) with no velocity, mm/s.
pub const NO_VELOCITY_MM_S: i16 = -32768;
/// How much of the file is read at a time, bytes.
const CHUNK: usize = 1 << 20;

/// The frame a PD0 file's velocities are in (the fixed leader's EX bits 3–4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Frame {
    Beam,
    Instrument,
    Ship,
    Earth,
}

impl Frame {
    pub fn words(self) -> &'static str {
        match self {
            Frame::Beam => "beam",
            Frame::Instrument => "instrument",
            Frame::Ship => "ship",
            Frame::Earth => "earth",
        }
    }
}

/// The fixed leader's settings that say how to read bottom track.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixedLeader {
    pub frame: Frame,
    /// Whether pitch and roll were used in the turn to ship or earth axes (EX bit 2).
    pub tilts_used: bool,
    /// Whether a three-beam solution was allowed (EX bit 1).
    pub three_beam_allowed: bool,
    /// The beams' angle from the instrument's axis, degrees.
    pub beam_angle_deg: f64,
    /// Convex (true) or concave beam pattern.
    pub convex: bool,
    pub looking_up: bool,
    /// The heading alignment (EA): beam 3's angle clockwise from the vehicle's
    /// forward axis, degrees.
    pub heading_alignment_deg: f64,
    /// The sensor-source byte (EZ): bit 4 set where the heading came from the DVL's
    /// own sensor, bits 3 and 2 pitch and roll, else from the vehicle (or fixed).
    pub sensor_source: u8,
}

/// Bottom track as one ensemble recorded it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BottomTrack {
    /// Beams 1–4 in beam coordinates, else x, y, z and the error velocity, mm/s, the
    /// bottom's relative to the instrument; [`NO_VELOCITY_MM_S`] for none.
    pub velocity_mm_s: [i16; 4],
    pub correlation: [u8; 4],
    pub amplitude: [u8; 4],
    pub percent_good: [u8; 4],
    /// The range to the bottom along each beam, m.
    pub range_m: [f64; 4],
    /// The thresholds the instrument ran with: correlation (BC), evaluation amplitude
    /// (BA) and percent good (BG).
    pub correlation_min: u8,
    pub amplitude_min: u8,
    pub percent_good_min: u8,
}

/// One ensemble as read.
#[derive(Debug, Clone, PartialEq)]
pub struct Ensemble {
    /// Where it starts in the file, bytes.
    pub byte: u64,
    /// Its number, as the variable leader counts.
    pub number: u32,
    /// Its clock, seconds since 1970-01-01 UTC.
    pub time_s: f64,
    /// Heading, pitch and roll as recorded, degrees.
    pub attitude_deg: [f64; 3],
    pub leader: FixedLeader,
    pub bottom: Option<BottomTrack>,
    /// The NMEA sentences a recorder wrote into it as text (WinRiver's IDs
    /// 0x2101–0x2104: a GNSS's GGA, VTG, ...), as written.
    pub sentences: Vec<String>,
    /// The last GNSS fix before its ping, where VmDAS wrote one (ID 0x2000).
    pub navigation: Option<NavigationFix>,
}

/// The last GNSS fix before an ensemble's ping, as VmDAS's navigation block gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavigationFix {
    /// s since 1970 UTC: the block's UTC date and the fix's time of day (0.1 ms); `None`
    /// where the date is no date.
    pub time_s: Option<f64>,
    pub latitude_deg: f64,
    pub longitude_deg: f64,
    /// The block's flags: bit 1 the position valid, bit 5 the date and time.
    pub position_valid: bool,
    pub time_valid: bool,
}

/// What a whole file held beyond its ensembles.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Pd0Survey {
    pub sha256: String,
    pub ensembles: usize,
    /// Where each ensemble whose checksum failed starts, bytes (0x7F 0x7F and a header
    /// whose first offset follows its table): left out, not read.
    pub bad_checksums: Vec<u64>,
    /// Bytes outside any ensemble read (before the first, after a failed checksum, or
    /// an ensemble cut short at the file's end), counted with those below.
    pub bytes_between: u64,
    /// The last ensemble, where the file ends inside it: where it starts, the bytes it
    /// states (with its checksum) and the bytes the file holds of it. Not read.
    pub cut_short: Option<(u64, usize, usize)>,
    /// How many ensembles held each data type, by ID.
    pub blocks: BTreeMap<u16, usize>,
    /// How many VmDAS navigation blocks were too short to hold a fix: not read.
    pub short_navigation: usize,
}

/// The name of a PD0 data type, where it is one this reader knows.
pub fn block_name(id: u16) -> &'static str {
    match id {
        0x0000 | 0x0001 => "fixed leader",
        0x0080 | 0x0081 => "variable leader",
        0x0100 => "velocity profile",
        0x0200 => "correlation profile",
        0x0300 => "echo intensity profile",
        0x0400 => "percent good profile",
        0x0500 => "status profile",
        0x0600 => "bottom track",
        0x2000 => "VmDAS navigation",
        0x2022 => "WinRiver II NMEA",
        0x2100..=0x2104 => "WinRiver NMEA",
        _ => "other",
    }
}

/// Reads `path` ensemble by ensemble, handing each to `visit`.
pub fn read(path: &Path, visit: &mut dyn FnMut(Ensemble)) -> Result<Pd0Survey, LogError> {
    let io = |source| LogError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut hasher = Sha256::new();
    let mut survey = Pd0Survey::default();
    // `pending` holds the bytes from `start` (the file's offset of its first byte).
    let (mut pending, mut start, mut at_end) = (Vec::new(), 0u64, false);
    let mut chunk = vec![0u8; CHUNK];
    loop {
        if !at_end {
            let read = file.read(&mut chunk).map_err(io)?;
            hasher.update(&chunk[..read]);
            pending.extend_from_slice(&chunk[..read]);
            at_end = read == 0;
        }
        let used = take_ensembles(path, &pending, start, at_end, &mut survey, visit)?;
        pending.drain(..used);
        start += used as u64;
        if at_end {
            survey.bytes_between += pending.len() as u64;
            break;
        }
    }
    if survey.ensembles == 0 {
        return Err(LogError::Empty {
            path: path.to_path_buf(),
            bytes: start + pending.len() as u64,
        });
    }
    survey.sha256 = format!("{:x}", hasher.finalize());
    Ok(survey)
}

/// Reads the whole ensembles at the front of `bytes` (the file's from `start`), and
/// says how many bytes they and what lay between them took. At the file's end an
/// ensemble that does not fit is refused.
fn take_ensembles(
    path: &Path,
    bytes: &[u8],
    start: u64,
    at_end: bool,
    survey: &mut Pd0Survey,
    visit: &mut dyn FnMut(Ensemble),
) -> Result<usize, LogError> {
    let mut at = 0;
    while let Some(found) = find_magic(&bytes[at..]) {
        survey.bytes_between += found as u64;
        at += found;
        let byte = start + at as u64;
        let Some(header) = bytes.get(at..at + 8) else {
            break;
        };
        let length = usize::from(u16::from_le_bytes([header[2], header[3]]));
        let types = usize::from(header[5]);
        let first_offset = usize::from(u16::from_le_bytes([header[6], header[7]]));
        // An ensemble's first data type follows its table of offsets: 0x7F 0x7F with
        // another header is no ensemble's start, only bytes between.
        if types == 0 || first_offset != 6 + 2 * types || length < first_offset {
            survey.bytes_between += 1;
            at += 1;
            continue;
        }
        if at + length + 2 > bytes.len() {
            if !at_end {
                break;
            }
            // The file ends inside it, unless a later ensemble's checksum holds.
            survey
                .cut_short
                .get_or_insert((byte, length + 2, bytes.len() - at));
            survey.bytes_between += 1;
            at += 1;
            continue;
        }
        let ensemble = &bytes[at..at + length];
        let stated = u16::from_le_bytes([bytes[at + length], bytes[at + length + 1]]);
        let sum = ensemble
            .iter()
            .fold(0u16, |sum, &b| sum.wrapping_add(u16::from(b)));
        if sum != stated {
            // Read on from the next byte: the next ensemble may start inside this one.
            survey.bad_checksums.push(byte);
            survey.bytes_between += 1;
            at += 1;
            continue;
        }
        let refuse = |problem: String| LogError::Ensemble {
            path: path.to_path_buf(),
            byte,
            problem,
        };
        visit(parse(ensemble, byte, survey).map_err(refuse)?);
        survey.ensembles += 1;
        survey.cut_short = None;
        at += length + 2;
    }
    if find_magic(&bytes[at..]).is_none() {
        // Keep a last 0x7F that may start the next ensemble.
        let keep = usize::from(bytes.last() == Some(&MAGIC[0]) && !at_end);
        let skipped = bytes.len() - at - keep;
        survey.bytes_between += skipped as u64;
        at += skipped;
    }
    Ok(at)
}

/// Where the next 0x7F 0x7F starts in `bytes`.
fn find_magic(bytes: &[u8]) -> Option<usize> {
    bytes.windows(2).position(|pair| pair == MAGIC)
}

/// The ensemble `bytes` (its checksum held), which starts at `byte` in the file.
fn parse(bytes: &[u8], byte: u64, survey: &mut Pd0Survey) -> Result<Ensemble, String> {
    let types = usize::from(bytes[5]);
    let table_end = 6 + 2 * types;
    if table_end > bytes.len() {
        return Err(format!(
            "its header lists {types} data types, whose offsets run past its {} bytes",
            bytes.len()
        ));
    }
    let mut offsets: Vec<usize> = (0..types)
        .map(|k| usize::from(u16_at(bytes, 6 + 2 * k)))
        .collect();
    offsets.sort_unstable();
    let mut blocks: Vec<(u16, usize, &[u8])> = Vec::with_capacity(types);
    for (k, &offset) in offsets.iter().enumerate() {
        let end = offsets.get(k + 1).copied().unwrap_or(bytes.len());
        if offset < table_end || offset + 2 > bytes.len() || (end == offset && k + 1 < types) {
            return Err(format!(
                "a data type's offset {offset} overlaps the header (its first {table_end} bytes), another data type or leaves the ensemble of {} bytes",
                bytes.len()
            ));
        }
        let id = u16_at(bytes, offset);
        if blocks.iter().all(|(seen, ..)| *seen != id) {
            *survey.blocks.entry(id).or_default() += 1;
        }
        blocks.push((id, offset, &bytes[offset..end]));
    }
    let block = |wanted: &[u16], what: &str, length: usize| {
        let Some(&(_, offset, block)) = blocks.iter().find(|(id, ..)| wanted.contains(id)) else {
            return Ok(None);
        };
        if block.len() < length {
            return Err(format!(
                "its {what} at offset {offset} holds {} bytes before the next data type or the ensemble's end, fewer than its {length}: the offsets overlap",
                block.len()
            ));
        }
        Ok(Some(block))
    };
    let fixed = block(&[FIXED_LEADER, 0x0001], "fixed leader", 31)?
        .ok_or("it has no fixed leader (ID 0x0000)")?;
    let leader = fixed_leader(fixed)?;
    let variable = block(&[VARIABLE_LEADER, 0x0081], "variable leader", 24)?
        .ok_or("it has no variable leader (ID 0x0080)")?;
    let (number, time_s, attitude_deg) = variable_leader(variable)?;
    let bottom = block(&[BOTTOM_TRACK], "bottom track", 44)?.map(bottom_track);
    let sentences = (blocks.iter())
        .filter(|(id, ..)| NMEA_TEXT.contains(id))
        .filter_map(|(_, _, block)| nmea_text(block))
        .collect();
    // A navigation block too short to hold a fix is counted, not refused: the log's
    // pings do not need it.
    let navigation = (blocks.iter())
        .find(|(id, ..)| *id == VMDAS_NAVIGATION)
        .and_then(
            |&(_, _, block)| match block.len() >= VMDAS_NAVIGATION_READ {
                true => Some(navigation_fix(block)),
                false => {
                    survey.short_navigation += 1;
                    None
                }
            },
        );
    Ok(Ensemble {
        byte,
        number,
        time_s,
        attitude_deg,
        leader,
        bottom,
        sentences,
        navigation,
    })
}

/// The last fix of VmDAS's navigation `block`, at least 48 bytes: its UTC date (day,
/// month, year, bytes 2–5: the first fix's), the last fix's time of day (bytes 22–25,
/// 0.1 ms; a day later where it is earlier than the first fix's, bytes 6–9: midnight
/// between them), latitude and longitude (26–33, binary angles of 32 bits) and the
/// flags (46–47).
fn navigation_fix(block: &[u8]) -> NavigationFix {
    let (day, month) = (u32::from(block[2]), u32::from(block[3]));
    let year = i32::from(u16_at(block, 4));
    let i32_at = |at: usize| i32::from_le_bytes(std::array::from_fn(|k| block[at + k]));
    let (first_s, last_s) = (i32_at(6) as u32, i32_at(22) as u32);
    let wrapped_s = if last_s < first_s { 86_400.0 } else { 0.0 };
    let of_day_s = f64::from(last_s) * 1e-4 + wrapped_s;
    let time_s = chrono::NaiveDate::from_ymd_opt(year, month, day)
        .map(|date| date.and_hms_opt(0, 0, 0).unwrap().and_utc().timestamp() as f64 + of_day_s);
    let flags = u16_at(block, 46);
    NavigationFix {
        time_s,
        latitude_deg: f64::from(i32_at(26)) * DEG_PER_BAM32,
        longitude_deg: f64::from(i32_at(30)) * DEG_PER_BAM32,
        position_valid: flags & 0b10 != 0,
        time_valid: flags & 0b10_0000 != 0,
    }
}

/// The NMEA sentence of a WinRiver text block: its ID, its length (2 bytes each), then
/// the sentence; `None` where it holds no `$` sentence.
fn nmea_text(block: &[u8]) -> Option<String> {
    let length = usize::from(*block.get(2)?) | usize::from(*block.get(3)?) << 8;
    let text = block.get(4..(4 + length).min(block.len()))?;
    let text = std::str::from_utf8(text)
        .ok()?
        .trim_end_matches(['\r', '\n', '\0']);
    text.starts_with('$').then(|| text.to_string())
}

fn u16_at(bytes: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([bytes[at], bytes[at + 1]])
}

fn i16_at(bytes: &[u8], at: usize) -> i16 {
    i16::from_le_bytes([bytes[at], bytes[at + 1]])
}

/// The fixed leader `block`, at least 31 bytes.
fn fixed_leader(block: &[u8]) -> Result<FixedLeader, String> {
    let (config_low, config_high, transform) = (block[4], block[5], block[25]);
    let beam_angle_deg =
        match config_high & 0b11 {
            0 => 15.0,
            1 => 20.0,
            2 => 30.0,
            _ if block.len() > 58 => f64::from(block[58]),
            _ => return Err(
                "its fixed leader states an \"other\" beam angle and does not give it (byte 58)"
                    .into(),
            ),
        };
    Ok(FixedLeader {
        frame: match (transform >> 3) & 0b11 {
            0 => Frame::Beam,
            1 => Frame::Instrument,
            2 => Frame::Ship,
            _ => Frame::Earth,
        },
        tilts_used: transform & 0b100 != 0,
        three_beam_allowed: transform & 0b10 != 0,
        beam_angle_deg,
        convex: config_low & 0b1000 != 0,
        looking_up: config_low & 0x80 != 0,
        heading_alignment_deg: f64::from(i16_at(block, 26)) / 100.0,
        sensor_source: block[30],
    })
}

/// The variable leader `block`, at least 24 bytes: the ensemble's number, clock (s
/// since 1970 UTC) and heading, pitch and roll (°).
fn variable_leader(block: &[u8]) -> Result<(u32, f64, [f64; 3]), String> {
    let number = u32::from(u16_at(block, 2)) | u32::from(block[11]) << 16;
    // The Y2K clock (bytes 57–64) where the firmware writes it, else the two-digit year.
    let (century, clock) = if block.len() >= 65 {
        (u32::from(block[57]), &block[58..65])
    } else {
        (20, &block[4..11])
    };
    let year = century as i32 * 100 + i32::from(clock[0]);
    let [month, day, hour, minute, second, hundredths] =
        [1, 2, 3, 4, 5, 6].map(|k| u32::from(clock[k]));
    let time = chrono::NaiveDate::from_ymd_opt(year, month, day)
        .and_then(|date| date.and_hms_milli_opt(hour, minute, second, hundredths * 10))
        .ok_or_else(|| {
            format!(
                "its clock reads {year}-{month:02}-{day:02} {hour:02}:{minute:02}:{second:02}.{hundredths:02}, not a time"
            )
        })?;
    let time_s = time.and_utc().timestamp_millis() as f64 / 1000.0;
    let attitude_deg = [
        f64::from(u16_at(block, 18)) / 100.0,
        f64::from(i16_at(block, 20)) / 100.0,
        f64::from(i16_at(block, 22)) / 100.0,
    ];
    Ok((number, time_s, attitude_deg))
}

/// The bottom track `block`, at least 44 bytes.
fn bottom_track(block: &[u8]) -> BottomTrack {
    let four_u8 = |at: usize| [block[at], block[at + 1], block[at + 2], block[at + 3]];
    let range_m = std::array::from_fn(|k| {
        // The range's most significant byte (bytes 77–80) where the firmware writes it.
        let high = block.get(77 + k).map_or(0, |&b| u32::from(b) << 16);
        f64::from(u32::from(u16_at(block, 16 + 2 * k)) | high) / 100.0
    });
    BottomTrack {
        velocity_mm_s: std::array::from_fn(|k| i16_at(block, 24 + 2 * k)),
        correlation: four_u8(32),
        amplitude: four_u8(36),
        percent_good: four_u8(40),
        range_m,
        correlation_min: block[6],
        amplitude_min: block[7],
        percent_good_min: block[8],
    }
}
