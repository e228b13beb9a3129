//! `GET /api/map`: the map as JSON for the page to draw (formats.md, "HTTP API").
//!
//! Instance fields are those of a saved map's `instances.json`, plus `description`
//! (words that pick the instance out, [`crate::describe::describe`]) and `region`.
//! Beyond formats.md's fields (additive): `bounds` `[xmin, ymin, xmax, ymax]`,
//! `start_pose`, `robot_radius`, and `obstacles`, the occupied cells as runs per grid
//! row (row 0 is the north edge): `{"encoding": "row-runs", "rows": [[col, len, col,
//! len, ...], ...]}`.

use map_core::persist::{InstanceRecord, RegionRecord};
use map_core::IvlMap;
use serde::Serialize;

/// One instance as `instances.json` writes it, with its description and region.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InstanceJson {
    /// The fields of `instances.json`.
    #[serde(flatten)]
    pub record: InstanceRecord,
    /// Words that pick this instance out ("the second yellow table from the west").
    pub description: Option<String>,
    /// The region its centroid lies in.
    pub region: Option<String>,
}

/// Occupied cells as runs per row.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ObstacleRuns {
    /// Always `row-runs`.
    pub encoding: &'static str,
    /// Per row (north first): `[col, len, col, len, ...]`.
    pub rows: Vec<Vec<u32>>,
}

/// The body of `GET /api/map`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MapJson {
    /// The map's name.
    pub name: String,
    /// The instance table.
    pub instances: Vec<InstanceJson>,
    /// Named regions.
    pub regions: Vec<RegionRecord>,
    /// `[cols, rows]`.
    pub size: [usize; 2],
    /// Metres per cell.
    pub cell_size: f64,
    /// World position of the north-west corner of cell (0, 0).
    pub origin: [f64; 2],
    /// `[xmin, ymin, xmax, ymax]`.
    pub bounds: [f64; 4],
    /// The robot's start pose `[x, y, heading]`.
    pub start_pose: [f64; 3],
    /// Robot radius in metres.
    pub robot_radius: f64,
    /// Occupied cells.
    pub obstacles: ObstacleRuns,
}

/// The map as the page draws it.
#[must_use]
pub fn map_json(map: &IvlMap) -> MapJson {
    let mut instances: Vec<InstanceJson> = map
        .instances
        .iter()
        .map(|i| InstanceJson {
            record: InstanceRecord::from(i),
            description: crate::describe::describe(map, i.id),
            region: map.region_at(i.centroid).map(|r| r.name.clone()),
        })
        .collect();
    instances.sort_by_key(|i| i.record.id);
    let rows = (0..map.obstacles.rows())
        .map(|r| {
            let mut runs = Vec::new();
            let mut start: Option<usize> = None;
            for c in 0..=map.obstacles.cols() {
                let occ = c < map.obstacles.cols()
                    && map
                        .obstacles
                        .get(map_core::Cell::new(r, c))
                        .copied()
                        .unwrap_or(false);
                match (occ, start) {
                    (true, None) => start = Some(c),
                    (false, Some(s)) => {
                        runs.push(u32::try_from(s).unwrap_or(u32::MAX));
                        runs.push(u32::try_from(c - s).unwrap_or(u32::MAX));
                        start = None;
                    }
                    _ => {}
                }
            }
            runs
        })
        .collect();
    MapJson {
        name: map.name.clone(),
        instances,
        regions: map.regions.iter().map(RegionRecord::from).collect(),
        size: [map.frame.cols, map.frame.rows],
        cell_size: map.frame.cell_size,
        origin: [map.frame.origin.x, map.frame.origin.y],
        bounds: map.frame.bounds(),
        start_pose: map.start_pose.to_array(),
        robot_radius: map.robot_radius,
        obstacles: ObstacleRuns {
            encoding: "row-runs",
            rows,
        },
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use map_core::Scene;

    #[test]
    fn runs_cover_exactly_the_occupied_cells() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/scenes/flat-a.scene.json"
        );
        let map = IvlMap::from_scene(&Scene::from_path(path).unwrap());
        let j = map_json(&map);
        assert_eq!(j.size, [map.frame.cols, map.frame.rows]);
        let mut n = 0usize;
        for (r, runs) in j.obstacles.rows.iter().enumerate() {
            for pair in runs.chunks(2) {
                for c in pair[0]..pair[0] + pair[1] {
                    assert!(map
                        .obstacles
                        .get(map_core::Cell::new(r, c as usize))
                        .copied()
                        .unwrap());
                    n += 1;
                }
            }
        }
        assert_eq!(n, map.obstacles.as_slice().iter().filter(|o| **o).count());
        assert_eq!(j.instances.len(), map.instances.len());
        assert!(j.instances.iter().all(|i| i.description.is_some()));
    }
}
