//! The typed plan: the straight-line part of a script as typed steps and targets, so
//! that checks, dry runs and repair prompts work on values instead of on text.
//!
//! [`TypedPlan::parse`] reads a script made of `let x = <pick>;` bindings and library
//! calls (as `f(..)` or `agent.f(..)`) with literal or variable arguments;
//! [`TypedPlan::to_rhai`] prints it back as ordinary Rhai that [`crate::Plan`] runs.
//! Printing then parsing gives the same plan (tested on every reference plan of the
//! example suites). Anything else (loops, conditions, functions, computed arguments)
//! is an error naming the line and column: such scripts stay ordinary validated Rhai.
//!
//! ```
//! use planner_dsl::typed::{Object, Step, TypedPlan};
//! let p = TypedPlan::parse(
//!     "let t = agent.get_obj_attributes(\"table\", 2, \"yellow\", \"west_to_east\");\nagent.move_to_object(t);",
//! )
//! .unwrap();
//! assert_eq!(p.steps.len(), 2);
//! assert_eq!(p.steps[1], Step::GoTo(Object::Var("t".into())));
//! assert_eq!(TypedPlan::parse(&p.to_rhai()).unwrap(), p);
//! ```

use std::fmt::Write as _;

use rhai::{Expr, FnCallExpr, Stmt};
use serde::{Deserialize, Serialize};

use map_core::select::Selection;
use map_core::ObjectOrder;

use crate::error::Span;

/// Which object a noun phrase means: design.md's selection, its "next to" anchor held
/// as the object expression the script wrote (resolved to an instance id at run time).
pub type Target = Selection<Box<Object>>;

/// An object argument.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Object {
    /// A selection made where it is used.
    Pick(Target),
    /// A bare name: the nearest object of that name, or a region.
    Name(String),
    /// A variable bound by an earlier [`Step::Let`].
    Var(String),
    /// `get_instance(id)`: an object by its id (one the conversation visited).
    Instance(u32),
}

/// The side functions: a move to one side of an object, or a turn putting it on one side.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// `move_to_left`.
    Left,
    /// `move_to_right`.
    Right,
    /// `move_north`.
    North,
    /// `move_south`.
    South,
    /// `move_east`.
    East,
    /// `move_west`.
    West,
    /// `with_object_on_left` (a turn).
    OnLeft,
    /// `with_object_on_right` (a turn).
    OnRight,
}

impl Side {
    const ALL: [(Side, &'static str); 8] = [
        (Side::Left, "move_to_left"),
        (Side::Right, "move_to_right"),
        (Side::North, "move_north"),
        (Side::South, "move_south"),
        (Side::East, "move_east"),
        (Side::West, "move_west"),
        (Side::OnLeft, "with_object_on_left"),
        (Side::OnRight, "with_object_on_right"),
    ];

    /// The library function.
    #[must_use]
    pub fn function(self) -> &'static str {
        Side::ALL
            .iter()
            .find(|(s, _)| *s == self)
            .map_or("move_to_left", |(_, f)| f)
    }

    /// The side a library function names (`"move_north"` is [`Side::North`]); `None`
    /// for any other function.
    #[must_use]
    pub fn from_function(f: &str) -> Option<Side> {
        Side::ALL.iter().find(|(_, n)| *n == f).map(|(s, _)| *s)
    }

    /// The move to the side a word names, read off the function's name: "left" is
    /// `move_to_left`, "north" is `move_north`; `None` for a word that names no side a
    /// move goes to (the turns `with_object_on_left/right` are not moves).
    #[must_use]
    pub fn toward(word: &str) -> Option<Side> {
        Side::ALL
            .iter()
            .filter(|(s, _)| s.is_move())
            .find(|(_, f)| f.rsplit('_').next() == Some(word))
            .map(|(s, _)| *s)
    }

    /// Whether the function moves the robot to that side (not a turn in place).
    #[must_use]
    pub fn is_move(self) -> bool {
        !matches!(self, Side::OnLeft | Side::OnRight)
    }
}

/// One step of a straight-line plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Step {
    /// `let var = <pick>;`: the object is chosen here (where the robot is now).
    Let {
        /// The variable.
        var: String,
        /// What it names.
        target: Target,
    },
    /// `move_to_object`.
    GoTo(Object),
    /// A side of an object (see [`Side`]).
    Side {
        /// Which side function.
        side: Side,
        /// Of what.
        object: Object,
    },
    /// `move_in_between(a, b)`.
    Between(Object, Object),
    /// `move_between_the_two(...)`: exactly two objects match.
    BetweenTwo(Target),
    /// `face`.
    Face(Object),
    /// `turn(angle)`, degrees clockwise.
    Turn(f64),
    /// `turn_absolute(heading)`, compass degrees.
    TurnAbsolute(f64),
    /// `move_forward(metres)`.
    Forward(f64),
    /// `move_to([x, y])`.
    MoveTo([f64; 2]),
    /// `move_to_start()`: back to where the plan began.
    ToStart,
    /// `say(text)`.
    Say(String),
}

/// The library functions a typed step calls (the grammar of the one-call answer offers
/// exactly these, with their registry signatures), and the pick function whose
/// canonical form every target prints as.
pub const STEP_FUNCTIONS: &[&str] = &[
    "move_to_object",
    "move_to_left",
    "move_to_right",
    "move_north",
    "move_south",
    "move_east",
    "move_west",
    "with_object_on_left",
    "with_object_on_right",
    "move_in_between",
    "move_between_the_two",
    "face",
    "turn",
    "turn_absolute",
    "move_forward",
    "move_to",
    "move_to_start",
    "say",
];

/// The pick function of [`Object::Pick`]'s canonical form.
pub const PICK_FUNCTION: &str = "get_obj";

/// A straight-line plan.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TypedPlan {
    /// The steps in order.
    pub steps: Vec<Step>,
}

/// Why a script is not a straight-line plan of library calls.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TypedError {
    /// Not valid Rhai.
    #[error("{span}: {message}")]
    Parse {
        /// Where.
        span: Span,
        /// The parser's message.
        message: String,
    },
    /// A statement or argument the typed plan does not hold (a loop, a condition, a
    /// computed argument, a function that is not a step or a pick).
    #[error("{span}: {what} is not part of a straight-line plan")]
    NotStraightLine {
        /// Where.
        span: Span,
        /// What was found.
        what: String,
    },
    /// A variable used before any `let` bound it.
    #[error("{span}: variable `{name}` is not bound by an earlier `let`")]
    UnknownVariable {
        /// Where.
        span: Span,
        /// The variable.
        name: String,
    },
    /// A call with the wrong number or kind of arguments.
    #[error("{span}: {function}: {message}")]
    Argument {
        /// Where.
        span: Span,
        /// The function.
        function: String,
        /// What is wrong.
        message: String,
    },
}

fn not_straight(pos: rhai::Position, what: impl Into<String>) -> TypedError {
    TypedError::NotStraightLine {
        span: Span::from_position(pos),
        what: what.into(),
    }
}

/// A library call: `f(..)` or `agent.f(..)`.
fn call_of(e: &Expr) -> Option<(&FnCallExpr, rhai::Position)> {
    match e {
        Expr::FnCall(x, p) => Some((x, *p)),
        Expr::Dot(b, _, _) => match (&b.lhs, &b.rhs) {
            (Expr::Variable(v, ..), Expr::MethodCall(x, p)) if v.1.as_str() == "agent" => {
                Some((x, *p))
            }
            _ => None,
        },
        _ => None,
    }
}

struct Reader {
    vars: Vec<String>,
}

impl Reader {
    fn arg_err(&self, pos: rhai::Position, f: &str, message: impl Into<String>) -> TypedError {
        TypedError::Argument {
            span: Span::from_position(pos),
            function: f.to_string(),
            message: message.into(),
        }
    }

    fn string(&self, e: &Expr, f: &str) -> Result<String, TypedError> {
        match e {
            Expr::StringConstant(s, _) => Ok(s.to_string()),
            other => Err(self.arg_err(other.position(), f, "expected a string literal")),
        }
    }

    fn opt_string(&self, e: Option<&Expr>, f: &str) -> Result<Option<String>, TypedError> {
        match e {
            None | Some(Expr::Unit(_)) => Ok(None),
            Some(e) => Ok(Some(self.string(e, f)?).filter(|s| !s.trim().is_empty())),
        }
    }

    fn order(&self, e: Option<&Expr>, f: &str) -> Result<ObjectOrder, TypedError> {
        match self.opt_string(e, f)? {
            None => Ok(ObjectOrder::default()),
            Some(o) => ObjectOrder::parse(&o).map_err(|err| {
                self.arg_err(
                    e.map_or(rhai::Position::NONE, Expr::position),
                    f,
                    err.to_string(),
                )
            }),
        }
    }

    fn number(&self, e: &Expr, f: &str) -> Result<f64, TypedError> {
        let x = self.literal_number(e, f)?;
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.arg_err(e.position(), f, "expected a finite number"))
        }
    }

    fn literal_number(&self, e: &Expr, f: &str) -> Result<f64, TypedError> {
        match e {
            Expr::IntegerConstant(i, _) => Ok(*i as f64),
            Expr::FloatConstant(x, _) => Ok(**x),
            Expr::FnCall(x, _) if x.name.as_str() == "-" && x.args.len() == 1 => {
                Ok(-self.literal_number(&x.args[0], f)?)
            }
            other => Err(self.arg_err(other.position(), f, "expected a number literal")),
        }
    }

    fn int(&self, e: Option<&Expr>, f: &str) -> Result<i64, TypedError> {
        match e {
            None | Some(Expr::Unit(_)) => Ok(0),
            Some(Expr::IntegerConstant(i, _)) => Ok(*i),
            Some(Expr::FnCall(x, _)) if x.name.as_str() == "-" && x.args.len() == 1 => {
                Ok(-self.int(x.args.first(), f)?)
            }
            Some(other) => Err(self.arg_err(other.position(), f, "expected an integer literal")),
        }
    }

    fn boolean(&self, e: &Expr, f: &str) -> Result<bool, TypedError> {
        match e {
            Expr::BoolConstant(b, _) => Ok(*b),
            other => Err(self.arg_err(other.position(), f, "expected true or false")),
        }
    }

    fn object(&self, e: &Expr, f: &str) -> Result<Object, TypedError> {
        match e {
            Expr::StringConstant(s, _) => Ok(Object::Name(s.to_string())),
            Expr::Variable(v, _, p) => {
                let name = v.1.to_string();
                if self.vars.contains(&name) {
                    Ok(Object::Var(name))
                } else {
                    Err(TypedError::UnknownVariable {
                        span: Span::from_position(*p),
                        name,
                    })
                }
            }
            other => match call_of(other) {
                Some((x, p)) if x.name.as_str() == "get_instance" => {
                    let a: Vec<&Expr> = x.args.iter().collect();
                    if a.len() != 1 {
                        return Err(self.arg_err(p, "get_instance", "takes 1 argument"));
                    }
                    let k = self.int(Some(a[0]), "get_instance")?;
                    u32::try_from(k).map(Object::Instance).map_err(|_| {
                        self.arg_err(a[0].position(), "get_instance", "expected an object id")
                    })
                }
                Some((x, p)) => Ok(Object::Pick(self.pick(x, p)?)),
                None => Err(self.arg_err(other.position(), f, "expected an object")),
            },
        }
    }

    /// A pick: get_obj_attributes, get_obj_in_region, get_obj.
    fn pick(&self, x: &FnCallExpr, p: rhai::Position) -> Result<Target, TypedError> {
        let f = x.name.as_str();
        let a: Vec<&Expr> = x.args.iter().collect();
        let arity = |lo: usize, hi: usize| {
            if (lo..=hi).contains(&a.len()) {
                Ok(())
            } else {
                Err(self.arg_err(
                    p,
                    f,
                    format!("takes {lo} to {hi} arguments, got {}", a.len()),
                ))
            }
        };
        match f {
            "get_obj_attributes" => {
                arity(1, 4)?;
                Ok(Target {
                    name: self.string(a[0], f)?,
                    ordinal: self.int(a.get(1).copied(), f)?,
                    colour: self.opt_string(a.get(2).copied(), f)?,
                    order: self.order(a.get(3).copied(), f)?,
                    ..Target::default()
                })
            }
            "get_obj_in_region" => {
                arity(2, 5)?;
                Ok(Target {
                    name: self.string(a[0], f)?,
                    region: Some(self.string(a[1], f)?),
                    ordinal: self.int(a.get(2).copied(), f)?,
                    colour: self.opt_string(a.get(3).copied(), f)?,
                    order: self.order(a.get(4).copied(), f)?,
                    ..Target::default()
                })
            }
            "get_obj" | "move_between_the_two" => {
                arity(1, 2)?;
                let mut t = Target {
                    name: self.string(a[0], f)?,
                    ..Target::default()
                };
                match a.get(1) {
                    None | Some(Expr::Unit(_)) => {}
                    Some(Expr::Map(m, _)) => {
                        for (key, v) in &m.0 {
                            match key.name.as_str() {
                                "ordinal" => t.ordinal = self.int(Some(v), f)?,
                                "colour" | "color" => t.colour = self.opt_string(Some(v), f)?,
                                "not_colour" | "not_color" => {
                                    t.not_colour = self.opt_string(Some(v), f)?;
                                }
                                "order" => t.order = self.order(Some(v), f)?,
                                "region" => t.region = self.opt_string(Some(v), f)?,
                                "near" => t.near = Some(Box::new(self.object(v, f)?)),
                                "other_than" => {
                                    t.other_than = Some(Box::new(self.object(v, f)?));
                                }
                                "visited" => t.visited = self.int(Some(v), f)?,
                                "not_visited" => t.not_visited = self.boolean(v, f)?,
                                other => {
                                    return Err(self.arg_err(
                                        key.pos,
                                        f,
                                        format!("unknown key `{other}`"),
                                    ))
                                }
                            }
                        }
                    }
                    Some(other) => {
                        return Err(self.arg_err(other.position(), f, "expected a map #{...}"))
                    }
                }
                Ok(t)
            }
            _ => Err(not_straight(p, format!("`{f}(..)` as an object"))),
        }
    }

    fn step(&mut self, s: &Stmt) -> Result<Step, TypedError> {
        match s {
            Stmt::Var(x, _, p) => {
                let (ident, value, _) = x.as_ref();
                let (c, cp) =
                    call_of(value).ok_or_else(|| not_straight(*p, "a `let` of a non-pick"))?;
                let target = self.pick(c, cp)?;
                self.vars.push(ident.name.to_string());
                Ok(Step::Let {
                    var: ident.name.to_string(),
                    target,
                })
            }
            Stmt::FnCall(x, p) => self.call(x, *p),
            Stmt::Expr(e) => match call_of(e) {
                Some((x, p)) => self.call(x, p),
                None => Err(not_straight(e.position(), "an expression statement")),
            },
            other => Err(not_straight(other.position(), "this statement")),
        }
    }

    fn call(&self, x: &FnCallExpr, p: rhai::Position) -> Result<Step, TypedError> {
        let f = x.name.as_str();
        let a: Vec<&Expr> = x.args.iter().collect();
        let n = |k: usize| {
            if a.len() == k {
                Ok(())
            } else {
                Err(self.arg_err(p, f, format!("takes {k} argument(s), got {}", a.len())))
            }
        };
        if let Some(side) = Side::from_function(f) {
            n(1)?;
            return Ok(Step::Side {
                side,
                object: self.object(a[0], f)?,
            });
        }
        match f {
            "move_to_object" => n(1).and_then(|()| Ok(Step::GoTo(self.object(a[0], f)?))),
            "face" => n(1).and_then(|()| Ok(Step::Face(self.object(a[0], f)?))),
            "move_in_between" => {
                n(2)?;
                Ok(Step::Between(self.object(a[0], f)?, self.object(a[1], f)?))
            }
            "move_between_the_two" => Ok(Step::BetweenTwo(self.pick(x, p)?)),
            "turn" => n(1).and_then(|()| Ok(Step::Turn(self.number(a[0], f)?))),
            "turn_absolute" => n(1).and_then(|()| Ok(Step::TurnAbsolute(self.number(a[0], f)?))),
            "move_forward" => n(1).and_then(|()| Ok(Step::Forward(self.number(a[0], f)?))),
            "move_to_start" => n(0).map(|()| Step::ToStart),
            "say" => n(1).and_then(|()| Ok(Step::Say(self.string(a[0], f)?))),
            "move_to" => {
                n(1)?;
                match a[0] {
                    Expr::Array(xs, _) if xs.len() == 2 => Ok(Step::MoveTo([
                        self.number(&xs[0], f)?,
                        self.number(&xs[1], f)?,
                    ])),
                    other => Err(self.arg_err(other.position(), f, "expected [x, y]")),
                }
            }
            _ => Err(not_straight(p, format!("a call of `{f}`"))),
        }
    }
}

/// A Rhai string literal.
fn lit(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c if (c as u32) < 0x20 || c == '\u{7f}' => {
                let _ = write!(out, "\\x{:02x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

fn num(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        format!("{x:.1}")
    } else {
        format!("{x}")
    }
}

/// The canonical call of a target: `agent.get_obj("name", #{...})` (or another function
/// taking a selection), keys only where not default.
fn target_call(t: &Target, function: &str) -> String {
    let mut keys = Vec::new();
    if t.ordinal != 0 {
        keys.push(format!("ordinal: {}", t.ordinal));
    }
    for (k, v) in [("colour", &t.colour), ("not_colour", &t.not_colour)] {
        if let Some(v) = v {
            keys.push(format!("{k}: {}", lit(v)));
        }
    }
    if t.order != ObjectOrder::default() {
        keys.push(format!("order: {}", lit(t.order.name())));
    }
    if let Some(v) = &t.region {
        keys.push(format!("region: {}", lit(v)));
    }
    if let Some(o) = &t.near {
        keys.push(format!("near: {}", o.to_rhai()));
    }
    if let Some(o) = &t.other_than {
        keys.push(format!("other_than: {}", o.to_rhai()));
    }
    if t.visited != 0 {
        keys.push(format!("visited: {}", t.visited));
    }
    if t.not_visited {
        keys.push("not_visited: true".to_string());
    }
    if keys.is_empty() {
        format!("agent.{function}({})", lit(&t.name))
    } else {
        format!(
            "agent.{function}({}, #{{{}}})",
            lit(&t.name),
            keys.join(", ")
        )
    }
}

impl Object {
    fn to_rhai(&self) -> String {
        match self {
            Object::Pick(t) => target_call(t, "get_obj"),
            Object::Name(n) => lit(n),
            Object::Var(v) => v.clone(),
            Object::Instance(id) => format!("agent.get_instance({id})"),
        }
    }
}

impl Object {
    /// Every selection inside this object expression, outermost first (a pick and,
    /// recursively, its `near` anchor and the object its `other_than` leaves out).
    #[must_use]
    pub fn targets(&self) -> Vec<&Target> {
        let mut out = Vec::new();
        if let Object::Pick(t) = self {
            out.push(t);
            out.extend(inner_targets(t));
        }
        out
    }
}

/// The selections inside a target's object-valued keys (`near`, then `other_than`).
fn inner_targets(t: &Target) -> Vec<&Target> {
    [&t.near, &t.other_than]
        .into_iter()
        .flatten()
        .flat_map(|o| o.targets())
        .collect()
}

impl Step {
    /// The object expressions this step names (its targets, bindings included), in
    /// argument order.
    #[must_use]
    pub fn targets(&self) -> Vec<&Target> {
        match self {
            Step::Let { target, .. } | Step::BetweenTwo(target) => {
                let mut v = vec![target];
                v.extend(inner_targets(target));
                v
            }
            Step::GoTo(o) | Step::Face(o) | Step::Side { object: o, .. } => o.targets(),
            Step::Between(a, b) => {
                let mut v = a.targets();
                v.extend(b.targets());
                v
            }
            Step::Turn(_)
            | Step::TurnAbsolute(_)
            | Step::Forward(_)
            | Step::MoveTo(_)
            | Step::ToStart
            | Step::Say(_) => Vec::new(),
        }
    }

    /// Whether the step ends in a stop (a goal-directed move).
    #[must_use]
    pub fn stops(&self) -> bool {
        match self {
            Step::GoTo(_)
            | Step::Between(..)
            | Step::BetweenTwo(_)
            | Step::MoveTo(_)
            | Step::ToStart => true,
            Step::Side { side, .. } => !matches!(side, Side::OnLeft | Side::OnRight),
            _ => false,
        }
    }

    /// The objects this step acts on directly (not the anchors inside them).
    #[must_use]
    pub fn objects(&self) -> Vec<&Object> {
        match self {
            Step::GoTo(o) | Step::Face(o) | Step::Side { object: o, .. } => vec![o],
            Step::Between(a, b) => vec![a, b],
            _ => Vec::new(),
        }
    }

    /// The bare names this step uses as objects (`move_to_object("kitchen")`).
    #[must_use]
    pub fn names(&self) -> Vec<&str> {
        fn of(o: &Object) -> Option<&str> {
            match o {
                Object::Name(n) => Some(n.as_str()),
                _ => None,
            }
        }
        match self {
            Step::GoTo(o) | Step::Face(o) | Step::Side { object: o, .. } => {
                of(o).into_iter().collect()
            }
            Step::Between(a, b) => of(a).into_iter().chain(of(b)).collect(),
            _ => Vec::new(),
        }
    }
}

impl TypedPlan {
    /// Reads a straight-line script.
    ///
    /// # Errors
    /// [`TypedError`] with the line and column of the first statement or argument the
    /// typed plan does not hold.
    pub fn parse(src: &str) -> Result<TypedPlan, TypedError> {
        let mut engine = rhai::Engine::new_raw();
        engine.set_optimization_level(rhai::OptimizationLevel::None);
        let ast = engine.compile(src).map_err(|e| TypedError::Parse {
            span: Span::from_position(e.position()),
            message: e.err_type().to_string(),
        })?;
        if let Some(f) = ast.iter_functions().next() {
            return Err(TypedError::NotStraightLine {
                span: Span { line: 0, col: 0 },
                what: format!("the script function `{}`", f.name),
            });
        }
        let mut reader = Reader { vars: Vec::new() };
        let steps = ast
            .statements()
            .iter()
            .map(|s| reader.step(s))
            .collect::<Result<_, _>>()?;
        Ok(TypedPlan { steps })
    }

    /// The plan as Rhai, one statement per line, picks in their canonical form.
    #[must_use]
    pub fn to_rhai(&self) -> String {
        let mut out = String::new();
        for s in &self.steps {
            let line = match s {
                Step::Let { var, target } => {
                    format!("let {var} = {};", target_call(target, "get_obj"))
                }
                Step::GoTo(o) => format!("agent.move_to_object({});", o.to_rhai()),
                Step::Side { side, object } => {
                    format!("agent.{}({});", side.function(), object.to_rhai())
                }
                Step::Between(a, b) => {
                    format!("agent.move_in_between({}, {});", a.to_rhai(), b.to_rhai())
                }
                Step::BetweenTwo(t) => format!("{};", target_call(t, "move_between_the_two")),
                Step::Face(o) => format!("agent.face({});", o.to_rhai()),
                Step::Turn(a) => format!("agent.turn({});", num(*a)),
                Step::TurnAbsolute(a) => format!("agent.turn_absolute({});", num(*a)),
                Step::Forward(d) => format!("agent.move_forward({});", num(*d)),
                Step::MoveTo([x, y]) => format!("agent.move_to([{}, {}]);", num(*x), num(*y)),
                Step::ToStart => "agent.move_to_start();".to_string(),
                Step::Say(t) => format!("say({});", lit(t)),
            };
            let _ = writeln!(out, "{line}");
        }
        out
    }
}
