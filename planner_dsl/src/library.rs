//! The robot function library, host side: checks each call's arguments against the
//! registry, answers queries from the map and drives the robot.

use crate::error::{RuntimeError, RuntimeErrorKind, Span};
use crate::limits::Limits;
use crate::registry::{FunctionSpec, ParamType};
use crate::trace::TraceEntry;
use crate::value::{point_to_dynamic, to_json, type_word, ObjectRecord};
use map_core::goals::{
    approach_point, between_point, face_heading, heading_with_object_on, lateral_point,
    region_point, side_point, Side,
};
use map_core::select::Selection;
use map_core::{
    Instance, IvlMap, ObjectOrder, Point, QueryError, Region, Robot, RobotError, StopTarget,
};
use rhai::Dynamic;
use std::time::Instant;

/// Largest |ordinal| accepted (more is certainly a mistake).
const MAX_ORDINAL: i64 = 10_000;
/// Largest |angle| in degrees accepted.
const MAX_ANGLE_DEG: f64 = 36_000.0;
/// Positions farther than this outside the map's bounds are rejected as absurd.
const MAX_OUTSIDE_M: f64 = 1_000.0;
/// Longest name, colour or order string accepted.
const MAX_NAME_LEN: usize = 200;
/// Longest `say` text kept.
const MAX_SAY_LEN: usize = 2_000;

/// A number for messages: plain when moderate, scientific when huge.
fn num(x: f64) -> String {
    if x.is_finite() && x.abs() >= 1e6 {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// Why a library call failed.
#[derive(Debug)]
struct CallError {
    kind: RuntimeErrorKind,
    message: String,
}

fn arg_err(spec: &FunctionSpec, idx: usize, what: impl std::fmt::Display) -> CallError {
    let name = spec.params.get(idx).map(|p| p.name).unwrap_or("?");
    CallError {
        kind: RuntimeErrorKind::Argument,
        message: format!("argument `{name}` {what}"),
    }
}

fn map_err(e: impl std::fmt::Display) -> CallError {
    CallError {
        kind: RuntimeErrorKind::Map,
        message: e.to_string(),
    }
}

fn robot_err(e: RobotError) -> CallError {
    let kind = match e {
        RobotError::NotFinite { .. } | RobotError::OutOfRange { .. } => RuntimeErrorKind::Argument,
        _ => RuntimeErrorKind::Map,
    };
    CallError {
        kind,
        message: e.to_string(),
    }
}

/// What an object argument resolved to.
enum Target<'m> {
    Instance(&'m Instance),
    Region(&'m Region),
}

impl Target<'_> {
    fn point(&self) -> Point {
        match self {
            Target::Instance(i) => i.center(),
            Target::Region(r) => region_point(r),
        }
    }
}

/// A successful call: the value returned to the script and an optional warning.
struct Done {
    value: Dynamic,
    warning: Option<String>,
}

impl Done {
    fn unit() -> Self {
        Done {
            value: Dynamic::UNIT,
            warning: None,
        }
    }
}

/// The host side of a run: owns access to the map and robot, records the trace.
pub(crate) struct Host<'a> {
    map: &'a IvlMap,
    robot: &'a mut dyn Robot,
    max_calls: usize,
    /// Where the robot was when the plan began (`move_to_start`).
    start: Point,
    pub(crate) trace: Vec<TraceEntry>,
    pub(crate) said: Vec<String>,
    pub(crate) failure: Option<RuntimeError>,
}

pub(crate) fn record(inst: &Instance) -> ObjectRecord {
    let c = inst.center();
    ObjectRecord {
        id: inst.id,
        name: inst.label.clone(),
        label_id: inst.label_id,
        colour: inst.colour.clone(),
        position: [c.x, c.y],
        count: inst.num_of_same_class,
    }
}

impl<'a> Host<'a> {
    pub(crate) fn new(map: &'a IvlMap, robot: &'a mut dyn Robot, limits: &Limits) -> Self {
        Host {
            map,
            start: robot.pose().position,
            robot,
            max_calls: limits.max_library_calls,
            trace: Vec::new(),
            said: Vec::new(),
            failure: None,
        }
    }

    pub(crate) fn robot(&mut self) -> &mut dyn Robot {
        self.robot
    }

    /// The objects visited so far, oldest first, a repeat visit listed again: the
    /// robot's stops at objects in its trajectory (in a conversation, every turn's, as
    /// the session runs each plan on the same robot), which the selection keys
    /// `visited` and `not_visited` count over.
    fn visits(&self) -> Vec<u32> {
        self.robot
            .trajectory()
            .stops
            .iter()
            .filter_map(|s| match s.target {
                StopTarget::Instance(id) => Some(id),
                _ => None,
            })
            .collect()
    }

    /// Handles one call; `Err(())` means the plan must stop (the error is in
    /// `self.failure`).
    pub(crate) fn handle(
        &mut self,
        spec: &'static FunctionSpec,
        args: &[Dynamic],
        span: Span,
    ) -> Result<Dynamic, ()> {
        if self.failure.is_some() {
            return Err(());
        }
        if self.trace.len() >= self.max_calls {
            self.failure = Some(RuntimeError {
                span,
                function: Some(spec.name.to_string()),
                kind: RuntimeErrorKind::TooManyCalls,
                message: format!(
                    "the plan made more than {} robot function calls",
                    self.max_calls
                ),
            });
            return Err(());
        }
        let start = Instant::now();
        let result = self.exec(spec, args);
        let duration_us = u64::try_from(start.elapsed().as_micros()).unwrap_or(u64::MAX);
        let mut entry = TraceEntry {
            function: spec.name.to_string(),
            args: args.iter().map(to_json).collect(),
            result: serde_json::Value::Null,
            pose_after: self.robot.pose().to_array(),
            duration_us,
            span,
            warning: None,
            error: None,
        };
        match result {
            Ok(done) => {
                entry.result = to_json(&done.value);
                entry.warning = done.warning;
                self.trace.push(entry);
                Ok(done.value)
            }
            Err(e) => {
                entry.error = Some(e.message.clone());
                self.trace.push(entry);
                self.failure = Some(RuntimeError {
                    span,
                    function: Some(spec.name.to_string()),
                    kind: e.kind,
                    message: e.message,
                });
                Err(())
            }
        }
    }

    fn exec(&mut self, spec: &'static FunctionSpec, args: &[Dynamic]) -> Result<Done, CallError> {
        if !spec.accepts_arity(args.len()) {
            return Err(CallError {
                kind: RuntimeErrorKind::Argument,
                message: format!(
                    "takes {}, got {}: {}",
                    spec.arity_text(),
                    args.len(),
                    spec.signature()
                ),
            });
        }
        let name = spec.name;
        let pose = self.robot.pose();
        let value = |v: Dynamic| {
            Ok(Done {
                value: v,
                warning: None,
            })
        };
        match name {
            "get_nearest_obj_pos" | "get_specifed_obj_pos" | "get_specified_obj_pos" => {
                let p = self.target(spec, 0, &args[0])?.point();
                value(point_to_dynamic([p.x, p.y]))
            }
            "get_nearest_obj_contour" | "get_obj_contour" => {
                let poly = match self.target(spec, 0, &args[0])? {
                    Target::Instance(i) => &i.contour,
                    Target::Region(r) => &r.polygon,
                };
                let pts = poly
                    .vertices()
                    .iter()
                    .map(|p| point_to_dynamic([p.x, p.y]))
                    .collect::<Vec<_>>();
                value(Dynamic::from_array(pts))
            }
            "get_obj_attributes" => {
                let obj_name = self.name_arg(spec, 0, &args[0])?;
                let (k, colour, order) = self.pick_args(spec, args, 1)?;
                let inst = self
                    .map
                    .get_obj_attributes(&obj_name, k, colour.as_deref(), order, pose)
                    .map_err(map_err)?;
                value(Dynamic::from(record(inst)))
            }
            "get_obj_in_region" => {
                let obj_name = self.name_arg(spec, 0, &args[0])?;
                let region = self.name_arg(spec, 1, &args[1])?;
                let (k, colour, order) = self.pick_args(spec, args, 2)?;
                let inst = self
                    .map
                    .get_obj_in_region(&obj_name, &region, k, colour.as_deref(), order, pose)
                    .map_err(map_err)?;
                value(Dynamic::from(record(inst)))
            }
            "get_instance" => {
                let k = self.ordinal_arg(spec, 0, &args[0])?;
                let inst = u32::try_from(k)
                    .ok()
                    .and_then(|id| self.map.instance_by_id(id))
                    .ok_or_else(|| {
                        arg_err(spec, 0, format!("{k}: no object on this map has that id"))
                    })?;
                value(Dynamic::from(record(inst)))
            }
            "get_obj" => {
                let sel = self.selection_args(spec, args)?;
                let inst = self
                    .map
                    .select_visited(&sel, pose, &self.visits())
                    .map_err(map_err)?;
                value(Dynamic::from(record(inst)))
            }
            "move_to" => {
                let goal = self.position_arg(spec, 0, &args[0])?;
                let rep = self
                    .robot
                    .move_to(goal, name, StopTarget::Point([goal.x, goal.y]))
                    .map_err(robot_err)?;
                Ok(Done {
                    value: Dynamic::UNIT,
                    warning: rep.warning,
                })
            }
            "move_to_left" | "move_to_right" => {
                let inst = self.instance(spec, 0, &args[0])?;
                let goal = lateral_point(pose, inst, name == "move_to_left");
                self.go(goal, name, StopTarget::Instance(inst.id))
            }
            "move_north" | "move_south" | "move_east" | "move_west" => {
                let side = match name {
                    "move_north" => Side::North,
                    "move_south" => Side::South,
                    "move_east" => Side::East,
                    _ => Side::West,
                };
                let inst = self.instance(spec, 0, &args[0])?;
                self.go(side_point(inst, side), name, StopTarget::Instance(inst.id))
            }
            "move_in_between" => {
                let a = self.instance(spec, 0, &args[0])?;
                let b = self.instance(spec, 1, &args[1])?;
                if a.id == b.id {
                    // Said to whoever wrote the script (a model, a mission's author): the
                    // usual cause is "between the two X" written as two equal picks.
                    let colour = a
                        .colour
                        .as_deref()
                        .map(|c| format!(", #{{colour: \"{c}\"}}"))
                        .unwrap_or_default();
                    return Err(arg_err(
                        spec,
                        1,
                        format!(
                            "is the same object as `object_a` ({}); to stop between the two {}s that match, use move_between_the_two(\"{}\"{colour})",
                            record(a),
                            a.label,
                            a.label
                        ),
                    ));
                }
                self.go(between_point(a, b), name, StopTarget::Between([a.id, b.id]))
            }
            "move_between_the_two" => {
                let sel = self.selection_args(spec, args)?;
                let [a, b] = self
                    .map
                    .select_pair_visited(&sel, pose, &self.visits())
                    .map_err(map_err)?;
                self.go(between_point(a, b), name, StopTarget::Between([a.id, b.id]))
            }
            "move_to_start" => {
                let p = self.start;
                self.go(p, name, StopTarget::Point([p.x, p.y]))
            }
            "move_to_object" => match self.target(spec, 0, &args[0])? {
                Target::Instance(inst) => self.go(
                    approach_point(pose, inst),
                    name,
                    StopTarget::Instance(inst.id),
                ),
                Target::Region(r) => {
                    self.go(region_point(r), name, StopTarget::Region(r.name.clone()))
                }
            },
            "face" => {
                let heading = match self.target(spec, 0, &args[0])? {
                    Target::Instance(inst) => face_heading(pose, inst),
                    Target::Region(r) => pose.position.heading_to(region_point(r)),
                };
                self.robot.turn_absolute(heading).map_err(robot_err)?;
                Ok(Done::unit())
            }
            "with_object_on_left" | "with_object_on_right" => {
                let inst = self.instance(spec, 0, &args[0])?;
                let heading = heading_with_object_on(pose, inst, name == "with_object_on_left");
                self.robot.turn_absolute(heading).map_err(robot_err)?;
                Ok(Done::unit())
            }
            "turn" | "turn_absolute" => {
                let a = self.number_arg(spec, 0, &args[0])?;
                if a.abs() > MAX_ANGLE_DEG {
                    return Err(arg_err(
                        spec,
                        0,
                        format!("of {} degrees is absurd (limit ±{MAX_ANGLE_DEG})", num(a)),
                    ));
                }
                if name == "turn" {
                    self.robot.turn(a)
                } else {
                    self.robot.turn_absolute(a)
                }
                .map_err(robot_err)?;
                Ok(Done::unit())
            }
            "move_forward" => {
                let d = self.number_arg(spec, 0, &args[0])?;
                if d.abs() > map_core::robot::MAX_FORWARD_M {
                    return Err(arg_err(
                        spec,
                        0,
                        format!(
                            "of {} m is absurd (limit ±{} m)",
                            num(d),
                            map_core::robot::MAX_FORWARD_M
                        ),
                    ));
                }
                let rep = self.robot.move_forward(d).map_err(robot_err)?;
                Ok(Done {
                    value: Dynamic::UNIT,
                    warning: rep.warning,
                })
            }
            "say" => {
                let a = &args[0];
                let mut text = if a.is_string() {
                    a.to_string()
                } else {
                    match a.read_lock::<ObjectRecord>() {
                        Some(o) => o.to_string(),
                        None => a.to_string(),
                    }
                };
                if text.len() > MAX_SAY_LEN {
                    let mut cut = MAX_SAY_LEN;
                    while !text.is_char_boundary(cut) {
                        cut -= 1;
                    }
                    text.truncate(cut);
                    text.push('…');
                }
                self.said.push(text);
                Ok(Done::unit())
            }
            other => Err(CallError {
                kind: RuntimeErrorKind::Internal,
                message: format!("`{other}` is in the registry but has no implementation"),
            }),
        }
    }

    fn go(&mut self, goal: Point, call: &str, target: StopTarget) -> Result<Done, CallError> {
        let rep = self.robot.move_to(goal, call, target).map_err(robot_err)?;
        Ok(Done {
            value: Dynamic::UNIT,
            warning: rep.warning,
        })
    }

    fn target(
        &self,
        spec: &FunctionSpec,
        idx: usize,
        a: &Dynamic,
    ) -> Result<Target<'a>, CallError> {
        if let Some(rec) = a.read_lock::<ObjectRecord>() {
            return self
                .map
                .instance_by_id(rec.id)
                .map(Target::Instance)
                .ok_or_else(|| map_err(QueryError::UnknownInstance { id: rec.id }));
        }
        if a.is_string() {
            let name = self.name_arg(spec, idx, a)?;
            let pose = self.robot.pose();
            return match self
                .map
                .get_obj_attributes(&name, 0, None, ObjectOrder::NearToFar, pose)
            {
                Ok(inst) => Ok(Target::Instance(inst)),
                Err(e @ QueryError::UnknownObject { .. }) => match self.map.find_region(&name) {
                    Ok(r) => Ok(Target::Region(r)),
                    Err(_) => Err(map_err(e)),
                },
                Err(e) => Err(map_err(e)),
            };
        }
        Err(arg_err(
            spec,
            idx,
            format!(
                "must be an object record (from get_obj_attributes) or a name such as \"sofa\", got {}",
                type_word(a)
            ),
        ))
    }

    fn instance(
        &self,
        spec: &FunctionSpec,
        idx: usize,
        a: &Dynamic,
    ) -> Result<&'a Instance, CallError> {
        match self.target(spec, idx, a)? {
            Target::Instance(i) => Ok(i),
            Target::Region(r) => Err(arg_err(
                spec,
                idx,
                format!(
                    "names the region {:?}, not an object; use move_to_object({:?}) to go there",
                    r.name, r.name
                ),
            )),
        }
    }

    fn name_arg(&self, spec: &FunctionSpec, idx: usize, a: &Dynamic) -> Result<String, CallError> {
        if !a.is_string() {
            return Err(arg_err(
                spec,
                idx,
                format!("must be a name such as \"table\", got {}", type_word(a)),
            ));
        }
        let s = a.to_string();
        if s.trim().is_empty() {
            return Err(arg_err(spec, idx, "must not be empty"));
        }
        if s.len() > MAX_NAME_LEN {
            return Err(arg_err(
                spec,
                idx,
                format!("is {} bytes long; names are short words", s.len()),
            ));
        }
        Ok(s)
    }

    fn number_arg(&self, spec: &FunctionSpec, idx: usize, a: &Dynamic) -> Result<f64, CallError> {
        let x = if let Ok(i) = a.as_int() {
            i as f64
        } else if let Ok(f) = a.as_float() {
            f
        } else {
            let unit = match spec.params.get(idx).map(|p| p.ty) {
                Some(ParamType::Angle) => "degrees",
                _ => "metres",
            };
            return Err(arg_err(
                spec,
                idx,
                format!("must be a number ({unit}), got {}", type_word(a)),
            ));
        };
        if !x.is_finite() {
            return Err(arg_err(
                spec,
                idx,
                format!("must be a finite number, got {x}"),
            ));
        }
        Ok(x)
    }

    /// `(object_name, [select])`: the name and the optional selection map.
    fn selection_args(
        &self,
        spec: &FunctionSpec,
        args: &[Dynamic],
    ) -> Result<Selection, CallError> {
        let name = self.name_arg(spec, 0, &args[0])?;
        match args.get(1) {
            Some(a) => self.selection_arg(spec, 1, a, name),
            None => Ok(Selection::new(name)),
        }
    }

    /// A selection map: `#{ordinal, colour, not_colour, order, region, near, other_than,
    /// visited, not_visited}`
    /// ([`crate::registry::SELECTION_KEYS`]).
    fn selection_arg(
        &self,
        spec: &FunctionSpec,
        idx: usize,
        a: &Dynamic,
        name: String,
    ) -> Result<Selection, CallError> {
        let mut sel = Selection::new(name);
        if a.is_unit() {
            return Ok(sel);
        }
        let Some(m) = a.read_lock::<rhai::Map>() else {
            return Err(arg_err(
                spec,
                idx,
                format!(
                    "must be a map such as #{{ordinal: 2, colour: \"red\"}}, got {}",
                    type_word(a)
                ),
            ));
        };
        for (key, v) in m.iter() {
            match key.as_str() {
                "ordinal" => sel.ordinal = self.ordinal_arg(spec, idx, v)?,
                "colour" | "color" => sel.colour = self.colour_arg(spec, idx, v)?,
                "not_colour" | "not_color" => sel.not_colour = self.colour_arg(spec, idx, v)?,
                "order" => sel.order = self.order_arg(spec, idx, v)?,
                "region" => sel.region = Some(self.name_arg(spec, idx, v)?),
                "near" => sel.near = Some(self.object_key(spec, idx, v, "near")?),
                "other_than" => {
                    sel.other_than = Some(self.object_key(spec, idx, v, "other_than")?)
                }
                "visited" => sel.visited = self.ordinal_arg(spec, idx, v)?,
                "not_visited" => {
                    sel.not_visited = v.as_bool().map_err(|_| {
                        arg_err(
                            spec,
                            idx,
                            format!(
                                "key `not_visited` must be true or false, got {}",
                                type_word(v)
                            ),
                        )
                    })?;
                }
                other => {
                    return Err(arg_err(
                        spec,
                        idx,
                        format!(
                            "has an unknown key `{other}`; the keys are {}",
                            crate::registry::SELECTION_KEYS.join(", ")
                        ),
                    ))
                }
            }
        }
        Ok(sel)
    }

    /// The instance id of an object-valued selection key (`near`, `other_than`); a
    /// region there is an argument error naming the key.
    fn object_key(
        &self,
        spec: &FunctionSpec,
        idx: usize,
        a: &Dynamic,
        key: &str,
    ) -> Result<u32, CallError> {
        match self.target(spec, idx, a)? {
            Target::Instance(i) => Ok(i.id),
            Target::Region(r) => {
                let hint = if key == "near" { " (use `region`)" } else { "" };
                Err(arg_err(
                    spec,
                    idx,
                    format!(
                        "key `{key}` must be an object, got the region {:?}{hint}",
                        r.name
                    ),
                ))
            }
        }
    }

    fn ordinal_arg(&self, spec: &FunctionSpec, idx: usize, a: &Dynamic) -> Result<i64, CallError> {
        if a.is_unit() {
            return Ok(0);
        }
        let k = if let Ok(i) = a.as_int() {
            i
        } else if let Ok(f) = a.as_float() {
            if !f.is_finite() || f.fract() != 0.0 || f.abs() > MAX_ORDINAL as f64 {
                return Err(arg_err(
                    spec,
                    idx,
                    format!("must be a whole number such as 3, got {f}"),
                ));
            }
            f as i64
        } else {
            return Err(arg_err(
                spec,
                idx,
                format!(
                    "must be an integer (3 for the third, -1 for the last, 0 for the nearest), got {}",
                    type_word(a)
                ),
            ));
        };
        if !(-MAX_ORDINAL..=MAX_ORDINAL).contains(&k) {
            return Err(arg_err(
                spec,
                idx,
                format!("of {} is out of range: use k >= 1 for the k-th, -1 for the last, -2 for the second to last, 0 for the nearest", num(k as f64)),
            ));
        }
        Ok(k)
    }

    /// The optional (ordinal, colour, order) arguments of a pick, starting at `from`.
    fn pick_args(
        &self,
        spec: &FunctionSpec,
        args: &[Dynamic],
        from: usize,
    ) -> Result<(i64, Option<String>, ObjectOrder), CallError> {
        let k = match args.get(from) {
            Some(a) => self.ordinal_arg(spec, from, a)?,
            None => 0,
        };
        let colour = match args.get(from + 1) {
            Some(a) => self.colour_arg(spec, from + 1, a)?,
            None => None,
        };
        let order = match args.get(from + 2) {
            Some(a) => self.order_arg(spec, from + 2, a)?,
            None => ObjectOrder::NearToFar,
        };
        Ok((k, colour, order))
    }

    fn colour_arg(
        &self,
        spec: &FunctionSpec,
        idx: usize,
        a: &Dynamic,
    ) -> Result<Option<String>, CallError> {
        if a.is_unit() {
            return Ok(None);
        }
        if !a.is_string() {
            return Err(arg_err(
                spec,
                idx,
                format!(
                    "must be a colour word such as \"red\" or \"\" for any, got {}",
                    type_word(a)
                ),
            ));
        }
        let s = a.to_string();
        if s.len() > MAX_NAME_LEN {
            return Err(arg_err(spec, idx, "is too long for a colour word"));
        }
        Ok(Some(s).filter(|s| !s.trim().is_empty()))
    }

    fn order_arg(
        &self,
        spec: &FunctionSpec,
        idx: usize,
        a: &Dynamic,
    ) -> Result<ObjectOrder, CallError> {
        if a.is_unit() {
            return Ok(ObjectOrder::NearToFar);
        }
        if !a.is_string() {
            return Err(arg_err(
                spec,
                idx,
                format!(
                    "must be an order name such as \"left_to_right\", got {}",
                    type_word(a)
                ),
            ));
        }
        ObjectOrder::parse(&a.to_string()).map_err(|e| arg_err(spec, idx, e))
    }

    fn position_arg(
        &self,
        spec: &FunctionSpec,
        idx: usize,
        a: &Dynamic,
    ) -> Result<Point, CallError> {
        if let Some(rec) = a.read_lock::<ObjectRecord>() {
            return Ok(Point::new(rec.position[0], rec.position[1]));
        }
        let Some(arr) = a.read_lock::<rhai::Array>() else {
            let hint = if a.is_string() {
                "; to go to a named object use move_to_object(name)"
            } else {
                ""
            };
            return Err(arg_err(
                spec,
                idx,
                format!(
                    "must be a position [x, y] in metres, got {}{hint}",
                    type_word(a)
                ),
            ));
        };
        if arr.len() != 2 {
            return Err(arg_err(
                spec,
                idx,
                format!("must be [x, y] (2 numbers), got an array of {}", arr.len()),
            ));
        }
        let mut xy = [0.0; 2];
        for (i, v) in arr.iter().enumerate() {
            xy[i] = if let Ok(n) = v.as_int() {
                n as f64
            } else if let Ok(f) = v.as_float() {
                f
            } else {
                return Err(arg_err(
                    spec,
                    idx,
                    format!(
                        "must be [x, y] of numbers, got {} at index {i}",
                        type_word(v)
                    ),
                ));
            };
            if !xy[i].is_finite() {
                return Err(arg_err(
                    spec,
                    idx,
                    format!("must hold finite numbers, got {} at index {i}", xy[i]),
                ));
            }
        }
        let b = self.map.frame.bounds();
        let outside = (b[0] - xy[0])
            .max(xy[0] - b[2])
            .max(b[1] - xy[1])
            .max(xy[1] - b[3]);
        if outside > MAX_OUTSIDE_M {
            return Err(arg_err(
                spec,
                idx,
                format!(
                    "[{}, {}] is absurd: the map spans x {}..{}, y {}..{} m",
                    num(xy[0]),
                    num(xy[1]),
                    b[0],
                    b[2],
                    b[1],
                    b[3]
                ),
            ));
        }
        Ok(Point::new(xy[0], xy[1]))
    }
}
