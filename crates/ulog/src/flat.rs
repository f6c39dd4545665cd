//! Formats flattened to columns: nested types expanded as `outer.inner`,
//! arrays as `name[i]` (pyulog's and PlotJuggler's naming), padding fields
//! skipped, each column with its base type and byte offset in the record.

use crate::format::UlogType;
use crate::reader::{Format, Value, decode_value};
use crate::spec;
use helicon_config::escape_control;
use std::collections::HashMap;

/// The deepest nesting of formats accepted (PX4's messages nest 2–3 deep).
pub const MAX_DEPTH: usize = 8;

/// The most columns one format may flatten to: one per byte of the largest
/// record a ULog message holds (each base type is at least one byte).
pub const MAX_COLUMNS: usize = spec::MAX_PAYLOAD;

/// Why a format could not be flattened.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FlattenError {
    /// A rule of the format broken (unknown nested type, a cycle, nesting
    /// deeper than [`MAX_DEPTH`], a record larger than a message holds).
    #[error("{0}")]
    Rule(String),
    /// More columns than the limit asked.
    #[error("topic `{topic}`: more than {limit} columns")]
    TooManyColumns {
        /// The topic (control characters escaped).
        topic: String,
        /// The limit.
        limit: usize,
    },
}

/// One column of a flattened format.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Column {
    /// Flattened name (`timestamp`, `command[2]`, `esc[0].rpm`).
    pub name: String,
    /// Base type.
    pub ty: UlogType,
    /// Byte offset in the record (after the message id).
    pub offset: usize,
}

/// A format flattened to its columns.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FlatFormat {
    /// Format name.
    pub name: String,
    /// Columns in file order.
    pub columns: Vec<Column>,
    /// Bytes a record needs (the end of its last column; a trailing padding
    /// field is not logged).
    pub min_len: usize,
}

impl FlatFormat {
    /// The index of the `timestamp` column.
    pub fn timestamp_column(&self) -> Option<usize> {
        self.columns
            .iter()
            .position(|c| c.name == "timestamp" && c.ty == UlogType::UInt64)
    }

    /// The value of column `i` in `record` (`None` if out of range).
    pub fn value(&self, record: &[u8], i: usize) -> Option<Value> {
        let c = self.columns.get(i)?;
        let b = record.get(c.offset..c.offset + c.ty.size())?;
        Some(decode_value(c.ty, b))
    }
}

/// Flatten format `name` using the file's `formats`. Errors (a rule, as
/// text) for unknown nested types, cycles, nesting deeper than
/// [`MAX_DEPTH`] and records larger than a message can hold.
pub fn flatten(name: &str, formats: &HashMap<String, Format>) -> Result<FlatFormat, String> {
    flatten_limited(name, formats, MAX_COLUMNS).map_err(|e| e.to_string())
}

/// [`flatten`], refusing a format of more than `max_columns` columns (the
/// work and memory of a flattening are proportional to its columns, at
/// most [`MAX_COLUMNS`] whatever the limit).
pub fn flatten_limited(
    name: &str,
    formats: &HashMap<String, Format>,
    max_columns: usize,
) -> Result<FlatFormat, FlattenError> {
    let mut columns = Vec::new();
    let topic = || escape_control(name).into_owned();
    let end =
        walk(name, "", 0, 0, true, formats, &mut columns, max_columns).map_err(|e| match e {
            Walk::Rule(rule) => FlattenError::Rule(format!("topic `{}`: {rule}", topic())),
            Walk::TooMany => FlattenError::TooManyColumns {
                topic: topic(),
                limit: max_columns,
            },
        })?;
    Ok(FlatFormat {
        name: name.to_string(),
        columns,
        min_len: end,
    })
}

/// Why a walk stopped.
enum Walk {
    Rule(String),
    TooMany,
}

impl From<String> for Walk {
    fn from(rule: String) -> Walk {
        Walk::Rule(rule)
    }
}

#[allow(clippy::too_many_arguments)] // one recursive walk: its state, spelt out
fn walk(
    name: &str,
    prefix: &str,
    mut offset: usize,
    depth: usize,
    top: bool,
    formats: &HashMap<String, Format>,
    out: &mut Vec<Column>,
    max_columns: usize,
) -> Result<usize, Walk> {
    if depth > MAX_DEPTH {
        return Err(format!(
            "types nest deeper than {MAX_DEPTH} levels (or refer to themselves) at `{}`",
            escape_control(name)
        )
        .into());
    }
    let f = formats
        .get(name)
        .ok_or_else(|| format!("type `{}` has no format", escape_control(name)))?;
    let last = f.fields.len().saturating_sub(1);
    for (i, field) in f.fields.iter().enumerate() {
        let padding = field.name.starts_with("_padding");
        if padding && top && i == last {
            // trailing padding of a top-level record is not logged
            break;
        }
        let count = field.array_len.unwrap_or(1);
        for k in 0..count {
            let col = match field.array_len {
                Some(_) => format!("{prefix}{}[{k}]", field.name),
                None => format!("{prefix}{}", field.name),
            };
            match field.base_type() {
                Some(ty) => {
                    if !padding {
                        if out.len() >= max_columns {
                            return Err(Walk::TooMany);
                        }
                        out.push(Column {
                            name: col,
                            ty,
                            offset,
                        });
                    }
                    offset += ty.size();
                }
                None => {
                    let mut sink = Vec::new();
                    let target = if padding { &mut sink } else { &mut *out };
                    let before = offset;
                    offset = walk(
                        &field.type_name,
                        &format!("{col}."),
                        offset,
                        depth + 1,
                        false,
                        formats,
                        target,
                        max_columns,
                    )?;
                    if offset == before {
                        return Err(format!(
                            "type `{}` is empty",
                            escape_control(&field.type_name)
                        )
                        .into());
                    }
                }
            }
            if offset > spec::MAX_PAYLOAD {
                return Err(format!(
                    "`{}` is larger than a ULog message can hold",
                    escape_control(name)
                )
                .into());
            }
        }
    }
    Ok(offset)
}
