//! # map_core: the IVLMap core
//!
//! An instance-level semantic grid map (IVLMap): obstacle, category, instance (U)
//! and colour (V) layers plus an instance table, built from a scene file; the
//! instance queries the robot function library relies on ("the third yellow
//! table"), goal points for spatial words, an A* planner with any-angle smoothing,
//! and a `Robot` trait with a simulated robot that records its trajectory.
//!
//! Conventions: world frame in metres, x east, y north; headings on the compass
//! (0 north, 90 east, clockwise positive); grid row 0 is the north edge.
//!
//! ```
//! use map_core::{Point, GridFrame};
//! let frame = GridFrame::from_bounds([0.0, 0.0, 10.0, 5.0], 0.05);
//! assert_eq!((frame.rows, frame.cols), (100, 200));
//! let cell = frame.cell_at(Point::new(0.01, 4.99)).unwrap();
//! assert_eq!((cell.row, cell.col), (0, 0)); // north-west corner
//! ```

#![warn(missing_docs)]

pub mod geometry;
pub mod goals;
pub mod grid;
pub mod map;
pub mod matcher;
pub mod models;
pub mod npy;
pub mod persist;
pub mod planner;
pub mod query;
pub mod render;
pub mod robot;
pub mod scene;
pub mod select;

pub use crate::geometry::{Point, Polygon, Pose};
pub use crate::grid::{Cell, Grid, GridFrame};
pub use crate::map::{Instance, IvlMap, Region};
pub use crate::matcher::{LexicalMatcher, NameMatcher};
pub use crate::planner::{GridPlanner, PlanError};
pub use crate::query::{ObjectOrder, QueryError};
pub use crate::robot::{Robot, RobotError, SimRobot, Stop, StopTarget, Trajectory};
pub use crate::scene::{Scene, SceneError};
