//! Grid path planning: disk inflation, jump point search (optimal 8-connected A*
//! without corner cutting), any-angle smoothing by conservative line of sight, and
//! snapping of starts and goals that lie in obstacles.
//!
//! Obstacle grids are `Grid<bool>` with `true` = occupied. The search works on any
//! map that implements [`Passability`]; [`GridPlanner`] copies such a map once into a
//! padded byte grid; its connected free areas are labelled on first need (goal
//! snapping), after which unreachable goals are refused without a search.
//!
//! ```
//! use map_core::{Cell, Grid, GridPlanner};
//! use map_core::planner::inflate;
//! let mut obstacles = Grid::new(40, 40, false);
//! for r in 0..30 { obstacles.set(Cell::new(r, 20), true); } // a wall with a gap at the bottom
//! let planner = GridPlanner::new(inflate(&obstacles, 2.0));
//! let path = planner.plan(Cell::new(5, 5), Cell::new(5, 35)).unwrap();
//! assert!(path.smoothed_len <= path.raw_len + 1e-9);
//! assert_eq!(path.waypoints.first(), Some(&Cell::new(5, 5)));
//! ```

mod astar;
mod components;
mod inflate;
mod jps;
mod line_of_sight;
mod nearest;
mod smooth;

use std::sync::{Mutex, OnceLock};

use crate::geometry::Point;
use crate::grid::{Cell, Grid, GridFrame};

/// The eight grid moves as (row, column) offsets: the four sides, then the diagonals.
pub const MOVES8: [(isize, isize); 8] = [
    (-1, 0),
    (1, 0),
    (0, -1),
    (0, 1),
    (-1, -1),
    (-1, 1),
    (1, -1),
    (1, 1),
];

pub use astar::astar;
pub use inflate::{inflate, inflate_m};
pub use line_of_sight::{line_of_sight, supercover_cells};

/// A map the planner can search: its size and which cells a robot centre may occupy.
pub trait Passability {
    /// Number of rows (north to south).
    fn rows(&self) -> usize;
    /// Number of columns (west to east).
    fn cols(&self) -> usize;
    /// Whether the cell is free; out-of-bounds cells are never free.
    fn is_free(&self, c: Cell) -> bool;
}

/// `Grid<bool>` as an obstacle grid: `true` = occupied.
impl Passability for Grid<bool> {
    fn rows(&self) -> usize {
        Grid::rows(self)
    }
    fn cols(&self) -> usize {
        Grid::cols(self)
    }
    fn is_free(&self, c: Cell) -> bool {
        self.get(c).is_some_and(|occ| !*occ)
    }
}

/// Why no path could be planned.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanError {
    /// No path joins the (snapped) start to the goal.
    #[error("goal {} is unreachable from start {}", describe(.goal, .goal_world), describe(.start, .start_world))]
    Unreachable {
        /// The start cell as asked.
        start: Cell,
        /// The goal cell as asked.
        goal: Cell,
        /// The start point in world metres, when planning in the world frame.
        start_world: Option<Point>,
        /// The goal point in world metres, when planning in the world frame.
        goal_world: Option<Point>,
    },
    /// The start cell lies outside the grid.
    #[error("start cell (row {}, col {}) lies outside the {rows}x{cols} grid", .start.row, .start.col)]
    StartOutside {
        /// The start cell as asked.
        start: Cell,
        /// Rows in the grid.
        rows: usize,
        /// Columns in the grid.
        cols: usize,
    },
    /// The goal cell lies outside the grid.
    #[error("goal cell (row {}, col {}) lies outside the {rows}x{cols} grid", .goal.row, .goal.col)]
    GoalOutside {
        /// The goal cell as asked.
        goal: Cell,
        /// Rows in the grid.
        rows: usize,
        /// Columns in the grid.
        cols: usize,
    },
    /// A world start or goal point lies outside the frame's bounds.
    #[error("{what} point ({}, {}) lies outside the map bounds {bounds:?}", .point.x, .point.y)]
    PointOutside {
        /// Which point: "start" or "goal".
        what: &'static str,
        /// The point, in world metres.
        point: Point,
        /// The frame's [xmin, ymin, xmax, ymax] in metres.
        bounds: [f64; 4],
    },
    /// A world start or goal point has a NaN or infinite coordinate.
    #[error("{what} point is not finite: ({}, {})", .point.x, .point.y)]
    NonFinite {
        /// Which point: "start" or "goal".
        what: &'static str,
        /// The point as given.
        point: Point,
    },
    /// The frame given to [`GridPlanner::plan_world`] differs in size from the planner's grid.
    #[error(
        "the map frame ({frame_rows}x{frame_cols}) does not match the planner grid ({rows}x{cols})"
    )]
    FrameMismatch {
        /// Rows in the frame.
        frame_rows: usize,
        /// Columns in the frame.
        frame_cols: usize,
        /// Rows in the planner's grid.
        rows: usize,
        /// Columns in the planner's grid.
        cols: usize,
    },
    /// The map has no free cell to snap the start or goal to.
    #[error("the map has no free cell")]
    NoFreeCell,
}

fn describe(c: &Cell, w: &Option<Point>) -> String {
    match w {
        Some(p) => format!(
            "({:.2}, {:.2}) m, cell (row {}, col {})",
            p.x, p.y, c.row, c.col
        ),
        None => format!("cell (row {}, col {})", c.row, c.col),
    }
}

/// A planned path in grid cells.
#[derive(Debug, Clone, PartialEq)]
pub struct GridPath {
    /// Any-angle waypoints from (snapped) start to (snapped) goal; consecutive
    /// waypoints see each other under the conservative line-of-sight test.
    pub waypoints: Vec<Cell>,
    /// Length of the optimal 8-connected cell path, in cells (octile metric).
    pub raw_len: f64,
    /// Length of the smoothed polyline through `waypoints`, in cells.
    pub smoothed_len: f64,
    /// Start as asked and as used (differs when the start lay in an obstacle).
    pub start: Cell,
    /// Whether the start lay in an obstacle and was moved to the nearest free cell.
    pub start_snapped: bool,
    /// Goal as used: the nearest free cell reachable from the start when the asked
    /// goal lay in an obstacle.
    pub goal: Cell,
    /// Whether the goal lay in an obstacle and was moved.
    pub goal_snapped: bool,
}

/// A planned path in world metres.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldPath {
    /// From the start point (or the centre of its snapped cell) to the goal point
    /// (or the centre of its snapped cell).
    pub waypoints: Vec<Point>,
    /// Length of `waypoints` in metres.
    pub length_m: f64,
    /// Whether the start lay in an obstacle and was moved to the nearest free cell.
    pub start_snapped: bool,
    /// Whether the goal lay in an obstacle and was moved.
    pub goal_snapped: bool,
    /// The goal actually reached: the asked point unless it was snapped.
    pub goal: Point,
    /// The path in cells it came from.
    pub grid: GridPath,
}

/// An obstacle grid copied with a one-cell blocked border, so that neighbour reads
/// never leave the array: cell (r, c) is at `(r + 1) * w + c + 1`.
#[derive(Debug, Clone)]
pub(crate) struct Padded {
    pub rows: usize,
    pub cols: usize,
    pub w: usize,
    pub free: Vec<bool>,
    /// `free` as bits by padded row and by padded column, for straight jumps.
    pub row_bits: jps::Lines,
    pub col_bits: jps::Lines,
}

impl Padded {
    fn from_map<P: Passability + ?Sized>(map: &P) -> Self {
        let (rows, cols) = (map.rows(), map.cols());
        let w = cols + 2;
        let mut free = vec![false; w * (rows + 2)];
        for r in 0..rows {
            let base = (r + 1) * w + 1;
            for c in 0..cols {
                free[base + c] = map.is_free(Cell::new(r, c));
            }
        }
        Self::with_bits(rows, cols, w, free)
    }

    fn from_obstacles(g: &Grid<bool>) -> Self {
        let (rows, cols) = (g.rows(), g.cols());
        let w = cols + 2;
        let mut free = vec![false; w * (rows + 2)];
        for (r, row) in g
            .as_slice()
            .chunks_exact(cols.max(1))
            .enumerate()
            .take(rows)
        {
            let base = (r + 1) * w + 1;
            for (dst, occ) in free[base..base + cols].iter_mut().zip(row) {
                *dst = !occ;
            }
        }
        Self::with_bits(rows, cols, w, free)
    }

    fn with_bits(rows: usize, cols: usize, w: usize, free: Vec<bool>) -> Self {
        let h = rows + 2;
        let row_bits = jps::Lines::build(h, w, |r, c| free[r * w + c]);
        let col_bits = jps::Lines::build(w, h, |c, r| free[r * w + c]);
        Self {
            rows,
            cols,
            w,
            free,
            row_bits,
            col_bits,
        }
    }

    #[inline]
    pub fn idx(&self, c: Cell) -> usize {
        (c.row + 1) * self.w + c.col + 1
    }

    #[inline]
    pub fn cell(&self, i: usize) -> Cell {
        Cell::new(i / self.w - 1, i % self.w - 1)
    }
}

impl Passability for Padded {
    fn rows(&self) -> usize {
        self.rows
    }
    fn cols(&self) -> usize {
        self.cols
    }
    fn is_free(&self, c: Cell) -> bool {
        c.row < self.rows && c.col < self.cols && self.free[self.idx(c)]
    }
}

/// A planner over one (already inflated) obstacle grid. Build once, query often;
/// queries may run from several threads (each borrows or makes its own scratch).
#[derive(Debug)]
pub struct GridPlanner {
    map: Padded,
    /// Connected-area labels, computed on first need (goal snapping,
    /// `nearest_reachable_free`, `connected`), so that a fresh planner answers its
    /// first ordinary query without labelling the whole map.
    labels: OnceLock<Vec<u32>>,
    scratch: Mutex<jps::Scratch>,
}

impl GridPlanner {
    /// Take an inflated obstacle grid (`true` = occupied).
    pub fn new(inflated: Grid<bool>) -> Self {
        Self::from_padded(Padded::from_obstacles(&inflated))
    }

    /// Build from any map that tells free cells.
    pub fn from_passability<P: Passability + ?Sized>(map: &P) -> Self {
        Self::from_padded(Padded::from_map(map))
    }

    fn from_padded(map: Padded) -> Self {
        let scratch = Mutex::new(jps::Scratch::new(map.free.len()));
        Self {
            map,
            labels: OnceLock::new(),
            scratch,
        }
    }

    fn labels(&self) -> &[u32] {
        self.labels.get_or_init(|| components::label(&self.map))
    }

    /// Number of rows in the planner's grid.
    pub fn rows(&self) -> usize {
        self.map.rows
    }

    /// Number of columns in the planner's grid.
    pub fn cols(&self) -> usize {
        self.map.cols
    }

    /// Whether `c` is inside the grid and free.
    pub fn is_free(&self, c: Cell) -> bool {
        self.map.is_free(c)
    }

    /// Whether a path joins `a` and `b` (both must be free).
    pub fn connected(&self, a: Cell, b: Cell) -> bool {
        self.is_free(a)
            && self.is_free(b)
            && self.labels()[self.map.idx(a)] == self.labels()[self.map.idx(b)]
    }

    /// The free cell nearest to `cell` (Euclidean between centres; `cell` itself when free).
    /// `cell` may lie outside the grid.
    pub fn nearest_free(&self, cell: Cell) -> Option<Cell> {
        nearest::nearest(&self.map, cell, |i| self.map.free[i])
    }

    /// The free cell nearest to `target` that a path joins to `from` (`from` must be
    /// free; `target` may be anywhere, also outside the grid).
    pub fn nearest_reachable_free(&self, from: Cell, target: Cell) -> Option<Cell> {
        if !self.is_free(from) {
            return None;
        }
        let labels = self.labels();
        let lab = labels[self.map.idx(from)];
        nearest::nearest(&self.map, target, |i| labels[i] == lab)
    }

    /// Plan from `start` to `goal`. A start in an obstacle moves to the nearest free
    /// cell; a goal in an obstacle moves to the nearest free cell reachable from the
    /// start. A free goal that no path reaches is [`PlanError::Unreachable`].
    pub fn plan(&self, start: Cell, goal: Cell) -> Result<GridPath, PlanError> {
        self.plan_inner(start, goal, None, None)
    }

    fn plan_inner(
        &self,
        start: Cell,
        goal: Cell,
        start_world: Option<Point>,
        goal_world: Option<Point>,
    ) -> Result<GridPath, PlanError> {
        let (rows, cols) = (self.rows(), self.cols());
        if start.row >= rows || start.col >= cols {
            return Err(PlanError::StartOutside { start, rows, cols });
        }
        if goal.row >= rows || goal.col >= cols {
            return Err(PlanError::GoalOutside { goal, rows, cols });
        }
        let s = if self.is_free(start) {
            start
        } else {
            self.nearest_free(start).ok_or(PlanError::NoFreeCell)?
        };
        let g = if self.is_free(goal) {
            goal
        } else {
            self.nearest_reachable_free(s, goal)
                .ok_or(PlanError::NoFreeCell)?
        };
        // labels known (from an earlier snap): refuse at once instead of searching in vain
        if let Some(labels) = self.labels.get() {
            if labels[self.map.idx(s)] != labels[self.map.idx(g)] {
                return Err(PlanError::Unreachable {
                    start,
                    goal,
                    start_world,
                    goal_world,
                });
            }
        }
        let mut local;
        let mut guard = self.scratch.try_lock();
        let scratch = match guard.as_deref_mut() {
            Ok(s) => s,
            Err(_) => {
                local = jps::Scratch::new(self.map.free.len());
                &mut local
            }
        };
        let (cells, raw_len) = jps::search(&self.map, scratch, self.map.idx(s), self.map.idx(g))
            .ok_or(PlanError::Unreachable {
                start,
                goal,
                start_world,
                goal_world,
            })?;
        drop(guard);
        let dense = jps::densify(self.map.w, &cells);
        let waypoints = smooth::smooth(&self.map, &dense);
        let smoothed_len = polyline_len(&waypoints);
        Ok(GridPath {
            waypoints,
            raw_len,
            smoothed_len,
            start: s,
            start_snapped: s != start,
            goal: g,
            goal_snapped: g != goal,
        })
    }

    /// Plan between world points on `frame` (which must have this planner's size).
    /// Waypoints are cell centres, with the exact start and goal points added at the
    /// ends when they were not snapped.
    pub fn plan_world(
        &self,
        frame: &GridFrame,
        start: Point,
        goal: Point,
    ) -> Result<WorldPath, PlanError> {
        if frame.rows != self.rows() || frame.cols != self.cols() {
            return Err(PlanError::FrameMismatch {
                frame_rows: frame.rows,
                frame_cols: frame.cols,
                rows: self.rows(),
                cols: self.cols(),
            });
        }
        for (what, p) in [("start", start), ("goal", goal)] {
            if !p.is_finite() {
                return Err(PlanError::NonFinite { what, point: p });
            }
        }
        let sc = frame.cell_at(start).ok_or(PlanError::PointOutside {
            what: "start",
            point: start,
            bounds: frame.bounds(),
        })?;
        let gc = frame.cell_at(goal).ok_or(PlanError::PointOutside {
            what: "goal",
            point: goal,
            bounds: frame.bounds(),
        })?;
        let grid = self.plan_inner(sc, gc, Some(start), Some(goal))?;
        let mut waypoints = Vec::with_capacity(grid.waypoints.len() + 2);
        if !grid.start_snapped {
            waypoints.push(start);
        }
        for &c in &grid.waypoints {
            let p = frame.cell_center(c);
            if waypoints.last().is_none_or(|q: &Point| q.dist(p) > 1e-9) {
                waypoints.push(p);
            }
        }
        if !grid.goal_snapped && waypoints.last().is_none_or(|q: &Point| q.dist(goal) > 1e-9) {
            waypoints.push(goal);
        }
        let length_m = waypoints.windows(2).map(|w| w[0].dist(w[1])).sum();
        let goal_used = if grid.goal_snapped {
            frame.cell_center(grid.goal)
        } else {
            goal
        };
        Ok(WorldPath {
            waypoints,
            length_m,
            start_snapped: grid.start_snapped,
            goal_snapped: grid.goal_snapped,
            goal: goal_used,
            grid,
        })
    }
}

/// Length of a polyline through cell centres, in cells.
pub fn polyline_len(cells: &[Cell]) -> f64 {
    cells
        .windows(2)
        .map(|w| {
            let dr = w[0].row as f64 - w[1].row as f64;
            let dc = w[0].col as f64 - w[1].col as f64;
            dr.hypot(dc)
        })
        .sum()
}

/// Octile distance between cells (8-connected grid metric).
pub fn octile(a: Cell, b: Cell) -> f64 {
    let dr = a.row.abs_diff(b.row) as f64;
    let dc = a.col.abs_diff(b.col) as f64;
    let (lo, hi) = if dr < dc { (dr, dc) } else { (dc, dr) };
    hi + (std::f64::consts::SQRT_2 - 1.0) * lo
}

#[cfg(test)]
mod tests {
    use super::*;

    fn open(rows: usize, cols: usize) -> Grid<bool> {
        Grid::new(rows, cols, false)
    }

    #[test]
    fn straight_path_in_open_space() {
        let p = GridPlanner::new(open(10, 10));
        let path = p.plan(Cell::new(0, 0), Cell::new(9, 9)).unwrap();
        assert_eq!(path.waypoints, vec![Cell::new(0, 0), Cell::new(9, 9)]);
        assert!((path.raw_len - 9.0 * 2f64.sqrt()).abs() < 1e-9);
        assert!(!path.start_snapped && !path.goal_snapped);
    }

    #[test]
    fn start_in_obstacle_snaps_to_nearest_free() {
        let mut g = open(10, 10);
        for r in 3..6 {
            for c in 3..6 {
                g.set(Cell::new(r, c), true);
            }
        }
        let p = GridPlanner::new(g);
        assert_eq!(
            p.nearest_free(Cell::new(4, 4))
                .map(|c| c.row.abs_diff(4) + c.col.abs_diff(4)),
            Some(2)
        );
        let path = p.plan(Cell::new(4, 3), Cell::new(0, 0)).unwrap();
        assert!(path.start_snapped);
        assert_eq!(path.start, Cell::new(4, 2));
        assert_eq!(path.waypoints[0], Cell::new(4, 2));
    }

    #[test]
    fn goal_in_obstacle_snaps_to_nearest_reachable_cell() {
        // a closed room on the right: its free interior is nearer to the goal but unreachable
        let mut g = open(20, 20);
        for r in 0..20 {
            g.set(Cell::new(r, 8), true);
        }
        for r in 0..20 {
            for c in 9..12 {
                g.set(Cell::new(r, c), true);
            }
        }
        // goal at (10, 11): nearest free is (10, 12) on the other side, unreachable from (0, 0)
        let p = GridPlanner::new(g);
        assert_eq!(p.nearest_free(Cell::new(10, 11)), Some(Cell::new(10, 12)));
        let path = p.plan(Cell::new(0, 0), Cell::new(10, 11)).unwrap();
        assert!(path.goal_snapped);
        assert_eq!(path.goal, Cell::new(10, 7));
        assert_eq!(path.waypoints.last(), Some(&Cell::new(10, 7)));
        assert_eq!(
            p.nearest_reachable_free(Cell::new(0, 0), Cell::new(10, 11)),
            Some(Cell::new(10, 7))
        );
    }

    #[test]
    fn unreachable_error_names_the_goal() {
        let mut g = open(10, 10);
        for r in 0..10 {
            g.set(Cell::new(r, 5), true);
        }
        let p = GridPlanner::new(g);
        let err = p.plan(Cell::new(1, 1), Cell::new(7, 8)).unwrap_err();
        assert!(matches!(err, PlanError::Unreachable { goal, .. } if goal == Cell::new(7, 8)));
        assert!(
            err.to_string()
                .contains("goal cell (row 7, col 8) is unreachable"),
            "{err}"
        );

        let frame = GridFrame::from_bounds([0.0, 0.0, 1.0, 1.0], 0.1);
        let err = p
            .plan_world(&frame, Point::new(0.15, 0.85), Point::new(0.85, 0.25))
            .unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("goal (0.85, 0.25) m, cell (row 7, col 8)"),
            "{msg}"
        );
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let p = GridPlanner::new(open(5, 5));
        assert!(matches!(
            p.plan(Cell::new(9, 0), Cell::new(0, 0)),
            Err(PlanError::StartOutside { .. })
        ));
        assert!(matches!(
            p.plan(Cell::new(0, 0), Cell::new(0, usize::MAX)),
            Err(PlanError::GoalOutside { .. })
        ));
        let frame = GridFrame::from_bounds([0.0, 0.0, 0.5, 0.5], 0.1);
        let nan = Point::new(f64::NAN, 0.1);
        assert!(matches!(
            p.plan_world(&frame, nan, Point::new(0.1, 0.1)),
            Err(PlanError::NonFinite { .. })
        ));
        assert!(matches!(
            p.plan_world(&frame, Point::new(0.1, 0.1), Point::new(7.0, 0.1)),
            Err(PlanError::PointOutside { .. })
        ));
        let other = GridFrame::from_bounds([0.0, 0.0, 1.0, 0.5], 0.1);
        assert!(matches!(
            p.plan_world(&other, Point::new(0.1, 0.1), Point::new(0.2, 0.2)),
            Err(PlanError::FrameMismatch { .. })
        ));
        let blocked = GridPlanner::new(Grid::new(3, 3, true));
        assert_eq!(
            blocked.plan(Cell::new(0, 0), Cell::new(2, 2)),
            Err(PlanError::NoFreeCell)
        );
        let empty = GridPlanner::new(Grid::new(0, 0, false));
        assert!(empty.plan(Cell::new(0, 0), Cell::new(0, 0)).is_err());
    }

    #[test]
    fn world_path_runs_from_start_point_to_goal_point() {
        let p = GridPlanner::new(open(20, 20));
        let frame = GridFrame::from_bounds([0.0, 0.0, 2.0, 2.0], 0.1);
        let (s, g) = (Point::new(0.12, 0.13), Point::new(1.81, 1.72));
        let wp = p.plan_world(&frame, s, g).unwrap();
        assert_eq!(wp.waypoints.first(), Some(&s));
        assert_eq!(wp.waypoints.last(), Some(&g));
        // the ends run through the centres of the start and goal cells: at most a cell diagonal more
        assert!(
            wp.length_m >= s.dist(g) - 1e-9 && wp.length_m <= s.dist(g) + 2f64.sqrt() * 0.1,
            "{}",
            wp.length_m
        );
    }
}
