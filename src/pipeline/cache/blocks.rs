//! The Monte Carlo blocks of the cache, `OUT/.cache/monte_carlo/<key>.parquet`: the
//! per-run rows of one estimator on one DVL, keyed by [`super::block_key`].

use crate::evaluate::RunRow;
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

    pub fn contains(&self, key: &str) -> bool {
        self.path(key).is_file()
    }

    pub fn save(&self, key: &str, rows: &[RunRow]) -> Result<(), ResultsError> {
        std::fs::create_dir_all(&self.folder).map_err(|source| ResultsError::Io {
            path: self.folder.clone(),
            source,
        })?;
        results::write_table(&self.path(key), &results::monte_carlo_batch(rows))
    }

    pub fn load(&self, key: &str) -> Result<Vec<RunRow>, read::ReadError> {
        read::run_rows_at(&self.path(key))
    }
}
