//! A Nav2 stand-in on real DDS: ros2-client's action server hosting
//! `/navigate_to_pose` (nav2_msgs/action/NavigateToPose), a simulated base that turns
//! toward the goal, drives straight to it and turns to the goal's yaw, feedback each
//! tick, and `/tf` (`map -> odom` fixed and non-trivial, `odom -> base_link` moving).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use robot_ros2::msgs::{
    Header, NavResult, NavigateToPoseFeedback, NavigateToPoseGoal, NavigateToPoseResultHumble,
    NavigateToPoseResultJazzy, Point, PoseWithCovarianceStamped, Quaternion, TfMessage, Time,
    Transform, TransformStamped,
};
use ros2_client::action::{ActionServerQosPolicies, GetResultResponse, SendGoalResponse};
use ros2_client::action_msgs::{
    CancelGoalResponse, CancelGoalResponseEnum, GoalId, GoalInfo, GoalStatusEnum,
};
use ros2_client::qos::{Durability, History};
use ros2_client::{
    ActionTypeName, Context, ContextOptions, MessageTypeName, Name, NodeName, NodeOptions,
    QosProfile, ServiceMapping,
};

/// What the stand-in does with goals.
#[derive(Debug, Clone, PartialEq)]
pub enum Behaviour {
    /// Drive to every goal.
    Drive,
    /// Refuse every goal.
    Reject,
    /// Accept, drive for the duration, then abort with the code and message.
    AbortAfter(Duration, u16, String),
}

/// How the stand-in publishes the pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PoseOut {
    /// `/tf`: map -> odom -> base_link.
    Tf,
    /// `/amcl_pose` only.
    Amcl,
}

/// The stand-in's settings.
#[derive(Debug, Clone)]
pub struct Config {
    pub domain: u16,
    pub behaviour: Behaviour,
    pub pose_out: PoseOut,
    /// Start pose in `map`: x, y, yaw (radians).
    pub start: [f64; 3],
    /// m/s.
    pub speed: f64,
    /// rad/s.
    pub turn_rate: f64,
    /// Humble's result layout instead of Jazzy's.
    pub humble: bool,
}

impl Config {
    pub fn new(domain: u16) -> Self {
        Config {
            domain,
            behaviour: Behaviour::Drive,
            pose_out: PoseOut::Tf,
            start: [1.0, 1.0, 0.0],
            speed: 2.0,
            turn_rate: 6.0,
            humble: false,
        }
    }
}

/// What the stand-in saw, for the tests to check.
#[derive(Debug, Clone, Default)]
pub struct Seen {
    pub goals: Vec<NavigateToPoseGoal>,
    pub canceled: usize,
    /// The base pose in `map`.
    pub pose: [f64; 3],
}

/// A running stand-in; stops when dropped.
pub struct StandIn {
    stop: Arc<AtomicBool>,
    pub seen: Arc<Mutex<Seen>>,
    thread: Option<JoinHandle<()>>,
}

impl Drop for StandIn {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The fixed map -> odom transform the stand-in publishes.
const ODOM: [f64; 3] = [0.5, -0.25, 0.3];

fn compose(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    let (s, c) = a[2].sin_cos();
    [
        a[0] + c * b[0] - s * b[1],
        a[1] + s * b[0] + c * b[1],
        a[2] + b[2],
    ]
}

fn inverse(a: [f64; 3]) -> [f64; 3] {
    let (s, c) = a[2].sin_cos();
    [-(c * a[0] + s * a[1]), s * a[0] - c * a[1], -a[2]]
}

fn wrap(a: f64) -> f64 {
    a.sin().atan2(a.cos())
}

fn transform(parent: &str, child: &str, p: [f64; 3]) -> TransformStamped {
    TransformStamped {
        header: Header {
            stamp: Time::now(),
            frame_id: parent.into(),
        },
        child_frame_id: child.into(),
        transform: Transform {
            translation: Point {
                x: p[0],
                y: p[1],
                z: 0.0,
            },
            rotation: Quaternion::from_yaw(p[2]),
        },
    }
}

/// Start a stand-in on `cfg.domain`.
pub fn start(cfg: Config) -> StandIn {
    let stop = Arc::new(AtomicBool::new(false));
    let seen = Arc::new(Mutex::new(Seen {
        pose: cfg.start,
        ..Seen::default()
    }));
    let (s2, seen2) = (stop.clone(), seen.clone());
    let thread = std::thread::spawn(move || {
        if cfg.humble {
            serve::<NavigateToPoseResultHumble>(cfg, &s2, &seen2, |_, _| {
                NavigateToPoseResultHumble::default()
            });
        } else {
            serve::<NavigateToPoseResultJazzy>(cfg, &s2, &seen2, |code, msg| {
                NavigateToPoseResultJazzy {
                    error_code: code,
                    error_msg: msg.to_string(),
                }
            });
        }
    });
    StandIn {
        stop,
        seen,
        thread: Some(thread),
    }
}

struct Active {
    id: GoalId,
    target: [f64; 3],
    result_req: Option<ros2_client::RmwRequestId>,
    started: Instant,
    ended: Option<(GoalStatusEnum, u16, String)>,
}

fn serve<R: NavResult>(
    cfg: Config,
    stop: &AtomicBool,
    seen: &Mutex<Seen>,
    make_result: impl Fn(u16, &str) -> R,
) {
    let ctx = Context::with_options(ContextOptions::new().domain_id(cfg.domain)).unwrap();
    let mut node = ctx
        .new_node(
            NodeName::new("/", "nav2_standin").unwrap(),
            NodeOptions::new(),
        )
        .unwrap();
    let spinner = node.spinner().unwrap();
    std::thread::spawn(move || futures::executor::block_on(spinner.spin()));
    let service = QosProfile::publisher_default()
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 });
    let qos = ActionServerQosPolicies {
        goal_service: service.clone(),
        result_service: service.clone(),
        cancel_service: service.clone(),
        feedback_publisher: service.clone(),
        status_publisher: service.clone().durability(Durability::TransientLocal),
    };
    let server = node
        .create_action_server::<NavigateToPoseGoal, R, NavigateToPoseFeedback>(
            ServiceMapping::Enhanced,
            &Name::new("/", "navigate_to_pose").unwrap(),
            &ActionTypeName::new("nav2_msgs", "NavigateToPose"),
            qos,
        )
        .unwrap();
    let tf_topic = node
        .create_topic(
            &Name::new("/", "tf").unwrap(),
            MessageTypeName::new("tf2_msgs", "TFMessage"),
            &service,
        )
        .unwrap();
    let tf_pub = node.create_publisher::<TfMessage>(&tf_topic, None).unwrap();
    let amcl_topic = node
        .create_topic(
            &Name::new("/", "amcl_pose").unwrap(),
            MessageTypeName::new("geometry_msgs", "PoseWithCovarianceStamped"),
            &service,
        )
        .unwrap();
    let amcl_pub = node
        .create_publisher::<PoseWithCovarianceStamped>(&amcl_topic, None)
        .unwrap();

    let tick = Duration::from_millis(20);
    let dt = tick.as_secs_f64();
    let mut pose = cfg.start;
    let mut active: Option<Active> = None;
    while !stop.load(Ordering::SeqCst) {
        // New goals: one at a time, a new one preempts (aborts) the old one.
        while let Ok(Some((req, sg))) = server.receive_goal() {
            let accepted = cfg.behaviour != Behaviour::Reject;
            seen.lock().unwrap().goals.push(sg.goal.clone());
            let _ = server.send_goal_response(
                req,
                SendGoalResponse {
                    accepted,
                    stamp: ros2_client::builtin_interfaces::Time::ZERO,
                },
            );
            if accepted {
                let p = &sg.goal.pose.pose;
                active = Some(Active {
                    id: sg.goal_id,
                    target: [p.position.x, p.position.y, p.orientation.yaw()],
                    result_req: None,
                    started: Instant::now(),
                    ended: None,
                });
            }
        }
        while let Ok(Some((req, rr))) = server.receive_result_request() {
            if let Some(a) = active.as_mut().filter(|a| a.id == rr.goal_id) {
                a.result_req = Some(req);
            }
        }
        // (The request's goal id is private in ros2-client: one goal at a time, any cancel
        // request is for it.)
        while let Ok(Some((req, _c))) = server.receive_cancel_request() {
            let mine = active.as_mut();
            let (code, list) = match mine {
                Some(a) if a.ended.is_none() => {
                    a.ended = Some((GoalStatusEnum::Canceled, 0, String::new()));
                    seen.lock().unwrap().canceled += 1;
                    (
                        CancelGoalResponseEnum::None,
                        vec![GoalInfo {
                            goal_id: a.id,
                            stamp: ros2_client::builtin_interfaces::Time::ZERO,
                        }],
                    )
                }
                _ => (CancelGoalResponseEnum::UnknownGoal, vec![]),
            };
            let _ = server.send_cancel_response(
                req,
                CancelGoalResponse {
                    return_code: code,
                    goals_canceling: list,
                },
            );
        }
        if let Some(a) = active.as_mut() {
            if a.ended.is_none() {
                let (dx, dy) = (a.target[0] - pose[0], a.target[1] - pose[1]);
                let dist = dx.hypot(dy);
                let step = cfg.speed * dt;
                let turn_step = cfg.turn_rate * dt;
                let turn_to = |from: f64, to: f64| {
                    let d = wrap(to - from);
                    if d.abs() <= turn_step {
                        to
                    } else {
                        from + turn_step * d.signum()
                    }
                };
                if dist > 1e-3 {
                    let bearing = dy.atan2(dx);
                    // Drive backwards when the goal lies behind and its yaw is ours.
                    let back = wrap(bearing - a.target[2]).abs() > 2.0
                        && wrap(pose[2] - a.target[2]).abs() < 1e-3;
                    let face = if back {
                        wrap(bearing + std::f64::consts::PI)
                    } else {
                        bearing
                    };
                    if wrap(face - pose[2]).abs() > 1e-3 {
                        pose[2] = wrap(turn_to(pose[2], face));
                    } else {
                        let s = step.min(dist);
                        pose[0] += s * dx / dist;
                        pose[1] += s * dy / dist;
                    }
                } else if wrap(a.target[2] - pose[2]).abs() > 1e-3 {
                    pose[2] = wrap(turn_to(pose[2], a.target[2]));
                } else {
                    a.ended = Some((GoalStatusEnum::Succeeded, 0, String::new()));
                }
                if let Behaviour::AbortAfter(after, code, msg) = &cfg.behaviour {
                    if a.started.elapsed() >= *after {
                        a.ended = Some((GoalStatusEnum::Aborted, *code, msg.clone()));
                    }
                }
                let mut fb = NavigateToPoseFeedback::default();
                fb.current_pose.header.frame_id = "map".into();
                fb.current_pose.pose.position = Point {
                    x: pose[0],
                    y: pose[1],
                    z: 0.0,
                };
                fb.current_pose.pose.orientation = Quaternion::from_yaw(pose[2]);
                fb.distance_remaining = dist as f32;
                let _ = server.send_feedback(a.id, fb);
            }
        }
        match cfg.pose_out {
            PoseOut::Tf => {
                let odom_base = compose(inverse(ODOM), pose);
                let _ = tf_pub.publish(TfMessage {
                    transforms: vec![
                        transform("map", "odom", ODOM),
                        transform("odom", "base_link", odom_base),
                    ],
                });
            }
            PoseOut::Amcl => {
                let mut m = PoseWithCovarianceStamped::default();
                m.header.frame_id = "map".into();
                m.pose.pose.position = Point {
                    x: pose[0],
                    y: pose[1],
                    z: 0.0,
                };
                m.pose.pose.orientation = Quaternion::from_yaw(pose[2]);
                let _ = amcl_pub.publish(m);
            }
        }
        seen.lock().unwrap().pose = pose;
        // Answer the result request once the goal ended (after the pose went out).
        if let Some(a) = &active {
            if let (Some((status, code, msg)), Some(req)) = (&a.ended, a.result_req) {
                let _ = server.send_result(
                    req,
                    GetResultResponse {
                        status: *status,
                        result: make_result(*code, msg),
                    },
                );
                active = None;
            }
        }
        std::thread::sleep(tick);
    }
}
