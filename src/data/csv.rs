//! Reads a recording from a CSV file: a header row, then one row a sample, with the
//! x, y, z velocity in m/s in the three columns the spec names (by default those of
//! `trajectories.parquet`, [`crate::VELOCITY_COLUMNS`]); other columns are
//! ignored, in any order. [`read_columns`] reads any named columns the same way (the
//! recordings of a DVL beside a reference use it).
//! Every row is checked: a field that is missing, empty, not a number or not finite is
//! an error that names the file, the line (the header is line 1) and the column, and so
//! is a blank line between samples (blank lines at the end are allowed).

use crate::Vec3;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum CsvError {
    #[error("{}: file not found", path.display())]
    Missing { path: PathBuf },
    #[error("{}: not a regular file (a device or a pipe): a recording is a CSV file", path.display())]
    NotAFile { path: PathBuf },
    #[error("{}: {what}", path.display())]
    NotCsv { path: PathBuf, what: &'static str },
    #[error("{}: cannot read as CSV", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: ::csv::Error,
    },
    #[error("{}: cannot read as CSV", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}:1: {column}: not in the header, which has {}", path.display(), found_list(found))]
    MissingColumn {
        path: PathBuf,
        column: String,
        found: Vec<String>,
    },
    #[error("{}:1: {column}: named twice in the header", path.display())]
    DuplicateColumn { path: PathBuf, column: String },
    #[error("{}: no rows below the header: a recording needs at least one sample", path.display())]
    NoRows { path: PathBuf },
    #[error(
        "{}:{line}: blank line: every line below the header is a sample, and a blank one would shift the samples after it",
        path.display()
    )]
    BlankLine { path: PathBuf, line: u64 },
    #[error("{}:{line}: {column}: {problem}", path.display())]
    Field {
        path: PathBuf,
        line: u64,
        /// The column's name in the header, or `field N` beyond it.
        column: String,
        problem: FieldProblem,
    },
}

/// What is wrong with one field of a row.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FieldProblem {
    #[error("missing: the row has {fields} fields, the header {header}")]
    Missing { fields: usize, header: usize },
    #[error("not in the header: the row has {fields} fields, the header {header}")]
    Extra { fields: usize, header: usize },
    #[error("empty: every row needs {}", .0.with_article())]
    Empty(Quantity),
    #[error("{0:?} is not a number")]
    NotANumber(String),
    #[error(
        "{0:?} is not a validity flag: give 1 or true for a valid sample, 0 or false for one that is not"
    )]
    NotAFlag(String),
    #[error("{0:?} is not finite: every {noun} must be a finite number", noun = .1.noun())]
    NonFinite(String, Quantity),
}

/// What a column holds, in the words its faults use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    Time,
    Velocity,
    /// A DVL's velocity, which is missing where the DVL lost bottom lock: an empty or
    /// NaN field is read as NaN, for the recording's checks to leave the sample out and
    /// count it.
    MeasuredVelocity,
    Angle,
    AngularRate,
    /// A sample's validity: 1 or `true` valid, 0 or `false` not (read as 1 or 0).
    Validity,
    /// A position: metres, or a latitude or longitude.
    Position,
}

impl Quantity {
    /// "velocity", as in "every velocity must be a finite number".
    pub fn noun(self) -> &'static str {
        match self {
            Quantity::Time => "time stamp",
            Quantity::Velocity | Quantity::MeasuredVelocity => "velocity",
            Quantity::Angle => "angle",
            Quantity::AngularRate => "angular rate",
            Quantity::Validity => "validity flag",
            Quantity::Position => "position",
        }
    }

    /// "a velocity", as in "every row needs a velocity".
    pub fn with_article(self) -> &'static str {
        match self {
            Quantity::Time => "a time stamp",
            Quantity::Velocity | Quantity::MeasuredVelocity => "a velocity",
            Quantity::Angle => "an angle",
            Quantity::AngularRate => "an angular rate",
            Quantity::Validity => "a validity flag (1, 0, true or false)",
            Quantity::Position => "a position",
        }
    }
}

/// One column to read: its name in the header and what it holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Column<'a> {
    pub name: &'a str,
    pub holds: Quantity,
}

/// The columns asked of a CSV file, read and checked: each row's line in the file (the
/// header is line 1) and its values, in the order the columns were asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct Rows {
    /// The line of each row.
    pub lines: Vec<u64>,
    /// How many values a row has: the number of columns asked for.
    pub width: usize,
    /// The values, row after row.
    pub values: Vec<f64>,
}

impl Rows {
    pub fn len(&self) -> usize {
        self.lines.len()
    }

    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }

    /// The values of row `index`, in the order the columns were asked for.
    pub fn row(&self, index: usize) -> &[f64] {
        &self.values[index * self.width..(index + 1) * self.width]
    }

    /// The values of column `column` (its place among those asked for), row after row.
    pub fn column(&self, column: usize) -> impl Iterator<Item = f64> + '_ {
        self.values.iter().skip(column).step_by(self.width).copied()
    }
}

fn found_list(found: &[String]) -> String {
    if found.iter().all(String::is_empty) {
        "no names (the first line is empty)".into()
    } else {
        found.join(", ")
    }
}

/// The velocity samples of `path`, one `[x, y, z]` per row, from `columns` (x, y, z).
pub fn read_velocities(path: &Path, columns: &[String; 3]) -> Result<Vec<Vec3>, CsvError> {
    let columns = columns.each_ref().map(|name| Column {
        name,
        holds: Quantity::Velocity,
    });
    let rows = read_columns(path, &columns)?;
    if rows.is_empty() {
        return Err(CsvError::NoRows {
            path: path.to_path_buf(),
        });
    }
    Ok(rows
        .values
        .chunks_exact(3)
        .map(|row| [row[0], row[1], row[2]])
        .collect())
}

/// The `columns` of `path`, every row checked: each field of a row must be there and,
/// in the columns asked for, a finite number; a blank line between rows is an error.
/// A file with a header and no rows gives no rows.
pub fn read_columns(path: &Path, columns: &[Column]) -> Result<Rows, CsvError> {
    parse_columns(path, &read_bytes(path)?, columns)
}

/// The `columns` of `bytes`, the contents of `path` already read (by [`read_bytes`]),
/// checked as [`read_columns`] checks them.
pub fn parse_columns(path: &Path, bytes: &[u8], columns: &[Column]) -> Result<Rows, CsvError> {
    let read_error = |source| CsvError::Read {
        path: path.to_path_buf(),
        source,
    };
    let mut reader = ::csv::ReaderBuilder::new()
        .flexible(true)
        .trim(::csv::Trim::All)
        .from_reader(bytes);
    let header: Vec<String> = reader
        .headers()
        .map_err(read_error)?
        .iter()
        .map(String::from)
        .collect();
    let positions = column_positions(path, &header, columns)?;
    let mut rows = Rows {
        lines: Vec::new(),
        width: columns.len(),
        values: Vec::new(),
    };
    for record in reader.records() {
        let record = record.map_err(read_error)?;
        let (line, first_blank) = record
            .position()
            .map_or((0, None), |position| record_lines(bytes, position));
        if let Some(line) = first_blank {
            return Err(CsvError::BlankLine {
                path: path.to_path_buf(),
                line,
            });
        }
        read_row(path, line, &header, &positions, &record, &mut rows.values)?;
        rows.lines.push(line);
    }
    Ok(rows)
}

/// How many rows below the header `path` holds, counted without parsing them: an
/// upper bound of its samples, known before it is read.
pub fn row_count(path: &Path) -> Result<usize, CsvError> {
    use std::io::Read;
    regular(path)?;
    let mut file = std::fs::File::open(path).map_err(|source| io_error(path, source))?;
    let mut buffer = vec![0u8; 1 << 20];
    // Lines that hold something: each newline after another byte than a newline, and a
    // last line without one.
    let (mut lines, mut previous) = (0, b'\n');
    loop {
        let read = match file.read(&mut buffer) {
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            read => read.map_err(|source| io_error(path, source))?,
        };
        let Some(&last) = buffer[..read].last() else {
            break;
        };
        let chunk = &buffer[..read];
        lines += usize::from(chunk[0] == b'\n' && previous != b'\n');
        lines += chunk
            .windows(2)
            .filter(|pair| pair[1] == b'\n' && pair[0] != b'\n')
            .count();
        previous = last;
    }
    lines += usize::from(previous != b'\n');
    Ok(lines.saturating_sub(1))
}

/// The bytes of `path`; a missing file is [`CsvError::Missing`], a device or a pipe
/// (`/dev/zero` would be read until memory runs out) [`CsvError::NotAFile`].
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, CsvError> {
    regular(path)?;
    std::fs::read(path).map_err(|source| io_error(path, source))
}

/// Refuses a `path` that is a device or a pipe (followed through its links), a folder
/// (a rosbag2 folder that lost its `metadata.yaml`, say) and a ROS 1 bag, each as what
/// it is rather than as a CSV file that could not be read.
fn regular(path: &Path) -> Result<(), CsvError> {
    let metadata = std::fs::metadata(path).map_err(|source| io_error(path, source))?;
    let not_csv = |what: &'static str| {
        Err(CsvError::NotCsv {
            path: path.to_path_buf(),
            what,
        })
    };
    if metadata.is_dir() {
        not_csv(
            "a folder with no metadata.yaml, so not a bag, and not a CSV file: a rosbag2 folder holds metadata.yaml beside its files (give its .mcap or .db3 file itself where that was lost)",
        )
    } else if path.extension().is_some_and(|e| e == "bag") {
        not_csv(
            "a ROS 1 bag, which this tool does not read: convert it to a ROS 2 bag first (rosbags-convert, of the Python package rosbags, writes one)",
        )
    } else if metadata.is_file() {
        Ok(())
    } else {
        Err(CsvError::NotAFile {
            path: path.to_path_buf(),
        })
    }
}

/// `source`, met opening or reading `path`: [`CsvError::Missing`] where the file is
/// not there.
fn io_error(path: &Path, source: std::io::Error) -> CsvError {
    match source.kind() {
        std::io::ErrorKind::NotFound => CsvError::Missing {
            path: path.to_path_buf(),
        },
        _ => CsvError::Io {
            path: path.to_path_buf(),
            source,
        },
    }
}

/// The index in `header` of each of `columns` and what it holds; each column must be
/// there exactly once.
fn column_positions(
    path: &Path,
    header: &[String],
    columns: &[Column],
) -> Result<Vec<(usize, Quantity)>, CsvError> {
    let mut positions = Vec::with_capacity(columns.len());
    for column in columns {
        let mut found = header
            .iter()
            .enumerate()
            .filter(|(_, name)| *name == column.name);
        let position = match (found.next(), found.next()) {
            (Some((index, _)), None) => index,
            (Some(_), Some(_)) => {
                return Err(CsvError::DuplicateColumn {
                    path: path.to_path_buf(),
                    column: column.name.to_string(),
                });
            }
            (None, _) => {
                return Err(CsvError::MissingColumn {
                    path: path.to_path_buf(),
                    column: column.name.to_string(),
                    found: header.to_vec(),
                });
            }
        };
        positions.push((position, column.holds));
    }
    Ok(positions)
}

/// A record's line in `bytes` and, when blank lines precede it, the first of them.
///
/// A record's position starts at the line ends the reader skipped before it: the `\n`
/// of the previous line's `\r\n`, then those of blank lines.
fn record_lines(bytes: &[u8], position: &::csv::Position) -> (u64, Option<u64>) {
    let start = position.byte() as usize;
    let newlines = bytes[start..]
        .iter()
        .take_while(|b| matches!(b, b'\n' | b'\r'))
        .filter(|b| **b == b'\n')
        .count() as u64;
    let crlf_end =
        u64::from(start > 0 && bytes[start - 1] == b'\r' && bytes.get(start) == Some(&b'\n'));
    let first_blank = (newlines > crlf_end).then_some(position.line() + crlf_end);
    (position.line() + newlines, first_blank)
}

/// The values of `record`, on `line`, from the fields at `positions`, appended to
/// `values`; the record must be as wide as `header`.
fn read_row(
    path: &Path,
    line: u64,
    header: &[String],
    positions: &[(usize, Quantity)],
    record: &::csv::StringRecord,
    values: &mut Vec<f64>,
) -> Result<(), CsvError> {
    let fault = |index: usize, problem| CsvError::Field {
        path: path.to_path_buf(),
        line,
        column: header
            .get(index)
            .cloned()
            .unwrap_or_else(|| format!("field {}", index + 1)),
        problem,
    };
    let (fields, width) = (record.len(), header.len());
    if fields < width {
        return Err(fault(
            fields,
            FieldProblem::Missing {
                fields,
                header: width,
            },
        ));
    }
    if fields > width {
        return Err(fault(
            width,
            FieldProblem::Extra {
                fields,
                header: width,
            },
        ));
    }
    for &(index, holds) in positions {
        values.push(parse(&record[index], holds).map_err(|problem| fault(index, problem))?);
    }
    Ok(())
}

/// One field, which holds `holds`, as a finite number; a DVL's velocity that is empty
/// or NaN as NaN, a validity flag as 1 or 0.
fn parse(text: &str, holds: Quantity) -> Result<f64, FieldProblem> {
    let missing = text.is_empty() || text.eq_ignore_ascii_case("nan");
    if holds == Quantity::MeasuredVelocity && missing {
        return Ok(f64::NAN);
    }
    if text.is_empty() {
        return Err(FieldProblem::Empty(holds));
    }
    if holds == Quantity::Validity {
        return match text.to_ascii_lowercase().as_str() {
            "1" | "true" => Ok(1.0),
            "0" | "false" => Ok(0.0),
            _ => Err(FieldProblem::NotAFlag(text.to_string())),
        };
    }
    match text.parse::<f64>() {
        Ok(value) if value.is_finite() => Ok(value),
        Ok(_) => Err(FieldProblem::NonFinite(text.to_string(), holds)),
        Err(_) => Err(FieldProblem::NotANumber(text.to_string())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows below the header, blank lines not counted, whether the last row ends in a
    /// newline or not, with CRLF endings, and across the counting's 1 MiB reads.
    #[test]
    fn rows_are_counted_without_blank_lines() {
        let folder = tempfile::tempdir().unwrap();
        let counted = |text: &str| {
            let path = folder.path().join("rows.csv");
            std::fs::write(&path, text).unwrap();
            row_count(&path).unwrap()
        };
        assert_eq!(counted("t,v\n1,2\n\n3,4\n"), 2);
        assert_eq!(counted("t,v\r\n1,2\r\n3,4"), 2);
        assert_eq!(counted("\n\nt,v\n\n"), 0);
        assert_eq!(counted(""), 0);
        let long = "t,v\n".to_string() + &"12345.678,0.25\n\n".repeat(200_000);
        assert!(long.len() > 2 << 20);
        assert_eq!(counted(&long), 200_000);
    }

    fn columns() -> [String; 3] {
        crate::VELOCITY_COLUMNS.map(String::from)
    }

    /// Reads `text` as a CSV file; errors with the file's path shown as FILE.
    fn read(text: &str) -> Result<Vec<Vec3>, String> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("recording.csv");
        std::fs::write(&path, text).unwrap();
        read_velocities(&path, &columns())
            .map_err(|e| e.to_string().replace(&path.display().to_string(), "FILE"))
    }

    #[test]
    fn reads_the_named_columns_in_any_order_and_ignores_the_others() {
        let text = "time_s, vz_m_s,depth_m,vx_m_s,vy_m_s\n\
                    0,0.01,5.0,1.5,-0.25\n\
                    1, -0.02 ,5.1,1.25,1e-3\n";
        assert_eq!(
            read(text).unwrap(),
            vec![[1.5, -0.25, 0.01], [1.25, 0.001, -0.02]]
        );
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("other.csv");
        std::fs::write(&path, "u,v,w\n1,2,3\n").unwrap();
        let named = ["w", "u", "v"].map(String::from);
        assert_eq!(
            read_velocities(&path, &named).unwrap(),
            vec![[3.0, 1.0, 2.0]]
        );
    }

    #[test]
    fn a_bad_row_names_the_line_and_the_column() {
        let header = "time_s,vx_m_s,vy_m_s,vz_m_s\n0,1.0,0.5,0.0\n";
        for (row, expected) in [
            ("1,1.0,abc,0.0", "FILE:3: vy_m_s: \"abc\" is not a number"),
            (
                "1,1.0,,0.0",
                "FILE:3: vy_m_s: empty: every row needs a velocity",
            ),
            (
                "1,NaN,0.5,0.0",
                "FILE:3: vx_m_s: \"NaN\" is not finite: every velocity must be a finite number",
            ),
            (
                "1,1.0,0.5,inf",
                "FILE:3: vz_m_s: \"inf\" is not finite: every velocity must be a finite number",
            ),
            (
                "1,1.0,0.5",
                "FILE:3: vz_m_s: missing: the row has 3 fields, the header 4",
            ),
            (
                "1,1.0,0.5,0.0,9",
                "FILE:3: field 5: not in the header: the row has 5 fields, the header 4",
            ),
        ] {
            assert_eq!(read(&format!("{header}{row}\n")).unwrap_err(), expected);
        }
        // A blank line between samples would shift the ones after it; at the end it
        // shifts nothing.
        let blank = "blank line: every line below the header is a sample, and a blank one would shift the samples after it";
        assert_eq!(
            read(&format!("{header}1,0,0,0\n\n2,1,1,1\n")).unwrap_err(),
            format!("FILE:4: {blank}")
        );
        assert_eq!(
            read("vx_m_s,vy_m_s,vz_m_s\r\n0,1,2\r\n\r\n1,2,3\r\n").unwrap_err(),
            format!("FILE:3: {blank}")
        );
        assert_eq!(
            read(&format!("{header}1,0,0,0\n\n\r\n")).unwrap(),
            vec![[1.0, 0.5, 0.0], [0.0, 0.0, 0.0]]
        );
        // Windows line ends, and a quoted field over two lines, keep the count.
        assert_eq!(
            read("vx_m_s,vy_m_s,vz_m_s\r\n0,1,2\r\n1,z,3\r\n").unwrap_err(),
            "FILE:3: vy_m_s: \"z\" is not a number"
        );
        assert_eq!(
            read("note,vx_m_s,vy_m_s,vz_m_s\n\"a\nb\",0,1,2\n,1,w,3\n").unwrap_err(),
            "FILE:4: vy_m_s: \"w\" is not a number"
        );
    }

    #[test]
    fn a_file_that_cannot_be_read_keeps_its_cause_and_prints_it_once() {
        let dir = tempfile::tempdir().unwrap();
        // A path beneath a file: the system says it is not a folder.
        std::fs::write(dir.path().join("file"), b"").unwrap();
        let beneath = dir.path().join("file/x.csv");
        let error = read_velocities(&beneath, &columns()).unwrap_err();
        assert!(matches!(error, CsvError::Io { .. }), "{error:?}");
        let cause = std::error::Error::source(&error)
            .expect("the cause is kept")
            .to_string();
        let shown = format!("{:#}", anyhow::Error::from(error));
        assert_eq!(
            shown,
            format!("{}: cannot read as CSV: {cause}", beneath.display())
        );
        let error = read_velocities(dir.path(), &columns()).unwrap_err();
        assert!(
            error.to_string().contains("a folder with no metadata.yaml"),
            "{error}"
        );
        // Invalid UTF-8 in the header is the CSV reader's fault, kept as the cause.
        let path = dir.path().join("latin1.csv");
        std::fs::write(&path, b"vx_m_s,vy_m_s,vz_\xb5\n0,1,2\n").unwrap();
        let error = read_velocities(&path, &columns()).unwrap_err();
        assert!(matches!(error, CsvError::Read { .. }), "{error:?}");
        let shown = format!("{:#}", anyhow::Error::from(error));
        assert!(
            shown.starts_with(&format!(
                "{}: cannot read as CSV: CSV parse error",
                path.display()
            )),
            "{shown}"
        );
        assert_eq!(shown.matches("cannot read").count(), 1, "{shown}");
    }

    #[test]
    fn a_bad_header_names_the_column_and_what_was_found() {
        assert_eq!(
            read("time_s,vx_m_s,vy_m_s\n0,1,2\n").unwrap_err(),
            "FILE:1: vz_m_s: not in the header, which has time_s, vx_m_s, vy_m_s"
        );
        assert_eq!(
            read("vx_m_s,vy_m_s,vz_m_s,vx_m_s\n0,1,2,3\n").unwrap_err(),
            "FILE:1: vx_m_s: named twice in the header"
        );
        assert_eq!(
            read("vx_m_s,vy_m_s,vz_m_s\n").unwrap_err(),
            "FILE: no rows below the header: a recording needs at least one sample"
        );
        assert_eq!(
            read("").unwrap_err(),
            "FILE:1: vx_m_s: not in the header, which has no names (the first line is empty)"
        );
    }
}
