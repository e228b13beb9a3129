//! # eval: extraction and navigation suites against a backend, a model and a prompt
//! variant, scored per formats.md, with the VLMaps baseline for the paper's comparison.
//!
//! - [`suite::load_extract_suite`] / [`suite::load_nav_suite`]: read suites; errors name file, line, field.
//! - [`run_extract`]: the objects line of each case ([`agent::extract_tuples`]), compared with `expected` ([`agent::tuples::same_tuples`]).
//! - [`chat::run_chat`]: chat suites, turn by turn in one session; turn accuracy and
//!   dialogue success.
//! - [`run_nav`]: each task planned by a [`Method`] and executed on a simulated robot from
//!   the task's start pose; [`score::reached`] scores the stops; [`Report`] holds T_1..T_K and SR.

#![warn(missing_docs)]

pub mod baseline;
pub mod chat;
pub mod noise;
pub mod report;
pub mod score;
pub mod suite;

use std::sync::{Arc, Mutex};
use std::time::Instant;

use map_core::{IvlMap, Robot, SimRobot, Stop, Trajectory};
use planner_dsl::{Limits, Plan};

use agent::extract_tuples;
use agent::tuples::same_tuples;
use agent::{plan_instruction, Outcome, PlanContext, PlanOptions, PlanSource, Prompts, Tuple};
use llm::{Completion, CompletionRequest, LlmBackend, LlmError};

use crate::baseline::vlmap_script;
use crate::report::CaseResult;
use crate::score::{reached, side_stops};
use crate::suite::{ExtractCase, NavTask};

pub use report::Report;
pub use suite::SuiteError;

/// How a navigation task is planned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// The ivlmap language layer: tuples, then a checked Rhai plan on the instance map.
    Ivlmap,
    /// The VLMaps behaviour: the nearest instance of each mentioned category.
    Vlmap,
    /// The task's hand-written `reference` plan (no model; checks the suite and scorer).
    Reference,
}

impl Method {
    /// The name used on the command line and in reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Method::Ivlmap => "ivlmap",
            Method::Vlmap => "vlmap",
            Method::Reference => "reference",
        }
    }
}

/// The objects line of every case; `on_case` sees each result as it is made (for progress).
pub fn run_extract(
    cases: &[ExtractCase],
    backend: &dyn LlmBackend,
    prompts: &Prompts,
    options: &PlanOptions,
    on_case: &mut dyn FnMut(&CaseResult),
) -> Vec<CaseResult> {
    cases
        .iter()
        .map(|c| {
            let t0 = Instant::now();
            let r = extract_tuples(backend, prompts, &c.instruction, options);
            let latency_ms = ms(t0);
            let res = match r {
                Ok((got, _)) => CaseResult {
                    id: c.id.clone(),
                    ok: same_tuples(&got, &c.expected),
                    got: serde_json::to_value(&got).unwrap_or_default(),
                    latency_ms,
                    error: None,
                    instruction: Some(c.instruction.clone()),
                    trajectory: None,
                    reached: None,
                    turns: None,
                    reasks: None,
                    first_answer_ok: None,
                    sides: None,
                },
                Err(e) => CaseResult {
                    id: c.id.clone(),
                    ok: false,
                    got: serde_json::Value::Null,
                    latency_ms,
                    error: Some(e.to_string()),
                    instruction: Some(c.instruction.clone()),
                    trajectory: None,
                    reached: None,
                    turns: None,
                    reasks: None,
                    first_answer_ok: None,
                    sides: None,
                },
            };
            on_case(&res);
            res
        })
        .collect()
}

/// What planning produced for a task before it ran.
struct Planned {
    tuples: Option<Vec<Tuple>>,
    plan: Result<Plan, String>,
    /// Re-asks the language layer made (`None` without a model).
    reasks: Option<u32>,
    /// The language layer's first answer, where it was re-asked: the one its checks
    /// judged before any re-ask.
    first_answer: Option<String>,
}

impl Planned {
    fn without_model(plan: Result<Plan, String>, tuples: Option<Vec<Tuple>>) -> Self {
        Self {
            tuples,
            plan,
            reasks: None,
            first_answer: None,
        }
    }
}

/// A backend that keeps the first answer it passes on (the language layer's first
/// answer to an instruction, before any re-ask).
struct KeepFirst<'a> {
    inner: &'a dyn LlmBackend,
    first: Mutex<Option<String>>,
}

impl<'a> KeepFirst<'a> {
    fn new(inner: &'a dyn LlmBackend) -> Self {
        Self {
            inner,
            first: Mutex::new(None),
        }
    }

    fn first(self) -> Option<String> {
        self.first.into_inner().ok().flatten()
    }
}

impl LlmBackend for KeepFirst<'_> {
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn model(&self) -> &str {
        self.inner.model()
    }

    fn complete(&self, req: &CompletionRequest) -> Result<Completion, LlmError> {
        let c = self.inner.complete(req)?;
        if let Ok(mut first) = self.first.lock() {
            first.get_or_insert_with(|| c.text.clone());
        }
        Ok(c)
    }
}

/// Whether `answer` (a model's answer in the v2 form: objects line, then plan), run as
/// it stands from the task's start, reaches every subgoal: for a re-asked task, whether
/// the checks re-asked a plan that was right.
fn answer_reaches_all(task: &NavTask, answer: &str) -> bool {
    let Ok(a) = agent::v2::answer::parse_answer(answer) else {
        return false;
    };
    let Ok(plan) = Plan::compile(&a.plan.to_rhai()) else {
        return false;
    };
    let (stops, ran) = run_from_start(task, &plan);
    ran && reached(&task.map, &task.subgoals, &stops)
        .iter()
        .all(|b| *b)
}

/// Runs `plan` on a simulated robot at the task's start: its stops, and whether it ran
/// to the end without an error.
fn run_from_start(task: &NavTask, plan: &Plan) -> (Vec<Stop>, bool) {
    let mut robot = SimRobot::with_pose(task.map.clone(), task.start);
    let out = planner_dsl::run(plan, &task.map, &mut robot, &Limits::default());
    (robot.trajectory().stops.clone(), out.error.is_none())
}

fn plan_task(
    task: &NavTask,
    robot: &SimRobot,
    method: Method,
    backend: Option<&dyn LlmBackend>,
    prompts: &Prompts,
    options: &PlanOptions,
) -> Planned {
    let need = || "this method needs an LLM backend".to_string();
    match method {
        Method::Reference => Planned::without_model(
            match &task.reference {
                Some(src) => Plan::compile(src).map_err(|e| format!("reference plan: {e}")),
                None => Err(format!("task {} has no \"reference\" plan", task.id)),
            },
            None,
        ),
        Method::Vlmap => {
            let Some(b) = backend else {
                return Planned::without_model(Err(need()), None);
            };
            match extract_tuples(b, prompts, &task.instruction, options) {
                Ok((tuples, _)) => Planned::without_model(
                    Plan::compile(&vlmap_script(&tuples)).map_err(|e| e.to_string()),
                    Some(tuples),
                ),
                Err(e) => Planned::without_model(Err(e.to_string()), None),
            }
        }
        Method::Ivlmap => {
            let Some(b) = backend else {
                return Planned::without_model(Err(need()), None);
            };
            let mut ctx = PlanContext::new(&task.map).with_robot(robot);
            ctx.options = options.clone();
            let keep = KeepFirst::new(b);
            let outcome = plan_instruction(&keep, prompts, &task.instruction, &ctx);
            let first = keep.first();
            match outcome {
                Ok(Outcome::Plan(p)) => {
                    let PlanSource::Llm { repairs } = p.source;
                    Planned {
                        tuples: Some(p.tuples.clone()),
                        plan: Ok(p.plan.clone()),
                        reasks: Some(repairs),
                        first_answer: first.filter(|_| repairs > 0),
                    }
                }
                // A question or refusal comes when the answer after the re-ask (if
                // re-asks are on) still disagrees.
                Ok(Outcome::Question(q)) => Planned {
                    tuples: None,
                    plan: Err(format!("asked a question instead of planning: {q}")),
                    reasks: Some(u32::from(options.reask)),
                    first_answer: first,
                },
                Ok(Outcome::Refusal(r)) => Planned {
                    tuples: None,
                    plan: Err(format!("refused: {r}")),
                    reasks: Some(u32::from(options.reask)),
                    first_answer: first,
                },
                Err(e) => Planned::without_model(Err(e.to_string()), None),
            }
        }
    }
}

/// Plans and runs every task from its start pose, scoring the stops.
/// `backend` may be `None` only for [`Method::Reference`].
pub fn run_nav(
    tasks: &[NavTask],
    method: Method,
    backend: Option<&dyn LlmBackend>,
    prompts: &Prompts,
    options: &PlanOptions,
    on_case: &mut dyn FnMut(&CaseResult),
) -> Vec<CaseResult> {
    tasks
        .iter()
        .map(|task| {
            let res = run_task(task, method, backend, prompts, options);
            on_case(&res);
            res
        })
        .collect()
}

/// Plans and runs one task.
pub fn run_task(
    task: &NavTask,
    method: Method,
    backend: Option<&dyn LlmBackend>,
    prompts: &Prompts,
    options: &PlanOptions,
) -> CaseResult {
    let map: &Arc<IvlMap> = &task.map;
    let mut robot = SimRobot::with_pose(map.clone(), task.start);
    let t0 = Instant::now();
    let planned = plan_task(task, &robot, method, backend, prompts, options);
    let latency_ms = ms(t0);
    let (trajectory, error, script) = match planned.plan {
        Ok(plan) => {
            let out = planner_dsl::run(&plan, map, &mut robot, &Limits::default());
            (
                robot.trajectory().clone(),
                out.error.map(|e| e.to_string()),
                Some(plan.source().to_string()),
            )
        }
        Err(e) => {
            let mut t: Trajectory = robot.trajectory().clone();
            t.error = Some(e.clone());
            (t, Some(e), None)
        }
    };
    let reached = reached(map, &task.subgoals, &trajectory.stops);
    let sides = reference_stops(task)
        .map(|r| side_stops(map, &task.subgoals, &r, &trajectory.stops))
        .filter(|s| !s.is_empty());
    CaseResult {
        id: task.id.clone(),
        ok: reached.iter().all(|b| *b),
        got: serde_json::json!({"tuples": planned.tuples, "script": script}),
        latency_ms,
        error,
        instruction: Some(task.instruction.clone()),
        trajectory: Some(trajectory),
        reached: Some(reached),
        turns: None,
        reasks: planned.reasks,
        first_answer_ok: planned.first_answer.map(|a| answer_reaches_all(task, &a)),
        sides,
    }
}

/// The stops of the task's reference plan run from its start; `None` without one (or
/// when it does not compile).
fn reference_stops(task: &NavTask) -> Option<Vec<Stop>> {
    let plan = Plan::compile(task.reference.as_deref()?).ok()?;
    Some(run_from_start(task, &plan).0)
}

fn ms(t0: Instant) -> u64 {
    u64::try_from(t0.elapsed().as_millis()).unwrap_or(u64::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::suite::{load_nav_suite, Subgoal};
    use planner_dsl::typed::{Step, TypedPlan};
    use std::path::Path;

    /// Every public navigation suite: each task's hand-written reference plan runs on
    /// its scene and reaches every subgoal (the tasks are achievable, the ids are right
    /// for what the reference does, and the scorer credits a correct run).
    #[test]
    fn public_nav_suites_are_achievable_by_their_reference_plans() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/suites");
        let mut n = 0;
        let mut failures = Vec::new();
        for entry in std::fs::read_dir(&dir).unwrap() {
            let p = entry.unwrap().path();
            if !p.to_string_lossy().ends_with(".nav.jsonl") {
                continue;
            }
            let tasks = load_nav_suite(&p).unwrap();
            let prompts = Prompts::builtin();
            for t in &tasks {
                assert_eq!(
                    t.subgoals.len(),
                    4,
                    "{}: task {} must have 4 subgoals",
                    p.display(),
                    t.id
                );
                assert!(
                    t.reference.is_some(),
                    "{}: task {} has no reference",
                    p.display(),
                    t.id
                );
                let r = run_task(
                    t,
                    Method::Reference,
                    None,
                    &prompts,
                    &PlanOptions::default(),
                );
                // Each object subgoal was reached by a stop aimed at that very object.
                let stops = &r.trajectory.as_ref().unwrap().stops;
                for g in &t.subgoals {
                    if let Subgoal::Object(id) = g {
                        if !stops
                            .iter()
                            .any(|s| s.target == map_core::StopTarget::Instance(*id))
                        {
                            failures.push(format!(
                                "{} {}: no stop aimed at object {id}",
                                p.display(),
                                t.id
                            ));
                        }
                    }
                }
                if !r.ok {
                    failures.push(format!(
                        "{}:{} {}: reached {:?}, error {:?}",
                        p.display(),
                        t.line,
                        t.id,
                        r.reached,
                        r.error
                    ));
                }
                n += 1;
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
        assert!(n >= 24, "only {n} tasks");
    }

    #[test]
    fn a_wrong_plan_scores_what_it_reached() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/suites");
        let p = dir.join("flat-a.nav.jsonl");
        let mut tasks = load_nav_suite(&p).unwrap();
        let mut t = tasks.remove(0);
        // Reversing the reference plan's moves visits the subgoals in the wrong order.
        let src = t.reference.clone().unwrap();
        let mut lines: Vec<&str> = src.lines().collect();
        lines.reverse();
        t.reference = Some(lines.join("\n"));
        let r = run_task(
            &t,
            Method::Reference,
            None,
            &Prompts::builtin(),
            &PlanOptions::default(),
        );
        assert!(!r.ok, "{:?}", r.reached);
        // No backend: an LLM method fails cleanly with a recorded error.
        let r = run_task(
            &t,
            Method::Ivlmap,
            None,
            &Prompts::builtin(),
            &PlanOptions::default(),
        );
        assert!(!r.ok && r.error.is_some());
        assert_eq!(r.trajectory.unwrap().error, r.error);
    }

    #[test]
    fn a_run_reports_the_side_stops_of_its_reference_and_which_it_kept() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/suites");
        let tasks = load_nav_suite(&dir.join("flat-a.nav.jsonl")).unwrap();
        // The reference's typed steps; its side moves (`move_north`, `move_to_left`...).
        let typed = |t: &NavTask| TypedPlan::parse(t.reference.as_deref().unwrap()).unwrap();
        let side_move = |s: &Step| matches!(s, Step::Side { side, .. } if side.is_move());
        let side = |p: &TypedPlan| p.steps.iter().filter(|s| side_move(s)).count();
        let n: usize = tasks.iter().map(|t| side(&typed(t))).sum();
        assert!(n > 0, "flat-a's references make a side move");
        let run = |tasks: &[NavTask]| {
            let cases = run_nav(
                tasks,
                Method::Reference,
                None,
                &Prompts::builtin(),
                &PlanOptions::default(),
                &mut |_| {},
            );
            Report::new("s".into(), "-".into(), "-".into(), "-".into(), None, cases)
        };
        let r = run(&tasks);
        assert_eq!(r.summary.side_stops, Some(n));
        assert_eq!(
            r.summary.side_stops_kept,
            Some(n),
            "the reference keeps its sides"
        );
        // The same task planned with `move_to_object` at the side stop still reaches
        // every subgoal (1.0 m of the object), and the side is reported not kept.
        let (t, mut p, at) = tasks
            .iter()
            .find_map(|t| {
                let p = typed(t);
                let at = p.steps.iter().position(side_move)?;
                Some((t, p, at))
            })
            .unwrap();
        let Step::Side { side: was, object } = p.steps[at].clone() else {
            unreachable!("found as a side step")
        };
        let f = was.function();
        p.steps[at] = Step::GoTo(object);
        let plan = Plan::compile(&p.to_rhai()).unwrap();
        let (stops, ran) = run_from_start(t, &plan);
        assert!(ran);
        assert!(reached(&t.map, &t.subgoals, &stops).iter().all(|b| *b));
        let sides = side_stops(&t.map, &t.subgoals, &reference_stops(t).unwrap(), &stops);
        assert_eq!(sides.len(), 1);
        assert_eq!(sides[0].want, f);
        assert_eq!(sides[0].got.as_deref(), Some("move_to_object"));
        assert!(!sides[0].kept());
    }

    #[test]
    fn a_first_answer_is_judged_by_running_it_as_it_was() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/suites");
        let tasks = load_nav_suite(&dir.join("flat-a.nav.jsonl")).unwrap();
        // fa1: the red sofa, the second yellow table from the west, the kitchen, the
        // bathtub.
        let t = &tasks[0];
        let objects = "objects: [(sofa, None, red), (table, 2, yellow, west_to_east), (kitchen, None, None), (bathtub, None, None)]\nplan:\n";
        let sofa = "move_to_object(get_obj(\"sofa\", #{colour: \"red\"}));\n";
        let rest = "move_to_object(\"kitchen\");\nmove_to_object(get_obj(\"bathtub\"));\n";
        let table = |ordinal: i32| {
            format!("move_to_object(get_obj(\"table\", #{{ordinal: {ordinal}, colour: \"yellow\", order: \"west_to_east\"}}));\n")
        };
        assert!(answer_reaches_all(
            t,
            &format!("{objects}{sofa}{}{rest}", table(2))
        ));
        // The first yellow table from the west is the wrong one.
        assert!(!answer_reaches_all(
            t,
            &format!("{objects}{sofa}{}{rest}", table(1))
        ));
        // A plan that fails on the map (no third yellow table), and an answer that
        // cannot be read, reach nothing.
        assert!(!answer_reaches_all(
            t,
            &format!("{objects}{sofa}{}{rest}", table(3))
        ));
        assert!(!answer_reaches_all(
            t,
            "plan:\nmove_to_object(\"kitchen\");"
        ));
    }
}
