//! Aligning a script's object picks with the instruction's tuples before it is checked.
//!
//! Measured on the navigation suites (README, "Navigation figures"): most rejected plans
//! were right about *what to do* and wrong about a literal argument of an object pick
//! (an ordinal counted from 0, a direction where the colour goes, an order left out, a
//! room passed to `get_obj_attributes`). Step 1's tuples are the focused reading of those
//! details, so where a pick names an object of a tuple, its arguments are rewritten from
//! that tuple instead of sending the model round the repair loop:
//!
//! - `get_obj_attributes("table", 1, "west")` with the tuple `(table, 2, yellow,
//!   west_to_east)` becomes `get_obj_attributes("table", 2, "yellow", "west_to_east")`;
//! - a bare name where an object goes (`move_to_object("sofa")`) whose tuple has an
//!   ordinal, colour or order becomes a pick (`move_to_object(agent.get_obj_attributes(
//!   "sofa", 0, "red"))`);
//! - `get_obj_attributes("kitchen", ...)` on a region of the map becomes the bare name
//!   `"kitchen"`, which every moving function accepts.
//!
//! - a pick made at the top of the script (`let t = get_obj_attributes("table", 0, "");`)
//!   but used only after earlier moves is moved down to just before its first use: "the
//!   nearest table" (and "the second from the left") mean from where the robot is when it
//!   gets there, not from where it started (a model habit seen on office-b, task ob6).
//!
//! Picks are matched to tuples by name in order of mention. Only literal string names
//! are aligned; what the model computed (variables, expressions) is left to the checks.
//! Each rewrite is reported as a [`Fix`] so that the user sees what changed.

use map_core::matcher::canonical;
use map_core::{IvlMap, ObjectOrder};
use planner_dsl::ParamType;
use serde::Serialize;

use planner_dsl::Span;

use crate::checks::{is_region_only, library_calls, Arg, LibCall};
use crate::tuples::Tuple;

/// One rewrite made by [`align_script`].
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Fix {
    /// Where the rewritten call was (in the script before alignment).
    pub pos: Span,
    /// The text before.
    pub before: String,
    /// The text after.
    pub after: String,
}

impl std::fmt::Display for Fix {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: `{}` -> `{}`", self.pos, self.before, self.after)
    }
}

/// A Rhai string literal for `s`.
fn lit(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// The call arguments a tuple stands for: `"name", k, "colour"[, "order"]`.
fn pick_args(name: &str, t: &Tuple) -> String {
    let mut s = format!(
        "{}, {}, {}",
        lit(name),
        t.ordinal.unwrap_or(0),
        lit(t.colour.as_deref().unwrap_or(""))
    );
    let order = t.object_order();
    if order != ObjectOrder::NearToFar {
        s.push_str(&format!(", {}", lit(order.name())));
    }
    s
}

/// `name` without leading colour, ordinal or superlative words ("red chair" -> "chair",
/// "second yellow table" -> "table"); unchanged when nothing would be left.
fn strip_modifiers(name: &str) -> String {
    let words: Vec<&str> = name.split_whitespace().collect();
    let skip = words
        .iter()
        .take_while(|w| {
            map_core::matcher::is_colour_word(w)
                || crate::tuples::parse_ordinal_with_order(w).is_ok_and(|(k, _)| k.is_some())
        })
        .count();
    if skip == 0 || skip == words.len() {
        name.to_string()
    } else {
        words[skip..].join(" ")
    }
}

/// Byte offset of a 1-based line and column in `src`.
fn offset_of(src: &str, pos: Span) -> Option<usize> {
    let mut off = 0usize;
    for (i, line) in src.split_inclusive('\n').enumerate() {
        if i + 1 == pos.line {
            let col = line
                .char_indices()
                .nth(pos.col.saturating_sub(1))
                .map_or(line.len(), |(b, _)| b);
            return Some(off + col);
        }
        off += line.len();
    }
    None
}

/// The byte range of the balanced `( ... )` that starts at `open` (strings respected).
fn paren_span(src: &str, open: usize) -> Option<(usize, usize)> {
    let bytes = src.as_bytes();
    if bytes.get(open) != Some(&b'(') {
        return None;
    }
    let mut depth = 0usize;
    let mut in_str = false;
    let mut escaped = false;
    for (i, &b) in bytes.iter().enumerate().skip(open) {
        if in_str {
            match (escaped, b) {
                (true, _) => escaped = false,
                (false, b'\\') => escaped = true,
                (false, b'"') => in_str = false,
                _ => {}
            }
            continue;
        }
        match b {
            b'"' => in_str = true,
            b'(' => depth += 1,
            b')' => {
                depth -= 1;
                if depth == 0 {
                    return Some((open, i + 1));
                }
            }
            _ => {}
        }
    }
    None
}

/// Where the call `call` sits in `src`: the start of the whole call expression (with any
/// `agent.` receiver), the start of its argument list `(`, and the end after `)`.
fn call_span(src: &str, call: &LibCall, spelled: &[&str]) -> Option<(usize, usize, usize)> {
    let at = offset_of(src, call.pos)?;
    // Rhai reports a method call at its name or at the dot; look a little around.
    let from = src[..at].char_indices().rev().nth(8).map_or(0, |(b, _)| b);
    let (name_at, name) = spelled
        .iter()
        .filter_map(|n| src[from..].find(n).map(|i| (from + i, *n)))
        .min_by_key(|(i, _)| *i)?;
    let mut open = name_at + name.len();
    while src[open..].starts_with([' ', '\t']) {
        open += 1;
    }
    let (_, end) = paren_span(src, open)?;
    let start = src[..name_at]
        .strip_suffix("agent.")
        .map_or(name_at, |p| p.len());
    Some((start, open, end))
}

/// Rewrites the object picks of `src` to agree with `tuples` (see the module docs). The
/// aligned script and what was changed; `src` unchanged (and no fixes) when it does not
/// parse or nothing needs changing.
#[must_use]
pub fn align_script(src: &str, tuples: &[Tuple], map: Option<&IvlMap>) -> (String, Vec<Fix>) {
    let Ok(calls) = library_calls(src) else {
        return (src.to_string(), Vec::new());
    };
    let mut used = vec![false; tuples.len()];
    // (start, end, replacement, pos)
    let mut edits: Vec<(usize, usize, String, Span)> = Vec::new();
    let mut take = |name: &str| -> Option<usize> {
        // "red chair" names a chair: a colour or ordinal word glued to the name is the
        // model restating the tuple.
        let key = canonical(&strip_modifiers(name));
        let i = (0..tuples.len()).find(|&i| !used[i] && canonical(&tuples[i].object) == key)?;
        used[i] = true;
        Some(i)
    };
    for call in &calls {
        let Some(spec) = planner_dsl::lookup(&call.function) else {
            continue;
        };
        if call.function == "get_obj_attributes" {
            let Some(Arg::Str(name)) = call.args.first() else {
                continue;
            };
            let Some((start, open, end)) = call_span(src, call, &[spec.name]) else {
                continue;
            };
            if map.is_some_and(|m| is_region_only(m, name)) {
                take(name);
                edits.push((start, end, lit(name), call.pos));
                continue;
            }
            // Every argument must be a literal for the pick to be rewritten wholesale.
            let literal = call
                .args
                .iter()
                .all(|a| matches!(a, Arg::Str(_) | Arg::Int(_) | Arg::Unit));
            if let Some(i) = take(name) {
                if literal {
                    let args = format!("({})", pick_args(&tuples[i].object, &tuples[i]));
                    if src[open..end] != args {
                        edits.push((open, end, args, call.pos));
                    }
                }
            }
            continue;
        }
        if call.function == "get_obj_in_region" {
            // Its names are a category and a room, not objects: the checks compare its
            // ordinal and colour with the tuple; the object and the room count as used.
            for a in &call.args {
                if let Arg::Str(name) = a {
                    take(name);
                }
            }
            continue;
        }
        // Bare names where an object goes.
        let Some((_, open, end)) = call_span(src, call, &[spec.name]) else {
            continue;
        };
        let object_params: Vec<bool> = spec
            .params
            .iter()
            .map(|p| matches!(p.ty, ParamType::Object | ParamType::Name))
            .collect();
        if !call
            .args
            .iter()
            .zip(&object_params)
            .any(|(a, o)| *o && matches!(a, Arg::Str(_)))
        {
            continue;
        }
        // Rewrite each string argument in place, left to right, within the argument list.
        let mut cursor = open + 1;
        for (a, is_obj) in call.args.iter().zip(&object_params) {
            let Arg::Str(name) = a else { continue };
            if !is_obj {
                continue;
            }
            let quoted = lit(name);
            let Some(rel) = src[cursor..end].find(&quoted) else {
                continue;
            };
            let (s, e) = (cursor + rel, cursor + rel + quoted.len());
            cursor = e;
            if map.is_some_and(|m| is_region_only(m, name)) {
                take(name);
                continue;
            }
            if let Some(i) = take(name) {
                let t = &tuples[i];
                if t.ordinal.is_some()
                    || t.colour.is_some()
                    || t.object_order() != ObjectOrder::NearToFar
                {
                    edits.push((
                        s,
                        e,
                        format!("agent.get_obj_attributes({})", pick_args(name, t)),
                        call.pos,
                    ));
                }
            }
        }
    }
    if edits.is_empty() {
        return sink_picks(src, Vec::new());
    }
    edits.sort_by_key(|e| e.0);
    // Nested or overlapping edits (a pick inside an aligned call): keep the outermost.
    let mut kept: Vec<(usize, usize, String, Span)> = Vec::new();
    for e in edits {
        match kept.last() {
            Some(last) if e.0 < last.1 => {}
            _ => kept.push(e),
        }
    }
    let mut out = src.to_string();
    let mut fixes = Vec::new();
    for (s, e, rep, pos) in kept.into_iter().rev() {
        fixes.push(Fix {
            pos,
            before: src[s..e].to_string(),
            after: rep.clone(),
        });
        out.replace_range(s..e, &rep);
    }
    fixes.reverse();
    sink_picks(&out, fixes)
}

/// Brace depth change of a line (braces inside string literals and comments ignored).
fn brace_delta(line: &str) -> i64 {
    let mut d = 0i64;
    let mut in_str = false;
    let mut prev = ' ';
    for c in line.chars() {
        if in_str {
            if c == '"' && prev != '\\' {
                in_str = false;
            }
        } else if c == '"' {
            in_str = true;
        } else if c == '/' && prev == '/' {
            break;
        } else if c == '{' {
            d += 1;
        } else if c == '}' {
            d -= 1;
        }
        prev = c;
    }
    d
}

/// A one-line `let name = [agent.]rhs;`: the name and the right-hand side without
/// `agent.`.
fn let_binding(line: &str) -> Option<(&str, &str)> {
    let rest = line.trim().strip_prefix("let ")?;
    let (name, rhs) = rest.split_once('=')?;
    let name = name.trim();
    let rhs = rhs.trim();
    let rhs = rhs.strip_prefix("agent.").unwrap_or(rhs);
    (rhs.ends_with(';')
        && !name.is_empty()
        && name.chars().all(|c| c.is_alphanumeric() || c == '_'))
    .then_some((name, rhs))
}

/// The variable a top-level one-line pick binds: `let v = [agent.]get_obj_attributes(...);`.
fn pick_binding(line: &str) -> Option<&str> {
    let_binding(line)
        .filter(|(_, rhs)| rhs.starts_with("get_obj_attributes"))
        .map(|(name, _)| name)
}

/// `let x = agent.get_nearest_obj_pos("plant");`: a target a plan picks to go to (a
/// script that never uses it stops short). A bare region name (`let r = "kitchen";`) is
/// not one: "the plant in the kitchen" names a room that nothing goes to.
fn target_binding(line: &str) -> Option<&str> {
    const PICKS: &[&str] = &[
        "get_obj_in_region",
        "get_nearest_obj_pos",
        "get_specifed_obj_pos",
        "get_specified_obj_pos",
    ];
    let_binding(line)
        .filter(|(_, rhs)| PICKS.iter().any(|f| rhs.starts_with(f)))
        .map(|(name, _)| name)
}

fn mentions(line: &str, var: &str) -> bool {
    line.match_indices(var).any(|(i, _)| {
        let before = line[..i].chars().next_back();
        let after = line[i + var.len()..].chars().next();
        let word = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
        !word(before) && !word(after)
    })
}

/// Picks bound to a variable that nothing uses afterwards: `(line, variable)`, 1-based.
/// A script that picks "the second chair" and never goes there did not do what was asked.
pub(crate) fn unused_picks(src: &str) -> Vec<(usize, String)> {
    let lines: Vec<&str> = src.lines().collect();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        if let Some(var) = pick_binding(l).or_else(|| target_binding(l)) {
            if !lines[i + 1..].iter().any(|later| mentions(later, var)) {
                out.push((i + 1, var.to_string()));
            }
        }
    }
    out
}

/// Moves top-level picks down to just before their first use when moves come between
/// (see the module docs). Lines keep their text; only their order changes.
fn sink_picks(src: &str, mut fixes: Vec<Fix>) -> (String, Vec<Fix>) {
    let mut lines: Vec<String> = src.lines().map(str::to_string).collect();
    let moving: Vec<&str> = planner_dsl::registry()
        .iter()
        .filter(|f| f.moves_robot)
        .map(|f| f.name)
        .collect();
    let mut i = 0;
    while i < lines.len() {
        let depth_before: i64 = lines[..i].iter().map(|l| brace_delta(l)).sum();
        let Some(var) = pick_binding(&lines[i]).map(str::to_string) else {
            i += 1;
            continue;
        };
        if depth_before != 0 {
            i += 1;
            continue;
        }
        let Some(j) = (i + 1..lines.len()).find(|&j| mentions(&lines[j], &var)) else {
            i += 1;
            continue;
        };
        let depth_at_j: i64 = lines[..j].iter().map(|l| brace_delta(l)).sum();
        let moves_between = lines[i + 1..j]
            .iter()
            .any(|l| moving.iter().any(|m| mentions(l, m)));
        if depth_at_j != 0 || !moves_between {
            i += 1;
            continue;
        }
        let line = lines.remove(i);
        fixes.push(Fix {
            pos: Span {
                line: i + 1,
                col: 1,
            },
            before: line.trim().to_string(),
            after: format!("the same pick, made just before line {} uses it", j + 1),
        });
        lines.insert(j - 1, line);
        // Line i now holds the next line: look at it without advancing.
    }
    let mut out = lines.join("\n");
    if src.ends_with('\n') {
        out.push('\n');
    }
    (out, fixes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(o: &str, k: Option<i64>, c: Option<&str>, order: Option<&str>) -> Tuple {
        Tuple::new(o, k, c).with_order(order)
    }

    #[test]
    fn pick_arguments_follow_the_tuple() {
        let src =
            "let t = agent.get_obj_attributes(\"table\", 1, \"west\");\nagent.move_to_object(t);";
        let (out, fixes) = align_script(
            src,
            &[t("table", Some(2), Some("yellow"), Some("west_to_east"))],
            None,
        );
        assert_eq!(
            out,
            "let t = agent.get_obj_attributes(\"table\", 2, \"yellow\", \"west_to_east\");\nagent.move_to_object(t);"
        );
        assert_eq!(fixes.len(), 1);
        assert_eq!(fixes[0].pos.line, 1);
    }

    #[test]
    fn picks_match_tuples_in_order_of_mention() {
        let src = "let a = get_obj_attributes(\"chair\", 0, \"\");\nlet b = agent.get_obj_attributes(\"chair\", 0, \"\");\nmove_in_between(a, b);";
        let (out, _) = align_script(
            src,
            &[
                t("chair", Some(1), Some("red"), None),
                t("chair", Some(-1), None, None),
            ],
            None,
        );
        assert!(
            out.contains("get_obj_attributes(\"chair\", 1, \"red\")"),
            "{out}"
        );
        assert!(
            out.contains("get_obj_attributes(\"chair\", -1, \"\")"),
            "{out}"
        );
    }

    #[test]
    fn bare_names_with_a_specific_tuple_become_picks() {
        let src = "agent.move_to_object(\"sofa\");\nagent.move_to_object(\"lamp\");";
        let (out, fixes) = align_script(
            src,
            &[
                t("sofa", None, Some("red"), None),
                t("lamp", None, None, None),
            ],
            None,
        );
        assert_eq!(
            out,
            "agent.move_to_object(agent.get_obj_attributes(\"sofa\", 0, \"red\"));\nagent.move_to_object(\"lamp\");"
        );
        assert_eq!(fixes.len(), 1);
    }

    #[test]
    fn a_colour_glued_to_the_name_is_the_tuples_object() {
        let src = "let c = agent.get_obj_attributes(\"white counter\", (), \"white\");";
        let (out, _) = align_script(src, &[t("counter", None, Some("white"), None)], None);
        assert_eq!(
            out,
            "let c = agent.get_obj_attributes(\"counter\", 0, \"white\");"
        );
    }

    #[test]
    fn agreeing_scripts_are_left_alone() {
        let src = "let c = agent.get_obj_attributes(\"chair\", 2, \"white\");\nagent.move_to_object(c);\nagent.turn(180);";
        let (out, fixes) = align_script(src, &[t("chair", Some(2), Some("white"), None)], None);
        assert_eq!(out, src);
        assert!(fixes.is_empty());
    }

    #[test]
    fn computed_arguments_are_not_rewritten() {
        let src = "let k = 1 + 1;\nlet c = agent.get_obj_attributes(\"chair\", k, \"white\");";
        let (out, _) = align_script(src, &[t("chair", Some(3), Some("white"), None)], None);
        assert_eq!(out, src);
    }

    #[test]
    fn picks_are_made_where_the_robot_is_when_it_needs_them() {
        let src = "let plant = agent.get_obj_attributes(\"plant\", 0, \"\");\nlet table = agent.get_obj_attributes(\"table\", 0, \"\");\nagent.move_to_object(plant);\nagent.move_to_object(table);\n";
        let (out, fixes) = align_script(
            src,
            &[t("plant", None, None, None), t("table", None, None, None)],
            None,
        );
        assert_eq!(
            out,
            "let plant = agent.get_obj_attributes(\"plant\", 0, \"\");\nagent.move_to_object(plant);\nlet table = agent.get_obj_attributes(\"table\", 0, \"\");\nagent.move_to_object(table);\n"
        );
        assert_eq!(fixes.len(), 1, "{fixes:?}");
        // Inside a loop body nothing moves.
        let looped = "let c = agent.get_obj_attributes(\"chair\", 0, \"\");\nfor i in 0..2 {\nagent.turn(90);\nagent.face(c);\n}\n";
        assert_eq!(
            align_script(looped, &[t("chair", None, None, None)], None).0,
            looped
        );
    }

    #[test]
    fn unparsable_scripts_come_back_unchanged() {
        let (out, fixes) = align_script("let x = (;", &[t("chair", None, None, None)], None);
        assert_eq!(out, "let x = (;");
        assert!(fixes.is_empty());
    }
}
