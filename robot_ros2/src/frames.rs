//! The IVLMap frame and the robot's `map` frame, and their two heading conventions.
//!
//! IVLMap: metres, x east, y north, headings in compass degrees (0 north, 90 east,
//! clockwise positive). ROS (REP 103): yaw in radians, counter-clockwise from the
//! frame's x axis. In one frame, `yaw = 90 deg - heading`.
//!
//! The two frames are tied by a [`FrameConfig`], a small JSON file:
//!
//! ```json
//! {"format": "ivlmap-frame/1", "translation": [2.0, -1.5], "rotation_deg": 90.0,
//!  "map_frame": "map", "odom_frame": "odom", "base_frame": "base_link"}
//! ```
//!
//! A point `p` of the IVLMap lies at `R(rotation_deg) p + translation` in the robot's
//! `map` frame (`R` rotates counter-clockwise). Every field may be left out: the
//! identity (a map built from the robot's own data in its `map` frame) and Nav2's
//! frame names are the defaults.

use std::path::Path;

use map_core::geometry::normalise_heading;
use map_core::{Point, Pose};
use serde::{Deserialize, Serialize};

use crate::error::Ros2Error;

/// The `format` field of a frame config file.
pub const FRAME_FORMAT: &str = "ivlmap-frame/1";

/// A pose in the robot's `map` frame, ROS conventions.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RosPose2d {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// Yaw, radians, counter-clockwise from x, in (-pi, pi].
    pub yaw: f64,
}

/// How the IVLMap frame sits in the robot's `map` frame, and the TF frame names.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameConfig {
    /// Must be [`FRAME_FORMAT`].
    #[serde(default = "default_format")]
    pub format: String,
    /// Where the IVLMap origin lies in the robot's `map` frame, metres.
    #[serde(default)]
    pub translation: [f64; 2],
    /// How far the IVLMap axes are rotated counter-clockwise in the `map` frame, degrees.
    #[serde(default)]
    pub rotation_deg: f64,
    /// The global frame of goals and poses.
    #[serde(default = "default_map_frame")]
    pub map_frame: String,
    /// The odometry frame (`map -> odom -> base`).
    #[serde(default = "default_odom_frame")]
    pub odom_frame: String,
    /// The robot's base frame.
    #[serde(default = "default_base_frame")]
    pub base_frame: String,
}

fn default_format() -> String {
    FRAME_FORMAT.to_string()
}
fn default_map_frame() -> String {
    "map".to_string()
}
fn default_odom_frame() -> String {
    "odom".to_string()
}
fn default_base_frame() -> String {
    "base_link".to_string()
}

impl Default for FrameConfig {
    fn default() -> Self {
        FrameConfig {
            format: default_format(),
            translation: [0.0, 0.0],
            rotation_deg: 0.0,
            map_frame: default_map_frame(),
            odom_frame: default_odom_frame(),
            base_frame: default_base_frame(),
        }
    }
}

/// A compass heading (degrees) as a ROS yaw (radians, (-pi, pi]) in the same frame.
pub fn heading_to_yaw(heading_deg: f64) -> f64 {
    normalise_heading(90.0 - heading_deg).to_radians()
}

/// A ROS yaw (radians) as a compass heading (degrees, (-180, 180]) in the same frame.
pub fn yaw_to_heading(yaw: f64) -> f64 {
    normalise_heading(90.0 - yaw.to_degrees())
}

impl FrameConfig {
    /// Parse a config file's text; `origin` names it in errors.
    pub fn from_json_str(text: &str, origin: &str) -> Result<Self, Ros2Error> {
        let c: FrameConfig = serde_json::from_str(text).map_err(|e| Ros2Error::FrameConfig {
            origin: origin.to_string(),
            reason: format!("line {} column {}: {e}", e.line(), e.column()),
        })?;
        c.validate(origin)?;
        Ok(c)
    }

    /// Read a config file.
    pub fn load(path: &Path) -> Result<Self, Ros2Error> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| Ros2Error::FrameConfig {
            origin: origin.clone(),
            reason: e.to_string(),
        })?;
        Self::from_json_str(&text, &origin)
    }

    fn validate(&self, origin: &str) -> Result<(), Ros2Error> {
        let bad = |reason: String| {
            Err(Ros2Error::FrameConfig {
                origin: origin.to_string(),
                reason,
            })
        };
        if self.format != FRAME_FORMAT {
            return bad(format!(
                "format is {:?}, expected {FRAME_FORMAT:?}",
                self.format
            ));
        }
        let finite = self.translation.iter().all(|v| v.is_finite());
        if !finite || !self.rotation_deg.is_finite() {
            return bad("translation and rotation_deg must be finite numbers".to_string());
        }
        for (name, f) in [
            ("map_frame", &self.map_frame),
            ("odom_frame", &self.odom_frame),
            ("base_frame", &self.base_frame),
        ] {
            if f.trim().is_empty() {
                return bad(format!("{name} is empty"));
            }
        }
        Ok(())
    }

    fn rotate(&self, p: Point, sign: f64) -> Point {
        let (s, c) = (sign * self.rotation_deg.to_radians()).sin_cos();
        Point::new(c * p.x - s * p.y, s * p.x + c * p.y)
    }

    /// An IVLMap point in the robot's `map` frame.
    pub fn point_to_robot(&self, p: Point) -> Point {
        self.rotate(p, 1.0)
            .add(Point::new(self.translation[0], self.translation[1]))
    }

    /// A robot `map` frame point in the IVLMap frame.
    pub fn point_from_robot(&self, p: Point) -> Point {
        self.rotate(
            p.sub(Point::new(self.translation[0], self.translation[1])),
            -1.0,
        )
    }

    /// An IVLMap pose (compass heading) as a ROS pose in the robot's `map` frame.
    pub fn to_robot(&self, pose: Pose) -> RosPose2d {
        let p = self.point_to_robot(pose.position);
        let yaw = heading_to_yaw(pose.heading - self.rotation_deg);
        RosPose2d {
            x: p.x,
            y: p.y,
            yaw,
        }
    }

    /// A ROS pose in the robot's `map` frame as an IVLMap pose.
    pub fn from_robot(&self, pose: RosPose2d) -> Pose {
        let p = self.point_from_robot(Point::new(pose.x, pose.y));
        Pose::new(p.x, p.y, yaw_to_heading(pose.yaw) + self.rotation_deg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-9
    }

    fn same_heading(a: f64, b: f64) -> bool {
        normalise_heading(a - b).abs() < 1e-7
    }

    #[test]
    fn compass_north_is_ros_yaw_90_and_east_is_0() {
        assert!(close(heading_to_yaw(0.0), std::f64::consts::FRAC_PI_2));
        assert!(close(heading_to_yaw(90.0), 0.0));
        assert!(close(heading_to_yaw(-90.0).abs(), std::f64::consts::PI));
        assert!(close(heading_to_yaw(180.0), -std::f64::consts::FRAC_PI_2));
        // A right turn (clockwise, +heading) lowers the yaw.
        assert!(heading_to_yaw(10.0) < heading_to_yaw(0.0));
        assert!(close(yaw_to_heading(0.0), 90.0));
        assert!(close(yaw_to_heading(std::f64::consts::FRAC_PI_2), 0.0));
    }

    #[test]
    fn identity_keeps_positions_and_converts_headings() {
        let c = FrameConfig::default();
        let r = c.to_robot(Pose::new(3.0, -2.0, 90.0));
        assert!(close(r.x, 3.0) && close(r.y, -2.0) && close(r.yaw, 0.0));
    }

    #[test]
    fn a_rotated_and_shifted_frame_maps_known_points() {
        // IVLMap turned 90 deg counter-clockwise and moved to (10, 5) in `map`.
        let c = FrameConfig {
            translation: [10.0, 5.0],
            rotation_deg: 90.0,
            ..FrameConfig::default()
        };
        // IVLMap east (1, 0) is map north of the origin: (10, 6).
        let p = c.point_to_robot(Point::new(1.0, 0.0));
        assert!(close(p.x, 10.0) && close(p.y, 6.0), "{p:?}");
        // Facing IVLMap east (heading 90) is facing the map's +y: yaw 90 deg.
        let r = c.to_robot(Pose::new(1.0, 0.0, 90.0));
        assert!(close(r.yaw, std::f64::consts::FRAC_PI_2), "{r:?}");
        let back = c.from_robot(r);
        assert!(close(back.position.x, 1.0) && close(back.position.y, 0.0));
        assert!(same_heading(back.heading, 90.0));
    }

    #[test]
    fn config_files_parse_with_defaults_and_refuse_mistakes() {
        let c = FrameConfig::from_json_str(r#"{"rotation_deg": 30}"#, "f.json").unwrap();
        assert_eq!(c.map_frame, "map");
        assert_eq!(c.translation, [0.0, 0.0]);
        for bad in [
            r#"{"rotation": 30}"#,
            r#"{"format": "other/1"}"#,
            r#"{"base_frame": " "}"#,
            r#"{"translation": [1]}"#,
            "[",
        ] {
            let e = FrameConfig::from_json_str(bad, "f.json").unwrap_err();
            assert!(e.to_string().contains("f.json"), "{e}");
        }
    }

    proptest! {
        #[test]
        fn ivlmap_to_robot_and_back_is_the_identity(
            x in -1e3..1e3f64, y in -1e3..1e3f64, h in -720.0..720.0f64,
            tx in -1e3..1e3f64, ty in -1e3..1e3f64, rot in -360.0..360.0f64,
        ) {
            let c = FrameConfig { translation: [tx, ty], rotation_deg: rot, ..FrameConfig::default() };
            let back = c.from_robot(c.to_robot(Pose::new(x, y, h)));
            prop_assert!((back.position.x - x).abs() < 1e-6 && (back.position.y - y).abs() < 1e-6);
            prop_assert!(same_heading(back.heading, h));
        }

        #[test]
        fn robot_to_ivlmap_and_back_is_the_identity(
            x in -1e3..1e3f64, y in -1e3..1e3f64, yaw in -10.0..10.0f64,
            tx in -1e3..1e3f64, ty in -1e3..1e3f64, rot in -360.0..360.0f64,
        ) {
            let c = FrameConfig { translation: [tx, ty], rotation_deg: rot, ..FrameConfig::default() };
            let r = c.to_robot(c.from_robot(RosPose2d { x, y, yaw }));
            prop_assert!((r.x - x).abs() < 1e-6 && (r.y - y).abs() < 1e-6);
            let d = (r.yaw - yaw).rem_euclid(std::f64::consts::TAU);
            prop_assert!(d < 1e-9 || std::f64::consts::TAU - d < 1e-9);
        }

        #[test]
        fn a_turn_right_in_the_ivlmap_is_clockwise_in_the_robot_frame(
            h in -180.0..180.0f64, rot in -360.0..360.0f64, a in 1.0..170.0f64,
        ) {
            let c = FrameConfig { rotation_deg: rot, ..FrameConfig::default() };
            let y0 = c.to_robot(Pose::new(0.0, 0.0, h)).yaw;
            let y1 = c.to_robot(Pose::new(0.0, 0.0, h + a)).yaw;
            // Clockwise: the yaw decreases by a (mod 360).
            let d = (y0 - y1).to_degrees().rem_euclid(360.0);
            prop_assert!((d - a).abs() < 1e-6, "{d} vs {a}");
        }
    }
}
