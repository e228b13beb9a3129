//! Fuzz target: the typed plan's parse/print round trip, and compile + validate + dry
//! run of arbitrary text as a plan, on the
//! flat-a example scene. Any panic, any run past libFuzzer's -timeout, or memory past
//! -rss_limit_mb is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;
use map_core::{IvlMap, Robot, Scene, SimRobot};
use planner_dsl::{dry_run, Limits, Plan, PlanError};
use std::sync::{Arc, OnceLock};
use std::time::Duration;

fn world() -> &'static (Arc<IvlMap>, SimRobot) {
    static WORLD: OnceLock<(Arc<IvlMap>, SimRobot)> = OnceLock::new();
    WORLD.get_or_init(|| {
        let text = include_str!("../../examples/scenes/flat-a.scene.json");
        let scene = Scene::from_json_str(text, "flat-a.scene.json").expect("scene");
        let map = Arc::new(IvlMap::from_scene(&scene));
        let robot = SimRobot::new(map.clone());
        (map, robot)
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(source) = std::str::from_utf8(data) else {
        return;
    };
    let limits = Limits {
        max_operations: 50_000,
        max_library_calls: 200,
        deadline: Duration::from_millis(300),
        ..Limits::default()
    };
    // The typed plan never panics, and what it reads prints back to the same plan.
    if let Ok(typed) = planner_dsl::typed::TypedPlan::parse(source) {
        let printed = typed.to_rhai();
        assert_eq!(
            planner_dsl::typed::TypedPlan::parse(&printed).as_ref(),
            Ok(&typed),
            "{printed}"
        );
    }
    match Plan::compile_with(source, &limits) {
        Err(PlanError::Syntax { message, .. }) => assert!(!message.is_empty()),
        Err(PlanError::TooLong { bytes, limit }) => assert!(bytes > limit),
        Err(PlanError::Rejected { violations }) => {
            assert!(!violations.is_empty());
            for v in &violations {
                assert!(!v.to_string().is_empty());
            }
        }
        Ok(plan) => {
            let (map, robot) = world();
            let preview = dry_run(&plan, map, robot, &limits);
            let out = &preview.outcome;
            assert!(out.trace.len() <= limits.max_library_calls);
            if let Some(e) = &out.error {
                assert!(!e.message.is_empty());
            }
            // The real robot never moves in a dry run.
            assert!(robot.trajectory().stops.is_empty());
            // Every outcome serialises (the trace is part of the public output).
            assert!(!format!("{out:?}").is_empty());
        }
    }
});
