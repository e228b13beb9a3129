//! `poses.txt` (VLMaps' format: one pose per frame, `px py pz qx qy qz qw`, or a
//! row-major 4x4 matrix of 16 numbers) and the conventions that turn a pose record
//! into the robot base and camera poses in the ivlmap world (x east, y north, z up).

use std::fmt::Write as _;
use std::path::Path;

use nalgebra::{Isometry3, Matrix3, Quaternion, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::Deserialize;

use super::ReconstructError;
use map_core::geometry::{normalise_heading, Pose};

/// What a `poses.txt` record is the pose of, and in which world frame.
///
/// Every convention yields the robot *base* frame (x forward, y left, z up, on the
/// floor) and the *camera* optical frame (OpenCV: x right, y down, z forward) in the
/// ivlmap world (x east, y north, z up).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PoseConvention {
    /// VLMaps' Habitat datasets (`pose_type: mobile_base`, the default): the Habitat
    /// agent's pose in the Habitat world, which is y-up: Habitat (x, y, z) is ivlmap
    /// (x, -z, y), so Habitat's -z is north. The agent looks along its -z with x to its
    /// right and y up; the camera sits `camera_height` above it along the agent's y,
    /// rotated by diag(1, -1, -1) (VLMaps' `base2cam_rot`).
    HabitatBase,
    /// A ROS base pose (x forward, y left, z up) in a z-up world whose x is east and
    /// y north (REP 103's ENU, the same as ivlmap's): the paper's real-robot setup. The
    /// camera sits `camera_height` above the base with the paper's rotation
    /// [[0, 0, 1], [-1, 0, 0], [0, -1, 0]] (camera axes in base coordinates).
    RosBase,
    /// The camera's optical frame (OpenCV) directly, in the ivlmap world; the base is
    /// `camera_height` below the camera, facing the camera's horizontal heading.
    CameraOpencv,
}

impl PoseConvention {
    /// The name `camera.json` uses.
    pub fn name(self) -> &'static str {
        match self {
            PoseConvention::HabitatBase => "habitat_base",
            PoseConvention::RosBase => "ros_base",
            PoseConvention::CameraOpencv => "camera_opencv",
        }
    }

    /// Base and camera poses in the ivlmap world for one `poses.txt` record.
    pub fn to_world(self, record: &Isometry3<f64>, camera_height: f64) -> FramePose {
        match self {
            PoseConvention::HabitatBase => {
                let t_wa = habitat_to_world() * record;
                FramePose {
                    base: t_wa * agent_to_base(),
                    camera: t_wa * habitat_agent_to_camera(camera_height),
                }
            }
            PoseConvention::RosBase => FramePose {
                base: *record,
                camera: record * ros_base_to_camera(camera_height),
            },
            PoseConvention::CameraOpencv => {
                let camera = *record;
                let fwd = camera.rotation * Vector3::z();
                let up_img = camera.rotation * -Vector3::y();
                let dir = if fwd.x.hypot(fwd.y) > 1e-6 {
                    fwd
                } else {
                    up_img
                };
                let yaw = dir.y.atan2(dir.x);
                let t = camera.translation.vector - Vector3::new(0.0, 0.0, camera_height);
                FramePose {
                    base: Isometry3::from_parts(
                        Translation3::from(t),
                        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw),
                    ),
                    camera,
                }
            }
        }
    }

    /// The `poses.txt` record that puts the base at `base` (ivlmap world, anchor
    /// `world`): the inverse of [`PoseConvention::to_world`] for the base.
    pub fn record_for_base(self, base: &Isometry3<f64>, camera_height: f64) -> Isometry3<f64> {
        match self {
            PoseConvention::HabitatBase => {
                habitat_to_world().inverse() * base * agent_to_base().inverse()
            }
            PoseConvention::RosBase => *base,
            PoseConvention::CameraOpencv => base * ros_base_to_camera(camera_height),
        }
    }
}

/// Which frame the map is built in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Anchor {
    /// The poses' own world, mapped onto ivlmap axes (the default).
    #[default]
    World,
    /// VLMaps' choice: the first frame's base is the origin, its forward direction is
    /// north and its right east, and its floor is z = 0.
    FirstFrame,
}

impl Anchor {
    /// The name `camera.json` uses.
    pub fn name(self) -> &'static str {
        match self {
            Anchor::World => "world",
            Anchor::FirstFrame => "first_frame",
        }
    }
}

/// One frame's base and camera poses in the ivlmap world.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FramePose {
    /// Robot base: x forward, y left, z up, on the floor.
    pub base: Isometry3<f64>,
    /// Camera optical frame: x right, y down, z forward.
    pub camera: Isometry3<f64>,
}

/// Every frame's poses in the map frame plus the floor height.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldPoses {
    /// Each frame's base and camera poses, in frame order.
    pub frames: Vec<FramePose>,
    /// World z of the floor: the first frame's base z (heights are measured from it;
    /// one floor level per dataset, as in VLMaps).
    pub floor_z: f64,
}

/// Convert `poses.txt` records to base and camera poses in the map frame.
pub fn world_poses(
    records: &[Isometry3<f64>],
    convention: PoseConvention,
    camera_height: f64,
    anchor: Anchor,
) -> WorldPoses {
    let mut frames: Vec<FramePose> = records
        .iter()
        .map(|r| convention.to_world(r, camera_height))
        .collect();
    if anchor == Anchor::FirstFrame {
        if let Some(first) = frames.first().copied() {
            let h0 = heading_frame(&first.base);
            let inv = h0.inverse();
            for f in &mut frames {
                f.base = inv * f.base;
                f.camera = inv * f.camera;
            }
        }
    }
    let floor_z = frames.first().map_or(0.0, |f| f.base.translation.z);
    WorldPoses { frames, floor_z }
}

/// The frame at a base's position whose y axis is the base's horizontal forward
/// direction, x its right and z up.
fn heading_frame(base: &Isometry3<f64>) -> Isometry3<f64> {
    let fwd = base.rotation * Vector3::x();
    let yaw = fwd.y.atan2(fwd.x);
    Isometry3::from_parts(
        base.translation,
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw - std::f64::consts::FRAC_PI_2),
    )
}

/// A base pose on the floor at height `z` from a 2-D compass pose (heading 0 =
/// north, clockwise).
pub fn base_from_pose2d(pose: Pose, z: f64) -> Isometry3<f64> {
    let yaw = (90.0 - pose.heading).to_radians();
    Isometry3::from_parts(
        Translation3::new(pose.position.x, pose.position.y, z),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw),
    )
}

/// The 2-D compass pose of a base frame (its horizontal forward direction).
pub fn pose2d_from_base(base: &Isometry3<f64>) -> Pose {
    let fwd = base.rotation * Vector3::x();
    let t = base.translation.vector;
    Pose::new(t.x, t.y, normalise_heading(fwd.x.atan2(fwd.y).to_degrees()))
}

fn iso(rot: Matrix3<f64>, t: Vector3<f64>) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::from(t),
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rot)),
    )
}

/// Habitat world (x, y up, z) to ivlmap world: (x, -z, y).
fn habitat_to_world() -> Isometry3<f64> {
    iso(
        Matrix3::new(
            1.0, 0.0, 0.0, //
            0.0, 0.0, -1.0, //
            0.0, 1.0, 0.0,
        ),
        Vector3::zeros(),
    )
}

/// Habitat agent frame (x right, y up, z back) to the base frame (x forward, y left,
/// z up): the columns are the base axes in agent coordinates (VLMaps'
/// `base_transform` is the transpose).
fn agent_to_base() -> Isometry3<f64> {
    iso(
        Matrix3::new(
            0.0, -1.0, 0.0, //
            0.0, 0.0, 1.0, //
            -1.0, 0.0, 0.0,
        ),
        Vector3::zeros(),
    )
}

/// VLMaps' `base2cam_tf`: camera `camera_height` up the agent's y, rotated diag(1, -1, -1).
fn habitat_agent_to_camera(camera_height: f64) -> Isometry3<f64> {
    iso(
        Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0)),
        Vector3::new(0.0, camera_height, 0.0),
    )
}

/// The paper's base-to-camera rotation (Eq. "rot") with the camera `camera_height` up.
fn ros_base_to_camera(camera_height: f64) -> Isometry3<f64> {
    iso(
        Matrix3::new(
            0.0, 0.0, 1.0, //
            -1.0, 0.0, 0.0, //
            0.0, -1.0, 0.0,
        ),
        Vector3::new(0.0, 0.0, camera_height),
    )
}

/// Parse `poses.txt` text; `source` names the file in errors. Blank lines and lines
/// starting with `#` are skipped; numbers are separated by spaces, tabs or commas.
pub fn parse_poses_txt(text: &str, source: &Path) -> Result<Vec<Isometry3<f64>>, ReconstructError> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        let err = |message: String| ReconstructError::Poses {
            path: source.to_path_buf(),
            line: n,
            message,
        };
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let mut vals = Vec::with_capacity(16);
        for (k, tok) in t
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .enumerate()
        {
            match tok.parse::<f64>() {
                Ok(v) if v.is_finite() => vals.push(v),
                _ => {
                    return Err(err(format!(
                        "value {} ({tok:?}) is not a finite number",
                        k + 1
                    )))
                }
            }
        }
        let pose = match vals.len() {
            7 => {
                let q = Quaternion::new(vals[6], vals[3], vals[4], vals[5]);
                let norm = q.norm();
                if !(0.99..=1.01).contains(&norm) {
                    return Err(err(format!(
                        "quaternion (qx qy qz qw) = ({} {} {} {}) has norm {norm:.4}; expected a unit quaternion",
                        vals[3], vals[4], vals[5], vals[6]
                    )));
                }
                Isometry3::from_parts(
                    Translation3::new(vals[0], vals[1], vals[2]),
                    UnitQuaternion::from_quaternion(q),
                )
            }
            16 => {
                if vals[12..16] != [0.0, 0.0, 0.0, 1.0] {
                    return Err(err(format!(
                        "the last row of a 4x4 pose must be 0 0 0 1, found {:?}",
                        &vals[12..16]
                    )));
                }
                let r = Matrix3::new(
                    vals[0], vals[1], vals[2], vals[4], vals[5], vals[6], vals[8], vals[9],
                    vals[10],
                );
                let off = (r.transpose() * r - Matrix3::identity()).abs().max();
                if off > 1e-3 || r.determinant() < 0.0 {
                    return Err(err(format!(
                        "the 3x3 part of the 4x4 pose is not a rotation (|R^T R - I| = {off:.2e}, det {:.3})",
                        r.determinant()
                    )));
                }
                Isometry3::from_parts(
                    Translation3::new(vals[3], vals[7], vals[11]),
                    UnitQuaternion::from_matrix(&r),
                )
            }
            k => {
                return Err(err(format!(
                    "expected 7 numbers (px py pz qx qy qz qw) or 16 (a row-major 4x4 matrix), found {k}"
                )))
            }
        };
        out.push(pose);
    }
    Ok(out)
}

/// Read `poses.txt`.
pub fn read_poses_txt(path: impl AsRef<Path>) -> Result<Vec<Isometry3<f64>>, ReconstructError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|source| ReconstructError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_poses_txt(&text, path)
}

/// Write `poses.txt` as VLMaps does: `px py pz qx qy qz qw`, tab-separated, one line
/// per pose (numbers in Rust's shortest round-trip form).
pub fn write_poses_txt(
    path: impl AsRef<Path>,
    poses: &[Isometry3<f64>],
) -> Result<(), ReconstructError> {
    let path = path.as_ref();
    let mut s = String::new();
    for p in poses {
        let t = p.translation.vector;
        let q = p.rotation.quaternion();
        let _ = writeln!(
            s,
            "{}\t{}\t{}\t{}\t{}\t{}\t{}",
            t.x, t.y, t.z, q.i, q.j, q.k, q.w
        );
    }
    std::fs::write(path, s).map_err(|source| ReconstructError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vector3<f64>, b: [f64; 3]) -> bool {
        (a - Vector3::from(b)).abs().max() < 1e-9
    }

    #[test]
    fn habitat_identity_agent_faces_north_with_camera_up() {
        // Habitat agent at (1, 0, -2), identity rotation.
        let rec = Isometry3::translation(1.0, 0.0, -2.0);
        let fp = PoseConvention::HabitatBase.to_world(&rec, 1.5);
        assert!(close(fp.base.translation.vector, [1.0, 2.0, 0.0]));
        assert!(close(fp.base.rotation * Vector3::x(), [0.0, 1.0, 0.0])); // forward north
        assert!(close(fp.base.rotation * Vector3::y(), [-1.0, 0.0, 0.0])); // left west
        assert!(close(fp.camera.translation.vector, [1.0, 2.0, 1.5]));
        assert!(close(fp.camera.rotation * Vector3::z(), [0.0, 1.0, 0.0])); // looks north
        assert!(close(fp.camera.rotation * Vector3::x(), [1.0, 0.0, 0.0])); // right east
        assert!(close(fp.camera.rotation * Vector3::y(), [0.0, 0.0, -1.0])); // down
        assert!(pose2d_from_base(&fp.base).heading.abs() < 1e-9);
    }

    #[test]
    fn habitat_positive_yaw_turns_left() {
        // +90 degrees about Habitat's y (up) turns the agent from -z to -x: west.
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let rec = parse_poses_txt(&format!("0 0 0 0 {s} 0 {s}\n"), Path::new("p.txt")).unwrap();
        let fp = PoseConvention::HabitatBase.to_world(&rec[0], 1.5);
        assert!((pose2d_from_base(&fp.base).heading + 90.0).abs() < 1e-9);
        assert!(close(fp.camera.rotation * Vector3::z(), [-1.0, 0.0, 0.0]));
    }

    #[test]
    fn ros_base_camera_matches_the_paper_rotation() {
        let base = base_from_pose2d(Pose::new(3.0, 4.0, 90.0), 0.0); // facing east
        let fp = PoseConvention::RosBase.to_world(&base, 0.5);
        assert!(close(fp.camera.rotation * Vector3::z(), [1.0, 0.0, 0.0]));
        assert!(close(fp.camera.rotation * Vector3::x(), [0.0, -1.0, 0.0])); // right = south
        assert!(close(fp.camera.translation.vector, [3.0, 4.0, 0.5]));
    }

    #[test]
    fn record_for_base_inverts_to_world() {
        for conv in [
            PoseConvention::HabitatBase,
            PoseConvention::RosBase,
            PoseConvention::CameraOpencv,
        ] {
            for h in [0.0, 37.0, -120.0, 180.0] {
                let base = base_from_pose2d(Pose::new(2.5, -1.0, h), 0.2);
                let rec = conv.record_for_base(&base, 1.2);
                let back = conv.to_world(&rec, 1.2).base;
                assert!(
                    (back.to_homogeneous() - base.to_homogeneous()).abs().max() < 1e-9,
                    "{conv:?} {h}"
                );
            }
        }
    }

    #[test]
    fn first_frame_anchor_puts_the_first_base_at_the_origin_facing_north() {
        let recs: Vec<_> = [Pose::new(5.0, 1.0, 90.0), Pose::new(6.0, 1.0, 90.0)]
            .iter()
            .map(|p| PoseConvention::HabitatBase.record_for_base(&base_from_pose2d(*p, 0.3), 1.5))
            .collect();
        let wp = world_poses(&recs, PoseConvention::HabitatBase, 1.5, Anchor::FirstFrame);
        assert_eq!(wp.floor_z, 0.0);
        let p0 = pose2d_from_base(&wp.frames[0].base);
        assert!(
            p0.position.x.abs() < 1e-9 && p0.position.y.abs() < 1e-9 && p0.heading.abs() < 1e-9
        );
        // one metre east of the first pose, which faced east: straight ahead = north
        let p1 = pose2d_from_base(&wp.frames[1].base);
        assert!(p1.position.x.abs() < 1e-9 && (p1.position.y - 1.0).abs() < 1e-9);
        let world = world_poses(&recs, PoseConvention::HabitatBase, 1.5, Anchor::World);
        assert!((world.floor_z - 0.3).abs() < 1e-12);
    }

    #[test]
    fn bad_lines_name_file_and_line() {
        let e = parse_poses_txt("0 0 0 0 0 0 1\n\n1 2 3 4 5\n", Path::new("d/poses.txt"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "d/poses.txt line 3: expected 7 numbers (px py pz qx qy qz qw) or 16 (a row-major 4x4 matrix), found 5"
        );
        let e = parse_poses_txt("0 0 0 0 0 0 2\n", Path::new("poses.txt"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 1") && e.contains("norm 2"), "{e}");
        let e = parse_poses_txt("0 0 nan 0 0 0 1\n", Path::new("poses.txt"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("value 3"), "{e}");
    }

    #[test]
    fn matrix_rows_and_roundtrip() {
        let m = "0 -1 0 1  1 0 0 2  0 0 1 3  0 0 0 1\n";
        let p = parse_poses_txt(m, Path::new("p.txt")).unwrap();
        assert!(close(p[0].translation.vector, [1.0, 2.0, 3.0]));
        assert!(close(p[0].rotation * Vector3::x(), [0.0, 1.0, 0.0]));
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("poses.txt");
        write_poses_txt(&f, &p).unwrap();
        let back = read_poses_txt(&f).unwrap();
        assert!(
            (back[0].to_homogeneous() - p[0].to_homogeneous())
                .abs()
                .max()
                < 1e-12
        );
    }
}
