//! VLMaps' legacy map files (the `map/` folder its original
//! `create_lseg_map_batch` writes, which IVLMap builds on): read them onto an
//! ivlmap grid, and write our top-down layers in the same form.
//!
//! | file | dtype, shape | meaning |
//! |---|---|---|
//! | `obstacles.npy` | uint8 (gs, gs) | 1 = free, 0 = occupied (bool, other ints and floats accepted: non-zero = free) |
//! | `color_top_down_{v}.npy` | uint8 (gs, gs, 3) | RGB of the highest point per cell |
//! | `grid_lseg_{v}.npy` | float32 (gs, gs, C), C = 512 for LSeg/CLIP ViT-B/32 | averaged pixel features per cell |
//! | `weight_lseg_{v}.npy` | float64 (gs, gs) | feature count per cell |
//! | `grid_{v}_gt.npy` (or `grid_gt_{v}.npy`) | int32 (gs, gs) | ground-truth class id per cell |
//!
//! `{v}` is VLMaps' `mask_version` (1 in its code; 0 is tried when no `_1` file exists).
//! Rows and columns: VLMaps indexes `grid[row, col]` with row `gs/2 - int(forward/cs)`
//! and column `gs/2 + int(right/cs)` in the frame of the first camera/base pose, so
//! row 0 is the far-forward edge and columns grow to the right: exactly ivlmap's
//! "row 0 north, column 0 west" once the first pose's forward is called north. No
//! flip or transpose is needed; the frame comes from [`vlmaps_grid_frame`] (the
//! reconstruction's `anchor: first_frame` frame) unless an origin is given.
//!
//! VLMaps' legacy builder writes 0 into `obstacles.npy` for every point that is not
//! below the floor (`if p_local[1] > camera_height: continue`), and newer VLMaps
//! thresholds a voxel map between 0 and 1.5 m; the import keeps whichever it is given.

use std::path::{Path, PathBuf};

use super::birdseye::{crop, TopDownMaps};
use super::camera::vlmaps_grid_frame;
use super::ReconstructError;
use crate::embed::{EmbedError, FeatureMap};
use map_core::geometry::Point;
use map_core::grid::{Cell, Grid, GridFrame};
use map_core::npy::nd::{self as ndnpy, shape_str, NdArray, NdData};
use map_core::npy::NpyError;

/// Which part of VLMaps' (usually 1000 x 1000, mostly empty) grid to keep.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VlmapsCrop {
    /// The whole grid.
    Full,
    /// The bounding box of the occupied cells grown by `margin` cells (VLMaps' own
    /// crop: `np.where(obstacles == 0)`); the whole grid when nothing is occupied.
    ObstacleBBox {
        /// Cells added on every side of the bounding box.
        margin: usize,
    },
    /// An explicit window of the full grid.
    Window {
        /// First row of the window (row 0 = north edge of the full grid).
        row0: usize,
        /// First column of the window (column 0 = west edge of the full grid).
        col0: usize,
        /// Number of rows kept.
        rows: usize,
        /// Number of columns kept.
        cols: usize,
    },
}

/// How to read a legacy map folder.
#[derive(Debug, Clone, PartialEq)]
pub struct VlmapsImportOptions {
    /// Metres per cell (VLMaps' `cs`). Default 0.05.
    pub cell_size: f64,
    /// The `_{v}` suffix; `None` = 1, or 0 when only `_0` files exist.
    pub mask_version: Option<u32>,
    /// Default: `ObstacleBBox { margin: 10 }`.
    pub crop: VlmapsCrop,
    /// Load `grid_lseg_{v}.npy` (the largest file). Default true.
    pub features: bool,
    /// World position of the full grid's north-west corner; `None` =
    /// [`vlmaps_grid_frame`]'s (the first pose at the origin, facing north).
    pub origin: Option<Point>,
}

impl Default for VlmapsImportOptions {
    fn default() -> Self {
        Self {
            cell_size: 0.05,
            mask_version: None,
            crop: VlmapsCrop::ObstacleBBox { margin: 10 },
            features: true,
            origin: None,
        }
    }
}

/// Per-cell feature vectors, row-major `[row][col][channel]`, for the later
/// P = Q x E^T labelling (Q: cell features, E: text embeddings).
#[derive(Debug, Clone, PartialEq)]
pub struct FeatureGrid {
    /// Number of grid rows (row 0 = north edge).
    pub rows: usize,
    /// Number of grid columns.
    pub cols: usize,
    /// Feature length C.
    pub dim: usize,
    /// The `rows * cols * dim` values, row-major, cell by cell.
    pub data: Vec<f32>,
}

impl FeatureGrid {
    /// The feature vector of `cell`.
    pub fn cell(&self, cell: Cell) -> Option<&[f32]> {
        if cell.row >= self.rows || cell.col >= self.cols {
            return None;
        }
        let i = (cell.row * self.cols + cell.col) * self.dim;
        self.data.get(i..i + self.dim)
    }

    /// `[rows, cols, dim]`.
    pub fn shape(&self) -> [usize; 3] {
        [self.rows, self.cols, self.dim]
    }

    /// The same values as the embedding layer's [`FeatureMap`] (same row-major,
    /// cell-by-cell layout), ready for [`label_cells`](crate::embed::label_cells).
    pub fn into_feature_map(self) -> Result<FeatureMap, EmbedError> {
        FeatureMap::new(self.rows, self.cols, self.dim, self.data)
    }
}

/// The part of the full grid that was kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VlmapsWindow {
    /// First kept row of the full grid (row 0 = north edge).
    pub row0: usize,
    /// First kept column of the full grid (column 0 = west edge).
    pub col0: usize,
    /// Number of rows kept.
    pub rows: usize,
    /// Number of columns kept.
    pub cols: usize,
    /// Shape of the full grid in the files.
    pub full_rows: usize,
    /// Number of columns of the full grid in the files.
    pub full_cols: usize,
}

/// A legacy VLMaps map on an ivlmap grid (row 0 north).
#[derive(Debug, Clone, PartialEq)]
pub struct VlmapsLegacyMap {
    /// The frame of the kept window.
    pub frame: GridFrame,
    /// Which part of the full grid was kept.
    pub window: VlmapsWindow,
    /// The `_{v}` suffix of the files read.
    pub mask_version: u32,
    /// True where `obstacles.npy` is 0.
    pub obstacles: Grid<bool>,
    /// `color_top_down_{v}.npy`, if present.
    pub rgb: Option<Grid<[u8; 3]>>,
    /// `grid_lseg_{v}.npy`, if present and asked for.
    pub features: Option<FeatureGrid>,
    /// `weight_lseg_{v}.npy`, if present.
    pub weight: Option<Grid<f32>>,
    /// `grid_{v}_gt.npy` / `grid_gt_{v}.npy`, if present.
    pub gt_classes: Option<Grid<i32>>,
    /// The files read, in order.
    pub files: Vec<PathBuf>,
}

fn arr_err(path: &Path, message: String) -> ReconstructError {
    ReconstructError::Array {
        path: path.to_path_buf(),
        message,
    }
}

fn hw(arr: &NdArray, path: &Path, what: &str) -> Result<(usize, usize), ReconstructError> {
    match arr.shape[..] {
        [h, w] => Ok((h, w)),
        _ => Err(arr_err(
            path,
            format!(
                "expected {what} of shape (H, W), found {} of {}",
                arr.shape_str(),
                arr.dtype
            ),
        )),
    }
}

fn check_hw(
    path: &Path,
    found: (usize, usize),
    want: (usize, usize),
    dtype: &str,
) -> Result<(), ReconstructError> {
    if found == want {
        Ok(())
    } else {
        Err(arr_err(
            path,
            format!(
                "expected H x W = {} x {} as in obstacles.npy, found {} x {} (dtype {dtype})",
                want.0, want.1, found.0, found.1
            ),
        ))
    }
}

/// Read a legacy VLMaps map folder (`obstacles.npy` required, the rest optional).
pub fn import_vlmaps_legacy(
    dir: impl AsRef<Path>,
    opts: &VlmapsImportOptions,
) -> Result<VlmapsLegacyMap, ReconstructError> {
    let dir = dir.as_ref();
    if !(opts.cell_size.is_finite() && opts.cell_size > 0.0) {
        return Err(ReconstructError::Options(format!(
            "cell_size must be > 0, got {}",
            opts.cell_size
        )));
    }
    let mut files = Vec::new();
    let obs_path = dir.join("obstacles.npy");
    if !obs_path.is_file() {
        return Err(ReconstructError::Dataset {
            path: dir.to_path_buf(),
            message: "no obstacles.npy here (a VLMaps legacy map folder holds obstacles.npy, color_top_down_1.npy, grid_lseg_1.npy, weight_lseg_1.npy)".into(),
        });
    }
    let obs = ndnpy::read_array(&obs_path)?;
    let (h, w) = hw(&obs, &obs_path, "an obstacle map (1 = free, 0 = occupied)")?;
    let free: Vec<bool> = obs.to_f64().into_iter().map(|v| v != 0.0).collect();
    files.push(obs_path.clone());

    let v = opts.mask_version.unwrap_or_else(|| {
        let has = |v: u32| {
            dir.join(format!("color_top_down_{v}.npy")).is_file()
                || dir.join(format!("grid_lseg_{v}.npy")).is_file()
        };
        if !has(1) && has(0) {
            0
        } else {
            1
        }
    });

    // the window
    let full = (h, w);
    let (row0, col0, rows, cols) = match opts.crop {
        VlmapsCrop::Full => (0, 0, h, w),
        VlmapsCrop::Window {
            row0,
            col0,
            rows,
            cols,
        } => {
            if rows == 0 || cols == 0 || row0 + rows > h || col0 + cols > w {
                return Err(ReconstructError::Options(format!(
                    "crop window rows {row0}..{} cols {col0}..{} does not fit the {h} x {w} grid of {}",
                    row0 + rows,
                    col0 + cols,
                    obs_path.display()
                )));
            }
            (row0, col0, rows, cols)
        }
        VlmapsCrop::ObstacleBBox { margin } => {
            let (mut r0, mut r1, mut c0, mut c1) = (usize::MAX, 0, usize::MAX, 0);
            for (i, &f) in free.iter().enumerate() {
                if !f {
                    let (r, c) = (i / w, i % w);
                    r0 = r0.min(r);
                    r1 = r1.max(r);
                    c0 = c0.min(c);
                    c1 = c1.max(c);
                }
            }
            if r0 == usize::MAX {
                (0, 0, h, w)
            } else {
                let (r0, c0) = (r0.saturating_sub(margin), c0.saturating_sub(margin));
                let (r1, c1) = ((r1 + margin).min(h - 1), (c1 + margin).min(w - 1));
                (r0, c0, r1 - r0 + 1, c1 - c0 + 1)
            }
        }
    };
    let window = VlmapsWindow {
        row0,
        col0,
        rows,
        cols,
        full_rows: h,
        full_cols: w,
    };
    let cs = opts.cell_size;
    let full_frame = match opts.origin {
        Some(origin) => GridFrame {
            origin,
            cell_size: cs,
            rows: h,
            cols: w,
        },
        None => vlmaps_grid_frame(h, w, cs),
    };
    let frame = GridFrame {
        origin: Point::new(
            full_frame.origin.x + col0 as f64 * cs,
            full_frame.origin.y - row0 as f64 * cs,
        ),
        cell_size: cs,
        rows,
        cols,
    };
    let obstacles = crop(
        &Grid::from_vec(h, w, free.into_iter().map(|f| !f).collect())
            .unwrap_or_else(|| Grid::new(h, w, false)),
        row0,
        col0,
        rows,
        cols,
    );

    // colour
    let rgb_path = dir.join(format!("color_top_down_{v}.npy"));
    let rgb = if rgb_path.is_file() {
        let a = ndnpy::read_array(&rgb_path)?;
        let NdData::U8(data) = &a.data else {
            return Err(arr_err(
                &rgb_path,
                format!(
                    "expected uint8 (|u1) RGB of shape (H, W, 3), found {} of {}",
                    a.shape_str(),
                    a.dtype
                ),
            ));
        };
        let [ah, aw, 3] = a.shape[..] else {
            return Err(arr_err(
                &rgb_path,
                format!(
                    "expected shape (H, W, 3) = {}, found {} of {}",
                    shape_str(&[h, w, 3]),
                    a.shape_str(),
                    a.dtype
                ),
            ));
        };
        check_hw(&rgb_path, (ah, aw), full, &a.dtype)?;
        let px: Vec<[u8; 3]> = data.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        files.push(rgb_path.clone());
        Some(crop(
            &Grid::from_vec(h, w, px).unwrap_or_else(|| Grid::new(h, w, [0; 3])),
            row0,
            col0,
            rows,
            cols,
        ))
    } else {
        None
    };

    // features
    let feat_path = dir.join(format!("grid_lseg_{v}.npy"));
    let features = if opts.features && feat_path.is_file() {
        let (shape, dim, data) = ndnpy::read_hwc_window_f32(&feat_path, row0, rows, col0, cols)
            .map_err(|e| match e {
                NpyError::Array { path, message } if message.contains("window") => {
                    ReconstructError::Array {
                        path,
                        message: format!("{message} (obstacles.npy is {h} x {w})"),
                    }
                }
                other => other.into(),
            })?;
        check_hw(&feat_path, (shape[0], shape[1]), full, "float32")?;
        files.push(feat_path.clone());
        Some(FeatureGrid {
            rows,
            cols,
            dim,
            data,
        })
    } else {
        None
    };

    // weights
    let weight_path = dir.join(format!("weight_lseg_{v}.npy"));
    let weight = if weight_path.is_file() {
        let a = ndnpy::read_array(&weight_path)?;
        let (ah, aw) = hw(&a, &weight_path, "feature weights")?;
        check_hw(&weight_path, (ah, aw), full, &a.dtype)?;
        if matches!(a.data, NdData::Bool(_)) {
            return Err(arr_err(
                &weight_path,
                format!("expected float64 weights, found {}", a.dtype),
            ));
        }
        let g: Vec<f32> = a.to_f64().into_iter().map(|x| x as f32).collect();
        files.push(weight_path.clone());
        Some(crop(
            &Grid::from_vec(h, w, g).unwrap_or_else(|| Grid::new(h, w, 0.0)),
            row0,
            col0,
            rows,
            cols,
        ))
    } else {
        None
    };

    // ground-truth classes
    let gt_path = [format!("grid_{v}_gt.npy"), format!("grid_gt_{v}.npy")]
        .into_iter()
        .map(|n| dir.join(n))
        .find(|p| p.is_file());
    let gt_classes = match gt_path {
        Some(p) => {
            let a = ndnpy::read_array(&p)?;
            let (ah, aw) = hw(&a, &p, "class ids")?;
            check_hw(&p, (ah, aw), full, &a.dtype)?;
            let ids: Vec<i32> = match &a.data {
                NdData::I32(v) => v.clone(),
                NdData::I64(v) => v
                    .iter()
                    .map(|&x| x.clamp(-1, i64::from(i32::MAX)) as i32)
                    .collect(),
                NdData::U8(v) => v.iter().map(|&x| i32::from(x)).collect(),
                NdData::U16(v) => v.iter().map(|&x| i32::from(x)).collect(),
                NdData::I16(v) => v.iter().map(|&x| i32::from(x)).collect(),
                _ => {
                    return Err(arr_err(
                        &p,
                        format!("expected int32 class ids, found {}", a.dtype),
                    ))
                }
            };
            files.push(p.clone());
            Some(crop(
                &Grid::from_vec(h, w, ids).unwrap_or_else(|| Grid::new(h, w, 0)),
                row0,
                col0,
                rows,
                cols,
            ))
        }
        None => None,
    };

    Ok(VlmapsLegacyMap {
        frame,
        window,
        mask_version: v,
        obstacles,
        rgb,
        features,
        weight,
        gt_classes,
        files,
    })
}

/// Write top-down layers as VLMaps legacy files: `obstacles.npy` (uint8, 1 = free,
/// 0 = obstacle) and `color_top_down_{mask_version}.npy` (uint8, H x W x 3). The grid
/// position is implicit in VLMaps' format: reading the files back with default
/// options places them by [`vlmaps_grid_frame`]; pass `origin` =
/// `maps.frame.origin` (with `VlmapsCrop::Full`) for any other frame.
pub fn write_vlmaps_legacy(
    dir: impl AsRef<Path>,
    maps: &TopDownMaps,
    mask_version: u32,
) -> Result<Vec<PathBuf>, ReconstructError> {
    let dir = dir.as_ref();
    std::fs::create_dir_all(dir).map_err(|source| ReconstructError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let (h, w) = (maps.frame.rows, maps.frame.cols);
    let obs: Vec<u8> = maps
        .obstacles
        .as_slice()
        .iter()
        .map(|&o| u8::from(!o))
        .collect();
    let obs_path = dir.join("obstacles.npy");
    ndnpy::write_array(&obs_path, &[h, w], &obs)?;
    let rgb: Vec<u8> = maps.rgb.as_slice().iter().flatten().copied().collect();
    let rgb_path = dir.join(format!("color_top_down_{mask_version}.npy"));
    ndnpy::write_array(&rgb_path, &[h, w, 3], &rgb)?;
    Ok(vec![obs_path, rgb_path])
}
