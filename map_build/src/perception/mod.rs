//! Map building from perception outputs (paper Section III-A/B): SAM masks, a
//! per-cell category label map and a top-down RGB map become an [`IvlMap`] with
//! instances, their categories (Eq. 2), counting ids and colours.
//!
//! The pieces, each usable alone:
//!
//! | step | API | input -> output |
//! |---|---|---|
//! | read SAM output | [`read_sam_masks`], [`sam_masks_from_str`] | SAM JSON (compressed/uncompressed COCO RLE or boolean rows) -> [`SamMask`]s |
//! | write SAM output | [`write_sam_masks`] | [`SamMask`]s -> SAM JSON in a [`SegmentationForm`] |
//! | masks | [`Mask`], [`Rle`] | row-major runs; COCO RLE encode/decode |
//! | Eq. 2 | [`label_masks`] with [`LabelConfig`] | [`LabelMap`] + masks -> [`Labelling`] (kept [`MaskLabel`]s, [`DroppedMask`]s with a [`DropReason`]) |
//! | colour | [`ColourClassifier`] with [`ColourConfig`] / [`ColourPalette`] | RGB pixels of a mask -> [`MaskColour`] |
//! | assembly | [`build_map`] with [`BuildConfig`] | [`PerceptionInputs`] -> [`BuiltMap`] (map + kept + dropped) |
//! | simulated perception | [`PerceptionInputs::from_scene`] | a scene -> the inputs a perfect perception stack would give |
//! | noise | [`PerceptionInputs::with_noise`] with [`PerceptionNoise`] | inputs -> corrupted inputs + [`NoiseLog`] (label flips, split/merged/dropped masks, colour shifts; seeded) |
//!
//! Conventions: every layer and mask is on the map's [`GridFrame`] (row 0 = north
//! edge, column 0 = west edge; a bird's-eye image's pixel (x, y) is cell (row y,
//! col x)). A label map cell holds the index of its category in the category list
//! (the argmax of the pixel-text similarity); [`LabelConfig::background`] lists the
//! labels that are no object (default label 0, "other"). Instance ids are
//! `mask index + 1`, so `map.instance` cells point back at SAM's masks.
//!
//! A caller with files (the `ivlmap map build` command, the RGB-D reconstruction):
//!
//! ```no_run
//! use map_build::perception::{build_map, read_sam_masks, BuildConfig, LabelMap, PerceptionInputs};
//! use map_core::npy::read_npy;
//! use map_core::GridFrame;
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let labels = read_npy::<u16>("labels.npy")?; // argmax of the pixel-text similarity
//! let categories: Vec<String> = vec!["other".into(), "sofa".into(), "table".into()];
//! let frame = GridFrame::from_bounds([0.0, 0.0, 50.0, 50.0], 0.05);
//! let obstacles = read_npy::<bool>("obstacles.npy")?;
//! let masks = read_sam_masks("masks.json")?
//!     .into_iter()
//!     .map(|m| m.segmentation)
//!     .collect();
//! let mut inputs = PerceptionInputs::new(
//!     "flat",
//!     frame,
//!     obstacles,
//!     LabelMap::new(labels, categories)?,
//!     masks,
//! );
//! inputs.rgb = Some(map_build::reconstruct::read_rgb_png("topdown.png")?); // the paper's B
//! let built = build_map(&inputs, &BuildConfig::default())?;
//! for d in &built.dropped {
//!     eprintln!("mask {}: {}", d.mask, d.reason);
//! }
//! built.map.save("out/map")?;
//! # Ok(())
//! # }
//! ```
//!
//! A scene as perfect perception, then built back (a noise study corrupts
//! `inputs` in between):
//!
//! ```
//! use map_core::{IvlMap, Scene};
//! use map_build::perception::{build_map, BuildConfig, PerceptionInputs};
//! let scene = Scene::from_json_str(
//!     r#"{"format": "ivlmap-scene/1", "name": "t", "bounds": [0, 0, 4, 3], "cell_size": 0.05,
//!         "objects": [{"id": 7, "category": "sofa", "colour": "red",
//!                      "center": [2.0, 1.5], "size": [1.6, 0.8]}],
//!         "robot": {"pose": [0.5, 0.5, 0], "radius": 0.2}}"#,
//!     "t.scene.json",
//! )
//! .unwrap();
//! let inputs = PerceptionInputs::from_scene(&scene);
//! let built = build_map(&inputs, &BuildConfig::default()).unwrap();
//! let sofa = &built.map.instances[0];
//! assert_eq!((sofa.label.as_str(), sofa.colour.as_deref()), ("sofa", Some("red")));
//! assert_eq!(sofa.id, 1); // mask 0
//! ```

mod assemble;
mod colour;
mod error;
mod labelling;
mod mask;
mod noise;
mod sam;

pub use assemble::{
    build_map, BuildConfig, BuiltMap, ColourEvidence, KeptMask, PerceptionInputs,
    DEFAULT_ROBOT_RADIUS_M, FLOOR_RGB, OTHER,
};
pub use colour::{
    ciede2000, srgb_to_lab, ColourClassifier, ColourConfig, ColourPalette, MaskColour,
    PaletteColour, BASIC_COLOURS, BASIC_EXTRA_PROTOTYPES,
};
pub use error::{MaskLocation, PerceptionError};
pub use labelling::{
    eq2_scores, label_masks, unique_labels, DropReason, DroppedMask, LabelConfig, LabelMap,
    LabelScore, Labelling, MaskLabel,
};
pub use mask::{Mask, Rle, RleError, MAX_MASK_CELLS};
pub use noise::{NoiseError, NoiseLog, PerceptionNoise, DEFAULT_MERGE_RADIUS_M};
pub use sam::{
    read_sam_masks, sam_masks_from_str, write_sam_masks, write_sam_masks_to, SamMask,
    SegmentationForm,
};

#[cfg(doc)]
use map_core::{GridFrame, IvlMap};
