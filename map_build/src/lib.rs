//! # map_build: IVLMaps from data
//!
//! The offline toolchain that turns what a robot saw into a [`map_core::IvlMap`]
//! (the paper's Sec. III-A): nothing at run time depends on this crate.
//!
//! - [`perception`]: SAM masks (COCO RLE), Eq. 2 labelling of masks against a
//!   per-cell label map, the CIELAB colour attribute, and
//!   [`perception::build_map`], which assembles the instance table; simulated
//!   perception noise for robustness studies.
//! - [`reconstruct`]: RGB-D frames back-projected into bird's-eye colour, height and
//!   obstacle maps (Eq. 1), camera and pose conventions, VLMaps' legacy map import
//!   and export.
//! - [`embed`]: an ONNX text encoder (all-MiniLM-L6-v2 or a CLIP text tower, through
//!   ONNX Runtime loaded at run time): embedding-based name matching and the
//!   `P = Q x E^T` labelling of a VLMaps feature map.
//!
//! ```
//! use map_build::perception::{build_map, BuildConfig, PerceptionInputs};
//! use map_core::Scene;
//! let scene = Scene::from_json_str(
//!     r#"{"format": "ivlmap-scene/1", "name": "t", "bounds": [0, 0, 4, 3],
//!         "objects": [{"id": 7, "category": "sofa", "colour": "red",
//!                      "center": [2.0, 1.5], "size": [1.6, 0.8]}],
//!         "robot": {"pose": [0.5, 0.5, 0], "radius": 0.2}}"#,
//!     "t.scene.json",
//! )
//! .unwrap();
//! let built = build_map(&PerceptionInputs::from_scene(&scene), &BuildConfig::default()).unwrap();
//! assert_eq!(built.map.instances[0].label, "sofa");
//! ```

#![warn(missing_docs)]

pub mod embed;
pub mod perception;
pub mod reconstruct;
