//! Lexical evidence for step 1: words of the instruction that every correct tuple list
//! must reflect.
//!
//! A small model's typical misses (measured on the navigation suites) drop information
//! the instruction states in plain words: a superlative copied from an earlier mention
//! ("the easternmost plant ... the northernmost plant" read as two easternmost plants), a
//! colour left out, an ordinal on the wrong noun. Each ordinal word, superlative, counting
//! phrase and colour word of the instruction is counted; where the tuples hold fewer of
//! them, a message says what is missing, and the pipeline asks the model once more with
//! those messages (see [`crate::pipeline::extract_tuples_with`]). Nothing is rewritten here: the
//! model makes the correction, and a corrected answer is kept only if it misses less.

use crate::tuples::{
    normalise_colour, normalise_order, parse_ordinal, parse_ordinal_with_order, Tuple,
};
use crate::words::words;

/// A modifier of the instruction: what it requires of its noun's tuple.
#[derive(Debug, Clone, PartialEq)]
enum Need {
    /// Ordinal 1 in this order (a superlative).
    First(String),
    /// This ordinal.
    Ordinal(i64),
    /// This colour.
    Colour(String),
}

impl Need {
    fn met_by(&self, t: &Tuple) -> bool {
        match self {
            Need::First(o) => t.ordinal == Some(1) && t.order.as_deref() == Some(o.as_str()),
            Need::Ordinal(k) => t.ordinal == Some(*k),
            Need::Colour(c) => t.colour.as_deref() == Some(c.as_str()),
        }
    }

    fn describe(&self) -> String {
        match self {
            Need::First(o) => format!("ordinal 1 counted {o} (4th field {o})"),
            Need::Ordinal(-1) => "ordinal last".to_string(),
            Need::Ordinal(k) => format!("ordinal {k}"),
            Need::Colour(c) => format!("colour {c}"),
        }
    }
}

/// What a word at `i` requires, if it is a modifier.
fn need_of(w: &[String], i: usize) -> Option<Need> {
    let word = &w[i];
    if let Ok((Some(1), Some(order))) = parse_ordinal_with_order(word) {
        return Some(Need::First(order));
    }
    // Only "the second ...": "first go to the kitchen" counts nothing.
    let after_the = i > 0 && w[i - 1] == "the";
    let ordinal_like = word.chars().next().is_some_and(char::is_alphabetic)
        || ["st", "nd", "rd", "th"].iter().any(|s| word.ends_with(s));
    if after_the && ordinal_like {
        if let Ok(Some(k)) = parse_ordinal(word) {
            if k != -1 || word == "last" {
                return Some(Need::Ordinal(k));
            }
        }
    }
    if map_core::matcher::is_colour_word(word) {
        return normalise_colour(word).map(Need::Colour);
    }
    None
}

fn is_modifier(w: &[String], i: usize) -> bool {
    need_of(w, i).is_some() || matches!(w[i].as_str(), "nearest" | "closest" | "the")
}

/// The noun a modifier at `i` belongs to: the first following word that is no modifier,
/// singular, with its index.
fn noun_after(w: &[String], i: usize) -> Option<(usize, String)> {
    (i + 1..w.len().min(i + 5))
        .find(|&j| !is_modifier(w, j))
        .map(|j| (j, map_core::matcher::singular(&w[j])))
}

fn first_word(object: &str) -> String {
    map_core::matcher::singular(object.split_whitespace().next().unwrap_or(""))
}

/// What the tuples miss of what the instruction says. Where a modifier's noun can be
/// matched to a tuple (the j-th "plant" of the instruction is the j-th plant tuple) the
/// message names it; otherwise occurrences are counted.
#[must_use]
pub fn missing_evidence(instruction: &str, tuples: &[Tuple]) -> Vec<String> {
    let w = words(instruction);
    let mut out = Vec::new();
    let mut counted: Vec<String> = Vec::new();
    for i in 0..w.len() {
        let Some(need) = need_of(&w, i) else {
            continue;
        };
        let located = noun_after(&w, i).and_then(|(at, noun)| {
            let nth = (0..at)
                .filter(|&k| map_core::matcher::singular(&w[k]) == noun && !is_modifier(&w, k))
                .count();
            let same: Vec<&Tuple> = tuples
                .iter()
                .filter(|t| {
                    first_word(&t.object) == noun || map_core::matcher::singular(&t.object) == noun
                })
                .collect();
            same.get(nth).map(|t| (noun, nth, *t))
        });
        match located {
            Some((noun, nth, t)) => {
                if !need.met_by(t) {
                    out.push(format!(
                        "\"{} {noun}\" is the {} {noun} mentioned: its tuple needs {}",
                        w[i],
                        map_core::query::ordinal_word(i64::try_from(nth).unwrap_or(0) + 1),
                        need.describe()
                    ));
                }
            }
            None => {
                if counted.contains(&w[i]) {
                    continue;
                }
                counted.push(w[i].clone());
                let said = (0..w.len())
                    .filter(|&k| w[k] == w[i] && need_of(&w, k).as_ref() == Some(&need))
                    .count();
                let have = tuples.iter().filter(|t| need.met_by(t)).count();
                if have < said {
                    out.push(format!(
                        "\"{}\" is in the instruction but no tuple has {}",
                        w[i],
                        need.describe()
                    ));
                }
            }
        }
    }
    for t in tuples {
        if map_core::matcher::is_colour_word(&t.object) {
            out.push(format!(
                "\"{}\" is a colour, not an object: write the object it describes, with {} as its colour",
                t.object, t.object
            ));
        }
    }
    // Counting phrases: "from the west", "from west to east".
    let mut seen_orders: Vec<String> = Vec::new();
    for i in 0..w.len() {
        if w[i] != "from" {
            continue;
        }
        let order = [3usize, 5, 4]
            .iter()
            .find_map(|len| normalise_order(&w[i..w.len().min(i + len)].join(" ")));
        let Some(order) = order else { continue };
        if seen_orders.contains(&order) {
            continue;
        }
        seen_orders.push(order.clone());
        let said = count_orders(&w, &order);
        let have = tuples
            .iter()
            .filter(|t| t.order.as_deref() == Some(order.as_str()))
            .count();
        if have < said {
            out.push(format!(
                "the instruction counts {order} (\"{}\"): give that object's tuple a 4th field {order}",
                w[i..w.len().min(i + 3)].join(" ")
            ));
        }
    }
    out
}

/// How many counting phrases of `order` the instruction holds.
fn count_orders(w: &[String], order: &str) -> usize {
    let mut n = 0;
    let mut i = 0;
    while i < w.len() {
        if w[i] == "from" {
            let hit = (3..=5)
                .filter(|len| i + len <= w.len() || *len == 3)
                .any(|len| {
                    normalise_order(&w[i..w.len().min(i + len)].join(" ")).as_deref() == Some(order)
                });
            if hit {
                n += 1;
                i += 2;
                continue;
            }
        }
        i += 1;
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(o: &str, k: Option<i64>, c: Option<&str>, order: Option<&str>) -> Tuple {
        Tuple::new(o, k, c).with_order(order)
    }

    #[test]
    fn a_copied_superlative_is_found() {
        let i = "go to the easternmost plant, then the red sofa, then the northernmost plant, then the kitchen";
        let got = vec![
            t("plant", Some(1), None, Some("east_to_west")),
            t("sofa", None, Some("red"), None),
            t("plant", Some(1), None, Some("east_to_west")),
            t("kitchen", None, None, None),
        ];
        let m = missing_evidence(i, &got);
        assert_eq!(m.len(), 1, "{m:?}");
        assert_eq!(
            m[0],
            "\"northernmost plant\" is the 2nd plant mentioned: its tuple needs ordinal 1 counted north_to_south (4th field north_to_south)"
        );
        // Swapped: both plants are named.
        let swapped = vec![
            t("plant", Some(1), None, Some("north_to_south")),
            got[1].clone(),
            t("plant", Some(1), None, Some("east_to_west")),
            got[3].clone(),
        ];
        assert_eq!(missing_evidence(i, &swapped).len(), 2);
        let fixed = vec![
            got[0].clone(),
            got[1].clone(),
            t("plant", Some(1), None, Some("north_to_south")),
            got[3].clone(),
        ];
        assert!(missing_evidence(i, &fixed).is_empty());
    }

    #[test]
    fn missing_colours_ordinals_and_orders_are_found() {
        let i = "go to the second yellow table from the west, then the last black chair";
        assert!(missing_evidence(
            i,
            &[
                t("table", Some(2), Some("yellow"), Some("west_to_east")),
                t("chair", Some(-1), Some("black"), None)
            ]
        )
        .is_empty());
        let m = missing_evidence(
            i,
            &[
                t("table", Some(2), None, None),
                t("chair", None, Some("black"), None),
            ],
        );
        assert_eq!(m.len(), 3, "{m:?}");
    }

    #[test]
    fn nearest_and_sides_ask_for_nothing() {
        let i = "first stop on the west side of the nearest table, then go to the closest lamp and move forward 2 meters";
        assert!(missing_evidence(
            i,
            &[t("table", None, None, None), t("lamp", None, None, None)]
        )
        .is_empty());
    }
}
