//! The bird's-eye reconstruction (the paper's Eq. 1 and its maps B and H): depth
//! pixels back-projected, moved into the map frame by the camera pose, and dropped
//! into grid cells; per cell the colour and height of the highest point below the
//! robot height, the number of points, and the obstacle mark.

use std::path::Path;

use nalgebra::{Isometry3, Point3};

use super::camera::{vlmaps_grid_frame, Intrinsics, MapSpec, MAX_CELLS};
use super::frames::{RgbdDataset, RgbdFrame};
use super::ReconstructError;
use map_core::geometry::Point;
use map_core::grid::{Cell, Grid, GridFrame};

/// Reconstruction settings; `Default` gives the documented defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct ReconstructOptions {
    /// Use every `stride`-th pixel along rows and columns (1 = every pixel). Default 4.
    /// VLMaps keeps a random 1/100 of the pixels; a regular stride is deterministic.
    pub stride: usize,
    /// Use every `frame_step`-th frame (VLMaps' `skip_frame`). Default 1.
    pub frame_step: usize,
    /// Depth readings outside [min_depth, max_depth] metres are skipped.
    /// Defaults 0.1 and 6.0 (VLMaps' `_backproject_depth` for mobile-base maps).
    pub min_depth: f64,
    /// Farthest depth reading used, metres (see `min_depth`).
    pub max_depth: f64,
    /// The paper's robot height h: points this high above the floor or higher
    /// (ceilings, lamps) are ignored for every layer. `None` = the camera height
    /// (VLMaps: voxels up to `camera_height`; obstacle band up to 1.5 m = its camera height).
    pub robot_height: Option<f64>,
    /// Points from `floor_margin` up to the robot height mark obstacles; points lower
    /// than `-floor_margin` (below the floor: depth noise, holes) are dropped.
    /// Default 0.1 m (VLMaps' obstacle band starts one 0.05 m voxel above the floor).
    pub floor_margin: f64,
    /// A cell is an obstacle with at least this many points in the obstacle band. Default 1.
    pub min_obstacle_points: u32,
    /// The grid; `None` = camera.json's `map`, else [`MapSpec::Auto`] with 0.05 m cells.
    pub map: Option<MapSpec>,
}

impl Default for ReconstructOptions {
    fn default() -> Self {
        Self {
            stride: 4,
            frame_step: 1,
            min_depth: 0.1,
            max_depth: 6.0,
            robot_height: None,
            floor_margin: 0.1,
            min_obstacle_points: 1,
            map: None,
        }
    }
}

/// The reconstructed top-down layers, all on `frame`.
#[derive(Debug, Clone, PartialEq)]
pub struct TopDownMaps {
    /// The grid every layer lies on.
    pub frame: GridFrame,
    /// The paper's B: colour of the highest point below the robot height; black where
    /// nothing was seen.
    pub rgb: Grid<[u8; 3]>,
    /// The paper's H: height (m above the floor) of that point; NaN where nothing was seen.
    pub height: Grid<f32>,
    /// Obstacle cells: at least `min_obstacle_points` points between the floor
    /// margin and the robot height.
    pub obstacles: Grid<bool>,
    /// Points that landed in each cell (any height kept: from `-floor_margin` up to
    /// the robot height). 0 = unobserved.
    pub hits: Grid<u32>,
    /// Points in the obstacle band.
    pub obstacle_hits: Grid<u32>,
    /// Frames integrated and points kept.
    pub frames: usize,
    /// Points that landed in a cell, over all frames (the sum of `hits`).
    pub points: u64,
}

impl TopDownMaps {
    /// Whether any point landed in `cell`.
    pub fn observed(&self, cell: Cell) -> bool {
        self.hits.get(cell).is_some_and(|&h| h > 0)
    }

    /// Number of observed cells.
    pub fn observed_count(&self) -> usize {
        self.hits.as_slice().iter().filter(|&&h| h > 0).count()
    }

    /// B as an image (what SAM segments), `unobserved` where nothing was seen.
    pub fn rgb_image(&self, unobserved: [u8; 3]) -> image::RgbImage {
        image::RgbImage::from_fn(self.frame.cols as u32, self.frame.rows as u32, |x, y| {
            let c = Cell::new(y as usize, x as usize);
            image::Rgb(if self.observed(c) {
                self.rgb.get(c).copied().unwrap_or(unobserved)
            } else {
                unobserved
            })
        })
    }

    /// Write B as a PNG.
    pub fn write_rgb_png(
        &self,
        path: impl AsRef<Path>,
        unobserved: [u8; 3],
    ) -> Result<(), ReconstructError> {
        let path = path.as_ref();
        self.rgb_image(unobserved)
            .save_with_format(path, image::ImageFormat::Png)
            .map_err(|source| ReconstructError::Image {
                path: path.to_path_buf(),
                source,
            })
    }

    /// The bounding box of the observed cells grown by `margin` cells, as a new map
    /// (its frame shifted accordingly); `None` if nothing was observed.
    pub fn crop_to_observed(&self, margin: usize) -> Option<TopDownMaps> {
        let (mut r0, mut r1, mut c0, mut c1) = (usize::MAX, 0, usize::MAX, 0);
        for (cell, &h) in self.hits.iter_cells() {
            if h > 0 {
                r0 = r0.min(cell.row);
                r1 = r1.max(cell.row);
                c0 = c0.min(cell.col);
                c1 = c1.max(cell.col);
            }
        }
        if r0 == usize::MAX {
            return None;
        }
        let r0 = r0.saturating_sub(margin);
        let c0 = c0.saturating_sub(margin);
        let r1 = (r1 + margin).min(self.frame.rows - 1);
        let c1 = (c1 + margin).min(self.frame.cols - 1);
        let (rows, cols) = (r1 - r0 + 1, c1 - c0 + 1);
        let cs = self.frame.cell_size;
        let frame = GridFrame {
            origin: Point::new(
                self.frame.origin.x + c0 as f64 * cs,
                self.frame.origin.y - r0 as f64 * cs,
            ),
            cell_size: cs,
            rows,
            cols,
        };
        Some(TopDownMaps {
            frame,
            rgb: crop(&self.rgb, r0, c0, rows, cols),
            height: crop(&self.height, r0, c0, rows, cols),
            obstacles: crop(&self.obstacles, r0, c0, rows, cols),
            hits: crop(&self.hits, r0, c0, rows, cols),
            obstacle_hits: crop(&self.obstacle_hits, r0, c0, rows, cols),
            frames: self.frames,
            points: self.points,
        })
    }
}

pub(crate) fn crop<T: Clone + Default>(
    g: &Grid<T>,
    r0: usize,
    c0: usize,
    rows: usize,
    cols: usize,
) -> Grid<T> {
    let mut out = Vec::with_capacity(rows * cols);
    for r in r0..r0 + rows {
        for c in c0..c0 + cols {
            out.push(g.get(Cell::new(r, c)).cloned().unwrap_or_default());
        }
    }
    Grid::from_vec(rows, cols, out).unwrap_or_else(|| Grid::new(0, 0, T::default()))
}

/// Integrates frames one at a time into the top-down layers (for callers with their
/// own frame source or progress display; [`reconstruct`] drives it for a dataset).
#[derive(Debug, Clone)]
pub struct TopDownBuilder {
    maps: TopDownMaps,
    floor_z: f64,
    robot_height: f64,
    floor_margin: f64,
    min_depth: f64,
    max_depth: f64,
    stride: usize,
    min_obstacle_points: u32,
}

impl TopDownBuilder {
    /// An empty builder on `frame`; heights are measured from world z = `floor_z`,
    /// and `robot_height` is the resolved height limit.
    pub fn new(
        frame: GridFrame,
        floor_z: f64,
        robot_height: f64,
        opts: &ReconstructOptions,
    ) -> Self {
        let (rows, cols) = (frame.rows, frame.cols);
        Self {
            maps: TopDownMaps {
                frame,
                rgb: Grid::new(rows, cols, [0, 0, 0]),
                height: Grid::new(rows, cols, f32::NAN),
                obstacles: Grid::new(rows, cols, false),
                hits: Grid::new(rows, cols, 0),
                obstacle_hits: Grid::new(rows, cols, 0),
                frames: 0,
                points: 0,
            },
            floor_z,
            robot_height,
            floor_margin: opts.floor_margin,
            min_depth: opts.min_depth,
            max_depth: opts.max_depth,
            stride: opts.stride.max(1),
            min_obstacle_points: opts.min_obstacle_points.max(1),
        }
    }

    /// Add one frame seen from `camera` (the optical frame's pose in the map frame).
    /// Colour and depth must have the same size; extra colour rows/columns are ignored.
    pub fn integrate(
        &mut self,
        frame: &RgbdFrame,
        intrinsics: &Intrinsics,
        camera: &Isometry3<f64>,
    ) {
        let s = self.stride;
        let (h, w) = (frame.depth.rows(), frame.depth.cols());
        let m = &mut self.maps;
        for v in (s / 2..h).step_by(s) {
            for u in (s / 2..w).step_by(s) {
                let d = frame.depth.get(Cell::new(v, u)).copied().unwrap_or(0.0);
                let d = f64::from(d);
                if !(d.is_finite() && d >= self.min_depth && d <= self.max_depth) {
                    continue;
                }
                let pc = intrinsics.backproject(u as f64, v as f64, d);
                let pw = camera * Point3::from(pc);
                let z = pw.z - self.floor_z;
                if z >= self.robot_height || z < -self.floor_margin {
                    continue;
                }
                let Some(cell) = m.frame.cell_at(Point::new(pw.x, pw.y)) else {
                    continue;
                };
                let i = m.hits.index(cell);
                let hits = &mut m.hits.as_mut_slice()[i];
                *hits = hits.saturating_add(1);
                m.points += 1;
                let zf = z as f32;
                let top = m.height.as_slice()[i];
                if top.is_nan() || zf > top {
                    m.height.as_mut_slice()[i] = zf;
                    if let Some(&c) = frame.rgb.get(Cell::new(v, u)) {
                        m.rgb.as_mut_slice()[i] = c;
                    }
                }
                if z >= self.floor_margin {
                    let n = &mut m.obstacle_hits.as_mut_slice()[i];
                    *n = n.saturating_add(1);
                }
            }
        }
        m.frames += 1;
    }

    /// The layers so far (obstacles set from the counts).
    pub fn finish(mut self) -> TopDownMaps {
        let k = self.min_obstacle_points;
        self.maps.obstacles = self.maps.obstacle_hits.map(|&n| n >= k);
        self.maps
    }
}

/// The grid a dataset is reconstructed on.
pub fn map_frame(
    spec: &MapSpec,
    camera_positions: &[[f64; 2]],
    max_depth: f64,
) -> Result<GridFrame, ReconstructError> {
    let frame = match *spec {
        MapSpec::Bounds { bounds, cell_size } => GridFrame::from_bounds(bounds, cell_size),
        MapSpec::VlmapsGrid {
            grid_size,
            cell_size,
        } => vlmaps_grid_frame(grid_size, grid_size, cell_size),
        MapSpec::Auto { cell_size } => {
            let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
            for p in camera_positions {
                x0 = x0.min(p[0]);
                y0 = y0.min(p[1]);
                x1 = x1.max(p[0]);
                y1 = y1.max(p[1]);
            }
            if x0 > x1 {
                x0 = 0.0;
                y0 = 0.0;
                x1 = 0.0;
                y1 = 0.0;
            }
            let snap_lo = |v: f64| ((v - max_depth) / cell_size).floor() * cell_size;
            let snap_hi = |v: f64| ((v + max_depth) / cell_size).ceil() * cell_size;
            GridFrame::from_bounds(
                [snap_lo(x0), snap_lo(y0), snap_hi(x1), snap_hi(y1)],
                cell_size,
            )
        }
    };
    if frame.rows.saturating_mul(frame.cols) > MAX_CELLS {
        return Err(ReconstructError::Options(format!(
            "the map would have {} x {} cells (limit {MAX_CELLS}); give map bounds or a larger cell size",
            frame.rows, frame.cols
        )));
    }
    Ok(frame)
}

/// Reconstruct a dataset's top-down layers.
pub fn reconstruct(
    dataset: &RgbdDataset,
    opts: &ReconstructOptions,
) -> Result<TopDownMaps, ReconstructError> {
    reconstruct_with_progress(dataset, opts, |_, _| {})
}

/// [`reconstruct`], calling `progress(frames_done, frames_total)` after each frame.
pub fn reconstruct_with_progress(
    dataset: &RgbdDataset,
    opts: &ReconstructOptions,
    mut progress: impl FnMut(usize, usize),
) -> Result<TopDownMaps, ReconstructError> {
    if !(opts.min_depth >= 0.0 && opts.max_depth > opts.min_depth && opts.max_depth.is_finite()) {
        return Err(ReconstructError::Options(format!(
            "depth range [{}, {}] is empty or not finite",
            opts.min_depth, opts.max_depth
        )));
    }
    if !(opts.floor_margin.is_finite() && opts.floor_margin >= 0.0) {
        return Err(ReconstructError::Options(format!(
            "floor_margin must be >= 0, got {}",
            opts.floor_margin
        )));
    }
    let robot_height = opts.robot_height.unwrap_or(dataset.camera.camera_height);
    if !(robot_height.is_finite() && robot_height > opts.floor_margin) {
        return Err(ReconstructError::Options(format!(
            "robot_height {robot_height} must be finite and above floor_margin {}",
            opts.floor_margin
        )));
    }
    let poses = dataset.world_poses();
    let spec = opts.map.or(dataset.camera.map).unwrap_or_default();
    let positions: Vec<[f64; 2]> = poses
        .frames
        .iter()
        .map(|f| [f.camera.translation.x, f.camera.translation.y])
        .collect();
    let frame = map_frame(&spec, &positions, opts.max_depth).map_err(|e| match e {
        ReconstructError::Options(message) => ReconstructError::Dataset {
            path: dataset.root.clone(),
            message,
        },
        other => other,
    })?;
    let mut b = TopDownBuilder::new(frame, poses.floor_z, robot_height, opts);
    let step = opts.frame_step.max(1);
    let total = dataset.len().div_ceil(step);
    for (done, i) in (0..dataset.len()).step_by(step).enumerate() {
        let f = dataset.load_frame(i)?;
        b.integrate(&f, &dataset.camera.intrinsics, &poses.frames[i].camera);
        progress(done + 1, total);
    }
    Ok(b.finish())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A camera 1 m up looking straight down at a floor with a 0.5 m high step: the
    /// step's cells are obstacles at height 0.5 and the floor's are free at 0.
    #[test]
    fn downward_camera_sees_floor_and_step() {
        let intr = Intrinsics::new(10.0, 10.0, 10.0, 10.0);
        let (w, h) = (20usize, 20usize);
        // camera optical z = world -z, x = east, y = south
        let cam = Isometry3::from_parts(
            nalgebra::Translation3::new(0.0, 0.0, 1.0),
            nalgebra::UnitQuaternion::from_rotation_matrix(
                &nalgebra::Rotation3::from_matrix_unchecked(nalgebra::Matrix3::new(
                    1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0,
                )),
            ),
        );
        let mut depth = Grid::new(h, w, 1.0f32);
        let mut rgb = Grid::new(h, w, [128u8, 128, 128]);
        for v in 0..h {
            for u in 10..w {
                depth.set(Cell::new(v, u), 0.5); // east half: a 0.5 m step
                rgb.set(Cell::new(v, u), [200, 0, 0]);
            }
        }
        let frame = GridFrame::from_bounds([-1.0, -1.0, 1.0, 1.0], 0.1);
        let opts = ReconstructOptions {
            stride: 1,
            ..Default::default()
        };
        let mut b = TopDownBuilder::new(frame, 0.0, 0.9, &opts);
        b.integrate(&RgbdFrame { rgb, depth }, &intr, &cam);
        let m = b.finish();
        let east = frame.cell_at(Point::new(0.15, 0.05)).unwrap();
        let west = frame.cell_at(Point::new(-0.35, -0.05)).unwrap();
        assert!(m.obstacles.get(east).copied().unwrap());
        assert_eq!(m.rgb.get(east), Some(&[200, 0, 0]));
        assert!((m.height.get(east).unwrap() - 0.5).abs() < 1e-6);
        assert!(!m.obstacles.get(west).copied().unwrap());
        assert_eq!(m.rgb.get(west), Some(&[128, 128, 128]));
        assert!(m.height.get(west).unwrap().abs() < 1e-6);
        // the 1 m wide footprint seen at depth 1 with f = 10 covers 2 m x 2 m of floor
        assert!(m.observed_count() > 100);
        let far = frame.cell_at(Point::new(0.95, 0.95)).unwrap();
        // east of the step's far edge (x > 0.475) nothing was seen
        assert!(!m.observed(far) && m.height.get(far).unwrap().is_nan());
        let c = m.crop_to_observed(0).unwrap();
        assert_eq!(c.observed_count(), m.observed_count());
    }

    #[test]
    fn auto_frame_covers_cameras_plus_depth() {
        let f = map_frame(
            &MapSpec::Auto { cell_size: 0.05 },
            &[[1.0, 2.0], [3.0, 2.5]],
            2.0,
        )
        .unwrap();
        let b = f.bounds();
        assert!((b[0] + 1.0).abs() < 1e-9 && (b[1] - 0.0).abs() < 1e-9);
        assert!((b[2] - 5.0).abs() < 1e-9 && (b[3] - 4.5).abs() < 1e-9);
    }
}
