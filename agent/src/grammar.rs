//! GBNF grammars for local models: step 1's tuple list and step 2's script.
//!
//! The tuple grammar admits exactly the paper's notation with our optional order field:
//! `[(object, ordinal, colour[, order]), ...]` where the ordinal is a number, `last` or
//! `None`, the colour one of map_core's colour words or `None`, and the order one of
//! map_core's order names. A model held to it cannot put a direction where the colour
//! goes or a word where the ordinal goes. The script grammar is planner_dsl's
//! ([`planner_dsl::script_grammar`], generated from the function registry).

use map_core::matcher::COLOUR_WORDS;
use map_core::ObjectOrder;

/// GBNF for step 1's answer (see the module docs); the rule `root` is the start.
#[must_use]
pub fn tuple_grammar() -> String {
    let alt = |words: &mut Vec<&str>| {
        // Longer words first so that none is cut short by a prefix of it.
        words.sort_by_key(|w| std::cmp::Reverse(w.len()));
        words
            .iter()
            .map(|w| format!("\"{w}\""))
            .collect::<Vec<_>>()
            .join(" | ")
    };
    let mut colours: Vec<&str> = COLOUR_WORDS.to_vec();
    let mut orders: Vec<&str> = ObjectOrder::ALL
        .iter()
        .map(|(_, n)| *n)
        .filter(|n| *n != ObjectOrder::NearToFar.name())
        .collect();
    format!(
        r#"root ::= "[" (tuple (", " tuple)*)? "]"
tuple ::= "(" object ", " ordinal ", " colour (", " order)? ")"
object ::= word (" " word)? (" " word)?
word ::= [a-z] [a-z]{{0,15}}
ordinal ::= "None" | "last" | [1-9] [0-9]?
colour ::= "None" | {}
order ::= {}
"#,
        alt(&mut colours),
        alt(&mut orders)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tuple_grammar_names_every_colour_and_order() {
        let g = tuple_grammar();
        for c in COLOUR_WORDS {
            assert!(g.contains(&format!("\"{c}\"")), "{c}");
        }
        assert!(g.contains("\"west_to_east\""));
        assert!(
            !g.contains("\"near_to_far\""),
            "the default order is written by leaving it out"
        );
    }
}
