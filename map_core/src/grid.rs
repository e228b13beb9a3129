//! Dense 2-D grids (row-major, row 0 = north edge, column 0 = west edge) and the
//! frame that maps grid cells to world metres.

use serde::{Deserialize, Serialize};

use crate::geometry::Point;

/// A grid cell index: `row` counts south from the north edge, `col` east from the west edge.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Cell {
    /// Row index, counting south from the north edge (row 0).
    pub row: usize,
    /// Column index, counting east from the west edge (column 0).
    pub col: usize,
}

impl Cell {
    /// The cell at (`row`, `col`).
    pub const fn new(row: usize, col: usize) -> Self {
        Self { row, col }
    }
}

/// A dense row-major grid of `T`.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid<T> {
    rows: usize,
    cols: usize,
    data: Vec<T>,
}

impl<T: Clone> Grid<T> {
    /// A `rows` x `cols` grid with every cell set to `fill`.
    pub fn new(rows: usize, cols: usize, fill: T) -> Self {
        Self {
            rows,
            cols,
            data: vec![fill; rows * cols],
        }
    }
}

impl<T> Grid<T> {
    /// Wrap row-major data; `None` when `data.len() != rows * cols`.
    pub fn from_vec(rows: usize, cols: usize, data: Vec<T>) -> Option<Self> {
        (rows.checked_mul(cols) == Some(data.len())).then_some(Self { rows, cols, data })
    }

    /// Number of rows (north to south).
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns (west to east).
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Number of cells (`rows * cols`).
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// Whether the grid has no cells.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Whether signed (`row`, `col`) lies inside the grid.
    pub fn in_bounds(&self, row: isize, col: isize) -> bool {
        row >= 0 && col >= 0 && (row as usize) < self.rows && (col as usize) < self.cols
    }

    /// Row-major index of a cell (not bounds-checked).
    pub fn index(&self, c: Cell) -> usize {
        c.row * self.cols + c.col
    }

    /// The cell at a row-major index (inverse of [`Grid::index`]).
    pub fn cell_of(&self, index: usize) -> Cell {
        Cell::new(index / self.cols, index % self.cols)
    }

    /// The value at a cell, or `None` out of bounds.
    pub fn get(&self, c: Cell) -> Option<&T> {
        if c.row < self.rows && c.col < self.cols {
            self.data.get(c.row * self.cols + c.col)
        } else {
            None
        }
    }

    /// Mutable access to a cell's value, or `None` out of bounds.
    pub fn get_mut(&mut self, c: Cell) -> Option<&mut T> {
        if c.row < self.rows && c.col < self.cols {
            self.data.get_mut(c.row * self.cols + c.col)
        } else {
            None
        }
    }

    /// Set a cell; out-of-bounds writes are ignored.
    pub fn set(&mut self, c: Cell, v: T) {
        if let Some(x) = self.get_mut(c) {
            *x = v;
        }
    }

    /// The row-major data.
    pub fn as_slice(&self) -> &[T] {
        &self.data
    }

    /// The row-major data, mutably.
    pub fn as_mut_slice(&mut self) -> &mut [T] {
        &mut self.data
    }

    /// Consume the grid, returning its row-major data.
    pub fn into_vec(self) -> Vec<T> {
        self.data
    }

    /// Iterate `(cell, &value)` in row-major order.
    pub fn iter_cells(&self) -> impl Iterator<Item = (Cell, &T)> + '_ {
        let cols = self.cols.max(1);
        self.data
            .iter()
            .enumerate()
            .map(move |(i, v)| (Cell::new(i / cols, i % cols), v))
    }

    /// A grid of the same shape with `f` applied to every cell.
    pub fn map<U>(&self, f: impl Fn(&T) -> U) -> Grid<U> {
        Grid {
            rows: self.rows,
            cols: self.cols,
            data: self.data.iter().map(f).collect(),
        }
    }
}

/// Where a grid lies in the world: the north-west corner of cell (0, 0) and the cell size.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GridFrame {
    /// World position of the north-west corner of cell (0, 0): (xmin, ymax).
    pub origin: Point,
    /// Metres per cell.
    pub cell_size: f64,
    /// Number of rows (north to south).
    pub rows: usize,
    /// Number of columns (west to east).
    pub cols: usize,
}

impl GridFrame {
    /// The frame covering `bounds` = [xmin, ymin, xmax, ymax] with square cells.
    pub fn from_bounds(bounds: [f64; 4], cell_size: f64) -> Self {
        let cols = ((bounds[2] - bounds[0]) / cell_size - 1e-9).ceil().max(1.0) as usize;
        let rows = ((bounds[3] - bounds[1]) / cell_size - 1e-9).ceil().max(1.0) as usize;
        Self {
            origin: Point::new(bounds[0], bounds[1] + rows as f64 * cell_size),
            cell_size,
            rows,
            cols,
        }
    }

    /// World [xmin, ymin, xmax, ymax] covered by the grid.
    pub fn bounds(&self) -> [f64; 4] {
        [
            self.origin.x,
            self.origin.y - self.rows as f64 * self.cell_size,
            self.origin.x + self.cols as f64 * self.cell_size,
            self.origin.y,
        ]
    }

    /// Centre of a cell in world metres.
    pub fn cell_center(&self, c: Cell) -> Point {
        Point::new(
            self.origin.x + (c.col as f64 + 0.5) * self.cell_size,
            self.origin.y - (c.row as f64 + 0.5) * self.cell_size,
        )
    }

    /// Fractional (row, col) of a world point (may lie outside the grid).
    pub fn to_grid_f(&self, p: Point) -> (f64, f64) {
        (
            (self.origin.y - p.y) / self.cell_size,
            (p.x - self.origin.x) / self.cell_size,
        )
    }

    /// World point of fractional grid coordinates (row, col), cell centres at +0.5.
    pub fn from_grid_f(&self, row: f64, col: f64) -> Point {
        Point::new(
            self.origin.x + col * self.cell_size,
            self.origin.y - row * self.cell_size,
        )
    }

    /// The cell containing `p`, or `None` outside the grid (or for non-finite input).
    pub fn cell_at(&self, p: Point) -> Option<Cell> {
        if !p.is_finite() {
            return None;
        }
        let (r, c) = self.to_grid_f(p);
        if r < 0.0 || c < 0.0 {
            return None;
        }
        let (r, c) = (r.floor() as usize, c.floor() as usize);
        (r < self.rows && c < self.cols).then_some(Cell::new(r, c))
    }

    /// The cell nearest to `p`, clamped into the grid.
    pub fn clamp_cell(&self, p: Point) -> Cell {
        let (r, c) = self.to_grid_f(p);
        let clamp = |v: f64, n: usize| {
            if v.is_finite() {
                (v.floor().max(0.0) as usize).min(n.saturating_sub(1))
            } else {
                0
            }
        };
        Cell::new(clamp(r, self.rows), clamp(c, self.cols))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn row_zero_is_north_and_col_zero_is_west() {
        let f = GridFrame::from_bounds([0.0, 0.0, 2.0, 1.0], 0.5);
        assert_eq!((f.rows, f.cols), (2, 4));
        assert_eq!(f.cell_at(Point::new(0.1, 0.9)), Some(Cell::new(0, 0)));
        assert_eq!(f.cell_at(Point::new(1.9, 0.1)), Some(Cell::new(1, 3)));
        assert_eq!(f.cell_at(Point::new(2.1, 0.1)), None);
        let c = f.cell_center(Cell::new(0, 0));
        assert!((c.x - 0.25).abs() < 1e-12 && (c.y - 0.75).abs() < 1e-12);
        assert_eq!(f.bounds(), [0.0, 0.0, 2.0, 1.0]);
    }

    #[test]
    fn non_finite_points_have_no_cell() {
        let f = GridFrame::from_bounds([0.0, 0.0, 2.0, 1.0], 0.5);
        assert_eq!(f.cell_at(Point::new(f64::NAN, 0.0)), None);
        assert_eq!(
            f.clamp_cell(Point::new(f64::INFINITY, -5.0)),
            Cell::new(1, 0)
        );
    }
}
