//! The Monte Carlo blocks of the cache, `OUT/.cache/monte_carlo/<key>.parquet`: the
//! per-run rows of one estimator on one DVL, keyed by [`super::block_key`].

use crate::evaluate::RunRow;
use crate::files::{self, Seal};
use crate::results::{self, ResultsError, read};
use std::path::PathBuf;

/// The Monte Carlo blocks of the cache.
pub struct BlockStore {
    pub folder: PathBuf,
}

impl BlockStore {
    pub fn new(folder: PathBuf) -> Self {
        Self { folder }
    }

    pub fn path(&self, key: &str) -> PathBuf {
        self.folder.join(format!("{}.parquet", &key[..16]))
    }

    /// Whether the block of `key` is stored and intact.
    pub fn contains(&self, key: &str) -> bool {
        self.integrity(key) == Seal::Intact
    }

    /// Whether the block of `key` is there and has the bytes its seal names.
    pub fn integrity(&self, key: &str) -> Seal {
        files::check_seal(&self.path(key), key)
    }

    /// Moves a damaged block of `key` into the cache's `damaged/` folder, so that it is
    /// computed again; returns what was wrong with it.
    pub fn set_aside_damaged(&self, key: &str) -> Result<Option<String>, ResultsError> {
        let path = self.path(key);
        let damaged = self.folder.with_file_name("damaged");
        files::set_aside_if_damaged(&path, key, &damaged, "Monte Carlo block")
            .map_err(|source| ResultsError::Io { path, source })
    }

    pub fn save(&self, key: &str, rows: &[RunRow]) -> Result<(), ResultsError> {
        crate::files::create_folder(&self.folder).map_err(|source| ResultsError::Io {
            path: self.folder.clone(),
            source,
        })?;
        let path = self.path(key);
        let bytes = results::table_bytes(&path, &results::monte_carlo_batch(rows))?;
        files::write_sealed(&path, &bytes, key).map_err(|source| ResultsError::Io { path, source })
    }

    pub fn load(&self, key: &str) -> Result<Vec<RunRow>, read::ReadError> {
        read::run_rows_at(&self.path(key))
    }
}
