//! Reads a recording from a NumPy `.npy` file: a float array of shape (3, N) or (N, 3)
//! holding x, y, z velocity in m/s, checked for shape, dtype and finite values.

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

/// How many samples `path` holds, from its header alone.
pub fn sample_count(path: &Path) -> Result<usize, NpyError> {
    let read_error = |source| NpyError::Read {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(|source| match source.kind() {
        std::io::ErrorKind::NotFound => NpyError::Missing {
            path: path.to_path_buf(),
        },
        _ => read_error(source),
    })?;
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
}
