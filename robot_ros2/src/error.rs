//! What can go wrong talking to a robot over ROS 2.

use std::time::Duration;

use crate::msgs::nav2_error_name;

/// Why the Nav2 driver could not do something.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Ros2Error {
    /// The DDS middleware refused to start or create an entity.
    #[error("ROS 2 middleware: {0}")]
    Middleware(String),
    /// No action server answered in time.
    #[error("no action server for {action} on ROS_DOMAIN_ID {domain_id} after {:.1} s (is Nav2 running, on this domain and network?)", waited.as_secs_f64())]
    NoActionServer {
        /// The action's name, e.g. "/navigate_to_pose".
        action: String,
        /// The DDS domain.
        domain_id: u16,
        /// How long we waited.
        waited: Duration,
    },
    /// The robot's pose could not be read.
    #[error("no robot pose after {:.1} s: neither /tf ({map} -> {odom} -> {base}) nor /amcl_pose was received", waited.as_secs_f64())]
    NoPose {
        /// How long we waited.
        waited: Duration,
        /// The global frame.
        map: String,
        /// The odometry frame.
        odom: String,
        /// The base frame.
        base: String,
    },
    /// Nav2 did not answer a request in time.
    #[error("{what}: no answer from Nav2 within {:.1} s", waited.as_secs_f64())]
    Timeout {
        /// What we waited for.
        what: String,
        /// How long.
        waited: Duration,
    },
    /// The goal was refused.
    #[error("Nav2 rejected the goal {goal}")]
    Rejected {
        /// The goal, in words.
        goal: String,
    },
    /// The goal was aborted.
    #[error("Nav2 aborted the goal {goal}{}", code.as_ref().map(|(c, m)| format!(": error {c} ({}){}", nav2_error_name(*c), if m.is_empty() { String::new() } else { format!(": {m}") })).unwrap_or_default())]
    Aborted {
        /// The goal, in words.
        goal: String,
        /// Nav2's error code and message (none on Humble).
        code: Option<(u16, String)>,
    },
    /// The goal was canceled, by us (Ctrl-C, a timeout) or by someone else.
    #[error("the goal {goal} was canceled{}", if *by_us { " (stopped here)" } else { " by another node" })]
    Canceled {
        /// The goal, in words.
        goal: String,
        /// Whether this driver asked for it.
        by_us: bool,
    },
    /// A goal ended in a state the action protocol does not end in.
    #[error("the goal {goal} ended with status {status}")]
    UnexpectedStatus {
        /// The goal, in words.
        goal: String,
        /// The status, in words.
        status: String,
    },
    /// The frame config file could not be used.
    #[error("frame config {origin}: {reason}")]
    FrameConfig {
        /// The file.
        origin: String,
        /// What is wrong.
        reason: String,
    },
    /// An option was out of range.
    #[error("{0}")]
    BadOption(String),
}

impl From<Ros2Error> for map_core::RobotError {
    fn from(e: Ros2Error) -> Self {
        map_core::RobotError::Driver(e.to_string())
    }
}
