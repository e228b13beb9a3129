//! A chat session: instructions one after another, with what each did, so that
//! "go back to the table you just visited", "the other one" and "come back here" can be
//! understood.
//!
//! The conversation reaches the model as named references in the request (after the
//! shared prompt prefix, so caching still works): where the session started, where the
//! robot is, and each visited instance with its id, which the plan may name with
//! `get_instance`. No word list decides what a follow-up means: the model writes the
//! plan and the typed checks hold it to the map and the references.

use map_core::{IvlMap, Pose, Robot, StopTarget};
use planner_dsl::{Limits, RunOutcome};
use serde::Serialize;

use llm::LlmBackend;

use crate::pipeline::{plan_instruction, LanguageError, Outcome, PlanContext, PlannedInstruction};
use crate::prompts::Prompts;
use crate::tuples::Tuple;

/// One executed instruction.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Turn {
    /// What the user said.
    pub instruction: String,
    /// The objects it mentioned.
    pub tuples: Vec<Tuple>,
    /// The script that ran.
    pub script: String,
    /// Instance ids the robot stopped at, in order.
    pub visited: Vec<u32>,
    /// Stop poses `[x, y, heading]`, in order.
    pub stops: Vec<[f64; 3]>,
    /// Pose when the turn began.
    pub start_pose: [f64; 3],
    /// Pose when it ended.
    pub end_pose: [f64; 3],
    /// Why it stopped early, if it did.
    pub error: Option<String>,
}

/// An instruction the session answered with a question or a refusal instead of a plan.
/// The person's next words are often the answer to it ("oh sorry, I meant the two red
/// ones", "the black one then"), which mean nothing without it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Unanswered {
    /// What the person said.
    pub instruction: String,
    /// The question (or refusal) they got.
    pub reply: String,
}

/// A conversation with the robot.
#[derive(Debug, Clone)]
pub struct Session {
    start: Pose,
    turns: Vec<Turn>,
    unanswered: Option<Unanswered>,
}

impl Session {
    /// A session whose robot starts at `start`.
    #[must_use]
    pub fn new(start: Pose) -> Self {
        Self {
            start,
            turns: Vec::new(),
            unanswered: None,
        }
    }

    /// Records that `instruction` got `reply`, a question or a refusal, instead of a
    /// plan: until a plan runs, the next instruction is planned as a possible answer to
    /// it (see [`Session::references`] and [`PlanContext::earlier`]).
    pub fn not_done(&mut self, instruction: &str, reply: &str) {
        self.unanswered = Some(Unanswered {
            instruction: instruction.to_string(),
            reply: reply.to_string(),
        });
    }

    /// The last instruction that got a question or a refusal, if no plan ran since.
    #[must_use]
    pub fn unanswered(&self) -> Option<&Unanswered> {
        self.unanswered.as_ref()
    }

    /// The turns so far.
    #[must_use]
    pub fn turns(&self) -> &[Turn] {
        &self.turns
    }

    /// The conversation as named references for v2's request: where the session
    /// started, then each visited instance, most recent last, with its id, e.g.
    /// `start: [1.0, 1.0]; visited: table 17 (yellow) in turn 1, sofa 2 (black) in turn 2`;
    /// then the last instruction that got a question or a refusal, if no plan ran since
    /// ([`Session::not_done`]). `None` before anything was said.
    #[must_use]
    pub fn references(&self, map: &IvlMap) -> Option<String> {
        if self.turns.is_empty() && self.unanswered.is_none() {
            return None;
        }
        let p = self.start.position;
        let mut visited = Vec::new();
        for (k, t) in self.turns.iter().enumerate() {
            for id in &t.visited {
                if let Some(i) = map.instance_by_id(*id) {
                    visited.push(format!(
                        "{} in turn {}",
                        crate::v2::check::instance_words(i),
                        k + 1
                    ));
                }
            }
        }
        let last = self
            .turns
            .last()
            .map_or_else(|| self.start.to_array(), |t| t.end_pose);
        let mut s = format!(
            "we started at [{:.1}, {:.1}]; you are at [{:.1}, {:.1}]; visited so far: {}",
            p.x,
            p.y,
            last[0],
            last[1],
            if visited.is_empty() {
                "nothing".to_string()
            } else {
                visited.join(", ")
            }
        );
        if let Some(u) = &self.unanswered {
            s.push_str(&format!(
                "; not done: the person said \"{}\" and you answered \"{}\"",
                u.instruction, u.reply
            ));
        }
        Some(s)
    }

    /// Plans the next instruction in the light of the conversation: the session's
    /// references (see [`Session::references`]) go into the request unless `ctx`
    /// carries a history of its own, the instances visited so far may be named by id in
    /// the plan, and an instruction left unanswered ([`Session::not_done`]) is
    /// [`PlanContext::earlier`] unless `ctx` has one; then [`plan_instruction`].
    ///
    /// # Errors
    /// As [`plan_instruction`].
    pub fn plan(
        &self,
        backend: &dyn LlmBackend,
        prompts: &Prompts,
        instruction: &str,
        ctx: &PlanContext<'_>,
    ) -> Result<Outcome, LanguageError> {
        let mut ctx = ctx.clone();
        if ctx.history.is_none() {
            ctx.history = self.references(ctx.map);
        }
        if ctx.earlier.is_none() {
            ctx.earlier = self.unanswered.as_ref().map(|u| u.instruction.clone());
        }
        for t in &self.turns {
            for id in &t.visited {
                if !ctx.references.contains(id) {
                    ctx.references.push(*id);
                }
            }
        }
        plan_instruction(backend, prompts, instruction, &ctx)
    }

    /// Records a turn from a run: the stops the robot made since `stops_before` (the length
    /// of its trajectory's stop list before the run).
    pub fn record(
        &mut self,
        planned: &PlannedInstruction,
        robot: &dyn Robot,
        stops_before: usize,
        start_pose: Pose,
        error: Option<String>,
    ) {
        let tr = robot.trajectory();
        let new = tr.stops.get(stops_before..).unwrap_or_default();
        let visited = new
            .iter()
            .filter_map(|s| match s.target {
                StopTarget::Instance(id) => Some(id),
                _ => None,
            })
            .collect();
        self.unanswered = None;
        self.turns.push(Turn {
            instruction: planned.instruction.clone(),
            tuples: planned.tuples.clone(),
            script: planned.script.clone(),
            visited,
            stops: new.iter().map(|s| s.pose).collect(),
            start_pose: start_pose.to_array(),
            end_pose: robot.pose().to_array(),
            error,
        });
    }

    /// Runs a plan on `robot` and records the turn.
    pub fn execute(
        &mut self,
        planned: &PlannedInstruction,
        map: &IvlMap,
        robot: &mut dyn Robot,
        limits: &Limits,
    ) -> RunOutcome {
        let before = robot.trajectory().stops.len();
        let start = robot.pose();
        let out = planner_dsl::run(&planned.plan, map, robot, limits);
        let err = out.error.as_ref().map(ToString::to_string);
        self.record(planned, robot, before, start, err);
        out
    }
}
