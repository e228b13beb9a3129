//! The real `ivlmap` binary on the example scenes and missions: map inspect/save/render,
//! `run` of a .rhai mission (trajectory and PNG), a failing mission (non-zero exit,
//! partial trajectory with `error`), and clear errors for bad input.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

mod support;
use support::{ivlmap, text};

#[test]
fn map_inspect_prints_instances_and_regions() {
    let o = ivlmap(&["map", "inspect", "examples/scenes/flat-a.scene.json"]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    // 30 instances, one row each, with label, k/n and colour.
    assert!(out.contains("30 instances"), "{out}");
    let row17 = out
        .lines()
        .find(|l| l.trim_start().starts_with("17 "))
        .expect("row 17");
    assert!(
        row17.contains("table") && row17.contains("yellow") && row17.contains("/4"),
        "{row17}"
    );
    assert!(row17.contains("kitchen"), "{row17}");
    assert!(
        out.contains("regions:") && out.contains("bathroom"),
        "{out}"
    );
}

#[test]
fn map_save_then_inspect_and_render_the_folder() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("office");
    let o = ivlmap(&[
        "map",
        "save",
        "examples/scenes/office-b.scene.json",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o).1);
    let o = ivlmap(&["map", "inspect", dir.to_str().unwrap()]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        out.contains("\"office-b\"") && out.contains("sofa"),
        "{out}"
    );
    let png = d.path().join("office.png");
    let o = ivlmap(&[
        "map",
        "render",
        dir.to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o).1);
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
}

#[test]
fn run_rhai_mission_writes_trajectory_and_png() {
    let d = tempfile::tempdir().unwrap();
    let traj = d.path().join("t.json");
    let png = d.path().join("t.png");
    let o = ivlmap(&[
        "run",
        "examples/missions/flat-a-tour.rhai",
        "--trajectory",
        traj.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
    ]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(
        out.contains("get_obj_attributes") && out.contains("robot says: tour done"),
        "{out}"
    );
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&traj).unwrap()).unwrap();
    assert_eq!(t["scene"], "flat-a");
    assert!(t["error"].is_null());
    assert!(t["script"].as_str().unwrap().contains("move_to_left"));
    let stops = t["stops"].as_array().unwrap();
    assert_eq!(stops.len(), 6, "{t}");
    assert_eq!(stops[0]["target"], serde_json::json!({"instance": 1}));
    assert_eq!(stops[1]["target"], serde_json::json!({"instance": 17}));
    assert_eq!(stops[2]["target"], serde_json::json!({"region": "kitchen"}));
    assert!(t["length_m"].as_f64().unwrap() > 10.0);
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
}

#[test]
fn failing_mission_exits_non_zero_and_keeps_the_partial_trajectory() {
    let d = tempfile::tempdir().unwrap();
    let traj = d.path().join("t.json");
    let o = ivlmap(&[
        "run",
        "examples/missions/house-c-fails.rhai",
        "--trajectory",
        traj.to_str().unwrap(),
    ]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}\n{err}");
    assert!(
        err.contains("house-c-fails.rhai") && err.contains("2 white chairs"),
        "{err}"
    );
    assert!(err.contains("line 7"), "{err}");
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&traj).unwrap()).unwrap();
    let e = t["error"].as_str().expect("error set");
    assert!(e.contains("asked for the 3rd"), "{e}");
    // The two moves before the failure are kept; the kitchen was never reached.
    assert_eq!(t["stops"].as_array().unwrap().len(), 2, "{t}");
}

#[test]
fn rejected_plan_is_reported_with_position_and_nothing_moves() {
    let d = tempfile::tempdir().unwrap();
    let m = d.path().join("bad.rhai");
    std::fs::write(&m, "agent.move_to_object(\"sofa\");\nagent.fly(3);\n").unwrap();
    let traj = d.path().join("t.json");
    let o = ivlmap(&[
        "run",
        m.to_str().unwrap(),
        "--scene",
        "examples/scenes/flat-a.scene.json",
        "--trajectory",
        traj.to_str().unwrap(),
    ]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("fly") && err.contains("line 2"), "{err}");
    let t: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&traj).unwrap()).unwrap();
    assert!(t["stops"].as_array().unwrap().is_empty());
    assert!(t["error"].is_string());
}

#[test]
fn bad_input_gives_one_clear_line_and_exit_2() {
    // Missing scene file.
    let o = ivlmap(&["map", "inspect", "examples/scenes/nope.scene.json"]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(2));
    assert!(err.contains("nope.scene.json"), "{err}");
    // Malformed scene: the scene reader names file and field.
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("bad.scene.json");
    std::fs::write(&s, r#"{"format": "ivlmap-scene/1", "name": "x", "bounds": [0, 0, 5], "robot": {"pose": [1, 1, 0], "radius": 0.2}}"#).unwrap();
    let o = ivlmap(&["map", "inspect", s.to_str().unwrap()]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        err.contains("bad.scene.json") && err.contains("bounds"),
        "{err}"
    );
    // Unknown flag: clap's usage error.
    let o = ivlmap(&["map", "inspect", "--frobnicate", "x"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).1.contains("--frobnicate"));
    // A mission without a scene.
    let m = d.path().join("m.rhai");
    std::fs::write(&m, "agent.turn(90);\n").unwrap();
    let o = ivlmap(&["run", m.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).1.contains("--scene"), "{}", text(&o).1);
}

#[test]
fn help_is_everywhere() {
    for args in [
        vec!["--help"],
        vec!["chat", "--help"],
        vec!["eval", "--help"],
        vec!["map", "render", "--help"],
    ] {
        let o = ivlmap(&args);
        assert!(o.status.success(), "{args:?}");
        assert!(text(&o).0.contains("Usage"), "{args:?}");
    }
}
