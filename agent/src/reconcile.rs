//! Step 1's answer reconciled with the instruction's own words.
//!
//! A small model gets the structure of an instruction right far more often than its
//! details: measured on the extraction suite with the default 1.5B model, most misses
//! were a field the instruction does not support ("the white bed" read as the 1st white
//! bed, "the nearest lamp" given an order), a modifier on the wrong noun ("the chair next
//! to the yellow table" as a yellow chair), a mention left out ("in the dining room"), a
//! mention out of order, or a tuple for words that name no object ("turn around",
//! "right"). Each of these can be decided from the words alone, so this module decides
//! them instead of asking the model again:
//!
//! 1. the mentions of the instruction are found: the names in the model's tuples, and
//!    the names of a [`Lexicon`] (the map's categories and regions when there is a map,
//!    else a built-in list of indoor objects and rooms);
//! 2. each tuple is matched to a mention of the same name (synonyms count: "couch" is
//!    "sofa"); tuples that match nothing and name nothing of the instruction are dropped;
//!    mentions no tuple matched get a tuple;
//! 3. each tuple's ordinal, colour and order are set from the words of its own noun
//!    phrase: the modifiers after its determiner ("the *second yellow* table"), a counting
//!    phrase after it ("... *from the west*"), a relative clause ("that is red").
//!
//! The model's names are kept; only what the words decide is changed, and each change is
//! reported as a [`TupleFix`].

use crate::tuples::{normalise_colour, normalise_order, parse_ordinal_with_order, Tuple};
use crate::words::is_word_char;

/// The names a mention may have when no tuple names it: object categories and regions.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Lexicon {
    objects: Vec<String>,
    regions: Vec<String>,
}

/// Indoor object categories of Matterport3D's 40-category set (VLMaps' `mp3dcat`, minus
/// its structural and catch-all classes: wall, floor, ceiling, objects, misc, ...), with
/// common household objects besides.
const BUILTIN_OBJECTS: &[&str] = &[
    "chair",
    "door",
    "table",
    "picture",
    "cabinet",
    "cushion",
    "window",
    "sofa",
    "bed",
    "curtain",
    "chest of drawers",
    "plant",
    "sink",
    "stairs",
    "toilet",
    "stool",
    "towel",
    "mirror",
    "tv",
    "shower",
    "bathtub",
    "counter",
    "fireplace",
    "shelf",
    "desk",
    "armchair",
    "bench",
    "lamp",
    "fridge",
    "oven",
    "stove",
    "microwave",
    "dishwasher",
    "washing machine",
    "wardrobe",
    "dresser",
    "nightstand",
    "bedside table",
    "coffee table",
    "trash can",
    "bin",
    "rug",
    "clock",
    "computer",
    "monitor",
    "printer",
    "whiteboard",
    "piano",
    "bookshelf",
    "locker",
    "box",
];

/// Room names of Matterport3D's region categories, with the office-building rooms of
/// the example scenes. Any "<word> room" is a region too.
const BUILTIN_REGIONS: &[&str] = &[
    "kitchen",
    "bathroom",
    "bedroom",
    "living room",
    "dining room",
    "hallway",
    "corridor",
    "lounge",
    "office",
    "open office",
    "study",
    "closet",
    "garage",
    "laundry",
    "library",
    "lobby",
    "entryway",
    "porch",
    "balcony",
    "toilet room",
    "meeting room",
    "reception",
];

impl Lexicon {
    /// The built-in names (for instructions without a map).
    #[must_use]
    pub fn builtin() -> Self {
        Self {
            objects: BUILTIN_OBJECTS.iter().map(|s| (*s).to_string()).collect(),
            regions: BUILTIN_REGIONS.iter().map(|s| (*s).to_string()).collect(),
        }
    }

    /// The names on `map`: its categories and region names (what an instruction about
    /// this map can refer to; anything else the model names is kept only if the
    /// instruction says it).
    #[must_use]
    pub fn for_map(map: &map_core::IvlMap) -> Self {
        let mut objects: Vec<String> = map
            .label_counts()
            .into_iter()
            .map(|(l, _)| map_core::matcher::normalise(&l))
            .collect();
        objects.dedup();
        Self {
            objects,
            regions: map
                .regions
                .iter()
                .map(|r| map_core::matcher::normalise(&r.name))
                .collect(),
        }
    }
}

/// One change made to the model's tuples, for logs and the chat's display.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TupleFix {
    /// The tuple before, in paper form (empty when added).
    pub before: String,
    /// The tuple after (empty when dropped).
    pub after: String,
    /// Why, in words.
    pub why: String,
}

impl std::fmt::Display for TupleFix {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (self.before.is_empty(), self.after.is_empty()) {
            (true, _) => write!(f, "added {} ({})", self.after, self.why),
            (_, true) => write!(f, "dropped {} ({})", self.before, self.why),
            _ => write!(f, "{} -> {} ({})", self.before, self.after, self.why),
        }
    }
}

/// A token of the instruction: a lower-case word, or a clause boundary.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Tok {
    Word(String),
    Boundary,
}

impl Tok {
    fn word(&self) -> &str {
        match self {
            Tok::Word(w) => w,
            Tok::Boundary => "",
        }
    }
}

fn tokens(instruction: &str) -> Vec<Tok> {
    let mut out = Vec::new();
    let mut cur = String::new();
    for c in instruction.to_lowercase().chars() {
        if is_word_char(c) {
            cur.push(c);
            continue;
        }
        if !cur.is_empty() {
            out.push(Tok::Word(std::mem::take(&mut cur)));
        }
        if matches!(c, ',' | '.' | ';' | ':' | '!' | '?') {
            out.push(Tok::Boundary);
        }
    }
    if !cur.is_empty() {
        out.push(Tok::Word(cur));
    }
    out
}

/// Words that end one noun phrase's clause ("the red chair *and* the table").
fn is_boundary(t: &Tok) -> bool {
    matches!(t, Tok::Boundary) || matches!(t.word(), "and" | "then" | "or")
}

fn is_determiner(w: &str) -> bool {
    matches!(
        w,
        "the" | "a" | "an" | "this" | "these" | "those" | "its" | "my" | "your"
    )
}

/// Words a model sometimes lists that name no object: directions, sides, motions, a
/// colour on its own ("red" of "the red chair nearest to you").
fn names_nothing(object: &str) -> bool {
    map_core::matcher::is_colour_word(object)
        || object.split_whitespace().all(|w| {
            matches!(
                w,
                "left"
                    | "right"
                    | "front"
                    | "back"
                    | "behind"
                    | "side"
                    | "turn"
                    | "around"
                    | "forward"
                    | "backward"
                    | "north"
                    | "south"
                    | "east"
                    | "west"
                    | "meter"
                    | "metre"
                    | "degree"
                    | "it"
                    | "them"
                    | "you"
                    | "me"
                    | "here"
                    | "there"
                    | "way"
                    | "direction"
            ) || w.chars().all(|c| c.is_ascii_digit())
        })
}

/// A mention of a name in the instruction: token range and its canonical name.
#[derive(Debug, Clone)]
struct Mention {
    start: usize,
    end: usize,
    name: String,
    canon: String,
    /// "the two yellow tables": may stand for several tuples.
    plural: bool,
}

fn canon(s: &str) -> String {
    map_core::matcher::canonical(s)
}

/// The mentions of names in `toks`: the tuples' names first, then the lexicon's, longest
/// first; a name directly followed by another ("bathroom sink", "office chair") is a
/// modifier of the second, not a mention.
fn mentions(toks: &[Tok], tuples: &[Tuple], lex: &Lexicon) -> Vec<Mention> {
    let mut names: Vec<String> = tuples.iter().map(|t| t.object.clone()).collect();
    names.extend(lex.objects.iter().cloned());
    names.extend(lex.regions.iter().cloned());
    let canons: Vec<String> = names
        .iter()
        .filter(|n| !n.is_empty() && !names_nothing(n))
        .map(|n| canon(n))
        .collect();
    let mut found: Vec<Mention> = Vec::new();
    let mut i = 0;
    while i < toks.len() {
        if matches!(toks[i], Tok::Boundary) || is_determiner(toks[i].word()) {
            i += 1;
            continue;
        }
        let mut hit = None;
        for len in (1..=3).rev() {
            if i + len > toks.len() || toks[i..i + len].iter().any(|t| matches!(t, Tok::Boundary)) {
                continue;
            }
            let phrase: Vec<&str> = toks[i..i + len].iter().map(Tok::word).collect();
            let phrase = phrase.join(" ");
            let c = canon(&phrase);
            let room = len == 2 && matches!(toks[i + 1].word(), "room" | "rooms");
            let det_before = i > 0 && is_determiner(toks[i - 1].word());
            if canons.contains(&c) || (room && !is_determiner(toks[i].word()) && det_before) {
                let last = toks[i + len - 1].word();
                let plural = map_core::matcher::singular(last) != last && last != "stairs";
                hit = Some((len, map_core::matcher::singular(&phrase), c, plural));
                break;
            }
        }
        match hit {
            Some((len, name, c, plural)) => {
                found.push(Mention {
                    start: i,
                    end: i + len,
                    name,
                    canon: c,
                    plural,
                });
                i += len;
            }
            None => i += 1,
        }
    }
    // "the bathroom sink": the first name modifies the second.
    let mut out: Vec<Mention> = Vec::new();
    for (k, m) in found.iter().enumerate() {
        let modifies_next = found.get(k + 1).is_some_and(|n| n.start == m.end);
        if !modifies_next {
            out.push(m.clone());
        }
    }
    out
}

/// What the words around a mention say of its tuple.
#[derive(Debug, Default, PartialEq)]
struct Said {
    ordinal: Option<i64>,
    /// An ordinal marker was present ("second", "nearest", "last"), even if unspecified.
    ordinal_word: bool,
    order: Option<String>,
    colours: Vec<String>,
}

fn is_ordinal_word(w: &str) -> bool {
    if matches!(w, "last" | "final" | "farthest" | "furthest") {
        return true;
    }
    let digits = w
        .strip_suffix("st")
        .or_else(|| w.strip_suffix("nd"))
        .or_else(|| w.strip_suffix("rd"))
        .or_else(|| w.strip_suffix("th"));
    if digits.is_some_and(|d| !d.is_empty() && d.chars().all(|c| c.is_ascii_digit())) {
        return true;
    }
    matches!(
        w,
        "first"
            | "second"
            | "third"
            | "fourth"
            | "fifth"
            | "sixth"
            | "seventh"
            | "eighth"
            | "ninth"
            | "tenth"
            | "eleventh"
            | "twelfth"
    )
}

/// A counting phrase starting at `i` ("from the west", "from west to east", "counting
/// from the left"): its order.
fn order_at(words: &[&str], i: usize) -> Option<String> {
    if words.get(i) != Some(&"from") {
        return None;
    }
    // Longest first: "from west to east" before "from west".
    (2..=5)
        .rev()
        .filter(|len| i + len <= words.len())
        .find_map(|len| normalise_order(&words[i..i + len].join(" ")))
}

fn said_about(toks: &[Tok], mentions: &[Mention], k: usize) -> Said {
    let m = &mentions[k];
    let prev_end = if k == 0 { 0 } else { mentions[k - 1].end };
    // The noun phrase's own modifiers: after the last boundary or determiner before it.
    let mut from = prev_end;
    for (i, t) in toks.iter().enumerate().take(m.start).skip(prev_end) {
        if is_boundary(t) || is_determiner(t.word()) {
            from = i + 1;
        }
    }
    let mut said = Said::default();
    for t in &toks[from..m.start] {
        let w = t.word();
        if let Ok((k, order)) = parse_ordinal_with_order(w) {
            if order.is_some() {
                said.ordinal = k;
                said.order = order;
                said.ordinal_word = true;
                continue;
            }
            if is_ordinal_word(w) {
                said.ordinal = k;
                said.ordinal_word = true;
                continue;
            }
        }
        if matches!(w, "nearest" | "closest") {
            said.ordinal_word = true;
        } else if map_core::matcher::is_colour_word(w) {
            if let Some(c) = normalise_colour(w) {
                if !said.colours.contains(&c) {
                    said.colours.push(c);
                }
            }
        }
    }
    // After the noun, up to the clause's end or the next mention's phrase.
    let next_start = mentions.get(k + 1).map_or(toks.len(), |n| n.start);
    let mut post: Vec<&str> = Vec::new();
    for t in &toks[m.end..next_start] {
        if is_boundary(t) {
            break;
        }
        post.push(t.word());
    }
    // "the table second from the left"
    if let Some(w) = post.first() {
        if is_ordinal_word(w) && !said.ordinal_word {
            said.ordinal = parse_ordinal_with_order(w).ok().and_then(|(k, _)| k);
            said.ordinal_word = true;
        }
    }
    for i in 0..post.len() {
        if said.order.is_none() {
            if let Some(o) = order_at(&post, i) {
                said.order = Some(o);
            }
        }
        // "that is red", "which is red"
        if i + 2 < post.len()
            && matches!(post[i], "that" | "which")
            && matches!(post[i + 1], "is" | "looks")
            && map_core::matcher::is_colour_word(post[i + 2])
        {
            if let Some(c) = normalise_colour(post[i + 2]) {
                if !said.colours.contains(&c) {
                    said.colours.push(c);
                }
            }
        }
    }
    said
}

/// Edit distance, for names the instruction misspells ("frige").
fn close_spelling(a: &str, b: &str) -> bool {
    let allowed = match a.chars().count().min(b.chars().count()) {
        0..=3 => 0,
        4..=6 => 1,
        _ => 2,
    };
    strsim::levenshtein(a, b) <= allowed
}

/// Whether the instruction says `object` in some form (a word of it, or a word spelt
/// nearly like it).
fn instruction_says(toks: &[Tok], object: &str) -> bool {
    let c = canon(object);
    object.split_whitespace().any(|ow| {
        let ow = map_core::matcher::singular(ow);
        toks.iter().any(|t| {
            let w = map_core::matcher::singular(t.word());
            !w.is_empty() && (w == ow || canon(&w) == c || close_spelling(&w, &ow))
        })
    })
}

/// Whether the instruction refers to something named before ("go back to it", "that
/// one"): a tuple it does not name may then come from the conversation.
fn refers_back(toks: &[Tok]) -> bool {
    toks.iter()
        .any(|t| matches!(t.word(), "it" | "one" | "them" | "there" | "that" | "same"))
}

/// Step 1's tuples reconciled with `instruction` (see the module docs): the tuples in
/// order of mention, one per mention, each with the ordinal, colour and order its words
/// say, and the changes made.
#[must_use]
pub fn reconcile_tuples(
    instruction: &str,
    tuples: &[Tuple],
    lex: &Lexicon,
) -> (Vec<Tuple>, Vec<TupleFix>) {
    let toks = tokens(instruction);
    let ms = mentions(&toks, tuples, lex);
    let mut fixes = Vec::new();
    // Match each tuple to the first free mention of its name.
    let mut taken = vec![false; ms.len()];
    let mut placed: Vec<(usize, Tuple)> = Vec::new();
    let mut unplaced: Vec<Tuple> = Vec::new();
    for t in tuples {
        let c = canon(&t.object);
        let first_word = canon(t.object.split_whitespace().next().unwrap_or(""));
        let last_word = canon(t.object.split_whitespace().last().unwrap_or(""));
        let hit = (0..ms.len())
            .find(|&k| !taken[k] && ms[k].canon == c)
            .or_else(|| (0..ms.len()).find(|&k| ms[k].plural && ms[k].canon == c))
            .or_else(|| {
                // "open office" for "office", "table" for "coffee table"
                (0..ms.len()).find(|&k| {
                    !taken[k]
                        && (ms[k].canon == last_word
                            || canon(ms[k].name.split_whitespace().last().unwrap_or("")) == c
                            || ms[k].canon == first_word && t.object.contains(' '))
                })
            });
        match hit {
            Some(k) => {
                taken[k] = true;
                placed.push((k, t.clone()));
            }
            None => {
                let why = if t.object.is_empty() || names_nothing(&t.object) {
                    Some("names no object")
                } else if ms.iter().any(|m| m.canon == c) {
                    Some("the instruction mentions it fewer times")
                } else if !instruction_says(&toks, &t.object) && !refers_back(&toks) {
                    Some("the instruction does not mention it")
                } else {
                    None
                };
                match why {
                    Some(why) => fixes.push(TupleFix {
                        before: t.paper_form(),
                        after: String::new(),
                        why: why.to_string(),
                    }),
                    None => unplaced.push(t.clone()),
                }
            }
        }
    }
    // Mentions without a tuple get one.
    for (k, m) in ms.iter().enumerate() {
        if !taken[k] {
            let t = Tuple::new(&m.name, None, None);
            placed.push((k, t));
            fixes.push(TupleFix {
                before: String::new(),
                after: format!("({})", m.name),
                why: "mentioned but not listed".to_string(),
            });
        }
    }
    // Fields from the words of each mention.
    for (k, t) in &mut placed {
        let said = said_about(&toks, &ms, *k);
        let before = t.paper_form();
        let mut why: Vec<&str> = Vec::new();
        if ms[*k].plural {
            // "the two yellow tables": which of them is the model's reading.
        } else if said.ordinal_word {
            if t.ordinal != said.ordinal {
                t.ordinal = said.ordinal;
                why.push("ordinal");
            }
        } else if t.ordinal.is_some() {
            t.ordinal = None;
            why.push("no ordinal word");
        }
        let order = if ms[*k].plural {
            t.order.clone()
        } else if t.ordinal.is_some() {
            said.order.clone()
        } else {
            None
        };
        if t.order != order {
            t.order = order;
            why.push("order");
        }
        match said.colours.as_slice() {
            [] => {
                if t.colour.is_some() {
                    t.colour = None;
                    why.push("no colour word");
                }
            }
            [c] => {
                if t.colour.as_deref() != Some(c.as_str()) {
                    t.colour = Some(c.clone());
                    why.push("colour");
                }
            }
            // "the red and white chair": the model's pick stands if it is one of them.
            cs => {
                if !t.colour.as_ref().is_some_and(|c| cs.contains(c)) {
                    t.colour = Some(cs[0].clone());
                    why.push("colour");
                }
            }
        }
        let after = t.paper_form();
        if after != before && !before.is_empty() {
            fixes.push(TupleFix {
                before,
                after,
                why: format!("the words say: {}", why.join(", ")),
            });
        }
    }
    // In order of mention, unless a tuple could not be placed (then the model's order).
    if unplaced.is_empty() {
        let was: Vec<Tuple> = placed.iter().map(|(_, t)| t.clone()).collect();
        placed.sort_by_key(|(k, _)| *k);
        let now: Vec<Tuple> = placed.iter().map(|(_, t)| t.clone()).collect();
        if was != now && now.len() == tuples.len() {
            fixes.push(TupleFix {
                before: crate::tuples::tuples_paper_form(&was),
                after: crate::tuples::tuples_paper_form(&now),
                why: "order of mention".to_string(),
            });
        }
        return (now, fixes);
    }
    let mut out: Vec<Tuple> = placed.into_iter().map(|(_, t)| t).collect();
    out.extend(unplaced);
    (out, fixes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(o: &str, k: Option<i64>, c: Option<&str>) -> Tuple {
        Tuple::new(o, k, c)
    }

    fn run(instruction: &str, tuples: &[Tuple]) -> Vec<Tuple> {
        reconcile_tuples(instruction, tuples, &Lexicon::builtin()).0
    }

    #[test]
    fn an_ordinal_no_word_says_is_dropped() {
        let got = run(
            "please go to the white bed",
            &[t("bed", Some(1), Some("white"))],
        );
        assert_eq!(got, vec![t("bed", None, Some("white"))]);
    }

    #[test]
    fn nearest_is_unspecified_and_has_no_order() {
        let got = run(
            "head to the nearest lamp and then to the red bench",
            &[
                t("lamp", Some(1), None).with_order(Some("north_to_south")),
                t("bench", None, Some("red")),
            ],
        );
        assert_eq!(
            got,
            vec![t("lamp", None, None), t("bench", None, Some("red"))]
        );
    }

    #[test]
    fn colour_goes_to_the_noun_it_precedes() {
        let got = run(
            "go to the chair next to the yellow table",
            &[t("chair", None, Some("yellow"))],
        );
        assert_eq!(
            got,
            vec![t("chair", None, None), t("table", None, Some("yellow"))]
        );
    }

    #[test]
    fn regions_after_in_the_are_listed() {
        let got = run(
            "go to the second grey table in the meeting room",
            &[t("table", Some(2), Some("gray"))],
        );
        assert_eq!(
            got,
            vec![
                t("table", Some(2), Some("gray")),
                t("meeting room", None, None)
            ]
        );
        let got = run("walk to the bed in the guest room", &[t("bed", None, None)]);
        assert_eq!(got[1], t("guest room", None, None));
    }

    #[test]
    fn tuples_for_motions_and_sides_are_dropped() {
        assert!(run(
            "move forward three meters and then turn left",
            &[t("box", Some(3), None).with_order(Some("east_to_west"))]
        )
        .is_empty());
        let got = run(
            "drive to the fourth yellow table and turn around",
            &[
                t("table", Some(4), Some("yellow")),
                t("turn around", None, None),
            ],
        );
        assert_eq!(got, vec![t("table", Some(4), Some("yellow"))]);
        let got = run(
            "stand with the tv on your right",
            &[t("tv", None, None), t("right", None, None)],
        );
        assert_eq!(got, vec![t("tv", None, None)]);
        // A colour listed as an object: the noun it describes gets the tuple.
        let got = run(
            "go to the rightmost black chair, then the red chair nearest to you",
            &[
                t("chair", Some(1), Some("black")).with_order(Some("right_to_left")),
                t("red", None, None),
            ],
        );
        assert_eq!(got.len(), 2, "{got:?}");
        assert_eq!(got[1], t("chair", None, Some("red")));
    }

    #[test]
    fn repeated_tuples_beyond_the_mentions_are_dropped() {
        let mut model = vec![t("toilet", Some(2), None)];
        model.extend(std::iter::repeat_n(t("toilet", None, None), 10));
        let got = run("drive to the second toilet and then turn right", &model);
        assert_eq!(got, vec![t("toilet", Some(2), None)]);
    }

    #[test]
    fn tuples_come_in_order_of_mention() {
        let got = run(
            "walk to the bed in the guest room, then to the wardrobe",
            &[
                t("guest room", None, None),
                t("bed", None, None),
                t("wardrobe", None, None),
            ],
        );
        assert_eq!(
            got,
            vec![
                t("bed", None, None),
                t("guest room", None, None),
                t("wardrobe", None, None)
            ]
        );
    }

    #[test]
    fn superlatives_and_counting_phrases_set_the_order() {
        let got = run(
            "go to the easternmost plant, then the red sofa, then the northernmost plant",
            &[
                t("plant", Some(1), None).with_order(Some("east_to_west")),
                t("sofa", None, Some("red")),
                t("plant", Some(1), None).with_order(Some("east_to_west")),
            ],
        );
        assert_eq!(got[2].order.as_deref(), Some("north_to_south"));
        let got = run(
            "go to the last black chair from west to east, then the third table from the right",
            &[
                t("chair", Some(-1), Some("black")),
                t("table", Some(3), None),
            ],
        );
        assert_eq!(got[0].order.as_deref(), Some("west_to_east"));
        assert_eq!(got[1].order.as_deref(), Some("right_to_left"));
        let got = run(
            "stop next to the first yellow table counting from the east",
            &[t("table", Some(1), Some("yellow"))],
        );
        assert_eq!(got[0].order.as_deref(), Some("east_to_west"));
    }

    #[test]
    fn a_side_is_not_a_counting_order() {
        let got = run(
            "go to the second chair on the left of the table",
            &[t("chair", Some(2), None).with_order(Some("left_to_right"))],
        );
        assert_eq!(got, vec![t("chair", Some(2), None), t("table", None, None)]);
    }

    #[test]
    fn synonyms_and_model_names_are_kept() {
        // The model says "sofa" for "couch": same category, name kept.
        let got = run("go to the couch", &[t("sofa", None, None)]);
        assert_eq!(got, vec![t("sofa", None, None)]);
        // A misspelt instruction still supports the model's name.
        let got = run("go to the frige", &[t("fridge", None, None)]);
        assert_eq!(got, vec![t("fridge", None, None)]);
    }

    #[test]
    fn colour_after_the_noun_in_a_relative_clause() {
        let got = run("go to the chair that is red", &[t("chair", None, None)]);
        assert_eq!(got, vec![t("chair", None, Some("red"))]);
    }

    #[test]
    fn compound_names_are_one_mention() {
        let got = run("go to the bathroom sink", &[t("sink", None, None)]);
        assert_eq!(got, vec![t("sink", None, None)]);
    }

    #[test]
    fn a_plural_mention_holds_several_tuples() {
        let got = run(
            "go between the two yellow tables in the open office",
            &[
                t("table", Some(1), Some("yellow")),
                t("table", Some(2), Some("yellow")),
                t("open office", None, None),
            ],
        );
        assert_eq!(got.len(), 3);
        assert_eq!(got[1], t("table", Some(2), Some("yellow")));
    }

    #[test]
    fn adverb_first_is_not_an_ordinal() {
        let got = run("first go to the kitchen", &[t("kitchen", None, None)]);
        assert_eq!(got, vec![t("kitchen", None, None)]);
    }

    #[test]
    fn nothing_to_change_reports_nothing() {
        let (got, fixes) = reconcile_tuples(
            "go to the third yellow table, then stop on the left of the black sofa",
            &[
                t("table", Some(3), Some("yellow")),
                t("sofa", None, Some("black")),
            ],
            &Lexicon::builtin(),
        );
        assert_eq!(got.len(), 2);
        assert!(fixes.is_empty(), "{fixes:?}");
    }
}
