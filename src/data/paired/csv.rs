//! A paired recording from CSV: the DVL's columns from its file, the reference's from
//! its own (or both from one file), each field checked as [`crate::data::csv`] checks
//! it (there, not a number, finite), each sample's line kept for the plausibility
//! checks' messages.
//! In: the bytes of the DVL's file and, when it is another, the reference's, and the
//! [`PairedColumns`]. Out: the [`Unchecked`] samples and the [`Locator`] of their lines.

use super::checks::{Locator, Unchecked};
use super::{LeftOutWhy, PairedColumns, PairedError};
use crate::Vec3;
use crate::data::csv::{Column, Quantity, Rows, parse_columns};
use crate::data::nmea::reference::parse_reference as parse_nmea_reference;
use std::path::Path;

/// The samples of `dvl` (a path and its bytes) and, where the reference is in another
/// file, of `reference`, with `columns`; the reference's velocity only `with_velocity`
/// (an attitude alone, beside position fixes, has none).
pub fn parse(
    dvl: (&Path, &[u8]),
    reference: Option<(&Path, &[u8])>,
    columns: &PairedColumns,
    with_velocity: bool,
) -> Result<(Unchecked, Locator), PairedError> {
    let time = Column {
        name: &columns.time,
        holds: Quantity::Time,
    };
    let validity = columns.valid.as_deref().map(|name| Column {
        name,
        holds: Quantity::Validity,
    });
    let dvl_columns: Vec<Column> = std::iter::once(time)
        .chain(triple(&columns.dvl, Quantity::MeasuredVelocity))
        .collect();
    // In one file, the reference's values start after the time and the DVL's three;
    // the DVL's validity flag, where there is one, is the last.
    let (dvl_rows, (reference_samples, reference_lines), reference_path) = match reference {
        None => {
            let reference_columns = reference_columns(time, columns, with_velocity);
            let all: Vec<Column> = dvl_columns
                .iter()
                .chain(&reference_columns[1..])
                .chain(&validity)
                .copied()
                .collect();
            let rows = parse_columns(dvl.0, dvl.1, &all)?;
            let reference = reference_samples(&rows, 4, columns, with_velocity);
            let lines = rows.lines.clone();
            (rows, (reference, lines), dvl.0)
        }
        Some((path, bytes)) => {
            let dvl_with_flag: Vec<Column> = dvl_columns.iter().chain(&validity).copied().collect();
            let dvl_rows = parse_columns(dvl.0, dvl.1, &dvl_with_flag)?;
            (
                dvl_rows,
                parse_reference((path, bytes), columns, with_velocity)?,
                path,
            )
        }
    };
    let flag = dvl_rows.width - 1;
    let names = reference_names(&reference_samples, columns);
    let samples = Unchecked {
        dvl_time_s: dvl_rows.column(0).collect(),
        dvl_m_s: triples(&dvl_rows, 1),
        dvl_stated: validity.map(|_| {
            (dvl_rows.column(flag))
                .map(|v| (v == 0.0).then_some(LeftOutWhy::Flagged))
                .collect()
        }),
        ..reference_samples
    };
    let at = Locator {
        dvl: dvl.0.to_path_buf(),
        reference: reference_path.to_path_buf(),
        dvl_lines: dvl_rows.lines,
        reference_lines,
        names,
    };
    Ok((samples, at))
}

/// The names the plausibility checks give `reference`'s fields: `columns`, or where it
/// was read from NMEA, the sentences' (the DVL's as `columns` names them).
pub fn reference_names(reference: &Unchecked, columns: &PairedColumns) -> PairedColumns {
    if reference.reference_read.is_none() {
        return columns.clone();
    }
    PairedColumns {
        velocity_ned: ["RMC north", "RMC east", "RMC down (zero)"].map(String::from),
        attitude: ["PASHR roll", "PASHR pitch", "PASHR heading"].map(String::from),
        angles_in_degrees: true,
        rate: None,
        latitude_longitude: None,
        north_east: None,
        ..columns.clone()
    }
}

/// The reference's samples of the file `reference` (a path and its bytes) alone, the
/// DVL's fields left empty (a DVL's own log gives them), and the line of each: a CSV
/// file's columns, or an NMEA file's sentences (its first character `$`:
/// [`crate::data::nmea::reference`]).
pub fn parse_reference(
    (path, bytes): (&Path, &[u8]),
    columns: &PairedColumns,
    with_velocity: bool,
) -> Result<(Unchecked, Vec<u64>), PairedError> {
    if crate::data::nmea::holds_nmea(bytes) {
        let nmea = parse_nmea_reference(path, bytes, with_velocity)?;
        let samples = Unchecked {
            dvl_time_s: Vec::new(),
            dvl_m_s: Vec::new(),
            dvl_stated: None,
            reference_time_s: nmea.time_s,
            velocity_ned_m_s: nmea.velocity_ned_m_s,
            attitude: nmea.attitude_deg,
            rate: None,
            angles_in_degrees: true,
            position: None,
            reference_read: Some(nmea.read),
        };
        return Ok((samples, nmea.lines));
    }
    let time = Column {
        name: &columns.time,
        holds: Quantity::Time,
    };
    let rows = parse_columns(
        path,
        bytes,
        &reference_columns(time, columns, with_velocity),
    )?;
    Ok((
        reference_samples(&rows, 1, columns, with_velocity),
        rows.lines,
    ))
}

/// The reference's samples of `rows`, its values from `start` (after the time), the
/// DVL's fields empty.
fn reference_samples(
    rows: &Rows,
    start: usize,
    columns: &PairedColumns,
    with_velocity: bool,
) -> Unchecked {
    // Where the attitude starts: after the velocity, where it is read.
    let attitude = if with_velocity { start + 3 } else { start };
    Unchecked {
        dvl_time_s: Vec::new(),
        dvl_m_s: Vec::new(),
        dvl_stated: None,
        reference_time_s: rows.column(0).collect(),
        velocity_ned_m_s: if with_velocity {
            triples(rows, start)
        } else {
            Vec::new()
        },
        attitude: triples(rows, attitude),
        rate: columns.rate.as_ref().map(|_| triples(rows, attitude + 3)),
        angles_in_degrees: columns.angles_in_degrees,
        position: positions(rows, attitude + 3, columns),
        reference_read: None,
    }
}

/// The three values of each row from `start`.
fn triples(rows: &Rows, start: usize) -> Vec<Vec3> {
    (0..rows.len())
        .map(|row| {
            let values = &rows.row(row)[start..start + 3];
            [values[0], values[1], values[2]]
        })
        .collect()
}

/// The reference's position columns of `rows` where `columns` names them, after the
/// attitude's (which end at `after`) and the rate's, and whether they are latitude and
/// longitude.
fn positions(rows: &Rows, after: usize, columns: &PairedColumns) -> Option<(Vec<[f64; 2]>, bool)> {
    let (_, geographic) = columns.position()?;
    let start = after + if columns.rate.is_some() { 3 } else { 0 };
    let values = (0..rows.len())
        .map(|row| {
            let values = &rows.row(row)[start..start + 2];
            [values[0], values[1]]
        })
        .collect();
    Some((values, geographic))
}

/// The columns of `names`, each holding `holds`.
fn triple(names: &[String; 3], holds: Quantity) -> Vec<Column<'_>> {
    names.iter().map(|name| Column { name, holds }).collect()
}

/// The reference's columns: its time, velocity (`with_velocity`), attitude, rate and
/// position, those `columns` names.
fn reference_columns<'a>(
    time: Column<'a>,
    columns: &'a PairedColumns,
    with_velocity: bool,
) -> Vec<Column<'a>> {
    let velocity = with_velocity.then(|| triple(&columns.velocity_ned, Quantity::Velocity));
    std::iter::once(time)
        .chain(velocity.into_iter().flatten())
        .chain(triple(&columns.attitude, Quantity::Angle))
        .chain(
            columns
                .rate
                .iter()
                .flat_map(|rate| triple(rate, Quantity::AngularRate)),
        )
        .chain(columns.position().into_iter().flat_map(|(names, _)| {
            names.iter().map(|name| Column {
                name,
                holds: Quantity::Position,
            })
        }))
        .collect()
}
