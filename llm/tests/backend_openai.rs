//! The OpenAI-compatible backend against a real HTTP server on 127.0.0.1 (wiremock).

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test helpers

use std::time::{Duration, Instant};

use llm::{
    ChatMessage, CompletionRequest, FinishReason, LlmBackend, LlmError, OpenAiBackend, OpenAiConfig,
};
use serde_json::{json, Value};
use wiremock::matchers::{body_partial_json, header, method, path};
use wiremock::{Mock, MockBuilder, MockServer, ResponseTemplate};

fn rt() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap()
}

fn server(rt: &tokio::runtime::Runtime) -> MockServer {
    rt.block_on(MockServer::start())
}

fn mount(rt: &tokio::runtime::Runtime, server: &MockServer, mock: Mock) {
    rt.block_on(mock.mount(server));
}

fn bodies(rt: &tokio::runtime::Runtime, server: &MockServer) -> Vec<Value> {
    rt.block_on(server.received_requests())
        .unwrap_or_default()
        .iter()
        .map(|r| serde_json::from_slice(&r.body).unwrap())
        .collect()
}

fn ok_body(content: Value) -> Value {
    json!({
        "id": "chatcmpl-1",
        "object": "chat.completion",
        "choices": [{"index": 0, "message": {"role": "assistant", "content": content},
                     "finish_reason": "stop"}],
        "usage": {"prompt_tokens": 21, "completion_tokens": 5, "total_tokens": 26}
    })
}

fn fast_config(base: &str) -> OpenAiConfig {
    let mut cfg = OpenAiConfig::new(base, "test-model");
    cfg.backoff_base = Duration::from_millis(1);
    cfg.backoff_max = Duration::from_millis(5);
    cfg.read_timeout = Duration::from_secs(5);
    cfg
}

fn request() -> CompletionRequest {
    let mut req = CompletionRequest::new(
        vec![
            ChatMessage::system("You write robot plans."),
            ChatMessage::user("go to the sofa"),
        ],
        64,
    );
    req.temperature = 0.25;
    req.stop = vec!["```\n".into()];
    req
}

fn chat() -> MockBuilder {
    Mock::given(method("POST")).and(path("/v1/chat/completions"))
}

#[test]
fn success_sends_the_expected_body_and_parses_the_answer() {
    let rt = rt();
    let s = server(&rt);
    mount(
        &rt,
        &s,
        chat()
            .and(header("authorization", "Bearer sk-test"))
            .respond_with(
                ResponseTemplate::new(200)
                    .set_body_json(ok_body(json!("```rhai\nmove_to_object(\"sofa\");\n```"))),
            ),
    );
    let mut cfg = fast_config(&s.uri());
    cfg.api_key = Some("sk-test".into());
    let b = OpenAiBackend::new(cfg).unwrap();
    assert_eq!(b.name(), "openai");
    assert_eq!(b.model(), "test-model");
    let c = b.complete(&request()).unwrap();
    assert_eq!(c.text, "```rhai\nmove_to_object(\"sofa\");\n```");
    assert_eq!((c.prompt_tokens, c.completion_tokens), (21, 5));
    assert_eq!(c.finish_reason, FinishReason::Stop);
    assert!(c.generate_ms > 0.0);

    let sent = bodies(&rt, &s);
    assert_eq!(sent.len(), 1);
    let body = &sent[0];
    assert_eq!(body["model"], "test-model");
    assert_eq!(
        body["messages"],
        json!([{"role": "system", "content": "You write robot plans."},
               {"role": "user", "content": "go to the sofa"}])
    );
    assert_eq!(body["temperature"], 0.25);
    assert_eq!(body["max_tokens"], 64);
    assert_eq!(body["stop"], json!(["```\n"]));
    assert!(body.get("response_format").is_none(), "{body}");
    assert!(body.get("grammar").is_none(), "{body}");
}

#[test]
fn plain_text_answer_without_code_block_is_returned_as_is() {
    let rt = rt();
    let s = server(&rt);
    mount(
        &rt,
        &s,
        chat().respond_with(
            ResponseTemplate::new(200).set_body_json(ok_body(json!("Sure! Go to the sofa."))),
        ),
    );
    // Base URL given with /v1 and a trailing slash.
    let b = OpenAiBackend::new(fast_config(&format!("{}/v1/", s.uri()))).unwrap();
    assert_eq!(
        b.complete(&request()).unwrap().text,
        "Sure! Go to the sofa."
    );
}

#[test]
fn null_content_is_empty_text() {
    let rt = rt();
    let s = server(&rt);
    mount(
        &rt,
        &s,
        chat().respond_with(ResponseTemplate::new(200).set_body_json(json!({
            "choices": [{"message": {"role": "assistant", "content": null}, "finish_reason": "length"}]
        }))),
    );
    let c = OpenAiBackend::new(fast_config(&s.uri()))
        .unwrap()
        .complete(&request())
        .unwrap();
    assert_eq!(c.text, "");
    assert_eq!(c.finish_reason, FinishReason::Length);
}

#[test]
fn response_format_is_sent_when_asked_and_dropped_once_refused() {
    let rt = rt();
    let s = server(&rt);
    let schema = json!({"type": "object", "properties": {"plan": {"type": "string"}}});
    mount(
        &rt,
        &s,
        chat()
            .and(body_partial_json(
                json!({"response_format": {"type": "json_schema"}}),
            ))
            .respond_with(ResponseTemplate::new(400).set_body_json(json!({
                "error": {"message": "'response_format' of type 'json_schema' is not supported",
                          "type": "invalid_request_error", "code": "unsupported"}
            })))
            .with_priority(1),
    );
    mount(
        &rt,
        &s,
        chat()
            .respond_with(ResponseTemplate::new(200).set_body_json(ok_body(json!("{}"))))
            .with_priority(2),
    );
    let mut cfg = fast_config(&s.uri());
    cfg.use_json_schema = true;
    let b = OpenAiBackend::new(cfg).unwrap();
    let mut req = request();
    req.json_schema = Some(schema.clone());
    assert_eq!(b.complete(&req).unwrap().text, "{}");
    // Remembered: the next request goes without it straight away.
    assert_eq!(b.complete(&req).unwrap().text, "{}");

    let sent = bodies(&rt, &s);
    assert_eq!(sent.len(), 3);
    assert_eq!(
        sent[0]["response_format"],
        json!({"type": "json_schema",
               "json_schema": {"name": "response", "schema": schema, "strict": true}})
    );
    assert!(sent[1].get("response_format").is_none());
    assert!(sent[2].get("response_format").is_none());
}

#[test]
fn grammar_is_sent_only_when_configured() {
    let rt = rt();
    let s = server(&rt);
    mount(
        &rt,
        &s,
        chat().respond_with(ResponseTemplate::new(200).set_body_json(ok_body(json!("yes")))),
    );
    let mut req = request();
    req.grammar = Some(r#"root ::= "yes" | "no""#.into());
    OpenAiBackend::new(fast_config(&s.uri()))
        .unwrap()
        .complete(&req)
        .unwrap();
    let mut cfg = fast_config(&s.uri());
    cfg.send_grammar = true;
    OpenAiBackend::new(cfg).unwrap().complete(&req).unwrap();
    let sent = bodies(&rt, &s);
    assert!(sent[0].get("grammar").is_none());
    assert_eq!(sent[1]["grammar"], r#"root ::= "yes" | "no""#);
}

#[test]
fn rate_limit_honours_retry_after_then_succeeds() {
    let rt = rt();
    let s = server(&rt);
    mount(
        &rt,
        &s,
        chat()
            .respond_with(
                ResponseTemplate::new(429)
                    .insert_header("retry-after", "1")
                    .set_body_json(json!({"error": {"message": "Rate limit reached", "type": "requests", "code": "rate_limit_exceeded"}})),
            )
            .up_to_n_times(1)
            .with_priority(1),
    );
    mount(
        &rt,
        &s,
        chat()
            .respond_with(ResponseTemplate::new(200).set_body_json(ok_body(json!("done"))))
            .with_priority(2),
    );
    let b = OpenAiBackend::new(fast_config(&s.uri())).unwrap();
    let t = Instant::now();
    let c = b.complete(&request()).unwrap();
    let waited = t.elapsed();
    assert_eq!(c.text, "done");
    assert_eq!(bodies(&rt, &s).len(), 2);
    assert!(
        waited >= Duration::from_millis(950),
        "Retry-After: 1 not honoured (waited {waited:?})"
    );
}

#[test]
fn retry_after_is_bounded() {
    let rt = rt();
    let s = server(&rt);
    mount(
        &rt,
        &s,
        chat().respond_with(
            ResponseTemplate::new(503)
                .insert_header("retry-after", "3600")
                .set_body_string("Service Unavailable"),
        ),
    );
    let mut cfg = fast_config(&s.uri());
    cfg.max_retries = 1;
    cfg.retry_after_max = Duration::from_millis(200);
    let t = Instant::now();
    let err = OpenAiBackend::new(cfg)
        .unwrap()
        .complete(&request())
        .unwrap_err();
    assert!(t.elapsed() < Duration::from_secs(3), "{:?}", t.elapsed());
    match err {
        LlmError::Http {
            status,
            attempts,
            message,
            ..
        } => {
            assert_eq!((status, attempts), (503, 2));
            assert_eq!(message, "Service Unavailable");
        }
        other => panic!("expected Http, got {other}"),
    }
}

#[test]
fn repeated_server_errors_give_up_after_the_retry_budget() {
    let rt = rt();
    let s = server(&rt);
    // llama-server's error shape: numeric code.
    mount(
        &rt,
        &s,
        chat().respond_with(ResponseTemplate::new(500).set_body_json(json!({
            "error": {"code": 500, "message": "failed to decode the batch", "type": "server_error"}
        }))),
    );
    let mut cfg = fast_config(&s.uri());
    cfg.max_retries = 2;
    let err = OpenAiBackend::new(cfg)
        .unwrap()
        .complete(&request())
        .unwrap_err();
    let text = err.to_string();
    match err {
        LlmError::Http {
            status,
            attempts,
            message,
            ..
        } => {
            assert_eq!(status, 500);
            assert_eq!(attempts, 3);
            assert_eq!(
                message,
                "failed to decode the batch (type server_error, code 500)"
            );
        }
        other => panic!("expected Http, got {other}"),
    }
    assert!(text.contains("after 3 attempt"), "{text}");
    assert_eq!(bodies(&rt, &s).len(), 3);
}

#[test]
fn client_errors_are_not_retried() {
    let rt = rt();
    let s = server(&rt);
    mount(
        &rt,
        &s,
        chat().respond_with(ResponseTemplate::new(401).set_body_json(json!({
            "error": {"message": "Incorrect API key provided", "type": "invalid_request_error",
                      "code": "invalid_api_key"}
        }))),
    );
    let err = OpenAiBackend::new(fast_config(&s.uri()))
        .unwrap()
        .complete(&request())
        .unwrap_err();
    match err {
        LlmError::Http {
            status,
            attempts,
            message,
            ..
        } => {
            assert_eq!((status, attempts), (401, 1));
            assert!(
                message.starts_with("Incorrect API key provided"),
                "{message}"
            );
            assert!(message.contains("invalid_api_key"), "{message}");
        }
        other => panic!("expected Http, got {other}"),
    }
    assert_eq!(bodies(&rt, &s).len(), 1);
}

#[test]
fn slow_server_is_a_timeout_and_not_retried() {
    let rt = rt();
    let s = server(&rt);
    mount(
        &rt,
        &s,
        chat().respond_with(
            ResponseTemplate::new(200)
                .set_body_json(ok_body(json!("late")))
                .set_delay(Duration::from_secs(3)),
        ),
    );
    let mut cfg = fast_config(&s.uri());
    cfg.read_timeout = Duration::from_millis(300);
    let t = Instant::now();
    let err = OpenAiBackend::new(cfg)
        .unwrap()
        .complete(&request())
        .unwrap_err();
    assert!(t.elapsed() < Duration::from_secs(2), "{:?}", t.elapsed());
    match err {
        LlmError::Timeout {
            timeout_ms,
            attempts,
            ..
        } => assert_eq!((timeout_ms, attempts), (300, 1)),
        other => panic!("expected Timeout, got {other}"),
    }
}

#[test]
fn malformed_bodies_are_reported() {
    let rt = rt();
    let s = server(&rt);
    mount(
        &rt,
        &s,
        chat()
            .and(body_partial_json(json!({"max_tokens": 1})))
            .respond_with(
                ResponseTemplate::new(200).set_body_raw("{\"choices\": [", "application/json"),
            ),
    );
    mount(
        &rt,
        &s,
        chat()
            .and(body_partial_json(json!({"max_tokens": 2})))
            .respond_with(
                ResponseTemplate::new(200).set_body_json(json!({"object": "list", "data": []})),
            ),
    );
    let b = OpenAiBackend::new(fast_config(&s.uri())).unwrap();
    let mut req = request();
    req.max_tokens = 1;
    match b.complete(&req).unwrap_err() {
        LlmError::Malformed {
            message,
            body_start,
            ..
        } => {
            assert!(message.contains("not JSON"), "{message}");
            assert_eq!(body_start, "{\"choices\": [");
        }
        other => panic!("expected Malformed, got {other}"),
    }
    req.max_tokens = 2;
    match b.complete(&req).unwrap_err() {
        LlmError::Malformed { message, .. } => assert!(message.contains("choices"), "{message}"),
        other => panic!("expected Malformed, got {other}"),
    }
}

#[test]
fn unreachable_server_is_a_connect_error_after_retries() {
    // A port nobody listens on: bind, note it, close.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let mut cfg = fast_config(&format!("http://127.0.0.1:{port}"));
    cfg.max_retries = 2;
    let err = OpenAiBackend::new(cfg)
        .unwrap()
        .complete(&request())
        .unwrap_err();
    match &err {
        LlmError::Connect { attempts, url, .. } => {
            assert_eq!(*attempts, 3);
            assert_eq!(url, &format!("http://127.0.0.1:{port}/v1/chat/completions"));
        }
        other => panic!("expected Connect, got {other}"),
    }
    assert!(err.to_string().contains("is the server running"), "{err}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn works_when_called_inside_an_async_runtime() {
    let s = MockServer::start().await;
    chat()
        .respond_with(ResponseTemplate::new(200).set_body_json(ok_body(json!("from async"))))
        .mount(&s)
        .await;
    let b = OpenAiBackend::new(fast_config(&s.uri())).unwrap();
    assert_eq!(b.complete(&request()).unwrap().text, "from async");
    drop(b); // dropping inside a runtime must not panic either
}
