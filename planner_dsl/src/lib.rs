//! # planner_dsl: the sandboxed plan language
//!
//! The LLM writes a plan in [Rhai](https://rhai.rs); this crate makes sure that
//! whatever it writes can only call the robot function library (the IVLMap paper's
//! Appendix A functions plus `say`), cannot hang or exhaust memory, and fails with
//! an error a person or the repair loop can act on.
//!
//! - [`Plan::compile`] parses the script in a sandboxed engine
//!   (`Engine::new_raw()` plus arithmetic, logic, strings, arrays, maps, maths and
//!   the library; `eval`, `Fn`, `call`, `curry`, `import`, `print` disabled) and
//!   walks the AST: every call must be a library function with the right number of
//!   arguments, an allowed builtin or a function the script defines. All
//!   violations are reported at once, each with line and column. A rejected script
//!   never runs, so it never moves the robot.
//! - [`run`] executes a plan against an [`map_core::IvlMap`] and any
//!   [`map_core::Robot`] under [`Limits`] (operations, call depth, expression depth,
//!   string/array/map sizes, variables, functions, library calls, wall-clock
//!   deadline); [`dry_run`] does the same on a copy of a [`map_core::SimRobot`] and
//!   returns the preview trajectory.
//! - Every library call lands in the [`TraceEntry`] trace with its arguments,
//!   result, pose after and duration. A runtime error stops the plan where it is
//!   and reports line, column, the function and the map's own message.
//! - [`registry()`] describes every function (parameters, doc, example); prompts
//!   ([`function_list_for_prompt`]), docs ([`registry_markdown`]), the validator and
//!   the argument checks are all generated from it.
//!
//! Scripts call library functions as `agent.f(...)` (the paper's form) or `f(...)`.
//! Object arguments take an object record from `get_obj_attributes` (fields `name`,
//! `colour`, `label_id`, `id`, `position`, `count`) or a bare name meaning the
//! nearest of that name; positions are `[x, y]` arrays in metres.
//!
//! ```
//! use std::sync::Arc;
//! use map_core::{IvlMap, Robot, Scene, SimRobot};
//! use planner_dsl::{dry_run, run, Limits, Plan};
//!
//! let scene = Scene::from_json_str(r#"{
//!   "format": "ivlmap-scene/1", "name": "doc", "bounds": [0, 0, 8, 6],
//!   "objects": [
//!     {"id": 1, "category": "table", "colour": "yellow", "center": [2, 4], "size": [1, 1]},
//!     {"id": 2, "category": "table", "colour": "yellow", "center": [6, 4], "size": [1, 1]},
//!     {"id": 3, "category": "sofa", "colour": "red", "center": [4, 1.5], "size": [2, 0.9]}],
//!   "robot": {"pose": [1, 1, 0], "radius": 0.2}}"#, "doc.scene.json").unwrap();
//! let map = Arc::new(IvlMap::from_scene(&scene));
//! let mut robot = SimRobot::new(map.clone());
//!
//! let plan = Plan::compile(r#"
//!     let table = agent.get_obj_attributes("table", 2, "yellow");
//!     agent.move_to_object(table);
//!     say(`reached the ${table.colour} table #${table.label_id}`);
//! "#).unwrap();
//!
//! // Preview first: the real robot stays where it is.
//! let preview = dry_run(&plan, &map, &robot, &Limits::default());
//! assert!(preview.outcome.is_ok());
//! assert_eq!(preview.trajectory.stops.len(), 1);
//! assert_eq!(robot.trajectory().stops.len(), 0);
//!
//! let outcome = run(&plan, &map, &mut robot, &Limits::default());
//! assert!(outcome.is_ok(), "{:?}", outcome.error);
//! assert_eq!(outcome.trace.len(), 3); // get_obj_attributes, move_to_object, say
//! # let _ = outcome;
//!
//! // A bad plan fails before running, with every problem and its position.
//! let err = Plan::compile("agent.fly(2);\nlet x = eval(\"1\");").unwrap_err();
//! println!("{err}");
//! ```

#![warn(missing_docs)]

mod engine;
mod error;
mod exec;
mod grammar;
mod library;
mod limits;
mod plan;
mod registry;
mod trace;
pub mod typed;
mod validate;
mod value;

pub use crate::error::{PlanError, RuntimeError, RuntimeErrorKind, Span, Violation, ViolationKind};
pub use crate::exec::{dry_run, run};
pub use crate::grammar::script_grammar;
pub use crate::limits::Limits;
pub use crate::plan::Plan;
pub use crate::registry::{
    function_list_for_prompt, lookup, registry, registry_markdown, FunctionSpec, ParamSpec,
    ParamType, BUILTIN_ALLOW_LIST, FORBIDDEN, SELECTION_KEYS,
};
pub use crate::trace::{DryRun, RunOutcome, TraceEntry};
pub use crate::validate::CallSite;
pub use crate::value::ObjectRecord;
