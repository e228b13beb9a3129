//! The typed plan: every reference plan of the example suites parses into typed steps,
//! prints back to Rhai that parses to the same steps, and the printed script drives the
//! robot to the same stops as the original. Non-straight-line scripts are refused with
//! their position; printing is proptested for round trips.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use std::path::PathBuf;

use common::world;
use map_core::ObjectOrder;
use planner_dsl::typed::{Object, Side, Step, Target, TypedError, TypedPlan};
use planner_dsl::{run, Limits, Plan, Span};
use proptest::prelude::*;

fn reference_plans() -> Vec<(String, String, String)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/suites");
    let mut out = Vec::new();
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".nav.jsonl"))
        .collect();
    files.sort();
    for f in files {
        for line in std::fs::read_to_string(&f).unwrap().lines() {
            if line.trim().is_empty() {
                continue;
            }
            let v: serde_json::Value = serde_json::from_str(line).unwrap();
            if let Some(r) = v["reference"].as_str() {
                let scene = v["scene"].as_str().unwrap();
                let scene = scene
                    .rsplit('/')
                    .next()
                    .unwrap()
                    .trim_end_matches(".scene.json");
                out.push((
                    v["id"].as_str().unwrap().to_string(),
                    scene.to_string(),
                    r.to_string(),
                ));
            }
        }
    }
    out
}

#[test]
fn every_reference_plan_round_trips_and_runs_the_same() {
    let plans = reference_plans();
    assert!(plans.len() >= 70, "{} reference plans", plans.len());
    for (id, scene, src) in plans {
        let typed = TypedPlan::parse(&src).unwrap_or_else(|e| panic!("{id}: {e}\n{src}"));
        let printed = typed.to_rhai();
        assert_eq!(
            TypedPlan::parse(&printed).unwrap(),
            typed,
            "{id}:\n{printed}"
        );
        let (map, _) = world(&scene);
        let stops = |s: &str| {
            let mut robot = map_core::SimRobot::new(map.clone());
            let out = run(
                &Plan::compile(s).unwrap(),
                &map,
                &mut robot,
                &Limits::default(),
            );
            assert!(out.error.is_none(), "{id}: {:?}\n{s}", out.error);
            use map_core::Robot;
            robot.trajectory().stops.clone()
        };
        let (a, b) = (stops(&src), stops(&printed));
        assert_eq!(a.len(), b.len(), "{id}");
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.target, y.target, "{id}");
            assert!(
                (x.pose[0] - y.pose[0]).abs() < 1e-9 && (x.pose[1] - y.pose[1]).abs() < 1e-9,
                "{id}"
            );
        }
    }
}

#[test]
fn selections_nest_and_print_canonically() {
    let p = TypedPlan::parse(
        "let t = agent.get_obj(\"table\", #{colour: \"red\"});\n\
         agent.move_to_left(get_obj(\"chair\", #{ordinal: 2, near: t, not_colour: \"black\"}));\n\
         move_between_the_two(\"sofa\");\nagent.turn(-90);\nmove_to_start();\nsay(\"done \\\"ok\\\"\");",
    )
    .unwrap();
    assert_eq!(
        p.steps[1],
        Step::Side {
            side: Side::Left,
            object: Object::Pick(Target {
                name: "chair".into(),
                ordinal: 2,
                not_colour: Some("black".into()),
                near: Some(Box::new(Object::Var("t".into()))),
                ..Target::default()
            })
        }
    );
    assert_eq!(p.steps[3], Step::Turn(-90.0));
    assert_eq!(
        p.to_rhai(),
        "let t = agent.get_obj(\"table\", #{colour: \"red\"});\n\
         agent.move_to_left(agent.get_obj(\"chair\", #{ordinal: 2, not_colour: \"black\", near: t}));\n\
         agent.move_between_the_two(\"sofa\");\nagent.turn(-90.0);\nagent.move_to_start();\nsay(\"done \\\"ok\\\"\");\n"
    );
}

#[test]
fn the_other_one_holds_the_object_it_leaves_out() {
    // "now the other red chair", after red chair 9; and within one instruction, a
    // variable bound to the first
    let p = TypedPlan::parse(
        "move_to_object(get_obj(\"chair\", #{colour: \"red\", other_than: get_instance(9)}));\n\
         let c = get_obj(\"sofa\");\nmove_to_object(get_obj(\"sofa\", #{other_than: c}));",
    )
    .unwrap();
    assert_eq!(
        p.steps[0],
        Step::GoTo(Object::Pick(Target {
            name: "chair".into(),
            colour: Some("red".into()),
            other_than: Some(Box::new(Object::Instance(9))),
            ..Target::default()
        }))
    );
    assert_eq!(
        p.to_rhai(),
        "agent.move_to_object(agent.get_obj(\"chair\", #{colour: \"red\", other_than: agent.get_instance(9)}));\n\
         let c = agent.get_obj(\"sofa\");\nagent.move_to_object(agent.get_obj(\"sofa\", #{other_than: c}));\n"
    );
    assert_eq!(TypedPlan::parse(&p.to_rhai()).unwrap(), p);
    // a pick inside it is one of the step's targets, as a `near` anchor is
    let q = TypedPlan::parse(
        "move_to_object(get_obj(\"chair\", #{other_than: get_obj(\"chair\", #{colour: \"red\"})}));",
    )
    .unwrap();
    let names: Vec<(&str, Option<&str>)> = q.steps[0]
        .targets()
        .iter()
        .map(|t| (t.name.as_str(), t.colour.as_deref()))
        .collect();
    assert_eq!(names, [("chair", None), ("chair", Some("red"))]);
}

#[test]
fn comment_lines_are_not_steps_and_keep_positions() {
    // The language layer's answers quote the person's words in a comment above each call.
    let plain = "move_to_object(get_obj(\"sofa\", #{colour: \"red\"}));\nmove_to_start();";
    let commented = "// the red sofa\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));\n\
                     // and \"come back\" here\nmove_to_start();";
    assert_eq!(
        TypedPlan::parse(commented).unwrap(),
        TypedPlan::parse(plain).unwrap()
    );
    assert!(!TypedPlan::parse(commented)
        .unwrap()
        .to_rhai()
        .contains("//"));
    // Positions count the comment lines.
    let e = TypedPlan::parse("// first\nturn(90);\n// the loop\nfor i in 0..3 { turn(90); }")
        .unwrap_err();
    assert!(
        matches!(
            e,
            TypedError::NotStraightLine {
                span: Span { line: 4, col: 1 },
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn what_is_not_straight_line_is_refused_with_its_position() {
    let e = TypedPlan::parse("agent.move_to_object(\"sofa\");\nfor i in 0..3 { turn(90); }")
        .unwrap_err();
    assert!(
        matches!(
            e,
            TypedError::NotStraightLine {
                span: Span { line: 2, .. },
                ..
            }
        ),
        "{e}"
    );
    let e = TypedPlan::parse("move_to_object(x);").unwrap_err();
    assert!(matches!(e, TypedError::UnknownVariable { .. }), "{e}");
    let e = TypedPlan::parse("turn(1 + 2);").unwrap_err();
    assert!(matches!(e, TypedError::Argument { .. }), "{e}");
    let e = TypedPlan::parse("move_to_object(\"sofa\"").unwrap_err();
    assert!(matches!(e, TypedError::Parse { .. }), "{e}");
    let e = TypedPlan::parse("fn f() { 1 }\nsay(\"x\");").unwrap_err();
    assert!(e.to_string().contains("script function"), "{e}");
}

fn arb_target() -> impl Strategy<Value = Target> {
    let s = "[a-z \"\\\\\n\t]{0,8}";
    (
        "[a-z][a-z ]{0,8}",
        -1i64..20,
        proptest::option::of(s),
        proptest::option::of(s),
        0..ObjectOrder::ALL.len(),
        proptest::option::of(s),
        (-3i64..4, proptest::bool::ANY),
    )
        .prop_map(
            |(name, ordinal, colour, not_colour, order, region, (visited, not_visited))| {
                let nonempty = |o: Option<String>| o.filter(|x| !x.trim().is_empty());
                Target {
                    name,
                    ordinal,
                    colour: nonempty(colour),
                    not_colour: nonempty(not_colour),
                    order: ObjectOrder::ALL[order].0,
                    region: nonempty(region),
                    near: None,
                    other_than: None,
                    visited,
                    not_visited,
                }
            },
        )
}

proptest! {
    #[test]
    fn printed_plans_parse_back_to_themselves(
        t in arb_target(),
        near in proptest::option::of(arb_target()),
        other in proptest::option::of(0u32..100),
        angle in -720.0f64..720.0,
        text in "\\PC{0,12}",
    ) {
        let mut t = t;
        t.near = near.map(|n| Box::new(Object::Pick(n)));
        t.other_than = other.map(|id| Box::new(Object::Instance(id)));
        let p = TypedPlan {
            steps: vec![
                Step::Let { var: "x".into(), target: t.clone() },
                Step::GoTo(Object::Var("x".into())),
                Step::Face(Object::Pick(t.clone())),
                Step::BetweenTwo(t),
                Step::Turn(angle),
                Step::Say(text),
            ],
        };
        prop_assert_eq!(TypedPlan::parse(&p.to_rhai()).unwrap(), p);
    }
}

#[test]
fn each_side_function_names_its_side_and_only_the_turns_do_not_move() {
    let all = [
        Side::Left,
        Side::Right,
        Side::North,
        Side::South,
        Side::East,
        Side::West,
        Side::OnLeft,
        Side::OnRight,
    ];
    for side in all {
        assert_eq!(Side::from_function(side.function()), Some(side));
    }
    assert_eq!(Side::from_function("move_to_object"), None);
    for (word, side) in [
        ("left", Side::Left),
        ("right", Side::Right),
        ("north", Side::North),
        ("south", Side::South),
        ("east", Side::East),
        ("west", Side::West),
    ] {
        assert_eq!(Side::toward(word), Some(side), "{word}");
        assert!(side.function().ends_with(word));
    }
    for word in ["object", "on", "to", "Left", "northern", ""] {
        assert_eq!(Side::toward(word), None, "{word}");
    }
    assert_eq!(Side::from_function("move_north "), None);
    let moves: Vec<&str> = all
        .iter()
        .filter(|s| s.is_move())
        .map(|s| s.function())
        .collect();
    assert_eq!(
        moves,
        [
            "move_to_left",
            "move_to_right",
            "move_north",
            "move_south",
            "move_east",
            "move_west"
        ]
    );
}
