//! A PD0 writer for the tests, written from the format's byte layout and not from the
//! reader: ensembles of a fixed leader (59 bytes), a variable leader (65 bytes, the Y2K
//! clock) and bottom track (85 bytes), each with its checksum; and the beam velocities
//! of a bottom velocity by projection onto the four beams (the physics the reader's
//! transformation inverts).

/// How the instrument was set up: the frame code of EX bits 3–4 (0 beam, 1
/// instrument, 2 ship, 3 earth), the beam angle code (0: 15°, 1: 20°, 2: 30°), the
/// pattern, the heading alignment EA (°).
#[derive(Debug, Clone, Copy)]
pub struct Setup {
    pub frame: u8,
    pub beam_angle_code: u8,
    pub convex: bool,
    pub alignment_deg: f64,
}

/// One ping: its clock (s since 1970 UTC), bottom track's four velocities (mm/s,
/// −32768 for none), each beam's correlation and percent good, and heading, pitch,
/// roll (°).
#[derive(Debug, Clone, Copy)]
pub struct Ping {
    pub time_s: f64,
    pub velocity_mm_s: [i16; 4],
    pub correlation: [u8; 4],
    pub percent_good: [u8; 4],
    pub attitude_deg: [f64; 3],
}

impl Ping {
    /// A ping of four good beams at `time_s`, level and heading north.
    pub fn good(time_s: f64, velocity_mm_s: [i16; 4]) -> Ping {
        Ping {
            time_s,
            velocity_mm_s,
            correlation: [250; 4],
            percent_good: [100; 4],
            attitude_deg: [0.0; 3],
        }
    }
}

/// The beam angle of a setup, degrees.
pub fn beam_angle_deg(setup: &Setup) -> f64 {
    [15.0, 20.0, 30.0][usize::from(setup.beam_angle_code)]
}

/// The four beam velocities (m/s) of the vehicle moving at `forward, starboard, down`
/// (m/s) in the vehicle's axes: the bottom's velocity relative to the instrument (the
/// vehicle's negative, turned into the instrument's axes by −EA: x starboard of beam
/// 3, y toward beam 3, z up) projected onto each beam. Beams 1 and 2 lean toward +x
/// and −x, 3 and 4 toward −y and +y (a convex head; a concave one crosses them), each
/// by the beam angle from the instrument's axis.
pub fn beams_of(vehicle_m_s: [f64; 3], setup: &Setup) -> [f64; 4] {
    let (s, c) = setup.alignment_deg.to_radians().sin_cos();
    let [forward, starboard, down] = vehicle_m_s;
    // The vehicle's velocity in axes turned by EA (beam 3 forward).
    let (along_beam3, across) = (c * forward + s * starboard, -s * forward + c * starboard);
    let bottom = [across, along_beam3, -down].map(|v| -v);
    let angle = beam_angle_deg(setup).to_radians();
    let lean = if setup.convex { 1.0 } else { -1.0 } * angle.sin();
    let up = angle.cos() * bottom[2];
    [
        lean * bottom[0] + up,
        -lean * bottom[0] + up,
        -lean * bottom[1] + up,
        lean * bottom[1] + up,
    ]
}

/// The bytes of ensemble `number` of `ping` under `setup`, its checksum last.
pub fn ensemble(setup: &Setup, number: u32, ping: &Ping) -> Vec<u8> {
    framed(&blocks(setup, number, ping))
}

/// The data types of ensemble `number`: its fixed leader, variable leader and bottom
/// track.
pub fn blocks(setup: &Setup, number: u32, ping: &Ping) -> [Vec<u8>; 3] {
    let mut fixed = vec![0u8; 59];
    fixed[4] = 0b0000_0010 | if setup.convex { 0b1000 } else { 0 }; // 600 kHz, down
    fixed[5] = 0b0100_0000 | setup.beam_angle_code; // four-beam Janus
    fixed[8] = 4;
    fixed[25] = setup.frame << 3 | 0b110; // tilts used, three beams allowed
    fixed[26..28].copy_from_slice(&((setup.alignment_deg * 100.0).round() as i16).to_le_bytes());
    fixed[30] = 0b0001_1101; // heading, pitch, roll from its own sensors
    fixed[58] = beam_angle_deg(setup) as u8;
    let mut variable = vec![0u8; 65];
    variable[0] = 0x80;
    variable[2..4].copy_from_slice(&(number as u16).to_le_bytes());
    variable[11] = (number >> 16) as u8;
    let millis = (ping.time_s * 1000.0).round() as i64;
    let time = chrono::DateTime::from_timestamp_millis(millis).unwrap();
    use chrono::{Datelike, Timelike};
    let clock = [
        (time.year() % 100) as u8,
        time.month() as u8,
        time.day() as u8,
        time.hour() as u8,
        time.minute() as u8,
        time.second() as u8,
        (time.timestamp_subsec_millis() / 10) as u8,
    ];
    variable[4..11].copy_from_slice(&clock);
    variable[57] = (time.year() / 100) as u8;
    variable[58..65].copy_from_slice(&clock);
    let [heading, pitch, roll] = ping.attitude_deg.map(|a| (a * 100.0).round());
    variable[18..20].copy_from_slice(&(heading as u16).to_le_bytes());
    variable[20..22].copy_from_slice(&(pitch as i16).to_le_bytes());
    variable[22..24].copy_from_slice(&(roll as i16).to_le_bytes());
    let mut bottom = vec![0u8; 85];
    bottom[0] = 0x00;
    bottom[1] = 0x06;
    bottom[6] = 220; // BC
    bottom[7] = 30; // BA
    bottom[8] = 0; // BG
    for k in 0..4 {
        bottom[16 + 2 * k..18 + 2 * k].copy_from_slice(&1500u16.to_le_bytes());
        bottom[24 + 2 * k..26 + 2 * k].copy_from_slice(&ping.velocity_mm_s[k].to_le_bytes());
        bottom[32 + k] = ping.correlation[k];
        bottom[36 + k] = 80;
        bottom[40 + k] = ping.percent_good[k];
    }
    [fixed, variable, bottom]
}

/// The data types `blocks` as one ensemble: the header and its offsets, the blocks, the
/// checksum.
pub fn framed(blocks: &[Vec<u8>]) -> Vec<u8> {
    let header = 6 + 2 * blocks.len();
    let mut bytes = vec![0x7F, 0x7F, 0, 0, 0, blocks.len() as u8];
    let mut offset = header;
    for block in blocks {
        bytes.extend_from_slice(&(offset as u16).to_le_bytes());
        offset += block.len();
    }
    for block in blocks {
        bytes.extend_from_slice(block);
    }
    let length = bytes.len() as u16;
    bytes[2..4].copy_from_slice(&length.to_le_bytes());
    let sum = bytes
        .iter()
        .fold(0u16, |sum, &b| sum.wrapping_add(u16::from(b)));
    bytes.extend_from_slice(&sum.to_le_bytes());
    bytes
}

/// A log of `pings` under `setup`, numbered from 1.
pub fn log(setup: &Setup, pings: &[Ping]) -> Vec<u8> {
    (pings.iter().enumerate())
        .flat_map(|(k, ping)| ensemble(setup, k as u32 + 1, ping))
        .collect()
}

/// VmDAS's navigation block (ID 0x2000, 78 bytes) of a fix at `time_s` (s since 1970
/// UTC) at `position_deg` (latitude, longitude), flagged updated with its date and time
/// valid, and its position where `valid`: the UTC date (bytes 2–5: day, month, year), the last fix's
/// time of day (22–25, 0.1 ms), latitude and longitude (26–33, binary angles of 32
/// bits), the flags (46–47).
pub fn navigation(time_s: f64, position_deg: [f64; 2], valid: bool) -> Vec<u8> {
    use chrono::Datelike;
    let mut block = vec![0u8; 78];
    block[0..2].copy_from_slice(&0x2000u16.to_le_bytes());
    let millis = (time_s * 1000.0).round() as i64;
    let time = chrono::DateTime::from_timestamp_millis(millis).unwrap();
    block[2] = time.day() as u8;
    block[3] = time.month() as u8;
    block[4..6].copy_from_slice(&(time.year() as u16).to_le_bytes());
    let of_day = (time_s.rem_euclid(86_400.0) * 1e4).round() as u32;
    block[22..26].copy_from_slice(&of_day.to_le_bytes());
    for (k, degrees) in position_deg.into_iter().enumerate() {
        let bam = (degrees / 180.0 * 2_147_483_648.0).round() as i32;
        block[26 + 4 * k..30 + 4 * k].copy_from_slice(&bam.to_le_bytes());
    }
    let flags: u16 = if valid { 0b10_0011 } else { 0b10_0001 };
    block[46..48].copy_from_slice(&flags.to_le_bytes());
    block
}
