//! Prompt lookup: draft tokens for speculative decoding taken from the context itself.
//!
//! A v2 answer repeats what the prompt holds: the worked examples' calls
//! (`move_to_object(get_obj("`), selection keys, the map's names and colours, and the
//! answer's own earlier steps. Where the last few tokens of the context occurred before,
//! the tokens that followed them there are a guess at what comes next; the model checks
//! the guess in one batch ([`LlamaCppConfig::draft_tokens`](super::LlamaCppConfig)).
//!
//! Written here rather than taken from llama.cpp's `common/ngram-cache`: llama-cpp-2
//! binds llama.cpp's library, not its `common` helpers, and the search is a dozen lines.

/// Up to `max` tokens that followed the latest earlier occurrence of the last `n` tokens
/// of `ctx`, trying `n` from `longest` down to `shortest` (longer matches guess better);
/// empty when none occurred before or `max` is 0.
///
/// ```text
/// ctx  = a b c d | x b c  ->  (n = 2, "b c" at 1) -> draft "d x b"  (max 3)
/// ```
pub(crate) fn draft<T: PartialEq + Copy>(
    ctx: &[T],
    longest: usize,
    shortest: usize,
    max: usize,
) -> Vec<T> {
    if max == 0 || shortest == 0 {
        return Vec::new();
    }
    let len = ctx.len();
    for n in (shortest..=longest).rev() {
        if len <= n {
            continue;
        }
        let pattern = &ctx[len - n..];
        // The latest occurrence that is not the suffix itself.
        if let Some(start) = (0..len - n).rev().find(|&s| &ctx[s..s + n] == pattern) {
            let from = start + n;
            return ctx[from..(from + max).min(len)].to_vec();
        }
    }
    Vec::new()
}

#[cfg(test)]
mod tests {
    use super::draft;

    #[test]
    fn the_tokens_after_the_latest_earlier_match_are_the_draft() {
        let ctx = [1, 2, 3, 4, 9, 2, 3];
        assert_eq!(draft(&ctx, 3, 2, 3), vec![4, 9, 2]);
        // Cut at `max` and at the end of the context.
        assert_eq!(draft(&ctx, 3, 2, 1), vec![4]);
        assert_eq!(draft(&[5, 6, 5, 6], 2, 2, 8), vec![5, 6]);
        // The latest of several occurrences.
        assert_eq!(draft(&[1, 2, 7, 1, 2, 8, 1, 2], 2, 2, 1), vec![8]);
    }

    #[test]
    fn a_longer_match_wins_over_a_later_shorter_one() {
        // "2 3" occurs last at 4, but "1 2 3" occurs at 0: its continuation is drafted.
        let ctx = [1, 2, 3, 7, 2, 3, 8, 1, 2, 3];
        assert_eq!(draft(&ctx, 3, 2, 2), vec![7, 2]);
        assert_eq!(draft(&ctx, 2, 2, 2), vec![8, 1]);
    }

    #[test]
    fn no_earlier_match_or_no_room_drafts_nothing() {
        assert!(draft(&[1, 2, 3, 4], 3, 2, 4).is_empty());
        assert!(draft(&[1, 2, 1, 2], 3, 2, 0).is_empty());
        assert!(draft::<i32>(&[], 3, 1, 4).is_empty());
        assert!(draft(&[7], 3, 1, 4).is_empty());
        // A one-token match only when `shortest` allows it.
        assert!(draft(&[1, 5, 2, 1], 3, 2, 2).is_empty());
        assert_eq!(draft(&[1, 5, 2, 1], 3, 1, 2), vec![5, 2]);
    }
}
