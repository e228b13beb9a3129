//! `camera.json`: the camera intrinsics, depth units, pose convention, camera height
//! and (optionally) the map extent of an RGB-D dataset folder.

use std::path::Path;

use nalgebra::{Matrix3, Vector3};
use serde::Deserialize;
use serde_json::json;

use super::poses::{Anchor, PoseConvention};
use super::ReconstructError;
use map_core::grid::GridFrame;

/// The `format` string of `camera.json`.
pub const RGBD_FORMAT: &str = "ivlmap-rgbd/1";

/// Pinhole intrinsics in pixels. A pixel `(u, v)` (column, row, 0-based) is
/// back-projected through the point `(u + pixel_center, v + pixel_center)`:
/// `pixel_center` = 0.5 is VLMaps' and Habitat's convention (cx = W/2 is the image
/// centre), 0.0 is OpenCV's (pixel centres at integer coordinates, as calibration
/// tools report cx, cy).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    /// Focal length along image columns, pixels.
    pub fx: f64,
    /// Focal length along image rows, pixels.
    pub fy: f64,
    /// Principal point column, pixels.
    pub cx: f64,
    /// Principal point row, pixels.
    pub cy: f64,
    /// Offset added to a pixel's index to get the point it back-projects through.
    pub pixel_center: f64,
}

impl Intrinsics {
    /// Intrinsics with VLMaps' pixel-centre convention (0.5).
    pub fn new(fx: f64, fy: f64, cx: f64, cy: f64) -> Self {
        Self {
            fx,
            fy,
            cx,
            cy,
            pixel_center: 0.5,
        }
    }

    /// A Habitat-style camera: square pixels, principal point at the image centre,
    /// `hfov_deg` horizontal field of view (VLMaps' `get_sim_cam_mat_with_fov`).
    pub fn from_hfov(width: u32, height: u32, hfov_deg: f64) -> Self {
        let f = f64::from(width) / (2.0 * (hfov_deg.to_radians() / 2.0).tan());
        Self::new(f, f, f64::from(width) / 2.0, f64::from(height) / 2.0)
    }

    /// The 3x3 camera matrix K.
    pub fn k(&self) -> Matrix3<f64> {
        Matrix3::new(
            self.fx, 0.0, self.cx, //
            0.0, self.fy, self.cy, //
            0.0, 0.0, 1.0,
        )
    }

    /// The camera-frame point (OpenCV: x right, y down, z forward) seen at pixel
    /// (`u`, `v`) with depth `z` measured along the optical axis.
    pub fn backproject(&self, u: f64, v: f64, z: f64) -> Vector3<f64> {
        Vector3::new(
            (u + self.pixel_center - self.cx) / self.fx * z,
            (v + self.pixel_center - self.cy) / self.fy * z,
            z,
        )
    }

    /// The ray direction (camera frame, z = 1) through pixel (`u`, `v`).
    pub fn ray(&self, u: f64, v: f64) -> Vector3<f64> {
        self.backproject(u, v, 1.0)
    }

    /// The pixel (column, row) a camera-frame point projects into, `None` behind the camera.
    pub fn project(&self, p: &Vector3<f64>) -> Option<(f64, f64)> {
        (p.z > 0.0).then(|| {
            (
                self.fx * p.x / p.z + self.cx - self.pixel_center,
                self.fy * p.y / p.z + self.cy - self.pixel_center,
            )
        })
    }
}

/// Where the top-down grid lies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MapSpec {
    /// Covers every camera position +- the maximum depth, snapped outward to whole cells.
    Auto {
        /// Side of a grid cell, metres.
        cell_size: f64,
    },
    /// Explicit world bounds [xmin, ymin, xmax, ymax] (after anchoring), as in scene files.
    Bounds {
        /// `[xmin, ymin, xmax, ymax]` in metres.
        bounds: [f64; 4],
        /// Side of a grid cell, metres.
        cell_size: f64,
    },
    /// VLMaps' square `gs x gs` grid around the anchor origin, laid out as
    /// [`vlmaps_grid_frame`](crate::reconstruct::vlmaps_grid_frame) says (use with
    /// `anchor: first_frame` to match VLMaps' cells).
    VlmapsGrid {
        /// Cells along each side of the square grid (VLMaps' `gs`).
        grid_size: usize,
        /// Side of a grid cell, metres.
        cell_size: f64,
    },
}

impl MapSpec {
    /// Side of a grid cell, metres.
    pub fn cell_size(&self) -> f64 {
        match *self {
            MapSpec::Auto { cell_size }
            | MapSpec::Bounds { cell_size, .. }
            | MapSpec::VlmapsGrid { cell_size, .. } => cell_size,
        }
    }
}

impl Default for MapSpec {
    fn default() -> Self {
        MapSpec::Auto { cell_size: 0.05 }
    }
}

/// The contents of `camera.json`.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraInfo {
    /// The camera's pinhole intrinsics.
    pub intrinsics: Intrinsics,
    /// Image size, checked against every frame when given.
    pub width: Option<u32>,
    /// Image height in pixels, checked against every frame when given.
    pub height: Option<u32>,
    /// Integer depth units per metre (uint16 PNG or integer `.npy`), default 1000 (mm).
    /// Float `.npy` depth is always metres.
    pub depth_scale: f64,
    /// What a `poses.txt` record is the pose of, and in which world frame.
    pub pose_convention: PoseConvention,
    /// Camera optical centre above the floor under the robot, metres.
    pub camera_height: f64,
    /// Which frame the map is built in.
    pub anchor: Anchor,
    /// Where the top-down grid lies; `None` when `camera.json` has no `map`.
    pub map: Option<MapSpec>,
}

impl CameraInfo {
    /// VLMaps' Habitat dataset settings (`config/map_config/vlmaps.yaml`):
    /// K = [540, 0, 540; 0, 540, 360; 0, 0, 1] (1080 x 720, 90 degree hfov), camera
    /// 1.5 m above the base, `habitat_base` poses, map anchored on the first frame.
    pub fn vlmaps_habitat() -> Self {
        Self {
            intrinsics: Intrinsics::new(540.0, 540.0, 540.0, 360.0),
            width: Some(1080),
            height: Some(720),
            depth_scale: 1000.0,
            pose_convention: PoseConvention::HabitatBase,
            camera_height: 1.5,
            anchor: Anchor::FirstFrame,
            map: Some(MapSpec::VlmapsGrid {
                grid_size: 1000,
                cell_size: 0.05,
            }),
        }
    }

    /// Read and validate a `camera.json` file.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Self, ReconstructError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| ReconstructError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_json_str(&text, path)
    }

    /// Parse `camera.json` text; `source` names it in errors.
    pub fn from_json_str(text: &str, source: impl AsRef<Path>) -> Result<Self, ReconstructError> {
        let file = source.as_ref();
        let de = &mut serde_json::Deserializer::from_str(text);
        let raw: RawCamera = serde_path_to_error::deserialize(de).map_err(|e| {
            let field = e.path().to_string();
            let inner = e.into_inner();
            ReconstructError::Camera {
                path: file.to_path_buf(),
                line: Some(inner.line()),
                field: if field == "." { String::new() } else { field },
                message: strip_position(&inner.to_string()),
            }
        })?;
        raw.validate(text, file)
    }

    /// The `camera.json` text for these settings (what [`CameraInfo::from_json_str`] reads).
    pub fn to_json_string(&self) -> String {
        let i = &self.intrinsics;
        let mut v = json!({
            "format": RGBD_FORMAT,
            "intrinsics": {"fx": i.fx, "fy": i.fy, "cx": i.cx, "cy": i.cy},
            "pixel_center": i.pixel_center,
            "depth_scale": self.depth_scale,
            "pose_convention": self.pose_convention.name(),
            "camera_height": self.camera_height,
            "anchor": self.anchor.name(),
        });
        if let (Some(w), Some(h)) = (self.width, self.height) {
            v["width"] = json!(w);
            v["height"] = json!(h);
        }
        match self.map {
            None => {}
            Some(MapSpec::Auto { cell_size }) => v["map"] = json!({ "cell_size": cell_size }),
            Some(MapSpec::Bounds { bounds, cell_size }) => {
                v["map"] = json!({ "bounds": bounds, "cell_size": cell_size })
            }
            Some(MapSpec::VlmapsGrid {
                grid_size,
                cell_size,
            }) => v["map"] = json!({ "grid_size": grid_size, "cell_size": cell_size }),
        }
        serde_json::to_string_pretty(&v).unwrap_or_default()
    }

    /// Write `camera.json`.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<(), ReconstructError> {
        let path = path.as_ref();
        std::fs::write(path, self.to_json_string() + "\n").map_err(|source| ReconstructError::Io {
            path: path.to_path_buf(),
            source,
        })
    }
}

/// serde_json appends " at line L column C"; the error already carries the line.
fn strip_position(msg: &str) -> String {
    match msg.rfind(" at line ") {
        Some(i) => msg[..i].to_string(),
        None => msg.to_string(),
    }
}

/// 1-based line of the first occurrence of `needle`.
fn line_of(text: &str, needle: &str) -> Option<usize> {
    text.find(needle)
        .map(|i| text[..i].bytes().filter(|&b| b == b'\n').count() + 1)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawIntrinsics {
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RawK {
    Nested([[f64; 3]; 3]),
    Flat([f64; 9]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMap {
    #[serde(default)]
    bounds: Option<[f64; 4]>,
    #[serde(default)]
    grid_size: Option<usize>,
    #[serde(default)]
    cell_size: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    format: String,
    #[serde(default)]
    width: Option<u32>,
    #[serde(default)]
    height: Option<u32>,
    #[serde(default)]
    intrinsics: Option<RawIntrinsics>,
    #[serde(default, rename = "K")]
    k: Option<RawK>,
    #[serde(default)]
    hfov_deg: Option<f64>,
    #[serde(default)]
    pixel_center: Option<f64>,
    #[serde(default)]
    depth_scale: Option<f64>,
    #[serde(default)]
    pose_convention: Option<PoseConvention>,
    camera_height: f64,
    #[serde(default)]
    anchor: Option<Anchor>,
    #[serde(default)]
    map: Option<RawMap>,
}

impl RawCamera {
    fn validate(self, text: &str, file: &Path) -> Result<CameraInfo, ReconstructError> {
        let err = |field: &str, message: String| ReconstructError::Camera {
            path: file.to_path_buf(),
            line: line_of(
                text,
                &format!("\"{}\"", field.split('.').next().unwrap_or(field)),
            ),
            field: field.to_string(),
            message,
        };
        if self.format != RGBD_FORMAT {
            return Err(err(
                "format",
                format!(
                    "unsupported format {:?}, expected {RGBD_FORMAT:?}",
                    self.format
                ),
            ));
        }
        let given = [
            self.intrinsics.is_some(),
            self.k.is_some(),
            self.hfov_deg.is_some(),
        ];
        if given.iter().filter(|&&g| g).count() != 1 {
            return Err(err(
                "intrinsics",
                "give exactly one of \"intrinsics\" {fx, fy, cx, cy}, \"K\" (3x3) or \"hfov_deg\""
                    .into(),
            ));
        }
        let mut intr = if let Some(i) = self.intrinsics {
            Intrinsics::new(i.fx, i.fy, i.cx, i.cy)
        } else if let Some(k) = self.k {
            let m = match k {
                RawK::Nested(m) => m,
                RawK::Flat(f) => [[f[0], f[1], f[2]], [f[3], f[4], f[5]], [f[6], f[7], f[8]]],
            };
            if m[0][1] != 0.0 || m[1][0] != 0.0 || m[2] != [0.0, 0.0, 1.0] {
                return Err(err(
                    "K",
                    format!("expected [[fx, 0, cx], [0, fy, cy], [0, 0, 1]], got {m:?}"),
                ));
            }
            Intrinsics::new(m[0][0], m[1][1], m[0][2], m[1][2])
        } else {
            let hfov = self.hfov_deg.unwrap_or(90.0);
            let (Some(w), Some(h)) = (self.width, self.height) else {
                return Err(err(
                    "hfov_deg",
                    "\"hfov_deg\" needs \"width\" and \"height\"".into(),
                ));
            };
            if !(hfov > 0.0 && hfov < 180.0) {
                return Err(err(
                    "hfov_deg",
                    format!("must lie in (0, 180) degrees, got {hfov}"),
                ));
            }
            Intrinsics::from_hfov(w, h, hfov)
        };
        for (name, v) in [("fx", intr.fx), ("fy", intr.fy)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(err(
                    &format!("intrinsics.{name}"),
                    format!("must be a finite number > 0, got {v}"),
                ));
            }
        }
        for (name, v) in [("cx", intr.cx), ("cy", intr.cy)] {
            if !v.is_finite() {
                return Err(err(
                    &format!("intrinsics.{name}"),
                    format!("must be finite, got {v}"),
                ));
            }
        }
        if let Some(pc) = self.pixel_center {
            if !(0.0..=1.0).contains(&pc) {
                return Err(err("pixel_center", format!("must lie in [0, 1], got {pc}")));
            }
            intr.pixel_center = pc;
        }
        if self.width.is_some() != self.height.is_some() {
            return Err(err(
                "width",
                "give both \"width\" and \"height\" or neither".into(),
            ));
        }
        if self.width == Some(0) || self.height == Some(0) {
            return Err(err("width", "image size must be > 0".into()));
        }
        let depth_scale = self.depth_scale.unwrap_or(1000.0);
        if !(depth_scale.is_finite() && depth_scale > 0.0) {
            return Err(err(
                "depth_scale",
                format!("must be a finite number > 0 (units per metre), got {depth_scale}"),
            ));
        }
        if !(self.camera_height.is_finite()
            && self.camera_height > 0.0
            && self.camera_height < 10.0)
        {
            return Err(err(
                "camera_height",
                format!("must lie in (0, 10) metres, got {}", self.camera_height),
            ));
        }
        let map = match self.map {
            None => None,
            Some(m) => {
                let cs = m.cell_size.unwrap_or(0.05);
                if !(0.005..=1.0).contains(&cs) {
                    return Err(err(
                        "map.cell_size",
                        format!("must lie between 0.005 and 1.0 m, got {cs}"),
                    ));
                }
                Some(match (m.bounds, m.grid_size) {
                    (Some(_), Some(_)) => {
                        return Err(err(
                            "map",
                            "give \"bounds\" or \"grid_size\", not both".into(),
                        ))
                    }
                    (Some(b), None) => {
                        if !b.iter().all(|v| v.is_finite()) || b[0] >= b[2] || b[1] >= b[3] {
                            return Err(err(
                                "map.bounds",
                                format!("must be [xmin, ymin, xmax, ymax] with xmin < xmax and ymin < ymax, got {b:?}"),
                            ));
                        }
                        let cells = (b[2] - b[0]) / cs * ((b[3] - b[1]) / cs);
                        if cells > MAX_CELLS as f64 {
                            return Err(err(
                                "map.bounds",
                                format!("the grid would have {cells:.0} cells (limit {MAX_CELLS})"),
                            ));
                        }
                        MapSpec::Bounds {
                            bounds: b,
                            cell_size: cs,
                        }
                    }
                    (None, Some(gs)) => {
                        if gs == 0 || gs.saturating_mul(gs) > MAX_CELLS {
                            return Err(err(
                                "map.grid_size",
                                format!("must be > 0 with at most {MAX_CELLS} cells, got {gs}"),
                            ));
                        }
                        MapSpec::VlmapsGrid {
                            grid_size: gs,
                            cell_size: cs,
                        }
                    }
                    (None, None) => MapSpec::Auto { cell_size: cs },
                })
            }
        };
        Ok(CameraInfo {
            intrinsics: intr,
            width: self.width,
            height: self.height,
            depth_scale,
            pose_convention: self.pose_convention.unwrap_or(PoseConvention::HabitatBase),
            camera_height: self.camera_height,
            anchor: self.anchor.unwrap_or(Anchor::World),
            map,
        })
    }
}

/// Most cells a reconstructed grid may have (as for scene files).
pub(crate) const MAX_CELLS: usize = 25_000_000;

/// The grid frame of a VLMaps map of `rows x cols` cells of `cell_size` metres,
/// in the frame anchored on the first pose (see the module docs): VLMaps puts a point
/// (right `x`, forward `y`) of that frame in row `rows/2 - int(y/cs)` and column
/// `cols/2 + int(x/cs)` (`pos2grid_id`, `base_pos2grid_id_3d`; `/2` integer division,
/// `int` truncating toward zero). This frame reproduces that exactly for points east
/// and north of the origin; VLMaps' truncation makes its centre row and column two
/// cells wide, so its cells west and south of the origin sit one cell closer to the
/// centre than here.
pub fn vlmaps_grid_frame(rows: usize, cols: usize, cell_size: f64) -> GridFrame {
    GridFrame {
        origin: map_core::geometry::Point::new(
            -((cols / 2) as f64) * cell_size,
            ((rows / 2) as f64 + 1.0) * cell_size,
        ),
        cell_size,
        rows,
        cols,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn k_forms_and_errors_name_fields() {
        let base = r#"{"format": "ivlmap-rgbd/1", "camera_height": 1.5, "#;
        let c = CameraInfo::from_json_str(
            &format!("{base}\"K\": [540, 0, 540, 0, 540, 360, 0, 0, 1]}}"),
            "camera.json",
        )
        .unwrap();
        assert_eq!(c.intrinsics, Intrinsics::new(540.0, 540.0, 540.0, 360.0));
        assert_eq!(c.pose_convention, PoseConvention::HabitatBase);
        let c2 = CameraInfo::from_json_str(
            &format!("{base}\"K\": [[540, 0, 540], [0, 540, 360], [0, 0, 1]]}}"),
            "camera.json",
        )
        .unwrap();
        assert_eq!(c, c2);
        let h = CameraInfo::from_json_str(
            &format!("{base}\"width\": 160, \"height\": 120, \"hfov_deg\": 90}}"),
            "camera.json",
        )
        .unwrap();
        assert!((h.intrinsics.fx - 80.0).abs() < 1e-9 && h.intrinsics.cy == 60.0);

        let e = CameraInfo::from_json_str(
            &format!("{base}\n\"intrinsics\": {{\"fx\": -1, \"fy\": 1, \"cx\": 0, \"cy\": 0}}}}"),
            "cam/camera.json",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("cam/camera.json:2") && e.contains("intrinsics.fx"),
            "{e}"
        );
        let e = CameraInfo::from_json_str(&format!("{base}\"K\": [1, 2, 3]}}"), "camera.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("field `K`"), "{e}");
        let e = CameraInfo::from_json_str(
            &format!("{base}\"hfov_deg\": 90, \"pose_convention\": \"sideways\"}}"),
            "camera.json",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("pose_convention") && e.contains("habitat_base"),
            "{e}"
        );
    }

    #[test]
    fn json_roundtrip() {
        let mut c = CameraInfo::vlmaps_habitat();
        c.intrinsics.pixel_center = 0.0;
        let back = CameraInfo::from_json_str(&c.to_json_string(), "x.json").unwrap();
        assert_eq!(back, c);
        c.map = Some(MapSpec::Bounds {
            bounds: [0.0, 0.0, 12.0, 9.0],
            cell_size: 0.05,
        });
        c.anchor = Anchor::World;
        let back = CameraInfo::from_json_str(&c.to_json_string(), "x.json").unwrap();
        assert_eq!(back, c);
    }

    #[test]
    fn backproject_then_project_is_identity() {
        let k = Intrinsics::new(80.0, 80.0, 80.0, 60.0);
        let p = k.backproject(10.0, 100.0, 2.5);
        let (u, v) = k.project(&p).unwrap();
        assert!((u - 10.0).abs() < 1e-9 && (v - 100.0).abs() < 1e-9);
        // the image centre lies on the optical axis with VLMaps' +0.5 convention
        let c = k.backproject(79.5, 59.5, 1.0);
        assert!(c.x.abs() < 1e-12 && c.y.abs() < 1e-12);
    }

    #[test]
    fn vlmaps_frame_matches_pos2grid_id_east_and_north() {
        let (gs, cs) = (1000usize, 0.05);
        let f = vlmaps_grid_frame(gs, gs, cs);
        // VLMaps: row = gs/2 - int(y/cs), col = gs/2 + int(x/cs)
        for &(x, y) in &[(0.01, 0.01), (1.23, 4.56), (7.0 + 0.02, 0.3)] {
            let c = f.cell_at(map_core::geometry::Point::new(x, y)).unwrap();
            let row = gs / 2 - (y / cs) as usize;
            let col = gs / 2 + (x / cs) as usize;
            assert_eq!((c.row, c.col), (row, col), "({x}, {y})");
        }
    }
}
