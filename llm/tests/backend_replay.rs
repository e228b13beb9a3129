//! Cassettes: record from a real backend (an OpenAI-compatible server on 127.0.0.1, or the
//! local SmolLM2 when present), replay from the file, and report misses and bad lines.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test helpers

use std::path::PathBuf;

use llm::replay::CassetteRecord;
use llm::{
    ChatMessage, CompletionRequest, LlamaCppBackend, LlamaCppConfig, LlmBackend, LlmError,
    OpenAiBackend, OpenAiConfig, Recording, ReplayBackend,
};
use serde_json::json;
use wiremock::matchers::{body_string_contains, method};
use wiremock::{Mock, MockServer, ResponseTemplate};

fn req(user: &str) -> CompletionRequest {
    CompletionRequest::new(
        vec![
            ChatMessage::system("Extract tuples."),
            ChatMessage::user(user),
        ],
        32,
    )
}

fn answer(text: &str) -> serde_json::Value {
    json!({"choices": [{"message": {"content": text}, "finish_reason": "stop"}],
           "usage": {"prompt_tokens": 10, "completion_tokens": 3}})
}

/// Records two exchanges with a real HTTP server, then replays them without it.
#[test]
fn record_then_replay_round_trip() {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    let server = rt.block_on(MockServer::start());
    for (user, text) in [
        ("go to the sofa", "[(\"sofa\")]"),
        ("go to the bed", "[(\"bed\")]"),
    ] {
        rt.block_on(
            Mock::given(method("POST"))
                .and(body_string_contains(user))
                .respond_with(ResponseTemplate::new(200).set_body_json(answer(text)))
                .mount(&server),
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let cassette = dir.path().join("run.jsonl");
    {
        let live = OpenAiBackend::new(OpenAiConfig::new(server.uri(), "remote-model")).unwrap();
        let rec = Recording::new(live, &cassette).unwrap();
        assert_eq!(
            rec.complete(&req("go to the sofa")).unwrap().text,
            "[(\"sofa\")]"
        );
        assert_eq!(
            rec.complete(&req("go to the bed")).unwrap().text,
            "[(\"bed\")]"
        );
    }
    drop(server);

    let text = std::fs::read_to_string(&cassette).unwrap();
    assert_eq!(text.lines().count(), 2);
    let first: CassetteRecord = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    assert_eq!(first.backend, "openai");
    assert_eq!(first.model, "remote-model");
    assert_eq!(first.request, req("go to the sofa"));

    let replay = ReplayBackend::open(&cassette).unwrap();
    assert_eq!(replay.len(), 2);
    let asked: Vec<&CompletionRequest> = replay.records().map(|r| &r.request).collect();
    assert_eq!(asked, [&req("go to the sofa"), &req("go to the bed")]);
    assert_eq!(replay.name(), "replay");
    assert_eq!(replay.model(), "remote-model");
    let c = replay.complete(&req("go to the bed")).unwrap();
    assert_eq!(c.text, "[(\"bed\")]");
    assert_eq!((c.prompt_tokens, c.completion_tokens), (10, 3));
    assert_eq!(
        replay.complete(&req("go to the sofa")).unwrap().text,
        "[(\"sofa\")]"
    );
}

/// A recording from the local model replays the same text.
#[test]
fn records_the_local_model_when_present() {
    let dir = std::env::var_os("IVLMAP_MODELS")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(std::env::var_os("HOME").unwrap_or_default()).join(".cache/ivlmap/models")
        });
    let model = dir.join("SmolLM2-135M-Instruct.Q4_1.gguf");
    if !model.is_file() {
        eprintln!(
            "SKIPPED: {} is absent; run scripts/fetch-models.sh",
            model.display()
        );
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let cassette = tmp.path().join("llama.jsonl");
    let mut r = req("go to the third yellow table");
    r.grammar = Some(r#"root ::= "[(" [a-z ]+ ")]""#.into());
    let live_text = {
        let rec = Recording::new(
            LlamaCppBackend::new(LlamaCppConfig::new(&model)).unwrap(),
            &cassette,
        )
        .unwrap();
        rec.complete(&r).unwrap().text
    };
    let replay = ReplayBackend::open(&cassette).unwrap();
    assert_eq!(replay.model(), "SmolLM2-135M-Instruct.Q4_1.gguf");
    assert_eq!(replay.complete(&r).unwrap().text, live_text);
    // The grammar is part of the key.
    r.grammar = None;
    let err = replay.complete(&r).unwrap_err();
    assert!(err.to_string().contains("grammar differs"), "{err}");
}

fn write_cassette(records: &[(CompletionRequest, &str)]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.jsonl");
    let mut s = String::new();
    for (request, text) in records {
        let rec = CassetteRecord {
            backend: "llama".into(),
            model: "m.gguf".into(),
            request: request.clone(),
            response: llm::Completion {
                text: (*text).into(),
                prompt_tokens: 5,
                cached_prompt_tokens: 0,
                completion_tokens: 2,
                prompt_ms: 1.0,
                generate_ms: 2.0,
                finish_reason: llm::FinishReason::Stop,
                forced_tokens: 0,
            },
        };
        s.push_str(&serde_json::to_string(&rec).unwrap());
        s.push('\n');
    }
    std::fs::write(&path, s).unwrap();
    (dir, path)
}

#[test]
fn a_miss_names_the_nearest_record_and_the_first_difference() {
    let (_d, path) = write_cassette(&[
        (req("go to the black sofa"), "a"),
        (req("go to the yellow table"), "b"),
    ]);
    let replay = ReplayBackend::open(&path).unwrap();
    let err = replay
        .complete(&req("go to the yellow tables"))
        .unwrap_err();
    let msg = err.to_string();
    match &err {
        LlmError::CassetteMiss { path: p, detail } => {
            assert_eq!(p, &path);
            assert!(detail.contains("line 2"), "{detail}");
            assert!(detail.contains("message 1 (user)"), "{detail}");
            assert!(detail.contains("from character 22"), "{detail}");
        }
        other => panic!("expected CassetteMiss, got {other}"),
    }
    assert!(msg.contains("c.jsonl"), "{msg}");

    // Same messages, different sampling parameters.
    let mut r = req("go to the black sofa");
    r.temperature = 0.7;
    let err = replay.complete(&r).unwrap_err().to_string();
    assert!(err.contains("temperature recorded 0 vs asked 0.7"), "{err}");

    // A different number of messages.
    let mut r = req("go to the black sofa");
    r.messages.push(ChatMessage::assistant("ok"));
    let err = replay.complete(&r).unwrap_err().to_string();
    assert!(
        err.contains("message count: recorded 2 vs asked 3"),
        "{err}"
    );
}

#[test]
fn repeated_requests_are_served_in_recorded_order() {
    let r = req("go");
    let (_d, path) = write_cassette(&[
        (r.clone(), "first"),
        (req("other"), "x"),
        (r.clone(), "second"),
    ]);
    let replay = ReplayBackend::open(&path).unwrap();
    assert_eq!(replay.complete(&r).unwrap().text, "first");
    assert_eq!(replay.complete(&r).unwrap().text, "second");
    assert_eq!(replay.complete(&r).unwrap().text, "second");
}

#[test]
fn malformed_lines_name_file_and_line() {
    let (_d, path) = write_cassette(&[(req("go"), "a")]);
    let mut text = std::fs::read_to_string(&path).unwrap();
    text.push('\n'); // blank lines are fine
    text.push_str("{\"backend\": \"llama\", \"model\": \"m\"}\n");
    std::fs::write(&path, text).unwrap();
    match ReplayBackend::open(&path).unwrap_err() {
        LlmError::CassetteParse {
            path: p,
            line,
            message,
        } => {
            assert_eq!(p, path);
            assert_eq!(line, 3);
            assert!(message.contains("request"), "{message}");
        }
        other => panic!("expected CassetteParse, got {other}"),
    }
    let err = ReplayBackend::open(path.with_file_name("missing.jsonl")).unwrap_err();
    assert!(matches!(err, LlmError::CassetteIo { .. }), "{err}");
}

#[test]
fn an_empty_cassette_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("empty.jsonl");
    std::fs::write(&path, "").unwrap();
    let replay = ReplayBackend::open(&path).unwrap();
    assert!(replay.is_empty());
    let err = replay.complete(&req("go")).unwrap_err().to_string();
    assert!(err.contains("empty"), "{err}");
}
