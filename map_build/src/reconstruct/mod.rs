//! Bird's-eye reconstruction from RGB-D frames (the paper's Section III-A, Eq. 1:
//! the 3-D reconstruction map B and height map H) and VLMaps interop.
//!
//! # Dataset folder (`ivlmap-rgbd/1`)
//!
//! ```text
//! DATASET/
//!   camera.json        intrinsics, depth units, pose convention, camera height, map
//!   poses.txt          one pose per frame, in file-name order
//!   rgb/000000.png     colour (8-bit grey/RGB/RGBA PNG)
//!   depth/000000.npy   depth: float32/float64 metres, or integer units / depth_scale,
//!                      shape (H, W) or (H, W, 1); or depth/000000.png, 16-bit grey
//! ```
//!
//! Frames pair up by file stem (`rgb/000007.png` with `depth/000007.npy`) and are
//! taken in sorted order; `poses.txt` has exactly one pose per frame. This is VLMaps'
//! own dataset layout (`rgb/`, `depth/`, `poses.txt`) plus `camera.json`; a VLMaps
//! Habitat dataset without one opens with [`RgbdDataset::open_with`] and
//! [`CameraInfo::vlmaps_habitat`].
//!
//! `camera.json`:
//! ```json
//! {
//!   "format": "ivlmap-rgbd/1",
//!   "width": 160, "height": 120,
//!   "intrinsics": {"fx": 80, "fy": 80, "cx": 80, "cy": 60},
//!   "pixel_center": 0.5,
//!   "depth_scale": 1000,
//!   "pose_convention": "habitat_base",
//!   "camera_height": 1.5,
//!   "anchor": "world",
//!   "map": {"bounds": [0, 0, 12, 9], "cell_size": 0.05}
//! }
//! ```
//! - intrinsics: exactly one of `"intrinsics": {fx, fy, cx, cy}`, `"K"` (3x3 nested,
//!   or 9 numbers row-major as VLMaps' `cam_calib_mat`) or `"hfov_deg"` (needs
//!   `width`/`height`; Habitat's square-pixel, centred camera).
//! - `pixel_center` (optional, 0.5): pixel (u, v) is the ray through
//!   (u + pixel_center, v + pixel_center); 0.5 is VLMaps'/Habitat's convention, 0.0
//!   OpenCV's (calibrated K).
//! - `width`/`height` (optional): checked against every frame.
//! - `depth_scale` (optional, 1000): integer depth units per metre (1000 = mm);
//!   float depth is metres. Depth is distance along the optical axis (z), as Habitat
//!   and RGB-D cameras give it; 0 or non-finite = no reading.
//! - `pose_convention` (optional, `habitat_base`): see [`PoseConvention`]:
//!   `habitat_base` (VLMaps' Habitat agent poses, y-up world), `ros_base` (the paper's
//!   real robot: base pose in a z-up ENU world) or `camera_opencv`.
//! - `camera_height` (required): camera above the floor under the base, metres.
//! - `anchor` (optional, `world`): `world` keeps the poses' world (mapped onto ivlmap
//!   axes); `first_frame` re-centres on the first base pose, facing north (VLMaps).
//! - `map` (optional): `{"bounds": [xmin, ymin, xmax, ymax], "cell_size": 0.05}`, or
//!   `{"grid_size": 1000, "cell_size": 0.05}` (VLMaps' square grid, see
//!   [`vlmaps_grid_frame`]), or `{"cell_size": 0.05}` alone (auto: every camera
//!   position +- the maximum depth). [`ReconstructOptions::map`] overrides it.
//!
//! `poses.txt`: per line `px py pz qx qy qz qw` (VLMaps' format; scipy's x-y-z-w
//! quaternion order), or 16 numbers of a row-major 4x4 pose (VLMaps' `rot_type:
//! mat`); spaces, tabs or commas; blank lines and `#` comments skipped. Errors say
//! `poses.txt line N: ...`.
//!
//! # Frames and axes
//! The ivlmap world is x east, y north, z up; the grid has row 0 at the north edge
//! and 0.05 m cells by default. Camera frame = OpenCV optical frame (x right, y down,
//! z forward); base frame = x forward, y left, z up. For `habitat_base`, Habitat
//! (x, y, z) maps to ivlmap (x, -z, y): Habitat's -z (the direction an unrotated
//! agent faces) is north and its y is up. VLMaps itself places the first pose's
//! forward direction at the top of its grid (row `gs/2 - int(forward/cs)`, column
//! `gs/2 + int(right/cs)`): with `anchor: first_frame` our grid is the same, with no
//! flip or transpose.
//!
//! # Eq. 1 and the layers
//! Every `stride`-th pixel with a depth in [min_depth, max_depth] is back-projected
//! (`K^-1 (u + 0.5, v + 0.5, 1) * d`), moved into the map frame by the camera pose,
//! and dropped into the cell under its (x, y) ([`map_core::grid::GridFrame::cell_at`]: the
//! paper's Eq. 1 up to the grid origin). Its height is z minus the floor (the first
//! frame's base z). Points at or above the robot height h (default the camera
//! height), or lower than -floor_margin, are ignored. Per cell:
//! - `rgb`, `height` (the paper's B and H): the colour and height of the highest
//!   point kept (VLMaps: the colour of the highest point under the height limit);
//! - `obstacles`: at least `min_obstacle_points` (1) points from `floor_margin`
//!   (0.1 m) up to h;
//! - `hits` (all points kept) and `obstacle_hits` (those in the obstacle band).
//!
//! # Public API (for the CLI)
//! ```no_run
//! use map_build::reconstruct::{reconstruct, ReconstructOptions, RgbdDataset};
//! # fn main() -> Result<(), map_build::reconstruct::ReconstructError> {
//! let ds = RgbdDataset::open("data/flat-a")?;          // camera.json + poses.txt + rgb/ + depth/
//! let maps = reconstruct(&ds, &ReconstructOptions::default())?;
//! maps.write_rgb_png("topdown.png", [255, 255, 255])?;  // B, the image SAM segments
//! map_build::reconstruct::write_vlmaps_legacy("vlmaps_map", &maps, 1)?;
//! # Ok(()) }
//! ```
//! - Reading: [`RgbdDataset::open`] / [`RgbdDataset::open_with`],
//!   [`RgbdDataset::load_frame`], [`RgbdDataset::world_poses`]; [`CameraInfo`]
//!   (`from_path`, `write`), [`read_poses_txt`], [`read_rgb_png`], [`read_depth`].
//! - Reconstruction: [`reconstruct`], [`reconstruct_with_progress`],
//!   [`ReconstructOptions`], [`TopDownMaps`] (`crop_to_observed`, `rgb_image`,
//!   `write_rgb_png`), [`TopDownBuilder`] for other frame sources, [`map_frame`].
//! - Poses: [`PoseConvention`], [`Anchor`], [`world_poses`], [`base_from_pose2d`],
//!   [`pose2d_from_base`], [`write_poses_txt`].
//! - Synthetic data: [`RgbdRenderer`], [`render_rgbd`], [`RgbdDataset::write`].
//! - VLMaps legacy maps: [`import_vlmaps_legacy`] -> [`VlmapsLegacyMap`] (obstacles,
//!   colour, [`FeatureGrid`] of LSeg features, weights, GT classes) and
//!   [`write_vlmaps_legacy`].

mod birdseye;
mod camera;
mod frames;
mod poses;
mod synthetic;
mod vlmaps;

use std::path::PathBuf;

pub use birdseye::{
    map_frame, reconstruct, reconstruct_with_progress, ReconstructOptions, TopDownBuilder,
    TopDownMaps,
};
pub use camera::{vlmaps_grid_frame, CameraInfo, Intrinsics, MapSpec, RGBD_FORMAT};
pub use frames::{
    read_depth, read_rgb_png, write_depth_npy, write_depth_png, write_rgb_png, FrameFiles,
    RgbdDataset, RgbdFrame,
};
pub use poses::{
    base_from_pose2d, parse_poses_txt, pose2d_from_base, read_poses_txt, world_poses,
    write_poses_txt, Anchor, FramePose, PoseConvention, WorldPoses,
};
pub use synthetic::{render_rgbd, RgbdRenderer, SyntheticOptions, DEFAULT_OBJECT_HEIGHT};
pub use vlmaps::{
    import_vlmaps_legacy, write_vlmaps_legacy, FeatureGrid, VlmapsCrop, VlmapsImportOptions,
    VlmapsLegacyMap, VlmapsWindow,
};

/// Why a dataset, a VLMaps map or a reconstruction failed; every variant names the
/// file (and line or field where there is one).
#[derive(Debug, thiserror::Error)]
pub enum ReconstructError {
    /// A file or folder could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// An image could not be decoded or encoded.
    #[error("{}: {source}", path.display())]
    Image {
        /// The image file.
        path: PathBuf,
        /// The underlying image error.
        #[source]
        source: image::ImageError,
    },
    /// `camera.json` is malformed: `field` is a path such as `intrinsics.fx`.
    #[error("{}{}{}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default(), if field.is_empty() { String::new() } else { format!(": field `{field}`") })]
    Camera {
        /// The `camera.json` file.
        path: PathBuf,
        /// 1-based line of the problem, where known.
        line: Option<usize>,
        /// The offending field; empty when the problem is not in one field.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// A `poses.txt` line is malformed (1-based line number).
    #[error("{} line {line}: {message}", path.display())]
    Poses {
        /// The `poses.txt` file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// An array or image has the wrong shape or dtype (expected vs found).
    #[error("{}: {message}", path.display())]
    Array {
        /// The array or image file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A `.npy` file could not be read or written.
    #[error(transparent)]
    Npy(#[from] map_core::npy::NpyError),
    /// The folder's files do not fit together (missing pairs, pose count, sizes).
    #[error("{}: {message}", path.display())]
    Dataset {
        /// The dataset folder, or the file that does not fit.
        path: PathBuf,
        /// What does not fit.
        message: String,
    },
    /// Reconstruction or import options out of range.
    #[error("invalid options: {0}")]
    Options(String),
}
