//! [`Nav2Robot`]: the [`Robot`] trait on Nav2's `navigate_to_pose` action.
//!
//! Every robot call is one `NavigateToPose` goal in the `map` frame:
//! - `move_to`: the goal point, snapped and faced as the simulator would (a shadow
//!   [`SimRobot`] on the IVLMap plans from the robot's pose; Nav2 then drives its own
//!   path there);
//! - `turn`, `turn_absolute`: the same position, the new heading;
//! - `move_forward`: the point that far along the heading, the same heading (Nav2's
//!   costmaps stop it short of obstacles or abort the goal).
//!
//! Feedback poses are appended to the trajectory's path as they arrive. Every wait is
//! bounded ([`Nav2Options`]); a timeout, a cancel request ([`Nav2Robot::cancel_flag`],
//! e.g. from Ctrl-C) or dropping the robot cancels the active goal.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use map_core::robot::{args, MoveReport};
use map_core::{IvlMap, Point, Pose, Robot, RobotError, SimRobot, Stop, StopTarget, Trajectory};
use ros2_client::action::{ActionClient, ActionClientQosPolicies};
use ros2_client::action_msgs::{GoalId, GoalStatusEnum};
use ros2_client::qos::{Durability, History};
use ros2_client::{
    ActionTypeName, Context, ContextOptions, MessageTypeName, Name, Node, NodeName, NodeOptions,
    QosProfile, ServiceMapping, Subscription,
};

use crate::error::Ros2Error;
use crate::frames::{FrameConfig, RosPose2d};
use crate::msgs::{
    Header, NavResult, NavigateToPoseFeedback, NavigateToPoseGoal, NavigateToPoseResultHumble,
    NavigateToPoseResultJazzy, PoseStamped, PoseWithCovarianceStamped, Quaternion, RosDistro,
    TfMessage, Time,
};
use crate::tf::{PoseSource, TfState};
use crate::wait::with_retries;

/// How the driver connects and how long it waits.
#[derive(Debug, Clone)]
pub struct Nav2Options {
    /// `ROS_DOMAIN_ID`, 0..=232.
    pub domain_id: u16,
    /// The distro whose Nav2 message layouts to use.
    pub distro: RosDistro,
    /// IVLMap frame to robot `map` frame, and TF frame names.
    pub frames: FrameConfig,
    /// The action's name.
    pub action: String,
    /// Waiting for the action server to appear.
    pub server_timeout: Duration,
    /// Waiting for a first pose.
    pub pose_timeout: Duration,
    /// Waiting for an answer to a goal or cancel request.
    pub reply_timeout: Duration,
    /// The longest one goal may run before it is canceled.
    pub goal_timeout: Duration,
    /// Our node's name.
    pub node_name: String,
}

impl Default for Nav2Options {
    fn default() -> Self {
        Nav2Options {
            domain_id: 0,
            distro: RosDistro::default(),
            frames: FrameConfig::default(),
            action: "/navigate_to_pose".to_string(),
            server_timeout: Duration::from_secs(10),
            pose_timeout: Duration::from_secs(10),
            reply_timeout: Duration::from_secs(5),
            goal_timeout: Duration::from_secs(600),
            node_name: "ivlmap".to_string(),
        }
    }
}

/// The highest domain id ROS 2 allows on Linux with the default port mapping.
pub const MAX_DOMAIN_ID: u16 = 232;

/// How often the goal loop looks at the middleware.
const POLL: Duration = Duration::from_millis(10);
/// How often the wait for the action server checks the match state again
/// (`wait::with_retries`).
const RECHECK: Duration = Duration::from_millis(250);

enum NavClient {
    Humble(ActionClient<NavigateToPoseGoal, NavigateToPoseResultHumble, NavigateToPoseFeedback>),
    Jazzy(ActionClient<NavigateToPoseGoal, NavigateToPoseResultJazzy, NavigateToPoseFeedback>),
}

/// The subscriptions that give the pose, and what they said.
struct PoseLink {
    tf: Subscription<TfMessage>,
    tf_static: Subscription<TfMessage>,
    amcl: Subscription<PoseWithCovarianceStamped>,
    state: Mutex<TfState>,
}

impl PoseLink {
    /// Take everything that arrived; returns the sample count.
    fn drain(&self) -> u64 {
        let mut st = self
            .state
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        for sub in [&self.tf, &self.tf_static] {
            while let Ok(Some((m, _))) = sub.take() {
                st.add_tf(&m);
            }
        }
        while let Ok(Some((m, _))) = self.amcl.take() {
            st.add_amcl(&m);
        }
        st.samples
    }

    fn current(&self, f: &FrameConfig) -> Option<(RosPose2d, PoseSource)> {
        self.drain();
        let st = self
            .state
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        st.base_in_map(&f.map_frame, &f.odom_frame, &f.base_frame)
    }
}

/// A robot driven through Nav2 over DDS.
pub struct Nav2Robot {
    opts: Nav2Options,
    client: NavClient,
    pose_link: PoseLink,
    // Dropping the node stops its spinner thread; the context outlives both.
    _node: Node,
    _context: Context,
    shadow: Option<SimRobot>,
    pose: Pose,
    trajectory: Trajectory,
    cancel: Arc<AtomicBool>,
    active: Option<GoalId>,
}

impl std::fmt::Debug for Nav2Robot {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Nav2Robot")
            .field("opts", &self.opts)
            .field("pose", &self.pose)
            .field("active", &self.active.is_some())
            .finish_non_exhaustive()
    }
}

fn mw(e: impl std::fmt::Debug) -> Ros2Error {
    Ros2Error::Middleware(format!("{e:?}"))
}

impl Nav2Robot {
    /// Join the DDS domain, wait for the action server and a first pose.
    ///
    /// `map` (the IVLMap the plans are made on) lets goal points be snapped to
    /// reachable free cells and faced along the last leg as the simulator does; without
    /// it goals go to the point asked for, facing the way from the robot to it.
    pub fn connect(opts: Nav2Options, map: Option<Arc<IvlMap>>) -> Result<Self, Ros2Error> {
        if opts.domain_id > MAX_DOMAIN_ID {
            return Err(Ros2Error::BadOption(format!(
                "ROS_DOMAIN_ID {} is out of range (0..={MAX_DOMAIN_ID})",
                opts.domain_id
            )));
        }
        let context =
            Context::with_options(ContextOptions::new().domain_id(opts.domain_id)).map_err(mw)?;
        let node_name = NodeName::new("/", &opts.node_name).map_err(mw)?;
        let mut node = context
            .new_node(node_name, NodeOptions::new().enable_rosout(false))
            .map_err(mw)?;
        let spinner = node.spinner().map_err(mw)?;
        std::thread::Builder::new()
            .name("ros2-spinner".into())
            .spawn(move || {
                if let Err(e) = futures::executor::block_on(spinner.spin()) {
                    tracing::warn!("ROS 2 spinner stopped: {e:?}");
                }
            })
            .map_err(mw)?;

        let action_name = split_name(&opts.action)?;
        let type_name = ActionTypeName::new("nav2_msgs", "NavigateToPose");
        let client = match opts.distro {
            RosDistro::Humble => NavClient::Humble(
                node.create_action_client(
                    ServiceMapping::Enhanced,
                    &action_name,
                    &type_name,
                    action_qos(),
                )
                .map_err(mw)?,
            ),
            RosDistro::Jazzy | RosDistro::Kilted => NavClient::Jazzy(
                node.create_action_client(
                    ServiceMapping::Enhanced,
                    &action_name,
                    &type_name,
                    action_qos(),
                )
                .map_err(mw)?,
            ),
        };
        let pose_link = PoseLink {
            tf: subscribe(&mut node, "tf", "tf2_msgs", "TFMessage", false)?,
            tf_static: subscribe(&mut node, "tf_static", "tf2_msgs", "TFMessage", true)?,
            amcl: subscribe(
                &mut node,
                "amcl_pose",
                "geometry_msgs",
                "PoseWithCovarianceStamped",
                false,
            )?,
            state: Mutex::new(TfState::default()),
        };

        let waited = opts.server_timeout;
        let found = match &client {
            NavClient::Humble(c) => {
                with_retries(|| c.goal_client().wait_for_service(&node), waited, RECHECK)
            }
            NavClient::Jazzy(c) => {
                with_retries(|| c.goal_client().wait_for_service(&node), waited, RECHECK)
            }
        };
        if found.is_none() {
            return Err(Ros2Error::NoActionServer {
                action: opts.action.clone(),
                domain_id: opts.domain_id,
                waited,
            });
        }
        let t0 = Instant::now();
        let first = loop {
            if let Some((p, _)) = pose_link.current(&opts.frames) {
                break p;
            }
            if t0.elapsed() >= opts.pose_timeout {
                return Err(Ros2Error::NoPose {
                    waited: opts.pose_timeout,
                    map: opts.frames.map_frame.clone(),
                    odom: opts.frames.odom_frame.clone(),
                    base: opts.frames.base_frame.clone(),
                });
            }
            std::thread::sleep(POLL);
        };
        let pose = opts.frames.from_robot(first);
        let scene = map.as_ref().map(|m| m.name.clone()).unwrap_or_default();
        let shadow = map.map(|m| SimRobot::with_pose(m, pose));
        Ok(Nav2Robot {
            trajectory: Trajectory::starting_at(&scene, pose),
            opts,
            client,
            pose_link,
            _node: node,
            _context: context,
            shadow,
            pose,
            cancel: Arc::new(AtomicBool::new(false)),
            active: None,
        })
    }

    /// Set this flag (from a Ctrl-C handler, another thread) to cancel the active goal;
    /// the call driving it then returns an error. It is cleared when the next call
    /// starts.
    pub fn cancel_flag(&self) -> Arc<AtomicBool> {
        self.cancel.clone()
    }

    /// The options it was made with.
    pub fn options(&self) -> &Nav2Options {
        &self.opts
    }

    /// Read the pose now (from /tf, else /amcl_pose), keeping the last one if none
    /// arrived.
    pub fn refresh_pose(&mut self) -> Option<PoseSource> {
        let (p, src) = self.pose_link.current(&self.opts.frames)?;
        self.pose = self.opts.frames.from_robot(p);
        self.trajectory.final_pose = self.pose.to_array();
        Some(src)
    }

    /// Send one goal (IVLMap frame) and follow it to its end.
    fn drive(&mut self, target: Pose, words: &str) -> Result<(), Ros2Error> {
        self.cancel.store(false, Ordering::SeqCst);
        let r = self.opts.frames.to_robot(target);
        let goal = NavigateToPoseGoal {
            pose: PoseStamped {
                header: Header {
                    stamp: Time::now(),
                    frame_id: self.opts.frames.map_frame.clone(),
                },
                pose: crate::msgs::Pose {
                    position: crate::msgs::Point {
                        x: r.x,
                        y: r.y,
                        z: 0.0,
                    },
                    orientation: Quaternion::from_yaw(r.yaw),
                },
            },
            behavior_tree: String::new(),
        };
        let outcome = match &self.client {
            NavClient::Humble(c) => follow(
                c,
                goal,
                words,
                &self.opts,
                &self.cancel,
                &self.pose_link,
                &mut self.active,
                &mut self.trajectory,
            ),
            NavClient::Jazzy(c) => follow(
                c,
                goal,
                words,
                &self.opts,
                &self.cancel,
                &self.pose_link,
                &mut self.active,
                &mut self.trajectory,
            ),
        };
        // The pose after the goal: wait briefly for a sample newer than the result.
        let seen = self.pose_link.drain();
        let t0 = Instant::now();
        while self.pose_link.drain() == seen && t0.elapsed() < Duration::from_millis(500) {
            std::thread::sleep(POLL);
        }
        self.refresh_pose();
        self.trajectory.extend_path(&[self.pose.position]);
        outcome
    }

    fn cancel_active(&mut self) {
        if let Some(id) = self.active.take() {
            let sent = match &self.client {
                NavClient::Humble(c) => c.cancel_goal(id).is_ok(),
                NavClient::Jazzy(c) => c.cancel_goal(id).is_ok(),
            };
            tracing::info!("canceling the active Nav2 goal (sent: {sent})");
        }
    }
}

impl Drop for Nav2Robot {
    fn drop(&mut self) {
        self.cancel_active();
    }
}

fn split_name(full: &str) -> Result<Name, Ros2Error> {
    let full = full.trim();
    let (ns, base) = match full.rfind('/') {
        Some(i) => (&full[..i], &full[i + 1..]),
        None => ("", full),
    };
    let ns = if ns.is_empty() { "/" } else { ns };
    Name::new(ns, base).map_err(|e| Ros2Error::BadOption(format!("action name {full:?}: {e:?}")))
}

fn action_qos() -> ActionClientQosPolicies {
    // ROS 2 defaults: services and feedback reliable and volatile; status transient local.
    let service = QosProfile::publisher_default()
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 });
    ActionClientQosPolicies {
        goal_service: service.clone(),
        result_service: service.clone(),
        cancel_service: service.clone(),
        feedback_subscription: service.clone(),
        status_subscription: service.durability(Durability::TransientLocal),
    }
}

fn subscribe<M: ros2_client::Message + 'static>(
    node: &mut Node,
    topic: &str,
    package: &str,
    type_name: &str,
    latched: bool,
) -> Result<Subscription<M>, Ros2Error> {
    // /tf is published reliable or best effort; a best-effort reader takes both.
    // /tf_static is latched (transient local) and reliable.
    let qos = if latched {
        QosProfile::publisher_default()
            .durability(Durability::TransientLocal)
            .history(History::KeepLast { depth: 100 })
    } else {
        QosProfile::subscription_default().history(History::KeepLast { depth: 100 })
    };
    let name = Name::new("/", topic).map_err(mw)?;
    let t = node
        .create_topic(&name, MessageTypeName::new(package, type_name), &qos)
        .map_err(mw)?;
    node.create_subscription(&t, Some(qos)).map_err(mw)
}

/// Send `goal` and follow it to its end: feedback poses go into `trajectory.path`.
#[allow(clippy::too_many_arguments)]
fn follow<R: NavResult>(
    client: &ActionClient<NavigateToPoseGoal, R, NavigateToPoseFeedback>,
    goal: NavigateToPoseGoal,
    words: &str,
    opts: &Nav2Options,
    cancel: &AtomicBool,
    pose_link: &PoseLink,
    active: &mut Option<GoalId>,
    trajectory: &mut Trajectory,
) -> Result<(), Ros2Error> {
    let (req, goal_id) = client.send_goal(goal).map_err(mw)?;
    let t0 = Instant::now();
    let accepted = loop {
        match client.receive_goal_response(req) {
            Ok(Some(r)) => break r.accepted,
            Ok(None) => {}
            Err(e) => return Err(mw(e)),
        }
        if t0.elapsed() >= opts.reply_timeout {
            return Err(Ros2Error::Timeout {
                what: format!("sending the goal {words}"),
                waited: opts.reply_timeout,
            });
        }
        std::thread::sleep(POLL);
    };
    if !accepted {
        return Err(Ros2Error::Rejected {
            goal: words.to_string(),
        });
    }
    *active = Some(goal_id);
    let result_req = client.request_result(goal_id).map_err(mw)?;
    let started = Instant::now();
    let mut cancel_sent: Option<(Instant, bool)> = None;
    loop {
        pose_link.drain();
        while let Ok(Some(fb)) = client.receive_feedback(goal_id) {
            let p = fb.current_pose.pose;
            let ros = RosPose2d {
                x: p.position.x,
                y: p.position.y,
                yaw: p.orientation.yaw(),
            };
            let here = opts.frames.from_robot(ros).position;
            if here.is_finite() {
                trajectory.extend_path(&[here]);
            }
        }
        match client.receive_result(result_req) {
            Ok(Some((status, result))) => {
                *active = None;
                return match status {
                    GoalStatusEnum::Succeeded => Ok(()),
                    GoalStatusEnum::Canceled => Err(Ros2Error::Canceled {
                        goal: words.to_string(),
                        by_us: cancel_sent.is_some(),
                    }),
                    GoalStatusEnum::Aborted => Err(Ros2Error::Aborted {
                        goal: words.to_string(),
                        code: result.error(),
                    }),
                    other => Err(Ros2Error::UnexpectedStatus {
                        goal: words.to_string(),
                        status: format!("{other:?}"),
                    }),
                };
            }
            Ok(None) => {}
            Err(e) => return Err(mw(e)),
        }
        let timed_out = started.elapsed() >= opts.goal_timeout;
        match cancel_sent {
            None if cancel.load(Ordering::SeqCst) || timed_out => {
                let _ = client.cancel_goal(goal_id);
                cancel_sent = Some((Instant::now(), timed_out));
            }
            Some((at, timed_out)) if at.elapsed() >= opts.reply_timeout => {
                // Nav2 did not confirm the cancel with a result: stop waiting.
                *active = None;
                return Err(if timed_out {
                    Ros2Error::Timeout {
                        what: format!("the goal {words} (canceled)"),
                        waited: opts.goal_timeout,
                    }
                } else {
                    Ros2Error::Timeout {
                        what: format!("canceling the goal {words}"),
                        waited: opts.reply_timeout,
                    }
                });
            }
            _ => {}
        }
        std::thread::sleep(POLL);
    }
}

fn describe(p: Pose) -> String {
    format!(
        "to ({:.2}, {:.2}) facing {:.0} deg",
        p.position.x, p.position.y, p.heading
    )
}

impl Robot for Nav2Robot {
    fn pose(&self) -> Pose {
        self.pose
    }

    fn current_pose(&mut self) -> Pose {
        self.refresh_pose();
        self.pose
    }

    fn move_to(
        &mut self,
        goal: Point,
        call: &str,
        target: StopTarget,
    ) -> Result<MoveReport, RobotError> {
        args::goal(goal)?;
        self.refresh_pose();
        // Where the simulator would stop and face, from the robot's real pose.
        let (aim, snapped) = match &mut self.shadow {
            Some(sim) => {
                sim.reset_to(self.pose);
                let rep = sim.move_to(goal, call, target.clone())?;
                (sim.pose(), rep.snapped)
            }
            None => {
                let heading = if self.pose.position.dist(goal) > 1e-6 {
                    self.pose.position.heading_to(goal)
                } else {
                    self.pose.heading
                };
                (Pose::new(goal.x, goal.y, heading), false)
            }
        };
        let before = self.trajectory.length_m;
        let result = self.drive(aim, &describe(aim));
        let reached = self.pose.position;
        result?;
        self.trajectory.stops.push(Stop {
            pose: self.pose.to_array(),
            call: call.to_string(),
            target,
            goal: Some([goal.x, goal.y]),
            snapped,
        });
        Ok(MoveReport {
            reached,
            length_m: self.trajectory.length_m - before,
            snapped,
            warning: None,
        })
    }

    fn turn(&mut self, degrees: f64) -> Result<(), RobotError> {
        args::turn(degrees)?;
        self.refresh_pose();
        let aim = Pose::new(
            self.pose.position.x,
            self.pose.position.y,
            self.pose.heading + degrees,
        );
        Ok(self.drive(aim, &describe(aim))?)
    }

    fn turn_absolute(&mut self, heading: f64) -> Result<(), RobotError> {
        args::heading(heading)?;
        self.refresh_pose();
        let aim = Pose::new(self.pose.position.x, self.pose.position.y, heading);
        Ok(self.drive(aim, &describe(aim))?)
    }

    fn move_forward(&mut self, metres: f64) -> Result<MoveReport, RobotError> {
        args::forward(metres)?;
        self.refresh_pose();
        let start = self.pose;
        let end = start.position.add(start.forward().scale(metres));
        let aim = Pose::new(end.x, end.y, start.heading);
        let before = self.trajectory.length_m;
        self.drive(aim, &describe(aim))?;
        let reached = self.pose.position;
        let short = end.dist(reached);
        let warning = (short > 0.1).then(|| {
            format!(
                "stopped {short:.2} m short of ({:.2}, {:.2}), at ({:.2}, {:.2})",
                end.x, end.y, reached.x, reached.y
            )
        });
        Ok(MoveReport {
            reached,
            length_m: self.trajectory.length_m - before,
            snapped: false,
            warning,
        })
    }

    fn trajectory(&self) -> &Trajectory {
        &self.trajectory
    }

    fn trajectory_mut(&mut self) -> &mut Trajectory {
        &mut self.trajectory
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn action_names_split_into_namespace_and_base() {
        assert!(split_name("/navigate_to_pose").is_ok());
        assert!(split_name("/robot1/navigate_to_pose").is_ok());
        assert!(split_name("navigate_to_pose").is_ok());
        assert!(split_name("/bad name/").is_err());
    }
}
