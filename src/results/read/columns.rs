//! Typed access to the columns of a stored table, and the check that runs before it.
//! In: a Parquet file's schema and its record batches. Out: `check_schema` says
//! whether the schema is the one the writer produces (a column added later may be
//! missing); `Batch` hands out each column as a `Vec` of floats, counts, flags, text
//! or parsed names. Either way a fault is a [`ColumnError`] that names the column; the
//! caller puts the file's path in front of it.

use crate::vocab::{ErrorModel, EstimatorKind};
use arrow_array::{Array, BooleanArray, Float64Array, RecordBatch, StringArray, UInt32Array};
use arrow_schema::{DataType, Schema};

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

/// Columns added after the first results folders were written: a folder that lacks
/// one still reads, with the value those runs implied.
const LATER_COLUMNS: [&str; 2] = ["stop_reason", "efficiency"];

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

/// A batch whose schema was checked, read column by column.
pub(crate) struct Batch<'a>(pub(crate) &'a RecordBatch);

impl Batch<'_> {
    pub(crate) fn column<A: Array + 'static>(&self, name: &str) -> &A {
        self.0
            .column_by_name(name)
            .and_then(|c| c.as_any().downcast_ref::<A>())
            .expect("the schema was checked")
    }

    fn no_nulls(&self, name: &str) -> Result<(), ColumnError> {
        let column = self.0.column_by_name(name).expect("the schema was checked");
        if column.null_count() > 0 {
            return Err(ColumnError::Empty {
                column: name.to_string(),
            });
        }
        Ok(())
    }

    pub(crate) fn floats(&self, name: &str) -> Result<Vec<f64>, ColumnError> {
        self.no_nulls(name)?;
        Ok(self.column::<Float64Array>(name).values().to_vec())
    }

    pub(crate) fn optional_floats(&self, name: &str) -> Vec<Option<f64>> {
        self.column::<Float64Array>(name).iter().collect()
    }

    pub(crate) fn uints(&self, name: &str) -> Result<Vec<usize>, ColumnError> {
        self.no_nulls(name)?;
        Ok(self
            .column::<UInt32Array>(name)
            .values()
            .iter()
            .map(|&v| v as usize)
            .collect())
    }

    /// A column that only some tables have, empty values and all; all empty when the
    /// table lacks it.
    pub(super) fn optional_uints(&self, name: &str) -> Vec<Option<usize>> {
        match self.0.column_by_name(name) {
            Some(column) => column
                .as_any()
                .downcast_ref::<UInt32Array>()
                .map(|c| c.iter().map(|v| v.map(|v| v as usize)).collect())
                .unwrap_or_else(|| vec![None; self.0.num_rows()]),
            None => vec![None; self.0.num_rows()],
        }
    }

    /// Like [`Batch::optional_uints`], for floats.
    pub(crate) fn optional_float_column(&self, name: &str) -> Vec<Option<f64>> {
        match self.0.column_by_name(name) {
            Some(column) => column
                .as_any()
                .downcast_ref::<Float64Array>()
                .map(|c| c.iter().collect())
                .unwrap_or_else(|| vec![None; self.0.num_rows()]),
            None => vec![None; self.0.num_rows()],
        }
    }

    pub(super) fn bools(&self, name: &str) -> Result<Vec<bool>, ColumnError> {
        self.no_nulls(name)?;
        let column = self.column::<BooleanArray>(name);
        Ok((0..column.len()).map(|i| column.value(i)).collect())
    }

    pub(crate) fn strings(&self, name: &str) -> Result<Vec<String>, ColumnError> {
        self.no_nulls(name)?;
        Ok(self
            .column::<StringArray>(name)
            .iter()
            .map(|s| s.unwrap_or_default().to_string())
            .collect())
    }

    /// A column of names parsed into `T`; `optional` allows empty values.
    pub(crate) fn parsed<T: std::str::FromStr<Err = String>>(
        &self,
        name: &str,
        optional: bool,
    ) -> Result<Vec<Option<T>>, ColumnError> {
        if !optional {
            self.no_nulls(name)?;
        }
        self.column::<StringArray>(name)
            .iter()
            .map(|value| {
                value
                    .map(|v| {
                        v.parse().map_err(|problem| ColumnError::Value {
                            column: name.to_string(),
                            problem,
                        })
                    })
                    .transpose()
            })
            .collect()
    }

    pub(super) fn required<T: std::str::FromStr<Err = String>>(
        &self,
        name: &str,
    ) -> Result<Vec<T>, ColumnError> {
        Ok(self
            .parsed(name, false)?
            .into_iter()
            .map(|v| v.expect("no nulls"))
            .collect())
    }

    /// The `dvl`, `estimator` and `error_model` of each row: which series it belongs to.
    pub(crate) fn row_keys(&self) -> Result<Vec<RowKey>, ColumnError> {
        let dvl = self.strings("dvl")?;
        let estimator: Vec<EstimatorKind> = self.required("estimator")?;
        let error_model = self.parsed("error_model", true)?;
        Ok(dvl
            .into_iter()
            .zip(estimator)
            .zip(error_model)
            .map(|((dvl, estimator), error_model)| RowKey {
                dvl,
                estimator,
                error_model,
            })
            .collect())
    }
}

/// The DVL, estimator and error model a row belongs to.
pub(crate) struct RowKey {
    pub dvl: String,
    pub estimator: EstimatorKind,
    pub error_model: Option<ErrorModel>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::results::training_batch;
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
