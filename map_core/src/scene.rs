//! Scene files (`ivlmap-scene/1`): a ground-truth room layout that the map is
//! rasterised from. Every malformed case is an error naming the file, the line
//! and column where known, and the field (`objects[2].size`).

use std::collections::HashSet;
use std::fmt;
use std::path::{Path, PathBuf};

use serde::de::{self, Deserializer};
use serde::{Deserialize, Serialize};

use crate::geometry::{oriented_rect, Point, Polygon, Pose};

/// The only format string this reader accepts.
pub const SCENE_FORMAT: &str = "ivlmap-scene/1";

/// A scene file, validated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Format tag; must be [`SCENE_FORMAT`].
    pub format: String,
    /// Scene name; the map and trajectories carry it.
    pub name: String,
    /// [xmin, ymin, xmax, ymax] in metres.
    pub bounds: Bounds,
    /// Grid cell size in metres (default 0.05; 0.005 to 1.0).
    #[serde(default = "default_cell_size")]
    pub cell_size: Positive,
    /// Wall segments (obstacles without an instance).
    #[serde(default)]
    pub walls: Vec<Wall>,
    /// Named regions (rooms).
    #[serde(default)]
    pub regions: Vec<SceneRegion>,
    /// Objects; each becomes an instance of the map.
    #[serde(default)]
    pub objects: Vec<SceneObject>,
    /// The robot's start pose and radius.
    pub robot: SceneRobot,
}

fn default_cell_size() -> Positive {
    Positive(0.05)
}

fn default_thickness() -> Positive {
    Positive(0.1)
}

/// World bounds [xmin, ymin, xmax, ymax] with xmin < xmax and ymin < ymax.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(transparent)]
pub struct Bounds(pub [f64; 4]);

impl<'de> Deserialize<'de> for Bounds {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let b = <[Finite; 4]>::deserialize(d)?;
        let b = [b[0].0, b[1].0, b[2].0, b[3].0];
        if b[0] >= b[2] || b[1] >= b[3] {
            return Err(de::Error::custom(format!(
                "bounds must be [xmin, ymin, xmax, ymax] with xmin < xmax and ymin < ymax, got {b:?}"
            )));
        }
        if (b[2] - b[0]) * (b[3] - b[1]) > 1.0e6 {
            return Err(de::Error::custom(
                "bounds cover more than 1 km^2; is this in metres?",
            ));
        }
        Ok(Bounds(b))
    }
}

/// A finite number.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(transparent)]
pub struct Finite(pub f64);

impl<'de> Deserialize<'de> for Finite {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = f64::deserialize(d)?;
        if v.is_finite() {
            Ok(Finite(v))
        } else {
            Err(de::Error::custom(format!(
                "expected a finite number, got {v}"
            )))
        }
    }
}

/// A finite number > 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(transparent)]
pub struct Positive(pub f64);

impl<'de> Deserialize<'de> for Positive {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Finite::deserialize(d)?.0;
        if v > 0.0 {
            Ok(Positive(v))
        } else {
            Err(de::Error::custom(format!("expected a number > 0, got {v}")))
        }
    }
}

/// A finite [x, y] point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(transparent)]
pub struct XY(pub [f64; 2]);

impl<'de> Deserialize<'de> for XY {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let [x, y] = <[Finite; 2]>::deserialize(d)?;
        Ok(XY([x.0, y.0]))
    }
}

impl From<XY> for Point {
    fn from(p: XY) -> Point {
        Point::new(p.0[0], p.0[1])
    }
}

/// A wall segment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wall {
    /// One end of the centre line, world metres.
    pub from: XY,
    /// The other end of the centre line, world metres.
    pub to: XY,
    /// Thickness in metres (default 0.1).
    #[serde(default = "default_thickness")]
    pub thickness: Positive,
}

/// A named region (a room); not an obstacle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneRegion {
    /// Region name, e.g. "kitchen".
    pub name: NonEmpty,
    /// Outline in world metres.
    pub polygon: PolygonSpec,
}

/// A polygon with at least 3 finite vertices.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(transparent)]
pub struct PolygonSpec(pub Vec<XY>);

impl<'de> Deserialize<'de> for PolygonSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Vec::<XY>::deserialize(d)?;
        if v.len() < 3 {
            return Err(de::Error::custom(format!(
                "a polygon needs at least 3 vertices, got {}",
                v.len()
            )));
        }
        let poly = Polygon(v.iter().map(|p| Point::from(*p)).collect());
        if poly.area() <= 0.0 {
            return Err(de::Error::custom("polygon has zero area"));
        }
        Ok(PolygonSpec(v))
    }
}

/// A non-empty, trimmed, lower-cased word or phrase.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize)]
#[serde(transparent)]
pub struct NonEmpty(pub String);

impl<'de> Deserialize<'de> for NonEmpty {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        let t = s.trim().to_lowercase();
        if t.is_empty() {
            return Err(de::Error::custom("must not be empty"));
        }
        if t.len() > 64 {
            return Err(de::Error::custom("longer than 64 characters"));
        }
        Ok(NonEmpty(t))
    }
}

/// An object: an obstacle with a category, an optional colour and an oriented footprint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneObject {
    /// Unique object id; becomes the instance id.
    pub id: ObjectId,
    /// Category name, e.g. "table".
    pub category: NonEmpty,
    /// Colour word, if known.
    #[serde(default)]
    pub colour: Option<NonEmpty>,
    /// Footprint centre, world metres.
    pub center: XY,
    /// Footprint extent [along x, along y] in metres, before rotation.
    pub size: [Positive; 2],
    /// Footprint rotation in degrees, clockwise (compass sense); 0 when absent.
    #[serde(default)]
    pub yaw: Option<Finite>,
}

impl SceneObject {
    /// The object's footprint polygon in world metres.
    pub fn footprint(&self) -> Polygon {
        oriented_rect(
            self.center.into(),
            [self.size[0].0, self.size[1].0],
            self.yaw.map_or(0.0, |y| y.0),
        )
    }
}

/// A positive integer object id.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(transparent)]
pub struct ObjectId(pub u32);

impl<'de> Deserialize<'de> for ObjectId {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = i64::deserialize(d)?;
        if v >= 1 && v <= i64::from(u32::MAX) {
            Ok(ObjectId(v as u32))
        } else {
            Err(de::Error::custom(format!(
                "id must be a positive integer, got {v}"
            )))
        }
    }
}

/// The robot's start pose and radius.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneRobot {
    /// Start `[x, y, heading]`: metres and compass degrees.
    pub pose: [Finite; 3],
    /// Robot radius in metres.
    pub radius: Positive,
}

impl SceneRobot {
    /// The start pose, heading normalised.
    pub fn pose(&self) -> Pose {
        Pose::new(self.pose[0].0, self.pose[1].0, self.pose[2].0)
    }
}

/// Where a scene problem is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneLocation {
    /// The scene file (or the name the source was given).
    pub file: PathBuf,
    /// 1-based line and column, where the JSON reader knows them.
    pub line: Option<usize>,
    /// 1-based column, where known.
    pub column: Option<usize>,
    /// Field path, e.g. `objects[2].size[0]`.
    pub field: String,
}

impl fmt::Display for SceneLocation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        write_position(f, self.line, self.column, &self.field)
    }
}

/// `:line:column: field `path`` (each part only where known), shared by the scene
/// and saved-map readers.
pub(crate) fn write_position(
    f: &mut fmt::Formatter<'_>,
    line: Option<usize>,
    column: Option<usize>,
    field: &str,
) -> fmt::Result {
    if let Some(l) = line {
        write!(f, ":{l}")?;
        if let Some(c) = column {
            write!(f, ":{c}")?;
        }
    }
    if !field.is_empty() && field != "." {
        write!(f, ": field `{field}`")?;
    }
    Ok(())
}

/// A scene that could not be read.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("{}: cannot read scene file: {source}", path.display())]
    Io {
        /// The scene file concerned.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The JSON is malformed or breaks a scene rule.
    #[error("{at}: {message}")]
    Invalid {
        /// Where the problem is.
        at: SceneLocation,
        /// What is wrong.
        message: String,
    },
}

impl SceneError {
    fn invalid(
        file: &Path,
        line: Option<usize>,
        column: Option<usize>,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        SceneError::Invalid {
            at: SceneLocation {
                file: file.to_path_buf(),
                line,
                column,
                field: field.into(),
            },
            message: message.into(),
        }
    }
}

impl Scene {
    /// Read and validate a scene file.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Scene::from_json_str(&text, path)
    }

    /// Parse and validate scene JSON; `source` names it in errors.
    pub fn from_json_str(text: &str, source: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let file = source.as_ref();
        let de = &mut serde_json::Deserializer::from_str(text);
        let scene: Scene = match serde_path_to_error::deserialize(de) {
            Ok(s) => s,
            Err(e) => {
                let field = e.path().to_string();
                let inner = e.into_inner();
                let (line, col) = (inner.line(), inner.column());
                let msg = strip_position(&inner.to_string());
                return Err(SceneError::invalid(file, Some(line), Some(col), field, msg));
            }
        };
        scene.validate(file, text)?;
        Ok(scene)
    }

    fn validate(&self, file: &Path, text: &str) -> Result<(), SceneError> {
        let line_of = |needle: &str| find_line(text, needle);
        if self.format != SCENE_FORMAT {
            return Err(SceneError::invalid(
                file,
                line_of("\"format\""),
                None,
                "format",
                format!(
                    "unsupported format {:?}, expected {SCENE_FORMAT:?}",
                    self.format
                ),
            ));
        }
        let cs = self.cell_size.0;
        if !(0.005..=1.0).contains(&cs) {
            return Err(SceneError::invalid(
                file,
                line_of("\"cell_size\""),
                None,
                "cell_size",
                format!("cell_size must be between 0.005 and 1.0 m, got {cs}"),
            ));
        }
        let b = self.bounds.0;
        let cells = ((b[2] - b[0]) / cs) * ((b[3] - b[1]) / cs);
        if cells > 25.0e6 {
            return Err(SceneError::invalid(
                file,
                line_of("\"bounds\""),
                None,
                "bounds",
                format!("the grid would have {cells:.0} cells (limit 25 million); use a larger cell_size"),
            ));
        }
        let inside = |p: Point| p.x >= b[0] && p.x <= b[2] && p.y >= b[1] && p.y <= b[3];
        let mut ids = HashSet::new();
        for (i, o) in self.objects.iter().enumerate() {
            let line = line_of(&format!("\"id\": {}", o.id.0))
                .or_else(|| line_of(&format!("\"id\":{}", o.id.0)));
            if !ids.insert(o.id.0) {
                return Err(SceneError::invalid(
                    file,
                    line,
                    None,
                    format!("objects[{i}].id"),
                    format!("duplicate object id {}", o.id.0),
                ));
            }
            if !inside(o.center.into()) {
                return Err(SceneError::invalid(
                    file,
                    line,
                    None,
                    format!("objects[{i}].center"),
                    format!(
                        "object {} centre {:?} lies outside the bounds {:?}",
                        o.id.0, o.center.0, b
                    ),
                ));
            }
            if o.size[0].0 > 100.0 || o.size[1].0 > 100.0 {
                return Err(SceneError::invalid(
                    file,
                    line,
                    None,
                    format!("objects[{i}].size"),
                    "object larger than 100 m",
                ));
            }
            if o.category
                .0
                .chars()
                .any(|c| !(c.is_alphanumeric() || c == ' ' || c == '_' || c == '-'))
            {
                return Err(SceneError::invalid(
                    file,
                    line,
                    None,
                    format!("objects[{i}].category"),
                    format!(
                        "category {:?} must be a plain noun (letters, digits, spaces)",
                        o.category.0
                    ),
                ));
            }
        }
        let mut names = HashSet::new();
        for (i, r) in self.regions.iter().enumerate() {
            if !names.insert(r.name.0.clone()) {
                return Err(SceneError::invalid(
                    file,
                    line_of(&format!("\"{}\"", r.name.0)),
                    None,
                    format!("regions[{i}].name"),
                    format!("duplicate region name {:?}", r.name.0),
                ));
            }
        }
        let p = self.robot.pose();
        if !inside(p.position) {
            return Err(SceneError::invalid(
                file,
                line_of("\"robot\""),
                None,
                "robot.pose",
                format!(
                    "robot pose {:?} lies outside the bounds {:?}",
                    p.to_array(),
                    b
                ),
            ));
        }
        if self.robot.radius.0 > 5.0 {
            return Err(SceneError::invalid(
                file,
                line_of("\"radius\""),
                None,
                "robot.radius",
                "robot radius over 5 m",
            ));
        }
        Ok(())
    }
}

/// serde_json appends " at line L column C"; we report the position separately.
fn strip_position(msg: &str) -> String {
    match msg.rfind(" at line ") {
        Some(i) => msg[..i].to_string(),
        None => msg.to_string(),
    }
}

/// 1-based line of the first occurrence of `needle`.
fn find_line(text: &str, needle: &str) -> Option<usize> {
    text.find(needle)
        .map(|i| text[..i].matches('\n').count() + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    const OK: &str = r#"{
  "format": "ivlmap-scene/1",
  "name": "t",
  "bounds": [0.0, 0.0, 4.0, 3.0],
  "objects": [
    {"id": 1, "category": "Sofa", "colour": "red", "center": [2.0, 1.5], "size": [1.0, 0.5]}
  ],
  "robot": {"pose": [0.5, 0.5, 0.0], "radius": 0.2}
}"#;

    fn err(text: &str) -> String {
        Scene::from_json_str(text, "x.scene.json")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn valid_scene_loads_with_defaults() {
        let s = Scene::from_json_str(OK, "x.scene.json").unwrap();
        assert_eq!(s.cell_size.0, 0.05);
        assert_eq!(s.objects[0].category.0, "sofa");
        assert!(s.walls.is_empty());
    }

    #[test]
    fn negative_size_names_line_and_field() {
        let e = err(&OK.replace("[1.0, 0.5]", "[1.0, -0.5]"));
        assert!(e.starts_with("x.scene.json:6:"), "{e}");
        assert!(e.contains("field `objects[0].size[1]`"), "{e}");
        assert!(e.contains("> 0"), "{e}");
    }

    #[test]
    fn unknown_field_is_rejected_with_its_name() {
        let e = err(&OK
            .replace("\"yaw\"", "\"x\"")
            .replace("\"size\": [1.0, 0.5]", "\"size\": [1.0, 0.5], \"colr\": 1"));
        assert!(e.contains("colr"), "{e}");
        assert!(e.contains("objects[0]"), "{e}");
    }

    #[test]
    fn wrong_format_and_duplicate_ids_are_named() {
        let e = err(&OK.replace("ivlmap-scene/1", "ivlmap-scene/9"));
        assert!(e.contains("x.scene.json:2: field `format`"), "{e}");
        let dup = OK.replace(
            "\"size\": [1.0, 0.5]}",
            "\"size\": [1.0, 0.5]},\n    {\"id\": 1, \"category\": \"chair\", \"center\": [1.0, 1.0], \"size\": [0.5, 0.5]}",
        );
        let e = err(&dup);
        assert!(
            e.contains("objects[1].id") && e.contains("duplicate object id 1"),
            "{e}"
        );
    }

    #[test]
    fn bad_bounds_and_outside_objects_are_errors() {
        let e = err(&OK.replace("[0.0, 0.0, 4.0, 3.0]", "[4.0, 0.0, 0.0, 3.0]"));
        assert!(e.contains("field `bounds`"), "{e}");
        let e = err(&OK.replace("[2.0, 1.5]", "[9.0, 1.5]"));
        assert!(e.contains("objects[0].center"), "{e}");
        let e = err(&OK.replace("[0.5, 0.5, 0.0]", "[0.5, 50.5, 0.0]"));
        assert!(e.contains("robot.pose"), "{e}");
    }

    #[test]
    fn syntax_error_has_line_and_column() {
        let e = err("{\n  \"format\": \"ivlmap-scene/1\",\n  \"name\": ,\n}");
        assert!(e.starts_with("x.scene.json:3:"), "{e}");
    }

    #[test]
    fn missing_file_names_the_path() {
        let e = Scene::from_path("/nonexistent/a.scene.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("/nonexistent/a.scene.json"), "{e}");
    }
}
