//! Where local model files live: one cache folder for the GGUF language models
//! (the `llm` crate) and the ONNX text encoder (the `map_build` crate), filled by
//! `scripts/fetch-models.sh`.

use std::path::PathBuf;

/// Environment variable naming the models cache (default `$HOME/.cache/ivlmap/models`).
pub const MODELS_ENV: &str = "IVLMAP_MODELS";

/// The models cache: `$IVLMAP_MODELS`, else `$HOME/.cache/ivlmap/models`; `None`
/// when neither variable is set.
#[must_use]
pub fn models_dir() -> Option<PathBuf> {
    match std::env::var_os(MODELS_ENV) {
        Some(d) if !d.is_empty() => Some(PathBuf::from(d)),
        _ => match std::env::var_os("HOME") {
            Some(h) if !h.is_empty() => Some(PathBuf::from(h).join(".cache/ivlmap/models")),
            _ => None,
        },
    }
}
