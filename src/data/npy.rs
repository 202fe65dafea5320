//! Reads a recording from a NumPy `.npy` file: a float array of shape (3, N) or (N, 3)
//! holding x, y, z velocity in m/s, checked for a whole header and body, shape, dtype and
//! finite values.

use crate::Vec3;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum NpyError {
    #[error("{}: file not found{}", path.display(), crate::spec::recordings::hint_for(path))]
    Missing { path: PathBuf },
    #[error("{}: cannot read as .npy", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: the .npy header is truncated: expected {expected} bytes, found {found}", path.display())]
    TruncatedHeader {
        path: PathBuf,
        expected: u64,
        found: u64,
    },
    #[error("{}: the .npy data are truncated: expected {expected} bytes after the header, found {found}", path.display())]
    TruncatedData {
        path: PathBuf,
        expected: u64,
        found: u64,
    },
    #[error("{}: shape {shape:?}: expected (3, N) or (N, 3) velocity samples", path.display())]
    Shape { path: PathBuf, shape: Vec<u64> },
    #[error("{}: dtype {dtype}: expected float64 or float32", path.display())]
    Dtype { path: PathBuf, dtype: String },
    #[error("{}: sample {sample}, axis {axis} is {value}: every value must be finite", path.display())]
    NonFinite {
        path: PathBuf,
        sample: usize,
        axis: usize,
        value: f64,
    },
}

/// The magic string that opens every `.npy` file.
const MAGIC: &[u8] = b"\x93NUMPY";

/// The bytes before the header's text: the magic string, the version, and the header
/// length (two bytes in version 1, four in later ones).
const PRELUDE_BYTES: u64 = 10;

/// The length of the header of a `.npy` file that opens with `prefix` (at least its first
/// 12 bytes, or the whole file if shorter) and holds `found` bytes, or the
/// [`NpyError::TruncatedHeader`] it is cut in. A file that does not open with the magic
/// string is left to the `.npy` reader to refuse.
fn header_bytes(path: &Path, prefix: &[u8], found: u64) -> Result<u64, NpyError> {
    let truncated = |expected| NpyError::TruncatedHeader {
        path: path.to_path_buf(),
        expected,
        found,
    };
    let opening = &prefix[..prefix.len().min(MAGIC.len())];
    if found < PRELUDE_BYTES && MAGIC.starts_with(opening) {
        return Err(truncated(PRELUDE_BYTES));
    }
    if opening != MAGIC {
        return Ok(0);
    }
    let expected = if prefix[6] == 1 {
        PRELUDE_BYTES + u64::from(u16::from_le_bytes([prefix[8], prefix[9]]))
    } else if found < PRELUDE_BYTES + 2 {
        return Err(truncated(PRELUDE_BYTES + 2));
    } else {
        PRELUDE_BYTES
            + 2
            + u64::from(u32::from_le_bytes([
                prefix[8], prefix[9], prefix[10], prefix[11],
            ]))
    };
    if found < expected {
        return Err(truncated(expected));
    }
    Ok(expected)
}

/// How many samples `path` holds, from its header alone.
pub fn sample_count(path: &Path) -> Result<usize, NpyError> {
    use std::io::Read;
    let read_error = |source| NpyError::Read {
        path: path.to_path_buf(),
        source,
    };
    let mut file = std::fs::File::open(path).map_err(|source| match source.kind() {
        std::io::ErrorKind::NotFound => NpyError::Missing {
            path: path.to_path_buf(),
        },
        _ => read_error(source),
    })?;
    let found = file.metadata().map_err(read_error)?.len();
    let mut prefix = Vec::with_capacity(12);
    (&mut file)
        .take(12)
        .read_to_end(&mut prefix)
        .map_err(read_error)?;
    header_bytes(path, &prefix, found)?;
    let file = std::io::Read::chain(std::io::Cursor::new(prefix), file);
    let header = npyz::NpyFile::new(std::io::BufReader::new(file)).map_err(read_error)?;
    match header.shape() {
        [3, n] | [n, 3] => Ok(*n as usize),
        shape => Err(NpyError::Shape {
            path: path.to_path_buf(),
            shape: shape.to_vec(),
        }),
    }
}

/// The velocity samples of `path`, one `[x, y, z]` per sample.
pub fn read_velocities(path: &Path) -> Result<Vec<Vec3>, NpyError> {
    let read_error = |source| NpyError::Read {
        path: path.to_path_buf(),
        source,
    };
    let bytes = std::fs::read(path).map_err(|source| match source.kind() {
        std::io::ErrorKind::NotFound => NpyError::Missing {
            path: path.to_path_buf(),
        },
        _ => read_error(source),
    })?;
    let header = header_bytes(path, &bytes, bytes.len() as u64)?;
    let file = npyz::NpyFile::new(&bytes[..]).map_err(read_error)?;
    let shape = file.shape().to_vec();
    let strides = file.strides().to_vec();
    let (samples, sample_stride, axis_stride) = match shape[..] {
        [3, n] => (n as usize, strides[1] as usize, strides[0] as usize),
        [n, 3] => (n as usize, strides[0] as usize, strides[1] as usize),
        _ => {
            return Err(NpyError::Shape {
                path: path.to_path_buf(),
                shape,
            });
        }
    };
    let dtype = file.dtype();
    let expected = dtype.num_bytes().unwrap_or(0) as u64 * samples as u64 * 3;
    let found = bytes.len() as u64 - header;
    if header > 0 && found < expected {
        return Err(NpyError::TruncatedData {
            path: path.to_path_buf(),
            expected,
            found,
        });
    }
    let values: Vec<f64> = match dtype.descr().as_str() {
        "'<f8'" | "'>f8'" => file.into_vec::<f64>().map_err(read_error)?,
        "'<f4'" | "'>f4'" => file
            .into_vec::<f32>()
            .map_err(read_error)?
            .into_iter()
            .map(f64::from)
            .collect(),
        other => {
            return Err(NpyError::Dtype {
                path: path.to_path_buf(),
                dtype: other.trim_matches('\'').to_string(),
            });
        }
    };
    (0..samples)
        .map(|sample| {
            let mut v = [0.0; 3];
            for (axis, value) in v.iter_mut().enumerate() {
                *value = values[sample * sample_stride + axis * axis_stride];
                if !value.is_finite() {
                    return Err(NpyError::NonFinite {
                        path: path.to_path_buf(),
                        sample,
                        axis,
                        value: *value,
                    });
                }
            }
            Ok(v)
        })
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Writes `values` with `shape` as a little-endian float64 C-order `.npy`.
    pub(crate) fn write_f64(path: &Path, shape: &[u64], values: &[f64]) {
        let mut out = Vec::new();
        use npyz::WriterBuilder;
        let mut writer = npyz::WriteOptions::new()
            .default_dtype()
            .shape(shape)
            .writer(&mut out)
            .begin_nd()
            .unwrap();
        writer.extend(values.iter().copied()).unwrap();
        writer.finish().unwrap();
        std::fs::write(path, out).unwrap();
    }

    #[test]
    fn reads_both_layouts_to_the_same_samples() {
        let dir = tempfile::tempdir().unwrap();
        let rows = dir.path().join("rows.npy");
        let cols = dir.path().join("cols.npy");
        write_f64(&rows, &[3, 2], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        write_f64(&cols, &[2, 3], &[1.0, 3.0, 5.0, 2.0, 4.0, 6.0]);
        let expected = vec![[1.0, 3.0, 5.0], [2.0, 4.0, 6.0]];
        assert_eq!(read_velocities(&rows).unwrap(), expected);
        assert_eq!(read_velocities(&cols).unwrap(), expected);
    }

    #[test]
    fn rejects_bad_shape_dtype_and_non_finite_values() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.npy");
        write_f64(&path, &[4, 2], &[0.0; 8]);
        assert!(matches!(
            read_velocities(&path),
            Err(NpyError::Shape { .. })
        ));
        // Rows are axes: the third value is y of sample 0.
        write_f64(&path, &[3, 2], &[0.0, 1.0, f64::NAN, 0.0, 0.0, 0.0]);
        let error = read_velocities(&path).unwrap_err();
        assert!(
            matches!(
                error,
                NpyError::NonFinite {
                    sample: 0,
                    axis: 1,
                    ..
                }
            ),
            "{error}"
        );
        let mut out = Vec::new();
        use npyz::WriterBuilder;
        let mut writer = npyz::WriteOptions::<i32>::new()
            .default_dtype()
            .shape(&[3, 1])
            .writer(&mut out)
            .begin_nd()
            .unwrap();
        writer.extend([1, 2, 3]).unwrap();
        writer.finish().unwrap();
        std::fs::write(&path, out).unwrap();
        assert!(matches!(
            read_velocities(&path),
            Err(NpyError::Dtype { .. })
        ));
        let missing = read_velocities(&dir.path().join("V.npy"))
            .unwrap_err()
            .to_string();
        assert!(missing.contains("dcnet-exp data fetch"), "{missing}");
    }

    #[test]
    fn a_truncated_header_or_body_is_named_with_the_bytes_expected_and_found() {
        let dir = tempfile::tempdir().unwrap();
        let whole = dir.path().join("whole.npy");
        write_f64(&whole, &[3, 2], &[0.0; 6]);
        let bytes = std::fs::read(&whole).unwrap();
        // Version 1: a 10-byte prelude and a header padded to 128 bytes in all.
        let cut = dir.path().join("cut.npy");
        for (kept, expected) in [(4, 10), (9, 10), (60, 128)] {
            std::fs::write(&cut, &bytes[..kept]).unwrap();
            let message = format!(
                "{}: the .npy header is truncated: expected {expected} bytes, found {kept}",
                cut.display()
            );
            assert_eq!(read_velocities(&cut).unwrap_err().to_string(), message);
            assert_eq!(sample_count(&cut).unwrap_err().to_string(), message);
        }
        std::fs::write(&cut, &bytes[..bytes.len() - 5]).unwrap();
        assert_eq!(
            read_velocities(&cut).unwrap_err().to_string(),
            format!(
                "{}: the .npy data are truncated: expected 48 bytes after the header, found 43",
                cut.display()
            )
        );
    }
}
