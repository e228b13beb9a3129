//! The robot's pose from what `/tf`, `/tf_static` and `/amcl_pose` said last: the
//! base frame in the map frame through `map -> odom -> base` (or a direct
//! `map -> base`), else AMCL's estimate.

use std::collections::HashMap;

use crate::frames::RosPose2d;
use crate::msgs::{PoseWithCovarianceStamped, TfMessage, Transform};

/// Where a pose came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PoseSource {
    /// `/tf` (and `/tf_static`).
    Tf,
    /// `/amcl_pose`.
    Amcl,
}

/// The latest transforms and AMCL pose, in 2D.
#[derive(Debug, Clone, Default)]
pub struct TfState {
    /// (parent, child) -> child's pose in the parent frame.
    edges: HashMap<(String, String), RosPose2d>,
    amcl: Option<(String, RosPose2d)>,
    /// Messages taken so far (to tell a fresh pose from an old one).
    pub samples: u64,
}

fn strip(frame: &str) -> &str {
    frame.trim_start_matches('/')
}

fn planar(t: &Transform) -> RosPose2d {
    RosPose2d {
        x: t.translation.x,
        y: t.translation.y,
        yaw: t.rotation.yaw(),
    }
}

/// `b` (given in `a`'s frame) in the frame `a` is given in.
fn compose(a: RosPose2d, b: RosPose2d) -> RosPose2d {
    let (s, c) = a.yaw.sin_cos();
    let yaw = (a.yaw + b.yaw).sin().atan2((a.yaw + b.yaw).cos());
    RosPose2d {
        x: a.x + c * b.x - s * b.y,
        y: a.y + s * b.x + c * b.y,
        yaw,
    }
}

impl TfState {
    /// Take in a `/tf` or `/tf_static` message.
    pub fn add_tf(&mut self, m: &TfMessage) {
        for t in &m.transforms {
            let p = planar(&t.transform);
            if [p.x, p.y, p.yaw].iter().all(|v| v.is_finite()) {
                let key = (
                    strip(&t.header.frame_id).to_string(),
                    strip(&t.child_frame_id).to_string(),
                );
                self.edges.insert(key, p);
            }
        }
        self.samples += 1;
    }

    /// Take in an `/amcl_pose` message.
    pub fn add_amcl(&mut self, m: &PoseWithCovarianceStamped) {
        let pose = &m.pose.pose;
        let p = RosPose2d {
            x: pose.position.x,
            y: pose.position.y,
            yaw: pose.orientation.yaw(),
        };
        if [p.x, p.y, p.yaw].iter().all(|v| v.is_finite()) {
            self.amcl = Some((strip(&m.header.frame_id).to_string(), p));
        }
        self.samples += 1;
    }

    fn edge(&self, parent: &str, child: &str) -> Option<RosPose2d> {
        self.edges
            .get(&(parent.to_string(), child.to_string()))
            .copied()
    }

    /// The base frame's pose in the map frame, and where it came from.
    pub fn base_in_map(
        &self,
        map: &str,
        odom: &str,
        base: &str,
    ) -> Option<(RosPose2d, PoseSource)> {
        let (map, odom, base) = (strip(map), strip(odom), strip(base));
        let via_odom = self
            .edge(map, odom)
            .zip(self.edge(odom, base))
            .map(|(a, b)| compose(a, b));
        if let Some(p) = via_odom.or_else(|| self.edge(map, base)) {
            return Some((p, PoseSource::Tf));
        }
        match &self.amcl {
            Some((frame, p)) if frame == map || frame.is_empty() => Some((*p, PoseSource::Amcl)),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msgs::{Header, Quaternion, TransformStamped, Vector3};

    fn tf(parent: &str, child: &str, x: f64, y: f64, yaw: f64) -> TransformStamped {
        TransformStamped {
            header: Header {
                frame_id: parent.into(),
                ..Header::default()
            },
            child_frame_id: child.into(),
            transform: Transform {
                translation: Vector3 { x, y, z: 0.0 },
                rotation: Quaternion::from_yaw(yaw),
            },
        }
    }

    #[test]
    fn map_odom_base_compose_and_tf_wins_over_amcl() {
        let mut s = TfState::default();
        assert!(s.base_in_map("map", "odom", "base_link").is_none());
        let mut amcl = PoseWithCovarianceStamped::default();
        amcl.header.frame_id = "map".into();
        amcl.pose.pose.position.x = 7.0;
        s.add_amcl(&amcl);
        let (p, src) = s.base_in_map("map", "odom", "base_link").unwrap();
        assert_eq!((p.x, src), (7.0, PoseSource::Amcl));
        // odom is 1 m east of map's origin, turned 90 deg; base 2 m ahead along odom's x.
        s.add_tf(&TfMessage {
            transforms: vec![
                tf("map", "odom", 1.0, 0.0, std::f64::consts::FRAC_PI_2),
                tf("/odom", "base_link", 2.0, 0.0, 0.0),
            ],
        });
        let (p, src) = s.base_in_map("map", "odom", "base_link").unwrap();
        assert_eq!(src, PoseSource::Tf);
        assert!(
            (p.x - 1.0).abs() < 1e-9 && (p.y - 2.0).abs() < 1e-9,
            "{p:?}"
        );
        assert!((p.yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        assert_eq!(s.samples, 2);
    }

    #[test]
    fn non_finite_transforms_are_ignored() {
        let mut s = TfState::default();
        s.add_tf(&TfMessage {
            transforms: vec![tf("map", "base_link", f64::NAN, 0.0, 0.0)],
        });
        assert!(s.base_in_map("map", "odom", "base_link").is_none());
    }
}
