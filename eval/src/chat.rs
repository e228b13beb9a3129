//! Chat suites (`*.chat.jsonl`): each dialogue's turns run in order in one
//! [`agent::Session`] on one simulated robot; each turn's subgoals are scored on that
//! turn's stops, and a turn marked `"expect": "question"` is reached when the product
//! asks (or refuses) instead of moving.

use std::time::Instant;

use map_core::{Robot, SimRobot, Trajectory};
use planner_dsl::Limits;
use serde::{Deserialize, Serialize};

use agent::{Outcome, PlanContext, PlanOptions, Prompts, Session};
use llm::LlmBackend;

use crate::report::CaseResult;
use crate::score::reached;
use crate::suite::Dialogue;

/// One turn's result, as formats.md lays it out.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TurnResult {
    /// What the person said.
    pub say: String,
    /// The tuples of the plan, if one was made.
    pub tuples: Option<serde_json::Value>,
    /// The script that ran, if one did.
    pub script: Option<String>,
    /// This turn's stops and path.
    pub trajectory: Trajectory,
    /// The question (or refusal) the product answered with instead of moving.
    pub question: Option<String>,
    /// Why planning or running failed, if it did.
    pub error: Option<String>,
    /// Per subgoal, whether this turn reached it (for a question turn: one entry, whether
    /// the product asked).
    pub reached: Vec<bool>,
    /// Time the language layer took for this turn, ms.
    pub latency_ms: u64,
}

impl TurnResult {
    /// Every subgoal of the turn reached.
    #[must_use]
    pub fn ok(&self) -> bool {
        self.reached.iter().all(|b| *b)
    }
}

fn path_length(path: &[[f64; 2]]) -> f64 {
    path.windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum()
}

/// Runs one dialogue.
pub fn run_dialogue(
    d: &Dialogue,
    backend: &dyn LlmBackend,
    prompts: &Prompts,
    options: &PlanOptions,
) -> CaseResult {
    let mut robot = SimRobot::with_pose(d.map.clone(), d.start);
    let mut session = Session::new(d.start);
    let mut turns = Vec::new();
    let mut total_ms = 0;
    for turn in &d.turns {
        let stops_before = robot.trajectory().stops.len();
        let path_before = robot.trajectory().path.len().saturating_sub(1);
        let t0 = Instant::now();
        let outcome = {
            let mut ctx = PlanContext::new(&d.map).with_robot(&robot);
            ctx.options = options.clone();
            session.plan(backend, prompts, &turn.say, &ctx)
        };
        let latency_ms = u64::try_from(t0.elapsed().as_millis()).unwrap_or(u64::MAX);
        total_ms += latency_ms;
        let (tuples, script, question, error) = match outcome {
            Ok(Outcome::Plan(p)) => {
                let out = session.execute(&p, &d.map, &mut robot, &Limits::default());
                (
                    serde_json::to_value(&p.tuples).ok(),
                    Some(p.script.clone()),
                    None,
                    out.error.map(|e| e.to_string()),
                )
            }
            Ok(Outcome::Question(q) | Outcome::Refusal(q)) => {
                // The next turn may be the person's answer to it.
                session.not_done(&turn.say, &q);
                (None, None, Some(q), None)
            }
            Err(e) => (None, None, None, Some(e.to_string())),
        };
        let tr = robot.trajectory();
        let stops = tr.stops.get(stops_before..).unwrap_or_default().to_vec();
        let path = tr.path.get(path_before..).unwrap_or_default().to_vec();
        let reached = if turn.expect_question {
            vec![question.is_some() && stops.is_empty()]
        } else {
            reached(&d.map, &turn.subgoals, &stops)
        };
        turns.push(TurnResult {
            say: turn.say.clone(),
            tuples,
            script: script.clone(),
            trajectory: Trajectory {
                scene: tr.scene.clone(),
                script: script.unwrap_or_default(),
                stops,
                length_m: path_length(&path),
                path,
                final_pose: robot.pose().to_array(),
                error: error.clone(),
            },
            question,
            error,
            reached,
            latency_ms,
        });
    }
    CaseResult {
        id: d.id.clone(),
        ok: turns.iter().all(TurnResult::ok),
        got: serde_json::json!({ "turns_ok": turns.iter().filter(|t| t.ok()).count() }),
        latency_ms: total_ms,
        error: turns.iter().find_map(|t| t.error.clone()),
        instruction: None,
        trajectory: Some(robot.trajectory().clone()),
        reached: None,
        reasks: None,
        first_answer_ok: None,
        sides: None,
        turns: Some(turns),
    }
}

/// Runs every dialogue; `on_case` sees each result as it is made.
pub fn run_chat(
    dialogues: &[Dialogue],
    backend: &dyn LlmBackend,
    prompts: &Prompts,
    options: &PlanOptions,
    on_case: &mut dyn FnMut(&CaseResult),
) -> Vec<CaseResult> {
    dialogues
        .iter()
        .map(|d| {
            let r = run_dialogue(d, backend, prompts, options);
            on_case(&r);
            r
        })
        .collect()
}
