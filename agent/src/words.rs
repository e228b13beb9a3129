//! Splitting an instruction into words: one rule for every part of the language layer.

/// Whether `c` belongs to a word: letters, digits, and the apostrophe inside words
/// ("table's"). A hyphen splits words: "second-to-last" says what "second to last" says
/// (held-out v9, dev since its third run, hv04: "the second-to-last luggage trolley"
/// was read as no count, so the grammar offered only 1 and -1, and the plan went to the
/// last one).
pub(crate) fn is_word_char(c: char) -> bool {
    c.is_alphanumeric() || c == '\''
}

/// The words of `text`, lower-case, punctuation and hyphens stripped.
pub(crate) fn words(text: &str) -> Vec<String> {
    text.to_lowercase()
        .split(|c: char| !is_word_char(c))
        .filter(|w| !w.is_empty())
        .map(str::to_string)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_keep_apostrophes_and_drop_punctuation_and_hyphens() {
        assert_eq!(
            words("Go to the north-east corner, then the table's LEFT side!"),
            [
                "go", "to", "the", "north", "east", "corner", "then", "the", "table's", "left",
                "side"
            ]
        );
        assert!(words(" ,. ").is_empty());
        assert_eq!(
            words("the second-to-last one"),
            words("the second to last one")
        );
    }
}
