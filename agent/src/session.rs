//! A chat session: instructions one after another, with what each did, so that
//! "now go back" and "the other one" can be resolved.
//!
//! The history reaches the model as a compact summary in step 2's request (after the shared
//! prompt prefix, so caching still works). Two follow-ups are resolved without the model:
//! - "go back" (alone, with filler words): to the previous stop position (the stop before the
//!   last one, or where the session started);
//! - "the other one": the other instance of the category visited last (same colour first);
//!   when more than one other instance exists, a question.

use std::time::Instant;

use map_core::{IvlMap, ObjectOrder, Pose, Robot, StopTarget};
use planner_dsl::{Limits, RunOutcome};
use serde::Serialize;

use llm::LlmBackend;

use crate::pipeline::{
    assess, plan_instruction, LanguageError, Outcome, PlanContext, PlanSource, PlannedInstruction,
    Timing,
};
use crate::prompts::Prompts;
use crate::tuples::Tuple;
use crate::words::words;

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

/// A conversation with the robot.
#[derive(Debug, Clone)]
pub struct Session {
    start: Pose,
    turns: Vec<Turn>,
    /// How many recent turns the prompt summary covers (default 3).
    pub summary_turns: usize,
}

/// "go back", "now go back please", "return to where you were", "back".
fn is_go_back(instruction: &str) -> bool {
    let w = words(instruction);
    let has_back = w.iter().any(|x| x == "back") || w.first().is_some_and(|x| x == "return");
    let filler = [
        "now", "please", "go", "move", "head", "drive", "walk", "back", "return", "to", "where",
        "you", "were", "was", "i", "the", "previous", "last", "position", "place", "spot", "stop",
        "there", "again", "and", "ok", "okay", "then", "came", "from", "we", "one", "earlier",
        "before",
    ];
    has_back && w.iter().all(|x| filler.contains(&x.as_str()))
}

/// "the other one", "go to the other one", "now the other one please".
fn is_other_one(instruction: &str) -> bool {
    let w = words(instruction);
    let pos = w.windows(2).position(|p| p[0] == "other" && p[1] == "one");
    let filler = [
        "now", "please", "go", "to", "the", "other", "one", "move", "head", "drive", "walk",
        "instead", "try", "then", "no", "and", "visit",
    ];
    pos.is_some() && w.iter().all(|x| filler.contains(&x.as_str()))
}

impl Session {
    /// A session whose robot starts at `start`.
    #[must_use]
    pub fn new(start: Pose) -> Self {
        Self {
            start,
            turns: Vec::new(),
            summary_turns: 3,
        }
    }

    /// The turns so far.
    #[must_use]
    pub fn turns(&self) -> &[Turn] {
        &self.turns
    }

    /// Every stop position so far, after the start pose.
    fn positions(&self) -> Vec<[f64; 3]> {
        let mut v = vec![self.start.to_array()];
        for t in &self.turns {
            v.extend(t.stops.iter().copied());
        }
        v
    }

    /// Where "go back" leads: the stop before the last one (or the start).
    #[must_use]
    pub fn previous_stop(&self) -> Option<[f64; 3]> {
        let p = self.positions();
        (p.len() >= 2).then(|| p[p.len() - 2])
    }

    /// The conversation as named references for v2's request: where the session
    /// started, then each visited instance, most recent last, with its id, e.g.
    /// `start: [1.0, 1.0]; visited: table 17 (yellow) in turn 1, sofa 2 (black) in turn 2`.
    #[must_use]
    pub fn references(&self, map: &IvlMap) -> Option<String> {
        if self.turns.is_empty() {
            return None;
        }
        let p = self.start.position;
        let mut visited = Vec::new();
        for (k, t) in self.turns.iter().enumerate() {
            for id in &t.visited {
                if let Some(i) = map.instance_by_id(*id) {
                    visited.push(format!(
                        "{} {} ({}) in turn {}",
                        i.label,
                        i.id,
                        i.colour.as_deref().unwrap_or("unknown colour"),
                        k + 1
                    ));
                }
            }
        }
        let last = self.turns.last().map(|t| t.end_pose).unwrap_or_default();
        Some(format!(
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
        ))
    }

    /// A compact summary of the recent turns for the prompt, e.g.
    /// `"go to the red sofa" -> stopped at sofa (red, instance 2) at (3.1, 4.0)`.
    #[must_use]
    pub fn summary(&self, map: &IvlMap) -> Option<String> {
        if self.turns.is_empty() {
            return None;
        }
        let skip = self.turns.len().saturating_sub(self.summary_turns);
        let parts: Vec<String> = self.turns[skip..]
            .iter()
            .map(|t| {
                let visited: Vec<String> = t
                    .visited
                    .iter()
                    .filter_map(|id| map.instance_by_id(*id))
                    .map(|i| {
                        format!(
                            "{} ({}, instance {})",
                            i.label,
                            i.colour.as_deref().unwrap_or("unknown colour"),
                            i.id
                        )
                    })
                    .collect();
                let end = t.end_pose;
                format!(
                    "\"{}\" -> {}; ended at ({:.1}, {:.1})",
                    t.instruction,
                    if visited.is_empty() {
                        "no object visited".to_string()
                    } else {
                        format!("stopped at {}", visited.join(", "))
                    },
                    end[0],
                    end[1]
                )
            })
            .collect();
        Some(parts.join(" | "))
    }

    fn planned(
        &self,
        instruction: &str,
        script: String,
        tuples: Vec<Tuple>,
        ctx: &PlanContext<'_>,
        t0: Instant,
    ) -> Result<Outcome, LanguageError> {
        match assess(&script, &tuples, ctx) {
            Ok((src, plan, fixes)) => {
                let timing = Timing {
                    wall_ms: t0.elapsed().as_secs_f64() * 1000.0,
                    ..Timing::default()
                };
                Ok(Outcome::Plan(Box::new(PlannedInstruction {
                    instruction: instruction.to_string(),
                    tuples,
                    script: src,
                    plan,
                    source: PlanSource::History,
                    timing,
                    attempts: Vec::new(),
                    fixes,
                })))
            }
            Err(errors) => Ok(Outcome::Refusal(format!(
                "I can't do that from here: {}",
                errors.join("; ")
            ))),
        }
    }

    /// Plans the next instruction in the light of the conversation: "go back" and "the
    /// other one" are resolved from the history; anything else goes through
    /// [`plan_instruction`] with the history summary in the prompt.
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
        let t0 = Instant::now();
        if ctx.options.pipeline == crate::Pipeline::V2 {
            // v2: no word lists; the history reaches the model as named references
            // (what was visited, where the session started) and resolves through the
            // typed plan it writes.
            let mut ctx = ctx.clone();
            if ctx.history.is_none() {
                ctx.history = self.references(ctx.map);
            }
            for t in &self.turns {
                for id in &t.visited {
                    if !ctx.references.contains(id) {
                        ctx.references.push(*id);
                    }
                }
            }
            return plan_instruction(backend, prompts, instruction, &ctx);
        }
        if is_go_back(instruction) {
            let Some(p) = self.previous_stop() else {
                return Ok(Outcome::Question(
                    "There is nowhere to go back to yet: where should I go?".into(),
                ));
            };
            let script = format!("agent.move_to([{:.3}, {:.3}]);\n", p[0], p[1]);
            return self.planned(instruction, script, Vec::new(), ctx, t0);
        }
        if is_other_one(instruction) {
            return self.other_one(instruction, ctx, t0);
        }
        let mut ctx = ctx.clone();
        if ctx.history.is_none() {
            ctx.history = self.summary(ctx.map);
        }
        plan_instruction(backend, prompts, instruction, &ctx)
    }

    fn other_one(
        &self,
        instruction: &str,
        ctx: &PlanContext<'_>,
        t0: Instant,
    ) -> Result<Outcome, LanguageError> {
        let map = ctx.map;
        let Some(last) = self
            .turns
            .iter()
            .rev()
            .find_map(|t| t.visited.last())
            .and_then(|id| map.instance_by_id(*id))
        else {
            return Ok(Outcome::Question(
                "Which object do you mean by \"the other one\"? I have not been to any yet.".into(),
            ));
        };
        let same_label: Vec<_> = map
            .instances
            .iter()
            .filter(|i| i.label == last.label && i.id != last.id)
            .collect();
        let same_colour: Vec<_> = same_label
            .iter()
            .copied()
            .filter(|i| i.colour == last.colour)
            .collect();
        let (cands, colour) = if same_colour.is_empty() {
            (same_label, None)
        } else {
            (same_colour, last.colour.clone())
        };
        let what = match &colour {
            Some(c) => format!("{c} {}", map_core::matcher::plural(&last.label)),
            None => map_core::matcher::plural(&last.label),
        };
        match cands.len() {
            0 => Ok(Outcome::Refusal(format!(
                "There is no other {} on the map: the one I visited is the only one.",
                last.label
            ))),
            1 => {
                let target = cands[0];
                // Address it in a pose-independent order, so the dry run and the real run agree.
                let mut pool: Vec<_> = map
                    .instances
                    .iter()
                    .filter(|i| i.label == last.label && (colour.is_none() || i.colour == colour))
                    .collect();
                pool.sort_by(|a, b| a.center().x.total_cmp(&b.center().x).then(a.id.cmp(&b.id)));
                let k = pool.iter().position(|i| i.id == target.id).unwrap_or(0) as i64 + 1;
                let c = colour.clone().unwrap_or_default();
                let script = format!(
                    "let other = agent.get_obj_attributes(\"{}\", {k}, \"{c}\", \"{}\");\nagent.move_to_object(other);\n",
                    last.label,
                    ObjectOrder::WestToEast.name()
                );
                let tuple = Tuple::new(&last.label, Some(k), colour.as_deref());
                self.planned(instruction, script, vec![tuple], ctx, t0)
            }
            n => Ok(Outcome::Question(format!(
                "There are {n} other {what} besides the one I visited; which one do you mean?"
            ))),
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn follow_up_phrases() {
        for s in [
            "go back",
            "Now go back, please.",
            "return to where you were",
            "go back to the previous position",
        ] {
            assert!(is_go_back(s), "{s}");
        }
        for s in [
            "go back to the red sofa",
            "go to the table",
            "turn back 90 degrees to the left",
        ] {
            assert!(!is_go_back(s), "{s}");
        }
        assert!(is_other_one("now go to the other one"));
        assert!(is_other_one("the other one, please"));
        assert!(!is_other_one("go to the other one near the bed"));
    }
}
