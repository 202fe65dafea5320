//! What an operator's command will ask of this machine, known before it reads a
//! recording: the rows of the files it reads, counted, and the memory they need at the
//! command's measured bytes per row, beside the memory this process may use. Each
//! command states its cost on stderr before it starts, and refuses up front where the
//! memory is beyond the machine's (a recording too long once aborted on a failed
//! allocation, with a backtrace). In: the command's files and its [`PerRow`]. Out: a
//! [`Cost`], or the [`BeyondMemory`] that refuses it.

use crate::data::csv::row_count;
use crate::data::paired::PairedError;
use crate::data::paired::bag::{Bag, is_bag, message_counts};
use crate::footprint::{Bytes, machine_memory};
use crate::memory::address_space_limit;
use std::fmt;
use std::path::{Path, PathBuf};

/// A command's peak resident memory per row of the files it reads, bytes: a DVL row and
/// a row of the reference beside it (a file that holds both counts both). Read off the
/// peaks of synthetic dives of one and five hours at 100 Hz, the DVL at 100 and 10 Hz
/// (`cargo bench --bench dive -- --memory` prints each beside its estimate), and
/// rounded up: the estimate lies above every peak measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PerRow {
    /// The command, as the refusal says it ("calibrate").
    pub command: &'static str,
    pub dvl: f64,
    pub reference: f64,
    /// A position fix's row, where the command reads fixes.
    pub fix: f64,
    /// What to do instead, as the refusal says it.
    pub instead: &'static str,
}

/// `calibrate` of one recording: the rows read, the filter's state after each sample
/// and its terms against time.
pub const CALIBRATE: PerRow = PerRow {
    command: "calibrate",
    dvl: 3_200.0,
    reference: 400.0,
    fix: 0.0,
    instead: "calibrate a part of it, a file of fewer rows",
};

/// `correct` of a dive: the rows read, the dive corrected, and its files written.
pub const CORRECT: PerRow = PerRow {
    command: "correct",
    dvl: 450.0,
    reference: 500.0,
    fix: 0.0,
    instead: "correct it in parts, files of fewer rows",
};

/// A joint `calibrate`: every recording's rows, its fit alone and the joint fit's
/// stacked Jacobian.
pub const JOINT: PerRow = PerRow {
    command: "calibrate jointly",
    dvl: 1_200.0,
    reference: 450.0,
    fix: 0.0,
    instead: "calibrate fewer recordings jointly, or parts of them",
};

/// `calibrate --fixes`: the DVL's and the attitude's rows read, the fixes', and the fit's
/// dead reckoning and whitened fixes (linear in each: the fixes' noise is never held as
/// an n × n covariance). Peaks of an hour's dive with the attitude at 100 Hz, the DVL
/// at 100 Hz with a fix a second (257 MB) and at 10 Hz with ten fixes a second
/// (135 MB; `cargo bench --bench dive -- --memory fixes`), rounded up.
pub const FIXES: PerRow = PerRow {
    command: "calibrate with fixes",
    dvl: 600.0,
    reference: 400.0,
    fix: 2_000.0,
    instead: "calibrate a part of it, files of fewer rows",
};

/// `correct --fixes`: as [`FIXES`], its fit one parameter (the clock) and the dive
/// corrected.
pub const CORRECT_FIXES: PerRow = PerRow {
    command: "correct with fixes",
    instead: "correct it in parts, files of fewer rows",
    ..FIXES
};

/// A joint `calibrate` with fixes: as [`FIXES`] over every dive, each held until all
/// are fitted.
pub const JOINT_FIXES: PerRow = PerRow {
    command: "calibrate jointly with fixes",
    instead: "calibrate fewer dives jointly, or parts of them",
    ..FIXES
};

/// The rows of one recording's files.
#[derive(Debug, Clone, PartialEq)]
pub struct Rows {
    pub dvl: PathBuf,
    pub dvl_rows: usize,
    /// The rows of the reference's own file; `None` where the DVL's file holds it.
    pub reference_rows: Option<usize>,
    /// The rows of a file of position fixes read beside them.
    pub fix_rows: Option<usize>,
}

impl Rows {
    /// The rows of `dvl` and of `reference` where it is a file of its own; of a bag,
    /// the messages of the topics it could be read from.
    pub fn count(dvl: &Path, reference: Option<&Path>) -> Result<Rows, PairedError> {
        if is_bag(dvl) {
            let (dvl_rows, reference_rows) = message_counts(dvl, None)?;
            return Ok(Rows {
                dvl: dvl.to_path_buf(),
                dvl_rows: dvl_rows as usize,
                reference_rows: Some(reference_rows as usize),
                fix_rows: None,
            });
        }
        if crate::data::paired::dvl_log::format_of(dvl).is_some() {
            // A PD0 ensemble with bottom track holds 200 bytes or more.
            let bytes = std::fs::metadata(dvl).map_or(0, |m| m.len());
            return Ok(Rows {
                dvl: dvl.to_path_buf(),
                dvl_rows: (bytes / 200) as usize,
                reference_rows: reference.filter(|&r| r != dvl).map(row_count).transpose()?,
                fix_rows: None,
            });
        }
        Ok(Rows {
            dvl: dvl.to_path_buf(),
            dvl_rows: row_count(dvl)?,
            reference_rows: reference.map(row_count).transpose()?,
            fix_rows: None,
        })
    }

    /// These rows and those of the position fixes in `fixes`
    /// (a bag's messages of the topic `topic`, where named).
    pub fn with_fixes(self, fixes: &Path, topic: Option<&str>) -> Result<Rows, PairedError> {
        let fix_rows = match topic {
            // A log's own fixes, at most one a ping.
            None if fixes == self.dvl => self.dvl_rows,
            Some(topic) => (Bag::open(fixes)?.counts()?.topics.iter())
                .filter(|t| t.name == topic)
                .map(|t| t.count as usize)
                .sum(),
            None => row_count(fixes)?,
        };
        Ok(Rows {
            fix_rows: Some(fix_rows),
            ..self
        })
    }

    /// Every row read.
    fn all(&self) -> usize {
        self.dvl_rows + self.reference_rows.unwrap_or(0) + self.fix_rows.unwrap_or(0)
    }

    /// The memory of these rows at `per_row`, bytes.
    fn bytes(&self, per_row: PerRow) -> f64 {
        let fixes = self.fix_rows.unwrap_or(0) as f64 * per_row.fix;
        fixes
            + match self.reference_rows {
                Some(rows) => self.dvl_rows as f64 * per_row.dvl + rows as f64 * per_row.reference,
                None => self.dvl_rows as f64 * (per_row.dvl + per_row.reference),
            }
    }
}

/// What a command will ask: its recordings' rows and the memory they need, beside what
/// this process may use.
#[derive(Debug, Clone, PartialEq)]
pub struct Cost {
    pub per_row: PerRow,
    pub recordings: Vec<Rows>,
    /// Bytes: needed at the peak, and what this process may use.
    pub need: f64,
    pub have: f64,
}

impl Cost {
    /// The cost of `per_row`'s command over `recordings`, each a DVL file and its
    /// reference's where it is a file of its own, on this machine.
    pub fn of(per_row: PerRow, recordings: &[(&Path, Option<&Path>)]) -> Result<Cost, PairedError> {
        let recordings = recordings
            .iter()
            .map(|&(dvl, reference)| Rows::count(dvl, reference))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Cost::on(per_row, recordings, machine_memory() as f64))
    }

    /// The cost of `recordings` on a machine of `have` bytes.
    pub fn on(per_row: PerRow, recordings: Vec<Rows>, have: f64) -> Cost {
        let need = recordings.iter().map(|r| r.bytes(per_row)).sum();
        Cost {
            per_row,
            recordings,
            need,
            have,
        }
    }

    /// Every row the command reads.
    pub fn rows(&self) -> usize {
        self.recordings.iter().map(Rows::all).sum()
    }

    /// Says the cost on stderr, before the command reads its recordings, or refuses it
    /// where the memory is beyond this process's.
    pub fn state(&self) -> Result<(), BeyondMemory> {
        self.refused()?;
        eprintln!("{self}");
        Ok(())
    }

    /// The refusal of a cost beyond this machine's memory.
    pub fn refused(&self) -> Result<(), BeyondMemory> {
        if self.need <= self.have {
            return Ok(());
        }
        Err(BeyondMemory {
            files: self.files(),
            rows: self.rows(),
            need: self.need,
            have: self.have,
            per_row: self.per_row,
            address_limit: address_space_limit(),
        })
    }

    /// The files read, as a message names them: the first DVL's, and how many others.
    fn files(&self) -> String {
        let first = self.recordings[0].dvl.display();
        let files: usize = (self.recordings.iter())
            .map(|r| {
                let own = !is_bag(&r.dvl);
                1 + usize::from(r.reference_rows.is_some() && own)
                    + usize::from(r.fix_rows.is_some() && own)
            })
            .sum();
        let others = files - 1;
        match others {
            0 => first.to_string(),
            1 => format!("{first} and 1 other file"),
            n => format!("{first} and {n} other files"),
        }
    }
}

impl fmt::Display for Cost {
    /// `calibrate: 800 rows (dive.csv and 1 other file), about 1.4 MiB of memory of the 23.4 GiB this process may use`
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} rows ({}), about {} of memory of the {} this process may use",
            self.per_row.command,
            self.rows(),
            self.files(),
            Bytes(self.need),
            Bytes(self.have)
        )
    }
}

/// A command refused before it reads its recordings: they need more memory than this
/// process may use.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "{files}: {rows} rows need about {} of memory to {} and this process may use {}{}: {}",
    Bytes(*need),
    per_row.command,
    Bytes(*have),
    address_limit.map_or_else(String::new, |limit| format!(
        " (what its address-space limit, ulimit -v, of {} leaves once its code, stacks and threads are held)",
        Bytes(limit as f64)
    )),
    per_row.instead
)]
pub struct BeyondMemory {
    pub files: String,
    pub rows: usize,
    pub need: f64,
    pub have: f64,
    pub per_row: PerRow,
    /// The address-space limit this process runs under, bytes, where it has one.
    pub address_limit: Option<u64>,
}
