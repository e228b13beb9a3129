//! The VLMaps behaviour, as the paper's comparison runs it: VLMaps has no instance
//! layer, so for each object the instruction mentions it goes to the NEAREST instance
//! of that category (or into the named region); ordinals, colours and orders are
//! ignored. The plan is written as a Rhai script so it runs, and is recorded, like
//! any other.

use agent::Tuple;

/// The VLMaps plan for the extracted tuples: `move_to_object("<name>")` for each, in
/// order of mention (a bare name means the nearest instance, or the region so named).
#[must_use]
pub fn vlmap_script(tuples: &[Tuple]) -> String {
    let mut s = String::from("// VLMaps baseline: nearest instance of each category, in order\n");
    for t in tuples {
        // A JSON string literal is a valid Rhai string literal (same escapes).
        let name = serde_json::to_string(&t.object).unwrap_or_else(|_| "\"\"".into());
        s.push_str(&format!("agent.move_to_object({name});\n"));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    use map_core::{IvlMap, Robot, Scene, SimRobot, StopTarget};
    use planner_dsl::{run, Limits, Plan};

    #[test]
    fn goes_to_the_nearest_ignoring_ordinal_and_colour() {
        let scene = Scene::from_json_str(
            r#"{"format": "ivlmap-scene/1", "name": "b", "bounds": [0, 0, 10, 4],
            "regions": [{"name": "kitchen", "polygon": [[6,0],[10,0],[10,4],[6,4]]}],
            "objects": [{"id": 1, "category": "table", "colour": "red", "center": [2, 2], "size": [0.8, 0.8]},
                        {"id": 2, "category": "table", "colour": "yellow", "center": [5, 2], "size": [0.8, 0.8]}],
            "robot": {"pose": [0.5, 0.5, 0], "radius": 0.2}}"#,
            "b.scene.json",
        )
        .unwrap();
        let map = Arc::new(IvlMap::from_scene(&scene));
        let tuples = vec![
            Tuple::new("table", Some(2), Some("yellow")),
            Tuple::new("kitchen", None, None),
            Tuple::new("weird \"name\"", None, None),
        ];
        let src = vlmap_script(&tuples);
        let plan = Plan::compile(&src).unwrap();
        let mut robot = SimRobot::new(map.clone());
        let out = run(&plan, &map, &mut robot, &Limits::default());
        // The yellow (2nd) table is ignored: the red one is nearest.
        let stops = &robot.trajectory().stops;
        assert_eq!(stops[0].target, StopTarget::Instance(1));
        assert_eq!(stops[1].target, StopTarget::Region("kitchen".into()));
        // The odd name is quoted safely and fails as an unknown object, not a syntax error.
        let e = out.error.unwrap().to_string();
        assert!(e.contains("weird"), "{e}");
    }
}
