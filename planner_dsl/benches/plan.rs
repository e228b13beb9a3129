//! Compile + validate + run of a typical 10-line plan on the flat-a scene.
//!
//! `cargo bench -p planner_dsl --bench plan`

#![allow(clippy::panic, clippy::unwrap_used, clippy::expect_used)] // a benchmark aborts on bad setup

use criterion::{criterion_group, criterion_main, Criterion};
use map_core::{IvlMap, Scene, SimRobot};
use planner_dsl::{run, Limits, Plan};
use std::hint::black_box;
use std::sync::Arc;

const PLAN: &str = r#"let chair = agent.get_obj_attributes("chair", 0, "black");
agent.move_west(chair);
let sofa = agent.get_obj_attributes("sofa", 1, "red");
agent.with_object_on_right(sofa);
let table = agent.get_obj_attributes("table", 2, "");
agent.move_to_object(table);
agent.turn(90);
agent.move_forward(0.5);
agent.face("tv");
say(`done: ${table.colour} table`);"#;

/// The same shape without goal-directed moves (no A*): the engine's own cost.
const NO_PATHS: &str = r#"let chair = agent.get_obj_attributes("chair", 0, "black");
let p = agent.get_specified_obj_pos(chair);
let sofa = agent.get_obj_attributes("sofa", 1, "red");
agent.with_object_on_right(sofa);
let table = agent.get_obj_attributes("table", 2, "");
agent.face(table);
agent.turn(90);
agent.turn_absolute(p[0] * 10.0);
agent.face("tv");
say(`done: ${table.colour} table`);"#;

fn bench(c: &mut Criterion) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/scenes/flat-a.scene.json"
    );
    let scene = Scene::from_path(path).unwrap_or_else(|e| panic!("{e}"));
    let map = Arc::new(IvlMap::from_scene(&scene));
    let robot = SimRobot::new(map.clone());
    let limits = Limits::default();

    c.bench_function("compile+validate (10 lines)", |b| {
        b.iter(|| Plan::compile(black_box(PLAN)).map(|p| p.library_calls().len()))
    });
    c.bench_function("compile+validate+run, no path planning (10 lines)", |b| {
        b.iter(|| {
            let plan = Plan::compile(black_box(NO_PATHS)).unwrap_or_else(|e| panic!("{e}"));
            let mut r = robot.fresh();
            let out = run(&plan, &map, &mut r, &limits);
            assert!(out.is_ok());
            out.trace.len()
        })
    });
    c.bench_function("compile+validate+run with 2 A* moves (10 lines)", |b| {
        b.iter(|| {
            let plan = Plan::compile(black_box(PLAN)).unwrap_or_else(|e| panic!("{e}"));
            let mut r = robot.fresh();
            let out = run(&plan, &map, &mut r, &limits);
            assert!(out.is_ok());
            out.trace.len()
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
