//! Opening an LLM backend by name, as the command line names them (formats.md).

use std::path::PathBuf;

#[cfg(feature = "llama")]
use llm::{LlamaCppBackend, LlamaCppConfig};
use llm::{LlmBackend, LlmError, Recording, ReplayBackend};
#[cfg(feature = "openai")]
use llm::{OpenAiBackend, OpenAiConfig};

/// The default local model (fetched by `scripts/fetch-models.sh qwen1.5b`).
#[cfg(feature = "llama")]
pub const DEFAULT_MODEL_FILE: &str = "qwen2.5-coder-1.5b-instruct-q4_k_m.gguf";

/// Where the default model lives: `$IVLMAP_MODELS/<file>`, else
/// `~/.cache/ivlmap/models/<file>`.
#[cfg(feature = "llama")]
#[must_use]
pub fn default_model_path() -> PathBuf {
    // map_core's folder (the ONNX models live there too); with no HOME, relative.
    map_core::models::models_dir()
        .unwrap_or_else(|| PathBuf::from(".cache/ivlmap/models"))
        .join(DEFAULT_MODEL_FILE)
}

/// Which backend to open, as given on the command line.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BackendChoice {
    /// `llama` (default), `openai` or `replay`.
    pub name: String,
    /// llama: the GGUF file; openai: the model id; replay: ignored.
    pub model: Option<String>,
    /// openai: the server's base URL (else `IVLMAP_BASE_URL`).
    pub base_url: Option<String>,
    /// replay: the cassette to answer from.
    pub cassette: Option<PathBuf>,
    /// Record every request and answer to this cassette (any backend).
    pub record: Option<PathBuf>,
    /// llama: CPU threads (default 2).
    pub threads: Option<u32>,
    /// llama: flash attention on (`Some(true)`), off (`Some(false)`) or llama.cpp's own
    /// choice (`None`, the default).
    pub flash_attention: Option<bool>,
    /// openai: send each request's GBNF grammar as the `grammar` field (a llama-server
    /// extension; other servers may ignore or refuse it). Off: the grammar is not sent.
    pub send_grammar: bool,
    /// llama: the prompt cache's folder on disk (`None`: off).
    pub prompt_cache: Option<PathBuf>,
}

/// `~/.cache/ivlmap/prompt-cache` (`None` without a home folder).
#[must_use]
pub fn default_prompt_cache_dir() -> Option<PathBuf> {
    std::env::var_os("HOME")
        .filter(|h| !h.is_empty())
        .map(|h| PathBuf::from(h).join(".cache/ivlmap/prompt-cache"))
}

/// The backends this binary was built with (cargo features `llama` and `openai`).
pub const BUILT_BACKENDS: &[&str] = &[
    #[cfg(feature = "llama")]
    "llama",
    #[cfg(feature = "openai")]
    "openai",
    "replay",
];

/// Opens the backend `choice` names.
///
/// # Errors
/// [`LlmError::Config`] for an unknown name or a missing option; the backend's own
/// error when it cannot start (model file missing, bad URL, unreadable cassette).
pub fn open_backend(choice: &BackendChoice) -> Result<Box<dyn LlmBackend>, LlmError> {
    let name = if choice.name.is_empty() {
        "llama"
    } else {
        choice.name.as_str()
    };
    let inner: Box<dyn LlmBackend> = match name {
        #[cfg(feature = "llama")]
        "llama" => {
            let path = choice
                .model
                .as_ref()
                .map_or_else(default_model_path, PathBuf::from);
            let mut cfg = LlamaCppConfig::new(path);
            if let Some(t) = choice.threads {
                cfg.threads = t.max(1);
            }
            cfg.flash_attention = choice.flash_attention;
            cfg.prompt_cache_dir.clone_from(&choice.prompt_cache);
            Box::new(LlamaCppBackend::new(cfg)?)
        }
        #[cfg(feature = "openai")]
        "openai" => {
            let mut cfg = match &choice.base_url {
                Some(url) => {
                    let mut c = OpenAiConfig::new(
                        url.clone(),
                        std::env::var("IVLMAP_MODEL").unwrap_or_else(|_| "default".into()),
                    );
                    c.api_key = std::env::var("IVLMAP_API_KEY")
                        .ok()
                        .filter(|k| !k.trim().is_empty());
                    c
                }
                None => OpenAiConfig::from_env()?,
            };
            if let Some(m) = &choice.model {
                cfg.model = m.clone();
            }
            cfg.send_grammar = choice.send_grammar;
            Box::new(OpenAiBackend::new(cfg)?)
        }
        "replay" => {
            let Some(c) = &choice.cassette else {
                return Err(LlmError::Config {
                    message: "the replay backend needs --cassette FILE (a cassette recorded with --record)".into(),
                });
            };
            Box::new(ReplayBackend::open(c.clone())?)
        }
        other => {
            return Err(LlmError::Config {
                message: format!(
                    "unknown backend {other:?}: this ivlmap was built with {}",
                    BUILT_BACKENDS.join(", ")
                ),
            })
        }
    };
    match &choice.record {
        Some(path) => Ok(Box::new(Recording::new(inner, path.clone())?)),
        None => Ok(inner),
    }
}
