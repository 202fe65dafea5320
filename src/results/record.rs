//! A results table as typed rows: each table has a flat record type, one field per
//! column named as the column (a vector as three fields, a name as its text), and
//! serde_arrow turns a slice of records into an Arrow batch and a checked batch back
//! into records. In: records, or a stored batch whose schema `read` checked. Out: the
//! batch the Parquet writer takes (each column nullable only where a value is empty,
//! as the tables have always been written), or the records, a fault naming its column.

use arrow_array::{Array, ArrayRef, RecordBatch};
use arrow_schema::{DataType, FieldRef, Schema};
use serde::Serialize;
use serde::de::DeserializeOwned;
use serde_arrow::schema::{SchemaLike, TracingOptions};
use std::sync::Arc;

/// What is wrong with one column of a stored table: the fault itself, shown after the
/// file's path by `ReadError::Column`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ColumnError {
    #[error("column `{column}` is missing: this is not the schema dcnet-exp writes")]
    Missing { column: String },
    #[error(
        "column `{column}` holds {found}, expected {expected}: this is not the schema dcnet-exp writes"
    )]
    Type {
        column: String,
        found: DataType,
        expected: DataType,
    },
    #[error("column `{column}` has empty values")]
    Empty { column: String },
    /// A name that does not parse; `problem` is what the name's type says of it.
    #[error("column `{column}`: {problem}")]
    Value { column: String, problem: String },
    /// A swept key of the sweep's index that the sweep table lacks.
    #[error("column `{column}`, a swept key of {index}, is missing")]
    SweptMissing { column: String, index: &'static str },
    #[error("column `{column}` holds {found}, expected Int64, Float64 or Utf8")]
    SweptType { column: String, found: DataType },
    /// Columns of the checked types and without empty values that still do not decode
    /// into the table's records.
    #[error("its rows do not decode")]
    Decode(#[source] DecodeFault),
}

/// What serde_arrow said of rows it could not decode; two faults are equal when they
/// are the same one.
#[derive(Debug, Clone, thiserror::Error)]
#[error(transparent)]
pub struct DecodeFault(pub std::sync::Arc<serde_arrow::Error>);

impl PartialEq for DecodeFault {
    fn eq(&self, other: &Self) -> bool {
        std::sync::Arc::ptr_eq(&self.0, &other.0)
    }
}

/// The record of one row of a results table.
pub trait Record: Serialize + DeserializeOwned {
    /// Columns written only when some row has a value there (`replicate` with DCNet
    /// replicates, say): a table that lacks one reads as all empty there.
    const SOMETIMES: &'static [&'static str] = &[];
}

/// The columns of `R`, in the order of its fields: text as Utf8, an `Option` nullable.
pub fn fields<R: Record>() -> Vec<FieldRef> {
    let options = TracingOptions::default().strings_as_large_utf8(false);
    Vec::<FieldRef>::from_type::<R>(options).expect("a record of plain fields traces")
}

/// The schema a stored table of `R` is checked against: every column but those
/// written only sometimes.
pub fn expected<R: Record>() -> Schema {
    let fields = fields::<R>().into_iter();
    Schema::new(
        fields
            .filter(|f| !R::SOMETIMES.contains(&f.name().as_str()))
            .collect::<Vec<_>>(),
    )
}

/// `rows` as one batch; a sometimes-column where every row is empty is left out.
pub fn encode<R: Record>(rows: &[R]) -> RecordBatch {
    let fields = fields::<R>();
    let arrays = serde_arrow::to_arrow(&fields, rows).expect("a record of plain fields encodes");
    let columns = fields.iter().zip(arrays).filter(|(field, array)| {
        !(R::SOMETIMES.contains(&field.name().as_str()) && array.null_count() == array.len())
    });
    batch(columns.map(|(field, array)| (field.name().clone(), array)))
}

/// A batch of `columns`, each nullable where it holds an empty value.
pub fn batch(columns: impl IntoIterator<Item = (String, ArrayRef)>) -> RecordBatch {
    RecordBatch::try_from_iter(columns).expect("columns of one table have equal lengths")
}

/// The columns of `batch` by name, to put beside others in one table.
pub fn columns(batch: &RecordBatch) -> Vec<(String, ArrayRef)> {
    let schema = batch.schema();
    let names = schema.fields().iter().map(|f| f.name().clone());
    names.zip(batch.columns().iter().cloned()).collect()
}

/// The records of `batch`, whose schema was checked against [`schema`]: a column
/// that `R` requires with an empty value is a fault; a column `R` lacks is skipped.
pub fn decode<R: Record>(batch: &RecordBatch) -> Result<Vec<R>, ColumnError> {
    let wanted = fields::<R>();
    let schema = batch.schema();
    let mut fields = Vec::new();
    let mut arrays = Vec::new();
    for field in wanted {
        let Some((index, found)) = schema.column_with_name(field.name()) else {
            continue;
        };
        let array = batch.column(index);
        if !field.is_nullable() && array.null_count() > 0 {
            return Err(ColumnError::Empty {
                column: field.name().clone(),
            });
        }
        fields.push(Arc::new(found.clone()));
        arrays.push(array.clone());
    }
    serde_arrow::from_arrow(&fields, &arrays)
        .map_err(|source| ColumnError::Decode(DecodeFault(Arc::new(source))))
}

/// `value` of `column` parsed as a name (an estimator, an error model, …).
pub fn parsed<T: std::str::FromStr<Err = String>>(
    column: &str,
    value: &str,
) -> Result<T, ColumnError> {
    value.parse().map_err(|problem| ColumnError::Value {
        column: column.to_string(),
        problem,
    })
}

/// Like [`parsed`], for a column that may be empty.
pub fn optional<T: std::str::FromStr<Err = String>>(
    column: &str,
    value: Option<&str>,
) -> Result<Option<T>, ColumnError> {
    value.map(|v| parsed(column, v)).transpose()
}
