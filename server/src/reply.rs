//! The answer to an instruction (formats.md: `{"tuples", "script", "trace",
//! "trajectory", "question", "error"}`, plus additive fields) and the `step` events
//! of a run: one per library call with the pose after it and the stretch of path it
//! drove.

use agent::tuples::tuples_paper_form;
use agent::{PlannedInstruction, Tuple};
use map_core::{Stop, Trajectory};
use planner_dsl::{RunOutcome, TraceEntry};
use serde::Serialize;
use serde_json::{json, Value};

/// How an instruction ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// The plan ran to its end.
    Done,
    /// The plan stopped part-way (`error` says why; what ran is kept).
    Failed,
    /// Nothing moved: the robot asks (`question`).
    Question,
    /// Nothing moved: the map cannot do it (`error`).
    Refused,
    /// A dry run: the path the plan would take; nothing moved.
    Preview,
}

/// The body of a `200` answer to `POST /api/sessions/{id}/instructions`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InstructionReply {
    /// The objects the instruction mentions.
    pub tuples: Vec<Tuple>,
    /// The script (empty when nothing was planned).
    pub script: String,
    /// Every library call (of the dry run, for a preview).
    pub trace: Vec<TraceEntry>,
    /// This instruction's stretch of the robot's trajectory (the preview path for a
    /// preview; no stops and no path when nothing moved).
    pub trajectory: Trajectory,
    /// The question the robot asks instead of moving.
    pub question: Option<String>,
    /// Why the plan stopped part-way, or why it cannot be done.
    pub error: Option<String>,
    // Additive fields.
    /// The instruction as received.
    pub instruction: String,
    /// How it ended.
    pub outcome: Kind,
    /// Whether this was a preview.
    pub preview: bool,
    /// The tuples in the paper's form, `[(table, 2, yellow)]`.
    pub tuples_text: String,
    /// What the plan said (`say`).
    pub said: Vec<String>,
    /// The robot's pose afterwards (unchanged by a preview).
    pub pose: [f64; 3],
    /// The number the session's stops start from for this reply's stops (1-based).
    pub first_stop: usize,
    /// Where the script came from, and time and tokens spent.
    pub plan: Value,
}

impl InstructionReply {
    /// A reply in which nothing moved.
    #[must_use]
    pub fn without_plan(
        instruction: &str,
        outcome: Kind,
        message: String,
        scene: &str,
        pose: [f64; 3],
        first_stop: usize,
    ) -> Self {
        let (question, error) = match outcome {
            Kind::Question => (Some(message), None),
            _ => (None, Some(message)),
        };
        Self {
            tuples: Vec::new(),
            script: String::new(),
            trace: Vec::new(),
            trajectory: Trajectory::starting_at(
                scene,
                map_core::Pose::new(pose[0], pose[1], pose[2]),
            ),
            question,
            error,
            instruction: instruction.to_string(),
            outcome,
            preview: false,
            tuples_text: "[]".into(),
            said: Vec::new(),
            pose,
            first_stop,
            plan: Value::Null,
        }
    }

    /// A reply for a plan that ran (or dry-ran): `run` is its outcome, `trajectory`
    /// this instruction's stretch.
    #[must_use]
    pub fn ran(
        planned: &PlannedInstruction,
        run: RunOutcome,
        trajectory: Trajectory,
        preview: bool,
        pose: [f64; 3],
        first_stop: usize,
    ) -> Self {
        let error = run.error.as_ref().map(ToString::to_string);
        let outcome = match (preview, &error) {
            (true, _) => Kind::Preview,
            (false, None) => Kind::Done,
            (false, Some(_)) => Kind::Failed,
        };
        Self {
            tuples: planned.tuples.clone(),
            script: planned.script.clone(),
            trace: run.trace,
            trajectory,
            question: None,
            error,
            instruction: planned.instruction.clone(),
            outcome,
            preview,
            tuples_text: tuples_paper_form(&planned.tuples),
            said: run.said,
            pose,
            first_stop,
            plan: json!({"source": planned.source, "timing": planned.timing}),
        }
    }
}

/// The stretch of `whole` from stop `stops_before` and path point `path_before` on
/// (the point the robot started from included), with `script` and `error`.
#[must_use]
pub fn stretch(
    whole: &Trajectory,
    stops_before: usize,
    path_before: usize,
    length_before: f64,
) -> Trajectory {
    let from = path_before.saturating_sub(1).min(whole.path.len());
    Trajectory {
        scene: whole.scene.clone(),
        script: whole.script.clone(),
        stops: whole.stops.get(stops_before..).unwrap_or_default().to_vec(),
        path: whole.path.get(from..).unwrap_or_default().to_vec(),
        final_pose: whole.final_pose,
        length_m: (whole.length_m - length_before).max(0.0),
        error: whole.error.clone(),
    }
}

fn same_xy(a: [f64; 2], b: [f64; 2]) -> bool {
    (a[0] - b[0]).abs() < 1e-6 && (a[1] - b[1]).abs() < 1e-6
}

/// One `step` event per library call: the call, its arguments and result, the pose
/// after it, the path points it drove (`path`, starting where the previous step ended)
/// and, when it made a stop, the stop's session-wide number (`stop`, from
/// `first_stop`).
#[must_use]
pub fn steps(trace: &[TraceEntry], stretch: &Trajectory, first_stop: usize) -> Vec<Value> {
    let path = &stretch.path;
    let mut cursor = 0usize;
    let mut stops = stretch.stops.iter().enumerate().peekable();
    let n = trace.len();
    trace
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let here = [t.pose_after[0], t.pose_after[1]];
            let start = cursor;
            let at_cursor = path.get(cursor).is_some_and(|p| same_xy(*p, here));
            if !at_cursor {
                // The first point after the cursor where the robot is now.
                if let Some(k) = path.iter().skip(cursor + 1).position(|p| same_xy(*p, here)) {
                    cursor += k + 1;
                } else if i + 1 == n {
                    cursor = path.len().saturating_sub(1);
                }
            }
            if i + 1 == n {
                cursor = cursor.max(path.len().saturating_sub(1));
            }
            let segment: Vec<[f64; 2]> = if cursor > start {
                path.get(start..=cursor).unwrap_or_default().to_vec()
            } else {
                Vec::new()
            };
            let stop = match stops.peek() {
                Some((j, s)) if made(t, s) => {
                    let k = first_stop + j;
                    stops.next();
                    Some(k)
                }
                _ => None,
            };
            json!({
                "index": i + 1,
                "function": t.function,
                "args": t.args,
                "result": t.result,
                "pose": t.pose_after,
                "path": segment,
                "stop": stop,
                "warning": t.warning,
                "error": t.error,
            })
        })
        .collect()
}

fn made(t: &TraceEntry, s: &Stop) -> bool {
    t.function == s.call && same_xy([t.pose_after[0], t.pose_after[1]], [s.pose[0], s.pose[1]])
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use std::sync::Arc;

    use map_core::{IvlMap, Robot, Scene, SimRobot};
    use planner_dsl::{Limits, Plan};

    #[test]
    fn steps_split_the_path_at_each_call() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/scenes/flat-a.scene.json"
        );
        let map = Arc::new(IvlMap::from_scene(&Scene::from_path(path).unwrap()));
        let mut robot = SimRobot::new(map.clone());
        // A first run, so the stretch starts part-way through the trajectory.
        let first = Plan::compile("agent.move_to_object(\"fridge\");").unwrap();
        planner_dsl::run(&first, &map, &mut robot, &Limits::default());
        let (s0, p0, l0) = (
            robot.trajectory().stops.len(),
            robot.trajectory().path.len(),
            robot.trajectory().length_m,
        );
        let plan = Plan::compile(
            "let s = agent.get_obj_attributes(\"sofa\", 1, \"red\");\nagent.move_to_object(s);\nagent.turn(90);\nagent.move_to_object(\"bed\");",
        )
        .unwrap();
        let run = planner_dsl::run(&plan, &map, &mut robot, &Limits::default());
        assert!(run.is_ok(), "{:?}", run.error);
        let part = stretch(robot.trajectory(), s0, p0, l0);
        assert_eq!(part.stops.len(), 2);
        assert!(part.length_m > 0.0 && part.length_m < robot.trajectory().length_m);
        let ev = steps(&run.trace, &part, s0 + 1);
        assert_eq!(ev.len(), 4);
        assert_eq!(
            ev[0]["path"].as_array().unwrap().len(),
            0,
            "a lookup drives nowhere"
        );
        assert_eq!(ev[1]["stop"], json!(2));
        assert_eq!(ev[2]["stop"], Value::Null);
        assert_eq!(ev[3]["stop"], json!(3));
        // The segments join up into the stretch's path.
        let mut joined: Vec<Value> = Vec::new();
        for e in &ev {
            let seg = e["path"].as_array().unwrap();
            if let (Some(last), Some(first)) = (joined.last(), seg.first()) {
                assert_eq!(last, first);
                joined.extend(seg.iter().skip(1).cloned());
            } else {
                joined.extend(seg.iter().cloned());
            }
        }
        assert_eq!(joined.len(), part.path.len());
        assert_eq!(part.path[0], robot.trajectory().path[p0 - 1]);
    }
}
