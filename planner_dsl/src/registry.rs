//! The registry: one description of every function a plan may call.
//!
//! Prompts, the validator, argument checking and the docs are all generated from
//! [`registry()`], so what the LLM is told, what the validator accepts and what the
//! engine runs cannot drift apart.

use serde::Serialize;
use std::fmt::Write as _;

/// The kind of value a parameter takes (what the argument checker accepts).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ParamType {
    /// An object record (from `get_obj_attributes`) or a bare category name
    /// (meaning the nearest instance of that name).
    Object,
    /// A category name (string), e.g. `"table"`.
    Name,
    /// An ordinal: integer k >= 1 (k-th in the order), -1 (the last), 0 or `()` (the
    /// nearest / unspecified).
    Ordinal,
    /// A colour word, or `""` / `()` for any colour.
    Colour,
    /// An order name such as `"near_to_far"` (see `get_obj_attributes`).
    Order,
    /// A map position `[x, y]` in metres.
    Position,
    /// A distance in metres (negative moves backwards).
    Distance,
    /// An angle in degrees.
    Angle,
    /// Free text.
    Text,
    /// The id of an object on the map (as the conversation names the objects it visited).
    Id,
    /// What else the person said about the object, as a map with any of the keys
    /// `ordinal`, `colour`, `not_colour`, `order`, `region`, `near` (another object) and
    /// `other_than` (an object left out), `visited` (the k-th visited so far) and
    /// `not_visited` ([`SELECTION_KEYS`]): `#{ordinal: 2, near: table}`.
    Selection,
}

impl ParamType {
    /// How the type is written in docs and prompts.
    pub fn describe(self) -> &'static str {
        match self {
            ParamType::Object => "object record or name",
            ParamType::Name => "string",
            ParamType::Ordinal => "integer (k >= 1, -1 = last, -2 = second to last, 0 = nearest)",
            ParamType::Colour => "colour word or \"\"",
            ParamType::Order => "order name",
            ParamType::Position => "[x, y] in metres",
            ParamType::Distance => "number (metres)",
            ParamType::Angle => "number (degrees)",
            ParamType::Text => "string",
            ParamType::Id => "integer id of an object on the map",
            ParamType::Selection => {
                "map #{ordinal, colour, not_colour, order, region, near, other_than, visited, not_visited}, every key optional"
            }
        }
    }
}

/// One parameter of a library function.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct ParamSpec {
    /// Parameter name, as used in docs and error messages.
    pub name: &'static str,
    /// What it accepts.
    pub ty: ParamType,
    /// One-line description.
    pub doc: &'static str,
    /// Whether it may be left out (only trailing parameters are optional).
    pub optional: bool,
}

/// One function of the robot function library.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct FunctionSpec {
    /// Name, callable as `agent.name(...)` and `name(...)`.
    pub name: &'static str,
    /// Parameters in order.
    pub params: &'static [ParamSpec],
    /// What it returns.
    pub returns: &'static str,
    /// One-line description.
    pub doc: &'static str,
    /// A one-line usage example in Rhai.
    pub example: &'static str,
    /// Whether the call may move or turn the robot.
    pub moves_robot: bool,
}

impl FunctionSpec {
    /// Smallest number of arguments accepted.
    pub fn min_args(&self) -> usize {
        self.params.iter().filter(|p| !p.optional).count()
    }

    /// Largest number of arguments accepted.
    pub fn max_args(&self) -> usize {
        self.params.len()
    }

    /// Whether `n` arguments is an accepted arity.
    pub fn accepts_arity(&self, n: usize) -> bool {
        (self.min_args()..=self.max_args()).contains(&n)
    }

    /// The signature as written in prompts, e.g. `move_in_between(object_a, object_b)`;
    /// optional parameters are shown in brackets.
    pub fn signature(&self) -> String {
        let mut s = format!("{}(", self.name);
        for (i, p) in self.params.iter().enumerate() {
            if i > 0 {
                s.push_str(", ");
            }
            if p.optional {
                let _ = write!(s, "[{}]", p.name);
            } else {
                s.push_str(p.name);
            }
        }
        s.push(')');
        s
    }

    /// The arity in words for error messages, e.g. "1 argument" or "1 to 4 arguments".
    pub fn arity_text(&self) -> String {
        let (lo, hi) = (self.min_args(), self.max_args());
        let plural = |n: usize| if n == 1 { "argument" } else { "arguments" };
        if lo == hi {
            format!("{lo} {}", plural(lo))
        } else {
            format!("{lo} to {hi} {}", plural(hi))
        }
    }
}

/// The keys of a selection map ([`ParamType::Selection`]), as the runtime reads them.
pub const SELECTION_KEYS: [&str; 9] = [
    "ordinal",
    "colour",
    "not_colour",
    "order",
    "region",
    "near",
    "other_than",
    "visited",
    "not_visited",
];

const fn req(name: &'static str, ty: ParamType, doc: &'static str) -> ParamSpec {
    ParamSpec {
        name,
        ty,
        doc,
        optional: false,
    }
}

const fn opt(name: &'static str, ty: ParamType, doc: &'static str) -> ParamSpec {
    ParamSpec {
        name,
        ty,
        doc,
        optional: true,
    }
}

const REGION_ATTR_PARAMS: &[ParamSpec] = &[
    req("object_name", ParamType::Name, "category name, e.g. \"plant\""),
    req("region", ParamType::Name, "a region (room) name, e.g. \"lounge\""),
    opt(
        "instance_idx",
        ParamType::Ordinal,
        "k-th in the order among the objects in the region (1 = first), -1 = last, -2 = second to last, 0 = the nearest",
    ),
    opt(
        "object_color",
        ParamType::Colour,
        "colour word such as \"yellow\", or \"\" for any colour",
    ),
    opt(
        "order",
        ParamType::Order,
        "near_to_far (default), far_to_near, left_to_right, right_to_left, north_to_south, south_to_north, west_to_east, east_to_west, largest_to_smallest, smallest_to_largest",
    ),
];

const OBJ: &[ParamSpec] = &[req(
    "object",
    ParamType::Object,
    "an object record from get_obj_attributes, or a name meaning the nearest of that name",
)];

const OBJ_NAME: &[ParamSpec] = &[req(
    "object_name",
    ParamType::Object,
    "a name such as \"sofa\" (the nearest of that name), or an object record",
)];

const ATTR_PARAMS: &[ParamSpec] = &[
    req("object_name", ParamType::Name, "category name, e.g. \"table\""),
    opt(
        "instance_idx",
        ParamType::Ordinal,
        "k-th in the order (1 = first), -1 = last, -2 = second to last, 0 = unspecified (the nearest)",
    ),
    opt(
        "object_color",
        ParamType::Colour,
        "colour word such as \"yellow\", or \"\" for any colour",
    ),
    opt(
        "order",
        ParamType::Order,
        "near_to_far (default), far_to_near, left_to_right, right_to_left, north_to_south, south_to_north, west_to_east, east_to_west, largest_to_smallest, smallest_to_largest",
    ),
];

const OBJ_AB: &[ParamSpec] = &[
    req(
        "object_a",
        ParamType::Object,
        "first object (record or name)",
    ),
    req(
        "object_b",
        ParamType::Object,
        "second object (record or name)",
    ),
];

const POS: &[ParamSpec] = &[req("pos", ParamType::Position, "target [x, y] in metres")];

const ANGLE: &[ParamSpec] = &[req(
    "angle",
    ParamType::Angle,
    "degrees; positive turns right (clockwise), negative turns left",
)];

const HEADING: &[ParamSpec] = &[req(
    "angle",
    ParamType::Angle,
    "compass heading in degrees: 0 north, 90 east, 180 south, -90 west",
)];

const DIST: &[ParamSpec] = &[req(
    "dist",
    ParamType::Distance,
    "metres; negative moves backwards",
)];

const TEXT: &[ParamSpec] = &[req("text", ParamType::Text, "what to tell the user")];

const SELECT_PARAMS: &[ParamSpec] = &[
    req("object_name", ParamType::Name, "category name, e.g. \"chair\""),
    opt(
        "select",
        ParamType::Selection,
        "ordinal: k-th (1 = first, -1 = last, -2 = second to last); colour: a colour it has; not_colour: a colour it must not have; order: what the ordinal counts in (default near_to_far; largest_to_smallest for \"the biggest\"); region: a room it is in; near: an object it is next to (distances then count from that object); other_than: an object of the same kind it is not (\"the other red chair\": the one visited left out); visited: counted among the objects visited so far, in the order visited, instead of an ordinal (1 = \"the one you visited first\", -1 = the latest visited, \"that same one again\"); not_visited: true leaves out every object visited so far (\"the lamp you haven't been to yet\")",
    ),
];

const ID: &[ParamSpec] = &[req(
    "id",
    ParamType::Id,
    "the id of an object visited earlier in the conversation",
)];

const fn f(
    name: &'static str,
    params: &'static [ParamSpec],
    returns: &'static str,
    doc: &'static str,
    example: &'static str,
    moves_robot: bool,
) -> FunctionSpec {
    FunctionSpec {
        name,
        params,
        returns,
        doc,
        example,
        moves_robot,
    }
}

static REGISTRY: &[FunctionSpec] = &[
    f(
        "get_nearest_obj_pos",
        OBJ_NAME,
        "[x, y]",
        "get the map position [x, y] (footprint centre) of the nearest object of that name",
        "let p = agent.get_nearest_obj_pos(\"sofa\");",
        false,
    ),
    f(
        "get_obj_attributes",
        ATTR_PARAMS,
        "object record (fields: name, colour, label_id, id, position)",
        "pick one object by name, ordinal and colour; k counts in the order (default: nearest first)",
        "let table = agent.get_obj_attributes(\"table\", 3, \"yellow\");",
        false,
    ),
    f(
        "get_obj_in_region",
        REGION_ATTR_PARAMS,
        "object record (fields: name, colour, label_id, id, position)",
        "pick one object in a room (\"the plant in the lounge\"), like get_obj_attributes counting only the objects in that region",
        "let plant = agent.get_obj_in_region(\"plant\", \"lounge\");",
        false,
    ),
    f(
        "get_obj",
        SELECT_PARAMS,
        "object record (fields: name, colour, label_id, id, position)",
        "pick one object by everything said about it (\"the second chair next to the red table\", \"the sofa that isn't grey\", \"the biggest plant in the lounge\")",
        "let chair = agent.get_obj(\"chair\", #{ordinal: 2, near: agent.get_obj(\"table\", #{colour: \"red\"})});",
        false,
    ),
    f(
        "get_instance",
        ID,
        "object record (fields: name, colour, label_id, id, position)",
        "the object with this id: one visited earlier in the conversation (\"the table you just visited\", \"the same chair again\")",
        "let table = agent.get_instance(17);",
        false,
    ),
    f(
        "get_specifed_obj_pos",
        OBJ,
        "[x, y]",
        "get the map position [x, y] (footprint centre) of the object (the paper's spelling)",
        "let p = agent.get_specifed_obj_pos(table);",
        false,
    ),
    f(
        "get_specified_obj_pos",
        OBJ,
        "[x, y]",
        "get the map position [x, y] (footprint centre) of the object",
        "let p = agent.get_specified_obj_pos(table);",
        false,
    ),
    f(
        "get_nearest_obj_contour",
        OBJ_NAME,
        "array of [x, y]",
        "get the contour turning points [[x, y], ...] of the nearest object of that name",
        "let c = agent.get_nearest_obj_contour(\"sofa\");",
        false,
    ),
    f(
        "get_obj_contour",
        OBJ,
        "array of [x, y]",
        "get the contour turning points [[x, y], ...] of the object",
        "let c = agent.get_obj_contour(sofa);",
        false,
    ),
    f(
        "move_to",
        POS,
        "()",
        "move to a position [x, y] on the map (stops at the nearest reachable point)",
        "agent.move_to([2.0, 3.5]);",
        true,
    ),
    f(
        "move_to_left",
        OBJ,
        "()",
        "move to the left side of the object, as seen from the robot facing it",
        "agent.move_to_left(sofa);",
        true,
    ),
    f(
        "move_to_right",
        OBJ,
        "()",
        "move to the right side of the object, as seen from the robot facing it",
        "agent.move_to_right(sofa);",
        true,
    ),
    f(
        "with_object_on_left",
        OBJ,
        "()",
        "turn in place until the object is on the robot's left side",
        "agent.with_object_on_left(sofa);",
        true,
    ),
    f(
        "with_object_on_right",
        OBJ,
        "()",
        "turn in place until the object is on the robot's right side",
        "agent.with_object_on_right(sofa);",
        true,
    ),
    f(
        "move_in_between",
        OBJ_AB,
        "()",
        "move to the point midway between the two objects",
        "agent.move_in_between(\"sofa\", \"tv\");",
        true,
    ),
    f(
        "turn",
        ANGLE,
        "()",
        "turn right by angle degrees; a negative angle turns left",
        "agent.turn(90);",
        true,
    ),
    f(
        "face",
        OBJ,
        "()",
        "turn in place until the object is in front of the robot",
        "agent.face(table);",
        true,
    ),
    f(
        "turn_absolute",
        HEADING,
        "()",
        "turn to an absolute heading: 0 is north, 90 east, 180 south, -90 west",
        "agent.turn_absolute(180);",
        true,
    ),
    f(
        "move_north",
        OBJ,
        "()",
        "move to the north side of the object",
        "agent.move_north(\"table\");",
        true,
    ),
    f(
        "move_south",
        OBJ,
        "()",
        "move to the south side of the object",
        "agent.move_south(\"table\");",
        true,
    ),
    f(
        "move_east",
        OBJ,
        "()",
        "move to the east side of the object",
        "agent.move_east(\"table\");",
        true,
    ),
    f(
        "move_west",
        OBJ,
        "()",
        "move to the west side of the object",
        "agent.move_west(\"table\");",
        true,
    ),
    f(
        "move_to_object",
        OBJ,
        "()",
        "move to the object (the nearest reachable point next to it), or into a named region such as \"kitchen\"",
        "agent.move_to_object(table);",
        true,
    ),
    f(
        "move_forward",
        DIST,
        "()",
        "move forward dist metres; a negative value moves backward",
        "agent.move_forward(1.5);",
        true,
    ),
    f(
        "move_between_the_two",
        SELECT_PARAMS,
        "()",
        "move midway between the two objects that match (\"between the two yellow tables\"); an error says how many match when that is not two",
        "agent.move_between_the_two(\"table\", #{colour: \"yellow\"});",
        true,
    ),
    f(
        "move_to_start",
        &[],
        "()",
        "move back to where the robot was when this plan began (\"come back here\", \"back to where you started\")",
        "agent.move_to_start();",
        true,
    ),
    f(
        "say",
        TEXT,
        "()",
        "tell the user something (the only output a plan has)",
        "say(\"I cannot see a red chair\");",
        false,
    ),
];

/// Every function of the robot function library, in the paper's order, plus `say`.
pub fn registry() -> &'static [FunctionSpec] {
    REGISTRY
}

/// Looks a library function up by name.
pub fn lookup(name: &str) -> Option<&'static FunctionSpec> {
    REGISTRY.iter().find(|f| f.name == name)
}

/// Functions and methods of the Rhai standard packages that plans may call (as `f(x)`
/// or `x.f()`): arithmetic helpers, strings, arrays, maps and basic maths. Operators
/// (`+`, `==`, `..`, `in`, ...) are always allowed. Anything else is rejected.
pub const BUILTIN_ALLOW_LIST: &[&str] = &[
    // maths
    "abs",
    "sign",
    "sqrt",
    "exp",
    "ln",
    "log",
    "floor",
    "ceiling",
    "round",
    "int",
    "fraction",
    "sin",
    "cos",
    "tan",
    "asin",
    "acos",
    "atan",
    "hypot",
    "to_degrees",
    "to_radians",
    "min",
    "max",
    "is_nan",
    "is_finite",
    "is_infinite",
    "is_zero",
    "is_odd",
    "is_even",
    "PI",
    "E",
    // conversions
    "to_int",
    "to_float",
    "to_string",
    "parse_int",
    "parse_float",
    // iteration
    "range",
    // strings, arrays and maps
    "len",
    "is_empty",
    "contains",
    "index_of",
    "get",
    "to_upper",
    "to_lower",
    "trim",
    "starts_with",
    "ends_with",
    "sub_string",
    "split",
    "push",
    "pop",
    "shift",
    "insert",
    "remove",
    "clear",
    "reverse",
    "append",
    "extract",
    "keys",
    "values",
];

/// Names that are never allowed, with the reason given to the script's author.
pub const FORBIDDEN: &[(&str, &str)] = &[
    ("eval", "eval is disabled: write the plan directly"),
    ("Fn", "function pointers are disabled"),
    ("call", "function pointers are disabled"),
    ("curry", "function pointers are disabled"),
    ("import", "modules are disabled"),
    (
        "sleep",
        "there is no clock in plans; the robot waits for nothing",
    ),
    (
        "print",
        "there is no console; use say(text) to tell the user",
    ),
    (
        "debug",
        "there is no console; use say(text) to tell the user",
    ),
    ("is_def_fn", "reflection is disabled"),
    ("is_def_var", "reflection is disabled"),
    ("is_shared", "reflection is disabled"),
    ("type_of", "reflection is disabled"),
    ("timestamp", "there is no clock in plans"),
];

/// The function list for a prompt: one `# doc` line followed by the call, for each
/// function, generated from the registry.
pub fn function_list_for_prompt() -> String {
    let mut s = String::new();
    for f in REGISTRY {
        let _ = writeln!(s, "# {}.", f.doc);
        let _ = writeln!(s, "agent.{}", f.signature());
    }
    s
}

/// The registry as a Markdown reference (a table plus parameter details).
pub fn registry_markdown() -> String {
    let mut s =
        String::from("| function | returns | description | example |\n| --- | --- | --- | --- |\n");
    for f in REGISTRY {
        let _ = writeln!(
            s,
            "| `{}` | {} | {} | `{}` |",
            f.signature(),
            f.returns,
            f.doc,
            f.example
        );
    }
    s.push_str("\nParameters:\n\n");
    for f in REGISTRY {
        let _ = writeln!(s, "- `{}`", f.name);
        for p in f.params {
            let _ = writeln!(
                s,
                "  - `{}`{}: {} ({})",
                p.name,
                if p.optional { " (optional)" } else { "" },
                p.doc,
                p.ty.describe()
            );
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_selection_docs_name_every_key() {
        let doc = SELECT_PARAMS[1].doc;
        for key in SELECTION_KEYS {
            assert!(ParamType::Selection.describe().contains(key), "{key}");
            // each key opens one of the doc's clauses ("not_colour:" does not name "colour")
            assert!(
                doc.split("; ")
                    .any(|clause| clause.starts_with(&format!("{key}:"))),
                "{key}"
            );
        }
    }

    #[test]
    fn paper_functions_are_all_present() {
        for name in [
            "get_nearest_obj_pos",
            "get_obj_attributes",
            "get_specifed_obj_pos",
            "get_specified_obj_pos",
            "get_nearest_obj_contour",
            "get_obj_contour",
            "move_to",
            "move_to_left",
            "move_to_right",
            "with_object_on_left",
            "with_object_on_right",
            "move_in_between",
            "turn",
            "face",
            "turn_absolute",
            "move_north",
            "move_south",
            "move_east",
            "move_west",
            "move_to_object",
            "move_forward",
            "say",
        ] {
            assert!(lookup(name).is_some(), "{name} missing");
        }
        assert_eq!(registry().len(), 27); // the paper's 21 (two spellings) + say, get_obj_in_region, get_obj, get_instance, move_between_the_two, move_to_start
    }

    #[test]
    fn names_are_unique_and_optional_params_trail() {
        let mut names: Vec<_> = registry().iter().map(|f| f.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), registry().len());
        for f in registry() {
            let first_opt = f.params.iter().position(|p| p.optional);
            if let Some(i) = first_opt {
                assert!(f.params[i..].iter().all(|p| p.optional), "{}", f.name);
            }
            assert!(f.example.contains(f.name), "{} example", f.name);
        }
    }

    #[test]
    fn signatures_and_arity() {
        let attr = lookup("get_obj_attributes").unwrap();
        assert_eq!(
            attr.signature(),
            "get_obj_attributes(object_name, [instance_idx], [object_color], [order])"
        );
        assert_eq!((attr.min_args(), attr.max_args()), (1, 4));
        assert_eq!(attr.arity_text(), "1 to 4 arguments");
        assert_eq!(lookup("turn").unwrap().arity_text(), "1 argument");
        assert!(!attr.accepts_arity(0) && attr.accepts_arity(4) && !attr.accepts_arity(5));
    }

    #[test]
    fn prompt_and_markdown_list_every_function() {
        let p = function_list_for_prompt();
        let m = registry_markdown();
        for f in registry() {
            assert!(p.contains(&format!("agent.{}(", f.name)));
            assert!(m.contains(&format!("`{}(", f.name)));
        }
    }

    #[test]
    fn allow_lists_do_not_overlap() {
        for (name, _) in FORBIDDEN {
            assert!(!BUILTIN_ALLOW_LIST.contains(name));
            assert!(lookup(name).is_none());
        }
        for name in BUILTIN_ALLOW_LIST {
            assert!(lookup(name).is_none(), "{name}");
        }
    }
}
