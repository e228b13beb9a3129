//! Splitting an instruction into words: one rule for every part of the language layer.

/// Whether `c` belongs to a word: letters, digits, and the hyphen and apostrophe inside
/// words ("north-east", "table's").
pub(crate) fn is_word_char(c: char) -> bool {
    c.is_alphanumeric() || c == '-' || c == '\''
}

/// The words of `text`, lower-case, punctuation stripped.
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
    fn words_keep_hyphens_and_apostrophes_and_drop_punctuation() {
        assert_eq!(
            words("Go to the north-east corner, then the table's LEFT side!"),
            [
                "go",
                "to",
                "the",
                "north-east",
                "corner",
                "then",
                "the",
                "table's",
                "left",
                "side"
            ]
        );
        assert!(words(" ,. ").is_empty());
    }
}
