//! Lexical evidence for step 1: words of the instruction that every correct tuple list
//! must reflect.
//!
//! A small model's typical misses (measured on the navigation suites) drop information
//! the instruction states in plain words: a superlative copied from an earlier mention
//! ("the easternmost plant ... the northernmost plant" read as two easternmost plants), a
//! colour left out, an ordinal on the wrong noun. Each ordinal word, superlative, counting
//! phrase and colour word of the instruction is counted; where the tuples hold fewer of
//! them, a message says what is missing, and the pipeline asks the model once more with
//! those messages (see [`super::extract_tuples_with`]). Nothing is rewritten here: the
//! model makes the correction, and a corrected answer is kept only if it misses less.

use super::tuples::{
    normalise_colour, normalise_order, parse_ordinal, parse_ordinal_with_order, Tuple,
};

/// The words of `instruction`, lower-case, punctuation stripped.
fn words(instruction: &str) -> Vec<String> {
    instruction
        .to_lowercase()
        .split(|c: char| !(c.is_alphanumeric() || c == '-'))
        .filter(|w| !w.is_empty())
        .map(str::to_string)
        .collect()
}

/// What the tuples miss of what the instruction says, one message per kind of miss.
#[must_use]
pub fn missing_evidence(instruction: &str, tuples: &[Tuple]) -> Vec<String> {
    let w = words(instruction);
    let mut out = Vec::new();
    let mut seen: Vec<String> = Vec::new();
    for (i, word) in w.iter().enumerate() {
        if seen.contains(word) {
            continue;
        }
        let said = w.iter().filter(|x| *x == word).count();
        // Superlatives: the 1st in an order.
        if let Ok((Some(1), Some(order))) = parse_ordinal_with_order(word) {
            seen.push(word.clone());
            let have = tuples
                .iter()
                .filter(|t| t.ordinal == Some(1) && t.order.as_deref() == Some(order.as_str()))
                .count();
            if have < said {
                out.push(format!(
                    "\"{word}\" means ordinal 1 counted {order}: that object's tuple is (object, 1, colour, {order})"
                ));
            }
            continue;
        }
        // Counting phrases: "from the west", "from west to east".
        if word == "from" {
            let phrase = w[i..w.len().min(i + 5)].join(" ");
            let order = normalise_order(&w[i..w.len().min(i + 3)].join(" "))
                .or_else(|| normalise_order(&phrase))
                .or_else(|| normalise_order(&w[i..w.len().min(i + 4)].join(" ")));
            if let Some(order) = order {
                let key = format!("from:{order}");
                if seen.contains(&key) {
                    continue;
                }
                seen.push(key);
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
            continue;
        }
        // Ordinal words and numbers ("second", "2nd", "last"); "nearest" is no ordinal.
        let is_ordinal_word = word.chars().next().is_some_and(char::is_alphabetic)
            || word.ends_with("st")
            || word.ends_with("nd")
            || word.ends_with("rd")
            || word.ends_with("th");
        // Only "the second ...": "first go to the kitchen" counts nothing.
        let after_the = i > 0 && w[i - 1] == "the";
        if is_ordinal_word && after_the {
            if let Ok(Some(k)) = parse_ordinal(word) {
                if k == -1 && !matches!(word.as_str(), "last") {
                    continue;
                }
                seen.push(word.clone());
                let have = tuples.iter().filter(|t| t.ordinal == Some(k)).count();
                if have < said {
                    let k_text = if k == -1 {
                        "last".to_string()
                    } else {
                        k.to_string()
                    };
                    out.push(format!(
                        "\"{word}\" is in the instruction but no tuple has ordinal {k_text} for it"
                    ));
                }
                continue;
            }
        }
        // Colour words.
        if map_core::is_colour_word(word) {
            seen.push(word.clone());
            let c = normalise_colour(word);
            let have = tuples.iter().filter(|t| t.colour == c).count();
            if have < said {
                out.push(format!(
                    "\"{word}\" is in the instruction but no tuple has the colour {}",
                    c.as_deref().unwrap_or(word)
                ));
            }
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
        assert!(m[0].contains("northernmost"), "{m:?}");
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
