//! The OpenAI-compatible backend against a real llama-server on 127.0.0.1: llama.cpp's own
//! server, built by `scripts/llama-server.sh` from the llama.cpp sources of the
//! llama-cpp-python sdist, running the SmolLM2-135M-Instruct GGUF the other tests use.
//!
//! `backend_openai.rs` covers errors and retries against wiremock; this file checks what
//! only a real server shows: that the fields we send mean what we think (stop strings,
//! `max_tokens`, a GBNF `grammar`, `response_format: json_schema`) and that we read what
//! it answers (text, usage, cached tokens, timings, finish reasons, its error bodies).
//!
//! Each test starts its own server on a free port (a guard kills it on drop, a failing
//! test included) and a lock runs them one at a time. Every wait has a timeout.
//!
//! The server binary comes from `scripts/llama-server.sh`, which this runs once per test
//! binary: it prints the path of the binary it built earlier straight away
//! (`${IVLMAP_LLAMA_SERVER:-~/.cache/ivlmap/llama-server}/bin/llama-server`), or builds it
//! first (once, about 8 minutes on 2 cores; `.ci/run` builds it in a step of its own before
//! `cargo test`). When the script fails the tests fail and say so. Without the model they
//! skip, like `backend_llama.rs`.
//!
//! ```sh
//! scripts/llama-server.sh && cargo test --workspace --test openai_llama_server
//! ```

#![cfg(feature = "openai")]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test helpers

use std::fs::File;
use std::io::{Read, Write};
use std::net::{Ipv4Addr, SocketAddr, TcpListener, TcpStream};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::{Mutex, MutexGuard, OnceLock};
use std::time::{Duration, Instant};

use ivlmap_tests::{model, repo, SMOL};
use llm::{
    ChatMessage, CompletionRequest, FinishReason, LlmBackend, LlmError, OpenAiBackend, OpenAiConfig,
};
use serde_json::{json, Value};

/// The longest a server may take to load the model and answer `/health` with 200.
const START_TIMEOUT: Duration = Duration::from_secs(120);
/// The longest `scripts/llama-server.sh` may take (a first build on a loaded 2-core
/// machine took 12 minutes, the sdist download 2 more).
const BUILD_TIMEOUT: Duration = Duration::from_secs(45 * 60);
/// Context window of the server (one slot): small, so that overflowing it is cheap.
const N_CTX: u32 = 2048;

fn serial() -> MutexGuard<'static, ()> {
    static LOCK: Mutex<()> = Mutex::new(());
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

/// The llama-server binary, from `scripts/llama-server.sh` (run once per test binary).
fn server_binary() -> PathBuf {
    static BIN: OnceLock<Result<PathBuf, String>> = OnceLock::new();
    BIN.get_or_init(build_server)
        .clone()
        .unwrap_or_else(|e| panic!("{e}"))
}

/// Runs `scripts/llama-server.sh` (instant when the binary is there, a build otherwise)
/// and returns the path it prints last.
fn build_server() -> Result<PathBuf, String> {
    let script = repo().join("scripts").join("llama-server.sh");
    let dir = tempfile::tempdir().map_err(|e| format!("a temporary folder: {e}"))?;
    let (out_path, err_path) = (dir.path().join("stdout"), dir.path().join("stderr"));
    let out = File::create(&out_path).map_err(|e| e.to_string())?;
    let err = File::create(&err_path).map_err(|e| e.to_string())?;
    let mut child = Command::new("bash")
        .arg(&script)
        .stdin(Stdio::null())
        .stdout(out)
        .stderr(err)
        .process_group(0) // so that a timeout stops cmake and the compilers too
        .spawn()
        .map_err(|e| format!("cannot run {}: {e}", script.display()))?;
    let deadline = Instant::now() + BUILD_TIMEOUT;
    let status: Option<ExitStatus> = loop {
        match child.try_wait() {
            Ok(Some(status)) => break Some(status),
            Ok(None) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(200)),
            _ => {
                let _ = Command::new("kill")
                    .args(["-TERM", "--", &format!("-{}", child.id())])
                    .status();
                let _ = child.kill();
                let _ = child.wait();
                break None;
            }
        }
    };
    let stdout = std::fs::read_to_string(&out_path).unwrap_or_default();
    let stderr = std::fs::read_to_string(&err_path).unwrap_or_default();
    let tail = |t: &str| {
        let lines: Vec<&str> = t.lines().collect();
        lines[lines.len().saturating_sub(30)..].join("\n")
    };
    let failed = |why: String| {
        format!(
            "no llama-server for the openai backend's real-server tests: {} {why}; run it by \
             hand to see why (it builds llama.cpp's llama-server once into \
             $IVLMAP_LLAMA_SERVER, default ~/.cache/ivlmap/llama-server). Its output ends:\n{}",
            script.display(),
            tail(&stderr)
        )
    };
    match status {
        None => return Err(failed(format!("took longer than {BUILD_TIMEOUT:?}"))),
        Some(s) if !s.success() => return Err(failed(format!("failed ({s})"))),
        Some(_) => {}
    }
    let bin = PathBuf::from(stdout.lines().last().unwrap_or("").trim());
    if bin.is_file() {
        Ok(bin)
    } else {
        Err(failed(format!(
            "printed {:?}, which is not a file",
            bin.display()
        )))
    }
}

/// A llama-server child process on 127.0.0.1; killed (and reaped) on drop.
struct LlamaServer {
    child: Child,
    port: u16,
    log: PathBuf,
    _dir: tempfile::TempDir,
}

impl LlamaServer {
    /// Starts the server with the SmolLM2 model and waits until `/health` says ok; `None`
    /// (the test skips) when the model has not been fetched.
    fn start() -> Option<LlamaServer> {
        let model = model(SMOL)?;
        let bin = server_binary();
        // A free port can be taken between our probe and the server's bind: try again.
        let mut last_error = String::new();
        for _ in 0..3 {
            match Self::try_start(&bin, &model) {
                Ok(s) => return Some(s),
                Err(e) => last_error = e,
            }
        }
        panic!("llama-server did not start: {last_error}");
    }

    fn try_start(bin: &Path, model: &Path) -> Result<LlamaServer, String> {
        let port = free_port();
        let dir = tempfile::tempdir().expect("a temporary folder");
        let log = dir.path().join("llama-server.log");
        let out = File::create(&log).expect("the server log file");
        let err = out.try_clone().expect("the server log file");
        let mut cmd = Command::new(bin);
        cmd.arg("-m")
            .arg(model)
            .args(["--host", "127.0.0.1", "--port", &port.to_string()])
            .args([
                "-c",
                &N_CTX.to_string(),
                "-np",
                "1",
                "-t",
                "2",
                "--no-webui",
            ])
            .stdin(Stdio::null())
            .stdout(out)
            .stderr(err);
        // LLAMA_ARG_* variables would override these flags.
        for (k, _) in std::env::vars_os() {
            if k.to_string_lossy().starts_with("LLAMA_ARG_") {
                cmd.env_remove(k);
            }
        }
        if std::env::var_os("OMP_WAIT_POLICY").is_none() {
            cmd.env("OMP_WAIT_POLICY", "passive");
        }
        let child = cmd
            .spawn()
            .map_err(|e| format!("cannot run {}: {e}", bin.display()))?;
        let mut server = LlamaServer {
            child,
            port,
            log,
            _dir: dir,
        };
        let deadline = Instant::now() + START_TIMEOUT;
        loop {
            if let Ok(Some(status)) = server.child.try_wait() {
                return Err(format!(
                    "{} exited with {status} on port {port}; its log ends:\n{}",
                    bin.display(),
                    server.log_tail()
                ));
            }
            if let Some((200, _)) = http_get(port, "/health", Duration::from_secs(2)) {
                return Ok(server);
            }
            if Instant::now() > deadline {
                return Err(format!(
                    "no 200 from http://127.0.0.1:{port}/health within {START_TIMEOUT:?}; \
                     its log ends:\n{}",
                    server.log_tail()
                ));
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    fn base_url(&self) -> String {
        format!("http://127.0.0.1:{}", self.port)
    }

    fn log_tail(&self) -> String {
        let text = std::fs::read_to_string(&self.log).unwrap_or_default();
        let lines: Vec<&str> = text.lines().collect();
        lines[lines.len().saturating_sub(30)..].join("\n")
    }

    /// A backend for this server: short timeouts, no retries unless a test sets them.
    fn backend(&self, set: impl FnOnce(&mut OpenAiConfig)) -> OpenAiBackend {
        let mut cfg = OpenAiConfig::new(self.base_url(), "smollm2-135m");
        cfg.connect_timeout = Duration::from_secs(5);
        cfg.read_timeout = Duration::from_secs(60);
        cfg.request_timeout = Duration::from_secs(120);
        cfg.max_retries = 0;
        cfg.backoff_base = Duration::from_millis(10);
        cfg.backoff_max = Duration::from_millis(50);
        set(&mut cfg);
        OpenAiBackend::new(cfg).unwrap()
    }

    /// `b.complete(req)`, failing with the server's log on an error.
    fn complete(&self, b: &OpenAiBackend, req: &CompletionRequest) -> llm::Completion {
        b.complete(req)
            .unwrap_or_else(|e| panic!("{e}\nllama-server's log ends:\n{}", self.log_tail()))
    }
}

impl Drop for LlamaServer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn free_port() -> u16 {
    TcpListener::bind((Ipv4Addr::LOCALHOST, 0))
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free port on 127.0.0.1")
}

/// A plain HTTP/1.1 GET: (status, body), `None` when nothing answers in `timeout`.
fn http_get(port: u16, path: &str, timeout: Duration) -> Option<(u16, String)> {
    let addr = SocketAddr::from((Ipv4Addr::LOCALHOST, port));
    let mut s = TcpStream::connect_timeout(&addr, timeout).ok()?;
    s.set_read_timeout(Some(timeout)).ok()?;
    s.set_write_timeout(Some(timeout)).ok()?;
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n\r\n"
    )
    .ok()?;
    let mut text = String::new();
    s.read_to_string(&mut text).ok()?;
    let status = text.split_whitespace().nth(1)?.parse().ok()?;
    let body = text.split_once("\r\n\r\n").map_or("", |(_, b)| b);
    Some((status, body.to_string()))
}

fn ask(user: &str, max_tokens: u32) -> CompletionRequest {
    CompletionRequest::new(
        vec![
            ChatMessage::system("You are a helpful assistant. Answer briefly."),
            ChatMessage::user(user),
        ],
        max_tokens,
    )
}

#[test]
fn chat_completion_returns_text_usage_and_timings() {
    let _g = serial();
    let Some(server) = LlamaServer::start() else {
        return;
    };
    let (_, health) = http_get(server.port, "/health", Duration::from_secs(5)).unwrap();
    assert!(health.contains("ok"), "{health}");
    // The base URL as the README gives it, with /v1.
    let b = server.backend(|c| c.base_url = format!("{}/v1", server.base_url()));
    assert_eq!(b.name(), "openai");
    assert_eq!(b.model(), "smollm2-135m");
    let req = ask("What is the capital of France?", 24);
    let c = server.complete(&b, &req);
    assert!(!c.text.trim().is_empty(), "{c:?}");
    assert!(
        c.prompt_tokens >= 10,
        "the chat template alone is longer: {c:?}"
    );
    assert!((1..=24).contains(&c.completion_tokens), "{c:?}");
    match c.finish_reason {
        FinishReason::Stop => {}
        FinishReason::Length => assert_eq!(c.completion_tokens, 24, "{c:?}"),
        FinishReason::Unknown => panic!("llama-server names its finish reason: {c:?}"),
    }
    // llama-server's own timings, not our wall clock.
    assert!(c.prompt_ms > 0.0 && c.generate_ms > 0.0, "{c:?}");
    assert_eq!(c.forced_tokens, 0);

    // The same prompt again: llama-server reuses its KV cache and says so.
    let again = server.complete(&b, &req);
    assert_eq!(again.prompt_tokens, c.prompt_tokens, "{again:?}");
    assert!(
        again.cached_prompt_tokens > 0 && again.cached_prompt_tokens <= again.prompt_tokens,
        "{again:?}"
    );
}

#[test]
fn stop_strings_end_the_answer_and_are_left_out() {
    let _g = serial();
    let Some(server) = LlamaServer::start() else {
        return;
    };
    // A grammar fixes the text, so that where the stop strings fall does not depend on
    // what the model would say.
    let b = server.backend(|c| c.send_grammar = true);
    let mut req = ask("Say four words.", 32);
    req.grammar = Some(r#"root ::= "alpha beta gamma delta epsilon""#.into());
    let full = server.complete(&b, &req);
    assert_eq!(full.text, "alpha beta gamma delta epsilon", "{full:?}");
    assert_eq!(full.finish_reason, FinishReason::Stop);

    req.stop = vec!["delta".into()];
    let c = server.complete(&b, &req);
    assert_eq!(c.text, "alpha beta gamma ", "{c:?}");
    assert_eq!(c.finish_reason, FinishReason::Stop);
    assert!(c.completion_tokens < full.completion_tokens, "{c:?}");

    // The first of several stop strings to appear ends it.
    req.stop = vec!["epsilon".into(), "beta".into()];
    let c = server.complete(&b, &req);
    assert_eq!(c.text, "alpha ", "{c:?}");
    assert_eq!(c.finish_reason, FinishReason::Stop);
}

#[test]
fn gbnf_grammar_holds_the_answer_only_when_sent() {
    let _g = serial();
    let Some(server) = LlamaServer::start() else {
        return;
    };
    let with = server.backend(|c| c.send_grammar = true);
    let without = server.backend(|_| {});
    for q in [
        "Is the sky green?",
        "Is water wet?",
        "Tell me about the planet Mars.",
    ] {
        let mut req = ask(q, 8);
        req.grammar = Some(r#"root ::= "yes" | "no""#.into());
        let c = server.complete(&with, &req);
        assert!(c.text == "yes" || c.text == "no", "{q}: {c:?}");
        assert_eq!(c.finish_reason, FinishReason::Stop, "{q}: {c:?}");
    }
    // A word the model would never answer with on its own: only the grammar puts it there.
    let mut req = ask("Say hello to the robot.", 12);
    req.grammar = Some(r#"root ::= "zebra" [0-9] [0-9]"#.into());
    let held = server.complete(&with, &req);
    assert!(
        held.text.len() == 7
            && held.text.starts_with("zebra")
            && held.text[5..].bytes().all(|b| b.is_ascii_digit()),
        "{held:?}"
    );
    let free = server.complete(&without, &req);
    assert!(
        !free.text.starts_with("zebra"),
        "grammar sent anyway? {free:?}"
    );

    // A grammar the server cannot parse is its 400, reported and not retried.
    req.grammar = Some(r#"root ::= "zebra" ("#.into());
    let retrying = server.backend(|c| {
        c.send_grammar = true;
        c.max_retries = 3;
    });
    match retrying.complete(&req) {
        Err(LlmError::Http {
            status: 400,
            attempts: 1,
            message,
            ..
        }) => assert!(message.contains("grammar"), "{message}"),
        other => panic!("expected HTTP 400 after one attempt, got {other:?}"),
    }
}

fn tuple_schema() -> Value {
    // Property names the model would not write unprompted: only the schema yields them.
    json!({
        "type": "object",
        "properties": {
            "target_obj": {"type": "string", "enum": ["sofa", "table", "chair"]},
            "target_k": {"type": "integer", "minimum": 1, "maximum": 9}
        },
        "required": ["target_obj", "target_k"],
        "additionalProperties": false
    })
}

/// The answer as the two fields of [`tuple_schema`], or why not.
fn schema_answer(text: &str) -> Result<(String, i64), String> {
    let v: Value = serde_json::from_str(text).map_err(|e| format!("not JSON ({e}): {text:?}"))?;
    let obj = v.as_object().ok_or(format!("not an object: {text:?}"))?;
    let name = obj.get("target_obj").and_then(Value::as_str);
    let k = obj.get("target_k").and_then(Value::as_i64);
    match (name, k) {
        (Some(name), Some(k))
            if obj.len() == 2
                && ["sofa", "table", "chair"].contains(&name)
                && (1..=9).contains(&k) =>
        {
            Ok((name.to_string(), k))
        }
        _ => Err(format!("does not match the schema: {text:?}")),
    }
}

fn tuple_request() -> CompletionRequest {
    let mut req = ask(
        "Which object does 'go to the second sofa' name, and which one of them? Answer in JSON.",
        64,
    );
    req.json_schema = Some(tuple_schema());
    req
}

#[test]
fn json_schema_response_format_yields_matching_json() {
    let _g = serial();
    let Some(server) = LlamaServer::start() else {
        return;
    };
    let b = server.backend(|c| c.use_json_schema = true);
    let c = server.complete(&b, &tuple_request());
    schema_answer(&c.text).unwrap_or_else(|e| panic!("{e}: {c:?}"));
    assert_eq!(c.finish_reason, FinishReason::Stop, "{c:?}");

    // Off (the default), the schema stays home: the model's own answer.
    let off = server.complete(&server.backend(|_| {}), &tuple_request());
    assert!(!off.text.contains("target_k"), "{off:?}");

    // A request with both a schema and a grammar, both sent: llama-server holds the
    // answer to the schema and drops the grammar.
    let both = server.backend(|c| {
        c.use_json_schema = true;
        c.send_grammar = true;
    });
    let mut req = tuple_request();
    req.grammar = Some(r#"root ::= "zebra""#.into());
    let c = server.complete(&both, &req);
    schema_answer(&c.text).unwrap_or_else(|e| panic!("{e}: {c:?}"));
}

#[test]
fn a_schema_the_server_refuses_falls_back_to_no_response_format() {
    let _g = serial();
    let Some(server) = LlamaServer::start() else {
        return;
    };
    let b = server.backend(|c| c.use_json_schema = true);
    // llama-server cannot turn this schema into a grammar and answers 400 ("JSON schema
    // error at #/properties/a: cannot resolve $ref"): the backend asks again without
    // response_format.
    let mut req = ask("Name a colour.", 8);
    req.json_schema = Some(json!({
        "type": "object",
        "properties": {"a": {"$ref": "#/definitions/missing"}},
        "required": ["a"]
    }));
    let c = server.complete(&b, &req);
    assert!(c.completion_tokens > 0, "{c:?}");
    // Remembered: a later request goes without response_format straight away, even with
    // a schema the server would take.
    let later = server.complete(&b, &tuple_request());
    assert!(schema_answer(&later.text).is_err(), "{later:?}");
    // A fresh backend sends it again.
    let fresh = server.backend(|c| c.use_json_schema = true);
    let c = server.complete(&fresh, &tuple_request());
    schema_answer(&c.text).unwrap_or_else(|e| panic!("{e}: {c:?}"));
}

#[test]
fn max_tokens_cuts_the_answer_with_finish_reason_length() {
    let _g = serial();
    let Some(server) = LlamaServer::start() else {
        return;
    };
    let b = server.backend(|_| {});
    let c = server.complete(&b, &ask("Write a long story about a robot.", 5));
    assert_eq!(c.finish_reason, FinishReason::Length, "{c:?}");
    assert_eq!(c.completion_tokens, 5, "{c:?}");
    assert!(!c.text.is_empty(), "{c:?}");
}

#[test]
fn a_prompt_over_the_context_window_is_an_http_error_and_not_retried() {
    let _g = serial();
    let Some(server) = LlamaServer::start() else {
        return;
    };
    let b = server.backend(|c| c.max_retries = 3);
    let long = "the robot goes to the sofa and ".repeat(N_CTX as usize / 4); // ~4k tokens
    let err = b.complete(&ask(&long, 8)).unwrap_err();
    match &err {
        LlmError::Http {
            status,
            attempts,
            message,
            ..
        } => {
            assert_eq!((*status, *attempts), (400, 1), "{err}");
            assert!(message.contains("context"), "{err}");
        }
        other => panic!("expected an HTTP error, got {other}"),
    }
    // The server is still serving.
    assert!(!server.complete(&b, &ask("Hi", 4)).text.is_empty());
}

#[test]
fn works_when_called_inside_a_tokio_runtime() {
    let _g = serial();
    let Some(server) = LlamaServer::start() else {
        return;
    };
    let b = server.backend(|_| {});
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    let c = rt
        .block_on(async { b.complete(&ask("Name a colour.", 6)) })
        .unwrap_or_else(|e| panic!("{e}\n{}", server.log_tail()));
    assert!(c.completion_tokens > 0, "{c:?}");
}

#[test]
fn a_stopped_server_is_a_connect_error_after_the_retries() {
    let _g = serial();
    let Some(server) = LlamaServer::start() else {
        return;
    };
    let b = server.backend(|c| c.max_retries = 2);
    assert!(server.complete(&b, &ask("Hi", 2)).completion_tokens > 0);
    drop(server); // kills it; nothing listens on the port any more
    let err = b.complete(&ask("Hi", 2)).unwrap_err();
    assert!(
        matches!(err, LlmError::Connect { attempts: 3, .. }),
        "expected a connect error after 3 attempts, got {err}"
    );
}
