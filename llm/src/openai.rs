//! The remote backend: any OpenAI-compatible `POST {base}/v1/chat/completions` server
//! (OpenAI, vLLM, llama-server, Ollama, LM Studio, ...).
//!
//! It uses async reqwest on a small private tokio runtime (one worker thread) and blocks the
//! caller on it. Async reqwest rather than `reqwest::blocking` because only the async client
//! has a read (idle) timeout separate from the total timeout. The call is safe from any
//! thread: called from inside another tokio runtime it runs the request on a scoped helper
//! thread instead of nesting runtimes (which would panic).
//!
//! Retries: 429, 5xx and connection failures are retried up to `max_retries` times with
//! exponential backoff and jitter, honouring a numeric `Retry-After` (bounded). Timeouts are
//! not retried (the server may still be working on the request).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use serde_json::{json, Value};

use super::{snippet, Completion, CompletionRequest, FinishReason, LlmBackend, LlmError};

/// Settings of the OpenAI-compatible backend.
#[derive(Clone, PartialEq)]
pub struct OpenAiConfig {
    /// The server's base URL, with or without the trailing `/v1`
    /// (`http://127.0.0.1:8080`, `https://api.openai.com/v1`).
    pub base_url: String,
    /// Sent as `Authorization: Bearer ...` when set.
    pub api_key: Option<String>,
    /// The model id sent in each request (servers with one model, e.g. llama-server,
    /// ignore it).
    pub model: String,
    /// Time allowed to establish a connection (default 10 s).
    pub connect_timeout: Duration,
    /// The longest wait for the next bytes of the answer (default 120 s).
    pub read_timeout: Duration,
    /// The longest a whole request may take (default 300 s).
    pub request_timeout: Duration,
    /// Retries after the first attempt for 429, 5xx and connection errors (default 3).
    pub max_retries: u32,
    /// First backoff delay; doubles with each retry, with jitter (default 500 ms).
    pub backoff_base: Duration,
    /// The longest backoff delay (default 20 s).
    pub backoff_max: Duration,
    /// The longest `Retry-After` honoured; longer values are cut to this (default 60 s).
    pub retry_after_max: Duration,
    /// Send `response_format: json_schema` when a request carries a JSON schema
    /// (default off: not every server supports it; llama-server ignores some shapes).
    pub use_json_schema: bool,
    /// Send a request's GBNF grammar as the `grammar` field (a llama-server extension;
    /// default off, the grammar is then ignored).
    pub send_grammar: bool,
}

impl std::fmt::Debug for OpenAiConfig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OpenAiConfig")
            .field("base_url", &self.base_url)
            .field("api_key", &self.api_key.as_ref().map(|_| "<redacted>"))
            .field("model", &self.model)
            .field("connect_timeout", &self.connect_timeout)
            .field("read_timeout", &self.read_timeout)
            .field("request_timeout", &self.request_timeout)
            .field("max_retries", &self.max_retries)
            .field("use_json_schema", &self.use_json_schema)
            .field("send_grammar", &self.send_grammar)
            .finish_non_exhaustive()
    }
}

/// Environment variable holding the base URL.
pub const ENV_BASE_URL: &str = "IVLMAP_BASE_URL";
/// Environment variable holding the API key (optional).
pub const ENV_API_KEY: &str = "IVLMAP_API_KEY";
/// Environment variable holding the model id (optional).
pub const ENV_MODEL: &str = "IVLMAP_MODEL";

impl OpenAiConfig {
    /// Defaults for a server at `base_url` running `model`, without a key.
    pub fn new(base_url: impl Into<String>, model: impl Into<String>) -> Self {
        Self {
            base_url: base_url.into(),
            api_key: None,
            model: model.into(),
            connect_timeout: Duration::from_secs(10),
            read_timeout: Duration::from_secs(120),
            request_timeout: Duration::from_secs(300),
            max_retries: 3,
            backoff_base: Duration::from_millis(500),
            backoff_max: Duration::from_secs(20),
            retry_after_max: Duration::from_secs(60),
            use_json_schema: false,
            send_grammar: false,
        }
    }

    /// From `IVLMAP_BASE_URL` (required), `IVLMAP_API_KEY` and `IVLMAP_MODEL` (optional;
    /// the model defaults to `"default"`).
    ///
    /// # Errors
    /// [`LlmError::Config`] when `IVLMAP_BASE_URL` is unset or empty.
    pub fn from_env() -> Result<Self, LlmError> {
        Self::from_lookup(|k| std::env::var(k).ok())
    }

    fn from_lookup(get: impl Fn(&str) -> Option<String>) -> Result<Self, LlmError> {
        let nonempty = |k: &str| get(k).filter(|v| !v.trim().is_empty());
        let base = nonempty(ENV_BASE_URL).ok_or_else(|| LlmError::Config {
            message: format!(
                "{ENV_BASE_URL} is not set: give the server's base URL \
                 (e.g. http://127.0.0.1:8080 for llama-server) with --base-url or {ENV_BASE_URL}"
            ),
        })?;
        let model = nonempty(ENV_MODEL).unwrap_or_else(|| "default".into());
        let mut cfg = Self::new(base.trim(), model);
        cfg.api_key = nonempty(ENV_API_KEY);
        Ok(cfg)
    }

    /// The chat-completions endpoint for `base_url`.
    ///
    /// # Errors
    /// [`LlmError::Config`] when the base URL is not an http(s) URL.
    pub fn endpoint(&self) -> Result<String, LlmError> {
        let base = self.base_url.trim().trim_end_matches('/');
        let url = reqwest::Url::parse(base).map_err(|e| LlmError::Config {
            message: format!("base URL {base:?} is not a URL ({e}); e.g. http://127.0.0.1:8080"),
        })?;
        if url.scheme() != "http" && url.scheme() != "https" {
            return Err(LlmError::Config {
                message: format!("base URL {base:?} must start with http:// or https://"),
            });
        }
        Ok(if base.ends_with("/chat/completions") {
            base.to_string()
        } else if base.ends_with("/v1") {
            format!("{base}/chat/completions")
        } else {
            format!("{base}/v1/chat/completions")
        })
    }
}

/// A client of an OpenAI-compatible chat-completions server.
#[derive(Debug)]
pub struct OpenAiBackend {
    config: OpenAiConfig,
    url: String,
    client: reqwest::Client,
    runtime: Option<tokio::runtime::Runtime>,
    /// Set once the server refused `response_format`; later requests leave it out.
    schema_refused: AtomicBool,
}

impl OpenAiBackend {
    /// A backend for `config` (no request is sent yet).
    ///
    /// # Errors
    /// [`LlmError::Config`] for a bad URL or an API key that is not a valid header value.
    pub fn new(config: OpenAiConfig) -> Result<Self, LlmError> {
        let url = config.endpoint()?;
        let mut headers = reqwest::header::HeaderMap::new();
        if let Some(key) = &config.api_key {
            let mut v =
                reqwest::header::HeaderValue::from_str(&format!("Bearer {key}")).map_err(|_| {
                    LlmError::Config {
                        message: "the API key contains characters not allowed in an HTTP header"
                            .into(),
                    }
                })?;
            v.set_sensitive(true);
            headers.insert(reqwest::header::AUTHORIZATION, v);
        }
        let client = reqwest::Client::builder()
            .default_headers(headers)
            .connect_timeout(config.connect_timeout)
            .read_timeout(config.read_timeout)
            .timeout(config.request_timeout)
            .build()
            .map_err(|e| LlmError::Config {
                message: format!("cannot build the HTTP client: {e}"),
            })?;
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .thread_name("openai-http")
            .enable_all()
            .build()
            .map_err(|e| LlmError::Config {
                message: format!("cannot start the HTTP runtime: {e}"),
            })?;
        Ok(Self {
            config,
            url,
            client,
            runtime: Some(runtime),
            schema_refused: AtomicBool::new(false),
        })
    }

    /// The configuration it was built with.
    #[must_use]
    pub fn config(&self) -> &OpenAiConfig {
        &self.config
    }

    /// The URL requests go to.
    #[must_use]
    pub fn endpoint(&self) -> &str {
        &self.url
    }

    fn body(&self, req: &CompletionRequest, with_schema: bool) -> Value {
        let messages: Vec<Value> = req
            .messages
            .iter()
            .map(|m| json!({"role": m.role.as_str(), "content": m.content}))
            .collect();
        let mut body = json!({
            "model": self.config.model,
            "messages": messages,
            "temperature": req.temperature,
            "max_tokens": req.max_tokens,
            "stream": false,
        });
        if !req.stop.is_empty() {
            body["stop"] = json!(req.stop);
        }
        if let (Some(seed), true) = (req.seed, req.temperature > 0.0) {
            body["seed"] = json!(seed);
        }
        if with_schema {
            if let Some(schema) = &req.json_schema {
                body["response_format"] = json!({
                    "type": "json_schema",
                    "json_schema": {"name": "response", "schema": schema, "strict": true},
                });
            }
        }
        if self.config.send_grammar {
            if let Some(g) = &req.grammar {
                body["grammar"] = json!(g);
            }
        }
        body
    }

    fn backoff(&self, retry: u32) -> Duration {
        let exp = self
            .config
            .backoff_base
            .saturating_mul(1u32 << retry.saturating_sub(1).min(20));
        let capped = exp.min(self.config.backoff_max);
        // Jitter in [0.5, 1.0) of the delay, so that clients that failed together spread out.
        capped.mul_f64(0.5 + fastrand::f64() * 0.5)
    }

    async fn run(&self, req: &CompletionRequest) -> Result<Completion, LlmError> {
        let mut with_schema = self.config.use_json_schema
            && req.json_schema.is_some()
            && !self.schema_refused.load(Ordering::Relaxed);
        let mut attempts = 0u32;
        let mut retries = 0u32;
        loop {
            attempts += 1;
            let body = self.body(req, with_schema);
            let started = Instant::now();
            let sent = self.client.post(&self.url).json(&body).send().await;
            let resp = match sent {
                Ok(r) => r,
                Err(e) => {
                    let err = self.transport_error(&e, attempts);
                    if matches!(err, LlmError::Connect { .. }) && retries < self.config.max_retries
                    {
                        retries += 1;
                        let d = self.backoff(retries);
                        tracing::warn!(url = %self.url, attempt = attempts, delay_ms = d.as_millis() as u64, "connection failed, retrying: {e}");
                        tokio::time::sleep(d).await;
                        continue;
                    }
                    return Err(err);
                }
            };
            let status = resp.status();
            let retry_after = resp
                .headers()
                .get(reqwest::header::RETRY_AFTER)
                .and_then(|v| v.to_str().ok())
                .and_then(|v| v.trim().parse::<f64>().ok())
                .filter(|s| s.is_finite() && *s >= 0.0)
                .map(|s| Duration::from_secs_f64(s).min(self.config.retry_after_max));
            let text = match resp.text().await {
                Ok(t) => t,
                Err(e) => return Err(self.transport_error(&e, attempts)),
            };
            let elapsed_ms = started.elapsed().as_secs_f64() * 1e3;
            if status.is_success() {
                return parse_completion(&self.url, &text, elapsed_ms);
            }
            let message = error_message(&text);
            let code = status.as_u16();
            if code == 400 && with_schema && mentions_response_format(&text) {
                tracing::warn!(url = %self.url, "server refused response_format ({message}); retrying without it");
                self.schema_refused.store(true, Ordering::Relaxed);
                with_schema = false;
                continue;
            }
            if (code == 429 || status.is_server_error()) && retries < self.config.max_retries {
                retries += 1;
                let d = retry_after.unwrap_or_else(|| self.backoff(retries));
                tracing::warn!(url = %self.url, status = code, attempt = attempts, delay_ms = d.as_millis() as u64, "retrying: {message}");
                tokio::time::sleep(d).await;
                continue;
            }
            return Err(LlmError::Http {
                status: code,
                url: self.url.clone(),
                message,
                attempts,
            });
        }
    }

    fn transport_error(&self, e: &reqwest::Error, attempts: u32) -> LlmError {
        if e.is_connect() {
            LlmError::Connect {
                url: self.url.clone(),
                message: error_chain(e),
                attempts,
            }
        } else if e.is_timeout() {
            LlmError::Timeout {
                url: self.url.clone(),
                timeout_ms: u64::try_from(self.config.read_timeout.as_millis()).unwrap_or(u64::MAX),
                attempts,
            }
        } else {
            LlmError::Connect {
                url: self.url.clone(),
                message: error_chain(e),
                attempts,
            }
        }
    }
}

impl Drop for OpenAiBackend {
    fn drop(&mut self) {
        // Dropping a runtime inside another runtime panics; shutting it down in the
        // background never does.
        if let Some(rt) = self.runtime.take() {
            rt.shutdown_background();
        }
    }
}

impl LlmBackend for OpenAiBackend {
    fn name(&self) -> &str {
        "openai"
    }

    fn model(&self) -> &str {
        &self.config.model
    }

    fn complete(&self, req: &CompletionRequest) -> Result<Completion, LlmError> {
        req.validate()?;
        let rt = self.runtime.as_ref().ok_or_else(|| LlmError::Config {
            message: "the HTTP runtime has shut down".into(),
        })?;
        if tokio::runtime::Handle::try_current().is_ok() {
            // Inside someone else's runtime: block a helper thread, not theirs.
            std::thread::scope(|s| {
                s.spawn(|| rt.block_on(self.run(req)))
                    .join()
                    .unwrap_or_else(|_| {
                        Err(LlmError::Config {
                            message: "the HTTP helper thread panicked".into(),
                        })
                    })
            })
        } else {
            rt.block_on(self.run(req))
        }
    }
}

fn error_chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut src = e.source();
    while let Some(inner) = src {
        s.push_str(": ");
        s.push_str(&inner.to_string());
        src = inner.source();
    }
    s
}

/// Whether a 400's body refuses the `response_format` we sent: OpenAI-style servers name
/// the field; llama-server names the schema it cannot turn into a grammar ("... JSON
/// schema error at #/properties/a: cannot resolve $ref ...",
/// llm/tests/openai_llama_server.rs).
fn mentions_response_format(body: &str) -> bool {
    let b = body.to_ascii_lowercase();
    b.contains("response_format") || b.contains("json_schema") || b.contains("json schema")
}

/// The human message in an error body, whatever the server's dialect: OpenAI
/// `{"error":{"message","type","code":"..."}}`, llama-server `{"error":{"code":500,"message"}}`,
/// `{"error":"..."}`, `{"message":"..."}`, `{"detail":"..."}` (FastAPI), or plain text.
pub(crate) fn error_message(body: &str) -> String {
    let Ok(v) = serde_json::from_str::<Value>(body) else {
        let t = body.trim();
        return if t.is_empty() {
            "(empty body)".into()
        } else {
            snippet(t, 300)
        };
    };
    let scalar = |v: &Value| match v {
        Value::String(s) => Some(s.clone()),
        Value::Number(n) => Some(n.to_string()),
        _ => None,
    };
    let err = &v["error"];
    if let Some(s) = err.as_str() {
        return s.to_string();
    }
    if err.is_object() {
        let mut msg = err["message"]
            .as_str()
            .map(str::to_string)
            .unwrap_or_else(|| snippet(&err.to_string(), 300));
        let extra: Vec<String> = [("type", &err["type"]), ("code", &err["code"])]
            .iter()
            .filter_map(|(k, v)| scalar(v).map(|s| format!("{k} {s}")))
            .collect();
        if !extra.is_empty() {
            msg.push_str(&format!(" ({})", extra.join(", ")));
        }
        return msg;
    }
    for key in ["message", "detail"] {
        if let Some(s) = v[key].as_str() {
            return s.to_string();
        }
    }
    snippet(&v.to_string(), 300)
}

fn parse_completion(url: &str, body: &str, elapsed_ms: f64) -> Result<Completion, LlmError> {
    let malformed = |message: &str| LlmError::Malformed {
        url: url.to_string(),
        message: message.to_string(),
        body_start: snippet(body, 300),
    };
    let v: Value = serde_json::from_str(body).map_err(|e| malformed(&format!("not JSON ({e})")))?;
    let choice = v["choices"]
        .as_array()
        .and_then(|c| c.first())
        .ok_or_else(|| malformed("no choices[0] in the answer"))?;
    let content = &choice["message"]["content"];
    let text = match content {
        Value::String(s) => s.clone(),
        // Some servers send content as a list of parts.
        Value::Array(parts) => parts
            .iter()
            .filter_map(|p| p["text"].as_str())
            .collect::<Vec<_>>()
            .concat(),
        Value::Null => {
            tracing::warn!(url, finish_reason = %choice["finish_reason"], "answer has no message content");
            String::new()
        }
        _ => {
            return Err(malformed(
                "choices[0].message.content is neither text nor null",
            ))
        }
    };
    let finish_reason = match choice["finish_reason"].as_str() {
        Some("stop") | Some("eos") => FinishReason::Stop,
        Some("length") => FinishReason::Length,
        _ => FinishReason::Unknown,
    };
    let n = |v: &Value| v.as_u64().map(|x| u32::try_from(x).unwrap_or(u32::MAX));
    let usage = &v["usage"];
    let timings = &v["timings"]; // llama-server
    let prompt_tokens = n(&usage["prompt_tokens"])
        .or_else(|| {
            n(&timings["prompt_n"])
                .zip(n(&timings["cache_n"]))
                .map(|(a, b)| a + b)
        })
        .unwrap_or(0);
    let cached_prompt_tokens = n(&usage["prompt_tokens_details"]["cached_tokens"])
        .or_else(|| n(&timings["cache_n"]))
        .unwrap_or(0);
    let completion_tokens = n(&usage["completion_tokens"])
        .or_else(|| n(&timings["predicted_n"]))
        .unwrap_or(0);
    let (prompt_ms, generate_ms) = match (
        timings["prompt_ms"].as_f64(),
        timings["predicted_ms"].as_f64(),
    ) {
        (Some(p), Some(g)) => (p, g),
        _ => (0.0, elapsed_ms),
    };
    Ok(Completion {
        text,
        prompt_tokens,
        cached_prompt_tokens,
        completion_tokens,
        prompt_ms,
        generate_ms,
        finish_reason,
        forced_tokens: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endpoint_accepts_base_with_or_without_v1() {
        let e = |b: &str| OpenAiConfig::new(b, "m").endpoint();
        assert_eq!(
            e("http://127.0.0.1:8080").unwrap(),
            "http://127.0.0.1:8080/v1/chat/completions"
        );
        assert_eq!(
            e("https://api.openai.com/v1/").unwrap(),
            "https://api.openai.com/v1/chat/completions"
        );
        assert_eq!(
            e("http://h/v1/chat/completions").unwrap(),
            "http://h/v1/chat/completions"
        );
        assert!(matches!(e("localhost:8080"), Err(LlmError::Config { .. })));
        assert!(matches!(e("not a url"), Err(LlmError::Config { .. })));
    }

    #[test]
    fn from_lookup_needs_a_base_url_and_reads_key_and_model() {
        let err = OpenAiConfig::from_lookup(|_| None).unwrap_err();
        assert!(err.to_string().contains(ENV_BASE_URL), "{err}");
        let cfg = OpenAiConfig::from_lookup(|k| match k {
            ENV_BASE_URL => Some("http://x:1".into()),
            ENV_API_KEY => Some("sk-1".into()),
            _ => None,
        })
        .unwrap();
        assert_eq!(cfg.base_url, "http://x:1");
        assert_eq!(cfg.api_key.as_deref(), Some("sk-1"));
        assert_eq!(cfg.model, "default");
        assert!(!format!("{cfg:?}").contains("sk-1"), "key leaks into Debug");
    }

    #[test]
    fn a_seed_is_sent_only_with_a_temperature() {
        let b = OpenAiBackend::new(OpenAiConfig::new("http://127.0.0.1:1", "m")).unwrap();
        let mut req = CompletionRequest::new(vec![crate::ChatMessage::user("hi")], 8);
        req.seed = Some(7);
        assert!(b.body(&req, false).get("seed").is_none());
        req.temperature = 0.5;
        assert_eq!(b.body(&req, false)["seed"], 7);
    }

    #[test]
    fn error_messages_from_every_dialect() {
        assert_eq!(
            error_message(
                r#"{"error":{"message":"bad key","type":"invalid_request_error","code":"invalid_api_key"}}"#
            ),
            "bad key (type invalid_request_error, code invalid_api_key)"
        );
        assert_eq!(
            error_message(r#"{"error":{"code":500,"message":"boom","type":"server_error"}}"#),
            "boom (type server_error, code 500)"
        );
        assert_eq!(error_message(r#"{"error":"nope"}"#), "nope");
        assert_eq!(error_message(r#"{"detail":"Not Found"}"#), "Not Found");
        assert_eq!(error_message("Bad Gateway\n"), "Bad Gateway");
        assert_eq!(error_message(""), "(empty body)");
    }

    #[test]
    fn schema_refusals_are_recognised() {
        assert!(mentions_response_format(
            r#"{"error":{"message":"'response_format' of type 'json_schema' is not supported"}}"#
        ));
        assert!(mentions_response_format(
            r#"{"error":{"code":400,"message":"Unable to generate parser for this template. Automatic parser generation failed: JSON schema error at #/properties/a: cannot resolve $ref #/nope, nope not found","type":"invalid_request_error"}}"#
        ));
        assert!(!mentions_response_format(
            r#"{"error":{"code":400,"message":"request (8223 tokens) exceeds the available context size (2048 tokens), try increasing it","type":"exceed_context_size_error"}}"#
        ));
    }

    #[test]
    fn completion_parsing_is_lenient() {
        let c = parse_completion(
            "u",
            r#"{"choices":[{"message":{"role":"assistant","content":null},"finish_reason":"length"}]}"#,
            5.0,
        )
        .unwrap();
        assert_eq!(c.text, "");
        assert_eq!(c.finish_reason, FinishReason::Length);
        let c = parse_completion(
            "u",
            r#"{"choices":[{"message":{}}],"usage":{"prompt_tokens":7,"completion_tokens":2,"prompt_tokens_details":{"cached_tokens":4}}}"#,
            5.0,
        )
        .unwrap();
        assert_eq!(
            (c.prompt_tokens, c.cached_prompt_tokens, c.completion_tokens),
            (7, 4, 2)
        );
        let c = parse_completion(
            "u",
            r#"{"choices":[{"message":{"content":"hi"}}],"timings":{"prompt_n":3,"cache_n":10,"predicted_n":1,"prompt_ms":1.5,"predicted_ms":2.5}}"#,
            5.0,
        )
        .unwrap();
        assert_eq!(
            (c.prompt_tokens, c.cached_prompt_tokens, c.completion_tokens),
            (13, 10, 1)
        );
        assert_eq!((c.prompt_ms, c.generate_ms), (1.5, 2.5));
        assert!(matches!(
            parse_completion("u", r#"{"choices":[]}"#, 1.0),
            Err(LlmError::Malformed { .. })
        ));
    }
}
