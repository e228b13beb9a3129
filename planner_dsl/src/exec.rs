//! Running a plan. The script runs on its own thread (with a stack sized for the
//! call-level limit); each library call is sent to the calling thread, which alone
//! touches the map and the robot. So the robot never needs to be `Send`, and a
//! runaway script cannot touch anything but its own thread.

use crate::engine::{self, Link, Request, Response, TOKEN_DEADLINE, TOKEN_LIBRARY};
use crate::error::{RuntimeError, RuntimeErrorKind, Span};
use crate::library::Host;
use crate::limits::Limits;
use crate::plan::Plan;
use crate::trace::{DryRun, RunOutcome};
use map_core::{IvlMap, Robot, SimRobot};
use rhai::{EvalAltResult, Scope};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::Instant;

/// Stack of the script thread. Rhai's tree-walking evaluator needs a lot of stack
/// per call level in debug builds; this keeps `max_call_levels` safely reachable.
const SCRIPT_STACK_BYTES: usize = 64 * 1024 * 1024;

/// Runs `plan` against `map` with `robot` under `limits`.
///
/// The robot moves as the plan says. A runtime error stops the plan where it is:
/// the trace and the robot's trajectory up to that point are kept, and the error
/// carries line, column and the map's own message. The robot's trajectory gets the
/// script and (on failure) the error, as formats.md's trajectory file wants.
pub fn run(plan: &Plan, map: &IvlMap, robot: &mut dyn Robot, limits: &Limits) -> RunOutcome {
    let start = Instant::now();
    let mut host = Host::new(map, robot, limits);
    let operations = Arc::new(AtomicU64::new(0));
    let script_result = drive(plan, limits, &mut host, operations.clone());

    let error = match (host.failure.take(), script_result) {
        (Some(f), _) => Some(f),
        (None, Ok(())) => None,
        (None, Err(e)) => Some(e),
    };
    let robot = host.robot();
    let final_pose = robot.pose().to_array();
    let traj = robot.trajectory_mut();
    traj.script = plan.source().to_string();
    traj.error = error.as_ref().map(|e| e.to_string());
    RunOutcome {
        trace: host.trace,
        said: host.said,
        error,
        operations: operations.load(Ordering::Relaxed),
        elapsed_us: u64::try_from(start.elapsed().as_micros()).unwrap_or(u64::MAX),
        final_pose,
    }
}

/// Runs `plan` on a fresh copy of `robot` (same pose, a trajectory of its own) and
/// returns the preview trajectory, which holds only this plan's path and stops; the
/// real robot is not touched. The copy starts with the robot's earlier stops, so that
/// the selection keys `visited` and `not_visited` count what it visited before.
pub fn dry_run(plan: &Plan, map: &IvlMap, robot: &SimRobot, limits: &Limits) -> DryRun {
    let mut copy = robot.fresh();
    let earlier = robot.trajectory().stops.clone();
    let n = earlier.len();
    copy.trajectory_mut().stops = earlier;
    let outcome = run(plan, map, &mut copy, limits);
    let mut trajectory = copy.trajectory().clone();
    trajectory.stops.drain(..n.min(trajectory.stops.len()));
    DryRun {
        outcome,
        trajectory,
    }
}

/// Runs the script thread and serves its library calls until it finishes.
fn drive(
    plan: &Plan,
    limits: &Limits,
    host: &mut Host<'_>,
    operations: Arc<AtomicU64>,
) -> Result<(), RuntimeError> {
    let (req_tx, req_rx) = mpsc::channel::<Request>();
    let (resp_tx, resp_rx) = mpsc::channel::<Response>();
    let link = Arc::new(Link {
        chan: Mutex::new((req_tx.clone(), resp_rx)),
        library_nanos: AtomicU64::new(0),
    });
    let engine = engine::for_run(limits, link, operations);
    let ast = plan.ast();

    std::thread::scope(|s| {
        let worker = std::thread::Builder::new()
            .name("planner_dsl-script".into())
            .stack_size(SCRIPT_STACK_BYTES)
            .spawn_scoped(s, move || {
                let mut scope = Scope::new();
                let result = engine.run_ast_with_scope(&mut scope, ast);
                drop(scope);
                drop(engine); // drops the link's sender before `Done`
                let _ = req_tx.send(Request::Done(result));
            });
        let worker = match worker {
            Ok(w) => w,
            Err(e) => {
                return Err(internal(format!("could not start the script thread: {e}")));
            }
        };
        let mut finished = None;
        for req in req_rx.iter() {
            match req {
                Request::Call { spec, args, span } => {
                    let answer = host.handle(spec, &args, span);
                    if resp_tx.send(answer).is_err() {
                        break;
                    }
                }
                Request::Done(r) => {
                    finished = Some(r);
                    break;
                }
            }
        }
        let joined = worker.join();
        match (finished, joined) {
            (Some(r), _) => r.map_err(|e| convert(&e)),
            (None, Err(_)) => Err(internal("the script engine panicked".into())),
            (None, Ok(())) => Err(internal("the script thread ended without a result".into())),
        }
    })
}

fn internal(message: String) -> RuntimeError {
    RuntimeError {
        span: Span { line: 0, col: 0 },
        function: None,
        kind: RuntimeErrorKind::Internal,
        message,
    }
}

/// Turns a Rhai error into a [`RuntimeError`] at the innermost position.
pub(crate) fn convert(e: &EvalAltResult) -> RuntimeError {
    let inner = e.unwrap_inner();
    let mut span = Span::from_position(inner.position());
    if !span.is_known() {
        span = Span::from_position(e.position());
    }
    let kind = match inner {
        EvalAltResult::ErrorTooManyOperations(..) => RuntimeErrorKind::TooManyOperations,
        EvalAltResult::ErrorStackOverflow(..) => RuntimeErrorKind::CallDepth,
        EvalAltResult::ErrorDataTooLarge(..) => RuntimeErrorKind::DataTooLarge,
        EvalAltResult::ErrorTooManyVariables(..) => RuntimeErrorKind::TooManyVariables,
        EvalAltResult::ErrorTerminated(token, _) if token.to_string() == TOKEN_DEADLINE => {
            RuntimeErrorKind::Deadline
        }
        EvalAltResult::ErrorTerminated(token, _) if token.to_string() == TOKEN_LIBRARY => {
            RuntimeErrorKind::Internal
        }
        _ => RuntimeErrorKind::Script,
    };
    let message = match kind {
        RuntimeErrorKind::TooManyOperations => {
            "the plan ran too long (operation limit reached; is there an endless loop?)".into()
        }
        RuntimeErrorKind::Deadline => {
            "the plan ran past its time limit (is there an endless loop?)".into()
        }
        RuntimeErrorKind::CallDepth => {
            "functions call each other too deeply (endless recursion?)".into()
        }
        _ => {
            let mut text = inner.to_string();
            let pos = inner.position();
            if !pos.is_none() {
                if let Some(cut) = text.rfind(&format!(" ({pos})")) {
                    text.truncate(cut);
                }
            }
            text
        }
    };
    RuntimeError {
        span,
        function: None,
        kind,
        message,
    }
}
