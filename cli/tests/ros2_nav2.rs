//! `ivlmap run --robot nav2` against the real ROS 2 stack: an rclpy node (Kilted wheels,
//! Fast DDS; `scripts/ros2-venv.sh`) hosting `navigate_to_pose` with Nav2's own action
//! type and publishing /tf, inside `unshare -n` with a random ROS_DOMAIN_ID.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[path = "../../robot_ros2/tests/common/netns.rs"]
mod common;

use std::process::{Command, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_ivlmap");

/// A mission through the `ivlmap` binary with `--robot nav2` against the rclpy node
/// stops where the simulator stops.
#[test]
fn ivlmap_run_drives_an_rclpy_nav2_server_to_the_simulators_stops() {
    let v = common::ros2_venv();
    let Some(_domain) =
        common::in_netns("ivlmap_run_drives_an_rclpy_nav2_server_to_the_simulators_stops")
    else {
        return;
    };
    let repo = ivlmap_tests::repo();
    let mission = repo.join("examples/missions/flat-a-tour.rhai");
    let scene = repo.join("examples/scenes/flat-a.scene.json");
    let dir = tempfile::tempdir().unwrap();
    let (sim_t, nav_t) = (dir.path().join("sim.json"), dir.path().join("nav.json"));
    let sim = ivlmap_tests::run_binary(
        BIN,
        &[
            "run",
            mission.to_str().unwrap(),
            "--scene",
            scene.to_str().unwrap(),
            "--trajectory",
            sim_t.to_str().unwrap(),
        ],
    );
    assert!(sim.status.success(), "{:?}", ivlmap_tests::text(&sim));
    let s: map_core::Trajectory =
        serde_json::from_str(&std::fs::read_to_string(&sim_t).unwrap()).unwrap();
    let map = map_core::IvlMap::from_scene(&map_core::Scene::from_path(&scene).unwrap());
    let st = map.start_pose;
    let yaw = (90.0 - st.heading).to_radians();
    let node = repo.join("robot_ros2/tests/ros2/nav2_node.py");
    let mut server = Command::new("sh")
        .args([
            "-c",
            &common::in_venv(
                &v,
                &format!(
                    "exec '{}/bin/python' '{}' {} {} {yaw}",
                    v.display(),
                    node.display(),
                    st.position.x,
                    st.position.y
                ),
            ),
        ])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let nav = ivlmap_tests::run_binary(
        BIN,
        &[
            "run",
            mission.to_str().unwrap(),
            "--scene",
            scene.to_str().unwrap(),
            "--trajectory",
            nav_t.to_str().unwrap(),
            "--robot",
            "nav2",
            "--ros-distro",
            "kilted",
            "--ros-wait-s",
            "30",
        ],
    );
    let _ = server.kill();
    let _ = server.wait();
    assert!(nav.status.success(), "{:?}", ivlmap_tests::text(&nav));
    let n: map_core::Trajectory =
        serde_json::from_str(&std::fs::read_to_string(&nav_t).unwrap()).unwrap();
    assert!(!s.stops.is_empty());
    assert_eq!(n.stops.len(), s.stops.len());
    for (a, b) in s.stops.iter().zip(&n.stops) {
        assert_eq!(a.target, b.target);
        let d = (a.pose[0] - b.pose[0]).hypot(a.pose[1] - b.pose[1]);
        assert!(d < 0.03, "{a:?} vs {b:?}");
    }
    let d = (s.final_pose[0] - n.final_pose[0]).hypot(s.final_pose[1] - n.final_pose[1]);
    assert!(d < 0.03, "{:?} vs {:?}", s.final_pose, n.final_pose);
    assert!(
        n.path.len() > s.path.len(),
        "feedback adds points along the way"
    );
}
