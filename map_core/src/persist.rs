//! Saving an [`IvlMap`] to a folder and loading it back (format "ivlmap-map/1").
//!
//! Folder layout:
//! - `map.json`: `format` ("ivlmap-map/1"), `name`, `frame` (`origin` [x, y] of the
//!   north-west corner of cell (0, 0), `cell_size` m, `rows`, `cols`), `categories`
//!   and `colours` (names; layer id k means entry k - 1), `regions` (`name`,
//!   `polygon` [[x, y], ...]), `robot_radius` m, `start_pose` [x, y, heading_deg].
//! - `instances.json`: the instance table, an array of records with the paper's
//!   Listing-1 fields `label`, `label_id`, `num_of_same_class`, `color`, `area`
//!   (cells), `bbox` ([col, row, width, height] cells) plus `id`, `area_m2`, `bbox_m`
//!   ([xmin, ymin, xmax, ymax] m), `centroid` [x, y] and `contour` [[x, y], ...].
//! - layers, C-order 2-D `.npy` arrays of shape (rows, cols), row 0 = north:
//!   `obstacles.npy` (uint8, 1 = occupied), `category.npy` (uint16),
//!   `instance.npy` (int32: NumPy's default integer for ids; ids are kept below 2^31),
//!   `colour.npy` (uint8).
//!
//! Loading checks each file and then the whole: layer shapes against the frame,
//! instance ids in the instance layer against the table, category and colour ids
//! against the name lists, and each instance's cells against its label and colour.
//! Every error names the file and, where it applies, the field, line and column.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::geometry::{Aabb, Point, Polygon, Pose};
use crate::grid::{Grid, GridFrame};
use crate::map::{Instance, IvlMap, Region};
use crate::npy::{read_npy, write_npy, NpyElement, NpyError};

/// The format tag `map.json` carries.
pub const MAP_FORMAT: &str = "ivlmap-map/1";

const MAP_JSON: &str = "map.json";
const INSTANCES_JSON: &str = "instances.json";
const OBSTACLES_NPY: &str = "obstacles.npy";
const CATEGORY_NPY: &str = "category.npy";
const INSTANCE_NPY: &str = "instance.npy";
const COLOUR_NPY: &str = "colour.npy";

/// Largest grid a map file may declare (cells), so a corrupt header cannot ask for
/// terabytes.
const MAX_CELLS: usize = 400_000_000;

/// Where in a JSON file a problem is: 1-based line and column where known, and the
/// field path (`instances[3].bbox`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct JsonLocation {
    /// 1-based line, where known.
    pub line: Option<usize>,
    /// 1-based column, where known.
    pub column: Option<usize>,
    /// Path of the offending field, e.g. `instances[3].bbox`; empty when unknown.
    pub field: String,
}

impl fmt::Display for JsonLocation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        crate::scene::write_position(f, self.line, self.column, &self.field)
    }
}

/// Why a map folder could not be saved or loaded.
#[derive(Debug, thiserror::Error)]
pub enum PersistError {
    /// A file or folder could not be created, read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder concerned.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A JSON file does not parse into its records, or a record could not be serialised.
    #[error("{}{at}: {message}", path.display())]
    Json {
        /// The JSON file concerned.
        path: PathBuf,
        /// Where in the file the problem is.
        at: JsonLocation,
        /// What serde_json reported.
        message: String,
    },
    /// `map.json` carries a `format` tag other than [`MAP_FORMAT`].
    #[error("{}: field `format`: unknown map format {found:?}; this reader accepts {MAP_FORMAT:?}", path.display())]
    UnknownFormat {
        /// The `map.json` concerned.
        path: PathBuf,
        /// The format tag found in the file.
        found: String,
    },
    /// A layer `.npy` file could not be read or written.
    #[error(transparent)]
    Npy(#[from] NpyError),
    /// A layer's shape differs from the frame's rows and columns in `map.json`.
    #[error(
        "{}: layer shape {rows}x{cols} does not match the frame in map.json ({frame_rows}x{frame_cols})",
        path.display()
    )]
    Shape {
        /// The layer file concerned.
        path: PathBuf,
        /// Rows in the layer.
        rows: usize,
        /// Columns in the layer.
        cols: usize,
        /// Rows the frame declares.
        frame_rows: usize,
        /// Columns the frame declares.
        frame_cols: usize,
    },
    /// A value that parses but contradicts the rest of the map.
    #[error("{}: field `{field}`: {message}", path.display())]
    Invalid {
        /// The file concerned.
        path: PathBuf,
        /// The offending field, e.g. `regions[2].polygon`, or a layer cell `[row, col]`.
        field: String,
        /// What is wrong with the value.
        message: String,
    },
}

impl PersistError {
    fn invalid(path: &Path, field: impl Into<String>, message: impl Into<String>) -> Self {
        PersistError::Invalid {
            path: path.to_path_buf(),
            field: field.into(),
            message: message.into(),
        }
    }
}

/// `map.json`.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct MapFile {
    format: String,
    name: String,
    frame: FrameRecord,
    categories: Vec<String>,
    colours: Vec<String>,
    regions: Vec<RegionRecord>,
    robot_radius: f64,
    start_pose: [f64; 3],
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct FrameRecord {
    origin: [f64; 2],
    cell_size: f64,
    rows: usize,
    cols: usize,
}

/// A region as `map.json` writes it; also the region part of `GET /api/map`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionRecord {
    /// Its name.
    pub name: String,
    /// Outline in metres.
    pub polygon: Vec<[f64; 2]>,
}

impl From<&crate::map::Region> for RegionRecord {
    fn from(r: &crate::map::Region) -> Self {
        RegionRecord {
            name: r.name.clone(),
            polygon: arrs(r.polygon.vertices()),
        }
    }
}

/// Only the format tag, read before anything else so that a file of another
/// format is reported as such rather than as a missing field.
#[derive(Debug, Deserialize)]
struct FormatOnly {
    format: String,
}

/// One row of `instances.json`.
/// Also the instance part of `GET /api/map` (formats.md), so both stay one shape.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InstanceRecord {
    /// Instance id.
    pub id: u32,
    /// Category name.
    pub label: String,
    /// 1-based rank among the same label (west to east, then north to south).
    pub label_id: u32,
    /// Instances with the same label.
    pub num_of_same_class: u32,
    /// Colour word, if known.
    pub color: Option<String>,
    /// Area in cells.
    pub area: u64,
    /// Area in square metres.
    pub area_m2: f64,
    /// `[col, row, width, height]` in cells.
    pub bbox: [u32; 4],
    /// `[xmin, ymin, xmax, ymax]` in metres.
    pub bbox_m: [f64; 4],
    /// `[x, y]` in metres.
    pub centroid: [f64; 2],
    /// Footprint outline in metres.
    pub contour: Vec<[f64; 2]>,
}

fn pts(v: &[[f64; 2]]) -> Vec<Point> {
    v.iter().map(|p| Point::from(*p)).collect()
}

fn arrs(v: &[Point]) -> Vec<[f64; 2]> {
    v.iter().map(|p| [p.x, p.y]).collect()
}

impl From<&Instance> for InstanceRecord {
    fn from(i: &Instance) -> Self {
        InstanceRecord {
            id: i.id,
            label: i.label.clone(),
            label_id: i.label_id,
            num_of_same_class: i.num_of_same_class,
            color: i.colour.clone(),
            area: i.area,
            area_m2: i.area_m2,
            bbox: i.bbox,
            bbox_m: [
                i.bbox_m.min.x,
                i.bbox_m.min.y,
                i.bbox_m.max.x,
                i.bbox_m.max.y,
            ],
            centroid: [i.centroid.x, i.centroid.y],
            contour: arrs(i.contour.vertices()),
        }
    }
}

impl From<InstanceRecord> for Instance {
    fn from(r: InstanceRecord) -> Self {
        Instance {
            id: r.id,
            label: r.label,
            label_id: r.label_id,
            num_of_same_class: r.num_of_same_class,
            colour: r.color,
            area: r.area,
            area_m2: r.area_m2,
            bbox: r.bbox,
            bbox_m: Aabb {
                min: Point::new(r.bbox_m[0], r.bbox_m[1]),
                max: Point::new(r.bbox_m[2], r.bbox_m[3]),
            },
            centroid: r.centroid.into(),
            contour: Polygon(pts(&r.contour)),
        }
    }
}

fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), PersistError> {
    let mut text = serde_json::to_string_pretty(value).map_err(|e| PersistError::Json {
        path: path.to_path_buf(),
        at: JsonLocation {
            line: None,
            column: None,
            field: String::new(),
        },
        message: e.to_string(),
    })?;
    text.push('\n');
    std::fs::write(path, text).map_err(|source| PersistError::Io {
        path: path.to_path_buf(),
        source,
    })
}

fn read_text(path: &Path) -> Result<String, PersistError> {
    std::fs::read_to_string(path).map_err(|source| PersistError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Parse JSON into `T`, reporting line, column and field path on failure.
fn parse_json<T: DeserializeOwned>(path: &Path, text: &str) -> Result<T, PersistError> {
    let de = &mut serde_json::Deserializer::from_str(text);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let field = e.path().to_string();
        let inner = e.into_inner();
        let (line, column) = (inner.line(), inner.column());
        PersistError::Json {
            path: path.to_path_buf(),
            at: JsonLocation {
                line: (line > 0).then_some(line),
                column: (line > 0).then_some(column),
                field,
            },
            message: strip_position(&inner.to_string()),
        }
    })
}

/// serde_json appends " at line L column C"; the location is reported separately.
fn strip_position(msg: &str) -> String {
    match msg.rfind(" at line ") {
        Some(i) => msg[..i].to_string(),
        None => msg.to_string(),
    }
}

fn read_layer<T: NpyElement>(
    dir: &Path,
    file: &str,
    frame: &GridFrame,
) -> Result<Grid<T>, PersistError> {
    let path = dir.join(file);
    let grid: Grid<T> = read_npy(&path)?;
    if grid.rows() != frame.rows || grid.cols() != frame.cols {
        return Err(PersistError::Shape {
            path,
            rows: grid.rows(),
            cols: grid.cols(),
            frame_rows: frame.rows,
            frame_cols: frame.cols,
        });
    }
    Ok(grid)
}

impl IvlMap {
    /// Write the map into folder `dir` (created if missing; existing map files in it
    /// are overwritten). See the module documentation for the layout.
    pub fn save(&self, dir: impl AsRef<Path>) -> Result<(), PersistError> {
        let dir = dir.as_ref();
        std::fs::create_dir_all(dir).map_err(|source| PersistError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        let instance_path = dir.join(INSTANCE_NPY);
        // NumPy's int32 holds the ids; larger ids (possible in a hand-made table)
        // would wrap, so they are refused rather than written wrongly.
        if let Some(i) = self.instances.iter().find(|i| i.id > i32::MAX as u32) {
            return Err(PersistError::invalid(
                &instance_path,
                "instance",
                format!("instance id {} does not fit the int32 layer", i.id),
            ));
        }
        let map_file = MapFile {
            format: MAP_FORMAT.to_string(),
            name: self.name.clone(),
            frame: FrameRecord {
                origin: [self.frame.origin.x, self.frame.origin.y],
                cell_size: self.frame.cell_size,
                rows: self.frame.rows,
                cols: self.frame.cols,
            },
            categories: self.categories.clone(),
            colours: self.colours.clone(),
            regions: self.regions.iter().map(RegionRecord::from).collect(),
            robot_radius: self.robot_radius,
            start_pose: [
                self.start_pose.position.x,
                self.start_pose.position.y,
                self.start_pose.heading,
            ],
        };
        let records: Vec<InstanceRecord> =
            self.instances.iter().map(InstanceRecord::from).collect();
        write_json(&dir.join(MAP_JSON), &map_file)?;
        write_json(&dir.join(INSTANCES_JSON), &records)?;
        write_npy(
            dir.join(OBSTACLES_NPY),
            &self.obstacles.map(|&o| u8::from(o)),
        )?;
        write_npy(dir.join(CATEGORY_NPY), &self.category)?;
        write_npy(&instance_path, &self.instance.map(|&id| id as i32))?;
        write_npy(dir.join(COLOUR_NPY), &self.colour)?;
        Ok(())
    }

    /// Read a map folder written by [`IvlMap::save`] (or by hand / by NumPy), and
    /// check that its files agree with each other.
    pub fn load(dir: impl AsRef<Path>) -> Result<IvlMap, PersistError> {
        let dir = dir.as_ref();
        let map_path = dir.join(MAP_JSON);
        let text = read_text(&map_path)?;
        let tag: FormatOnly = parse_json(&map_path, &text)?;
        if tag.format != MAP_FORMAT {
            return Err(PersistError::UnknownFormat {
                path: map_path,
                found: tag.format,
            });
        }
        let mf: MapFile = parse_json(&map_path, &text)?;
        let frame = check_frame(&map_path, &mf.frame)?;
        if !(mf.robot_radius.is_finite() && mf.robot_radius >= 0.0) {
            return Err(PersistError::invalid(
                &map_path,
                "robot_radius",
                format!("expected a finite number >= 0, got {}", mf.robot_radius),
            ));
        }
        if mf.start_pose.iter().any(|v| !v.is_finite()) {
            return Err(PersistError::invalid(
                &map_path,
                "start_pose",
                "expected finite numbers",
            ));
        }
        check_names(&map_path, "categories", &mf.categories, u16::MAX as usize)?;
        check_names(&map_path, "colours", &mf.colours, u8::MAX as usize)?;
        for (k, r) in mf.regions.iter().enumerate() {
            if r.polygon.len() < 3 || r.polygon.iter().flatten().any(|v| !v.is_finite()) {
                return Err(PersistError::invalid(
                    &map_path,
                    format!("regions[{k}].polygon"),
                    "a polygon needs at least 3 finite vertices",
                ));
            }
        }

        let inst_path = dir.join(INSTANCES_JSON);
        let records: Vec<InstanceRecord> = parse_json(&inst_path, &read_text(&inst_path)?)?;
        let instances: Vec<Instance> = records.into_iter().map(Instance::from).collect();
        check_instances(&inst_path, &instances, &mf.categories, &mf.colours)?;

        let obstacles_u8: Grid<u8> = read_layer(dir, OBSTACLES_NPY, &frame)?;
        if let Some((c, v)) = obstacles_u8.iter_cells().find(|(_, v)| **v > 1) {
            return Err(PersistError::invalid(
                &dir.join(OBSTACLES_NPY),
                format!("[{}, {}]", c.row, c.col),
                format!("obstacle values must be 0 or 1, found {v}"),
            ));
        }
        let obstacles = obstacles_u8.map(|&v| v == 1);
        let category: Grid<u16> = read_layer(dir, CATEGORY_NPY, &frame)?;
        let instance_i32: Grid<i32> = read_layer(dir, INSTANCE_NPY, &frame)?;
        let colour: Grid<u8> = read_layer(dir, COLOUR_NPY, &frame)?;
        if let Some((c, v)) = instance_i32.iter_cells().find(|(_, v)| **v < 0) {
            return Err(PersistError::invalid(
                &dir.join(INSTANCE_NPY),
                format!("[{}, {}]", c.row, c.col),
                format!("instance ids must be >= 0, found {v}"),
            ));
        }
        let instance = instance_i32.map(|&v| v as u32);

        let map = IvlMap {
            name: mf.name,
            frame,
            obstacles,
            category,
            instance,
            colour,
            categories: mf.categories,
            colours: mf.colours,
            instances,
            regions: mf
                .regions
                .into_iter()
                .map(|r| Region {
                    name: r.name,
                    polygon: Polygon(pts(&r.polygon)),
                })
                .collect(),
            robot_radius: mf.robot_radius,
            // not Pose::new: the heading is kept exactly as stored
            start_pose: Pose {
                position: Point::new(mf.start_pose[0], mf.start_pose[1]),
                heading: mf.start_pose[2],
            },
        };
        check_layers(dir, &map)?;
        Ok(map)
    }
}

fn check_frame(path: &Path, f: &FrameRecord) -> Result<GridFrame, PersistError> {
    if !(f.cell_size.is_finite() && f.cell_size > 0.0) {
        return Err(PersistError::invalid(
            path,
            "frame.cell_size",
            format!("expected a finite number > 0, got {}", f.cell_size),
        ));
    }
    if f.origin.iter().any(|v| !v.is_finite()) {
        return Err(PersistError::invalid(
            path,
            "frame.origin",
            "expected finite numbers",
        ));
    }
    if f.rows == 0 || f.cols == 0 || f.rows.checked_mul(f.cols).is_none_or(|n| n > MAX_CELLS) {
        return Err(PersistError::invalid(
            path,
            "frame",
            format!(
                "{} x {} cells is empty or larger than {MAX_CELLS} cells",
                f.rows, f.cols
            ),
        ));
    }
    Ok(GridFrame {
        origin: f.origin.into(),
        cell_size: f.cell_size,
        rows: f.rows,
        cols: f.cols,
    })
}

fn check_names(path: &Path, field: &str, names: &[String], max: usize) -> Result<(), PersistError> {
    if names.len() > max {
        return Err(PersistError::invalid(
            path,
            field,
            format!(
                "{} names, but the layer holds at most {max} ids",
                names.len()
            ),
        ));
    }
    for (k, n) in names.iter().enumerate() {
        if n.trim().is_empty() {
            return Err(PersistError::invalid(
                path,
                format!("{field}[{k}]"),
                "empty name",
            ));
        }
        if names[..k].contains(n) {
            return Err(PersistError::invalid(
                path,
                format!("{field}[{k}]"),
                format!("{n:?} appears twice"),
            ));
        }
    }
    Ok(())
}

fn check_instances(
    path: &Path,
    instances: &[Instance],
    categories: &[String],
    colours: &[String],
) -> Result<(), PersistError> {
    for (k, i) in instances.iter().enumerate() {
        let at = |f: &str| format!("[{k}].{f}");
        if i.id == 0 || i.id > i32::MAX as u32 {
            return Err(PersistError::invalid(
                path,
                at("id"),
                format!("id must be in 1..=2147483647, got {}", i.id),
            ));
        }
        if instances[..k].iter().any(|j| j.id == i.id) {
            return Err(PersistError::invalid(
                path,
                at("id"),
                format!("id {} appears twice", i.id),
            ));
        }
        if !categories.contains(&i.label) {
            return Err(PersistError::invalid(
                path,
                at("label"),
                format!("label {:?} is not among map.json's categories", i.label),
            ));
        }
        if let Some(c) = &i.colour {
            if !colours.contains(c) {
                return Err(PersistError::invalid(
                    path,
                    at("color"),
                    format!("colour {c:?} is not among map.json's colours"),
                ));
            }
        }
        let finite = [
            i.area_m2,
            i.centroid.x,
            i.centroid.y,
            i.bbox_m.min.x,
            i.bbox_m.min.y,
        ]
        .into_iter()
        .chain([i.bbox_m.max.x, i.bbox_m.max.y])
        .chain(i.contour.vertices().iter().flat_map(|p| [p.x, p.y]))
        .all(f64::is_finite);
        if !finite {
            return Err(PersistError::invalid(
                path,
                format!("[{k}]"),
                "non-finite geometry",
            ));
        }
    }
    Ok(())
}

/// The layers against each other and against the tables: ids in range, every
/// instance cell an obstacle with its instance's category and colour.
fn check_layers(dir: &Path, map: &IvlMap) -> Result<(), PersistError> {
    let cat_id = |label: &str| {
        map.categories
            .iter()
            .position(|c| c == label)
            .map(|p| p as u16 + 1)
    };
    let col_id = |colour: &Option<String>| match colour {
        None => Some(0u8),
        Some(c) => map.colours.iter().position(|n| n == c).map(|p| p as u8 + 1),
    };
    // id -> (category id, colour id), for the ids present
    let mut expected: std::collections::HashMap<u32, (u16, u8)> = std::collections::HashMap::new();
    for i in &map.instances {
        if let (Some(c), Some(v)) = (cat_id(&i.label), col_id(&i.colour)) {
            expected.insert(i.id, (c, v));
        }
    }
    let inst_path = dir.join(INSTANCE_NPY);
    let cat_path = dir.join(CATEGORY_NPY);
    let col_path = dir.join(COLOUR_NPY);
    let n_cat = map.categories.len();
    let n_col = map.colours.len();
    let cells = map
        .instance
        .as_slice()
        .iter()
        .zip(map.category.as_slice())
        .zip(map.colour.as_slice())
        .zip(map.obstacles.as_slice());
    for (idx, (((&id, &cat), &col), &occ)) in cells.enumerate() {
        let cell = map.instance.cell_of(idx);
        let at = || format!("[{}, {}]", cell.row, cell.col);
        if usize::from(cat) > n_cat {
            return Err(PersistError::invalid(
                &cat_path,
                at(),
                format!("category id {cat}, but map.json lists {n_cat} categories"),
            ));
        }
        if usize::from(col) > n_col {
            return Err(PersistError::invalid(
                &col_path,
                at(),
                format!("colour id {col}, but map.json lists {n_col} colours"),
            ));
        }
        if id == 0 {
            continue;
        }
        let Some(&(want_cat, want_col)) = expected.get(&id) else {
            return Err(PersistError::invalid(
                &inst_path,
                at(),
                format!("instance id {id} is not in instances.json"),
            ));
        };
        if cat != want_cat {
            return Err(PersistError::invalid(
                &cat_path,
                at(),
                format!("category id {cat} differs from instance {id}'s label (id {want_cat})"),
            ));
        }
        if col != want_col {
            return Err(PersistError::invalid(
                &col_path,
                at(),
                format!("colour id {col} differs from instance {id}'s colour (id {want_col})"),
            ));
        }
        if !occ {
            return Err(PersistError::invalid(
                &dir.join(OBSTACLES_NPY),
                at(),
                format!("cell of instance {id} is not marked occupied"),
            ));
        }
    }
    Ok(())
}
