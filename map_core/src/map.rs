//! The IVLMap: grid layers (obstacles, category ids, instance ids U, colour ids V),
//! the instance table with the paper's Listing-1 fields, and named regions.

use serde::{Deserialize, Serialize};

use crate::geometry::{Aabb, Point, Polygon, Pose};
use crate::grid::{Cell, Grid, GridFrame};
use crate::scene::Scene;

/// One object instance: the paper's Listing-1 attributes plus geometry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Instance {
    /// Instance id (the scene object's id); the value of this instance's cells in U.
    pub id: u32,
    /// Category name, e.g. "table".
    pub label: String,
    /// 1-based counting id among instances of the same label (paper's `label_id`),
    /// assigned west to east, then north to south.
    pub label_id: u32,
    /// How many instances share this label.
    pub num_of_same_class: u32,
    /// Colour word, if known (`color` in JSON, as the paper's Listing 1).
    #[serde(rename = "color")]
    pub colour: Option<String>,
    /// Footprint area in cells (SAM's `area`).
    pub area: u64,
    /// Footprint area in square metres.
    pub area_m2: f64,
    /// Grid bounding box `[col, row, width, height]` in cells (SAM's `bbox`, x = column).
    pub bbox: [u32; 4],
    /// Footprint bounding box in world metres.
    pub bbox_m: Aabb,
    /// Footprint centroid in world metres.
    pub centroid: Point,
    /// Footprint contour in world metres (counter-clockwise).
    pub contour: Polygon,
}

impl Instance {
    /// Distance from `p` to the footprint (0 inside).
    pub fn distance(&self, p: Point) -> f64 {
        self.contour.distance(p)
    }

    /// Closest point of the footprint to `p` (`p` itself when inside).
    pub fn closest_point(&self, p: Point) -> Point {
        if self.contour.contains(p) {
            return p;
        }
        self.contour
            .closest_boundary_point(p)
            .unwrap_or(self.centroid)
    }

    /// Centre of the footprint's bounding box (the "footprint centre" of design.md).
    pub fn center(&self) -> Point {
        self.bbox_m.center()
    }
}

/// A named region (room); not an obstacle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Region {
    /// Region name from the scene, e.g. "kitchen".
    pub name: String,
    /// Outline in world metres.
    pub polygon: Polygon,
}

/// The instance-level semantic grid map.
#[derive(Debug, Clone, PartialEq)]
pub struct IvlMap {
    /// Name of the scene or map.
    pub name: String,
    /// Where the grid lies in the world; shared by every layer.
    pub frame: GridFrame,
    /// Occupied cells (walls and objects), not inflated.
    pub obstacles: Grid<bool>,
    /// Category id per cell: 0 = none, else 1 + index into `categories`.
    pub category: Grid<u16>,
    /// Instance id per cell (the paper's U): 0 = none.
    pub instance: Grid<u32>,
    /// Colour id per cell (the paper's V): 0 = none, else 1 + index into `colours`.
    pub colour: Grid<u8>,
    /// Category names, indexed by category id - 1.
    pub categories: Vec<String>,
    /// Colour names, indexed by colour id - 1.
    pub colours: Vec<String>,
    /// The instance table, one entry per object.
    pub instances: Vec<Instance>,
    /// Named regions (rooms).
    pub regions: Vec<Region>,
    /// Robot radius in metres (obstacles are inflated by it for planning).
    pub robot_radius: f64,
    /// The robot's start pose.
    pub start_pose: Pose,
}

impl IvlMap {
    /// Rasterise a scene: walls and objects become obstacles; each object's
    /// footprint cells get its category, instance id and colour id.
    pub fn from_scene(scene: &Scene) -> IvlMap {
        let frame = GridFrame::from_bounds(scene.bounds.0, scene.cell_size.0);
        let (rows, cols) = (frame.rows, frame.cols);
        let mut obstacles = Grid::new(rows, cols, false);
        let mut category = Grid::new(rows, cols, 0u16);
        let mut instance = Grid::new(rows, cols, 0u32);
        let mut colour = Grid::new(rows, cols, 0u8);
        let mut categories: Vec<String> = Vec::new();
        let mut colours: Vec<String> = Vec::new();

        for w in &scene.walls {
            let (a, b): (Point, Point) = (w.from.into(), w.to.into());
            let poly = wall_polygon(a, b, w.thickness.0);
            for c in rasterize(&frame, &poly) {
                obstacles.set(c, true);
            }
        }

        let mut instances = Vec::with_capacity(scene.objects.len());
        for o in &scene.objects {
            let poly = o.footprint();
            let label = o.category.0.clone();
            let cat_id = id_of(&mut categories, &label) as u16;
            let col_id = o
                .colour
                .as_ref()
                .map(|c| id_of(&mut colours, &c.0) as u8)
                .unwrap_or(0);
            let cells = rasterize(&frame, &poly);
            let (mut rmin, mut rmax, mut cmin, mut cmax) = (usize::MAX, 0, usize::MAX, 0);
            for &c in &cells {
                obstacles.set(c, true);
                category.set(c, cat_id);
                instance.set(c, o.id.0);
                colour.set(c, col_id);
                rmin = rmin.min(c.row);
                rmax = rmax.max(c.row);
                cmin = cmin.min(c.col);
                cmax = cmax.max(c.col);
            }
            let bbox = if cells.is_empty() {
                [0; 4]
            } else {
                [
                    cmin as u32,
                    rmin as u32,
                    (cmax - cmin + 1) as u32,
                    (rmax - rmin + 1) as u32,
                ]
            };
            let bbox_m = poly.bbox().unwrap_or(Aabb {
                min: o.center.into(),
                max: o.center.into(),
            });
            instances.push(Instance {
                id: o.id.0,
                label,
                label_id: 0,
                num_of_same_class: 0,
                colour: o.colour.as_ref().map(|c| c.0.clone()),
                area: cells.len() as u64,
                area_m2: poly.area(),
                bbox,
                bbox_m,
                centroid: poly.centroid(),
                contour: poly,
            });
        }
        assign_label_ids(&mut instances);

        let regions = scene
            .regions
            .iter()
            .map(|r| Region {
                name: r.name.0.clone(),
                polygon: Polygon(r.polygon.0.iter().map(|p| Point::from(*p)).collect()),
            })
            .collect();

        IvlMap {
            name: scene.name.clone(),
            frame,
            obstacles,
            category,
            instance,
            colour,
            categories,
            colours,
            instances,
            regions,
            robot_radius: scene.robot.radius.0,
            start_pose: scene.robot.pose(),
        }
    }

    /// The instance with this id.
    pub fn instance_by_id(&self, id: u32) -> Option<&Instance> {
        self.instances.iter().find(|i| i.id == id)
    }

    /// The instance whose footprint covers `p`, if any (looked up in U).
    pub fn instance_at(&self, p: Point) -> Option<&Instance> {
        let c = self.frame.cell_at(p)?;
        match *self.instance.get(c)? {
            0 => None,
            id => self.instance_by_id(id),
        }
    }

    /// Whether a world point lies on an (uninflated) obstacle or outside the map.
    pub fn is_occupied(&self, p: Point) -> bool {
        self.frame
            .cell_at(p)
            .and_then(|c| self.obstacles.get(c).copied())
            .unwrap_or(true)
    }

    /// Distinct labels with their counts, sorted by label.
    pub fn label_counts(&self) -> Vec<(String, usize)> {
        let mut v: Vec<(String, usize)> = Vec::new();
        for i in &self.instances {
            match v.iter_mut().find(|(l, _)| *l == i.label) {
                Some((_, n)) => *n += 1,
                None => v.push((i.label.clone(), 1)),
            }
        }
        v.sort();
        v
    }

    /// The names of the regions holding an instance labelled `label` (its footprint
    /// centroid inside the region, as a selection's `region` filter counts it), in the
    /// map's order of regions.
    pub fn regions_holding(&self, label: &str) -> Vec<&str> {
        self.regions_holding_at_least(label, 1)
    }

    /// The names of the regions holding `n` or more instances labelled `label` (as
    /// [`IvlMap::regions_holding`] counts them), in the map's order of regions: where
    /// "the two chairs in the kitchen" can be found.
    pub fn regions_holding_at_least(&self, label: &str, n: usize) -> Vec<&str> {
        self.regions
            .iter()
            .filter(|r| {
                self.instances
                    .iter()
                    .filter(|i| i.label == label && r.polygon.contains(i.centroid))
                    .count()
                    >= n
            })
            .map(|r| r.name.as_str())
            .collect()
    }
}

/// Resolution of the counting order: centroid coordinates are compared after
/// rounding to this many metres (1 micrometre), so two instances whose centroids
/// differ only by floating-point noise (3.599999999999996 and 3.5999999999999934,
/// from rotated footprints) count as level and the next rule decides.
pub const LABEL_ORDER_RESOLUTION_M: f64 = 1e-6;

/// A coordinate on the [`LABEL_ORDER_RESOLUTION_M`] lattice (rounding, not a
/// tolerance, so the order stays transitive).
fn order_key(v: f64) -> i64 {
    // `as` saturates; map coordinates are far inside +-9e12 m.
    (v / LABEL_ORDER_RESOLUTION_M).round() as i64
}

/// Recompute `label_id` (1-based, west to east then north to south by centroid,
/// each compared at [`LABEL_ORDER_RESOLUTION_M`]; then by id) and
/// `num_of_same_class` for every instance.
pub fn assign_label_ids(instances: &mut [Instance]) {
    let mut labels: Vec<String> = instances.iter().map(|i| i.label.clone()).collect();
    labels.sort();
    labels.dedup();
    for label in labels {
        let mut idx: Vec<usize> = (0..instances.len())
            .filter(|&k| instances[k].label == label)
            .collect();
        idx.sort_by(|&a, &b| {
            let (pa, pb) = (instances[a].centroid, instances[b].centroid);
            order_key(pa.x)
                .cmp(&order_key(pb.x))
                .then(order_key(pb.y).cmp(&order_key(pa.y)))
                .then(instances[a].id.cmp(&instances[b].id))
        });
        let n = idx.len() as u32;
        for (k, &i) in idx.iter().enumerate() {
            instances[i].label_id = k as u32 + 1;
            instances[i].num_of_same_class = n;
        }
    }
}

fn id_of(names: &mut Vec<String>, name: &str) -> usize {
    match names.iter().position(|n| n == name) {
        Some(i) => i + 1,
        None => {
            names.push(name.to_string());
            names.len()
        }
    }
}

/// A wall segment of the given thickness as a rectangle.
fn wall_polygon(a: Point, b: Point, thickness: f64) -> Polygon {
    let d = b.sub(a);
    let len = d.norm();
    let h = thickness / 2.0;
    let (u, n) = if len > 1e-12 {
        let u = d.scale(1.0 / len);
        (u, Point::new(-u.y, u.x))
    } else {
        (Point::new(1.0, 0.0), Point::new(0.0, 1.0))
    };
    // Extend the ends by half the thickness so corners close.
    let a2 = a.sub(u.scale(h));
    let b2 = b.add(u.scale(h));
    Polygon(vec![
        a2.add(n.scale(h)),
        a2.sub(n.scale(h)),
        b2.sub(n.scale(h)),
        b2.add(n.scale(h)),
    ])
}

/// Cells whose centre lies inside `poly`; thin shapes that cover no centre get the
/// cells their vertices and centroid fall in, so every object occupies at least one cell.
pub(crate) fn rasterize(frame: &GridFrame, poly: &Polygon) -> Vec<Cell> {
    let Some(bb) = poly.bbox() else {
        return Vec::new();
    };
    let (r0, c0) = frame.to_grid_f(Point::new(bb.min.x, bb.max.y));
    let (r1, c1) = frame.to_grid_f(Point::new(bb.max.x, bb.min.y));
    let clampi = |v: f64, n: usize| (v.floor().max(0.0) as usize).min(n.saturating_sub(1));
    let (r0, r1) = (clampi(r0, frame.rows), clampi(r1, frame.rows));
    let (c0, c1) = (clampi(c0, frame.cols), clampi(c1, frame.cols));
    let mut out = Vec::new();
    for r in r0..=r1 {
        for c in c0..=c1 {
            let cell = Cell::new(r, c);
            if poly.contains(frame.cell_center(cell)) {
                out.push(cell);
            }
        }
    }
    if out.is_empty() {
        // Thinner than a cell: walk each edge in half-cell steps.
        let v = poly.vertices();
        for i in 0..v.len() {
            let (a, b) = (v[i], v[(i + 1) % v.len()]);
            let steps = (a.dist(b) / (frame.cell_size * 0.5)).ceil().max(1.0) as usize;
            for s in 0..=steps {
                let p = a.add(b.sub(a).scale(s as f64 / steps as f64));
                if let Some(c) = frame.cell_at(p) {
                    out.push(c);
                }
            }
        }
        out.sort();
        out.dedup();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Scene {
        Scene::from_json_str(
            r#"{"format": "ivlmap-scene/1", "name": "t", "bounds": [0, 0, 6, 4], "cell_size": 0.1,
            "walls": [{"from": [0, 0], "to": [6, 0]}],
            "regions": [{"name": "kitchen", "polygon": [[0,0],[3,0],[3,4],[0,4]]}],
            "objects": [
              {"id": 4, "category": "chair", "colour": "yellow", "center": [4.0, 2.0], "size": [0.6, 0.6]},
              {"id": 2, "category": "chair", "colour": "grey", "center": [1.0, 2.0], "size": [0.6, 0.6]},
              {"id": 3, "category": "sofa", "colour": "red", "center": [3.0, 3.0], "size": [2.0, 0.8], "yaw": 90}
            ],
            "robot": {"pose": [0.5, 0.5, 0], "radius": 0.2}}"#,
            "t.scene.json",
        )
        .unwrap()
    }

    #[test]
    fn regions_holding_a_label_count_centroids_inside() {
        let m = IvlMap::from_scene(&scene());
        // chair 2 at x = 1 is in the kitchen (x 0..3); chair 4 at x = 4 is not.
        assert_eq!(m.regions_holding("chair"), ["kitchen"]);
        assert!(m.regions_holding("table").is_empty());
        // One chair in the kitchen: no region holds two.
        assert!(m.regions_holding_at_least("chair", 2).is_empty());
        assert_eq!(m.regions_holding_at_least("chair", 1), ["kitchen"]);
    }

    #[test]
    fn layers_hold_category_instance_and_colour() {
        let m = IvlMap::from_scene(&scene());
        assert_eq!((m.frame.rows, m.frame.cols), (40, 60));
        let c = m.frame.cell_at(Point::new(4.0, 2.0)).unwrap();
        assert_eq!(*m.instance.get(c).unwrap(), 4);
        assert!(*m.obstacles.get(c).unwrap());
        let cat = *m.category.get(c).unwrap() as usize;
        assert_eq!(m.categories[cat - 1], "chair");
        let col = *m.colour.get(c).unwrap() as usize;
        assert_eq!(m.colours[col - 1], "yellow");
        // wall along the south edge
        assert!(m.is_occupied(Point::new(3.0, 0.02)));
        assert!(!m.is_occupied(Point::new(2.0, 1.0)));
    }

    #[test]
    fn label_ids_count_west_to_east() {
        let m = IvlMap::from_scene(&scene());
        let west = m.instance_by_id(2).unwrap();
        let east = m.instance_by_id(4).unwrap();
        assert_eq!((west.label_id, east.label_id), (1, 2));
        assert_eq!(west.num_of_same_class, 2);
        assert_eq!(m.instance_by_id(3).unwrap().num_of_same_class, 1);
    }

    /// Regression: office-b's grey chairs 20 (3.6, 8.775, yaw 180) and 22 (3.6,
    /// 7.025) have centroids x = 3.599999999999996 and 3.5999999999999934 after
    /// rotation, so 22 used to count before 20; the order must follow the
    /// documented north-first rule, not the float noise.
    #[test]
    fn assign_label_ids_ties_on_float_noise_go_north_first() {
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../examples/scenes/office-b.scene.json");
        let m = IvlMap::from_scene(&Scene::from_path(&p).unwrap());
        let (c20, c22) = (m.instance_by_id(20).unwrap(), m.instance_by_id(22).unwrap());
        assert!((c20.centroid.x - c22.centroid.x).abs() < 1e-9);
        assert!(c20.centroid.y > c22.centroid.y);
        assert_eq!(c20.label_id + 1, c22.label_id, "{c20:?}\n{c22:?}");

        // The same pair by hand, with the noise on the southern one's side too.
        let m = IvlMap::from_scene(&scene());
        let mut north = m.instance_by_id(2).unwrap().clone();
        let mut south = north.clone();
        north.id = 9;
        north.centroid = Point::new(3.6000000000000005, 3.0);
        south.id = 8;
        south.centroid = Point::new(3.6, 1.0);
        for (n, s) in [(0.0, 0.0), (0.0, 4e-16), (4e-16, 0.0)] {
            let mut v = vec![south.clone(), north.clone()];
            v[1].centroid.x += n;
            v[0].centroid.x += s;
            assign_label_ids(&mut v);
            assert_eq!((v[1].label_id, v[0].label_id), (1, 2), "{n} {s}");
        }
        // A real difference (1 mm) still orders west first.
        let mut v = vec![south.clone(), north.clone()];
        v[0].centroid.x = 3.599;
        assign_label_ids(&mut v);
        assert_eq!((v[0].label_id, v[1].label_id), (1, 2));
        // Level on both axes: the lower id first.
        let mut v = vec![north.clone(), north.clone()];
        v[1].id = 3;
        assign_label_ids(&mut v);
        assert_eq!((v[1].label_id, v[0].label_id), (1, 2));
    }

    #[test]
    fn rotated_footprint_is_rasterised_rotated() {
        let m = IvlMap::from_scene(&scene());
        let sofa = m.instance_by_id(3).unwrap();
        // yaw 90: the 2.0 m extent now runs north-south.
        assert!(
            (sofa.bbox_m.height() - 2.0).abs() < 1e-9,
            "{:?}",
            sofa.bbox_m
        );
        assert_eq!(sofa.bbox[3], 20);
        assert_eq!(sofa.bbox[2], 8);
        assert_eq!(sofa.area, 160);
        assert_eq!(m.instance_at(Point::new(3.0, 3.9)).map(|i| i.id), Some(3));
    }
}
