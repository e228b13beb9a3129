//! `ivlmap eval` with the real binary: suite errors name file, line and field; the
//! public navigation suites are achievable (reference plans, SR = 1); an extraction
//! suite recorded from an OpenAI-compatible server (wiremock on 127.0.0.1) replays from
//! the cassette with the same answers; `--send-grammar` sends that server the grammar.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

mod support;
use support::{ivlmap, repo, text};

use std::path::Path;

use serde_json::{json, Value};
use wiremock::matchers::{body_string_contains, method, path};
use wiremock::{Mock, MockServer, ResponseTemplate};

fn read_json(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

#[test]
fn malformed_suite_line_names_file_line_and_field() {
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("bad.nav.jsonl");
    let scene = repo().join("examples/scenes/flat-a.scene.json");
    let good = json!({"id": "t1", "scene": scene, "instruction": "go to the sofa", "subgoals": [{"object": 1}]});
    let bad = json!({"id": "t2", "scene": scene, "instruction": "go to the sofa", "subgoals": [{"object": 1}, {"object": 99}]});
    std::fs::write(&s, format!("{good}\n\n{bad}\n")).unwrap();
    let report = d.path().join("r.json");
    let o = ivlmap(&[
        "eval",
        s.to_str().unwrap(),
        "--baseline",
        "reference",
        "--report",
        report.to_str().unwrap(),
    ]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("bad.nav.jsonl:3:"), "{err}");
    assert!(
        err.contains("subgoals[1].object") && err.contains("99"),
        "{err}"
    );
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(!report.exists());

    let s = d.path().join("bad.extract.jsonl");
    std::fs::write(&s, "{\"id\": \"p1\", \"instruction\": \"go\", \"expected\": [{\"object\": \"table\", \"colour\": 3}]}\n").unwrap();
    let o = ivlmap(&[
        "eval",
        s.to_str().unwrap(),
        "--backend",
        "replay",
        "--cassette",
        "none.jsonl",
        "--report",
        report.to_str().unwrap(),
    ]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("bad.extract.jsonl:1:") && err.contains("expected[0].colour"),
        "{err}"
    );

    let o = ivlmap(&[
        "eval",
        "examples/suites/nope.nav.jsonl",
        "--report",
        report.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).1.contains("nope.nav.jsonl"));
}

#[test]
fn reference_plans_reach_every_subgoal_of_the_public_suites() {
    let d = tempfile::tempdir().unwrap();
    let mut total = 0;
    for suite in ["flat-a", "office-b", "house-c", "heldout"] {
        let report = d.path().join(format!("{suite}.json"));
        let o = ivlmap(&[
            "eval",
            &format!("examples/suites/{suite}.nav.jsonl"),
            "--baseline",
            "reference",
            "--report",
            report.to_str().unwrap(),
        ]);
        let (out, err) = text(&o);
        assert!(o.status.success(), "{out}\n{err}");
        assert!(out.contains("T_4") && out.contains("SR"), "{out}");
        let r = read_json(&report);
        assert_eq!(r["method"], "reference");
        assert_eq!(r["summary"]["SR"], 1.0, "{suite}: {}", r["summary"]);
        assert_eq!(r["summary"]["T"], json!([1.0, 1.0, 1.0, 1.0]));
        for c in r["cases"].as_array().unwrap() {
            assert_eq!(c["reached"], json!([true, true, true, true]), "{}", c["id"]);
            assert!(c["trajectory"]["stops"].as_array().unwrap().len() >= 4);
            assert!(c["got"]["script"].is_string());
        }
        total += r["cases"].as_array().unwrap().len();
    }
    assert!(total >= 36, "{total}");
}

fn completion(content: &str) -> Value {
    json!({
        "id": "chatcmpl-1", "object": "chat.completion", "model": "stub",
        "choices": [{"index": 0, "message": {"role": "assistant", "content": content}, "finish_reason": "stop"}],
        "usage": {"prompt_tokens": 100, "completion_tokens": 10, "total_tokens": 110}
    })
}

#[test]
fn extraction_suite_recorded_then_replayed_from_a_cassette() {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    let server = rt.block_on(MockServer::start());
    for (needle, answer) in [
        ("visit the 4th purple lamp", "[(lamp, 4, purple)]"),
        ("find the last orange ottoman", "[(ottoman, last, orange)]"),
        ("head to the zinc counter", "[(counter, None, None)]"),
    ] {
        rt.block_on(
            Mock::given(method("POST"))
                .and(path("/v1/chat/completions"))
                .and(body_string_contains(needle))
                .respond_with(ResponseTemplate::new(200).set_body_json(completion(answer)))
                .mount(&server),
        );
    }
    let d = tempfile::tempdir().unwrap();
    let suite = d.path().join("mini.extract.jsonl");
    std::fs::write(
        &suite,
        [
            json!({"id": "p1", "instruction": "visit the 4th purple lamp", "expected": [{"object": "lamp", "ordinal": 4, "colour": "purple"}]}),
            json!({"id": "p2", "instruction": "find the last orange ottoman", "expected": [{"object": "ottoman", "ordinal": -1, "colour": "orange"}]}),
            json!({"id": "p3", "instruction": "head to the zinc counter", "expected": [{"object": "counter", "ordinal": null, "colour": "zinc"}]}),
        ]
        .iter()
        .map(|v| v.to_string() + "\n")
        .collect::<String>(),
    )
    .unwrap();
    let cassette = d.path().join("c.jsonl");
    let r1 = d.path().join("r1.json");
    let o = ivlmap(&[
        "eval",
        suite.to_str().unwrap(),
        "--backend",
        "openai",
        "--base-url",
        &server.uri(),
        "--record",
        cassette.to_str().unwrap(),
        "--report",
        r1.to_str().unwrap(),
    ]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    assert!(out.contains("accuracy") && out.contains("2/3"), "{out}");
    drop(server);

    // Replay: no server, same answers.
    let r2 = d.path().join("r2.json");
    let o = ivlmap(&[
        "eval",
        suite.to_str().unwrap(),
        "--backend",
        "replay",
        "--cassette",
        cassette.to_str().unwrap(),
        "--report",
        r2.to_str().unwrap(),
    ]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let (a, b) = (read_json(&r1), read_json(&r2));
    assert_eq!(b["backend"], "replay");
    assert_eq!(b["suite"], "mini.extract.jsonl");
    assert_eq!(b["summary"]["total"], 3);
    assert_eq!(b["summary"]["ok"], 2);
    for i in 0..3 {
        assert_eq!(a["cases"][i]["got"], b["cases"][i]["got"]);
        assert!(b["cases"][i]["error"].is_null());
    }
    assert_eq!(
        b["cases"][0]["got"],
        json!([{"object": "lamp", "ordinal": 4, "colour": "purple"}])
    );
    assert_eq!(b["cases"][2]["ok"], false);
    assert!(b["summary"].get("T").is_none());

    // Two prompt variants side by side: two reports and a two-column table.
    let variant = d.path().join("variant");
    std::fs::create_dir(&variant).unwrap();
    let r3 = d.path().join("r3.json");
    let o = ivlmap(&[
        "eval",
        suite.to_str().unwrap(),
        "--backend",
        "replay",
        "--cassette",
        cassette.to_str().unwrap(),
        "--prompts",
        "prompts",
        "--prompts",
        variant.to_str().unwrap(),
        "--report",
        r3.to_str().unwrap(),
    ]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let reports: Vec<&str> = out.lines().filter(|l| l.starts_with("report: ")).collect();
    assert_eq!(reports.len(), 2, "{out}");
    let acc = out.lines().find(|l| l.starts_with("accuracy")).unwrap();
    assert_eq!(acc.split_whitespace().count(), 3, "{acc}");
}

#[test]
fn send_grammar_passes_the_objects_grammar_to_an_openai_server() {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    let server = rt.block_on(MockServer::start());
    rt.block_on(
        Mock::given(method("POST"))
            .and(path("/v1/chat/completions"))
            .respond_with(
                ResponseTemplate::new(200).set_body_json(completion("[(lamp, 4, purple)]")),
            )
            .mount(&server),
    );
    let d = tempfile::tempdir().unwrap();
    let suite = d.path().join("one.extract.jsonl");
    std::fs::write(
        &suite,
        json!({"id": "p1", "instruction": "visit the 4th purple lamp", "expected": [{"object": "lamp", "ordinal": 4, "colour": "purple"}]}).to_string() + "\n",
    )
    .unwrap();
    let base_url = format!("{}/v1", server.uri());
    let mut grammars = Vec::new();
    let mut seen = 0;
    for send in [false, true] {
        let report = d.path().join(format!("r-{send}.json"));
        let mut args = vec![
            "eval",
            suite.to_str().unwrap(),
            "--backend",
            "openai",
            "--base-url",
            &base_url,
            "--report",
            report.to_str().unwrap(),
        ];
        if send {
            args.push("--send-grammar");
        }
        let o = ivlmap(&args);
        let (out, err) = text(&o);
        assert!(o.status.success(), "{out}\n{err}");
        let sent = rt.block_on(server.received_requests()).unwrap_or_default();
        let bodies: Vec<Value> = sent[seen..]
            .iter()
            .map(|r| serde_json::from_slice(&r.body).unwrap())
            .collect();
        seen = sent.len();
        assert!(!bodies.is_empty());
        grammars.push(
            bodies
                .iter()
                .map(|b| b.get("grammar").cloned())
                .collect::<Vec<_>>(),
        );
    }
    // Without the flag no request carries a grammar; with it the objects line's does, as
    // GBNF text.
    assert!(grammars[0].iter().all(Option::is_none), "{:?}", grammars[0]);
    let g = grammars[1][0]
        .as_ref()
        .and_then(Value::as_str)
        .unwrap_or_default();
    assert!(g.contains("root ::="), "{:?}", grammars[1]);
}
