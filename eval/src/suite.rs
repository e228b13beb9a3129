//! Reading suites: extraction suites (`*.extract.jsonl`) and navigation suites
//! (`*.nav.jsonl`) of formats.md. Every problem is reported with the file, the
//! 1-based line and the field (`subgoals[2].object`), and says what was expected.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use map_core::{IvlMap, Pose, Scene, SceneError};
use serde::{Deserialize, Serialize};
use serde_json::Value;

use agent::Tuple;

/// Which kind of suite a file holds, from its name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SuiteKind {
    /// `*.extract.jsonl`: instructions with the tuples they mention.
    Extract,
    /// `*.nav.jsonl`: multi-subgoal navigation tasks on a scene.
    Nav,
    /// `*.chat.jsonl`: dialogues, turns in one session.
    Chat,
}

impl SuiteKind {
    /// The kind named by the file's suffix, or an error saying which suffixes exist.
    ///
    /// # Errors
    /// [`SuiteError::UnknownKind`] when the name ends in neither suffix.
    pub fn from_path(path: &Path) -> Result<SuiteKind, SuiteError> {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .unwrap_or_default();
        if name.ends_with(".extract.jsonl") {
            Ok(SuiteKind::Extract)
        } else if name.ends_with(".nav.jsonl") {
            Ok(SuiteKind::Nav)
        } else if name.ends_with(".chat.jsonl") {
            Ok(SuiteKind::Chat)
        } else {
            Err(SuiteError::UnknownKind {
                file: path.to_path_buf(),
            })
        }
    }
}

/// Why a suite could not be read. Messages start with `file:line:` where a line applies.
#[derive(Debug, thiserror::Error)]
pub enum SuiteError {
    /// The suite file cannot be read.
    #[error("{}: cannot read suite file: {source}", file.display())]
    Io {
        /// The suite file.
        file: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The name does not say which kind of suite it is.
    #[error("{}: cannot tell the suite kind: the file name must end in .extract.jsonl, .nav.jsonl or .chat.jsonl", file.display())]
    UnknownKind {
        /// The suite file.
        file: PathBuf,
    },
    /// A line is not a JSON object.
    #[error("{}:{line}: not a JSON object: {message}", file.display())]
    Json {
        /// The suite file.
        file: PathBuf,
        /// 1-based line.
        line: usize,
        /// What serde_json said.
        message: String,
    },
    /// A field is missing or has the wrong shape or value.
    #[error("{}:{line}: field `{field}`: {message}", file.display())]
    Field {
        /// The suite file.
        file: PathBuf,
        /// 1-based line.
        line: usize,
        /// The field, e.g. `subgoals[1].region`.
        field: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A task's scene file could not be loaded.
    #[error("{}:{line}: field `scene`: {source}", file.display())]
    Scene {
        /// The suite file.
        file: PathBuf,
        /// 1-based line of the task naming the scene.
        line: usize,
        /// The scene reader's error (names the scene file and field).
        #[source]
        source: Box<SceneError>,
    },
    /// The suite holds no case at all.
    #[error("{}: the suite is empty (no non-blank lines)", file.display())]
    Empty {
        /// The suite file.
        file: PathBuf,
    },
}

/// One extraction case.
#[derive(Debug, Clone, PartialEq)]
pub struct ExtractCase {
    /// Case id (unique in the suite).
    pub id: String,
    /// The instruction.
    pub instruction: String,
    /// Every object the instruction mentions, in order of mention.
    pub expected: Vec<Tuple>,
    /// 1-based line in the suite file.
    pub line: usize,
}

/// What a navigation subgoal asks the robot to reach.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Subgoal {
    /// An object of the scene, by id: a stop within 1.0 m of its footprint.
    Object(u32),
    /// A region of the scene, by name: a stop inside its polygon.
    Region(String),
    /// A point: a stop within 1.0 m of it.
    Point([f64; 2]),
}

/// One navigation task.
#[derive(Debug, Clone)]
pub struct NavTask {
    /// Task id (unique in the suite).
    pub id: String,
    /// The scene file, resolved against the suite's folder.
    pub scene_path: PathBuf,
    /// The map of the scene (shared between tasks on the same scene).
    pub map: Arc<IvlMap>,
    /// Where the robot starts (the scene's robot pose when the task gives none).
    pub start: Pose,
    /// The instruction.
    pub instruction: String,
    /// What must be reached, in order.
    pub subgoals: Vec<Subgoal>,
    /// A hand-written Rhai plan that reaches every subgoal (optional; additive field).
    pub reference: Option<String>,
    /// 1-based line in the suite file.
    pub line: usize,
}

/// Reads an extraction suite.
///
/// # Errors
/// [`SuiteError`] naming the file, line and field of the first problem.
pub fn load_extract_suite(path: &Path) -> Result<Vec<ExtractCase>, SuiteError> {
    let mut ids = HashSet::new();
    let mut cases = Vec::new();
    for (line, obj) in json_lines(path)? {
        let at = At { file: path, line };
        let id = at.id(&obj, &mut ids)?;
        let instruction = at.string(&obj, "instruction")?;
        let expected =
            match obj.get("expected") {
                Some(Value::Array(items)) => items
                    .iter()
                    .enumerate()
                    .map(|(i, v)| at.tuple(v, &format!("expected[{i}]")))
                    .collect::<Result<Vec<_>, _>>()?,
                Some(_) => {
                    return Err(at.field("expected", "must be a list of tuples (it may be empty)"))
                }
                None => return Err(at.field(
                    "expected",
                    "is missing (a list of {\"object\", \"ordinal\", \"colour\"}; it may be empty)",
                )),
            };
        cases.push(ExtractCase {
            id,
            instruction,
            expected,
            line,
        });
    }
    Ok(cases)
}

/// Reads a navigation suite, loading each scene once (relative to the suite's folder)
/// and checking every subgoal against it: object ids that exist, region names that exist.
///
/// # Errors
/// [`SuiteError`] naming the file, line and field of the first problem.
pub fn load_nav_suite(path: &Path) -> Result<Vec<NavTask>, SuiteError> {
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut maps: HashMap<PathBuf, Arc<IvlMap>> = HashMap::new();
    let mut ids = HashSet::new();
    let mut tasks = Vec::new();
    for (line, obj) in json_lines(path)? {
        let at = At { file: path, line };
        let id = at.id(&obj, &mut ids)?;
        let (scene_path, map, start) = at.scene_and_start(&obj, &dir, &mut maps)?;
        let instruction = at.string(&obj, "instruction")?;
        let subgoals =
            match obj.get("subgoals") {
                Some(Value::Array(items)) if !items.is_empty() => items
                    .iter()
                    .enumerate()
                    .map(|(i, v)| at.subgoal(v, i, &map))
                    .collect::<Result<Vec<_>, _>>()?,
                Some(Value::Array(_)) => {
                    return Err(at.field("subgoals", "is empty: list at least one subgoal"))
                }
                Some(_) => return Err(at.field(
                    "subgoals",
                    "must be a list of {\"object\": id}, {\"region\": name} or {\"point\": [x, y]}",
                )),
                None => return Err(at.field("subgoals", "is missing")),
            };
        let reference = match obj.get("reference") {
            None | Some(Value::Null) => None,
            Some(Value::String(s)) => Some(s.clone()),
            Some(_) => return Err(at.field("reference", "must be a string (a Rhai plan)")),
        };
        tasks.push(NavTask {
            id,
            scene_path,
            map,
            start,
            instruction,
            subgoals,
            reference,
            line,
        });
    }
    Ok(tasks)
}

/// One turn of a dialogue.
#[derive(Debug, Clone)]
pub struct ChatTurn {
    /// What the person says.
    pub say: String,
    /// Where this turn must stop (scored on this turn's stops).
    pub subgoals: Vec<Subgoal>,
    /// `"expect": "question"`: the product should ask instead of moving.
    pub expect_question: bool,
}

/// One dialogue of a chat suite.
#[derive(Debug, Clone)]
pub struct Dialogue {
    /// Case id.
    pub id: String,
    /// The scene file (resolved against the suite's folder).
    pub scene_path: PathBuf,
    /// The map built from it (shared between dialogues on one scene).
    pub map: Arc<IvlMap>,
    /// Where the robot starts.
    pub start: Pose,
    /// The turns, in order.
    pub turns: Vec<ChatTurn>,
    /// 1-based line in the suite file.
    pub line: usize,
}

/// Reads a chat suite (formats.md, "Chat suite"), loading each scene once and checking
/// every subgoal against it.
///
/// # Errors
/// [`SuiteError`] naming the file, line and field (`turns[1].subgoals[0].object`).
pub fn load_chat_suite(path: &Path) -> Result<Vec<Dialogue>, SuiteError> {
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut maps: HashMap<PathBuf, Arc<IvlMap>> = HashMap::new();
    let mut ids = HashSet::new();
    let mut out = Vec::new();
    for (line, obj) in json_lines(path)? {
        let at = At { file: path, line };
        let id = at.id(&obj, &mut ids)?;
        let (scene_path, map, start) = at.scene_and_start(&obj, &dir, &mut maps)?;
        let items = match obj.get("turns") {
            Some(Value::Array(items)) if !items.is_empty() => items,
            Some(Value::Array(_)) => {
                return Err(at.field("turns", "is empty: list at least one turn"))
            }
            Some(v) => {
                return Err(at.field(
                    "turns",
                    format!(
                        "must be a list of {{\"say\", \"subgoals\"}}, found {}",
                        kind_of(v)
                    ),
                ))
            }
            None => return Err(at.field("turns", "is missing")),
        };
        let mut turns = Vec::new();
        for (i, t) in items.iter().enumerate() {
            let f = format!("turns[{i}]");
            let Some(t) = t.as_object() else {
                return Err(at.field(&f, format!("must be an object, found {}", kind_of(t))));
            };
            let say = at
                .string(t, "say")
                .map_err(|_| at.field(&format!("{f}.say"), "must be a non-empty string"))?;
            let expect_question = match t.get("expect") {
                None | Some(Value::Null) => false,
                Some(Value::String(s)) if s == "question" => true,
                Some(v) => {
                    return Err(at.field(
                        &format!("{f}.expect"),
                        format!("the only expectation is \"question\", found {v}"),
                    ))
                }
            };
            let subgoals = match t.get("subgoals") {
                Some(Value::Array(gs)) => gs
                    .iter()
                    .enumerate()
                    .map(|(j, v)| {
                        at.subgoal(v, j, &map).map_err(|e| match e {
                            SuiteError::Field { field, message, .. } => {
                                at.field(&format!("{f}.{field}"), message)
                            }
                            other => other,
                        })
                    })
                    .collect::<Result<Vec<_>, _>>()?,
                Some(v) => {
                    return Err(at.field(
                        &format!("{f}.subgoals"),
                        format!("must be a list, found {}", kind_of(v)),
                    ))
                }
                None => return Err(at.field(&format!("{f}.subgoals"), "is missing")),
            };
            if subgoals.is_empty() && !expect_question {
                return Err(at.field(
                    &format!("{f}.subgoals"),
                    "is empty: list where the turn must stop, or say \"expect\": \"question\"",
                ));
            }
            turns.push(ChatTurn {
                say,
                subgoals,
                expect_question,
            });
        }
        out.push(Dialogue {
            id,
            scene_path,
            map,
            start,
            turns,
            line,
        });
    }
    Ok(out)
}

/// Non-blank lines of a JSONL file as JSON objects with their 1-based line numbers.
fn json_lines(path: &Path) -> Result<Vec<(usize, Obj)>, SuiteError> {
    let text = std::fs::read_to_string(path).map_err(|source| SuiteError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        if raw.trim().is_empty() {
            continue;
        }
        match serde_json::from_str::<Value>(raw) {
            Ok(Value::Object(m)) => out.push((line, m)),
            Ok(other) => {
                return Err(SuiteError::Json {
                    file: path.to_path_buf(),
                    line,
                    message: format!("found {} instead of an object", kind_of(&other)),
                })
            }
            Err(e) => {
                return Err(SuiteError::Json {
                    file: path.to_path_buf(),
                    line,
                    message: format!("{e} (column {})", e.column()),
                })
            }
        }
    }
    if out.is_empty() {
        return Err(SuiteError::Empty {
            file: path.to_path_buf(),
        });
    }
    Ok(out)
}

fn kind_of(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "an object",
    }
}

/// A position in a suite file, to build errors.
struct At<'a> {
    file: &'a Path,
    line: usize,
}

type Obj = serde_json::Map<String, Value>;

impl At<'_> {
    fn field(&self, field: &str, message: impl Into<String>) -> SuiteError {
        SuiteError::Field {
            file: self.file.to_path_buf(),
            line: self.line,
            field: field.to_string(),
            message: message.into(),
        }
    }

    fn string(&self, obj: &Obj, key: &str) -> Result<String, SuiteError> {
        match obj.get(key) {
            Some(Value::String(s)) if !s.trim().is_empty() => Ok(s.clone()),
            Some(Value::String(_)) => Err(self.field(key, "is empty")),
            Some(v) => Err(self.field(key, format!("must be a string, found {}", kind_of(v)))),
            None => Err(self.field(key, "is missing")),
        }
    }

    /// The `scene` (loaded once per path into `maps`) and the `start` pose (the scene's
    /// start pose when absent).
    fn scene_and_start(
        &self,
        obj: &Obj,
        dir: &Path,
        maps: &mut HashMap<PathBuf, Arc<IvlMap>>,
    ) -> Result<(PathBuf, Arc<IvlMap>, Pose), SuiteError> {
        let scene_rel = self.string(obj, "scene")?;
        let scene_path = dir.join(&scene_rel);
        let map = match maps.get(&scene_path) {
            Some(m) => m.clone(),
            None => {
                let scene = Scene::from_path(&scene_path).map_err(|e| SuiteError::Scene {
                    file: self.file.to_path_buf(),
                    line: self.line,
                    source: Box::new(e),
                })?;
                let m = Arc::new(IvlMap::from_scene(&scene));
                maps.insert(scene_path.clone(), m.clone());
                m
            }
        };
        let start = match obj.get("start") {
            None | Some(Value::Null) => map.start_pose,
            Some(v) => {
                let a = self.numbers(v, "start", 3)?;
                Pose::new(a[0], a[1], a[2])
            }
        };
        Ok((scene_path, map, start))
    }

    fn id(&self, obj: &Obj, seen: &mut HashSet<String>) -> Result<String, SuiteError> {
        let id = match obj.get("id") {
            Some(Value::String(s)) if !s.trim().is_empty() => s.clone(),
            Some(Value::Number(n)) => n.to_string(),
            Some(v) => {
                return Err(self.field(
                    "id",
                    format!("must be a non-empty string, found {}", kind_of(v)),
                ))
            }
            None => return Err(self.field("id", "is missing")),
        };
        if !seen.insert(id.clone()) {
            return Err(self.field(
                "id",
                format!("{id:?} is used by an earlier line; ids must be unique"),
            ));
        }
        Ok(id)
    }

    fn numbers(&self, v: &Value, field: &str, n: usize) -> Result<Vec<f64>, SuiteError> {
        let items = v.as_array().filter(|a| a.len() == n).ok_or_else(|| {
            self.field(field, format!("must be a list of {n} numbers, found {v}"))
        })?;
        items
            .iter()
            .map(|x| {
                x.as_f64().filter(|f| f.is_finite()).ok_or_else(|| {
                    self.field(field, format!("must be a list of {n} numbers, found {v}"))
                })
            })
            .collect()
    }

    fn tuple(&self, v: &Value, field: &str) -> Result<Tuple, SuiteError> {
        let o = v.as_object().ok_or_else(|| {
            self.field(
                field,
                format!(
                    "must be an object {{\"object\", \"ordinal\", \"colour\"}}, found {}",
                    kind_of(v)
                ),
            )
        })?;
        let object = match o.get("object") {
            Some(Value::String(s)) if !s.trim().is_empty() => s.clone(),
            _ => return Err(self.field(&format!("{field}.object"), "must be a non-empty string")),
        };
        let ordinal = match o.get("ordinal") {
            None | Some(Value::Null) => None,
            Some(Value::Number(n)) => match n.as_i64() {
                Some(k) if k >= 1 || k == -1 => Some(k),
                _ => {
                    return Err(self.field(
                        &format!("{field}.ordinal"),
                        format!("must be k >= 1, -1 (last) or null, found {n}"),
                    ))
                }
            },
            Some(v) => {
                return Err(self.field(
                    &format!("{field}.ordinal"),
                    format!("must be an integer or null, found {}", kind_of(v)),
                ))
            }
        };
        let colour = match o.get("colour").or_else(|| o.get("color")) {
            None | Some(Value::Null) => None,
            Some(Value::String(s)) if !s.trim().is_empty() => Some(s.trim().to_lowercase()),
            Some(v) => {
                return Err(self.field(
                    &format!("{field}.colour"),
                    format!("must be a colour word or null, found {v}"),
                ))
            }
        };
        Ok(Tuple::new(&object, ordinal, colour.as_deref()))
    }

    fn subgoal(&self, v: &Value, i: usize, map: &IvlMap) -> Result<Subgoal, SuiteError> {
        let field = format!("subgoals[{i}]");
        let o = v.as_object().filter(|o| o.len() == 1).ok_or_else(|| {
            self.field(&field, format!("must be exactly one of {{\"object\": id}}, {{\"region\": name}}, {{\"point\": [x, y]}}, found {v}"))
        })?;
        if let Some(id) = o.get("object") {
            let id = id
                .as_u64()
                .and_then(|n| u32::try_from(n).ok())
                .filter(|n| *n > 0)
                .ok_or_else(|| {
                    self.field(
                        &format!("{field}.object"),
                        format!("must be a positive object id, found {id}"),
                    )
                })?;
            if map.instance_by_id(id).is_none() {
                let known: Vec<String> = map.instances.iter().map(|i| i.id.to_string()).collect();
                return Err(self.field(
                    &format!("{field}.object"),
                    format!(
                        "scene {:?} has no object with id {id} (ids: {})",
                        map.name,
                        known.join(", ")
                    ),
                ));
            }
            return Ok(Subgoal::Object(id));
        }
        if let Some(r) = o.get("region") {
            let name = r.as_str().ok_or_else(|| {
                self.field(
                    &format!("{field}.region"),
                    format!("must be a region name, found {r}"),
                )
            })?;
            if !map.regions.iter().any(|reg| reg.name == name) {
                let known: Vec<&str> = map.regions.iter().map(|r| r.name.as_str()).collect();
                return Err(self.field(
                    &format!("{field}.region"),
                    format!(
                        "scene {:?} has no region {name:?} (regions: {})",
                        map.name,
                        known.join(", ")
                    ),
                ));
            }
            return Ok(Subgoal::Region(name.to_string()));
        }
        if let Some(p) = o.get("point") {
            let a = self.numbers(p, &format!("{field}.point"), 2)?;
            return Ok(Subgoal::Point([a[0], a[1]]));
        }
        Err(self.field(&field, format!("must be one of {{\"object\": id}}, {{\"region\": name}}, {{\"point\": [x, y]}}, found {v}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        let mut f = std::fs::File::create(&p).unwrap();
        f.write_all(text.as_bytes()).unwrap();
        p
    }

    const SCENE: &str = r#"{"format": "ivlmap-scene/1", "name": "s", "bounds": [0, 0, 6, 4],
        "regions": [{"name": "kitchen", "polygon": [[0,0],[3,0],[3,4],[0,4]]}],
        "objects": [{"id": 1, "category": "table", "colour": "red", "center": [4.5, 2.0], "size": [0.8, 0.8]}],
        "robot": {"pose": [1, 1, 0], "radius": 0.2}}"#;

    #[test]
    fn kind_follows_the_name() {
        assert_eq!(
            SuiteKind::from_path(Path::new("a/x.extract.jsonl")).unwrap(),
            SuiteKind::Extract
        );
        assert_eq!(
            SuiteKind::from_path(Path::new("x.nav.jsonl")).unwrap(),
            SuiteKind::Nav
        );
        assert!(SuiteKind::from_path(Path::new("x.jsonl")).is_err());
    }

    #[test]
    fn chat_suites_read_and_errors_name_the_turn() {
        let public =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/suites/dialogues.chat.jsonl");
        let ds = load_chat_suite(&public).unwrap();
        assert!(ds.len() >= 20, "{} dialogues", ds.len());
        assert!(ds.iter().any(|d| d.turns.iter().any(|t| t.expect_question)));
        assert!(ds.iter().all(|d| d.turns.len() >= 2));

        let d = tempfile::tempdir().unwrap();
        let scene =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/scenes/flat-a.scene.json");
        let scene = scene.display().to_string();
        let ok = format!(
            r#"{{"id": "c1", "scene": "{scene}", "turns": [{{"say": "go to the fridge", "subgoals": [{{"object": 16}}]}}, {{"say": "the purple sofa", "subgoals": [], "expect": "question"}}]}}"#
        );
        let p = write(d.path(), "a.chat.jsonl", &format!("{ok}\n"));
        let ds = load_chat_suite(&p).unwrap();
        assert_eq!(ds[0].turns.len(), 2);
        assert!(ds[0].turns[1].expect_question && ds[0].turns[1].subgoals.is_empty());

        let bad = format!(
            r#"{{"id": "c1", "scene": "{scene}", "turns": [{{"say": "go", "subgoals": [{{"object": 16}}]}}, {{"say": "then there", "subgoals": [{{"object": 999}}]}}]}}"#
        );
        let p = write(d.path(), "b.chat.jsonl", &format!("{bad}\n"));
        let e = load_chat_suite(&p).unwrap_err().to_string();
        assert!(e.contains("b.chat.jsonl:1:"), "{e}");
        assert!(e.contains("turns[1].subgoals[0].object"), "{e}");
        let empty = format!(
            r#"{{"id": "c1", "scene": "{scene}", "turns": [{{"say": "go", "subgoals": []}}]}}"#
        );
        let p = write(d.path(), "c.chat.jsonl", &format!("{empty}\n"));
        let e = load_chat_suite(&p).unwrap_err().to_string();
        assert!(
            e.contains("turns[0].subgoals") && e.contains("question"),
            "{e}"
        );
    }

    #[test]
    fn extract_suite_reads_and_reports_line_and_field() {
        let d = tempfile::tempdir().unwrap();
        let p = write(
            d.path(),
            "a.extract.jsonl",
            concat!(
                r#"{"id": "p1", "instruction": "go to the third yellow table", "expected": [{"object": "table", "ordinal": 3, "colour": "yellow"}]}"#,
                "\n",
                "\n",
                r#"{"id": "p2", "instruction": "go on", "expected": []}"#,
                "\n"
            ),
        );
        let cases = load_extract_suite(&p).unwrap();
        assert_eq!(cases.len(), 2);
        assert_eq!(cases[0].expected[0].ordinal, Some(3));
        assert_eq!(cases[1].line, 3);

        let p = write(
            d.path(),
            "b.extract.jsonl",
            concat!(
                r#"{"id": "p1", "instruction": "x", "expected": []}"#,
                "\n",
                r#"{"id": "p2", "instruction": "y", "expected": [{"object": "table", "ordinal": "third"}]}"#,
                "\n"
            ),
        );
        let e = load_extract_suite(&p).unwrap_err().to_string();
        assert!(e.contains("b.extract.jsonl:2:"), "{e}");
        assert!(e.contains("expected[0].ordinal"), "{e}");

        let p = write(
            d.path(),
            "c.extract.jsonl",
            "{\"id\": \"p1\", \"instruction\": \"x\", \"expected\": []}\n{oops\n",
        );
        let e = load_extract_suite(&p).unwrap_err().to_string();
        assert!(e.contains("c.extract.jsonl:2:"), "{e}");

        let p = write(d.path(), "d.extract.jsonl", "{\"id\": \"p1\", \"instruction\": \"x\", \"expected\": []}\n{\"id\": \"p1\", \"instruction\": \"x\", \"expected\": []}\n");
        let e = load_extract_suite(&p).unwrap_err().to_string();
        assert!(e.contains(":2: field `id`"), "{e}");
    }

    #[test]
    fn nav_suite_checks_subgoals_against_the_scene() {
        let d = tempfile::tempdir().unwrap();
        write(d.path(), "s.scene.json", SCENE);
        let p = write(
            d.path(),
            "a.nav.jsonl",
            concat!(
                r#"{"id": "t1", "scene": "s.scene.json", "start": [1, 1, 0], "instruction": "x", "subgoals": [{"object": 1}, {"region": "kitchen"}, {"point": [2, 2]}], "reference": "move_to_object(\"table\");"}"#,
                "\n"
            ),
        );
        let t = load_nav_suite(&p).unwrap();
        assert_eq!(
            t[0].subgoals,
            vec![
                Subgoal::Object(1),
                Subgoal::Region("kitchen".into()),
                Subgoal::Point([2.0, 2.0])
            ]
        );
        assert!(t[0].reference.is_some());

        let p = write(
            d.path(),
            "b.nav.jsonl",
            r#"{"id": "t1", "scene": "s.scene.json", "instruction": "x", "subgoals": [{"object": 1}, {"object": 9}]}"#,
        );
        let e = load_nav_suite(&p).unwrap_err().to_string();
        assert!(
            e.contains("b.nav.jsonl:1: field `subgoals[1].object`"),
            "{e}"
        );
        assert!(e.contains("no object with id 9"), "{e}");

        let p = write(
            d.path(),
            "c.nav.jsonl",
            r#"{"id": "t1", "scene": "s.scene.json", "instruction": "x", "subgoals": [{"region": "attic"}]}"#,
        );
        let e = load_nav_suite(&p).unwrap_err().to_string();
        assert!(
            e.contains("subgoals[0].region") && e.contains("kitchen"),
            "{e}"
        );

        let p = write(
            d.path(),
            "d.nav.jsonl",
            r#"{"id": "t1", "scene": "missing.scene.json", "instruction": "x", "subgoals": [{"region": "attic"}]}"#,
        );
        let e = load_nav_suite(&p).unwrap_err().to_string();
        assert!(
            e.contains("d.nav.jsonl:1: field `scene`") && e.contains("missing.scene.json"),
            "{e}"
        );

        let p = write(
            d.path(),
            "e.nav.jsonl",
            r#"{"id": "t1", "scene": "s.scene.json", "start": [1, 1], "instruction": "x", "subgoals": [{"object": 1}]}"#,
        );
        let e = load_nav_suite(&p).unwrap_err().to_string();
        assert!(e.contains("field `start`"), "{e}");
    }
}
