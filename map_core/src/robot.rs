//! The [`Robot`] trait (the seam between the plan language and a simulator or a
//! driver), the simulated robot, and the trajectory it records (formats.md).

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::geometry::{normalise_heading, Point, Pose};
use crate::grid::Grid;
use crate::map::IvlMap;
use crate::planner::{inflate_m, GridPlanner, PlanError};

/// What a stop aimed at, as the trajectory records it (`{"instance": 7}`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopTarget {
    /// An object instance, by id.
    Instance(u32),
    /// A named region, by name.
    Region(String),
    /// A world point `[x, y]` in metres.
    Point([f64; 2]),
    /// Two instances (move_in_between).
    Between([u32; 2]),
}

/// A stop: where a goal-directed move ended and what it aimed at.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stop {
    /// `[x, y, heading]`.
    pub pose: [f64; 3],
    /// The library call that made the move, e.g. "move_to_object".
    pub call: String,
    /// What the move aimed at.
    pub target: StopTarget,
    /// The goal point asked for, before snapping to a reachable free cell.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub goal: Option<[f64; 2]>,
    /// Whether the goal lay in an inflated obstacle and was moved.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub snapped: bool,
}

/// The trajectory file of formats.md.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Trajectory {
    /// Name of the scene (map) the run was on.
    pub scene: String,
    /// Source text of the script that was run.
    pub script: String,
    /// Stops of the goal-directed moves, in order.
    pub stops: Vec<Stop>,
    /// The travelled path as `[x, y]` points in metres, from the start position.
    pub path: Vec<[f64; 2]>,
    /// `[x, y, heading]` at the end of the run.
    pub final_pose: [f64; 3],
    /// Length of `path` in metres.
    pub length_m: f64,
    /// The error that ended the run, if any.
    pub error: Option<String>,
}

impl Trajectory {
    /// A trajectory that starts at `pose`.
    pub fn starting_at(scene: &str, pose: Pose) -> Self {
        Trajectory {
            scene: scene.to_string(),
            path: vec![[pose.position.x, pose.position.y]],
            final_pose: pose.to_array(),
            ..Default::default()
        }
    }

    /// Append path points (a leading point equal to the current end is skipped).
    pub fn extend_path(&mut self, pts: &[Point]) {
        for p in pts {
            let a = [p.x, p.y];
            if let Some(last) = self.path.last() {
                let d = (last[0] - a[0]).hypot(last[1] - a[1]);
                if d < 1e-9 {
                    continue;
                }
                self.length_m += d;
            }
            self.path.push(a);
        }
    }
}

/// The result of a move.
#[derive(Debug, Clone, PartialEq)]
pub struct MoveReport {
    /// Where the robot ended.
    pub reached: Point,
    /// Distance travelled, metres.
    pub length_m: f64,
    /// Whether the goal lay in an obstacle and the nearest reachable free cell was used.
    pub snapped: bool,
    /// Something the user should know (e.g. stopped short of an obstacle).
    pub warning: Option<String>,
}

/// Why a robot could not do what was asked.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RobotError {
    /// No path could be planned to the goal.
    #[error(transparent)]
    Plan(#[from] PlanError),
    /// A goal coordinate, angle or distance was NaN or infinite.
    #[error("{what} must be a finite number, got {value}")]
    NotFinite {
        /// What the number was, e.g. "goal x".
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// An angle or distance lies outside the accepted range.
    #[error("{what} of {value} is out of range ({range})")]
    OutOfRange {
        /// What the number was, e.g. "turn angle".
        what: &'static str,
        /// The value given.
        value: f64,
        /// The accepted range, in words.
        range: &'static str,
    },
    /// A robot driver reported a failure (its message).
    #[error("robot driver: {0}")]
    Driver(String),
}

/// A mobile robot: a pose, goal-directed moves, turns and forward moves.
///
/// Headings are compass degrees: 0 north, 90 east; `turn(a)` with `a > 0` turns
/// clockwise (right).
pub trait Robot {
    /// The current pose.
    fn pose(&self) -> Pose;
    /// The pose read again from the robot's own sensing where it has any (a real robot
    /// may have been pushed or driven by hand since its last call); by default, and
    /// for the simulator, [`Robot::pose`].
    fn current_pose(&mut self) -> Pose {
        self.pose()
    }
    /// Plan to `goal` and follow the path; records a stop aimed at `target`.
    fn move_to(
        &mut self,
        goal: Point,
        call: &str,
        target: StopTarget,
    ) -> Result<MoveReport, RobotError>;
    /// Turn in place by `degrees`, clockwise positive.
    fn turn(&mut self, degrees: f64) -> Result<(), RobotError>;
    /// Turn in place to a compass heading.
    fn turn_absolute(&mut self, heading: f64) -> Result<(), RobotError>;
    /// Drive straight along the heading (negative = backwards), stopping short of obstacles.
    fn move_forward(&mut self, metres: f64) -> Result<MoveReport, RobotError>;
    /// What the robot has done so far.
    fn trajectory(&self) -> &Trajectory;
    /// Mutable access, to set the script and error of a run.
    fn trajectory_mut(&mut self) -> &mut Trajectory;
}

/// Largest distance a single move_forward may ask for, metres.
pub const MAX_FORWARD_M: f64 = 1000.0;

/// Largest turn or heading a call may give, degrees.
const MAX_TURN_DEG: f64 = 36_000.0;

/// The checks every [`Robot`] applies to its arguments before moving, so that a
/// simulator and a driver refuse the same calls with the same errors.
pub mod args {
    use super::{Point, RobotError, MAX_FORWARD_M, MAX_TURN_DEG};

    /// `v` itself, or [`RobotError::NotFinite`] naming `what`.
    pub fn finite(what: &'static str, v: f64) -> Result<f64, RobotError> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(RobotError::NotFinite { what, value: v })
        }
    }

    /// A goal with finite coordinates.
    pub fn goal(goal: Point) -> Result<Point, RobotError> {
        finite("goal x", goal.x)?;
        finite("goal y", goal.y)?;
        Ok(goal)
    }

    fn degrees(what: &'static str, v: f64) -> Result<f64, RobotError> {
        finite(what, v)?;
        if v.abs() > MAX_TURN_DEG {
            return Err(RobotError::OutOfRange {
                what,
                value: v,
                range: "-36000..36000 degrees",
            });
        }
        Ok(v)
    }

    /// A relative turn: finite, within +-36000 degrees.
    pub fn turn(degrees_cw: f64) -> Result<f64, RobotError> {
        degrees("turn angle", degrees_cw)
    }

    /// A compass heading: finite, within +-36000 degrees.
    pub fn heading(heading: f64) -> Result<f64, RobotError> {
        degrees("heading", heading)
    }

    /// A forward distance: finite, within +-[`MAX_FORWARD_M`].
    pub fn forward(metres: f64) -> Result<f64, RobotError> {
        finite("distance", metres)?;
        if metres.abs() > MAX_FORWARD_M {
            return Err(RobotError::OutOfRange {
                what: "distance",
                value: metres,
                range: "-1000..1000 m",
            });
        }
        Ok(metres)
    }
}

/// A simulated robot on an [`IvlMap`]: it plans with A* on the obstacles inflated
/// by its radius, follows the smoothed path exactly, and records the trajectory.
/// Cloning is cheap (the map and planner are shared), so a dry run can work on a copy.
#[derive(Debug, Clone)]
pub struct SimRobot {
    map: Arc<IvlMap>,
    planner: Arc<GridPlanner>,
    inflated: Arc<Grid<bool>>,
    pose: Pose,
    trajectory: Trajectory,
}

impl SimRobot {
    /// A robot at the map's start pose.
    pub fn new(map: Arc<IvlMap>) -> Self {
        let pose = map.start_pose;
        Self::with_pose(map, pose)
    }

    /// A robot at `pose`.
    pub fn with_pose(map: Arc<IvlMap>, pose: Pose) -> Self {
        let inflated = inflate_m(&map.obstacles, map.robot_radius, map.frame.cell_size);
        let planner = Arc::new(GridPlanner::new(inflated.clone()));
        Self::from_parts(map, planner, Arc::new(inflated), pose)
    }

    /// A robot sharing a planner built for this map (the planner's grid must be the
    /// map's obstacles inflated by its radius).
    pub fn from_parts(
        map: Arc<IvlMap>,
        planner: Arc<GridPlanner>,
        inflated: Arc<Grid<bool>>,
        pose: Pose,
    ) -> Self {
        let trajectory = Trajectory::starting_at(&map.name, pose);
        SimRobot {
            map,
            planner,
            inflated,
            pose,
            trajectory,
        }
    }

    /// The map the robot moves on.
    pub fn map(&self) -> &Arc<IvlMap> {
        &self.map
    }

    /// The planner it uses (over the map's obstacles inflated by the robot radius).
    pub fn planner(&self) -> &Arc<GridPlanner> {
        &self.planner
    }

    /// A copy at the same pose with a fresh trajectory (for a new plan).
    pub fn fresh(&self) -> Self {
        Self::from_parts(
            self.map.clone(),
            self.planner.clone(),
            self.inflated.clone(),
            self.pose,
        )
    }

    /// Put the robot at `pose` (teleport), starting a fresh trajectory there.
    pub fn reset_to(&mut self, pose: Pose) {
        self.pose = pose;
        self.trajectory = Trajectory::starting_at(&self.map.name, pose);
    }

    fn free(&self, p: Point) -> bool {
        self.map
            .frame
            .cell_at(p)
            .and_then(|c| self.inflated.get(c).copied())
            .is_some_and(|occ| !occ)
    }
}

impl Robot for SimRobot {
    fn pose(&self) -> Pose {
        self.pose
    }

    fn move_to(
        &mut self,
        goal: Point,
        call: &str,
        target: StopTarget,
    ) -> Result<MoveReport, RobotError> {
        args::goal(goal)?;
        // A goal outside the map is clamped to its edge, then snapped like any other.
        let b = self.map.frame.bounds();
        let eps = self.map.frame.cell_size * 0.01;
        let clamped = Point::new(
            goal.x.clamp(b[0] + eps, b[2] - eps),
            goal.y.clamp(b[1] + eps, b[3] - eps),
        );
        let path = self
            .planner
            .plan_world(&self.map.frame, self.pose.position, clamped)?;
        let before = self.trajectory.length_m;
        self.trajectory.extend_path(&path.waypoints);
        let end = path.waypoints.last().copied().unwrap_or(self.pose.position);
        // Face along the last leg of the path.
        let n = path.waypoints.len();
        let heading = if n >= 2 {
            path.waypoints[n - 2].heading_to(end)
        } else {
            self.pose.heading
        };
        self.pose = Pose::new(end.x, end.y, heading);
        let snapped = path.goal_snapped || clamped != goal;
        self.trajectory.stops.push(Stop {
            pose: self.pose.to_array(),
            call: call.to_string(),
            target,
            goal: Some([goal.x, goal.y]),
            snapped,
        });
        self.trajectory.final_pose = self.pose.to_array();
        Ok(MoveReport {
            reached: end,
            length_m: self.trajectory.length_m - before,
            snapped,
            warning: None,
        })
    }

    fn turn(&mut self, degrees: f64) -> Result<(), RobotError> {
        args::turn(degrees)?;
        self.pose.heading = normalise_heading(self.pose.heading + degrees);
        self.trajectory.final_pose = self.pose.to_array();
        Ok(())
    }

    fn turn_absolute(&mut self, heading: f64) -> Result<(), RobotError> {
        args::heading(heading)?;
        self.pose.heading = normalise_heading(heading);
        self.trajectory.final_pose = self.pose.to_array();
        Ok(())
    }

    fn move_forward(&mut self, metres: f64) -> Result<MoveReport, RobotError> {
        args::forward(metres)?;
        let dir = if metres >= 0.0 {
            self.pose.forward()
        } else {
            self.pose.forward().scale(-1.0)
        };
        let want = metres.abs();
        let step = self.map.frame.cell_size * 0.25;
        let start = self.pose.position;
        let mut done = 0.0;
        while done < want {
            let next = (done + step).min(want);
            if !self.free(start.add(dir.scale(next))) {
                break;
            }
            done = next;
        }
        let end = start.add(dir.scale(done));
        let before = self.trajectory.length_m;
        self.trajectory.extend_path(&[end]);
        self.pose.position = end;
        self.trajectory.final_pose = self.pose.to_array();
        let warning = (want - done > 1e-9).then(|| {
            format!(
                "stopped after {done:.2} m of {want:.2} m: obstacle ahead at ({:.2}, {:.2})",
                end.x, end.y
            )
        });
        Ok(MoveReport {
            reached: end,
            length_m: self.trajectory.length_m - before,
            snapped: false,
            warning,
        })
    }

    fn trajectory(&self) -> &Trajectory {
        &self.trajectory
    }

    fn trajectory_mut(&mut self) -> &mut Trajectory {
        &mut self.trajectory
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    fn robot() -> SimRobot {
        let s = Scene::from_json_str(
            r#"{"format": "ivlmap-scene/1", "name": "r", "bounds": [0, 0, 6, 4], "cell_size": 0.05,
            "walls": [{"from": [0, 0], "to": [6, 0]}, {"from": [6, 0], "to": [6, 4]},
                      {"from": [6, 4], "to": [0, 4]}, {"from": [0, 4], "to": [0, 0]},
                      {"from": [3, 0], "to": [3, 2.8]}],
            "objects": [{"id": 1, "category": "table", "colour": "red", "center": [4.5, 2.0], "size": [0.8, 0.8]}],
            "robot": {"pose": [1, 1, 0], "radius": 0.2}}"#,
            "r.scene.json",
        )
        .unwrap();
        SimRobot::new(Arc::new(IvlMap::from_scene(&s)))
    }

    #[test]
    fn turn_positive_is_clockwise_and_absolute_90_faces_east() {
        let mut r = robot();
        r.turn(30.0).unwrap();
        assert!((r.pose().heading - 30.0).abs() < 1e-9);
        r.turn(-60.0).unwrap();
        assert!((r.pose().heading + 30.0).abs() < 1e-9);
        r.turn_absolute(90.0).unwrap();
        assert!((r.pose().heading - 90.0).abs() < 1e-9);
        // Facing east, moving forward increases x.
        let x0 = r.pose().position.x;
        r.move_forward(0.5).unwrap();
        assert!((r.pose().position.x - x0 - 0.5).abs() < 1e-9);
        assert!(r.turn(f64::NAN).is_err());
    }

    #[test]
    fn move_forward_stops_short_of_obstacles_with_a_warning() {
        let mut r = robot();
        r.turn_absolute(90.0).unwrap();
        // The interior wall at x = 3 (0.1 thick, inflated by 0.2) blocks at ~2.75.
        let rep = r.move_forward(5.0).unwrap();
        let w = rep.warning.expect("a warning");
        assert!(w.contains("obstacle ahead"), "{w}");
        let x = r.pose().position.x;
        assert!(x < 2.76 && x > 2.6, "{x}");
        assert!((r.trajectory().length_m - rep.length_m).abs() < 1e-9);
    }

    #[test]
    fn move_to_goes_around_walls_and_records_a_stop() {
        let mut r = robot();
        let rep = r
            .move_to(
                Point::new(4.5, 1.0),
                "move_to",
                StopTarget::Point([4.5, 1.0]),
            )
            .unwrap();
        assert!(rep.reached.dist(Point::new(4.5, 1.0)) < 1e-9);
        // Around the wall's end at y = 2.8: longer than the straight line.
        assert!(rep.length_m > 3.5 + 2.0, "{}", rep.length_m);
        let t = r.trajectory();
        assert_eq!(t.stops.len(), 1);
        assert_eq!(t.stops[0].call, "move_to");
        assert_eq!(t.path.first(), Some(&[1.0, 1.0]));
        let json = serde_json::to_value(t).unwrap();
        assert_eq!(
            json["stops"][0]["target"],
            serde_json::json!({"point": [4.5, 1.0]})
        );
    }

    #[test]
    fn goal_inside_an_obstacle_snaps_to_a_reachable_free_cell() {
        let mut r = robot();
        let rep = r
            .move_to(
                Point::new(4.5, 2.0),
                "move_to_object",
                StopTarget::Instance(1),
            )
            .unwrap();
        assert!(rep.snapped);
        let table = r.map().instance_by_id(1).unwrap().clone();
        let d = table.distance(rep.reached);
        assert!(d > 0.19 && d < 0.35, "{d}");
        assert_eq!(r.trajectory().stops[0].target, StopTarget::Instance(1));
    }

    #[test]
    fn a_dry_run_copy_leaves_the_original_alone() {
        let r = robot();
        let mut copy = r.clone();
        copy.move_forward(0.5).unwrap();
        assert_eq!(r.trajectory().path.len(), 1);
        assert_eq!(r.pose(), Pose::new(1.0, 1.0, 0.0));
    }
}
