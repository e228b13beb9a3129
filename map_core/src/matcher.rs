//! Name matching: how a word from an instruction ("couches", "TV", "grey") finds a
//! category, colour or region name of the map. Behind the [`NameMatcher`] trait so
//! an embedding-based matcher can stand in for the lexical one.

use std::fmt::Debug;

/// Scores how well a word from an instruction names a label of the map.
pub trait NameMatcher: Debug + Send + Sync {
    /// Similarity in [0, 1]: 1 = same name, 0 = unrelated.
    fn score(&self, query: &str, label: &str) -> f32;

    /// The lowest score that still counts as a match.
    fn threshold(&self) -> f32 {
        0.75
    }

    /// The best-scoring label at or above the threshold (ties: first in `labels`).
    fn best<'a>(&self, query: &str, labels: &[&'a str]) -> Option<&'a str> {
        self.best_scored(query, labels).map(|(l, _)| l)
    }

    /// [`NameMatcher::best`] with its score.
    fn best_scored<'a>(&self, query: &str, labels: &[&'a str]) -> Option<(&'a str, f32)> {
        let mut best: Option<(&'a str, f32)> = None;
        for &l in labels {
            let s = self.score(query, l);
            if s >= self.threshold() && best.is_none_or(|(_, b)| s > b) {
                best = Some((l, s));
            }
        }
        best
    }
}

/// Case, articles, plural/singular and a table of common synonyms.
#[derive(Debug, Clone, Default)]
pub struct LexicalMatcher;

/// Synonym groups: every word maps to the first of its group.
const SYNONYMS: &[&[&str]] = &[
    &["sofa", "couch", "settee"],
    &["television", "tv", "telly", "tv monitor", "tv set"],
    &["refrigerator", "fridge"],
    &["table", "desk table"],
    &["plant", "potted plant", "houseplant", "pot plant"],
    &["bed", "bedstead"],
    &["toilet", "wc", "lavatory"],
    &["sink", "washbasin", "basin"],
    &["cabinet", "cupboard"],
    &["shelf", "shelves", "bookshelf", "bookcase"],
    &["counter", "countertop", "worktop"],
    &["armchair", "arm chair"],
    &["stool", "bar stool"],
    &["lamp", "floor lamp"],
    &[
        "trash can",
        "bin",
        "rubbish bin",
        "garbage can",
        "wastebasket",
        "trash bin",
    ],
    &["microwave", "microwave oven"],
    &["washing machine", "washer"],
    &["bathtub", "bath", "tub"],
    &["rug", "carpet", "mat"],
    &["living room", "lounge", "sitting room", "livingroom"],
    &["bedroom", "bed room"],
    &["bathroom", "bath room", "restroom"],
    &["kitchen", "kitchenette"],
    &["dining room", "diningroom"],
    &["hallway", "hall", "corridor"],
    &["office", "study"],
    // colours
    &["gray", "grey"],
    &["brown", "tan", "chocolate"],
    &["purple", "violet"],
    &["pink", "magenta"],
    &["beige", "cream"],
];

/// The colour words the map understands (any colour a scene uses is accepted too).
pub const COLOUR_WORDS: &[&str] = &[
    "black",
    "white",
    "gray",
    "grey",
    "silver",
    "red",
    "orange",
    "yellow",
    "gold",
    "green",
    "blue",
    "navy",
    "cyan",
    "teal",
    "purple",
    "violet",
    "pink",
    "magenta",
    "brown",
    "tan",
    "beige",
    "cream",
    "chocolate",
];

/// Whether `word` is a colour word (after normalisation).
pub fn is_colour_word(word: &str) -> bool {
    let w = normalise(word);
    COLOUR_WORDS.contains(&w.as_str())
}

/// Lower-case, trim, drop leading articles, collapse whitespace and underscores.
pub fn normalise(s: &str) -> String {
    let lower = s.trim().to_lowercase().replace(['_', '-'], " ");
    let mut words: Vec<&str> = lower.split_whitespace().collect();
    while words.len() > 1 && matches!(words[0], "the" | "a" | "an" | "that" | "this") {
        words.remove(0);
    }
    words.join(" ")
}

/// English singular of the last word of a phrase ("dining tables" -> "dining table").
pub fn singular(phrase: &str) -> String {
    let (head, last) = match phrase.rfind(' ') {
        Some(i) => (&phrase[..=i], &phrase[i + 1..]),
        None => ("", phrase),
    };
    let irregular = [
        ("shelves", "shelf"),
        ("people", "person"),
        ("knives", "knife"),
        ("leaves", "leaf"),
        ("wolves", "wolf"),
        ("children", "child"),
        ("mice", "mouse"),
        ("feet", "foot"),
    ];
    let s = if let Some((_, s)) = irregular.iter().find(|(p, _)| *p == last) {
        s.to_string()
    } else if last.len() > 3 && last.ends_with("ies") {
        format!("{}y", &last[..last.len() - 3])
    } else if last.ends_with("ches")
        || last.ends_with("shes")
        || last.ends_with("xes")
        || last.ends_with("sses")
    {
        last[..last.len() - 2].to_string()
    } else if last.len() > 2
        && last.ends_with('s')
        && !last.ends_with("ss")
        && !last.ends_with("us")
    {
        last[..last.len() - 1].to_string()
    } else {
        last.to_string()
    };
    format!("{head}{s}")
}

/// English plural of a noun phrase ("bench" -> "benches"), for messages.
pub fn plural(phrase: &str) -> String {
    let (head, last) = match phrase.rfind(' ') {
        Some(i) => (&phrase[..=i], &phrase[i + 1..]),
        None => ("", phrase),
    };
    let p = if last == "shelf" {
        "shelves".to_string()
    } else if last.ends_with("ch")
        || last.ends_with("sh")
        || last.ends_with('x')
        || last.ends_with('s')
    {
        format!("{last}es")
    } else if last.ends_with('y')
        && !last.ends_with("ay")
        && !last.ends_with("ey")
        && !last.ends_with("oy")
    {
        format!("{}ies", &last[..last.len() - 1])
    } else {
        format!("{last}s")
    };
    format!("{head}{p}")
}

/// The other words of `name`'s synonym group (not `name` itself), e.g. "couch" and
/// "settee" for "sofa"; empty when the table knows none.
///
/// ```
/// assert_eq!(map_core::matcher::synonyms("sofa"), ["couch", "settee"]);
/// assert!(map_core::matcher::synonyms("chair").is_empty());
/// ```
#[must_use]
pub fn synonyms(name: &str) -> Vec<&'static str> {
    let c = canonical(name);
    SYNONYMS
        .iter()
        .find(|g| g[0] == c)
        .map(|g| {
            g.iter()
                .copied()
                .filter(|w| *w != normalise(name))
                .collect()
        })
        .unwrap_or_default()
}

/// The canonical form of a name: normalised, singular, synonym group head.
pub fn canonical(s: &str) -> String {
    let n = normalise(s);
    for cand in [n.clone(), singular(&n)] {
        for group in SYNONYMS {
            if group.contains(&cand.as_str()) {
                return group[0].to_string();
            }
        }
    }
    singular(&n)
}

impl NameMatcher for LexicalMatcher {
    fn score(&self, query: &str, label: &str) -> f32 {
        let (q, l) = (canonical(query), canonical(label));
        if q.is_empty() || l.is_empty() {
            return 0.0;
        }
        if q == l {
            return 1.0;
        }
        // "dining table" names a "table" (and vice versa) a little less surely.
        let head = |s: &str| s.rsplit(' ').next().map(canonical).unwrap_or_default();
        if (q.contains(' ') || l.contains(' ')) && head(&q) == head(&l) {
            return 0.8;
        }
        // "livingroom" / "living room"
        if q.replace(' ', "") == l.replace(' ', "") {
            return 0.95;
        }
        // A closed compound names its head: "armchair" a "chair", "bookshelf" a "shelf"
        // (one way only: a chair need not be an armchair).
        let last = q.rsplit(' ').next().unwrap_or(&q);
        if !l.contains(' ') && l.len() >= 4 && last.len() > l.len() && last.ends_with(l.as_str()) {
            return 0.78;
        }
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_closed_compound_names_its_head_one_way() {
        let m = LexicalMatcher;
        assert_eq!(m.best("armchair", &["sofa", "chair"]), Some("chair"));
        assert_eq!(m.best("grey armchairs", &["chair"]), Some("chair"));
        assert_eq!(m.best("chair", &["armchair"]), None);
        // Exact names win over the compound rule.
        assert_eq!(m.best("armchair", &["chair", "armchair"]), Some("armchair"));
        // Short labels do not match word endings ("tv" in nothing, "bed" in "sofabed" is 3).
        assert_eq!(m.best("sofabed", &["bed"]), None);
    }

    #[test]
    fn plural_case_and_synonyms_match() {
        let m = LexicalMatcher;
        for (q, l) in [
            ("Sofas", "sofa"),
            ("couch", "sofa"),
            ("the TV", "television"),
            ("fridge", "refrigerator"),
            ("grey", "gray"),
            ("benches", "bench"),
            ("shelves", "shelf"),
            ("Living_Room", "lounge"),
            ("boxes", "box"),
            ("potted plants", "plant"),
        ] {
            assert_eq!(m.score(q, l), 1.0, "{q} vs {l}");
        }
        assert_eq!(m.score("chair", "table"), 0.0);
        assert_eq!(m.best("dining table", &["chair", "table"]), Some("table"));
        assert_eq!(m.best("piano", &["chair", "table"]), None);
    }

    #[test]
    fn plurals_for_messages() {
        assert_eq!(plural("table"), "tables");
        assert_eq!(plural("bench"), "benches");
        assert_eq!(plural("shelf"), "shelves");
        assert_eq!(plural("dining table"), "dining tables");
        assert_eq!(plural("box"), "boxes");
        assert_eq!(singular("glasses"), "glass");
    }

    #[test]
    fn colour_words_are_known() {
        assert!(is_colour_word("Grey"));
        assert!(!is_colour_word("left"));
    }
}
