//! [`EmbeddingMatcher`]: lexical match first, then MiniLM cosine similarity.

use std::collections::HashMap;
use std::path::Path;
use std::sync::{Arc, Mutex};

use super::encoder::TextEncoder;
use super::EmbedError;
use map_core::matcher::{normalise, LexicalMatcher, NameMatcher};

/// Lowest cosine similarity (of L2-normalised all-MiniLM-L6-v2 sentence embeddings)
/// at which a name counts as naming a label.
///
/// Measured with the int8 model (the `embed_matcher` tests print the scores): names
/// of the same thing the synonym table lacks score 0.63 to 0.97 ("freezer"/"fridge"
/// 0.66, "nightstand"/"bedside table" 0.68, "cupboard"/"cabinet" 0.73, "seat"/"chair"
/// 0.77, "tub"/"bathtub" 0.88), while unrelated words stay at or under 0.47
/// ("spaceship" 0.39 at best, "car"/"plant" 0.47) and near misses under 0.61
/// ("desk"/"chair" 0.60, "computer"/"television" 0.57, "pillow"/"bed" 0.54).
/// 0.62 keeps the near misses out: a wrong object is worse than "not on this map".
pub const DEFAULT_EMBEDDING_THRESHOLD: f32 = 0.62;

/// At most this many texts are cached before the cache is cleared.
const CACHE_LIMIT: usize = 4096;

/// Open-vocabulary name matching with sentence embeddings, behind [`NameMatcher`].
///
/// Matching a name against the labels of a map: if the [`LexicalMatcher`] finds a
/// label (same name, plural, synonym table, or a compound naming its head word),
/// that label wins with the lexical score. Otherwise each label's embedding (cached)
/// is compared with the name's by cosine similarity; the best at or above the
/// threshold ([`DEFAULT_EMBEDDING_THRESHOLD`] unless set) wins. Names and labels are
/// [`normalise`]d first (case, articles, underscores).
///
/// The [`NameMatcher`] methods cannot return errors: if the model fails on a text,
/// they fall back to the lexical answer. [`EmbeddingMatcher::try_best`] reports it.
#[derive(Debug)]
pub struct EmbeddingMatcher {
    encoder: TextEncoder,
    threshold: f32,
    lexical: LexicalMatcher,
    cache: Mutex<HashMap<String, Arc<[f32]>>>,
}

impl EmbeddingMatcher {
    /// A matcher over any sentence encoder, at [`DEFAULT_EMBEDDING_THRESHOLD`].
    pub fn new(encoder: TextEncoder) -> Self {
        EmbeddingMatcher {
            encoder,
            threshold: DEFAULT_EMBEDDING_THRESHOLD,
            lexical: LexicalMatcher,
            cache: Mutex::new(HashMap::new()),
        }
    }

    /// all-MiniLM-L6-v2 from the models cache (see [`TextEncoder::minilm`]).
    pub fn minilm(ort_lib: Option<&Path>) -> Result<Self, EmbedError> {
        Ok(EmbeddingMatcher::new(TextEncoder::minilm(ort_lib)?))
    }

    /// The same matcher with another cosine threshold.
    pub fn with_threshold(mut self, threshold: f32) -> Self {
        self.threshold = threshold;
        self
    }

    /// The encoder behind the matcher.
    pub fn encoder(&self) -> &TextEncoder {
        &self.encoder
    }

    /// Cosine similarity of the two names' embeddings, in [-1, 1].
    pub fn similarity(&self, a: &str, b: &str) -> Result<f32, EmbedError> {
        let v = self.embeddings(&[a, b])?;
        Ok(dot(&v[0], &v[1]))
    }

    /// The label `query` names, with its score: the lexical match if there is one,
    /// else the label of highest cosine similarity at or above the threshold.
    /// Ties go to the first in `labels`.
    pub fn try_best<'a>(
        &self,
        query: &str,
        labels: &[&'a str],
    ) -> Result<Option<(&'a str, f32)>, EmbedError> {
        if let Some(hit) = self.lexical.best_scored(query, labels) {
            return Ok(Some(hit));
        }
        if labels.is_empty() || normalise(query).is_empty() {
            return Ok(None);
        }
        let mut texts = Vec::with_capacity(labels.len() + 1);
        texts.push(query);
        texts.extend_from_slice(labels);
        let v = self.embeddings(&texts)?;
        let mut best: Option<(&'a str, f32)> = None;
        for (label, e) in labels.iter().zip(&v[1..]) {
            let s = dot(&v[0], e);
            if s >= self.threshold && best.is_none_or(|(_, b)| s > b) {
                best = Some((label, s));
            }
        }
        Ok(best)
    }

    /// Embeddings of the normalised texts, from the cache or one model run for the rest.
    fn embeddings(&self, texts: &[&str]) -> Result<Vec<Arc<[f32]>>, EmbedError> {
        let keys: Vec<String> = texts.iter().map(|t| normalise(t)).collect();
        let mut cache = self.cache.lock().unwrap_or_else(|p| p.into_inner());
        let mut missing: Vec<&str> = keys
            .iter()
            .filter(|k| !cache.contains_key(k.as_str()))
            .map(String::as_str)
            .collect();
        missing.sort_unstable();
        missing.dedup();
        if !missing.is_empty() {
            let e = self.encoder.embed(&missing)?;
            if cache.len() + missing.len() > CACHE_LIMIT {
                cache.clear();
            }
            for (i, k) in missing.iter().enumerate() {
                if let Some(row) = e.row(i) {
                    cache.insert((*k).to_string(), Arc::from(row));
                }
            }
        }
        keys.iter()
            .map(|k| {
                cache.get(k).cloned().ok_or_else(|| EmbedError::Run {
                    path: self.encoder.model_path().to_path_buf(),
                    message: format!("no embedding came back for {k:?}"),
                })
            })
            .collect()
    }
}

fn dot(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl NameMatcher for EmbeddingMatcher {
    /// The lexical score when it counts as a match, else the cosine similarity
    /// clamped to [0, 1] (0 if the model fails).
    fn score(&self, query: &str, label: &str) -> f32 {
        let lex = self.lexical.score(query, label);
        if lex >= self.lexical.threshold() {
            return lex;
        }
        self.similarity(query, label)
            .map(|s| s.clamp(0.0, 1.0))
            .unwrap_or(0.0)
    }

    /// The cosine threshold (lexical matches score at least the lexical threshold, 0.75).
    fn threshold(&self) -> f32 {
        self.threshold
    }

    fn best_scored<'a>(&self, query: &str, labels: &[&'a str]) -> Option<(&'a str, f32)> {
        self.try_best(query, labels)
            .unwrap_or_else(|_| self.lexical.best_scored(query, labels))
    }
}
