//! Agreement checks between a script, the instruction's tuples and the map.
//!
//! A script can be valid Rhai that calls only the library and still mean the wrong thing
//! (design.md: ordinals counted from 0, the order string passed as the colour, an ordinal
//! copied from another mention, a colour on the wrong noun). These checks find such
//! disagreements in the literal arguments of library calls; the pipeline turns each
//! [`Finding`] into repair feedback that quotes its line and column.

use map_core::matcher::{canonical, is_colour_word};
use map_core::{IvlMap, ObjectOrder, QueryError};
use planner_dsl::{ParamType, Span};
use rhai::{ASTNode, Expr, FnCallExpr, Stmt};
use serde::Serialize;

use crate::tuples::{normalise_colour, Tuple};

/// A call argument as written: a literal, a variable, or something computed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum Arg {
    /// A string literal.
    Str(String),
    /// An integer literal (negative literals included).
    Int(i64),
    /// A float literal.
    Float(f64),
    /// `()`.
    Unit,
    /// A variable.
    Var(String),
    /// Anything else (an expression, a call, an array...).
    Other,
}

/// A library call found in a script.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LibCall {
    /// The library function.
    pub function: String,
    /// Where the call is.
    pub pos: Span,
    /// The arguments as written.
    pub args: Vec<Arg>,
}

fn arg_of(e: &Expr) -> Arg {
    match e {
        Expr::StringConstant(s, _) => Arg::Str(s.to_string()),
        Expr::IntegerConstant(i, _) => Arg::Int(*i),
        Expr::FloatConstant(f, _) => Arg::Float(**f),
        Expr::Unit(_) => Arg::Unit,
        Expr::Variable(v, ..) => Arg::Var(v.1.to_string()),
        Expr::FnCall(x, _) if x.name.as_str() == "-" && x.args.len() == 1 => {
            match arg_of(&x.args[0]) {
                Arg::Int(i) => Arg::Int(-i),
                Arg::Float(f) => Arg::Float(-f),
                _ => Arg::Other,
            }
        }
        _ => Arg::Other,
    }
}

fn lib_call(x: &FnCallExpr, p: rhai::Position) -> Option<LibCall> {
    let spec = planner_dsl::lookup(x.name.as_str())?;
    Some(LibCall {
        function: spec.name.to_string(),
        pos: Span::from_position(p),
        args: x.args.iter().map(arg_of).collect(),
    })
}

/// Every call of a library function in `src` (as `f(..)` or `agent.f(..)`), in source
/// order, with literal arguments read out.
///
/// # Errors
/// The parse error, with its position, when `src` is not valid Rhai.
pub fn library_calls(src: &str) -> Result<Vec<LibCall>, String> {
    let engine = rhai::Engine::new_raw();
    let ast = engine
        .compile(src)
        .map_err(|e| format!("{}: {}", Span::from_position(e.position()), e.err_type()))?;
    let mut calls = Vec::new();
    ast.walk(&mut |path: &[ASTNode<'_>]| {
        let found = match path.last() {
            Some(ASTNode::Stmt(Stmt::FnCall(x, p))) => lib_call(x, *p),
            Some(ASTNode::Expr(Expr::FnCall(x, p) | Expr::MethodCall(x, p))) => lib_call(x, *p),
            _ => None,
        };
        calls.extend(found);
        true
    });
    calls.sort_by_key(|c| c.pos);
    calls.dedup();
    Ok(calls)
}

/// What disagrees.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FindingKind {
    /// The script picks an object the instruction does not mention.
    NotMentioned,
    /// The script's ordinal differs from the tuple's.
    Ordinal,
    /// The script's ordinal is the tuple's minus one: counted from 0.
    ZeroBased,
    /// The script's colour differs from the tuple's.
    Colour,
    /// The colour argument is not a colour (often an order string in the wrong place).
    NotAColour,
    /// The map has no such object (or the ordinal is past the count, or no such colour).
    Map,
    /// An order argument that is not an order name.
    BadOrder,
    /// A mentioned object the script never uses.
    Unused,
}

/// One disagreement, with where it is and a message for the model or the user.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Finding {
    /// The call it concerns, if any.
    pub pos: Option<Span>,
    /// Its kind.
    pub kind: FindingKind,
    /// What is wrong and what to do.
    pub message: String,
}

impl std::fmt::Display for Finding {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.pos {
            Some(p) => write!(f, "{p}: {}", self.message),
            None => f.write_str(&self.message),
        }
    }
}

fn same_name(a: &str, b: &str) -> bool {
    canonical(a) == canonical(b)
}

/// Whether `name` names a region of the map.
fn is_region(map: &IvlMap, name: &str) -> bool {
    map.find_region(name).is_ok()
}

/// Whether `name` names a region and no object: a room to go to, not to pick.
pub(crate) fn is_region_only(map: &IvlMap, name: &str) -> bool {
    is_region(map, name)
        && map
            .get_obj_attributes(name, 0, None, ObjectOrder::NearToFar, map.start_pose)
            .is_err()
}

fn tuple_text(t: &Tuple) -> String {
    let k = match t.ordinal {
        None => "no ordinal".to_string(),
        Some(k) => map_core::query::ordinal_word(k),
    };
    format!(
        "({}, {}, {})",
        t.object,
        k,
        t.colour.as_deref().unwrap_or("any colour")
    )
}

/// Checks a script against the instruction's tuples and (if given) the map. Only literal
/// arguments are checked; a variable or computed argument is trusted.
///
/// # Errors
/// The parse error when `src` is not valid Rhai.
pub fn check_script(
    src: &str,
    tuples: &[Tuple],
    map: Option<&IvlMap>,
) -> Result<Vec<Finding>, String> {
    let calls = library_calls(src)?;
    let mut out = Vec::new();
    let mut used = vec![false; tuples.len()];
    let map_colours: Vec<String> = map.map(|m| m.colours.clone()).unwrap_or_default();
    let colour_ok = |c: &str| is_colour_word(c) || map_colours.iter().any(|m| same_name(m, c));

    for call in &calls {
        let Some(spec) = planner_dsl::lookup(&call.function) else {
            continue;
        };
        let at = Some(call.pos);
        if call.function == "get_obj_attributes" || call.function == "get_obj_in_region" {
            // get_obj_in_region(name, region, k, colour, order): the same checks, and the
            // map's answer within the region.
            let (args, room): (Vec<Arg>, Option<String>) = if call.function == "get_obj_in_region" {
                let room = match call.args.get(1) {
                    Some(Arg::Str(r)) => Some(r.clone()),
                    _ => None,
                };
                let mut a = call.args.clone();
                if a.len() > 1 {
                    a.remove(1);
                }
                (a, room)
            } else {
                (call.args.clone(), None)
            };
            let Some(Arg::Str(name)) = args.first() else {
                continue;
            };
            let k = match args.get(1) {
                None | Some(Arg::Unit) => Some(0),
                Some(Arg::Int(k)) => Some(*k),
                _ => None,
            };
            let colour: Option<Option<String>> = match args.get(2) {
                None | Some(Arg::Unit) => Some(None),
                Some(Arg::Str(c)) if c.trim().is_empty() => Some(None),
                Some(Arg::Str(c)) => Some(Some(c.clone())),
                _ => None,
            };
            let order = match args.get(3) {
                None | Some(Arg::Unit) => Some(ObjectOrder::NearToFar),
                Some(Arg::Str(o)) => match ObjectOrder::parse(o) {
                    Ok(o) => Some(o),
                    Err(e) => {
                        out.push(Finding {
                            pos: at,
                            kind: FindingKind::BadOrder,
                            message: format!("get_obj_attributes(\"{name}\", ...): {e}"),
                        });
                        None
                    }
                },
                _ => None,
            };
            // A colour argument that is not a colour.
            let mut colour_valid = true;
            if let Some(Some(c)) = &colour {
                if !colour_ok(c) {
                    colour_valid = false;
                    let hint = if ObjectOrder::parse(c).is_ok() {
                        format!(
                            "\"{c}\" is an order: pass the colour (or \"\") as the 3rd argument and \"{c}\" as the 4th"
                        )
                    } else {
                        "the 3rd argument must be a colour word or \"\"".to_string()
                    };
                    out.push(Finding {
                        pos: at,
                        kind: FindingKind::NotAColour,
                        message: format!(
                            "get_obj_attributes(\"{name}\", ...): \"{c}\" is not a colour; {hint}"
                        ),
                    });
                }
            }
            // Agreement with the tuples.
            let cands: Vec<usize> = (0..tuples.len())
                .filter(|&i| same_name(&tuples[i].object, name))
                .collect();
            if cands.is_empty() {
                if !tuples.is_empty() {
                    out.push(Finding {
                        pos: at,
                        kind: FindingKind::NotMentioned,
                        message: format!(
                            "the instruction does not mention a \"{name}\"; it mentions {}",
                            tuples
                                .iter()
                                .map(|t| t.object.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    });
                }
            } else {
                let agrees = |i: usize| {
                    let t = &tuples[i];
                    k.is_some_and(|k| ordinal_agrees(k, t.ordinal, order))
                        && colour
                            .as_ref()
                            .is_some_and(|c| c.as_deref().and_then(normalise_colour) == t.colour)
                };
                let pick = cands
                    .iter()
                    .copied()
                    .find(|&i| !used[i] && agrees(i))
                    .or_else(|| cands.iter().copied().find(|&i| agrees(i)))
                    .or_else(|| cands.iter().copied().find(|&i| !used[i]))
                    .unwrap_or(cands[0]);
                used[pick] = true;
                let t = &tuples[pick];
                if let Some(k) = k {
                    if !ordinal_agrees(k, t.ordinal, order) {
                        let want = t.ordinal.unwrap_or(0);
                        if want >= 1 && k == want - 1 {
                            out.push(Finding {
                                pos: at,
                                kind: FindingKind::ZeroBased,
                                message: format!(
                                    "get_obj_attributes(\"{name}\", {k}, ...): ordinals count from 1; the instruction asks for the {} {name}, so pass {want}",
                                    map_core::query::ordinal_word(want)
                                ),
                            });
                        } else {
                            out.push(Finding {
                                pos: at,
                                kind: FindingKind::Ordinal,
                                message: format!(
                                    "get_obj_attributes(\"{name}\", {k}, ...): the instruction's tuple is {}, so the ordinal must be {want}",
                                    tuple_text(t)
                                ),
                            });
                        }
                    }
                }
                if let Some(c) = &colour {
                    let got = c.as_deref().and_then(normalise_colour);
                    if colour_valid && got != t.colour {
                        out.push(Finding {
                            pos: at,
                            kind: FindingKind::Colour,
                            message: format!(
                                "get_obj_attributes(\"{name}\", ..., {}): the instruction's tuple is {}, so the colour must be {}",
                                c.as_deref().map_or("\"\"".to_string(), |c| format!("\"{c}\"")),
                                tuple_text(t),
                                t.colour.as_deref().map_or("\"\"".to_string(), |c| format!("\"{c}\""))
                            ),
                        });
                    }
                }
            }
            // The map.
            if let (Some(m), Some(k), Some(c), Some(o)) = (map, k, &colour, order) {
                if is_region_only(m, name) {
                    out.push(Finding {
                        pos: at,
                        kind: FindingKind::Map,
                        message: format!(
                            "\"{name}\" is a region, not an object: go there with agent.move_to_object(\"{name}\")"
                        ),
                    });
                } else if colour_valid {
                    let answer = match &room {
                        Some(r) => m.get_obj_in_region(name, r, k, c.as_deref(), o, m.start_pose),
                        None => m.get_obj_attributes(name, k, c.as_deref(), o, m.start_pose),
                    };
                    if let Err(e) = answer {
                        out.push(map_finding(at, name, &e));
                    }
                }
            }
            continue;
        }
        // Bare names passed where an object goes: the nearest of that name.
        for (p, a) in spec.params.iter().zip(&call.args) {
            if !matches!(p.ty, ParamType::Object | ParamType::Name) {
                continue;
            }
            let Arg::Str(name) = a else { continue };
            let region = map.is_some_and(|m| is_region(m, name));
            let cands: Vec<usize> = (0..tuples.len())
                .filter(|&i| same_name(&tuples[i].object, name))
                .collect();
            if cands.is_empty() && !tuples.is_empty() {
                out.push(Finding {
                    pos: at,
                    kind: FindingKind::NotMentioned,
                    message: format!(
                        "{}(\"{name}\"): the instruction does not mention a \"{name}\"",
                        call.function
                    ),
                });
            } else if let Some(&i) = cands.iter().find(|&&i| !used[i]).or(cands.first()) {
                used[i] = true;
                let t = &tuples[i];
                if (t.ordinal.is_some_and(|k| k != 1) || t.colour.is_some()) && !region {
                    out.push(Finding {
                        pos: at,
                        kind: FindingKind::Ordinal,
                        message: format!(
                            "{}(\"{name}\") means the nearest {name} of any colour, but the instruction's tuple is {}: pick it with get_obj_attributes first",
                            call.function,
                            tuple_text(t)
                        ),
                    });
                }
            }
            if let Some(m) = map {
                if !region {
                    if let Err(e) =
                        m.get_obj_attributes(name, 0, None, ObjectOrder::NearToFar, m.start_pose)
                    {
                        out.push(map_finding(at, name, &e));
                    }
                }
            }
        }
    }
    for (line, var) in crate::align::unused_picks(src) {
        out.push(Finding {
            pos: Some(Span { line, col: 1 }),
            kind: FindingKind::Unused,
            message: format!(
                "`{var}` is picked but never used: go to it (agent.move_to_object({var})), face it or pass it to the function the instruction asks for"
            ),
        });
    }
    for (i, t) in tuples.iter().enumerate() {
        if used[i] || map.is_some_and(|m| is_region(m, &t.object)) {
            continue;
        }
        // A mention used anywhere (e.g. through a literal in other code) is fine.
        if calls.iter().any(|c| {
            c.args
                .iter()
                .any(|a| matches!(a, Arg::Str(s) if same_name(s, &t.object)))
        }) {
            continue;
        }
        out.push(Finding {
            pos: None,
            kind: FindingKind::Unused,
            message: format!(
                "the instruction mentions {} but the script never uses a \"{}\"",
                tuple_text(t),
                t.object
            ),
        });
    }
    Ok(out)
}

/// Whether a script ordinal `k` (0 = unspecified) agrees with a tuple ordinal: equal, or
/// both meaning "the first in the default order" (0 and 1 under near_to_far).
fn ordinal_agrees(k: i64, want: Option<i64>, order: Option<ObjectOrder>) -> bool {
    let want = want.unwrap_or(0);
    k == want || (order == Some(ObjectOrder::NearToFar) && matches!((k, want), (0, 1) | (1, 0)))
}

fn map_finding(pos: Option<Span>, name: &str, e: &QueryError) -> Finding {
    Finding {
        pos,
        kind: FindingKind::Map,
        message: format!("\"{name}\": {e}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_literal_args_in_both_call_forms() {
        let calls = library_calls(
            "let t = agent.get_obj_attributes(\"table\", -1, ());\nmove_to_object(t);\nagent.move_in_between(\"bed\", \"lamp\");",
        )
        .unwrap();
        assert_eq!(calls.len(), 3);
        assert_eq!(calls[0].function, "get_obj_attributes");
        assert_eq!(
            calls[0].args,
            vec![Arg::Str("table".into()), Arg::Int(-1), Arg::Unit]
        );
        assert_eq!(calls[0].pos.line, 1);
        assert_eq!(calls[1].args, vec![Arg::Var("t".into())]);
        assert_eq!(calls[2].pos.line, 3);
    }
}
