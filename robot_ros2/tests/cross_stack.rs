//! Against the real ROS 2 stack (Kilted rclpy with Fast DDS from PyPI wheels,
//! `scripts/ros2-venv.sh`, which also generates nav2_msgs and tf2_msgs with rosidl):
//! our CDR bytes equal rclpy's. (`ivlmap run --robot nav2` against an rclpy
//! `navigate_to_pose` server: cli/tests/ros2_nav2.rs.)
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use std::process::Command;

use byteorder::LittleEndian;
use robot_ros2::msgs::{
    Header, NavigateToPoseGoal, NavigateToPoseResultJazzy, Point, Pose, PoseStamped, Quaternion,
    Time,
};
use ros2_client::action::SendGoalRequest;
use ros2_client::dds::rustdds::cdr_encoding;

fn cdr<T: serde::Serialize>(v: &T) -> String {
    // CDR little endian after the 4-byte encapsulation header rclpy includes.
    let body = cdr_encoding::to_vec::<T, LittleEndian>(v).unwrap();
    let mut all = vec![0u8, 1, 0, 0];
    all.extend(body);
    all.iter().map(|b| format!("{b:02x}")).collect()
}

#[test]
fn our_cdr_equals_rclpys_for_pose_stamped_the_goal_and_the_result() {
    let v = common::ros2_venv();
    let script = ivlmap_tests::repo().join("robot_ros2/tests/ros2/cdr_dump.py");
    let out = Command::new("sh")
        .args([
            "-c",
            &common::in_venv(
                &v,
                &format!("'{}/bin/python' '{}'", v.display(), script.display()),
            ),
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let theirs = |name: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(&format!("{name} ")))
            .unwrap_or_else(|| panic!("{name} missing in {text}"))
            .to_string()
    };
    let ps = PoseStamped {
        header: Header {
            stamp: Time {
                sec: 1_700_000_000,
                nanosec: 123_456_789,
            },
            frame_id: "map".into(),
        },
        pose: Pose {
            position: Point {
                x: 1.5,
                y: -2.25,
                z: 0.0,
            },
            orientation: Quaternion {
                x: 0.0,
                y: 0.0,
                z: 0.6,
                w: 0.8,
            },
        },
    };
    assert_eq!(cdr(&ps), theirs("pose_stamped"));
    let mut id = ros2_client::action_msgs::GoalId::ZERO;
    // A GoalId is a UUID: 16 bytes, 1..=16 as rclpy's request sets them.
    let bytes: Vec<u8> = (1..=16).collect();
    let uuid_hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
    let req = SendGoalRequest {
        goal_id: {
            let s = serde_json::json!({"uuid": bytes});
            id = serde_json::from_value(s).unwrap_or(id);
            id
        },
        goal: NavigateToPoseGoal {
            pose: ps,
            behavior_tree: "bt.xml".into(),
        },
    };
    let ours = cdr(&req);
    assert!(
        ours.contains(&uuid_hex),
        "the goal id went in as 1..=16: {ours}"
    );
    assert_eq!(ours, theirs("send_goal_request"));
    let res = NavigateToPoseResultJazzy {
        error_code: 9002,
        error_msg: "no transform".into(),
    };
    assert_eq!(cdr(&res), theirs("result"));
}
