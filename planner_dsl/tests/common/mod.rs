//! Shared test helpers: the example scenes of examples/scenes/.
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use map_core::{IvlMap, Scene, SimRobot};
use std::path::PathBuf;
use std::sync::Arc;

pub fn scene_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../examples/scenes")
        .join(format!("{name}.scene.json"))
}

/// The map of an example scene and a simulated robot at its start pose.
pub fn world(name: &str) -> (Arc<IvlMap>, SimRobot) {
    let scene = Scene::from_path(scene_path(name)).expect("example scene loads");
    let map = Arc::new(IvlMap::from_scene(&scene));
    let robot = SimRobot::new(map.clone());
    (map, robot)
}

/// Distance from a point to an instance's footprint.
pub fn dist_to(map: &IvlMap, id: u32, p: [f64; 3]) -> f64 {
    map.instance_by_id(id)
        .expect("instance exists")
        .distance(map_core::Point::new(p[0], p[1]))
}
