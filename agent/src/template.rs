//! Plans written from the tuples without the LLM, for instructions that are a plain
//! sequence of clauses each of which names one library call:
//!
//! | clause | call |
//! |---|---|
//! | "go to the second red chair", "then the kitchen" | `move_to_object` |
//! | "stop on the left of the black sofa" | `move_to_left` / `move_to_right` |
//! | "go to the north side of the table", "go south of the bed" | `move_north` ... `move_west` |
//! | "go in between the black table and the red sofa" | `move_in_between` |
//! | "face the tv", "turn to face the tv" | `face` |
//! | "the plant in the lounge" (any of the above) | `get_obj_in_region` picks it |
//!
//! Every noun phrase must agree word for word with the tuple of its position (ordinal,
//! colour, counting order), so a tuple step 1 got wrong, or a clause this table does not
//! hold ("the chair next to the desk", "between the two yellow tables"), leaves the
//! instruction to step 2 and its checks. Measured on the navigation suites, step 2 with
//! the 1.5B model takes 10-70 s per spatial task and is where most of its misses were;
//! these clauses have exactly one reading, so the LLM adds only risk to them.

use map_core::{IvlMap, ObjectOrder};

use crate::checks::is_region_only;
use crate::tuples::{normalise_colour, normalise_object, parse_ordinal_with_order, Tuple};

const GOTO_PREFIXES: &[&str] = &[
    "go over to ",
    "go up to ",
    "go back to ",
    "drive up to ",
    "drive over to ",
    "walk up to ",
    "make your way to ",
    "take me to ",
    "head for ",
    "return to ",
    "come to ",
    "end up in ",
    "end up at ",
    "finish in ",
    "finish up in ",
    "wrap up in ",
    "stop in ",
    "stop at ",
    "stop next to ",
    "stop by ",
    "park next to ",
    "park by ",
    "go to ",
    "go into ",
    "go in to ",
    "navigate to ",
    "move to ",
    "move over to ",
    "walk to ",
    "walk over to ",
    "walk into ",
    "head to ",
    "head over to ",
    "head into ",
    "drive to ",
    "proceed to ",
    "travel to ",
    "get to ",
    "visit ",
    "reach ",
    "enter ",
];

const SEPARATORS: &[&str] = &[
    ", and then ",
    ", then ",
    " and then ",
    " then ",
    ", and ",
    " and ",
    "; ",
    ", ",
    ". ",
];

/// Verbs that may open a side or between clause ("stop on the left of ...").
const MOVE_VERBS: &[&str] = &[
    "go", "stop", "move", "walk", "head", "drive", "navigate", "stand", "wait", "get", "park",
];

const FACE_PREFIXES: &[&str] = &[
    "turn to face ",
    "turn and face ",
    "face ",
    "look at ",
    "turn towards ",
    "turn toward ",
];

/// What one clause asks for, with its noun phrases (one, or two for between).
#[derive(Debug, PartialEq)]
enum Action<'a> {
    GoTo(&'a str),
    Side(&'static str, &'a str),
    Between(&'a str, &'a str),
    Face(&'a str),
}

/// The library function for a side word.
fn side_function(word: &str) -> Option<&'static str> {
    Some(match word {
        "left" => "move_to_left",
        "right" => "move_to_right",
        "north" => "move_north",
        "south" => "move_south",
        "east" => "move_east",
        "west" => "move_west",
        _ => return None,
    })
}

/// Strips a leading move verb (optional for a later clause: "then to the north side of").
fn strip_verb(c: &str, later: bool) -> Option<&str> {
    let first = c.split_whitespace().next()?;
    if MOVE_VERBS.contains(&first) {
        return Some(c[first.len()..].trim_start());
    }
    later.then_some(c)
}

/// "on the left of X", "to the north side of X", "north of X", "the west side of X".
fn side_clause(rest: &str) -> Option<(&'static str, &str)> {
    let mut r = rest;
    for prep in ["over to ", "on to ", "onto ", "on ", "to ", "at ", "by "] {
        if let Some(x) = r.strip_prefix(prep) {
            r = x;
            break;
        }
    }
    let r = r.strip_prefix("the ").unwrap_or(r);
    let (word, after) = r.split_once(' ')?;
    let f = side_function(word)?;
    let after = after
        .strip_prefix("hand side of ")
        .or_else(|| after.strip_prefix("side of "))
        .or_else(|| after.strip_prefix("of "))?;
    Some((f, after))
}

/// The action of one clause; `later` when an earlier clause gave the verb.
fn classify(c: &str, later: bool) -> Option<Action<'_>> {
    if let Some(np) = FACE_PREFIXES.iter().find_map(|p| c.strip_prefix(p)) {
        return Some(Action::Face(np));
    }
    if let Some(rest) = strip_verb(c, later) {
        let b = rest
            .strip_prefix("in between ")
            .or_else(|| rest.strip_prefix("between "));
        if let Some(b) = b {
            let (x, y) = b.split_once(" & ")?;
            return Some(Action::Between(x, y));
        }
        if let Some((f, np)) = side_clause(rest) {
            return Some(Action::Side(f, np));
        }
    }
    // "go to A, then B, then to C": later clauses may leave the verb out.
    let rest = match GOTO_PREFIXES.iter().find_map(|p| c.strip_prefix(p)) {
        Some(r) => r,
        None if later => ["over to ", "on to ", "to ", "into ", ""]
            .iter()
            .find_map(|p| c.strip_prefix(p))
            .filter(|r| {
                r.starts_with("the ") || r.starts_with("a ") || r.starts_with("whichever ")
            })?,
        None => return None,
    };
    Some(Action::GoTo(rest))
}

/// "[the] [ordinal|superlative] [colour] noun [counting phrase]": the tuple its words say.
fn read_noun_phrase(np: &str) -> Option<Tuple> {
    // "whichever plant is closest": the nearest plant.
    let np = match np.strip_prefix("whichever ") {
        Some(r) => [
            "is closest",
            "is nearest",
            "is the closest",
            "is the nearest",
        ]
        .iter()
        .find_map(|q| r.strip_suffix(q))?
        .trim_end(),
        None => np,
    };
    let (rest, trailing_order) = strip_trailing_qualifier(np)?;
    let mut ordinal: Option<i64> = None;
    let mut order: Option<String> = trailing_order;
    let mut colour: Option<String> = None;
    let mut noun: Vec<&str> = Vec::new();
    for w in rest.split_whitespace() {
        if matches!(w, "the" | "a" | "an") && noun.is_empty() {
            continue;
        }
        if noun.is_empty() && ordinal.is_some() && matches!(w, "nearest" | "closest") {
            // "the second nearest": the default order, already counted.
            continue;
        }
        if noun.is_empty() && ordinal.is_none() && colour.is_none() {
            if let Ok((k, o)) = parse_ordinal_with_order(w) {
                // "nearest"/"closest" read as unspecified.
                if k.is_some() || matches!(w, "nearest" | "closest") {
                    ordinal = k;
                    if o.is_some() {
                        if order.is_some() {
                            return None;
                        }
                        order = o;
                    }
                    continue;
                }
            }
        }
        if noun.is_empty() && colour.is_none() && map_core::matcher::is_colour_word(w) {
            colour = normalise_colour(w);
            continue;
        }
        // Sizes are not on the map: "the little table" is a table.
        if noun.is_empty() && matches!(w, "little" | "small" | "big" | "large" | "tall" | "low") {
            continue;
        }
        if !w.chars().all(|ch| ch.is_alphabetic() || ch == '-') {
            return None;
        }
        noun.push(w);
    }
    if noun.is_empty() || noun.len() > 3 {
        return None;
    }
    let object = normalise_object(&noun.join(" "));
    Some(Tuple::new(&object, ordinal, colour.as_deref()).with_order(order.as_deref()))
}

/// Splits a counting phrase off the end of a noun phrase: "the second table from the
/// west" -> ("the second table", west_to_east); "counting from west to east" likewise;
/// "nearest to you" / "closest to you" / "nearest to it" (the default order: distances
/// from where the robot is) are dropped. `None` when a trailing phrase is not understood
/// ("the chair next to the desk" is for the LLM path).
fn strip_trailing_qualifier(rest: &str) -> Option<(&str, Option<String>)> {
    for q in [
        " nearest to you",
        " closest to you",
        " nearest to it",
        " closest to it",
        " next to it",
        " near it",
        " beside it",
        " by it",
        " nearest to the robot",
    ] {
        if let Some(r) = rest.strip_suffix(q) {
            return Some((r, None));
        }
    }
    for lead in [" counting from ", " from "] {
        if let Some(i) = rest.rfind(lead) {
            let phrase = &rest[i + 1..];
            let o = crate::tuples::normalise_order(phrase)?;
            return Some((&rest[..i], Some(o)));
        }
    }
    Some((rest, None))
}

/// The words split into clauses; "between A and B" keeps its "and" (as " & ").
fn clauses(instruction: &str) -> Vec<String> {
    let mut text = instruction.trim().to_lowercase();
    while text.ends_with(['.', '!', '?']) {
        text.pop();
    }
    let mut protected = String::new();
    let mut rest = text.as_str();
    while let Some(i) = rest.find("between ") {
        let (head, tail) = rest.split_at(i + "between ".len());
        protected.push_str(head);
        match tail.find(" and ").filter(|&j| !tail[..j].contains(", ")) {
            Some(j) => {
                protected.push_str(&tail[..j]);
                protected.push_str(" & ");
                rest = &tail[j + " and ".len()..];
            }
            None => rest = tail,
        }
    }
    protected.push_str(rest);
    for sep in SEPARATORS {
        protected = protected.replace(sep, "|");
    }
    protected
        .split('|')
        .map(str::trim)
        .filter(|c| !c.is_empty())
        .map(str::to_string)
        .collect()
}

/// A script for an instruction whose clauses each name one library call (see the module
/// docs), written from the tuples without the LLM: `None` unless every clause is
/// understood and every noun phrase agrees exactly with the tuple of its position (so a
/// tuple the extractor got wrong falls back to the LLM path and its checks).
#[must_use]
pub fn simple_goto_script(
    instruction: &str,
    tuples: &[Tuple],
    map: Option<&IvlMap>,
) -> Option<String> {
    if tuples.is_empty() {
        return None;
    }
    let mut script = String::new();
    let mut next = 0usize;
    let mut last: Option<String> = None;
    // The variable for the next tuple, declared in `script`; regions only where allowed;
    // "it" is the object named last.
    let mut pick = |np: &str, script: &mut String, region_ok: bool| -> Option<String> {
        if np == "it" {
            return last.clone().filter(|v| !v.starts_with('"'));
        }
        // "the plant in the lounge": the object's tuple, then the room's.
        let (np, room) = match np.rsplit_once(" in the ") {
            Some((o, r)) if map.is_some() => (o, Some(r)),
            _ => (np, None),
        };
        let t = tuples.get(next)?;
        let mine = read_noun_phrase(np)?;
        if mine.object != t.object
            || mine.ordinal != t.ordinal
            || mine.colour != t.colour
            || !mine.same_order(t)
        {
            return None;
        }
        let room = match room {
            Some(r) => {
                let rt = tuples.get(next + 1)?;
                let said = read_noun_phrase(r)?;
                let is_room = map.is_some_and(|m| is_region_only(m, &rt.object));
                if !is_room
                    || said.object != rt.object
                    || rt.ordinal.is_some()
                    || rt.colour.is_some()
                {
                    return None;
                }
                Some(rt.object.replace(['"', '\\'], ""))
            }
            None => None,
        };
        next += 1 + usize::from(room.is_some());
        let name = t.object.replace(['"', '\\'], "");
        if map.is_some_and(|m| is_region_only(m, &name)) {
            if !region_ok || t.ordinal.is_some() || t.colour.is_some() {
                return None;
            }
            let v = format!("\"{name}\"");
            last = Some(v.clone());
            return Some(v);
        }
        // Named after the object's tuple (the room's comes after it).
        let v = format!("target_{}", next - usize::from(room.is_some()));
        let order = match t.object_order() {
            ObjectOrder::NearToFar => String::new(),
            o => format!(", \"{}\"", o.name()),
        };
        let (f, room_arg) = match &room {
            Some(r) => ("get_obj_in_region", format!(", \"{r}\"")),
            None => ("get_obj_attributes", String::new()),
        };
        script.push_str(&format!(
            "let {v} = agent.{f}(\"{name}\"{room_arg}, {}, \"{}\"{order});\n",
            t.ordinal.unwrap_or(0),
            t.colour.as_deref().unwrap_or("")
        ));
        last = Some(v.clone());
        Some(v)
    };
    for (i, clause) in clauses(instruction).iter().enumerate() {
        let mut c = clause.as_str();
        for lead in [
            "please ", "then ", "and ", "next ", "finally ", "now ", "first ",
        ] {
            c = c.strip_prefix(lead).unwrap_or(c);
        }
        match classify(c, i > 0)? {
            Action::GoTo(np) => {
                let v = pick(np, &mut script, true)?;
                script.push_str(&format!("agent.move_to_object({v});\n"));
            }
            Action::Side(f, np) => {
                let v = pick(np, &mut script, false)?;
                script.push_str(&format!("agent.{f}({v});\n"));
            }
            Action::Between(a, b) => {
                let va = pick(a, &mut script, false)?;
                let vb = pick(b, &mut script, false)?;
                script.push_str(&format!("agent.move_in_between({va}, {vb});\n"));
            }
            Action::Face(np) => {
                let v = pick(np, &mut script, false)?;
                script.push_str(&format!("agent.face({v});\n"));
            }
        }
    }
    (next == tuples.len()).then_some(script)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clauses_keep_the_and_of_between() {
        assert_eq!(
            clauses("Stop on the left of the black sofa, then go in between the black table and the red sofa and then face the tv."),
            vec![
                "stop on the left of the black sofa",
                "go in between the black table & the red sofa",
                "face the tv"
            ]
        );
    }

    #[test]
    fn each_clause_names_its_call() {
        assert_eq!(
            classify("stop on the left of the black sofa", false),
            Some(Action::Side("move_to_left", "the black sofa"))
        );
        assert_eq!(
            classify("go to the north side of the nearest white table", false),
            Some(Action::Side("move_north", "the nearest white table"))
        );
        assert_eq!(
            classify("to the west side of the grey sofa", true),
            Some(Action::Side("move_west", "the grey sofa"))
        );
        assert_eq!(
            classify("go south of the bed", false),
            Some(Action::Side("move_south", "the bed"))
        );
        assert_eq!(
            classify("the south side of the white fridge", true),
            Some(Action::Side("move_south", "the white fridge"))
        );
        assert_eq!(
            classify("go between the fridge & the counter", false),
            Some(Action::Between("the fridge", "the counter"))
        );
        assert_eq!(
            classify("turn to face the tv", false),
            Some(Action::Face("the tv"))
        );
        assert_eq!(classify("the lamp", true), Some(Action::GoTo("the lamp")));
        assert_eq!(classify("the lamp", false), None);
        // A side of nothing is not a side clause.
        assert_eq!(
            classify("go to the left", false),
            Some(Action::GoTo("the left"))
        );
    }
}
