//! Running plans: runtime errors stop where they are and keep the trace and
//! trajectory; dry runs never move the real robot; traces serialise.

mod common;

use common::world;
use map_core::Robot;
use planner_dsl::{dry_run, run, Limits, Plan, RunOutcome, RuntimeErrorKind, Span};

#[test]
fn runtime_error_stops_the_plan_and_keeps_what_was_done() {
    let (map, mut robot) = world("flat-a");
    let plan = Plan::compile(
        "agent.move_to_object(\"fridge\");\nlet t = agent.get_obj_attributes(\"table\", 3, \"yellow\");\nagent.move_to_object(t);\nsay(\"never\");",
    )
    .unwrap();
    let out = run(&plan, &map, &mut robot, &Limits::default());
    let e = out.error.clone().expect("ordinal past count");
    assert_eq!(e.span, Span { line: 2, col: 15 });
    assert_eq!(e.kind, RuntimeErrorKind::Map);
    assert_eq!(e.function.as_deref(), Some("get_obj_attributes"));
    assert_eq!(e.message, "there are 2 yellow tables; asked for the 3rd");
    assert_eq!(
        e.to_string(),
        "line 2, column 15: get_obj_attributes: there are 2 yellow tables; asked for the 3rd"
    );
    // The first move happened and is kept; nothing after the error ran.
    assert_eq!(out.trace.len(), 2);
    assert_eq!(out.trace[1].error.as_deref(), Some(e.message.as_str()));
    assert!(out.said.is_empty());
    let traj = robot.trajectory();
    assert_eq!(traj.stops.len(), 1);
    assert_eq!(traj.error.as_deref(), Some(e.to_string().as_str()));
    assert_eq!(traj.script, plan.source());
    assert_eq!(out.final_pose, robot.pose().to_array());
}

#[test]
fn between_one_object_and_itself_names_the_function_for_the_two() {
    let (map, mut robot) = world("flat-a");
    let plan = Plan::compile(
        "let t = agent.get_obj(\"table\", #{colour: \"yellow\"});\nagent.move_in_between(t, t);",
    )
    .unwrap();
    let out = run(&plan, &map, &mut robot, &Limits::default());
    let e = out.error.expect("the same object twice");
    assert_eq!(e.kind, RuntimeErrorKind::Argument);
    assert_eq!(e.span, Span { line: 2, col: 7 });
    assert!(
        e.message.starts_with("argument `object_b` is the same object as `object_a` (yellow table")
            && e.message.ends_with(
                "; to stop between the two tables that match, use move_between_the_two(\"table\", #{colour: \"yellow\"})"
            ),
        "{}",
        e.message
    );
    assert!(robot.trajectory().stops.is_empty());
}

#[test]
fn error_inside_a_script_function_points_at_the_inner_call() {
    let (map, mut robot) = world("flat-a");
    let plan =
        Plan::compile("fn walk(n) {\n    agent.move_forward(n);\n}\nwalk(\"far\");").unwrap();
    let out = run(&plan, &map, &mut robot, &Limits::default());
    let e = out.error.expect("bad argument");
    assert_eq!(e.kind, RuntimeErrorKind::Argument);
    assert_eq!(e.span, Span { line: 2, col: 11 });
    assert_eq!(
        e.message,
        "argument `dist` must be a number (metres), got string \"far\""
    );
}

#[test]
fn script_errors_carry_positions() {
    let (map, mut robot) = world("flat-a");
    let plan = Plan::compile("let a = [1, 2];\nlet b = a[5];").unwrap();
    let out = run(&plan, &map, &mut robot, &Limits::default());
    let e = out.error.expect("index out of bounds");
    assert_eq!(e.kind, RuntimeErrorKind::Script);
    assert_eq!(e.span.line, 2);
    assert!(e.message.contains("out of bounds"), "{}", e.message);
    assert!(
        !e.message.contains("(line"),
        "position is not repeated: {}",
        e.message
    );
}

#[test]
fn dry_run_previews_without_moving_the_real_robot() {
    let (map, robot) = world("flat-a");
    let plan =
        Plan::compile("agent.move_to_object(\"bed\");\nagent.turn(45);\nagent.move_forward(0.5);")
            .unwrap();
    let before = robot.pose();
    let preview = dry_run(&plan, &map, &robot, &Limits::default());
    assert!(preview.outcome.is_ok(), "{:?}", preview.outcome.error);
    assert_eq!(robot.pose(), before);
    assert!(robot.trajectory().stops.is_empty());
    assert_eq!(preview.trajectory.stops.len(), 1);
    assert!(preview.trajectory.length_m > 1.0);
    assert_eq!(preview.trajectory.final_pose, preview.outcome.final_pose);
    // The same plan run for real ends in the same place.
    let mut real = robot.clone();
    let out = run(&plan, &map, &mut real, &Limits::default());
    assert_eq!(out.final_pose, preview.outcome.final_pose);
}

#[test]
fn a_run_lists_the_instances_its_selections_picked() {
    let (map, robot) = world("flat-a");
    // The anchor of `near` is picked, though no stop is made at it.
    let plan = Plan::compile(
        "agent.move_to_object(agent.get_obj(\"chair\", #{near: agent.get_obj(\"sofa\", #{colour: \"red\"})}));\nagent.move_to_object(agent.get_obj(\"fridge\"));\nagent.move_to_object(agent.get_obj(\"fridge\"));",
    )
    .unwrap();
    let preview = dry_run(&plan, &map, &robot, &Limits::default());
    assert!(preview.outcome.is_ok(), "{:?}", preview.outcome.error);
    let picked = preview.outcome.selected();
    let named: Vec<(String, Option<String>)> = picked
        .iter()
        .filter_map(|id| map.instance_by_id(*id))
        .map(|i| (i.label.clone(), i.colour.clone()))
        .collect();
    let labels: Vec<&str> = named.iter().map(|(l, _)| l.as_str()).collect();
    assert_eq!(labels, ["sofa", "chair", "fridge"], "{picked:?}");
    assert_eq!(named[0].1.as_deref(), Some("red"));
    assert_eq!(preview.trajectory.stops.len(), 3);
}

#[test]
fn trace_records_calls_and_round_trips_through_json() {
    let (map, mut robot) = world("flat-a");
    let plan = Plan::compile(
        "let s = get_obj_attributes(\"sofa\", 1, \"red\");\nlet p = get_specified_obj_pos(s);\nmove_to([p[0], p[1] + 1.2]);\nsay(s);",
    )
    .unwrap();
    let out = run(&plan, &map, &mut robot, &Limits::default());
    assert!(out.is_ok(), "{:?}", out.error);
    let t = &out.trace;
    assert_eq!(t.len(), 4);
    assert_eq!(
        t[0].args,
        [serde_json::json!("sofa"), 1.into(), "red".into()]
    );
    assert_eq!(t[0].result["name"], "sofa");
    assert_eq!(t[0].result["id"], 1);
    assert_eq!(t[1].result, serde_json::json!([2.6, 0.75]));
    assert_eq!(t[2].span, Span { line: 3, col: 1 });
    assert!(
        (t[2].pose_after[1] - 1.95).abs() < 0.1,
        "{:?}",
        t[2].pose_after
    );
    assert_eq!(out.said, ["red sofa #2"]);
    let json = serde_json::to_string(&out).unwrap();
    let back: RunOutcome = serde_json::from_str(&json).unwrap();
    assert_eq!(back, out);
}

#[test]
fn object_record_fields_are_readable() {
    let (map, mut robot) = world("office-b");
    let plan = Plan::compile(
        "let t = agent.get_obj_attributes(\"table\", -1, \"yellow\", \"west_to_east\");\nsay(`${t.name} ${t.colour} ${t.colour} ${t.label_id} ${t.id} ${t.count} ${t.position[0]}`);",
    )
    .unwrap();
    let out = run(&plan, &map, &mut robot, &Limits::default());
    assert!(out.is_ok(), "{:?}", out.error);
    // The easternmost yellow table of office-b is table 15 at x = 12.8.
    let inst = map.instance_by_id(15).unwrap();
    assert_eq!(
        out.said[0],
        format!(
            "table yellow yellow {} 15 {} 12.8",
            inst.label_id, inst.num_of_same_class
        )
    );
}

#[test]
fn same_limits_in_debug_and_release() {
    // Limits are explicit values, never Rhai's profile-dependent defaults.
    let l = Limits::default();
    assert_eq!(
        (
            l.max_operations,
            l.max_call_levels,
            l.max_expr_depth,
            l.max_function_expr_depth
        ),
        (200_000, 32, 48, 32)
    );
    let deep = format!(
        "fn f(n) {{ if n > 0 {{ f(n - 1) }} }}\nf({});",
        l.max_call_levels - 2
    );
    let (map, mut robot) = world("flat-a");
    let out = run(&Plan::compile(&deep).unwrap(), &map, &mut robot, &l);
    assert!(
        out.is_ok(),
        "recursion within the limit works: {:?}",
        out.error
    );
}

#[test]
fn plans_and_outcomes_cross_threads() {
    fn send_sync<T: Send + Sync>() {}
    send_sync::<Plan>();
    send_sync::<RunOutcome>();
    send_sync::<planner_dsl::PlanError>();
    send_sync::<Limits>();
    // A plan compiled on one thread runs on another.
    let plan = Plan::compile("agent.turn(90);").unwrap();
    let heading = std::thread::spawn(move || {
        let (map, mut robot) = world("flat-a");
        run(&plan, &map, &mut robot, &Limits::default());
        robot.pose().heading
    })
    .join()
    .unwrap();
    assert!((heading - 90.0).abs() < 1e-9);
}

/// An argument of `ty` that names something flat-a holds, so that most calls succeed
/// (the second object of a call is another one).
fn sample_arg((i, param): (usize, &planner_dsl::ParamSpec)) -> &'static str {
    use planner_dsl::ParamType;
    match param.ty {
        ParamType::Object if i > 0 => "\"sofa\"",
        ParamType::Object => "\"table\"",
        ParamType::Name if param.name.contains("region") => "\"kitchen\"",
        ParamType::Name => "\"table\"",
        ParamType::Ordinal => "1",
        ParamType::Colour => "\"\"",
        ParamType::Order => "\"west_to_east\"",
        ParamType::Position => "[2.0, 2.0]",
        ParamType::Distance => "0.5",
        ParamType::Angle => "30",
        ParamType::Text => "\"hello\"",
        ParamType::Id => "1",
        ParamType::Selection => "#{ordinal: 1, near: \"sofa\"}",
    }
}

/// Every signature the registry declares (each function at each arity, as `f(...)` and
/// as `agent.f(...)`) is callable at run time: it runs, or the map refuses it with a
/// map error; never "function not found" or an argument error for a declared arity.
#[test]
fn every_registered_signature_runs() {
    let (map, _) = world("flat-a");
    let mut checked = 0;
    for spec in planner_dsl::registry() {
        for arity in spec.min_args()..=spec.max_args() {
            let args: Vec<&str> = spec.params[..arity]
                .iter()
                .enumerate()
                .map(sample_arg)
                .collect();
            for prefix in ["", "agent."] {
                let src = format!("{prefix}{}({});", spec.name, args.join(", "));
                let plan = Plan::compile(&src).unwrap_or_else(|e| panic!("{src}: {e}"));
                let mut robot = map_core::SimRobot::new(map.clone());
                let out = run(&plan, &map, &mut robot, &Limits::default());
                if let Some(e) = &out.error {
                    assert_eq!(e.kind, RuntimeErrorKind::Map, "{src}: {e}");
                }
                checked += 1;
            }
        }
    }
    let expected: usize = planner_dsl::registry()
        .iter()
        .map(|f| 2 * (f.max_args() - f.min_args() + 1))
        .sum();
    assert_eq!(checked, expected);
}

/// `get_obj` resolves a selection map through `map_core::select` (the semantics are
/// unit-tested there); here: the map reaches it, and bad maps are argument errors that
/// name the key.
#[test]
fn get_obj_takes_a_selection_map() {
    let (map, _) = world("flat-a");
    let id_of = |src: &str| {
        let plan = Plan::compile(&format!("let o = {src};\nsay(`${{o.id}}`);")).unwrap();
        let mut robot = map_core::SimRobot::new(map.clone());
        let out = run(&plan, &map, &mut robot, &Limits::default());
        match out.error {
            None => Ok(out.said.join("")),
            Some(e) => Err(e),
        }
    };
    // "the biggest table": the 2.0 x 0.9 yellow one
    assert_eq!(
        id_of("get_obj(\"table\", #{order: \"largest_to_smallest\"})").unwrap(),
        "8"
    );
    assert_eq!(
        id_of("get_obj(\"table\", #{not_colour: \"yellow\", ordinal: 1, order: \"west_to_east\"})")
            .unwrap(),
        "19",
        "the westernmost table that isn't yellow: the white one at x = 2.65 (black 3 is at 2.7)"
    );
    // the table next to the black sofa (id 2) is the black table (id 3)
    assert_eq!(
        id_of("agent.get_obj(\"table\", #{near: get_obj(\"sofa\", #{colour: \"black\"})})")
            .unwrap(),
        "3"
    );
    assert_eq!(
        id_of("get_obj(\"table\")").unwrap(),
        id_of("get_obj_attributes(\"table\")").unwrap()
    );
    let e = id_of("get_obj(\"table\", #{colour: \"yellow\", nearest: true})").unwrap_err();
    assert_eq!(e.kind, RuntimeErrorKind::Argument);
    assert!(e.message.contains("unknown key `nearest`"), "{e}");
    let e = id_of("get_obj(\"table\", 3)").unwrap_err();
    assert!(e.message.contains("must be a map"), "{e}");
    let e = id_of("get_obj(\"table\", #{near: \"kitchen\"})").unwrap_err();
    assert!(e.message.contains("use `region`"), "{e}");
    let e = id_of("get_obj(\"table\", #{not_colour: \"yellow\", colour: \"yellow\"})").unwrap_err();
    assert_eq!(e.kind, RuntimeErrorKind::Map);
    // "now the other sofa", after the red sofa (id 1): the black one (id 2)
    assert_eq!(
        id_of("get_obj(\"sofa\", #{other_than: get_instance(1)})").unwrap(),
        "2"
    );
    assert_eq!(
        id_of("get_obj(\"sofa\", #{other_than: get_obj(\"sofa\", #{colour: \"black\"})})").unwrap(),
        "1"
    );
    let e = id_of("get_obj(\"sofa\", #{other_than: get_instance(3)})").unwrap_err();
    assert_eq!(e.kind, RuntimeErrorKind::Map);
    assert!(e.message.contains("is a table, not a sofa"), "{e}");
    let e = id_of("get_obj(\"sofa\", #{other_than: \"kitchen\"})").unwrap_err();
    assert!(e.message.contains("`other_than` must be an object"), "{e}");
}

/// "Between the two yellow tables" needs exactly two; "come back here" returns to where
/// the plan began.
#[test]
fn between_the_two_and_back_to_the_start() {
    let (map, _) = world("flat-a");
    let go = |src: &str| {
        let plan = Plan::compile(src).unwrap();
        let mut robot = map_core::SimRobot::new(map.clone());
        let out = run(&plan, &map, &mut robot, &Limits::default());
        (out, robot)
    };
    let (out, robot) = go("move_between_the_two(\"table\", #{colour: \"yellow\"});");
    assert!(out.error.is_none(), "{:?}", out.error);
    let stop = &robot.trajectory().stops[0];
    assert_eq!(stop.target, map_core::StopTarget::Between([8, 17]));
    let (out, _) = go("move_between_the_two(\"table\");");
    let e = out.error.unwrap();
    assert_eq!(e.kind, RuntimeErrorKind::Map);
    assert!(e.message.contains("not 2"), "{e}");
    let start = map.start_pose.position;
    let (out, robot) = go("agent.move_to_object(\"fridge\");\nagent.move_to_start();");
    assert!(out.error.is_none(), "{:?}", out.error);
    let back = robot.trajectory().stops[1].pose;
    assert!(
        (back[0] - start.x).hypot(back[1] - start.y) < 0.1,
        "{back:?} vs {start:?}"
    );
}

/// "The sofa you visited first", "that same sofa again", "a table you haven't been to":
/// counted over the robot's stops at objects, across plans run on the same robot (a
/// conversation's turns) and in a dry run.
#[test]
fn visited_counts_the_stops_of_earlier_plans_on_the_same_robot() {
    let (map, _) = world("flat-a");
    let mut robot = map_core::SimRobot::new(map.clone());
    let go = |src: &str, robot: &mut map_core::SimRobot| {
        let plan = Plan::compile(src).unwrap();
        run(&plan, &map, robot, &Limits::default())
    };
    let last_stop =
        |robot: &map_core::SimRobot| robot.trajectory().stops.last().unwrap().target.clone();
    // before any visit there is nothing to count
    let out = go(
        "move_to_object(get_obj(\"sofa\", #{visited: 1}));",
        &mut robot,
    );
    let e = out.error.unwrap();
    assert_eq!(e.kind, RuntimeErrorKind::Map);
    assert_eq!(e.message, "no sofa has been visited yet");
    // turn 1: the black sofa (2), then the red one (1)
    let out = go(
        "move_to_object(get_obj(\"sofa\", #{colour: \"black\"}));\nmove_to_object(get_obj(\"sofa\", #{colour: \"red\"}));",
        &mut robot,
    );
    assert!(out.error.is_none(), "{:?}", out.error);
    // turn 2: "the sofa you visited first" is the black one, though the red is nearer
    let out = go(
        "move_to_object(get_obj(\"sofa\", #{visited: 1}));",
        &mut robot,
    );
    assert!(out.error.is_none(), "{:?}", out.error);
    assert_eq!(last_stop(&robot), map_core::StopTarget::Instance(2));
    // "that same sofa again": the latest visit, the black one again
    let out = go(
        "move_to_object(get_obj(\"sofa\", #{visited: -1}));",
        &mut robot,
    );
    assert!(out.error.is_none(), "{:?}", out.error);
    assert_eq!(last_stop(&robot), map_core::StopTarget::Instance(2));
    let out = go(
        "move_to_object(get_obj(\"sofa\", #{visited: -2}));",
        &mut robot,
    );
    assert!(out.error.is_none(), "{:?}", out.error);
    assert_eq!(last_stop(&robot), map_core::StopTarget::Instance(1));
    // a dry run counts the same visits, and its preview holds only its own stops
    let plan = Plan::compile("move_to_object(get_obj(\"sofa\", #{not_visited: true}));").unwrap();
    let preview = dry_run(&plan, &map, &robot, &Limits::default());
    let e = preview.outcome.error.unwrap();
    assert_eq!(e.message, "every sofa here has been visited already");
    let plan = Plan::compile("move_to_object(get_obj(\"sofa\", #{visited: 2}));").unwrap();
    let preview = dry_run(&plan, &map, &robot, &Limits::default());
    assert!(
        preview.outcome.error.is_none(),
        "{:?}",
        preview.outcome.error
    );
    assert_eq!(preview.trajectory.stops.len(), 1);
    assert_eq!(
        preview.trajectory.stops[0].target,
        map_core::StopTarget::Instance(1)
    );
    // one way of counting at a time, and the keys' types are checked
    let out = go("get_obj(\"sofa\", #{visited: 1, ordinal: 2});", &mut robot);
    assert!(out.error.unwrap().message.contains("give one of them"));
    let out = go("get_obj(\"sofa\", #{not_visited: 1});", &mut robot);
    let e = out.error.unwrap();
    assert_eq!(e.kind, RuntimeErrorKind::Argument);
    assert!(
        e.message.contains("`not_visited` must be true or false"),
        "{e}"
    );
}
