//! The check that runs before a stored table is read, and what can be wrong with a
//! column. In: a Parquet file's schema and its record batches. Out: `check_schema`
//! says whether the schema is the one the writer produces (a column added later may
//! be missing); `Batch` is a batch whose schema passed, for `read::records` to decode
//! into the table's records. A fault is a [`ColumnError`] that names the column where
//! it has one; the caller puts the file's path in front of it.

pub use crate::results::record::{ColumnError, DecodeFault};
use arrow_array::RecordBatch;
use arrow_schema::Schema;

/// Columns added after the first results folders were written: a folder that lacks
/// one still reads, with the value those runs implied.
const LATER_COLUMNS: [&str; 7] = [
    "drift_rms_pct",
    "drift_end_pct",
    "stop_reason",
    "efficiency",
    "between_dives_std",
    "next_dive_low",
    "next_dive_high",
];

pub(super) fn check_schema(found: &Schema, expected: &Schema) -> Result<(), ColumnError> {
    for field in expected.fields() {
        match found.field_with_name(field.name()) {
            Err(_) if LATER_COLUMNS.contains(&field.name().as_str()) => {}
            Err(_) => {
                return Err(ColumnError::Missing {
                    column: field.name().clone(),
                });
            }
            Ok(column) if column.data_type() != field.data_type() => {
                return Err(ColumnError::Type {
                    column: field.name().clone(),
                    found: column.data_type().clone(),
                    expected: field.data_type().clone(),
                });
            }
            Ok(_) => {}
        }
    }
    Ok(())
}

/// A batch whose schema was checked: `read::records` decodes it into a table's
/// records; a sweep's swept columns are read by name.
pub(crate) struct Batch<'a>(pub(crate) &'a RecordBatch);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::training_batch;
    use arrow_schema::DataType;
    use arrow_schema::Field;

    /// The training table's schema with the column `name` dropped, or retyped as text.
    fn altered(name: &str, retype: bool) -> Schema {
        let expected = training_batch(&[]).schema();
        let fields = expected.fields().iter().filter_map(|field| {
            if field.name() != name {
                Some(field.as_ref().clone())
            } else {
                retype.then(|| Field::new(name, DataType::Utf8, false))
            }
        });
        Schema::new(fields.collect::<Vec<_>>())
    }

    #[test]
    fn only_a_later_column_may_be_missing_and_none_may_change_type() {
        let expected = training_batch(&[]).schema();
        assert_eq!(check_schema(&expected, &expected), Ok(()));
        assert_eq!(
            check_schema(&altered("stop_reason", false), &expected),
            Ok(())
        );
        assert_eq!(
            check_schema(&altered("is_best", false), &expected),
            Err(ColumnError::Missing {
                column: "is_best".into()
            })
        );
        assert_eq!(
            check_schema(&altered("epoch", true), &expected),
            Err(ColumnError::Type {
                column: "epoch".into(),
                found: DataType::Utf8,
                expected: DataType::UInt32,
            })
        );
    }
}
