//! The grammar of the one-call answer, built per request from planner_dsl's registry and
//! the map's vocabulary.
//!
//! The objects line is free in its words (they are the person's own: "couch", "piano"),
//! held to the paper's tuple shape; the plan may call only the typed plan's step
//! functions ([`planner_dsl::typed::STEP_FUNCTIONS`], each with its registry signature)
//! and pick objects only by the names, colours and regions this map holds, ordinals as
//! integers, orders from map_core. A local model under it cannot call anything outside
//! the library or name anything the map lacks; what it cannot say (a colour the map
//! has no object in) the checks find in the objects line and ask about.

use map_core::matcher::{synonyms, COLOUR_WORDS};
use map_core::{IvlMap, ObjectOrder};
use planner_dsl::typed::{PICK_FUNCTION, STEP_FUNCTIONS};
use planner_dsl::ParamType;

/// What a map lets a plan name.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Vocabulary {
    /// Object names: the map's labels and their synonyms.
    pub names: Vec<String>,
    /// Colours some instance has.
    pub colours: Vec<String>,
    /// Region (room) names.
    pub regions: Vec<String>,
    /// Object ids the plan may name with `get_instance` (what the conversation visited;
    /// empty outside a conversation).
    pub ids: Vec<u32>,
    /// The ordinals a selection may count (`None`: any from -99 to 99 but 0).
    pub ordinals: Option<Vec<i64>>,
    /// Offer only the orders that name no direction (nearest, farthest, size first).
    pub no_directions: bool,
    /// The colours a pick of each name may select on (`colour` and `not_colour`), as
    /// groups of names sharing one colour list (`None`: every name any of `colours`).
    /// A group with no colours picks that name without a colour key.
    pub colours_of: Option<Vec<(Vec<String>, Vec<String>)>>,
    /// The picks the plan may write, each held to a tuple of the answer's objects line
    /// (`None`: any pick of the map's names). Overrides `colours_of`.
    pub held: Option<Vec<HeldPick>>,
}

/// A pick held to one tuple of the objects line the model wrote: the names the tuple's
/// object goes by on the map, and the selection keys the tuple says (alternative
/// spellings of one selection: "ordinal: -2" and "ordinal: 2, order: \"far_to_near\""),
/// which the pick must write first; only the keys no tuple holds (`not_colour`,
/// `region`, `near`) may follow them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HeldPick {
    /// The names the pick may use (a label and its synonyms).
    pub names: Vec<String>,
    /// Alternative texts of the tuple's keys (`ordinal: 2, colour: "brown"`); an empty
    /// text when the tuple says none.
    pub keys: Vec<String>,
}

/// The names a label goes by in a plan: its synonyms, then the label (blank ones left out).
pub(crate) fn label_names(label: String) -> Vec<String> {
    let mut names: Vec<String> = synonyms(&label).into_iter().map(str::to_string).collect();
    names.push(label);
    names.retain(|n| !n.trim().is_empty());
    names
}

impl Vocabulary {
    /// The vocabulary of `map`, sorted and without duplicates.
    #[must_use]
    pub fn for_map(map: &IvlMap) -> Self {
        let mut names = Vec::new();
        for (label, _) in map.label_counts() {
            names.extend(label_names(label));
        }
        let mut colours: Vec<String> = map
            .instances
            .iter()
            .filter_map(|i| i.colour.clone())
            .collect();
        let mut regions: Vec<String> = map.regions.iter().map(|r| r.name.clone()).collect();
        for v in [&mut names, &mut colours, &mut regions] {
            v.retain(|s| !s.trim().is_empty());
            v.sort();
            v.dedup();
        }
        Self {
            names,
            colours,
            regions,
            ids: Vec::new(),
            ordinals: None,
            no_directions: false,
            colours_of: None,
            held: None,
        }
    }
}

/// A GBNF string literal of `s`.
fn q(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// Alternatives of literals, longest first (so that none is cut short by a prefix).
fn alt<S: AsRef<str>>(words: &[S], quoted: bool) -> String {
    let mut w: Vec<&str> = words.iter().map(AsRef::as_ref).collect();
    w.sort_by_key(|s| std::cmp::Reverse(s.len()));
    w.dedup();
    w.iter()
        .map(|s| if quoted { q(&format!("\"{s}\"")) } else { q(s) })
        .collect::<Vec<_>>()
        .join(" | ")
}

fn orders(with_default: bool) -> Vec<&'static str> {
    ObjectOrder::ALL
        .iter()
        .map(|(_, n)| *n)
        .filter(|n| with_default || *n != ObjectOrder::NearToFar.name())
        .collect()
}

/// The two grammar languages the answer's grammar is written in: GBNF for llama.cpp's
/// grammar sampler (and servers that take it), Lark for llguidance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Dialect {
    Gbnf,
    Lark,
}

/// A grammar being written in one dialect: rules, and character-level patterns (GBNF
/// character classes, Lark regular expressions).
struct Writer {
    d: Dialect,
    out: String,
}

impl Writer {
    fn new(d: Dialect) -> Self {
        Self {
            d,
            out: String::new(),
        }
    }

    /// `name ::= body` (GBNF) or `name: body` (Lark); the start rule is `root` or `start`.
    fn rule(&mut self, name: &str, body: &str) {
        let name = match (self.d, name) {
            (Dialect::Lark, "root") => "start",
            _ => name,
        };
        let op = if self.d == Dialect::Gbnf {
            " ::= "
        } else {
            ": "
        };
        self.out.push_str(name);
        self.out.push_str(op);
        self.out.push_str(body);
        self.out.push('\n');
    }

    /// A character-level pattern: `gbnf` as GBNF, `regex` as a Lark regular expression.
    fn pattern(&self, gbnf: &str, regex: &str) -> String {
        match self.d {
            Dialect::Gbnf => gbnf.to_string(),
            Dialect::Lark => format!("/{regex}/"),
        }
    }
}

/// The objects line's rules (`objects` and what it uses).
fn objects_rules(w: &mut Writer, map_colours: &[String]) {
    let mut colours: Vec<String> = COLOUR_WORDS.iter().map(|s| (*s).to_string()).collect();
    colours.extend(map_colours.iter().cloned());
    // Empty when the person names no object ("turn around", "go back to where we
    // started").
    w.rule("objects", "\"objects: [\" (tuple (\", \" tuple)*)? \"]\"");
    w.rule(
        "tuple",
        "\"(\" tword \", \" tordinal \", \" tcolour (\", \" torder)? \")\"",
    );
    let tword = w.pattern(
        "[a-z] [a-z-]{0,15} (\" \" [a-z] [a-z-]{0,15}){0,2}",
        "[a-z][a-z\\-]{0,15}( [a-z][a-z\\-]{0,15}){0,2}",
    );
    w.rule("tword", &tword);
    let n = w.pattern("[1-9] [0-9]?", "[1-9][0-9]?");
    w.rule("tordinal", &format!("\"None\" | \"last\" | {n}"));
    w.rule("tcolour", &format!("\"None\" | {}", alt(&colours, false)));
    w.rule("torder", &alt(&orders(false), false));
}

fn objects_only(d: Dialect) -> String {
    let mut w = Writer::new(d);
    // The line ends as in the whole answer, with a newline (the request's stop string):
    // measured, without it Qwen 1.5B did not end the line (its "]\n" token is masked)
    // and listed made-up tuples to the token limit (held-out extraction: 2/48 exact).
    w.rule("root", "objects \"\\n\"");
    objects_rules(&mut w, &[]);
    w.out
}

/// GBNF for the objects line alone (extraction without a map); rule `root`.
#[must_use]
pub fn objects_grammar() -> String {
    objects_only(Dialect::Gbnf)
}

/// [`objects_grammar`] in Lark (llguidance); rule `start`.
#[must_use]
pub fn objects_lark() -> String {
    objects_only(Dialect::Lark)
}

/// The rule that writes an argument of type `ty`.
fn arg_rule(ty: ParamType) -> &'static str {
    match ty {
        ParamType::Object => "obj",
        ParamType::Name => "pname",
        ParamType::Selection => "selmap",
        ParamType::Position => "pos",
        ParamType::Distance | ParamType::Angle => "num",
        ParamType::Text => "text",
        ParamType::Ordinal => "int",
        ParamType::Id => "inst",
        ParamType::Colour => "qcolour",
        ParamType::Order => "qorder",
    }
}

/// The call rule of a registered function: `"name(" args ")"`, optional parameters
/// optional. `None` when the registry does not hold it.
fn call_rule(name: &str) -> Option<String> {
    let f = planner_dsl::lookup(name)?;
    let mut r = q(&format!("{name}("));
    let mut first = true;
    let mut open = 0;
    for p in f.params {
        let sep = if first { "" } else { ", " };
        first = false;
        let rule = arg_rule(p.ty);
        if p.optional {
            r.push_str(" (");
            open += 1;
        }
        if !sep.is_empty() {
            r.push(' ');
            r.push_str(&q(sep));
        }
        r.push(' ');
        r.push_str(rule);
    }
    for _ in 0..open {
        r.push_str(")?");
    }
    r.push(' ');
    r.push_str(&q(")"));
    Some(r)
}

/// The selection map `selmap{suffix}`: its keys in a fixed order, each optional, at
/// least one; colours from the rule `colour` (none: no colour keys). Its key rules are
/// `sel0`, `sel1`... without a suffix (the names recorded cassettes hold) and
/// `sel{suffix}_0`... with one.
fn selection_rules(w: &mut Writer, suffix: &str, colour: Option<&str>, vocab: &Vocabulary) {
    let mut keys = vec!["\"ordinal: \" int".to_string()];
    if let Some(c) = colour {
        keys.push(format!("\"colour: \" {c}"));
        keys.push(format!("\"not_colour: \" {c}"));
    }
    keys.push("\"order: \" qorder".into());
    if !vocab.regions.is_empty() {
        keys.push("\"region: \" qregion".into());
    }
    keys.push("\"near: \" obj".into());
    let sel = |i: usize| {
        if suffix.is_empty() {
            format!("sel{i}")
        } else {
            format!("sel{suffix}_{i}")
        }
    };
    w.rule(
        &format!("selmap{suffix}"),
        &format!("\"#{{\" {} \"}}\"", sel(0)),
    );
    let n = keys.len();
    for (i, k) in keys.iter().enumerate() {
        if i + 1 == n {
            w.rule(&sel(i), k);
        } else {
            w.rule(
                &sel(i),
                &format!("{k} (\", \" {next})? | {next}", next = sel(i + 1)),
            );
        }
    }
}

/// GBNF for the whole answer: the objects line, `plan:`, then one typed step per line,
/// with names, colours and regions from `vocab`. Rule `root`.
///
/// ```
/// use agent::v2::grammar::{answer_grammar, Vocabulary};
/// let v = Vocabulary { names: vec!["chair".into()], colours: vec!["red".into()], ..Vocabulary::default() };
/// let g = answer_grammar(&v);
/// assert!(g.starts_with("root ::="));
/// assert!(g.contains("\"move_to_object(\""));
/// assert!(!g.contains("region: "), "no regions on this map");
/// ```
#[must_use]
pub fn answer_grammar(vocab: &Vocabulary) -> String {
    answer(vocab, Dialect::Gbnf)
}

/// [`answer_grammar`] in Lark, for llguidance (the same language); rule `start`.
#[must_use]
pub fn answer_lark(vocab: &Vocabulary) -> String {
    answer(vocab, Dialect::Lark)
}

/// GBNF for the answer's first part alone: the objects line and its newline (with the
/// map's colours, as in [`answer_grammar`]). Rule `root`.
#[must_use]
pub fn objects_line_grammar(vocab: &Vocabulary) -> String {
    answer_part(vocab, Dialect::Gbnf, Part::Objects)
}

/// [`objects_line_grammar`] in Lark; rule `start`.
#[must_use]
pub fn objects_line_lark(vocab: &Vocabulary) -> String {
    answer_part(vocab, Dialect::Lark, Part::Objects)
}

/// GBNF for the answer's second part alone: the plan's statements, after `plan:` (picks
/// held to `vocab.held` when it is given). Rule `root`.
#[must_use]
pub fn plan_grammar(vocab: &Vocabulary) -> String {
    answer_part(vocab, Dialect::Gbnf, Part::Plan)
}

/// [`plan_grammar`] in Lark; rule `start`.
#[must_use]
pub fn plan_lark(vocab: &Vocabulary) -> String {
    answer_part(vocab, Dialect::Lark, Part::Plan)
}

/// Which part of the answer a grammar holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Part {
    Whole,
    Objects,
    Plan,
}

fn answer(vocab: &Vocabulary, d: Dialect) -> String {
    answer_part(vocab, d, Part::Whole)
}

/// The rules of the held picks (`held0`...) and the keys that may follow a tuple's
/// (`xsel0`...); returns the alternatives of the rule `pick`.
fn held_rules(w: &mut Writer, held: &[HeldPick], vocab: &Vocabulary) -> Vec<String> {
    let get = q(&format!("{PICK_FUNCTION}("));
    let mut extra = Vec::new();
    if !vocab.colours.is_empty() {
        extra.push("\"not_colour: \" qcolour".to_string());
    }
    if !vocab.regions.is_empty() {
        extra.push("\"region: \" qregion".into());
    }
    extra.push("\"near: \" obj".into());
    let n = extra.len();
    for (i, k) in extra.iter().enumerate() {
        if i + 1 == n {
            w.rule(&format!("xsel{i}"), k);
        } else {
            w.rule(
                &format!("xsel{i}"),
                &format!("{k} (\", \" xsel{j})? | xsel{j}", j = i + 1),
            );
        }
    }
    let mut picks = Vec::new();
    let mut seen: Vec<&HeldPick> = Vec::new();
    for h in held {
        if h.names.is_empty() || h.keys.is_empty() || seen.contains(&h) {
            continue;
        }
        seen.push(h);
        let i = picks.len();
        let said: Vec<&String> = h.keys.iter().filter(|k| !k.is_empty()).collect();
        let mut body = Vec::new();
        if h.keys.iter().any(String::is_empty) {
            // Nothing said about it: the bare pick, or one with the other keys only.
            body.push("(\", #{\" xsel0 \"}\")?".to_string());
        }
        if !said.is_empty() {
            body.push(format!(
                "\", #{{\" ({}) (\", \" xsel0)? \"}}\"",
                alt(&said, false)
            ));
        }
        w.rule(
            &format!("held{i}"),
            &format!(
                "{get} ({}) ({}) \")\"",
                alt(&h.names, true),
                body.join(" | ")
            ),
        );
        picks.push(format!("held{i}"));
    }
    picks
}

fn answer_part(vocab: &Vocabulary, d: Dialect, part: Part) -> String {
    let mut w = Writer::new(d);
    // Statements are separated (not ended) by newlines, as in the worked examples, so
    // that after the last `;` the model can end its turn as it saw there; at most 16
    // statements, so that a weak model that repeats itself stops.
    match part {
        Part::Whole => {
            w.rule("root", "objects \"\\nplan:\\n\" stmt (\"\\n\" stmt){0,15}");
            objects_rules(&mut w, &vocab.colours);
        }
        Part::Objects => {
            w.rule("root", "objects \"\\n\"");
            objects_rules(&mut w, &vocab.colours);
            return w.out;
        }
        Part::Plan => w.rule("root", "stmt (\"\\n\" stmt){0,15}"),
    }
    let steps: Vec<String> = STEP_FUNCTIONS.iter().filter_map(|n| call_rule(n)).collect();
    w.rule("stmt", "letstmt | step");
    w.rule("letstmt", "\"let \" var \" = \" pick \";\"");
    w.rule("step", &format!("({}) \";\"", steps.join(" | ")));
    let var = w.pattern("[a-z] [a-z0-9_]{0,15}", "[a-z][a-z0-9_]{0,15}");
    w.rule("var", &var);
    let get = q(&format!("{PICK_FUNCTION}("));
    let held = match &vocab.held {
        Some(h) => held_rules(&mut w, h, vocab),
        None => Vec::new(),
    };
    match &vocab.colours_of {
        _ if !held.is_empty() => w.rule("pick", &held.join(" | ")),
        // One pick rule per group of names, each with its own colour list.
        Some(groups) if !groups.is_empty() => {
            let mut picks = Vec::new();
            for (g, (names, _)) in groups.iter().enumerate() {
                w.rule(
                    &format!("pick{g}"),
                    &format!("{get} ({}) (\", \" selmap{g})? \")\"", alt(names, true)),
                );
                picks.push(format!("pick{g}"));
            }
            w.rule("pick", &picks.join(" | "));
        }
        _ => w.rule("pick", &format!("{get} pname (\", \" selmap)? \")\"")),
    }
    if vocab.ids.is_empty() {
        w.rule("obj", "pick | qname | var");
    } else {
        let ids: Vec<String> = vocab.ids.iter().map(u32::to_string).collect();
        w.rule("obj", "pick | qname | var | inst");
        w.rule(
            "inst",
            &format!("\"get_instance(\" ({}) \")\"", alt(&ids, false)),
        );
    }
    // Objects are picked by their names; a bare name may also be a region (a room).
    if vocab.names.is_empty() {
        let free = w.pattern(
            "\"\\\"\" [a-z] [a-z ]{0,24} \"\\\"\"",
            "\"[a-z][a-z ]{0,24}\"",
        );
        w.rule("pname", &free);
    } else {
        w.rule("pname", &alt(&vocab.names, true));
    }
    if vocab.regions.is_empty() {
        w.rule("qname", "pname");
    } else {
        w.rule("qname", &format!("pname | {}", alt(&vocab.regions, true)));
    }
    if !vocab.colours.is_empty() {
        w.rule("qcolour", &alt(&vocab.colours, true));
    }
    if !vocab.regions.is_empty() {
        w.rule("qregion", &alt(&vocab.regions, true));
    }
    // The shared selection map: `move_between_the_two` selects with it whatever the
    // picks use.
    selection_rules(
        &mut w,
        "",
        (!vocab.colours.is_empty()).then_some("qcolour"),
        vocab,
    );
    for (g, (_, colours)) in vocab.colours_of.iter().flatten().enumerate() {
        let rule = (!colours.is_empty()).then(|| {
            w.rule(&format!("qcolour{g}"), &alt(colours, true));
            format!("qcolour{g}")
        });
        selection_rules(&mut w, &g.to_string(), rule.as_deref(), vocab);
    }
    let offered: Vec<&str> = orders(true)
        .into_iter()
        .filter(|o| {
            !vocab.no_directions || ObjectOrder::parse(o).is_ok_and(|o| !o.is_directional())
        })
        .collect();
    w.rule("qorder", &alt(&offered, true));
    match vocab.ordinals.as_deref() {
        Some(ks) if !ks.is_empty() => {
            let ks: Vec<String> = ks.iter().map(i64::to_string).collect();
            w.rule("int", &alt(&ks, false));
        }
        _ => {
            let int = w.pattern("\"-\"? [1-9] [0-9]?", "-?[1-9][0-9]?");
            w.rule("int", &int);
        }
    }
    let num = w.pattern(
        "\"-\"? [0-9] [0-9]{0,2} (\".\" [0-9] [0-9]?)?",
        "-?[0-9]{1,3}(\\.[0-9]{1,2})?",
    );
    w.rule("num", &num);
    w.rule("pos", "\"[\" num \", \" num \"]\"");
    let text = w.pattern(
        "\"\\\"\" [^\"\\\\\\n]{0,80} \"\\\"\"",
        "\"[^\"\\\\\\n]{0,80}\"",
    );
    w.rule("text", &text);
    w.out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vocab() -> Vocabulary {
        Vocabulary {
            names: vec!["chair".into(), "sofa".into(), "couch".into()],
            colours: vec!["red".into(), "black".into()],
            regions: vec!["kitchen".into()],
            ..Vocabulary::default()
        }
    }

    /// The rules a GBNF grammar uses but does not define (words outside its literals).
    fn undefined_rules(g: &str) -> Vec<String> {
        let mut defined = Vec::new();
        let mut used = Vec::new();
        for line in g.lines() {
            let Some((name, body)) = line.split_once(" ::= ") else {
                continue;
            };
            defined.push(name.to_string());
            let mut in_str = false;
            let mut escaped = false;
            let mut in_class = false;
            let mut word = String::new();
            for ch in body.chars().chain(std::iter::once(' ')) {
                if in_str {
                    match (escaped, ch) {
                        (true, _) => escaped = false,
                        (false, '\\') => escaped = true,
                        (false, '"') => in_str = false,
                        _ => {}
                    }
                    continue;
                }
                if in_class {
                    in_class = ch != ']';
                    continue;
                }
                if ch.is_ascii_alphanumeric() || ch == '_' {
                    word.push(ch);
                    continue;
                }
                if !word.is_empty() && word.starts_with(|c: char| c.is_ascii_lowercase()) {
                    used.push(std::mem::take(&mut word));
                }
                word.clear();
                in_str = ch == '"';
                in_class = ch == '[';
            }
        }
        used.retain(|u| !defined.contains(u));
        used.sort();
        used.dedup();
        used
    }

    #[test]
    fn every_rule_a_grammar_uses_is_defined() {
        let mut said = vocab();
        said.colours_of = Some(vec![
            (vec!["chair".into()], vec!["red".into()]),
            (vec!["sofa".into(), "couch".into()], vec![]),
        ]);
        let mut held = vocab();
        held.held = Some(vec![HeldPick {
            names: vec!["chair".into()],
            keys: vec!["ordinal: 2".into()],
        }]);
        for (what, g) in [
            ("default", answer_grammar(&vocab())),
            ("said colours", answer_grammar(&said)),
            ("objects line", objects_line_grammar(&vocab())),
            ("held plan", plan_grammar(&held)),
            ("free plan", plan_grammar(&vocab())),
        ] {
            assert_eq!(undefined_rules(&g), Vec::<String>::new(), "{what}:\n{g}");
        }
    }

    #[test]
    fn held_picks_write_their_tuple_first_and_only_free_keys_after() {
        let mut v = vocab();
        v.held = Some(vec![
            HeldPick {
                names: vec!["chair".into()],
                keys: vec!["ordinal: 2, colour: \"red\"".into()],
            },
            HeldPick {
                names: vec!["sofa".into(), "couch".into()],
                keys: vec![String::new()],
            },
            // The same tuple twice (two mentions) is one rule.
            HeldPick {
                names: vec!["chair".into()],
                keys: vec!["ordinal: 2, colour: \"red\"".into()],
            },
        ]);
        let g = plan_grammar(&v);
        assert!(g.starts_with("root ::= stmt "), "{g}");
        assert!(!g.contains("objects ::="), "{g}");
        assert!(g.contains("\npick ::= held0 | held1\n"), "{g}");
        assert!(
            g.contains(
                "held0 ::= \"get_obj(\" (\"\\\"chair\\\"\") (\", #{\" (\"ordinal: 2, colour: \\\"red\\\"\") (\", \" xsel0)? \"}\") \")\"\n"
            ),
            "{g}"
        );
        // Nothing said of the sofa: the bare pick, or the free keys only.
        assert!(
            g.contains("held1 ::= \"get_obj(\" (\"\\\"couch\\\"\" | \"\\\"sofa\\\"\") ((\", #{\" xsel0 \"}\")?) \")\"\n"),
            "{g}"
        );
        assert!(
            g.contains("xsel0 ::= \"not_colour: \" qcolour (\", \" xsel1)? | xsel1\n"),
            "{g}"
        );
        assert!(g.contains("xsel2 ::= \"near: \" obj\n"), "{g}");
        // The objects line alone ends with its newline.
        assert!(objects_line_grammar(&v).starts_with("root ::= objects \"\\n\"\n"));
        assert!(objects_line_lark(&v).starts_with("start: objects \"\\n\"\n"));
        assert!(plan_lark(&v).starts_with("start: stmt "));
    }

    #[test]
    fn every_step_function_of_the_registry_is_offered_and_nothing_else() {
        let g = answer_grammar(&vocab());
        for f in STEP_FUNCTIONS {
            assert!(g.contains(&format!("\"{f}(\"")), "{f}");
        }
        for f in planner_dsl::registry() {
            let offered = g.contains(&format!("\"{}(\"", f.name));
            assert_eq!(
                offered,
                STEP_FUNCTIONS.contains(&f.name) || f.name == PICK_FUNCTION,
                "{}",
                f.name
            );
        }
        // In a conversation, the objects it visited can be named by id, and only those.
        let mut v = vocab();
        v.ids = vec![17, 2];
        let g = answer_grammar(&v);
        assert!(
            g.contains("inst ::= \"get_instance(\" (\"17\" | \"2\") \")\""),
            "{g}"
        );
        assert!(!g.contains("eval"));
    }

    #[test]
    fn names_colours_and_regions_come_from_the_map() {
        let g = answer_grammar(&vocab());
        for lit in [
            "\"\\\"chair\\\"\"",
            "\"\\\"couch\\\"\"",
            "\"\\\"kitchen\\\"\"",
            "\"\\\"red\\\"\"",
        ] {
            assert!(g.contains(lit), "{lit} in\n{g}");
        }
        assert!(!g.contains("\"\\\"yellow\\\"\""), "a colour the map lacks");
        // Every rule used is defined.
        for rule in [
            "objects", "tuple", "stmt", "step", "pick", "obj", "qname", "pname", "selmap", "sel0",
            "qcolour", "qregion", "qorder", "int", "num", "pos", "text", "var",
        ] {
            assert!(g.contains(&format!("\n{rule} ::=")), "{rule}");
        }
    }

    #[test]
    fn the_lark_form_has_the_same_rules() {
        let g = answer_lark(&vocab());
        assert!(g.starts_with("start: objects"), "{g}");
        assert!(!g.contains("::="), "{g}");
        for rule in [
            "objects", "tuple", "stmt", "step", "pick", "obj", "qname", "pname", "selmap", "sel0",
            "qcolour", "qregion", "qorder", "int", "num", "pos", "text", "var",
        ] {
            assert!(g.contains(&format!("\n{rule}: ")), "{rule}");
        }
        // Character classes are regular expressions in Lark.
        assert!(g.contains("int: /-?[1-9][0-9]?/"), "{g}");
        assert!(objects_lark().starts_with("start: objects \"\\n\"\n"));
    }

    #[test]
    fn a_map_without_colours_or_regions_leaves_their_keys_out() {
        let g = answer_grammar(&Vocabulary {
            names: vec!["chair".into()],
            ..Vocabulary::default()
        });
        assert!(!g.contains("qcolour"), "{g}");
        assert!(!g.contains("qregion"), "{g}");
    }

    #[test]
    fn vocabulary_of_a_scene() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../examples/scenes/flat-a.scene.json"
        );
        let map = IvlMap::from_scene(&map_core::scene::Scene::from_path(path).unwrap());
        let v = Vocabulary::for_map(&map);
        for n in ["sofa", "couch", "refrigerator", "fridge"] {
            assert!(v.names.iter().any(|x| x == n), "{n}: {:?}", v.names);
        }
        assert!(v.colours.iter().any(|c| c == "red"), "{:?}", v.colours);
        assert!(
            v.regions.iter().any(|r| r == "living room"),
            "{:?}",
            v.regions
        );
        let mut sorted = v.names.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted, v.names);
    }
}
