//! A small ray-casting renderer that turns a scene file into RGB-D frames of known
//! geometry: the floor (z = 0, grey, inside the scene bounds), walls as vertical
//! slabs and objects as upright boxes over their footprints, each in a flat colour.
//! Depth is measured along the optical axis, as Habitat and RGB-D sensors report it.
//! Used to test the reconstruction end to end and to make example datasets.

use nalgebra::{Isometry3, Vector3};

use super::camera::Intrinsics;
use super::frames::RgbdFrame;
use map_core::geometry::{oriented_rect, Point};
use map_core::grid::{Cell, Grid};
use map_core::render::{colour_rgb, UNKNOWN_RGB, WALL_RGB};
use map_core::scene::{Scene, SceneObject};

/// How a scene is extruded into 3-D.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticOptions {
    /// Height of every wall, metres. Default 2.5.
    pub wall_height: f64,
    /// Floor colour. Default mid grey [128, 128, 128].
    pub floor_rgb: [u8; 3],
}

impl Default for SyntheticOptions {
    fn default() -> Self {
        Self {
            wall_height: 2.5,
            floor_rgb: [128, 128, 128],
        }
    }
}

/// The default object height of [`render_rgbd`], metres.
pub const DEFAULT_OBJECT_HEIGHT: f64 = 0.8;

/// A vertical prism: a convex counter-clockwise footprint from z = 0 to `top`.
#[derive(Debug, Clone)]
struct Prism {
    /// Vertices and outward edge normals (edge i runs from vertex i to i + 1).
    verts: Vec<[f64; 2]>,
    normals: Vec<[f64; 2]>,
    top: f64,
    rgb: [u8; 3],
}

impl Prism {
    fn new(poly: &[Point], top: f64, rgb: [u8; 3]) -> Option<Self> {
        let mut verts: Vec<[f64; 2]> = poly.iter().map(|p| [p.x, p.y]).collect();
        let n = verts.len();
        if n < 3 || top <= 0.0 {
            return None;
        }
        let area2: f64 = (0..n)
            .map(|i| {
                let (a, b) = (verts[i], verts[(i + 1) % n]);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum();
        if area2.abs() < 1e-12 {
            return None;
        }
        if area2 < 0.0 {
            verts.reverse();
        }
        let normals = (0..n)
            .map(|i| {
                let (a, b) = (verts[i], verts[(i + 1) % n]);
                [b[1] - a[1], -(b[0] - a[0])] // edge rotated clockwise: outward for CCW
            })
            .collect();
        Some(Self {
            verts,
            normals,
            top,
            rgb,
        })
    }

    /// Ray parameter where the ray `o + t d` enters the prism (t > 0), if it does.
    fn enter(&self, o: &[f64; 3], d: &[f64; 3]) -> Option<f64> {
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        // z slab [0, top]
        if d[2].abs() < 1e-12 {
            if o[2] < 0.0 || o[2] > self.top {
                return None;
            }
        } else {
            let (a, b) = ((0.0 - o[2]) / d[2], (self.top - o[2]) / d[2]);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
        // Cyrus-Beck against each edge's half-plane n . (p - a) <= 0
        for (v, n) in self.verts.iter().zip(&self.normals) {
            let num = n[0] * (o[0] - v[0]) + n[1] * (o[1] - v[1]);
            let den = n[0] * d[0] + n[1] * d[1];
            if den.abs() < 1e-15 {
                if num > 0.0 {
                    return None;
                }
            } else {
                let t = -num / den;
                if den < 0.0 {
                    t0 = t0.max(t);
                } else {
                    t1 = t1.min(t);
                }
            }
            if t0 > t1 {
                return None;
            }
        }
        (t0 > 1e-9 && t0 <= t1).then_some(t0)
    }
}

/// A scene prepared for ray casting.
#[derive(Debug, Clone)]
pub struct RgbdRenderer {
    prisms: Vec<Prism>,
    bounds: [f64; 4],
    floor_rgb: [u8; 3],
}

impl RgbdRenderer {
    /// Extrude `scene`: walls `opts.wall_height` high in [`WALL_RGB`], each object a
    /// box `object_height(object)` high in its colour word's RGB ([`colour_rgb`],
    /// [`UNKNOWN_RGB`] when it has none or the palette lacks it).
    pub fn new(
        scene: &Scene,
        opts: &SyntheticOptions,
        object_height: impl Fn(&SceneObject) -> f64,
    ) -> Self {
        let mut prisms = Vec::new();
        for w in &scene.walls {
            let (a, b): (Point, Point) = (w.from.into(), w.to.into());
            let t = w.thickness.0;
            let d = b.sub(a);
            let len = d.norm();
            // oriented_rect's yaw is clockwise from the x axis
            let yaw = if len > 1e-12 {
                -d.y.atan2(d.x).to_degrees()
            } else {
                0.0
            };
            let rect = oriented_rect(a.add(d.scale(0.5)), [len + t, t], yaw);
            prisms.extend(Prism::new(rect.vertices(), opts.wall_height, WALL_RGB));
        }
        for o in &scene.objects {
            let rgb = o
                .colour
                .as_ref()
                .and_then(|c| colour_rgb(&c.0))
                .unwrap_or(UNKNOWN_RGB);
            prisms.extend(Prism::new(o.footprint().vertices(), object_height(o), rgb));
        }
        Self {
            prisms,
            bounds: scene.bounds.0,
            floor_rgb: opts.floor_rgb,
        }
    }

    /// The nearest surface along `origin + t * dir` (t > 0): `(t, colour)`.
    pub fn cast(&self, origin: &Vector3<f64>, dir: &Vector3<f64>) -> Option<(f64, [u8; 3])> {
        let o = [origin.x, origin.y, origin.z];
        let d = [dir.x, dir.y, dir.z];
        let mut best: Option<(f64, [u8; 3])> = None;
        if d[2] < 0.0 && o[2] > 0.0 {
            let t = -o[2] / d[2];
            let (x, y) = (o[0] + t * d[0], o[1] + t * d[1]);
            let b = self.bounds;
            if x >= b[0] && x <= b[2] && y >= b[1] && y <= b[3] {
                best = Some((t, self.floor_rgb));
            }
        }
        for p in &self.prisms {
            if let Some(t) = p.enter(&o, &d) {
                if best.is_none_or(|(bt, _)| t < bt) {
                    best = Some((t, p.rgb));
                }
            }
        }
        best
    }

    /// Render a `width x height` frame from `camera` (the optical frame's pose in the
    /// world: x right, y down, z forward). Pixels that see nothing get depth 0 and black.
    pub fn render(
        &self,
        camera: &Isometry3<f64>,
        intrinsics: &Intrinsics,
        width: usize,
        height: usize,
    ) -> RgbdFrame {
        let mut rgb = Grid::new(height, width, [0u8; 3]);
        let mut depth = Grid::new(height, width, 0.0f32);
        let origin = camera.translation.vector;
        for v in 0..height {
            for u in 0..width {
                // camera-frame ray with z = 1, so the hit's t is the z-depth
                let dir = camera.rotation * intrinsics.ray(u as f64, v as f64);
                if let Some((t, c)) = self.cast(&origin, &dir) {
                    depth.set(Cell::new(v, u), t as f32);
                    rgb.set(Cell::new(v, u), c);
                }
            }
        }
        RgbdFrame { rgb, depth }
    }
}

/// Render one frame of `scene` with default walls and floor and
/// `object_height(object)` metre boxes (see [`RgbdRenderer`]).
pub fn render_rgbd(
    scene: &Scene,
    camera: &Isometry3<f64>,
    intrinsics: &Intrinsics,
    width: usize,
    height: usize,
    object_height: impl Fn(&SceneObject) -> f64,
) -> RgbdFrame {
    RgbdRenderer::new(scene, &SyntheticOptions::default(), object_height)
        .render(camera, intrinsics, width, height)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Scene {
        Scene::from_json_str(
            r#"{"format": "ivlmap-scene/1", "name": "t", "bounds": [0, 0, 6, 4],
            "walls": [{"from": [5, 0], "to": [5, 4], "thickness": 0.2}],
            "objects": [{"id": 1, "category": "box", "colour": "red", "center": [3, 2], "size": [1, 1]}],
            "robot": {"pose": [1, 2, 90], "radius": 0.2}}"#,
            "t.scene.json",
        )
        .unwrap()
    }

    #[test]
    fn rays_hit_box_wall_and_floor_at_the_right_range() {
        let r = RgbdRenderer::new(&scene(), &SyntheticOptions::default(), |_| 0.8);
        let east = Vector3::new(1.0, 0.0, 0.0);
        // at 0.5 m height: box face at x = 2.5
        let (t, c) = r.cast(&Vector3::new(1.0, 2.0, 0.5), &east).unwrap();
        assert!((t - 1.5).abs() < 1e-9 && c == colour_rgb("red").unwrap());
        // above the box (1.0 m): the wall face at x = 4.9
        let (t, c) = r.cast(&Vector3::new(1.0, 2.0, 1.0), &east).unwrap();
        assert!((t - 3.9).abs() < 1e-9 && c == WALL_RGB);
        // above the wall: nothing
        assert!(r.cast(&Vector3::new(1.0, 2.0, 3.0), &east).is_none());
        // straight down onto the box top and onto the floor
        let down = Vector3::new(0.0, 0.0, -1.0);
        let (t, _) = r.cast(&Vector3::new(3.2, 2.1, 1.5), &down).unwrap();
        assert!((t - 0.7).abs() < 1e-9);
        let (t, c) = r.cast(&Vector3::new(1.0, 1.0, 1.5), &down).unwrap();
        assert!((t - 1.5).abs() < 1e-9 && c == [128, 128, 128]);
    }

    #[test]
    fn depth_is_along_the_optical_axis() {
        // camera 0.5 m up at x = 1 looking east at the box face (x = 2.5, 1.5 m away)
        let base = super::super::poses::base_from_pose2d(
            map_core::geometry::Pose::new(1.0, 2.0, 90.0),
            0.0,
        );
        let cam = super::super::poses::PoseConvention::RosBase
            .to_world(&base, 0.5)
            .camera;
        let intr = Intrinsics::new(20.0, 20.0, 20.0, 15.0);
        let f = RgbdRenderer::new(&scene(), &SyntheticOptions::default(), |_| 0.8)
            .render(&cam, &intr, 40, 30);
        // every pixel that sees the flat box face reports 1.5 m, not the slant range
        let mut n = 0;
        for (cell, &d) in f.depth.iter_cells() {
            if f.rgb.get(cell) == Some(&colour_rgb("red").unwrap_or_default())
                && (d - 1.5).abs() < 1e-4
            {
                n += 1;
            }
        }
        assert!(n > 100, "{n} pixels on the box face");
    }
}
