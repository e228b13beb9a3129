//! # map_core: the IVLMap core
//!
//! An instance-level semantic grid map (IVLMap): obstacle, category, instance (U)
//! and colour (V) layers plus an instance table, built from a scene file; the
//! instance queries the robot function library relies on ("the third yellow
//! table"), goal points for spatial words, an A* planner with any-angle smoothing,
//! and a `Robot` trait with a simulated robot that records its trajectory.
//!
//! Conventions: world frame in metres, x east, y north; headings on the compass
//! (0 north, 90 east, clockwise positive); grid row 0 is the north edge.
//!
//! ```
//! use map_core::{Point, GridFrame};
//! let frame = GridFrame::from_bounds([0.0, 0.0, 10.0, 5.0], 0.05);
//! assert_eq!((frame.rows, frame.cols), (100, 200));
//! let cell = frame.cell_at(Point::new(0.01, 4.99)).unwrap();
//! assert_eq!((cell.row, cell.col), (0, 0)); // north-west corner
//! ```

mod embed;
mod geometry;
mod goals;
mod grid;
mod map;
mod matcher;
mod npy;
mod perception;
mod persist;
mod planner;
mod query;
mod reconstruct;
mod render;
mod robot;
mod scene;

pub use crate::embed::{
    label_cells, models_dir, ort_library_path, CellLabels, EmbedError, EmbeddingMatcher,
    Embeddings, FeatureMap, TextEncoder, TextEncoderOptions, DEFAULT_EMBEDDING_THRESHOLD,
    MINILM_MODEL_FILE, MINILM_TOKENIZER_FILE, MODELS_ENV, ORT_LIB_ENV, ORT_LIB_FILE,
};
pub use crate::geometry::{
    closest_on_segment, normalize_heading, oriented_rect, Aabb, Point, Polygon, Pose,
};
pub use crate::goals::{
    approach_point, between_point, closest_points, face_heading, heading_with_object_on,
    lateral_point, region_point, side_point, Side, SIDE_CLEARANCE_M,
};
pub use crate::grid::{Cell, Grid, GridFrame};
pub use crate::map::{Instance, IvlMap, Region};
pub use crate::matcher::{
    canonical, is_colour_word, normalize, plural, singular, LexicalMatcher, NameMatcher,
    COLOUR_WORDS,
};
pub use crate::npy::{read_npy, read_npy_from, write_npy, write_npy_to, NpyElement, NpyError};
pub use crate::perception::{
    ciede2000, eq2_scores, label_masks, read_sam_masks, sam_masks_from_str, srgb_to_lab,
    unique_labels, write_sam_masks, write_sam_masks_to, BuildConfig, BuiltMap, ColourClassifier,
    ColourConfig, ColourEvidence, ColourPalette, DropReason, DroppedMask, KeptMask, LabelConfig,
    LabelMap, LabelScore, Labelling, Mask, MaskColour, MaskLabel, MaskLocation, NoiseError,
    NoiseLog, PaletteColour, PerceptionError, PerceptionInputs, PerceptionNoise, Rle, RleError,
    SamMask, SegmentationForm, BASIC_COLOURS, BASIC_EXTRA_PROTOTYPES, DEFAULT_MERGE_RADIUS_M,
    DEFAULT_ROBOT_RADIUS_M, FLOOR_RGB, MAX_MASK_CELLS, OTHER,
};
pub use crate::persist::{JsonLocation, PersistError, MAP_FORMAT};
pub use crate::planner::{
    astar, inflate, inflate_m, line_of_sight, octile, polyline_len, supercover_cells, GridPath,
    GridPlanner, Passability, PlanError, WorldPath,
};
pub use crate::query::{ordinal_word, ObjectOrder, QueryError};
pub use crate::reconstruct::{
    base_from_pose2d, fortran_to_c, import_vlmaps_legacy, map_frame, parse_poses_txt,
    pose2d_from_base, read_depth, read_poses_txt, read_rgb_png, reconstruct,
    reconstruct_with_progress, render_rgbd, vlmaps_grid_frame, world_poses, write_depth_npy,
    write_depth_png, write_poses_txt, write_rgb_png, write_vlmaps_legacy, Anchor, CameraInfo,
    FeatureGrid, FrameFiles, FramePose, Intrinsics, MapSpec, PoseConvention, ReconstructError,
    ReconstructOptions, RgbdDataset, RgbdFrame, RgbdRenderer, SyntheticOptions, TopDownBuilder,
    TopDownMaps, VlmapsCrop, VlmapsImportOptions, VlmapsLegacyMap, VlmapsWindow, WorldPoses,
    DEFAULT_OBJECT_HEIGHT, RGBD_FORMAT,
};
pub use crate::render::{
    auto_scale, colour_rgb, render_png, render_rgb, render_trajectory_png, RenderError,
    RenderOptions, RenderOverlay, FINAL_RGB, MAX_SIDE_PX, PALETTE, PATH_RGB, START_RGB, STOP_RGB,
    UNKNOWN_RGB, WALL_RGB,
};
pub use crate::robot::{
    MoveReport, Robot, RobotError, SimRobot, Stop, StopTarget, Trajectory, MAX_FORWARD_M,
};
pub use crate::scene::{Scene, SceneError, SceneLocation, SceneObject, SCENE_FORMAT};
