//! The MiniLM encoder behind agent's `Embedder` seam, for v2's worked-example retrieval.

use std::sync::Arc;

use agent::v2::examples::{EmbedFailure, Embedder};
use agent::{PlanOptions, Prompts};
use map_build::embed::TextEncoder;

struct MiniLm(TextEncoder);

impl Embedder for MiniLm {
    fn embed(&self, texts: &[&str]) -> Result<Vec<Vec<f32>>, EmbedFailure> {
        let e = self
            .0
            .embed(texts)
            .map_err(|e| EmbedFailure(e.to_string()))?;
        Ok((0..e.len())
            .map(|i| e.row(i).map(<[f32]>::to_vec).unwrap_or_default())
            .collect())
    }

    fn name(&self) -> &str {
        "all-MiniLM-L6-v2"
    }
}

/// `prompts` with its worked examples ranked by MiniLM when some are picked per
/// instruction (`--examples K`; by default all are shown and none is ranked); when
/// the encoder cannot be loaded (no `scripts/setup.sh` yet) a warning says so and the
/// examples are ranked by words.
pub(crate) fn with_retrieval(prompts: Prompts, options: &PlanOptions) -> Prompts {
    if options.examples.is_none() {
        return prompts;
    }
    match TextEncoder::minilm(None) {
        Ok(enc) => match prompts.clone().with_embedder(Arc::new(MiniLm(enc))) {
            Ok(p) => p,
            Err(e) => {
                tracing::warn!("worked examples ranked by words: {e}");
                prompts
            }
        },
        Err(e) => {
            tracing::warn!("worked examples ranked by words (MiniLM not loaded: {e})");
            prompts
        }
    }
}
