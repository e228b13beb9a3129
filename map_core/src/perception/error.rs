//! Errors of the perception builders: every one names the file (or the input) and,
//! where it exists, the mask, the position and the field.

use std::fmt;
use std::path::PathBuf;

use crate::grid::Cell;

/// Where in a masks file a problem is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MaskLocation {
    /// 1-based line and column, where the JSON reader knows them.
    pub line: Option<usize>,
    pub column: Option<usize>,
    /// Index of the mask in the file's top-level list, where known.
    pub mask: Option<usize>,
    /// Field path inside the mask, e.g. `segmentation.counts`.
    pub field: String,
}

impl fmt::Display for MaskLocation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
            if let Some(c) = self.column {
                write!(f, ":{c}")?;
            }
        }
        if let Some(m) = self.mask {
            write!(f, ": mask {m}")?;
        }
        if !self.field.is_empty() {
            write!(f, ": field `{}`", self.field)?;
        }
        Ok(())
    }
}

/// Why perception inputs could not be read, written or assembled into a map.
#[derive(Debug, thiserror::Error)]
pub enum PerceptionError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A masks file that does not parse, or a mask in it that does not decode.
    #[error("{}{at}: {message}", path.display())]
    Masks {
        path: PathBuf,
        at: MaskLocation,
        message: String,
    },
    /// A layer or mask whose size differs from the map's.
    #[error("{what} is {rows}x{cols}, but the map frame is {frame_rows}x{frame_cols}")]
    Shape {
        what: String,
        rows: usize,
        cols: usize,
        frame_rows: usize,
        frame_cols: usize,
    },
    /// A label map cell naming a category the category list does not have.
    #[error(
        "{what}: cell (row {}, col {}) holds label {value}, but there are only {categories} categories (labels 0..{categories})",
        cell.row, cell.col
    )]
    LabelOutOfRange {
        what: String,
        cell: Cell,
        value: u16,
        categories: usize,
    },
    /// More categories than a `u16` label map can index.
    #[error("{what}: {count} categories, at most 65536 fit a u16 label map")]
    TooManyCategories { what: String, count: usize },
}
