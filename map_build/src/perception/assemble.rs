//! Assembly: perception outputs -> a full [`IvlMap`] (instance grid U, colour grid V,
//! category grid, instance records), plus the masks that yielded no instance.
//!
//! Overlaps: SAM's automatic masks overlap (a table, the table with its chairs, a
//! chair's seat). After Eq. 2 each cell goes to the *smallest* kept mask covering
//! it, as when SAM's masks are drawn largest first (`sorted(masks, key=area,
//! reverse=True)`, the convention of SAM's own notebooks): parts and small objects
//! stay visible on top of the larger regions that contain them. Equal areas: the
//! lower mask index is on top. A mask whose visible part has fewer than
//! `min_area` cells is dropped as [`DropReason::Covered`]; its category (from Eq. 2
//! on the whole mask) is kept for the visible part.

use super::colour::{ColourClassifier, ColourConfig, MaskColour};
use super::error::PerceptionError;
use super::labelling::{
    label_masks, mode_label, DropReason, DroppedMask, LabelConfig, LabelCounter, LabelMap,
    LabelScore, MaskLabel,
};
use super::mask::Mask;
use map_core::geometry::{Aabb, Point, Polygon, Pose};
use map_core::grid::{Grid, GridFrame};
use map_core::map::{assign_label_ids, Instance, IvlMap, Region};
use map_core::render::{colour_rgb, UNKNOWN_RGB, WALL_RGB};
use map_core::scene::Scene;

/// Everything the map is built from, on one grid frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PerceptionInputs {
    /// Name of the map.
    pub name: String,
    /// The grid every layer and mask lies on.
    pub frame: GridFrame,
    /// Occupied cells (from the reconstruction's heights); copied into the map as is.
    pub obstacles: Grid<bool>,
    /// Top-down RGB map (the paper's B), used for the colour attribute.
    pub rgb: Option<Grid<[u8; 3]>>,
    /// Cells of `rgb` that hold a colour (the reconstruction's `hits > 0`); the
    /// others are left out of the colour vote. `None`: every cell holds one.
    pub rgb_observed: Option<Grid<bool>>,
    /// Per-cell colour labels (argmax of a pixel-colour-text similarity, the paper's
    /// route to colour); when given, it names the colour instead of `rgb`: the most
    /// frequent colour label among the instance's cells.
    pub colour_labels: Option<LabelMap>,
    /// Per-cell category labels and the category list (Eq. 2's input).
    pub labels: LabelMap,
    /// SAM masks; instance ids are `mask index + 1`.
    pub masks: Vec<Mask>,
    /// Named regions (rooms); copied into the map as is.
    pub regions: Vec<Region>,
    /// Robot radius in metres; copied into the map as is.
    pub robot_radius: f64,
    /// The robot's start pose; copied into the map as is.
    pub start_pose: Pose,
}

/// Default robot radius of [`PerceptionInputs::new`], in metres.
pub const DEFAULT_ROBOT_RADIUS_M: f64 = 0.2;

impl PerceptionInputs {
    /// Inputs without RGB, regions or start pose: the robot (radius
    /// [`DEFAULT_ROBOT_RADIUS_M`]) starts at the centre of the frame facing north.
    pub fn new(
        name: impl Into<String>,
        frame: GridFrame,
        obstacles: Grid<bool>,
        labels: LabelMap,
        masks: Vec<Mask>,
    ) -> Self {
        let b = frame.bounds();
        PerceptionInputs {
            name: name.into(),
            frame,
            obstacles,
            rgb: None,
            rgb_observed: None,
            colour_labels: None,
            labels,
            masks,
            regions: Vec::new(),
            robot_radius: DEFAULT_ROBOT_RADIUS_M,
            start_pose: Pose::new((b[0] + b[2]) / 2.0, (b[1] + b[3]) / 2.0, 0.0),
        }
    }

    /// What a perfect perception stack would output for a scene: the label map is
    /// the scene's category layer (label 0 = "other", label k = the k-th category of
    /// [`IvlMap::from_scene`]), one mask per object (its visible cells, in the
    /// scene's object order, so instance id = object index + 1), a top-down RGB
    /// with each object in its colour word's renderer RGB ([`map_core::render::colour_rgb`];
    /// objects without a known colour in [`UNKNOWN_RGB`], walls in [`WALL_RGB`], the
    /// floor in [`FLOOR_RGB`]), and the scene's obstacles, regions and robot.
    /// Noise studies corrupt these inputs and compare the built map with the scene.
    pub fn from_scene(scene: &Scene) -> Self {
        let truth = IvlMap::from_scene(scene);
        let frame = truth.frame;
        let mut categories = vec![OTHER.to_string()];
        categories.extend(truth.categories.iter().cloned());
        let labels = LabelMap::new_trusted(truth.category.clone(), categories);

        let mut rgb = truth
            .obstacles
            .map(|&o| if o { WALL_RGB } else { FLOOR_RGB });
        let index_of: std::collections::HashMap<u32, usize> = scene
            .objects
            .iter()
            .enumerate()
            .map(|(i, o)| (o.id.0, i))
            .collect();
        let mut cells: Vec<Vec<usize>> = vec![Vec::new(); scene.objects.len()];
        let colours: Vec<[u8; 3]> = scene
            .objects
            .iter()
            .map(|o| {
                o.colour
                    .as_ref()
                    .and_then(|c| colour_rgb(&c.0))
                    .unwrap_or(UNKNOWN_RGB)
            })
            .collect();
        let px = rgb.as_mut_slice();
        for (i, &id) in truth.instance.as_slice().iter().enumerate() {
            if let Some(&k) = index_of.get(&id) {
                if let (Some(v), Some(p), Some(c)) =
                    (cells.get_mut(k), px.get_mut(i), colours.get(k))
                {
                    v.push(i);
                    *p = *c;
                }
            }
        }
        let masks = cells
            .iter()
            .map(|idx| Mask::from_sorted_indices(frame.rows, frame.cols, idx))
            .collect();
        PerceptionInputs {
            name: truth.name,
            frame,
            obstacles: truth.obstacles,
            rgb: Some(rgb),
            rgb_observed: None,
            colour_labels: None,
            labels,
            masks,
            regions: truth.regions,
            robot_radius: truth.robot_radius,
            start_pose: truth.start_pose,
        }
    }
}

/// Label 0 of [`PerceptionInputs::from_scene`]'s label map.
pub const OTHER: &str = "other";

/// Floor colour of [`PerceptionInputs::from_scene`]'s RGB map.
pub const FLOOR_RGB: [u8; 3] = [214, 200, 176];

/// Settings of [`build_map`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BuildConfig {
    /// Settings of Eq. 2's mask labelling.
    pub labelling: LabelConfig,
    /// Settings of the colour vote over the top-down RGB.
    pub colour: ColourConfig,
}

/// How an instance got its colour.
#[derive(Debug, Clone, PartialEq)]
pub enum ColourEvidence {
    /// Majority vote over the top-down RGB.
    Rgb(MaskColour),
    /// Most frequent label of the colour label map.
    Labels(LabelScore),
}

/// A mask that became an instance.
#[derive(Debug, Clone, PartialEq)]
pub struct KeptMask {
    /// Instance id in the map (mask index + 1).
    pub instance: u32,
    /// Eq. 2 outcome on the whole mask.
    pub label: MaskLabel,
    /// Cells the instance holds after overlaps are resolved.
    pub visible_area: u64,
    /// Where its colour came from; `None` when it has no colour.
    pub colour: Option<ColourEvidence>,
}

/// The built map and an account of every mask.
#[derive(Debug, Clone, PartialEq)]
pub struct BuiltMap {
    /// The built map.
    pub map: IvlMap,
    /// In mask order.
    pub kept: Vec<KeptMask>,
    /// In mask order.
    pub dropped: Vec<DroppedMask>,
}

fn check_shape(
    frame: &GridFrame,
    what: &str,
    rows: usize,
    cols: usize,
) -> Result<(), PerceptionError> {
    if (rows, cols) != (frame.rows, frame.cols) {
        return Err(PerceptionError::Shape {
            what: what.to_string(),
            rows,
            cols,
            frame_rows: frame.rows,
            frame_cols: frame.cols,
        });
    }
    Ok(())
}

/// Build a map from perception outputs: Eq. 2 labels the masks, overlaps go to
/// the smaller mask, and each surviving mask becomes an instance with its
/// category, colour, area, boxes, centroid and contour (the convex hull of its
/// cells). Errors when a layer or mask does not match the frame's size.
pub fn build_map(
    inputs: &PerceptionInputs,
    config: &BuildConfig,
) -> Result<BuiltMap, PerceptionError> {
    let frame = inputs.frame;
    check_shape(
        &frame,
        "obstacle layer",
        inputs.obstacles.rows(),
        inputs.obstacles.cols(),
    )?;
    let l = inputs.labels.labels();
    check_shape(&frame, "label map", l.rows(), l.cols())?;
    if let Some(g) = &inputs.rgb {
        check_shape(&frame, "RGB map", g.rows(), g.cols())?;
    }
    if let Some(g) = &inputs.rgb_observed {
        check_shape(&frame, "RGB observed layer", g.rows(), g.cols())?;
    }
    if let Some(c) = &inputs.colour_labels {
        check_shape(
            &frame,
            "colour label map",
            c.labels().rows(),
            c.labels().cols(),
        )?;
    }
    for (i, m) in inputs.masks.iter().enumerate() {
        check_shape(&frame, &format!("mask {i}"), m.rows(), m.cols())?;
    }

    let labelling = label_masks(&inputs.labels, &inputs.masks, &config.labelling)?;
    let mut dropped = labelling.dropped;

    // Smallest first = top layer first; each claims the cells no one above has.
    let mut order: Vec<&MaskLabel> = labelling.kept.iter().collect();
    order.sort_by_key(|k| (k.area, k.mask));
    let mut owner = vec![0u32; frame.rows * frame.cols];
    let mut visible: Vec<(&MaskLabel, u32, Mask)> = Vec::new();
    for k in order {
        let Some(mask) = inputs.masks.get(k.mask) else {
            continue;
        };
        let free: u64 = mask
            .runs()
            .iter()
            .map(|&(s, e)| {
                owner
                    .get(s..e)
                    .map_or(0, |o| o.iter().filter(|&&v| v == 0).count()) as u64
            })
            .sum();
        if free < config.labelling.min_area || free == 0 {
            dropped.push(DroppedMask {
                mask: k.mask,
                reason: DropReason::Covered {
                    visible: free,
                    min_area: config.labelling.min_area,
                },
            });
            continue;
        }
        let id = u32::try_from(k.mask + 1).unwrap_or(u32::MAX);
        let mut runs = Vec::new();
        for &(s, e) in mask.runs() {
            let mut open: Option<usize> = None;
            for i in s..e {
                match (owner.get_mut(i), open) {
                    (Some(o), None) if *o == 0 => {
                        *o = id;
                        open = Some(i);
                    }
                    (Some(o), Some(_)) if *o == 0 => *o = id,
                    (_, Some(start)) => {
                        runs.push((start, i));
                        open = None;
                    }
                    _ => {}
                }
            }
            if let Some(start) = open {
                runs.push((start, e));
            }
        }
        visible.push((
            k,
            id,
            Mask::from_runs_unchecked(frame.rows, frame.cols, runs),
        ));
    }
    visible.sort_by_key(|v| v.0.mask);
    dropped.sort_by_key(|d| d.mask);

    let classifier = ColourClassifier::new(config.colour.clone());
    let observed = inputs.rgb_observed.as_ref().map(Mask::from_grid);
    let mut counter = LabelCounter::new();
    let mut categories: Vec<String> = Vec::new();
    let mut colours: Vec<String> = Vec::new();
    let mut instances = Vec::with_capacity(visible.len());
    let mut kept = Vec::with_capacity(visible.len());
    let mut cat_of = vec![0u16; visible.len()];
    let mut col_of = vec![0u8; visible.len()];
    for (n, (label, id, vis)) in visible.iter().enumerate() {
        let name = inputs
            .labels
            .name(label.label)
            .map_or_else(|| format!("label {}", label.label), str::to_string);
        cat_of[n] = id_of(&mut categories, &name).try_into().unwrap_or(u16::MAX);
        let evidence = match (&inputs.colour_labels, &inputs.rgb) {
            (Some(cl), _) => mode_label(&mut counter, cl.labels(), vis, cl.categories().len())
                .map(ColourEvidence::Labels),
            (None, Some(rgb)) => {
                let seen = observed.as_ref().map(|o| vis.intersection(o));
                classifier
                    .classify_mask(rgb, seen.as_ref().unwrap_or(vis))
                    .map(ColourEvidence::Rgb)
            }
            (None, None) => None,
        };
        let color = match &evidence {
            Some(ColourEvidence::Rgb(v)) => Some(v.colour.clone()),
            Some(ColourEvidence::Labels(s)) => inputs
                .colour_labels
                .as_ref()
                .and_then(|cl| cl.name(s.label))
                .map(str::to_string),
            None => None,
        };
        col_of[n] = color
            .as_ref()
            .map_or(0, |c| id_of(&mut colours, c).try_into().unwrap_or(u8::MAX));
        instances.push(instance_of(&frame, *id, name, color, vis));
        kept.push(KeptMask {
            instance: *id,
            label: (*label).clone(),
            visible_area: vis.area(),
            colour: evidence,
        });
    }
    assign_label_ids(&mut instances);

    // Layers from the owner grid.
    // instance id (mask index + 1) -> position in `visible`
    let mut slot = vec![usize::MAX; inputs.masks.len() + 1];
    for (n, v) in visible.iter().enumerate() {
        if let Some(x) = slot.get_mut(v.1 as usize) {
            *x = n;
        }
    }
    let mut category = Grid::new(frame.rows, frame.cols, 0u16);
    let mut colour = Grid::new(frame.rows, frame.cols, 0u8);
    for (i, &o) in owner.iter().enumerate() {
        if o == 0 {
            continue;
        }
        if let Some(&n) = slot.get(o as usize).filter(|&&n| n != usize::MAX) {
            if let Some(c) = category.as_mut_slice().get_mut(i) {
                *c = cat_of[n];
            }
            if let Some(c) = colour.as_mut_slice().get_mut(i) {
                *c = col_of[n];
            }
        }
    }
    let instance = Grid::from_vec(frame.rows, frame.cols, owner)
        .unwrap_or_else(|| Grid::new(frame.rows, frame.cols, 0));

    Ok(BuiltMap {
        map: IvlMap {
            name: inputs.name.clone(),
            frame,
            obstacles: inputs.obstacles.clone(),
            category,
            instance,
            colour,
            categories,
            colours,
            instances,
            regions: inputs.regions.clone(),
            robot_radius: inputs.robot_radius,
            start_pose: inputs.start_pose,
        },
        kept,
        dropped,
    })
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

/// The instance record of a (non-empty) visible mask.
fn instance_of(
    frame: &GridFrame,
    id: u32,
    label: String,
    color: Option<String>,
    vis: &Mask,
) -> Instance {
    let [c0, r0, w, h] = vis.bbox().unwrap_or([0; 4]);
    let (c0, r0, w, h) = (f64::from(c0), f64::from(r0), f64::from(w), f64::from(h));
    let bbox_m = Aabb {
        min: frame.from_grid_f(r0 + h, c0),
        max: frame.from_grid_f(r0, c0 + w),
    };
    let centroid = vis
        .centroid_rc()
        .map_or(bbox_m.center(), |(r, c)| frame.from_grid_f(r, c));
    let cs = frame.cell_size;
    Instance {
        id,
        label,
        label_id: 0,
        num_of_same_class: 0,
        colour: color,
        area: vis.area(),
        area_m2: vis.area() as f64 * cs * cs,
        bbox: vis.bbox().unwrap_or([0; 4]),
        bbox_m,
        centroid,
        contour: cell_hull(frame, vis),
    }
}

/// Convex hull (counter-clockwise, world metres) of the mask's cells as squares:
/// the corners of every row run, by Andrew's monotone chain.
pub(crate) fn cell_hull(frame: &GridFrame, mask: &Mask) -> Polygon {
    let cols = mask.cols().max(1);
    let mut pts: Vec<Point> = Vec::with_capacity(mask.runs().len() * 4);
    for &(s, e) in mask.runs() {
        let (r, c0) = ((s / cols) as f64, (s % cols) as f64);
        let c1 = c0 + (e - s) as f64;
        for (rr, cc) in [(r, c0), (r, c1), (r + 1.0, c0), (r + 1.0, c1)] {
            pts.push(frame.from_grid_f(rr, cc));
        }
    }
    Polygon(convex_hull(pts))
}

/// Andrew's monotone chain: the hull's vertices counter-clockwise, without
/// collinear points.
pub(crate) fn convex_hull(mut pts: Vec<Point>) -> Vec<Point> {
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross =
        |o: Point, a: Point, b: Point| (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
    let mut hull: Vec<Point> = Vec::with_capacity(pts.len() + 1);
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Point>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_a_square_and_an_l_shape() {
        let h = convex_hull(vec![
            Point::new(0.0, 0.0),
            Point::new(1.0, 0.0),
            Point::new(1.0, 1.0),
            Point::new(0.0, 1.0),
            Point::new(0.5, 0.5),
            Point::new(0.5, 0.0),
        ]);
        assert_eq!(h.len(), 4);
        assert!(Polygon(h.clone()).area() > 0.99, "{h:?}");
        // counter-clockwise: positive signed area
        let signed: f64 = (0..h.len())
            .map(|i| {
                let (a, b) = (h[i], h[(i + 1) % h.len()]);
                a.x * b.y - b.x * a.y
            })
            .sum();
        assert!(signed > 0.0);

        let frame = GridFrame::from_bounds([0.0, 0.0, 1.0, 1.0], 0.1);
        // L: a 3-cell column plus one cell to its east at the bottom
        let m = Mask::from_cells(
            10,
            10,
            [(0, 0), (1, 0), (2, 0), (2, 1)].map(|(r, c)| map_core::grid::Cell::new(r, c)),
        );
        let hull = cell_hull(&frame, &m);
        // hull = the L (4 cells) plus the triangle under its step (half of 2 cells)
        assert!(
            (hull.area() - (0.04 + 0.01)).abs() < 1e-9,
            "{}",
            hull.area()
        );
        assert!(hull.contains(frame.cell_center(map_core::grid::Cell::new(1, 0))));
    }
}
