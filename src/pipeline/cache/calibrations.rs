//! The calibrations of installation studies in the cache,
//! `OUT/.cache/installation/<key>.msgpack`: what one calibration trajectory of one
//! study gives over every window and method (a [`Calibrated`]), keyed by
//! [`calibration_key`](super::calibration_key). MessagePack keeps every float as its
//! bits, an infinite standard deviation included, so a study put together from the
//! cache has the bytes of one computed whole.

use crate::files::{self, Seal};
use crate::installation::study::Calibrated;
use std::path::{Path, PathBuf};

/// Why a stored calibration cannot be used or kept.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationStoreError {
    #[error("{}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// The calibrations of the cache.
pub struct CalibrationStore {
    pub folder: PathBuf,
}

impl CalibrationStore {
    /// The store of the cache under the output folder `out`.
    pub fn new(out: &Path) -> Self {
        Self {
            folder: super::root(out).join("installation"),
        }
    }

    pub fn path(&self, key: &str) -> PathBuf {
        self.folder.join(format!("{}.msgpack", &key[..16]))
    }

    /// Whether the calibration of `key` is there and has the bytes its seal names.
    pub fn integrity(&self, key: &str) -> Seal {
        files::check_seal(&self.path(key), key)
    }

    /// The calibration of `key`, when it is stored and intact. One whose seal holds but
    /// whose bytes are no calibration of this version (forged, or written by another
    /// build) is set aside as a damaged one is, said so, and computed again.
    pub fn load(&self, key: &str) -> Result<Option<Calibrated>, CalibrationStoreError> {
        if self.integrity(key) != Seal::Intact {
            return Ok(None);
        }
        let path = self.path(key);
        let bytes = std::fs::read(&path).map_err(|source| CalibrationStoreError::Io {
            path: path.clone(),
            source,
        })?;
        match rmp_serde::from_slice(&bytes) {
            Ok(calibrated) => Ok(Some(calibrated)),
            Err(source) => {
                let damaged = self.damaged_folder();
                let moved = files::set_aside(&path, &damaged).map_err(|source| {
                    CalibrationStoreError::Io {
                        path: path.clone(),
                        source,
                    }
                })?;
                eprintln!(
                    "calibration {}: sealed, but not a calibration of this version ({source}); moved to {} and computed again",
                    path.display(),
                    moved.display()
                );
                Ok(None)
            }
        }
    }

    pub fn save(&self, key: &str, calibrated: &Calibrated) -> Result<(), CalibrationStoreError> {
        files::create_folder(&self.folder).map_err(|source| CalibrationStoreError::Io {
            path: self.folder.clone(),
            source,
        })?;
        let path = self.path(key);
        let bytes = rmp_serde::to_vec_named(calibrated).expect("a calibration serializes");
        files::write_sealed(&path, &bytes, key)
            .map_err(|source| CalibrationStoreError::Io { path, source })
    }

    /// The cache's `damaged/` folder, where entries that cannot be used are set aside.
    fn damaged_folder(&self) -> PathBuf {
        self.folder.with_file_name("damaged")
    }

    /// Moves a damaged calibration of `key` into the cache's `damaged/` folder, so that
    /// it is computed again; returns what was wrong with it.
    pub fn set_aside_damaged(&self, key: &str) -> Result<Option<String>, CalibrationStoreError> {
        let path = self.path(key);
        let damaged = self.damaged_folder();
        files::set_aside_if_damaged(&path, key, &damaged, "calibration")
            .map_err(|source| CalibrationStoreError::Io { path, source })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::installation::study::rows::TermRow;

    #[test]
    fn a_stored_calibration_comes_back_bit_for_bit_and_a_damaged_one_is_not_used() {
        let out = tempfile::tempdir().unwrap();
        let store = CalibrationStore::new(out.path());
        let key = "ab".repeat(32);
        let calibrated = Calibrated {
            terms: vec![TermRow {
                method: "installation all".into(),
                calibration: "T12".into(),
                window_s: 400.0,
                term: "lever_arm_x_m".into(),
                value: -1.886_432_1e-1,
                std: f64::INFINITY,
                bound_std: f64::INFINITY,
                unseen: "flat".into(),
                asked: String::new(),
                between_dives_std: 0.01,
                next_dive_low: -1.95,
                next_dive_high: -1.85,
            }],
            ..Calibrated::default()
        };
        assert_eq!(store.load(&key).unwrap(), None);
        store.save(&key, &calibrated).unwrap();
        let back = store.load(&key).unwrap().unwrap();
        assert_eq!(back, calibrated);
        assert_eq!(
            back.terms[0].value.to_bits(),
            calibrated.terms[0].value.to_bits()
        );
        let mut bytes = std::fs::read(store.path(&key)).unwrap();
        let last = bytes.len() - 1;
        bytes[last] ^= 1;
        std::fs::write(store.path(&key), bytes).unwrap();
        assert_eq!(store.load(&key).unwrap(), None);
        let said = store.set_aside_damaged(&key).unwrap().unwrap();
        assert!(said.contains("moved to"), "{said}");
        assert_eq!(store.integrity(&key), Seal::Absent);
        // Bytes that are no calibration under a seal that holds: set aside, not used.
        files::write_sealed(&store.path(&key), b"not a calibration", &key).unwrap();
        assert_eq!(store.integrity(&key), Seal::Intact);
        assert_eq!(store.load(&key).unwrap(), None);
        assert_eq!(store.integrity(&key), Seal::Absent);
        assert!(
            out.path()
                .join(".cache/damaged")
                .read_dir()
                .unwrap()
                .count()
                >= 2
        );
    }
}
