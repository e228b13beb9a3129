//! Errors of the perception builders: every one names the file (or the input) and,
//! where it exists, the mask, the position and the field.

use std::fmt;
use std::path::PathBuf;

use map_core::grid::Cell;

/// Where in a masks file a problem is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MaskLocation {
    /// 1-based line and column, where the JSON reader knows them.
    pub line: Option<usize>,
    /// 1-based column within `line`, where the JSON reader knows it.
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
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A masks file that does not parse, or a mask in it that does not decode.
    #[error("{}{at}: {message}", path.display())]
    Masks {
        /// The masks file.
        path: PathBuf,
        /// Where in the file the problem is.
        at: MaskLocation,
        /// What is wrong.
        message: String,
    },
    /// A layer or mask whose size differs from the map's.
    #[error("{what} is {rows}x{cols}, but the map frame is {frame_rows}x{frame_cols}")]
    Shape {
        /// Which layer or mask, e.g. "label map", "mask 3".
        what: String,
        /// Its number of rows.
        rows: usize,
        /// Its number of columns.
        cols: usize,
        /// Number of rows of the map frame.
        frame_rows: usize,
        /// Number of columns of the map frame.
        frame_cols: usize,
    },
    /// A label map cell naming a category the category list does not have.
    #[error(
        "{what}: cell (row {}, col {}) holds label {value}, but there are only {categories} categories (labels 0..{categories})",
        cell.row, cell.col
    )]
    LabelOutOfRange {
        /// Which label map.
        what: String,
        /// The cell holding the bad label.
        cell: Cell,
        /// The label it holds.
        value: u16,
        /// Number of categories in the list.
        categories: usize,
    },
    /// More categories than a `u16` label map can index.
    #[error("{what}: {count} categories, at most 65536 fit a u16 label map")]
    TooManyCategories {
        /// Which label map.
        what: String,
        /// Number of categories given.
        count: usize,
    },
}
