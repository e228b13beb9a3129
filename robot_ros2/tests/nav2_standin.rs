//! Nav2Robot against a Nav2 stand-in on real DDS (ros2-client's action server), each
//! test in a network namespace of its own with only loopback up and a random
//! ROS_DOMAIN_ID (`common::in_netns`).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use std::sync::Arc;
use std::time::{Duration, Instant};

use common::standin::{self, Behaviour, Config, PoseOut};
use map_core::{IvlMap, Point, Robot, Scene, SimRobot, StopTarget};
use robot_ros2::{FrameConfig, Nav2Options, Nav2Robot, RosDistro};

fn opts(domain: u16) -> Nav2Options {
    Nav2Options {
        domain_id: domain,
        server_timeout: Duration::from_secs(20),
        pose_timeout: Duration::from_secs(10),
        ..Nav2Options::default()
    }
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn goal_reached_with_feedback_in_the_trajectory() {
    let Some(domain) = common::in_netns("goal_reached_with_feedback_in_the_trajectory") else {
        return;
    };
    let s = standin::start(Config::new(domain));
    let mut r = Nav2Robot::connect(opts(domain), None).unwrap();
    // The stand-in starts at (1, 1) facing east (yaw 0): compass 90.
    let p = r.pose();
    assert!(
        close(p.position.x, 1.0, 1e-6) && close(p.position.y, 1.0, 1e-6),
        "{p:?}"
    );
    assert!(close(p.heading, 90.0, 1e-6), "{p:?}");
    let rep = r
        .move_to(
            Point::new(3.0, 2.0),
            "move_to",
            StopTarget::Point([3.0, 2.0]),
        )
        .unwrap();
    let p = r.pose();
    assert!(p.position.dist(Point::new(3.0, 2.0)) < 0.01, "{p:?}");
    // Faced the way it drove: from (1, 1) to (3, 2).
    let want = Point::new(1.0, 1.0).heading_to(Point::new(3.0, 2.0));
    assert!(close(p.heading, want, 0.5), "{} vs {want}", p.heading);
    let t = r.trajectory();
    assert_eq!(t.stops.len(), 1);
    assert_eq!(t.stops[0].goal, Some([3.0, 2.0]));
    // Feedback on the way: many points along the segment, about sqrt(5) m long.
    assert!(t.path.len() > 10, "{}", t.path.len());
    assert!(close(t.length_m, 5f64.sqrt(), 0.05), "{}", t.length_m);
    assert!(close(rep.length_m, t.length_m, 1e-9));
    let seen = s.seen.lock().unwrap().clone();
    assert_eq!(seen.goals.len(), 1);
    assert_eq!(seen.goals[0].pose.header.frame_id, "map");
}

#[test]
fn turns_are_clockwise_and_forward_follows_the_heading() {
    let Some(domain) = common::in_netns("turns_are_clockwise_and_forward_follows_the_heading")
    else {
        return;
    };
    let s = standin::start(Config::new(domain));
    let mut r = Nav2Robot::connect(opts(domain), None).unwrap();
    r.turn(90.0).unwrap(); // east -> south
    assert!(
        close(r.pose().heading, 180.0, 0.2) || close(r.pose().heading, -180.0, 0.2),
        "{:?}",
        r.pose()
    );
    // ROS side: yaw -90 deg (clockwise from east).
    let yaw = s.seen.lock().unwrap().pose[2];
    assert!(close(yaw, -std::f64::consts::FRAC_PI_2, 0.01), "{yaw}");
    r.turn_absolute(0.0).unwrap(); // north
    assert!(close(r.pose().heading, 0.0, 0.2), "{:?}", r.pose());
    let rep = r.move_forward(1.5).unwrap();
    let p = r.pose();
    assert!(
        close(p.position.x, 1.0, 0.01) && close(p.position.y, 2.5, 0.01),
        "{p:?}"
    );
    assert!(rep.warning.is_none());
    assert!(close(rep.length_m, 1.5, 0.05), "{}", rep.length_m);
    assert!(r.move_forward(f64::NAN).is_err());
    assert!(r.turn(1e9).is_err());
    // Nothing was sent for the refused calls.
    assert_eq!(s.seen.lock().unwrap().goals.len(), 3);
}

#[test]
fn cancel_mid_move_stops_the_robot_part_way() {
    let Some(domain) = common::in_netns("cancel_mid_move_stops_the_robot_part_way") else {
        return;
    };
    let mut cfg = Config::new(domain);
    cfg.speed = 1.0;
    let s = standin::start(cfg);
    let mut r = Nav2Robot::connect(opts(domain), None).unwrap();
    let flag = r.cancel_flag();
    let canceller = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(1500));
        flag.store(true, std::sync::atomic::Ordering::SeqCst);
    });
    let e = r
        .move_to(
            Point::new(21.0, 1.0),
            "move_to",
            StopTarget::Point([21.0, 1.0]),
        )
        .unwrap_err();
    canceller.join().unwrap();
    assert!(e.to_string().contains("canceled (stopped here)"), "{e}");
    assert_eq!(s.seen.lock().unwrap().canceled, 1);
    let x = r.pose().position.x;
    assert!(x > 1.2 && x < 10.0, "{x}");
    // The robot stays put after the cancel, and no stop was recorded.
    std::thread::sleep(Duration::from_millis(300));
    assert!(close(s.seen.lock().unwrap().pose[0], x, 0.05));
    assert!(r.trajectory().stops.is_empty());
    assert!(r.trajectory().path.len() > 2);
}

#[test]
fn a_rejected_goal_is_an_error() {
    let Some(domain) = common::in_netns("a_rejected_goal_is_an_error") else {
        return;
    };
    let mut cfg = Config::new(domain);
    cfg.behaviour = Behaviour::Reject;
    let _s = standin::start(cfg);
    let mut r = Nav2Robot::connect(opts(domain), None).unwrap();
    let e = r.turn(45.0).unwrap_err();
    assert!(e.to_string().contains("Nav2 rejected the goal"), "{e}");
}

#[test]
fn an_aborted_goal_reports_nav2s_error_code_and_message() {
    let Some(domain) = common::in_netns("an_aborted_goal_reports_nav2s_error_code_and_message")
    else {
        return;
    };
    let mut cfg = Config::new(domain);
    cfg.behaviour = Behaviour::AbortAfter(Duration::from_millis(300), 9002, "no transform".into());
    let _s = standin::start(cfg);
    let mut r = Nav2Robot::connect(opts(domain), None).unwrap();
    let e = r
        .move_to(
            Point::new(9.0, 1.0),
            "move_to",
            StopTarget::Point([9.0, 1.0]),
        )
        .unwrap_err();
    let m = e.to_string();
    assert!(
        m.contains("aborted") && m.contains("9002 (TF_ERROR): no transform"),
        "{m}"
    );
}

#[test]
fn humble_results_abort_without_a_code() {
    let Some(domain) = common::in_netns("humble_results_abort_without_a_code") else {
        return;
    };
    let mut cfg = Config::new(domain);
    cfg.humble = true;
    cfg.behaviour = Behaviour::AbortAfter(Duration::from_millis(200), 9002, String::new());
    let _s = standin::start(cfg);
    let o = Nav2Options {
        distro: RosDistro::Humble,
        ..opts(domain)
    };
    let mut r = Nav2Robot::connect(o, None).unwrap();
    let m = r.move_forward(5.0).unwrap_err().to_string();
    assert!(m.ends_with("facing 90 deg"), "{m}");
}

#[test]
fn the_pose_falls_back_to_amcl_and_goes_through_the_frame_config() {
    let Some(domain) =
        common::in_netns("the_pose_falls_back_to_amcl_and_goes_through_the_frame_config")
    else {
        return;
    };
    let mut cfg = Config::new(domain);
    cfg.pose_out = PoseOut::Amcl;
    cfg.start = [10.0, 5.0, std::f64::consts::FRAC_PI_2];
    let s = standin::start(cfg);
    // The IVLMap is the robot's map turned 90 deg and shifted to (10, 5).
    let frames =
        FrameConfig::from_json_str(r#"{"translation": [10, 5], "rotation_deg": 90}"#, "test")
            .unwrap();
    let o = Nav2Options {
        frames,
        ..opts(domain)
    };
    let mut r = Nav2Robot::connect(o, None).unwrap();
    let p = r.pose();
    assert!(p.position.dist(Point::new(0.0, 0.0)) < 1e-6, "{p:?}");
    // Map yaw 90 deg is IVLMap yaw 0: facing IVLMap east, compass 90.
    assert!(close(p.heading, 90.0, 1e-6), "{p:?}");
    r.move_forward(1.0).unwrap();
    let p = r.pose();
    assert!(p.position.dist(Point::new(1.0, 0.0)) < 0.01, "{p:?}");
    // In the robot's map: one metre north of (10, 5).
    let m = s.seen.lock().unwrap().pose;
    assert!(close(m[0], 10.0, 0.01) && close(m[1], 6.0, 0.01), "{m:?}");
}

#[test]
fn no_action_server_is_a_timeout_error() {
    let Some(domain) = common::in_netns("no_action_server_is_a_timeout_error") else {
        return;
    };
    let o = Nav2Options {
        server_timeout: Duration::from_secs(2),
        ..opts(domain)
    };
    let t0 = Instant::now();
    let e = Nav2Robot::connect(o, None).unwrap_err();
    let waited = t0.elapsed();
    assert!(
        e.to_string()
            .contains("no action server for /navigate_to_pose"),
        "{e}"
    );
    assert!(
        waited >= Duration::from_secs(2) && waited < Duration::from_secs(10),
        "{waited:?}"
    );
}

/// A plan run on Nav2 stops where the simulator stops (the driver aims its goals as
/// the simulator would; the stand-in drives straight there). Headings within 5 deg:
/// the shadow simulator plans from the pose read back from /tf, and the last leg of
/// its smoothed path can differ by a degree or two (measured 1.6).
#[test]
fn a_plan_stops_where_the_simulator_stops() {
    let Some(domain) = common::in_netns("a_plan_stops_where_the_simulator_stops") else {
        return;
    };
    let scene =
        Scene::from_path(ivlmap_tests::repo().join("examples/scenes/flat-a.scene.json")).unwrap();
    let map = Arc::new(IvlMap::from_scene(&scene));
    let start = map.start_pose;
    let yaw = robot_ros2::frames::heading_to_yaw(start.heading);
    let mut cfg = Config::new(domain);
    cfg.start = [start.position.x, start.position.y, yaw];
    cfg.speed = 4.0;
    let _s = standin::start(cfg);
    let script =
        "move_to_object(\"sofa\");\nturn(90);\nmove_forward(0.5);\nmove_to_object(\"fridge\");\n";
    let plan = planner_dsl::Plan::compile(script).unwrap();
    let limits = planner_dsl::Limits::default();
    let mut sim = SimRobot::new(map.clone());
    let so = planner_dsl::run(&plan, &map, &mut sim, &limits);
    assert!(so.error.is_none(), "{:?}", so.error);
    let mut nav = Nav2Robot::connect(opts(domain), Some(map.clone())).unwrap();
    let no = planner_dsl::run(&plan, &map, &mut nav, &limits);
    assert!(no.error.is_none(), "{:?}", no.error);
    let (ts, tn) = (sim.trajectory(), nav.trajectory());
    assert_eq!(ts.stops.len(), 2);
    assert_eq!(tn.stops.len(), ts.stops.len());
    for (a, b) in ts.stops.iter().zip(&tn.stops) {
        assert_eq!(a.target, b.target);
        assert!(
            close(a.pose[0], b.pose[0], 0.02) && close(a.pose[1], b.pose[1], 0.02),
            "{a:?} vs {b:?}"
        );
        assert!(
            map_core::geometry::normalise_heading(a.pose[2] - b.pose[2]).abs() < 5.0,
            "{a:?} vs {b:?}"
        );
    }
    for i in 0..2 {
        assert!(
            close(ts.final_pose[i], tn.final_pose[i], 0.02),
            "{:?} vs {:?}",
            ts.final_pose,
            tn.final_pose
        );
    }
}
