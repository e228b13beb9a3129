//! Agreement checks, deterministic plans and tuple resolution on a real example scene.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use agent::checks::{check_script, library_calls, Arg, FindingKind};
use agent::template::simple_goto_script;
use agent::Tuple;
use map_core::{IvlMap, Scene};

fn flat_a() -> IvlMap {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/scenes/flat-a.scene.json"
    );
    IvlMap::from_scene(&Scene::from_path(path).unwrap())
}

fn kinds(src: &str, tuples: &[Tuple], map: &IvlMap) -> Vec<FindingKind> {
    check_script(src, tuples, Some(map))
        .unwrap()
        .into_iter()
        .map(|f| f.kind)
        .collect()
}

#[test]
fn agreeing_script_has_no_findings() {
    let map = flat_a();
    let tuples = [
        Tuple::new("table", Some(2), Some("yellow")),
        Tuple::new("sofa", None, Some("red")),
    ];
    let src = "let t = agent.get_obj_attributes(\"table\", 2, \"yellow\");\nagent.move_to_object(t);\nlet s = agent.get_obj_attributes(\"sofa\", 0, \"red\");\nagent.move_to_right(s);\n";
    assert_eq!(kinds(src, &tuples, &map), vec![]);
    // Synonyms, plural, "()" for unspecified and default arity are all fine.
    let src = "let s = get_obj_attributes(\"couches\", (), \"red\");\nface(s);\nlet t = get_obj_attributes(\"table\", 2, \"yellow\", \"near_to_far\");\nface(t);";
    assert_eq!(kinds(src, &tuples, &map), vec![]);
}

#[test]
fn each_disagreement_is_found_with_its_position() {
    let map = flat_a();
    let table3 = [Tuple::new("chair", Some(3), Some("red"))];
    // Ordinal counted from 0.
    let f = check_script(
        "let c = agent.get_obj_attributes(\"chair\", 2, \"red\");\nagent.face(c);",
        &table3,
        Some(&map),
    )
    .unwrap();
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(f[0].kind, FindingKind::ZeroBased);
    assert_eq!(
        (f[0].pos.unwrap().line, f[0].pos.unwrap().col > 0),
        (1, true)
    );
    assert!(f[0].message.contains("count from 1"), "{}", f[0].message);
    // Another ordinal.
    assert!(kinds(
        "agent.face(agent.get_obj_attributes(\"chair\", 1, \"red\"));",
        &table3,
        &map
    )
    .contains(&FindingKind::Ordinal));
    // A colour that disagrees.
    assert!(kinds(
        "agent.face(agent.get_obj_attributes(\"chair\", 3, \"black\"));",
        &table3,
        &map
    )
    .contains(&FindingKind::Colour));
    // The order where the colour goes (design.md's observed failure).
    let f = check_script(
        "let c = agent.get_obj_attributes(\"chair\", 3, \"left_to_right\");\nagent.face(c);",
        &[Tuple::new("chair", Some(3), None)],
        Some(&map),
    )
    .unwrap();
    assert_eq!(
        f.iter().map(|f| f.kind.clone()).collect::<Vec<_>>(),
        vec![FindingKind::NotAColour]
    );
    assert!(f[0].message.contains("4th"), "{}", f[0].message);
    // An object the instruction never mentions, and the mentioned one left unused.
    let k = kinds(
        "agent.move_to_object(agent.get_obj_attributes(\"bed\", 0, \"\"));",
        &table3,
        &map,
    );
    assert!(
        k.contains(&FindingKind::NotMentioned) && k.contains(&FindingKind::Unused),
        "{k:?}"
    );
    // A bare name meaning the nearest when the instruction asks for a specific one.
    assert!(
        kinds("agent.move_to_object(\"chair\");", &table3, &map).contains(&FindingKind::Ordinal)
    );
    // The map: an unknown object, an ordinal past the count, a bad order.
    let piano = [Tuple::new("piano", None, None)];
    let f = check_script("agent.move_to_object(\"piano\");", &piano, Some(&map)).unwrap();
    assert_eq!(f[0].kind, FindingKind::Map);
    assert!(f[0].message.contains("has no"), "{}", f[0].message);
    let nine = [Tuple::new("chair", Some(9), None)];
    let f = check_script(
        "agent.face(agent.get_obj_attributes(\"chair\", 9, \"\"));",
        &nine,
        Some(&map),
    )
    .unwrap();
    assert_eq!(f[0].kind, FindingKind::Map);
    assert!(
        f[0].message.contains("there are 8 chairs"),
        "{}",
        f[0].message
    );
    assert!(kinds(
        "agent.face(agent.get_obj_attributes(\"chair\", 3, \"red\", \"sideways\"));",
        &table3,
        &map
    )
    .contains(&FindingKind::BadOrder));
}

#[test]
fn variables_and_computed_arguments_are_trusted() {
    let map = flat_a();
    let t = [Tuple::new("chair", Some(2), None)];
    let src =
        "let k = 1 + 1;\nlet c = agent.get_obj_attributes(\"chair\", k, \"\");\nagent.face(c);";
    assert_eq!(kinds(src, &t, &map), vec![]);
    let calls = library_calls(src).unwrap();
    assert_eq!(calls[0].args[1], Arg::Var("k".into()));
}

#[test]
fn regions_are_names_on_the_map() {
    let map = flat_a();
    let t = [
        Tuple::new("kitchen", None, None),
        Tuple::new("fridge", None, None),
    ];
    let src = "agent.move_to_object(\"kitchen\");\nagent.move_to_object(agent.get_obj_attributes(\"fridge\", 0, \"\"));";
    assert_eq!(kinds(src, &t, &map), vec![]);
    let f = check_script("let k = agent.get_obj_attributes(\"kitchen\", 0, \"\");\nagent.move_to_object(k);\nagent.move_to_object(\"fridge\");", &t, Some(&map)).unwrap();
    assert_eq!(f.len(), 1, "{f:?}");
    assert!(f[0].message.contains("is a region"), "{}", f[0].message);
}

#[test]
fn deterministic_goto_plans_only_when_words_agree() {
    let map = flat_a();
    let t = vec![
        Tuple::new("chair", Some(2), Some("red")),
        Tuple::new("kitchen", None, None),
        Tuple::new("table", Some(-1), None),
    ];
    let s = simple_goto_script(
        "Go to the second red chair, then head into the kitchen and then walk to the last table.",
        &t,
        Some(&map),
    )
    .unwrap();
    assert_eq!(
        s,
        "let target_1 = agent.get_obj_attributes(\"chair\", 2, \"red\");\nagent.move_to_object(target_1);\nagent.move_to_object(\"kitchen\");\nlet target_3 = agent.get_obj_attributes(\"table\", -1, \"\");\nagent.move_to_object(target_3);\n"
    );
    assert!(planner_dsl::Plan::compile(&s).is_ok());
    // A tuple that disagrees with the words (extractor dropped the colour): no template.
    let wrong = vec![Tuple::new("chair", Some(2), None)];
    assert_eq!(
        simple_goto_script("go to the second red chair", &wrong, Some(&map)),
        None
    );
    // A side of the object is its own call.
    let one = vec![Tuple::new("sofa", None, Some("red"))];
    assert_eq!(
        simple_goto_script("go to the left of the red sofa", &one, Some(&map)).unwrap(),
        "let target_1 = agent.get_obj_attributes(\"sofa\", 0, \"red\");\nagent.move_to_left(target_1);\n"
    );
    // A relation the table does not hold is left to the LLM.
    let two = vec![
        Tuple::new("chair", None, None),
        Tuple::new("desk", None, None),
    ];
    assert_eq!(
        simple_goto_script("go to the chair next to the desk", &two, Some(&map)),
        None
    );
    assert!(simple_goto_script("go to the red sofa", &one, Some(&map)).is_some());
    assert_eq!(simple_goto_script("turn left", &[], Some(&map)), None);
}

#[test]
fn deterministic_goto_plans_read_orders_superlatives_and_verbless_clauses() {
    let map = flat_a();
    let t = vec![
        Tuple::new("table", Some(2), Some("yellow")).with_order(Some("west_to_east")),
        Tuple::new("plant", Some(1), None).with_order(Some("east_to_west")),
        Tuple::new("chair", None, Some("red")),
        Tuple::new("kitchen", None, None),
    ];
    let s = simple_goto_script(
        "go to the second yellow table from the west, then the easternmost plant, then the red chair nearest to you, and finally to the kitchen",
        &t,
        Some(&map),
    )
    .unwrap();
    assert_eq!(
        s,
        "let target_1 = agent.get_obj_attributes(\"table\", 2, \"yellow\", \"west_to_east\");\nagent.move_to_object(target_1);\nlet target_2 = agent.get_obj_attributes(\"plant\", 1, \"\", \"east_to_west\");\nagent.move_to_object(target_2);\nlet target_3 = agent.get_obj_attributes(\"chair\", 0, \"red\");\nagent.move_to_object(target_3);\nagent.move_to_object(\"kitchen\");\n"
    );
    // The tuple's order must agree with the words.
    let no_order = vec![Tuple::new("table", Some(2), Some("yellow"))];
    assert_eq!(
        simple_goto_script(
            "go to the second yellow table from the west",
            &no_order,
            Some(&map)
        ),
        None
    );
    // An unknown trailing phrase is left to the LLM.
    let one = vec![Tuple::new("chair", None, None)];
    assert_eq!(
        simple_goto_script("go to the chair from yesterday", &one, Some(&map)),
        None
    );
}

#[test]
fn deterministic_plans_for_sides_between_and_face() {
    let map = flat_a();
    let t = vec![
        Tuple::new("sofa", None, Some("black")),
        Tuple::new("table", None, Some("black")),
        Tuple::new("sofa", None, Some("red")),
        Tuple::new("chair", None, Some("gray")),
        Tuple::new("tv", None, None),
    ];
    let s = simple_goto_script(
        "stop on the left of the black sofa, then go in between the black table and the red sofa, then to the north side of the grey chair and face the tv",
        &t,
        Some(&map),
    )
    .unwrap();
    assert_eq!(
        s,
        "let target_1 = agent.get_obj_attributes(\"sofa\", 0, \"black\");\nagent.move_to_left(target_1);\n\
         let target_2 = agent.get_obj_attributes(\"table\", 0, \"black\");\nlet target_3 = agent.get_obj_attributes(\"sofa\", 0, \"red\");\nagent.move_in_between(target_2, target_3);\n\
         let target_4 = agent.get_obj_attributes(\"chair\", 0, \"gray\");\nagent.move_north(target_4);\n\
         let target_5 = agent.get_obj_attributes(\"tv\", 0, \"\");\nagent.face(target_5);\n"
    );
    assert!(planner_dsl::Plan::compile(&s).is_ok());
    // A side of a room has no single reading: left to the LLM.
    let room = vec![Tuple::new("kitchen", None, None)];
    assert_eq!(
        simple_goto_script("go to the north side of the kitchen", &room, Some(&map)),
        None
    );
    // Fewer tuples than noun phrases: no template.
    assert_eq!(
        simple_goto_script(
            "go between the black table and the red sofa",
            &t[1..2],
            Some(&map)
        ),
        None
    );
}

#[test]
fn picks_nothing_uses_are_reported() {
    let map = flat_a();
    let t = vec![Tuple::new("chair", Some(2), Some("red"))];
    let f = check_script(
        "let chair = agent.get_obj_attributes(\"chair\", 2, \"red\");\nagent.turn(90);",
        &t,
        Some(&map),
    )
    .unwrap();
    assert_eq!(f.len(), 1, "{f:?}");
    assert_eq!(f[0].kind, FindingKind::Unused);
    assert_eq!(f[0].pos.map(|p| p.line), Some(1));
    assert!(f[0].message.contains("`chair` is picked but never used"));
}

#[test]
fn targets_picked_by_position_and_never_used_are_reported() {
    let map = flat_a();
    let t = vec![
        Tuple::new("plant", None, None),
        Tuple::new("kitchen", None, None),
    ];
    let f = check_script(
        "let plant = agent.get_nearest_obj_pos(\"plant\");\nlet kitchen = \"kitchen\";\nagent.turn(90);",
        &t,
        Some(&map),
    )
    .unwrap();
    let unused: Vec<_> = f
        .iter()
        .filter(|f| f.kind == FindingKind::Unused)
        .map(|f| f.pos.map(|p| p.line))
        .collect();
    // A room's name may qualify an object ("the plant in the kitchen"): not reported.
    assert_eq!(unused, vec![Some(1)], "{f:?}");
}

#[test]
fn deterministic_plans_read_it_and_whichever_is_closest() {
    let map = flat_a();
    let t = vec![
        Tuple::new("tv", None, None),
        Tuple::new("plant", None, None),
        Tuple::new("table", None, None),
    ];
    let s = simple_goto_script(
        "head over to the tv and face it, then whichever plant is closest, then the table next to it",
        &t,
        Some(&map),
    )
    .unwrap();
    assert_eq!(
        s,
        "let target_1 = agent.get_obj_attributes(\"tv\", 0, \"\");\nagent.move_to_object(target_1);\nagent.face(target_1);\n\
         let target_2 = agent.get_obj_attributes(\"plant\", 0, \"\");\nagent.move_to_object(target_2);\n\
         let target_3 = agent.get_obj_attributes(\"table\", 0, \"\");\nagent.move_to_object(target_3);\n"
    );
    // "it" before anything was named is not understood.
    assert_eq!(simple_goto_script("face it", &t[..0], Some(&map)), None);
}

#[test]
fn deterministic_plans_pick_an_object_in_a_room() {
    let map = flat_a();
    let t = vec![
        Tuple::new("plant", None, None),
        Tuple::new("office", None, None),
        Tuple::new("chair", Some(2), Some("black")),
        Tuple::new("dining room", None, None),
    ];
    let s = simple_goto_script(
        "go to the plant in the office, then the second black chair in the dining room",
        &t,
        Some(&map),
    )
    .unwrap();
    assert_eq!(
        s,
        "let target_1 = agent.get_obj_in_region(\"plant\", \"office\", 0, \"\");\nagent.move_to_object(target_1);\n\
         let target_3 = agent.get_obj_in_region(\"chair\", \"dining room\", 2, \"black\");\nagent.move_to_object(target_3);\n"
    );
    let f = check_script(&s, &t, Some(&map)).unwrap();
    assert!(f.is_empty(), "{f:?}");
    // Alignment leaves its names alone.
    let (aligned, fixes) = agent::align::align_script(&s, &t, Some(&map));
    assert_eq!((aligned.as_str(), fixes.len()), (s.as_str(), 0));
    // The plan runs and stops at the office's plant (id 30), not the nearer ones.
    let plan = planner_dsl::Plan::compile(&s).unwrap();
    let map = std::sync::Arc::new(map);
    let mut robot = map_core::SimRobot::new(map.clone());
    let out = planner_dsl::run(&plan, &map, &mut robot, &planner_dsl::Limits::default());
    assert!(out.error.is_none(), "{:?}", out.error);
    let stops = &map_core::Robot::trajectory(&robot).stops;
    assert_eq!(stops.len(), 2);
    // A room that is not on the map is not a room: left to the LLM.
    let garage = vec![
        Tuple::new("plant", None, None),
        Tuple::new("garage", None, None),
    ];
    assert_eq!(
        simple_goto_script("go to the plant in the garage", &garage, Some(&map)),
        None
    );
}

#[test]
fn deterministic_goto_plans_read_second_nearest_as_the_default_order() {
    let map = flat_a();
    let t = vec![Tuple::new("chair", Some(2), Some("red"))];
    let s = simple_goto_script("go to the second nearest red chair", &t, Some(&map)).unwrap();
    assert!(
        s.contains("get_obj_attributes(\"chair\", 2, \"red\")"),
        "{s}"
    );
}
