//! Every scene in `examples/scenes/` is a usable test world: it parses, no object
//! overlaps a wall or another object, every object has free space around it once
//! obstacles are inflated by the robot radius, that space (and every named region)
//! is reachable from the robot's start, the regions cover the rooms, and the scene
//! has the variety the navigation suites rely on (several instances of a category in
//! different colours, a row of 3+ same-category objects, rotated objects).

// Test helpers outside #[test] functions may unwrap and panic too.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::collections::{HashMap, VecDeque};
use std::path::PathBuf;

use map_core::planner::inflate;
use map_core::{Cell, Grid, GridFrame, GridPlanner, IvlMap, Point, Scene};

fn scene_paths() -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/scenes");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".scene.json"))
        .collect();
    v.sort();
    v
}

/// Cells whose centre lies inside the polygon (the rasteriser's rule).
fn footprint_cells(frame: &GridFrame, poly: &map_core::Polygon) -> Vec<Cell> {
    let mut out = Vec::new();
    for r in 0..frame.rows {
        for c in 0..frame.cols {
            let cell = Cell::new(r, c);
            if poly.contains(frame.cell_center(cell)) {
                out.push(cell);
            }
        }
    }
    out
}

/// Cells reachable from `start` through free cells of the planner (8-connected, as
/// the planner moves), found by a plain flood fill and cross-checked with
/// `GridPlanner::connected` by the caller.
fn reachable(planner: &GridPlanner, start: Cell) -> Grid<bool> {
    let (rows, cols) = (planner.rows(), planner.cols());
    let mut seen = Grid::new(rows, cols, false);
    let mut q = VecDeque::from([start]);
    seen.set(start, true);
    while let Some(c) = q.pop_front() {
        for dr in -1isize..=1 {
            for dc in -1isize..=1 {
                let (r, k) = (c.row as isize + dr, c.col as isize + dc);
                if (dr, dc) == (0, 0) || !seen.in_bounds(r, k) {
                    continue;
                }
                let n = Cell::new(r as usize, k as usize);
                // no corner cutting, like the planner
                let side_a = Cell::new(c.row, n.col);
                let side_b = Cell::new(n.row, c.col);
                if planner.is_free(n)
                    && planner.is_free(side_a)
                    && planner.is_free(side_b)
                    && !seen.get(n).unwrap()
                {
                    seen.set(n, true);
                    q.push_back(n);
                }
            }
        }
    }
    seen
}

#[test]
fn there_are_at_least_three_example_scenes() {
    let names: Vec<String> = scene_paths()
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    for want in [
        "flat-a.scene.json",
        "office-b.scene.json",
        "house-c.scene.json",
    ] {
        assert!(
            names.iter().any(|n| n == want),
            "missing {want} in {names:?}"
        );
    }
}

#[test]
fn example_scenes_are_valid_reachable_and_varied() {
    for path in scene_paths() {
        let name = path.display().to_string();
        let scene = Scene::from_path(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.cell_size.0, 0.05, "{name}");
        let [x0, y0, x1, y1] = scene.bounds.0;
        let (w, h) = (x1 - x0, y1 - y0);
        assert!(
            (10.0..=16.0).contains(&w) && (8.0..=12.0).contains(&h),
            "{name}: {w} x {h} m"
        );
        let n = scene.objects.len();
        assert!((15..=30).contains(&n), "{name}: {n} objects");

        let map = IvlMap::from_scene(&scene);
        let frame = map.frame;
        let mut walls_only = scene.clone();
        walls_only.objects.clear();
        let walls = IvlMap::from_scene(&walls_only).obstacles;

        // Objects: inside the bounds, not on walls, not on each other.
        let mut owner: HashMap<Cell, u32> = HashMap::new();
        let mut cells_of: HashMap<u32, Vec<Cell>> = HashMap::new();
        for o in &scene.objects {
            let poly = o.footprint();
            let bb = poly.bbox().unwrap();
            assert!(
                bb.min.x >= x0 && bb.min.y >= y0 && bb.max.x <= x1 && bb.max.y <= y1,
                "{name}: object {} leaves the bounds",
                o.id.0
            );
            let cells = footprint_cells(&frame, &poly);
            assert!(
                !cells.is_empty(),
                "{name}: object {} covers no cell",
                o.id.0
            );
            for &c in &cells {
                assert!(
                    !walls.get(c).unwrap(),
                    "{name}: object {} ({}) overlaps a wall at {:?}",
                    o.id.0,
                    o.category.0,
                    frame.cell_center(c)
                );
                if let Some(other) = owner.insert(c, o.id.0) {
                    panic!(
                        "{name}: objects {other} and {} overlap at {:?}",
                        o.id.0,
                        frame.cell_center(c)
                    );
                }
            }
            cells_of.insert(o.id.0, cells);
        }

        // Inflate by the robot radius and search from the start.
        let radius_cells = map.robot_radius / frame.cell_size;
        let planner = GridPlanner::new(inflate(&map.obstacles, radius_cells));
        let start = frame
            .cell_at(map.start_pose.position)
            .unwrap_or_else(|| panic!("{name}: start outside the map"));
        assert!(
            planner.is_free(start),
            "{name}: start pose is in an inflated obstacle"
        );
        let reach = reachable(&planner, start);

        // Every object: some reachable free cell within 0.5 m of its footprint.
        for inst in &map.instances {
            let near: Vec<Cell> = reach
                .iter_cells()
                .filter(|(c, r)| **r && inst.distance(frame.cell_center(*c)) <= 0.5)
                .map(|(c, _)| c)
                .collect();
            assert!(
                !near.is_empty(),
                "{name}: object {} ({} {:?}) has no reachable free cell within 0.5 m",
                inst.id,
                inst.label,
                inst.colour
            );
            // the planner agrees
            assert!(
                planner.connected(start, near[0]),
                "{name}: planner disagrees on object {}",
                inst.id
            );
            assert!(
                planner.plan(start, near[near.len() / 2]).is_ok(),
                "{name}: no plan to object {}",
                inst.id
            );
        }

        // Regions: at least 4, each reachable, together covering the free space.
        assert!(
            map.regions.len() >= 4,
            "{name}: {} regions",
            map.regions.len()
        );
        for r in &map.regions {
            let inside = reach
                .iter_cells()
                .filter(|(c, ok)| **ok && r.polygon.contains(frame.cell_center(*c)))
                .count();
            assert!(
                inside > 100,
                "{name}: region {} has only {inside} reachable cells",
                r.name
            );
        }
        let free: Vec<Cell> = map
            .obstacles
            .iter_cells()
            .filter(|(_, occ)| !**occ)
            .map(|(c, _)| c)
            .collect();
        let covered = free
            .iter()
            .filter(|c| {
                let p: Point = frame.cell_center(**c);
                map.regions.iter().any(|r| r.polygon.contains(p))
            })
            .count();
        assert!(
            covered as f64 >= 0.97 * free.len() as f64,
            "{name}: regions cover only {covered} of {} free cells",
            free.len()
        );
        // Nearly all free space is reachable (no sealed rooms).
        let reached = reach.as_slice().iter().filter(|r| **r).count();
        let inflated_free = (0..frame.rows)
            .flat_map(|r| (0..frame.cols).map(move |c| Cell::new(r, c)))
            .filter(|c| planner.is_free(*c))
            .count();
        assert!(
            reached as f64 >= 0.97 * inflated_free as f64,
            "{name}: only {reached} of {inflated_free} free cells reachable"
        );

        // Variety for the suites.
        let counts = map.label_counts();
        assert!(
            counts.iter().any(|(_, k)| *k >= 4),
            "{name}: no category with 4+ instances: {counts:?}"
        );
        let multi_colour = counts.iter().filter(|(label, k)| {
            let mut cols: Vec<_> = map
                .instances
                .iter()
                .filter(|i| &i.label == label)
                .filter_map(|i| i.colour.clone())
                .collect();
            cols.sort();
            cols.dedup();
            *k >= 2 && cols.len() >= 2
        });
        assert!(
            multi_colour.count() >= 2,
            "{name}: fewer than two categories in several colours"
        );
        assert!(
            scene
                .objects
                .iter()
                .any(|o| o.yaw.is_some_and(|y| y.0 % 90.0 != 0.0)),
            "{name}: no object at an oblique yaw"
        );
        assert!(
            has_row_of_three(&map),
            "{name}: no row of 3+ same-category objects"
        );
    }
}

/// Three instances of one category whose centres lie on a line (same x or same y
/// within 5 cm) and are spaced at most 2.0 m apart.
fn has_row_of_three(map: &IvlMap) -> bool {
    let insts = &map.instances;
    for a in insts {
        for axis in [0, 1] {
            let key = |p: Point| if axis == 0 { (p.y, p.x) } else { (p.x, p.y) };
            let mut row: Vec<f64> = insts
                .iter()
                .filter(|b| {
                    b.label == a.label && (key(b.center()).0 - key(a.center()).0).abs() < 0.05
                })
                .map(|b| key(b.center()).1)
                .collect();
            row.sort_by(f64::total_cmp);
            if row
                .windows(3)
                .any(|w| w[1] - w[0] <= 2.0 && w[2] - w[1] <= 2.0)
            {
                return true;
            }
        }
    }
    false
}

/// "The plant in the lounge": only objects whose centroid lies in the room count, k
/// counts among them, and a room without one says how many there are elsewhere.
#[test]
fn objects_in_a_region_are_those_inside_it() {
    use map_core::{ObjectOrder, QueryError};
    let mut inside_any = 0;
    let mut none_in = 0;
    for path in scene_paths() {
        let map = IvlMap::from_scene(&Scene::from_path(&path).unwrap());
        let mut labels: Vec<String> = map.instances.iter().map(|i| i.label.clone()).collect();
        labels.sort();
        labels.dedup();
        for r in &map.regions {
            for label in &labels {
                let inside: Vec<u32> = map
                    .instances
                    .iter()
                    .filter(|i| &i.label == label && r.polygon.contains(i.centroid))
                    .map(|i| i.id)
                    .collect();
                let got = map.get_obj_in_region(
                    label,
                    &r.name,
                    0,
                    None,
                    ObjectOrder::NearToFar,
                    map.start_pose,
                );
                match got {
                    Ok(i) => {
                        assert!(inside.contains(&i.id), "{label} in {}", r.name);
                        inside_any += 1;
                        // The last in the region is in it too, and past the count errs.
                        let last = map
                            .get_obj_in_region(
                                label,
                                &r.name,
                                -1,
                                None,
                                ObjectOrder::WestToEast,
                                map.start_pose,
                            )
                            .unwrap();
                        assert!(inside.contains(&last.id));
                        let past = map.get_obj_in_region(
                            label,
                            &r.name,
                            inside.len() as i64 + 1,
                            None,
                            ObjectOrder::NearToFar,
                            map.start_pose,
                        );
                        assert!(
                            matches!(past, Err(QueryError::OrdinalPastCount { count, .. }) if count == inside.len())
                        );
                    }
                    Err(QueryError::NoneInRegion { elsewhere, .. }) => {
                        assert!(inside.is_empty());
                        assert!(elsewhere >= 1);
                        none_in += 1;
                    }
                    Err(e) => panic!("{label} in {}: {e}", r.name),
                }
            }
        }
    }
    assert!(inside_any >= 10 && none_in >= 10, "{inside_any} {none_in}");
}
