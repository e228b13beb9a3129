//! Mission files for `ivlmap run`: a Rhai plan (`.rhai`) or a list of instructions (one
//! per line, `#` comments). Either may name its scene in a header comment
//! (`// scene: ../scenes/flat-a.scene.json` or `# scene: ...`), relative to the file.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use map_core::{IvlMap, Robot, SimRobot, Trajectory};
use planner_dsl::{Limits, Plan, RunOutcome};

use crate::error::CliError;
use agent::tuples::tuples_paper_form;
use agent::{Outcome, PlanContext, Prompts, Session};
use llm::LlmBackend;

/// What a mission file holds.
#[derive(Debug, Clone, PartialEq)]
pub enum Mission {
    /// A Rhai plan.
    Script(String),
    /// Instructions with their 1-based line numbers.
    Instructions(Vec<(usize, String)>),
}

impl Mission {
    /// Whether running it needs an LLM backend.
    #[must_use]
    pub fn needs_backend(&self) -> bool {
        matches!(self, Mission::Instructions(_))
    }
}

/// Reads a mission file; returns it and the scene its header names, if any.
///
/// # Errors
/// [`CliError::Input`] when the file cannot be read or holds no instruction.
pub fn load_mission(path: &Path) -> Result<(Mission, Option<PathBuf>), CliError> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        CliError::Input(format!("{}: cannot read mission file: {e}", path.display()))
    })?;
    let dir = path.parent().unwrap_or_else(|| Path::new(""));
    let is_script = path.extension().is_some_and(|e| e == "rhai");
    let mut scene = None;
    for line in text.lines().take(20) {
        let t = line.trim();
        let body = t
            .strip_prefix("//")
            .or_else(|| t.strip_prefix('#'))
            .map(str::trim);
        if let Some(rest) = body.and_then(|b| b.strip_prefix("scene:")) {
            scene = Some(dir.join(rest.trim()));
            break;
        }
    }
    if is_script {
        return Ok((Mission::Script(text), scene));
    }
    let items: Vec<(usize, String)> = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
        .map(|(i, l)| (i, l.to_string()))
        .collect();
    if items.is_empty() {
        return Err(CliError::Input(format!(
            "{}: the mission holds no instruction (one per line; lines starting with # are comments)",
            path.display()
        )));
    }
    Ok((Mission::Instructions(items), scene))
}

/// What a mission did: the whole trajectory (with `error` set when a step failed).
#[derive(Debug, Clone)]
pub struct MissionReport {
    /// The trajectory of formats.md (script = every script that ran).
    pub trajectory: Trajectory,
    /// Why the mission stopped early, if it did (file:line: ...).
    pub error: Option<String>,
}

/// Prints a run's execution trace, one line per library call.
pub(crate) fn print_trace(out: &mut dyn Write, outcome: &RunOutcome) {
    for (i, t) in outcome.trace.iter().enumerate() {
        let args: Vec<String> = t.args.iter().map(compact).collect();
        let result = if t.result.is_null() {
            String::new()
        } else {
            format!(" -> {}", compact(&t.result))
        };
        let _ = writeln!(
            out,
            "  {:>2}. {}({}){}  @ ({:.2}, {:.2}, {:.0}°)",
            i + 1,
            t.function,
            args.join(", "),
            result,
            t.pose_after[0],
            t.pose_after[1],
            t.pose_after[2]
        );
        if let Some(w) = &t.warning {
            let _ = writeln!(out, "      warning: {w}");
        }
        if let Some(e) = &t.error {
            let _ = writeln!(out, "      error: {e}");
        }
    }
    for s in &outcome.said {
        let _ = writeln!(out, "  robot says: {s}");
    }
}

fn compact(v: &serde_json::Value) -> String {
    if let Some(o) = v.as_object() {
        // Object records: "table #3 (yellow, id 8)".
        if let (Some(n), Some(id)) = (o.get("name").and_then(|x| x.as_str()), o.get("id")) {
            let colour = o.get("colour").and_then(|c| c.as_str()).unwrap_or("");
            let k = o
                .get("label_id")
                .map(ToString::to_string)
                .unwrap_or_default();
            return format!("{colour} {n} #{k} (id {id})").trim().to_string();
        }
    }
    let s = v.to_string();
    if s.len() > 80 {
        format!(
            "{}...",
            &s[..s.char_indices().nth(77).map_or(s.len(), |(i, _)| i)]
        )
    } else {
        s
    }
}

/// Runs a mission on `robot` (the simulator at the map's start pose, or a driver),
/// printing what happens. Instruction lists need `backend`; candidate plans are
/// dry-run on a simulator at the robot's pose; a failing step stops the mission,
/// keeping what was done.
pub fn run_mission(
    mission: &Mission,
    mission_path: &Path,
    map: &Arc<IvlMap>,
    robot: &mut dyn Robot,
    backend: Option<&dyn LlmBackend>,
    prompts: &Prompts,
    out: &mut dyn Write,
) -> MissionReport {
    let limits = Limits::default();
    let file = mission_path.display().to_string();
    let error = match mission {
        Mission::Script(src) => match Plan::compile(src) {
            Err(e) => {
                robot.trajectory_mut().script = src.clone();
                Some(format!(
                    "{file}: the plan was rejected before running:\n{e}"
                ))
            }
            Ok(plan) => {
                let outcome = planner_dsl::run(&plan, map, robot, &limits);
                print_trace(out, &outcome);
                outcome.error.map(|e| format!("{file}: {e}"))
            }
        },
        Mission::Instructions(items) => match backend {
            None => Some(format!(
                "{file}: a list of instructions needs an LLM backend"
            )),
            Some(b) => run_instructions(items, &file, map, b, prompts, robot, &limits, out),
        },
    };
    let mut trajectory = robot.trajectory().clone();
    trajectory.error.clone_from(&error);
    let _ = writeln!(
        out,
        "{} stop(s), path {:.2} m{}",
        trajectory.stops.len(),
        trajectory.length_m,
        if error.is_some() {
            " (stopped early)"
        } else {
            ""
        }
    );
    MissionReport { trajectory, error }
}

#[allow(clippy::too_many_arguments)]
fn run_instructions(
    items: &[(usize, String)],
    file: &str,
    map: &Arc<IvlMap>,
    backend: &dyn LlmBackend,
    prompts: &Prompts,
    robot: &mut dyn Robot,
    limits: &Limits,
    out: &mut dyn Write,
) -> Option<String> {
    let mut session = Session::new(robot.pose());
    let mut scripts = String::new();
    let mut failure = None;
    for (line, instr) in items {
        let _ = writeln!(out, "> {instr}");
        // The dry run is always the simulator's, from where the robot is.
        let sim = SimRobot::with_pose(map.clone(), robot.pose());
        let ctx = PlanContext::new(map).with_robot(&sim);
        let outcome = session.plan(backend, prompts, instr, &ctx);
        let planned = match outcome {
            Ok(Outcome::Plan(p)) => p,
            Ok(Outcome::Question(q)) => {
                failure = Some(format!(
                    "{file}:{line}: {instr:?}: the robot needs an answer: {q}"
                ));
                break;
            }
            Ok(Outcome::Refusal(r)) => {
                failure = Some(format!(
                    "{file}:{line}: {instr:?}: cannot do this here: {r}"
                ));
                break;
            }
            Err(e) => {
                failure = Some(format!("{file}:{line}: {instr:?}: {e}"));
                break;
            }
        };
        let _ = writeln!(out, "  tuples: {}", tuples_paper_form(&planned.tuples));
        let _ = writeln!(out, "  script:");
        for l in planned.script.lines() {
            let _ = writeln!(out, "    {l}");
        }
        scripts.push_str(&format!(
            "// {file}:{line}: {instr}\n{}\n",
            planned.script.trim_end()
        ));
        let before = robot.trajectory().length_m;
        let run = session.execute(&planned, map, robot, limits);
        print_trace(out, &run);
        let _ = writeln!(out, "  path {:.2} m", robot.trajectory().length_m - before);
        if let Some(e) = run.error {
            failure = Some(format!("{file}:{line}: {instr:?}: {e}"));
            break;
        }
    }
    robot.trajectory_mut().script = scripts;
    failure
}
