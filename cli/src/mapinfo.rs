//! Loading a map from a scene file or a saved map folder, the inspection table, and
//! rendering with a trajectory overlay.

use std::fmt::Write as _;
use std::path::Path;

use map_core::render::{render_png, RenderOptions, RenderOverlay};
use map_core::{IvlMap, Point, Pose, Scene, Trajectory};

use crate::error::CliError;

/// A scene file (`*.scene.json`) rasterised, or a map folder saved by `ivlmap map save`.
///
/// # Errors
/// [`CliError::Input`] naming the file and what is wrong with it.
pub fn load_map(path: &Path) -> Result<IvlMap, CliError> {
    if path.is_dir() {
        IvlMap::load(path).map_err(CliError::input)
    } else if path.exists() {
        let scene = Scene::from_path(path).map_err(CliError::input)?;
        Ok(IvlMap::from_scene(&scene))
    } else {
        Err(CliError::Input(format!(
            "{}: no such file or folder (give a .scene.json file or a folder saved by `ivlmap map save`)",
            path.display()
        )))
    }
}

/// The instance table and region list of `ivlmap map inspect`.
#[must_use]
pub fn inspect_table(map: &IvlMap) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "map {:?}: {} x {} cells of {:.3} m, bounds {:?}, {} instances, {} regions",
        map.name,
        map.frame.cols,
        map.frame.rows,
        map.frame.cell_size,
        map.frame.bounds(),
        map.instances.len(),
        map.regions.len()
    );
    let _ = writeln!(
        out,
        "{:>4}  {:<12} {:>7}  {:<8} {:>8}  {:>16}  region",
        "id", "label", "k/n", "colour", "area m2", "centroid (x, y)"
    );
    let mut inst: Vec<_> = map.instances.iter().collect();
    inst.sort_by_key(|i| i.id);
    for i in inst {
        let c = i.centroid;
        let region = map.region_at(c).map_or("-", |r| r.name.as_str());
        let _ = writeln!(
            out,
            "{:>4}  {:<12} {:>7}  {:<8} {:>8.2}  {:>16}  {}",
            i.id,
            i.label,
            format!("{}/{}", i.label_id, i.num_of_same_class),
            i.colour.as_deref().unwrap_or("-"),
            i.area_m2,
            format!("({:.2}, {:.2})", c.x, c.y),
            region
        );
    }
    if !map.regions.is_empty() {
        let _ = writeln!(out, "regions:");
        for r in &map.regions {
            let c = r.polygon.centroid();
            let _ = writeln!(
                out,
                "  {:<14} area {:>6.2} m2, centre ({:.2}, {:.2})",
                r.name,
                r.polygon.area(),
                c.x,
                c.y
            );
        }
    }
    let s = map.start_pose;
    let _ = writeln!(
        out,
        "robot start: ({:.2}, {:.2}) heading {:.0}, radius {:.2} m",
        s.position.x, s.position.y, s.heading, map.robot_radius
    );
    out
}

/// The stops of a trajectory as the renderer wants them.
#[must_use]
pub fn overlay_stops(t: &Trajectory) -> Vec<(Pose, String)> {
    t.stops
        .iter()
        .map(|s| (Pose::new(s.pose[0], s.pose[1], s.pose[2]), s.call.clone()))
        .collect()
}

/// Renders `map` (and `trajectory`, when given) to a PNG.
///
/// # Errors
/// [`CliError::Output`] when the file cannot be written.
pub fn render_map(
    map: &IvlMap,
    trajectory: Option<&Trajectory>,
    out: &Path,
) -> Result<(), CliError> {
    let path: Vec<Point> = trajectory
        .map(|t| t.path.iter().map(|p| Point::new(p[0], p[1])).collect())
        .unwrap_or_default();
    let stops = trajectory.map(overlay_stops).unwrap_or_default();
    let overlay = RenderOverlay {
        path: &path,
        stops: &stops,
        final_pose: trajectory
            .map(|t| Pose::new(t.final_pose[0], t.final_pose[1], t.final_pose[2])),
    };
    render_png(map, &overlay, &RenderOptions::default(), out).map_err(|e| CliError::output(out, e))
}
