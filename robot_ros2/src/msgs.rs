//! ROS 2 message types written with serde, field for field in the order of their
//! `.msg`/`.action` definitions, so that ros2-client's CDR encoding of them is the
//! byte layout rclpy and rclcpp use (checked against rclpy in
//! `tests/cross_stack.rs`).
//!
//! Nav2's `NavigateToPose` differs between distros in its result only:
//!
//! | distro | result |
//! |---|---|
//! | Humble | `std_msgs/Empty result` |
//! | Jazzy (nav2_msgs 1.3.2 on), Kilted | `uint16 error_code`, `string error_msg` |
//!
//! The goal (`geometry_msgs/PoseStamped pose`, `string behavior_tree`) and the feedback
//! are the same in all three. [`RosDistro`] picks the layout at run time.

use serde::{Deserialize, Serialize};

/// The ROS 2 distribution whose Nav2 message layouts to speak.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RosDistro {
    /// Humble Hawksbill (2022): `NavigateToPose` has an empty result.
    Humble,
    /// Jazzy Jalisco (2024), the default.
    #[default]
    Jazzy,
    /// Kilted Kaiju (2025): `NavigateToPose` as in Jazzy.
    Kilted,
}

impl RosDistro {
    /// Every distro, in release order.
    pub const ALL: [RosDistro; 3] = [RosDistro::Humble, RosDistro::Jazzy, RosDistro::Kilted];

    /// The lower-case name, as `ROS_DISTRO` spells it.
    pub fn name(self) -> &'static str {
        match self {
            RosDistro::Humble => "humble",
            RosDistro::Jazzy => "jazzy",
            RosDistro::Kilted => "kilted",
        }
    }

    /// Whether `NavigateToPose`'s result carries an error code and message.
    pub fn result_has_error_code(self) -> bool {
        !matches!(self, RosDistro::Humble)
    }
}

impl std::str::FromStr for RosDistro {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        RosDistro::ALL
            .into_iter()
            .find(|d| d.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| format!("unknown ROS distro {s:?} (humble, jazzy or kilted)"))
    }
}

impl std::fmt::Display for RosDistro {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// `builtin_interfaces/Time`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Time {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds, 0..1e9.
    pub nanosec: u32,
}

/// `builtin_interfaces/Duration` (same layout as Time).
pub type Duration = Time;

impl Time {
    /// The wall clock now (zero before 1970 or after 2038).
    pub fn now() -> Self {
        let d = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        Time {
            sec: i32::try_from(d.as_secs()).unwrap_or(0),
            nanosec: d.subsec_nanos(),
        }
    }
}

/// `std_msgs/Header`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Header {
    /// Time stamp.
    pub stamp: Time,
    /// The frame the data is in.
    pub frame_id: String,
}

/// `geometry_msgs/Point` (and `Vector3`, the same layout).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Point {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// z, metres.
    pub z: f64,
}

/// `geometry_msgs/Vector3`.
pub type Vector3 = Point;

/// `geometry_msgs/Quaternion`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Quaternion::from_yaw(0.0)
    }
}

impl Quaternion {
    /// A rotation about z by `yaw` radians (counter-clockwise seen from above).
    pub fn from_yaw(yaw: f64) -> Self {
        let h = yaw / 2.0;
        Quaternion {
            x: 0.0,
            y: 0.0,
            z: h.sin(),
            w: h.cos(),
        }
    }

    /// The rotation about z, radians in (-pi, pi] (roll and pitch ignored; a zero
    /// quaternion gives 0).
    pub fn yaw(&self) -> f64 {
        let siny = 2.0 * (self.w * self.z + self.x * self.y);
        let cosy = 1.0 - 2.0 * (self.y * self.y + self.z * self.z);
        siny.atan2(cosy)
    }
}

/// `geometry_msgs/Pose`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Pose {
    /// Position.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

/// `geometry_msgs/PoseStamped`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PoseStamped {
    /// Stamp and frame.
    pub header: Header,
    /// The pose.
    pub pose: Pose,
}

/// `geometry_msgs/PoseWithCovariance`. The 36 covariance doubles are a fixed array,
/// which CDR writes without a length: a 6x6 array of arrays is the same bytes.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct PoseWithCovariance {
    /// The pose.
    pub pose: Pose,
    /// Row-major 6x6 covariance.
    pub covariance: [[f64; 6]; 6],
}

/// `geometry_msgs/PoseWithCovarianceStamped` (AMCL's `/amcl_pose`).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PoseWithCovarianceStamped {
    /// Stamp and frame.
    pub header: Header,
    /// Pose and covariance.
    pub pose: PoseWithCovariance,
}

/// `geometry_msgs/Transform`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Transform {
    /// Translation.
    pub translation: Vector3,
    /// Rotation.
    pub rotation: Quaternion,
}

/// `geometry_msgs/TransformStamped`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TransformStamped {
    /// Stamp and parent frame.
    pub header: Header,
    /// The child frame.
    pub child_frame_id: String,
    /// Child pose in the parent frame.
    pub transform: Transform,
}

/// `tf2_msgs/TFMessage` (`/tf`, `/tf_static`).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TfMessage {
    /// The transforms.
    pub transforms: Vec<TransformStamped>,
}

/// `std_msgs/Empty`: C/C++ typesupport gives an empty struct one byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Empty {
    /// Always 0.
    pub structure_needs_at_least_one_member: u8,
}

/// `nav2_msgs/action/NavigateToPose` goal (every distro).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct NavigateToPoseGoal {
    /// Where to go.
    pub pose: PoseStamped,
    /// A behaviour tree file or id; empty for the navigator's default.
    pub behavior_tree: String,
}

/// `NavigateToPose` feedback (every distro).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct NavigateToPoseFeedback {
    /// The robot's pose in the global frame.
    pub current_pose: PoseStamped,
    /// Time since the goal started.
    pub navigation_time: Duration,
    /// Estimate of the time left.
    pub estimated_time_remaining: Duration,
    /// Recovery behaviours run so far.
    pub number_of_recoveries: i16,
    /// Path distance left, metres.
    pub distance_remaining: f32,
}

/// `NavigateToPose` result, Humble.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct NavigateToPoseResultHumble {
    /// Nothing.
    pub result: Empty,
}

/// `NavigateToPose` result, Jazzy and Kilted.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct NavigateToPoseResultJazzy {
    /// 0 none, 9000 unknown, 9001 failed to load the behaviour tree, 9002 TF error,
    /// 9003 timeout (Nav2's constants).
    pub error_code: u16,
    /// Nav2's words for it.
    pub error_msg: String,
}

/// What any distro's result says, for error reports.
pub trait NavResult: ros2_client::Message + Clone + Send + 'static {
    /// Nav2's error code and message (none on Humble).
    fn error(&self) -> Option<(u16, String)>;
}

impl NavResult for NavigateToPoseResultHumble {
    fn error(&self) -> Option<(u16, String)> {
        None
    }
}

impl NavResult for NavigateToPoseResultJazzy {
    fn error(&self) -> Option<(u16, String)> {
        Some((self.error_code, self.error_msg.clone()))
    }
}

/// Nav2's name for an error code of `NavigateToPose`'s result.
pub fn nav2_error_name(code: u16) -> &'static str {
    match code {
        0 => "NONE",
        9000 => "UNKNOWN",
        9001 => "FAILED_TO_LOAD_BEHAVIOR_TREE",
        9002 => "TF_ERROR",
        9003 => "TIMEOUT",
        _ => "unlisted code",
    }
}

impl ros2_client::Message for Time {}
impl ros2_client::Message for PoseStamped {}
impl ros2_client::Message for PoseWithCovarianceStamped {}
impl ros2_client::Message for TfMessage {}
impl ros2_client::Message for NavigateToPoseGoal {}
impl ros2_client::Message for NavigateToPoseFeedback {}
impl ros2_client::Message for NavigateToPoseResultHumble {}
impl ros2_client::Message for NavigateToPoseResultJazzy {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yaw_survives_a_quaternion() {
        for deg in [-179.0_f64, -90.0, -1.0, 0.0, 1.0, 45.0, 90.0, 135.0, 180.0] {
            let y = deg.to_radians();
            let back = Quaternion::from_yaw(y).yaw();
            let d = (back - y).rem_euclid(std::f64::consts::TAU);
            assert!(
                d < 1e-12 || (std::f64::consts::TAU - d) < 1e-12,
                "{deg}: {back}"
            );
        }
    }

    #[test]
    fn distros_parse_by_name_and_humble_alone_lacks_error_codes() {
        for d in RosDistro::ALL {
            assert_eq!(d.name().parse::<RosDistro>(), Ok(d));
            assert_eq!(d.result_has_error_code(), d != RosDistro::Humble);
        }
        assert!("rolling".parse::<RosDistro>().is_err());
        assert_eq!(RosDistro::default(), RosDistro::Jazzy);
    }
}
