//! # llm: LLM backends behind one synchronous trait, [`LlmBackend`]
//!
//! The seam between the language layer (the `agent` crate, which knows only this
//! trait) and the models. Cargo features pick the heavy backends: `llama` (compiles
//! llama.cpp) and `openai` (reqwest + tokio), both on by default; `replay` is always
//! here.
//!
//! - [`LlamaCppBackend`]: a local GGUF model run by llama.cpp (llama-cpp-2), with prompt-prefix
//!   KV caching and optional GBNF grammars.
//! - [`OpenAiBackend`]: any OpenAI-compatible `/v1/chat/completions` server (OpenAI, vLLM,
//!   llama-server, Ollama, ...), with retries and lenient parsing.
//! - [`ReplayBackend`] / [`Recording`]: answer from a recorded cassette (JSONL), or record one
//!   from any backend.
//!
//! Every backend takes a [`CompletionRequest`] (chat messages plus sampling parameters) and
//! returns a [`Completion`] (the text plus token counts and timings), or an [`LlmError`] whose
//! message says what to do about it.

#![warn(missing_docs)]

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

#[cfg(feature = "llama")]
pub mod llama;
#[cfg(feature = "openai")]
pub mod openai;
pub mod replay;

#[cfg(feature = "llama")]
pub use llama::{LlamaCppBackend, LlamaCppConfig};
#[cfg(feature = "openai")]
pub use openai::{OpenAiBackend, OpenAiConfig};
pub use replay::{Recording, ReplayBackend};

/// Who speaks a chat message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Role {
    /// Instructions that frame the whole conversation.
    System,
    /// The person (or the program speaking for them).
    User,
    /// The model's earlier answers (few-shot examples, chat history).
    Assistant,
}

impl Role {
    /// The role's name as chat templates and the OpenAI API spell it.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Role::System => "system",
            Role::User => "user",
            Role::Assistant => "assistant",
        }
    }
}

impl std::fmt::Display for Role {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One message of a chat.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct ChatMessage {
    /// Who speaks.
    pub role: Role,
    /// What they say.
    pub content: String,
}

impl ChatMessage {
    /// A system message.
    pub fn system(content: impl Into<String>) -> Self {
        Self {
            role: Role::System,
            content: content.into(),
        }
    }
    /// A user message.
    pub fn user(content: impl Into<String>) -> Self {
        Self {
            role: Role::User,
            content: content.into(),
        }
    }
    /// An assistant message.
    pub fn assistant(content: impl Into<String>) -> Self {
        Self {
            role: Role::Assistant,
            content: content.into(),
        }
    }
}

/// What to ask a backend for. Serializable, so that cassettes can key on it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CompletionRequest {
    /// The chat so far; the model answers as the assistant. A final assistant message
    /// (after at least one other) is the beginning of the answer, which the model
    /// continues: the llama backend opens the assistant turn and appends it; the openai
    /// backend sends it as it is (a server that takes an assistant prefill continues it;
    /// one that does not starts a new answer). The completion's text is only what
    /// follows it.
    pub messages: Vec<ChatMessage>,
    /// The most tokens to generate.
    pub max_tokens: u32,
    /// Sampling temperature; 0 means greedy (deterministic).
    #[serde(default)]
    pub temperature: f32,
    /// Seed of the sampler when `temperature` > 0 (the backend's own when `None`): two
    /// requests alike but for their seed draw two answers. Ignored when greedy.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u32>,
    /// Generation ends before any of these strings (which are not part of the answer).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub stop: Vec<String>,
    /// A GBNF grammar the output must follow (root rule `root`). Honoured by the llama
    /// backend; the openai backend sends it only when configured to (llama-server accepts it)
    /// and otherwise ignores it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grammar: Option<String>,
    /// A Lark grammar (llguidance's syntax, start rule `start`) the output must follow.
    /// The llama backend prefers it to `grammar` (llguidance computes each token mask in
    /// microseconds where GBNF takes milliseconds); other backends ignore it, so send a
    /// `grammar` too where they should be held.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lark: Option<String>,
    /// A JSON schema the output should follow. The openai backend sends it as
    /// `response_format` when configured to; the llama backend converts it to a grammar
    /// when no `grammar` is given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub json_schema: Option<serde_json::Value>,
}

impl CompletionRequest {
    /// A greedy request for `messages` with up to `max_tokens` tokens.
    #[must_use]
    pub fn new(messages: Vec<ChatMessage>, max_tokens: u32) -> Self {
        Self {
            messages,
            max_tokens,
            temperature: 0.0,
            seed: None,
            stop: Vec::new(),
            grammar: None,
            lark: None,
            json_schema: None,
        }
    }

    /// Checks what every backend needs: at least one message, at least one token, a
    /// temperature that is a finite number >= 0.
    ///
    /// # Errors
    /// [`LlmError::InvalidRequest`] naming the field.
    pub fn validate(&self) -> Result<(), LlmError> {
        if self.messages.is_empty() {
            return Err(LlmError::InvalidRequest {
                message: "messages is empty: give at least one message".into(),
            });
        }
        if self.max_tokens == 0 {
            return Err(LlmError::InvalidRequest {
                message: "max_tokens is 0: ask for at least 1 token".into(),
            });
        }
        if !self.temperature.is_finite() || self.temperature < 0.0 {
            return Err(LlmError::InvalidRequest {
                message: format!(
                    "temperature is {}: use a number >= 0 (0 = greedy)",
                    self.temperature
                ),
            });
        }
        if self.stop.iter().any(String::is_empty) {
            return Err(LlmError::InvalidRequest {
                message: "stop contains an empty string: remove it".into(),
            });
        }
        Ok(())
    }
}

/// Why generation ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FinishReason {
    /// The model finished (end-of-generation token) or a stop string was reached.
    Stop,
    /// `max_tokens` (or the context window) ran out: the text may be cut short.
    Length,
    /// The backend did not say.
    #[default]
    Unknown,
}

/// A backend's answer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Completion {
    /// The generated text (without the stop string that ended it).
    pub text: String,
    /// Tokens in the prompt (as the backend counts them; 0 if it did not say).
    #[serde(default)]
    pub prompt_tokens: u32,
    /// Of those, how many were reused from the KV cache instead of recomputed.
    #[serde(default)]
    pub cached_prompt_tokens: u32,
    /// Tokens generated.
    #[serde(default)]
    pub completion_tokens: u32,
    /// Milliseconds spent processing the prompt (0 if unknown).
    #[serde(default)]
    pub prompt_ms: f64,
    /// Milliseconds spent generating (for remote backends: the whole round trip when the
    /// server gives no timings).
    #[serde(default)]
    pub generate_ms: f64,
    /// Why generation ended.
    #[serde(default)]
    pub finish_reason: FinishReason,
    /// Of the generated tokens, how many a grammar forced and were decoded in a batch
    /// instead of sampled one by one (llama with a Lark grammar; 0 elsewhere).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub forced_tokens: u32,
}

#[allow(clippy::trivially_copy_pass_by_ref)] // serde's skip_serializing_if passes a reference
fn is_zero(n: &u32) -> bool {
    *n == 0
}

/// A language model that completes chats. Synchronous: call it from a plain thread (an
/// async caller should use `spawn_blocking`).
pub trait LlmBackend: Send + Sync {
    /// The backend kind: "llama", "openai", "replay", ...
    fn name(&self) -> &str;
    /// The model it runs (a GGUF file name, a remote model id, a cassette's model).
    fn model(&self) -> &str;
    /// Answers one request.
    ///
    /// # Errors
    /// See [`LlmError`].
    fn complete(&self, req: &CompletionRequest) -> Result<Completion, LlmError>;
}

impl<B: LlmBackend + ?Sized> LlmBackend for Box<B> {
    fn name(&self) -> &str {
        (**self).name()
    }
    fn model(&self) -> &str {
        (**self).model()
    }
    fn complete(&self, req: &CompletionRequest) -> Result<Completion, LlmError> {
        (**self).complete(req)
    }
}

impl<B: LlmBackend + ?Sized> LlmBackend for std::sync::Arc<B> {
    fn name(&self) -> &str {
        (**self).name()
    }
    fn model(&self) -> &str {
        (**self).model()
    }
    fn complete(&self, req: &CompletionRequest) -> Result<Completion, LlmError> {
        (**self).complete(req)
    }
}

/// Everything that can go wrong asking a model.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LlmError {
    /// The request itself is unusable.
    #[error("invalid request: {message}")]
    InvalidRequest {
        /// What is wrong and how to fix it.
        message: String,
    },
    /// A backend's configuration is unusable (missing URL, bad number, ...).
    #[error("backend configuration: {message}")]
    Config {
        /// What is wrong and how to fix it.
        message: String,
    },
    /// The GGUF model could not be loaded.
    #[error("cannot load model {}: {reason}", path.display())]
    ModelLoad {
        /// The file asked for.
        path: PathBuf,
        /// Why (missing file, not a GGUF llama.cpp can read, out of memory, ...).
        reason: String,
    },
    /// The chat template could not render the messages.
    #[error("chat template: {message}")]
    ChatTemplate {
        /// What failed and what to do.
        message: String,
    },
    /// A GBNF grammar (or JSON schema converted to one) was rejected.
    #[error("grammar rejected: {message}")]
    Grammar {
        /// Why (llama.cpp logs the parse error at `warn`/`error` level in tracing).
        message: String,
    },
    /// The sampler stopped holding the answer to its grammar: llguidance could not compute
    /// a token mask (it ran out of lexer fuel on a costly regular expression) and the model
    /// wrote a token the grammar does not allow. A defect of the grammar, not of the model.
    #[error(
        "the answer left its grammar after {after_bytes} bytes ({reason}): the grammar is too \
         costly for llguidance to follow"
    )]
    GrammarNotHeld {
        /// How much of the answer the grammar held.
        after_bytes: usize,
        /// llguidance's reason for the token it refused.
        reason: String,
    },
    /// The prompt does not fit the context window.
    #[error(
        "prompt is {prompt_tokens} tokens but the context window holds {n_ctx}: \
         shorten the prompt or raise n_ctx"
    )]
    ContextOverflow {
        /// Tokens in the rendered prompt.
        prompt_tokens: usize,
        /// The context window.
        n_ctx: u32,
    },
    /// llama.cpp failed while evaluating tokens.
    #[error("llama.cpp decode failed: {message}")]
    Decode {
        /// The failure.
        message: String,
    },
    /// The thread that runs the local model is gone.
    #[error("llama worker thread stopped: {message}")]
    Worker {
        /// What happened.
        message: String,
    },
    /// The server answered with an error status (after any retries).
    #[error("HTTP {status} from {url} after {attempts} attempt(s): {message}")]
    Http {
        /// The HTTP status.
        status: u16,
        /// The URL asked.
        url: String,
        /// The server's error message (parsed from its body when possible).
        message: String,
        /// How many times the request was sent.
        attempts: u32,
    },
    /// No answer in time.
    #[error("timed out waiting for {url} after {attempts} attempt(s) (timeout {timeout_ms} ms): raise the timeout or use a smaller model")]
    Timeout {
        /// The URL asked.
        url: String,
        /// The timeout that elapsed.
        timeout_ms: u64,
        /// How many times the request was sent.
        attempts: u32,
    },
    /// The server could not be reached.
    #[error("cannot connect to {url} after {attempts} attempt(s): {message}; is the server running and the base URL right?")]
    Connect {
        /// The URL asked.
        url: String,
        /// The transport error.
        message: String,
        /// How many times the request was sent.
        attempts: u32,
    },
    /// The server's answer is not what an OpenAI-compatible server sends.
    #[error("malformed response from {url}: {message}; body starts: {body_start:?}")]
    Malformed {
        /// The URL asked.
        url: String,
        /// What is missing or wrong.
        message: String,
        /// The first few hundred characters of the body.
        body_start: String,
    },
    /// A replay cassette has no exchange for this request.
    #[error("cassette {} has no recorded answer for this request: {detail}", path.display())]
    CassetteMiss {
        /// The cassette file.
        path: PathBuf,
        /// Which recorded request is nearest and where it differs.
        detail: String,
    },
    /// A cassette line is not a valid record.
    #[error("{}:{line}: bad cassette record: {message}", path.display())]
    CassetteParse {
        /// The cassette file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// The JSON error.
        message: String,
    },
    /// A cassette could not be read or written.
    #[error("cassette {}: {message}", path.display())]
    CassetteIo {
        /// The cassette file.
        path: PathBuf,
        /// The I/O error.
        message: String,
    },
}

/// Cuts `s` to at most `max` characters (on a char boundary), marking the cut.
pub(crate) fn snippet(s: &str, max: usize) -> String {
    match s.char_indices().nth(max) {
        Some((i, _)) => format!("{}...", &s[..i]),
        None => s.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn request_roundtrips_through_json_and_omits_empty_options() {
        let req = CompletionRequest::new(
            vec![ChatMessage::system("be brief"), ChatMessage::user("hi")],
            16,
        );
        let s = serde_json::to_string(&req).unwrap();
        assert!(!s.contains("grammar"), "{s}");
        assert!(!s.contains("stop"), "{s}");
        assert!(s.contains("\"role\":\"system\""), "{s}");
        let back: CompletionRequest = serde_json::from_str(&s).unwrap();
        assert_eq!(back, req);
    }

    #[test]
    fn validate_names_the_bad_field() {
        let mut req = CompletionRequest::new(vec![], 16);
        assert!(req.validate().unwrap_err().to_string().contains("messages"));
        req.messages.push(ChatMessage::user("x"));
        req.max_tokens = 0;
        assert!(req
            .validate()
            .unwrap_err()
            .to_string()
            .contains("max_tokens"));
        req.max_tokens = 1;
        req.temperature = f32::NAN;
        assert!(req
            .validate()
            .unwrap_err()
            .to_string()
            .contains("temperature"));
        req.temperature = 0.5;
        assert!(req.validate().is_ok());
    }

    #[test]
    fn snippet_cuts_on_char_boundaries() {
        assert_eq!(snippet("héllo", 2), "hé...");
        assert_eq!(snippet("hé", 2), "hé");
    }
}
