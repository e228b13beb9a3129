//! `ivlmap run`, `chat` and `serve` with `--robot nav2` against the real ROS 2 stack: an
//! rclpy node (Kilted wheels, Fast DDS; `scripts/ros2-venv.sh`) hosting
//! `navigate_to_pose` with Nav2's own action type and publishing /tf, inside `unshare -n`
//! with a random ROS_DOMAIN_ID. Chat and serve answer from a cassette recorded from the
//! default model (`cassettes/sofa_kitchen.jsonl`, Qwen2.5-Coder-1.5B: `ivlmap chat
//! --record` on "go to the red sofa", ":preview go to the kitchen", "go to the kitchen",
//! then a new chat on "go to the kitchen"; SmolLM2 answers these with a bathtub).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[path = "../../robot_ros2/tests/common/netns.rs"]
mod common;
mod support;

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::{json, Value};

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
    let mut server = start_node(&v, &repo);
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
    same_stops(&s, &n);
    let d = (s.final_pose[0] - n.final_pose[0]).hypot(s.final_pose[1] - n.final_pose[1]);
    assert!(d < 0.03, "{:?} vs {:?}", s.final_pose, n.final_pose);
    assert!(
        n.path.len() > s.path.len(),
        "feedback adds points along the way"
    );
}

/// The robot stopped where the simulator stopped, for the same targets, within 3 cm.
fn same_stops(sim: &map_core::Trajectory, nav: &map_core::Trajectory) {
    assert_eq!(nav.stops.len(), sim.stops.len());
    for (a, b) in sim.stops.iter().zip(&nav.stops) {
        assert_eq!(a.target, b.target);
        let d = (a.pose[0] - b.pose[0]).hypot(a.pose[1] - b.pose[1]);
        assert!(d < 0.03, "{a:?} vs {b:?}");
    }
}

/// The rclpy Nav2 node, its base at the map's start pose.
fn start_node(v: &Path, repo: &Path) -> Child {
    let scene = repo.join("examples/scenes/flat-a.scene.json");
    let map = map_core::IvlMap::from_scene(&map_core::Scene::from_path(&scene).unwrap());
    let st = map.start_pose;
    let yaw = (90.0 - st.heading).to_radians();
    let node = repo.join("robot_ros2/tests/ros2/nav2_node.py");
    Command::new("sh")
        .args([
            "-c",
            &common::in_venv(
                v,
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
        .unwrap()
}

fn cassette() -> String {
    ivlmap_tests::repo()
        .join("cli/tests/cassettes/sofa_kitchen.jsonl")
        .display()
        .to_string()
}

const NAV2: [&str; 6] = [
    "--robot",
    "nav2",
    "--ros-distro",
    "kilted",
    "--ros-wait-s",
    "30",
];

/// `ivlmap chat` answering from the cassette, with `extra` flags.
fn chat(input: &str, extra: &[&str]) -> (Option<i32>, String, String) {
    let cassette = cassette();
    let mut args = vec!["--backend", "replay", "--cassette", &cassette];
    args.extend_from_slice(extra);
    support::chat(input, &args)
}

/// The `(x, y)` of the last chat line starting with `at (`, and that line.
fn last_where(out: &str) -> ([f64; 2], String) {
    let line = out
        .lines()
        .rev()
        .find(|l| l.starts_with("at ("))
        .unwrap_or_else(|| panic!("no :where answer in {out}"))
        .to_string();
    let inner = &line[4..line.find(')').unwrap()];
    let (x, y) = inner.split_once(", ").unwrap();
    ([x.parse().unwrap(), y.parse().unwrap()], line)
}

/// `ivlmap chat --robot nav2`: instructions typed on stdin drive the rclpy node to the
/// simulator's stops; `:preview` leaves it where it is; `:undo` forgets the
/// instruction and the robot stays (the simulator's chat goes back).
#[test]
fn ivlmap_chat_drives_an_rclpy_nav2_server_and_undo_leaves_it_in_place() {
    let v = common::ros2_venv();
    let Some(_domain) =
        common::in_netns("ivlmap_chat_drives_an_rclpy_nav2_server_and_undo_leaves_it_in_place")
    else {
        return;
    };
    let repo = ivlmap_tests::repo();
    let dir = tempfile::tempdir().unwrap();
    let (sim_t, nav_t) = (dir.path().join("sim.json"), dir.path().join("nav.json"));
    let input = |t: &Path| {
        format!(
            "go to the red sofa\n:preview go to the kitchen\n:where\ngo to the kitchen\n\
             :save {}\n:undo\n:where\n:quit\n",
            t.display()
        )
    };
    let (code, sim, err) = chat(&input(&sim_t), &[]);
    assert_eq!(code, Some(0), "{err}");
    let mut server = start_node(&v, &repo);
    let (code, nav, err) = chat(&input(&nav_t), &NAV2);
    let _ = server.kill();
    let _ = server.wait();
    println!("--- sim ---\n{sim}\n--- nav2 ---\n{nav}\n{err}");
    assert_eq!(code, Some(0), "{err}");
    assert!(!nav.contains("error:"), "{nav}");
    let s: map_core::Trajectory =
        serde_json::from_str(&std::fs::read_to_string(&sim_t).unwrap()).unwrap();
    let n: map_core::Trajectory =
        serde_json::from_str(&std::fs::read_to_string(&nav_t).unwrap()).unwrap();
    assert_eq!(s.stops.len(), 2, "sofa, kitchen");
    same_stops(&s, &n);
    // After the preview, both are still at the sofa.
    let sofa = s.stops[0].pose;
    let nav_preview_where = nav
        .split(":preview")
        .nth(1)
        .and_then(|rest| rest.lines().find(|l| l.starts_with("at (")))
        .unwrap();
    assert!(
        nav_preview_where.contains("living room"),
        "{nav_preview_where}"
    );
    // Undo: the simulator goes back to the sofa; the real robot stays in the kitchen.
    assert!(sim.contains("undone; back at"), "{sim}");
    let (p, line) = last_where(&sim);
    assert!((p[0] - sofa[0]).hypot(p[1] - sofa[1]) < 0.01, "{line}");
    assert!(
        nav.contains("undone: the last instruction is forgotten")
            && nav.contains("not driven back"),
        "{nav}"
    );
    let kitchen = n.stops[1].pose;
    let (p, line) = last_where(&nav);
    assert!(
        (p[0] - kitchen[0]).hypot(p[1] - kitchen[1]) < 0.02 && line.contains("in kitchen"),
        "{line}"
    );
}

/// One HTTP/1.1 request with a JSON body (or none): (status, JSON answer).
fn http(addr: &str, method: &str, path: &str, body: Option<&Value>) -> (u16, Value) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(120))).unwrap();
    let body = body.map(Value::to_string).unwrap_or_default();
    write!(
        s,
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    )
    .unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    let status = out
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    let text = out
        .split_once("\r\n\r\n")
        .map(|(_, b)| b)
        .unwrap_or_default();
    (status, serde_json::from_str(text).unwrap_or(Value::Null))
}

fn near(pose: &Value, xy: [f64; 2], tol: f64) -> bool {
    let (x, y) = (pose[0].as_f64().unwrap(), pose[1].as_f64().unwrap());
    (x - xy[0]).hypot(y - xy[1]) < tol
}

/// `ivlmap serve --robot nav2`'s API with two sessions and the rclpy node: the first to
/// run a plan drives the robot; the other previews from the robot's pose and is refused
/// with 409 `robot_busy` until the first is deleted; undo leaves the robot in place.
#[test]
fn ivlmap_serve_lets_one_session_drive_the_rclpy_nav2_robot() {
    let v = common::ros2_venv();
    let Some(_domain) =
        common::in_netns("ivlmap_serve_lets_one_session_drive_the_rclpy_nav2_robot")
    else {
        return;
    };
    let repo = ivlmap_tests::repo();
    let mut node = start_node(&v, &repo);
    let cassette = cassette();
    let mut serve = Command::new(BIN)
        .args(["serve", "--scene", "examples/scenes/flat-a.scene.json"])
        .args(["--addr", "127.0.0.1:0", "--backend", "replay"])
        .args(["--cassette", &cassette])
        .args(NAV2)
        .current_dir(&repo)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(serve.stdout.take().unwrap()).lines();
    let t0 = Instant::now();
    let (mut addr, mut said) = (None, String::new());
    while addr.is_none() && t0.elapsed() < Duration::from_secs(60) {
        let Some(Ok(line)) = lines.next() else { break };
        said.push_str(&line);
        addr = line
            .split_whitespace()
            .find_map(|w| w.strip_prefix("http://"))
            .map(|a| a.trim_end_matches('/').to_string());
    }
    let result = std::panic::catch_unwind(|| {
        let addr = addr.clone().unwrap_or_else(|| panic!("no address: {said}"));
        assert!(said.contains("robot nav2"), "{said}");
        api_with_two_sessions(&addr);
    });
    let _ = serve.kill();
    let _ = serve.wait();
    let _ = node.kill();
    let _ = node.wait();
    if let Err(e) = result {
        std::panic::resume_unwind(e);
    }
}

/// The simulator's stops on flat-a from the start: the red sofa, then the kitchen.
const SOFA: [f64; 2] = [3.875, 1.225];
const KITCHEN: [f64; 2] = [10.9, 2.75];

fn api_with_two_sessions(addr: &str) {
    let t0 = Instant::now();
    let (st, info) = http(addr, "GET", "/api/info", None);
    assert_eq!(st, 200);
    assert_eq!(
        info["robot"],
        json!({"kind": "nav2", "shared": true, "driven": false})
    );
    let (st, a) = http(addr, "POST", "/api/sessions", Some(&json!({})));
    assert_eq!(st, 201, "{a}");
    let (_, b) = http(addr, "POST", "/api/sessions", Some(&json!({})));
    let (a, b) = (a["id"].as_str().unwrap(), b["id"].as_str().unwrap());
    let instr = |id: &str, text: &str, preview: bool| {
        http(
            addr,
            "POST",
            &format!("/api/sessions/{id}/instructions"),
            Some(&json!({"text": text, "preview": preview})),
        )
    };

    // A drives the robot to the red sofa.
    let (st, r) = instr(a, "go to the red sofa", false);
    assert_eq!(st, 200, "{r}");
    assert_eq!(r["outcome"], "done", "{r}");
    assert!(near(&r["pose"], SOFA, 0.03), "{r}");
    assert!(
        r["trajectory"]["path"].as_array().unwrap().len() > 2,
        "feedback"
    );

    // B may preview (from where the robot is now), not drive.
    let (st, r) = instr(b, "go to the kitchen", true);
    assert_eq!(st, 200, "{r}");
    assert_eq!(r["outcome"], "preview");
    assert!(
        near(&r["pose"], SOFA, 0.03),
        "previews start at the robot: {r}"
    );
    assert!(near(&r["trajectory"]["path"][0], SOFA, 0.03), "{r}");
    let (st, r) = instr(b, "go to the kitchen", false);
    assert_eq!(st, 409, "{r}");
    assert_eq!(r["code"], "robot_busy", "{r}");
    let (st, r) = http(addr, "POST", &format!("/api/sessions/{b}/confirm"), None);
    assert_eq!(st, 409, "{r}");
    assert_eq!(
        r["code"], "robot_busy",
        "a previewed plan cannot run either: {r}"
    );
    let (_, sb) = http(addr, "GET", &format!("/api/sessions/{b}"), None);
    assert_eq!(sb["robot"]["driving"], false);
    assert_eq!(sb["robot"]["free"], false);
    assert_eq!(sb["turns"], json!([]), "B unchanged");

    // Undo in A: the conversation forgets, the robot stays at the sofa.
    let (st, u) = http(addr, "POST", &format!("/api/sessions/{a}/undo"), None);
    assert_eq!(st, 200, "{u}");
    assert!(
        u["note"].as_str().unwrap().contains("not driven back"),
        "{u}"
    );
    assert_eq!(u["turns"], json!([]));
    assert!(near(&u["pose"], SOFA, 0.03), "{u}");
    assert_eq!(u["robot"]["driving"], true);

    // A goes; B drives the robot on from the sofa to the kitchen.
    let (st, _) = http(addr, "DELETE", &format!("/api/sessions/{a}"), None);
    assert_eq!(st, 204);
    let (st, r) = instr(b, "go to the kitchen", false);
    assert_eq!(st, 200, "{r}");
    assert_eq!(r["outcome"], "done", "{r}");
    assert!(near(&r["pose"], KITCHEN, 0.03), "{r}");
    assert!(near(&r["trajectory"]["path"][0], SOFA, 0.03), "{r}");
    let (_, sb) = http(addr, "GET", &format!("/api/sessions/{b}"), None);
    assert_eq!(sb["robot"]["driving"], true);
    assert_eq!(sb["trajectory"]["stops"].as_array().unwrap().len(), 1);
    let (_, info) = http(addr, "GET", "/api/info", None);
    assert_eq!(info["robot"]["driven"], true);
    println!(
        "serve API with the rclpy robot: {:.1} s",
        t0.elapsed().as_secs_f64()
    );
}
