//! The one model of a report's tables, for every kind of run and both renderings
//! (`report.md` in the kit's `markdown`, `report.tex` in its `latex`). In: the
//! numbers a content room picks from its results. Out: [`Table`]s of [`Entry`]s and
//! the [`Section`]s around them.
//!
//! - [`entry`]: one cell, and how each rendering writes it;
//! - [`cell`]: an RMSE of the paper's layout beside its published value, and the rule
//!   that flags the two apart;
//! - this module: a table (header, label columns, rows in groups, notes) and a section
//!   (a table with its title, caption and the paragraph after it).

pub mod cell;
pub mod entry;

pub(crate) use cell::{Cell, Detail, RmseValue, Signs, Tally};
pub(crate) use entry::{Entry, symbols};

/// A table: its header, its first columns labels of the rows (set left, the values
/// right), its rows in groups set apart by a rule, and the notes set under it.
pub(crate) struct Table {
    pub(crate) header: Vec<String>,
    /// How many of the first columns label the rows.
    pub(crate) label_columns: usize,
    pub(crate) groups: Vec<Vec<Vec<Entry>>>,
    pub(crate) notes: Vec<String>,
}

impl Table {
    /// A table of one label column and one group of `rows`, as a section's is.
    pub(crate) fn new(header: Vec<String>, rows: Vec<Vec<Entry>>, notes: Vec<String>) -> Table {
        Table {
            header,
            label_columns: 1,
            groups: vec![rows],
            notes,
        }
    }

    /// Its cells compared with a published value, and those flagged.
    pub(crate) fn tally(&self) -> Tally {
        Tally::of(
            self.groups
                .iter()
                .flatten()
                .flatten()
                .filter_map(|entry| match entry {
                    Entry::Published(cell) => Some(cell),
                    _ => None,
                }),
        )
    }
}

/// One table of a report's section, with its title, caption and what follows it.
pub(crate) struct Section {
    pub(crate) title: String,
    pub(crate) caption: String,
    pub(crate) table: Table,
    pub(crate) paragraph: Option<String>,
}
