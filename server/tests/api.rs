//! `ivlmap serve`'s HTTP API against the real server on 127.0.0.1: every route, every
//! error status, the token, and a bounded load test (the real SmolLM2 behind the queue,
//! then 3 rounds of 50 sessions x 4 instructions replayed).
//!
//! Instructions that plan come from a cassette recorded from SmolLM2 through the server
//! at the start of the run (support::recorded); without the model those tests say
//! SKIPPED, as the workspace's other model tests do. Error paths need no model: an
//! empty cassette is a backend that cannot answer.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests

mod support;

use std::sync::Arc;
use std::time::{Duration, Instant};

use llm::{LlmBackend, ReplayBackend};
use reqwest::StatusCode;
use serde_json::{json, Value};
use server::{ServeConfig, ServeError, Server, Service};
use support::*;

/// A backend that answers nothing: an empty cassette.
fn mute() -> Arc<dyn LlmBackend> {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("serve");
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("empty.jsonl");
    std::fs::write(&p, "").unwrap();
    Arc::new(ReplayBackend::open(p).unwrap())
}

fn replay(rec: &Recorded) -> Arc<dyn LlmBackend> {
    Arc::new(ReplayBackend::open(&rec.cassette).unwrap())
}

/// The load test measures; nothing else should run beside it.
static SERIAL: tokio::sync::Mutex<()> = tokio::sync::Mutex::const_new(());

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn page_map_info_and_session_routes() {
    let _g = SERIAL.lock().await;
    let s = start(Service::new(flat_a(), mute()), local()).await;
    let api = s.api();

    // The page and its files, without a token.
    let page = reqwest::get(&s.url).await.unwrap();
    assert_eq!(page.status(), StatusCode::OK);
    assert!(page.headers()["content-type"]
        .to_str()
        .unwrap()
        .starts_with("text/html"));
    let html = page.text().await.unwrap();
    assert!(html.contains("<canvas id=\"map\"") && html.contains("/assets/app.js"));
    for (path, ty) in [
        ("/assets/app.js", "text/javascript"),
        ("/assets/app.css", "text/css"),
    ] {
        let r = reqwest::get(api.url(path)).await.unwrap();
        assert_eq!(r.status(), StatusCode::OK, "{path}");
        assert!(r.headers()["content-type"]
            .to_str()
            .unwrap()
            .starts_with(ty));
        assert!(r.text().await.unwrap().len() > 1000);
    }

    let (st, info) = api.get("/api/info").await;
    assert_eq!(st, StatusCode::OK);
    assert_eq!(info["scene"], "flat-a");
    assert_eq!(info["backend"], "replay");
    assert_eq!(info["queue"]["workers"], 1);

    let (st, m) = api.get("/api/map").await;
    assert_eq!(st, StatusCode::OK);
    assert_eq!(m["name"], "flat-a");
    let map = flat_a();
    assert_eq!(m["size"], json!([map.frame.cols, map.frame.rows]));
    assert_eq!(m["cell_size"], json!(map.frame.cell_size));
    assert_eq!(m["origin"], json!([map.frame.origin.x, map.frame.origin.y]));
    assert_eq!(
        m["obstacles"]["rows"].as_array().unwrap().len(),
        map.frame.rows
    );
    let insts = m["instances"].as_array().unwrap();
    assert_eq!(insts.len(), map.instances.len());
    for i in insts {
        for f in [
            "id",
            "label",
            "color",
            "bbox_m",
            "centroid",
            "contour",
            "description",
        ] {
            assert!(!i[f].is_null() || f == "color", "{f} missing in {i}");
        }
    }
    let t17 = insts.iter().find(|i| i["id"] == 17).unwrap();
    assert_eq!(t17["description"], "the second yellow table from the west");
    assert_eq!(t17["region"], "kitchen");
    let regions: Vec<&str> = m["regions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["name"].as_str().unwrap())
        .collect();
    assert!(regions.contains(&"kitchen") && regions.contains(&"office"));

    // Create, read, draw, undo with nothing to undo, reset, delete.
    let (st, created) = api.post("/api/sessions", &json!({})).await;
    assert_eq!(st, StatusCode::CREATED);
    let id = created["id"].as_str().unwrap().to_string();
    assert_eq!(created["scene"], "flat-a");
    assert_eq!(created["pose"], json!(map.start_pose.to_array()));
    // An empty body creates one too.
    let (st, _) = api.post_raw("/api/sessions", Vec::new()).await;
    assert_eq!(st, StatusCode::CREATED);

    let (st, got) = api.get(&format!("/api/sessions/{id}")).await;
    assert_eq!(st, StatusCode::OK);
    assert_eq!(got["id"], json!(id));
    assert_eq!(got["pose"], created["pose"]);
    assert_eq!(got["turns"], json!([]));
    assert_eq!(got["trajectory"]["stops"], json!([]));
    assert_eq!(got["trajectory"]["scene"], "flat-a");

    let png = reqwest::get(api.url(&format!("/api/sessions/{id}/map.png")))
        .await
        .unwrap();
    assert_eq!(png.status(), StatusCode::OK);
    assert_eq!(png.headers()["content-type"], "image/png");
    assert_eq!(&png.bytes().await.unwrap()[1..4], b"PNG");

    let (st, e) = api
        .post(&format!("/api/sessions/{id}/undo"), &json!({}))
        .await;
    assert_eq!(
        (st, e["code"].as_str()),
        (StatusCode::CONFLICT, Some("nothing_to_undo"))
    );
    let (st, e) = api
        .post(&format!("/api/sessions/{id}/confirm"), &json!({}))
        .await;
    assert_eq!(
        (st, e["code"].as_str()),
        (StatusCode::CONFLICT, Some("nothing_to_confirm"))
    );
    let (st, _) = api
        .post(&format!("/api/sessions/{id}/cancel"), &json!({}))
        .await;
    assert_eq!(st, StatusCode::OK);
    let (st, r) = api
        .post(&format!("/api/sessions/{id}/reset"), &json!({}))
        .await;
    assert_eq!((st, &r["pose"]), (StatusCode::OK, &created["pose"]));

    let (st, v) = api.delete(&format!("/api/sessions/{id}")).await;
    assert_eq!((st, v), (StatusCode::NO_CONTENT, Value::Null));
    let (st, e) = api.get(&format!("/api/sessions/{id}")).await;
    assert_eq!(
        (st, e["code"].as_str()),
        (StatusCode::NOT_FOUND, Some("unknown_session"))
    );
    s.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn every_error_status_leaves_the_session_as_it_was() {
    let _g = SERIAL.lock().await;
    let s = start(Service::new(flat_a(), mute()), local()).await;
    let api = s.api();
    let id = api.session().await;
    let before = api.get(&format!("/api/sessions/{id}")).await.1;
    let at = format!("/api/sessions/{id}/instructions");

    // 400: malformed JSON, missing or wrong fields, empty or overlong text.
    for body in [
        b"{\"text\": ".to_vec(),
        b"not json".to_vec(),
        b"{}".to_vec(),
        b"{\"text\": 42}".to_vec(),
        b"{\"text\": \"go\", \"preview\": \"yes\"}".to_vec(),
        b"[\"go to the sofa\"]".to_vec(),
        b"{\"text\": \"   \"}".to_vec(),
        serde_json::to_vec(&json!({"text": "go ".repeat(1000)})).unwrap(),
    ] {
        let (st, e) = api.post_raw(&at, body.clone()).await;
        assert_eq!(
            st,
            StatusCode::BAD_REQUEST,
            "{}",
            String::from_utf8_lossy(&body)
        );
        assert_eq!(e["code"], "bad_request");
        assert!(e["error"].as_str().unwrap().len() > 10, "{e}");
    }
    let (st, e) = api.post_raw("/api/sessions", b"[1, 2]".to_vec()).await;
    assert_eq!(
        (st, e["code"].as_str()),
        (StatusCode::BAD_REQUEST, Some("bad_request"))
    );
    let (st, _) = api.post_raw("/api/sessions", b"{".to_vec()).await;
    assert_eq!(st, StatusCode::BAD_REQUEST);

    // 404: unknown session on every session route; unknown route.
    for (method, path) in [
        ("GET", "/api/sessions/nope"),
        ("DELETE", "/api/sessions/nope"),
        ("POST", "/api/sessions/nope/instructions"),
        ("POST", "/api/sessions/nope/undo"),
        ("POST", "/api/sessions/nope/reset"),
        ("POST", "/api/sessions/nope/confirm"),
        ("POST", "/api/sessions/nope/cancel"),
        ("GET", "/api/sessions/nope/events"),
        ("GET", "/api/sessions/nope/map.png"),
    ] {
        let r = api
            .http
            .request(method.parse().unwrap(), api.url(path))
            .json(&json!({"text": "go to the fridge"}))
            .send()
            .await
            .unwrap();
        assert_eq!(r.status(), StatusCode::NOT_FOUND, "{method} {path}");
        let e: Value = r.json().await.unwrap();
        assert_eq!(e["code"], "unknown_session", "{method} {path}");
    }
    let (st, e) = api.get("/api/nothing-here").await;
    assert_eq!(
        (st, e["code"].as_str()),
        (StatusCode::NOT_FOUND, Some("not_found"))
    );
    let r = api.http.put(api.url("/api/map")).send().await.unwrap();
    assert_eq!(r.status(), StatusCode::METHOD_NOT_ALLOWED);

    // 413: a body over 1 MiB, on every route that takes one.
    let big = serde_json::to_vec(&json!({"text": "x".repeat(1 << 20)})).unwrap();
    for path in [at.as_str(), "/api/sessions"] {
        let (st, e) = api.post_raw(path, big.clone()).await;
        assert_eq!(
            (st, e["code"].as_str()),
            (StatusCode::PAYLOAD_TOO_LARGE, Some("body_too_large")),
            "{path}"
        );
    }

    // 503: the model cannot answer (the cassette holds nothing); the reason is given.
    let mut events = api.events(&id).await;
    let (st, e) = api.say(&id, "go to the fridge", false).await;
    assert_eq!(st, StatusCode::SERVICE_UNAVAILABLE, "{e}");
    assert_eq!(e["code"], "model_unavailable");
    assert!(e["error"].as_str().unwrap().contains("cassette"), "{e}");
    let (st, _) = api.say(&id, "go to the fridge", true).await;
    assert_eq!(st, StatusCode::SERVICE_UNAVAILABLE);
    let seen = events.until_done(2, Duration::from_secs(30)).await;
    let names: Vec<&str> = seen.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        ["queued", "planning", "done", "queued", "planning", "done"]
    );
    assert_eq!(seen[2].1["status"], 503);
    assert_eq!(seen[0].1["position"], 1);
    assert_eq!(
        (seen[0].1["request"].as_u64(), seen[5].1["request"].as_u64()),
        (Some(1), Some(2))
    );

    // Nothing above changed the session.
    let after = api.get(&format!("/api/sessions/{id}")).await.1;
    assert_eq!(after, before);

    // Garbage at every POST route: a 4xx, never a failure of the server.
    for path in [
        at.clone(),
        "/api/sessions".into(),
        format!("/api/sessions/{id}/undo"),
        format!("/api/sessions/{id}/confirm"),
    ] {
        for body in [
            vec![0xff, 0xfe, 0x00],
            b"{\"text\": \"\\ud800\"}".to_vec(),
            b"nul\0l".to_vec(),
        ] {
            let (st, _) = api.post_raw(&path, body).await;
            assert!(st.is_client_error(), "{path}: {st}");
        }
    }
    assert_eq!(api.get("/api/info").await.0, StatusCode::OK);
    s.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn the_token_guards_the_api_not_the_page() {
    let _g = SERIAL.lock().await;
    // Off loopback without a token: refused, nothing listens.
    let open = ServeConfig {
        addr: "0.0.0.0:0".into(),
        ..ServeConfig::default()
    };
    let err = Server::bind(open, Service::new(flat_a(), mute()))
        .await
        .unwrap_err();
    assert!(matches!(err, ServeError::TokenRequired { .. }), "{err}");
    assert!(err.to_string().contains("--token"), "{err}");

    let s = start(
        Service::new(flat_a(), mute()),
        ServeConfig {
            token: Some("s3cret-token".into()),
            ..local()
        },
    )
    .await;
    let page = reqwest::get(&s.url).await.unwrap();
    assert_eq!(page.status(), StatusCode::OK);
    let anonymous = s.api();
    for path in ["/api/info", "/api/map", "/api/sessions/x"] {
        let (st, e) = anonymous.get(path).await;
        assert_eq!(
            (st, e["code"].as_str()),
            (StatusCode::UNAUTHORIZED, Some("unauthorized")),
            "{path}"
        );
    }
    let (st, _) = anonymous.post("/api/sessions", &json!({})).await;
    assert_eq!(st, StatusCode::UNAUTHORIZED);
    let r = anonymous
        .http
        .get(anonymous.url("/api/info"))
        .send()
        .await
        .unwrap();
    assert_eq!(r.headers()["www-authenticate"], "Bearer");
    let wrong = Api::new(&s.url, Some("s3cret-tokeN"));
    assert_eq!(wrong.get("/api/info").await.0, StatusCode::UNAUTHORIZED);
    let right = Api::new(&s.url, Some("s3cret-token"));
    assert_eq!(right.get("/api/info").await.0, StatusCode::OK);
    let id = right.session().await;
    let _events = right.events(&id).await;
    s.stop().await;

    // Off loopback with a token: it starts.
    let guarded = ServeConfig {
        addr: "0.0.0.0:0".into(),
        token: Some("t".into()),
        ..ServeConfig::default()
    };
    let s = Server::bind(guarded, Service::new(flat_a(), mute()))
        .await
        .unwrap();
    assert!(!s.local_addr().ip().is_loopback());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn sessions_are_bounded_and_idle_ones_expire() {
    let _g = SERIAL.lock().await;
    let s = start(
        Service::new(flat_a(), mute()),
        ServeConfig {
            max_sessions: 2,
            session_ttl: Duration::from_millis(400),
            ..local()
        },
    )
    .await;
    let api = s.api();
    let a = api.session().await;
    let _b = api.session().await;
    let (st, e) = api.post("/api/sessions", &json!({})).await;
    assert_eq!(
        (st, e["code"].as_str()),
        (StatusCode::SERVICE_UNAVAILABLE, Some("too_many_sessions"))
    );
    let mut events = api.events(&a).await;
    tokio::time::sleep(Duration::from_millis(1200)).await;
    assert_eq!(
        api.get(&format!("/api/sessions/{a}")).await.0,
        StatusCode::NOT_FOUND
    );
    assert_eq!(api.get("/api/info").await.1["sessions"], 0);
    // The expired session's event stream ends.
    assert!(events.next(Duration::from_secs(5)).await.is_none());
    api.session().await;
    s.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn instructions_preview_confirm_undo_and_events() {
    let Some(rec) = recorded() else { return };
    let _g = SERIAL.lock().await;
    // The first recorded answer that ran: SmolLM2-135M's answers change with the prompt
    // and grammar, and most end in a question.
    let ran = (0..SEQUENCES.len())
        .flat_map(|k| (0..SEQUENCES[k].len()).map(move |i| (k, i)))
        .find(|&(k, i)| {
            let (st, v) = &rec.replies[k][i];
            *st == StatusCode::OK && v["outcome"] == "done"
        });
    let Some((k, i)) = ran else {
        println!("SKIPPED: none of SmolLM2's recorded answers ran; this test needs a plan");
        return;
    };
    let s = start(smol_service(replay(rec)), local()).await;
    let api = s.api();
    let id = api.session().await;
    // The sequence up to it, as recorded.
    for (j, text) in SEQUENCES[k][..i].iter().enumerate() {
        let (st, v) = api.say(&id, text, false).await;
        assert_eq!(
            reply_key(st, &v),
            reply_key(rec.replies[k][j].0, &rec.replies[k][j].1)
        );
    }
    let before = api.get(&format!("/api/sessions/{id}")).await.1;
    let start_pose = before["pose"].clone();
    let turns = before["turns"].as_array().unwrap().len();
    let mut events = api.events(&id).await;

    // The recorded answer again, and its events.
    let (st, first) = api.say(&id, SEQUENCES[k][i], false).await;
    assert_eq!(
        reply_key(st, &first),
        reply_key(rec.replies[k][i].0, &rec.replies[k][i].1)
    );
    for f in [
        "tuples",
        "script",
        "trace",
        "trajectory",
        "question",
        "error",
    ] {
        assert!(first.get(f).is_some(), "{f} missing: {first}");
    }
    assert!(first["script"].as_str().unwrap().contains("move_to"));
    assert_ne!(first["pose"], start_pose, "the robot moved");
    let tr = &first["trajectory"];
    assert_eq!(tr["path"][0], json!([start_pose[0], start_pose[1]]));
    assert!(!tr["stops"].as_array().unwrap().is_empty());
    let seen = events.until_done(1, Duration::from_secs(30)).await;
    let names: Vec<&str> = seen.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(&names[..4], ["queued", "planning", "tuples", "script"]);
    assert_eq!(names.last(), Some(&"done"));
    let steps: Vec<&Value> = seen
        .iter()
        .filter(|(n, _)| n == "step")
        .map(|(_, d)| d)
        .collect();
    assert_eq!(steps.len(), first["trace"].as_array().unwrap().len());
    assert_eq!(steps.last().unwrap()["pose"], first["pose"]);
    assert!(steps.iter().any(|s| s["stop"] == 1));
    assert_eq!(seen.last().unwrap().1["script"], first["script"]);

    // Undo goes back one instruction, to the state it was said in.
    let (st, undone) = api
        .post(&format!("/api/sessions/{id}/undo"), &json!({}))
        .await;
    assert_eq!(st, StatusCode::OK, "{undone}");
    assert_eq!(undone["pose"], start_pose);
    assert_eq!(undone["turns"].as_array().unwrap().len(), turns);

    // The same instruction as a preview (the same request: the replay answers it the
    // same) moves nothing; confirm runs exactly the previewed plan.
    let (st, pre) = api.say(&id, SEQUENCES[k][i], true).await;
    assert_eq!(st, StatusCode::OK, "{pre}");
    assert_eq!(pre["outcome"], "preview", "{pre}");
    assert_eq!(pre["script"], first["script"]);
    let session = api.get(&format!("/api/sessions/{id}")).await.1;
    assert_eq!(session["pose"], start_pose, "a preview moves nothing");
    assert_eq!(session["turns"].as_array().unwrap().len(), turns);
    assert_eq!(session["pending"]["script"], pre["script"]);
    let stops_before = before["trajectory"]["stops"].as_array().map_or(0, Vec::len);
    assert_eq!(pre["first_stop"], json!(stops_before + 1));
    let (st, run) = api
        .post(&format!("/api/sessions/{id}/confirm"), &json!({}))
        .await;
    assert_eq!(st, StatusCode::OK, "{run}");
    assert_eq!(run["script"], pre["script"]);
    assert_eq!(run["trajectory"]["stops"], pre["trajectory"]["stops"]);
    assert_eq!(run["trajectory"]["path"], pre["trajectory"]["path"]);
    assert_eq!(run["pose"], first["pose"]);
    let (st, e) = api
        .post(&format!("/api/sessions/{id}/confirm"), &json!({}))
        .await;
    assert_eq!(
        (st, e["code"].as_str()),
        (StatusCode::CONFLICT, Some("nothing_to_confirm"))
    );
    let session = api.get(&format!("/api/sessions/{id}")).await.1;
    assert_eq!(session["pose"], run["pose"]);
    assert_eq!(session["turns"].as_array().unwrap().len(), turns + 1);
    let (st, _) = api
        .post(&format!("/api/sessions/{id}/undo"), &json!({}))
        .await;
    assert_eq!(st, StatusCode::OK);
    assert_eq!(
        api.get(&format!("/api/sessions/{id}")).await.1["pose"],
        start_pose
    );
    s.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn load_50_sessions_by_4_instructions() {
    let Some(rec) = recorded() else { return };
    let _g = SERIAL.lock().await;
    // An instruction that got a question stays in the session's conversation: the
    // request for the next one names it, where that one was answered. The cassette is
    // read once: its requests here, its answers for the load below.
    let cassette = Arc::new(ReplayBackend::open(&rec.cassette).unwrap());
    let asked: Vec<&str> = cassette
        .records()
        .flat_map(|r| r.request.messages.iter().map(|m| m.content.as_str()))
        .collect();
    let mut questions = 0;
    for (k, seq) in rec.replies.iter().enumerate() {
        for (i, pair) in seq.windows(2).enumerate() {
            let ((st, v), (next, _)) = (&pair[0], &pair[1]);
            if *st == StatusCode::OK && v["outcome"] == "question" && *next == StatusCode::OK {
                questions += 1;
                let said = format!("not done: the person said \"{}\"", SEQUENCES[k][i]);
                assert!(
                    asked.iter().any(|c| c.contains(&said)),
                    "no request after the question to {:?} names it",
                    SEQUENCES[k][i]
                );
            }
        }
    }
    println!("{questions} recorded question(s) named in the next instruction's request");
    const SESSIONS: usize = 50;
    let s = start(
        smol_service(cassette.clone()),
        ServeConfig {
            workers: 4,
            ..local()
        },
    )
    .await;
    let api = s.api();
    let mut rss = Vec::new();
    for round in 1..=3 {
        // Every fifth session also listens to its events.
        let listeners: Vec<_> = (0..SESSIONS / 5).map(|_| api.clone()).collect();
        let mut watched = Vec::new();
        for (j, a) in listeners.into_iter().enumerate() {
            let id = a.session().await;
            let ev = a.events(&id).await;
            watched.push((id, j % SEQUENCES.len(), ev, a));
        }
        let t0 = Instant::now();
        let watched_tasks: Vec<_> = watched
            .into_iter()
            .map(|(id, k, mut ev, a)| {
                tokio::spawn(async move {
                    let mut replies = Vec::new();
                    let mut ms = Vec::new();
                    for text in SEQUENCES[k] {
                        let t = Instant::now();
                        replies.push(a.say(&id, text, false).await);
                        ms.push(t.elapsed().as_secs_f64() * 1000.0);
                    }
                    let events = ev
                        .until_done(SEQUENCES[k].len(), Duration::from_secs(60))
                        .await;
                    (id, k, replies, ms, events)
                })
            })
            .collect();
        let (plain, mut ms) =
            run_sessions(&api, SESSIONS - SESSIONS / 5, |i| i % SEQUENCES.len()).await;
        let mut all: Vec<SessionRun> = plain;
        for t in watched_tasks {
            let (id, k, replies, m, events) = t.await.unwrap();
            ms.extend(m);
            // Each done event is this session's answer, in order.
            let dones: Vec<&Value> = events
                .iter()
                .filter(|(n, _)| n == "done")
                .map(|(_, d)| d)
                .collect();
            for (i, ((st, reply), d)) in replies.iter().zip(&dones).enumerate() {
                if *st == StatusCode::OK {
                    assert_eq!(
                        d["instruction"], SEQUENCES[k][i],
                        "event for another session"
                    );
                    assert_eq!(reply_key(*st, d), reply_key(*st, reply));
                } else {
                    assert_eq!(d["status"], st.as_u16());
                }
                assert_eq!(d["request"], json!(i + 1));
            }
            all.push((id, k, replies));
        }
        let wall = t0.elapsed().as_secs_f64();
        let n = ms.len();
        assert_eq!(n, SESSIONS * 4, "no request lost");
        let (p50, p95) = percentiles(&mut ms);
        println!(
            "load round {round} (replay, 4 workers): {n} instructions from {SESSIONS} sessions in parallel in {wall:.2} s: \
             {:.0} instructions/s; latency p50 {p50:.0} ms, p95 {p95:.0} ms",
            n as f64 / wall
        );
        // Every answer is the one recorded for that session's sequence: none went astray.
        for (id, k, replies) in &all {
            assert_eq!(replies.len(), 4);
            for (i, (st, v)) in replies.iter().enumerate() {
                let (rst, rv) = &rec.replies[*k][i];
                assert_eq!(
                    reply_key(*st, v),
                    reply_key(*rst, rv),
                    "session {id} step {i}"
                );
            }
            let sess = api.get(&format!("/api/sessions/{id}")).await.1;
            let said: Vec<&str> = sess["turns"]
                .as_array()
                .unwrap()
                .iter()
                .map(|t| t["instruction"].as_str().unwrap())
                .collect();
            let executed: Vec<&str> = replies
                .iter()
                .zip(SEQUENCES[*k])
                .filter(|((st, v), _)| {
                    *st == StatusCode::OK && (v["outcome"] == "done" || v["outcome"] == "failed")
                })
                .map(|(_, t)| t)
                .collect();
            assert_eq!(said, executed, "session {id}");
            assert_eq!(
                api.delete(&format!("/api/sessions/{id}")).await.0,
                StatusCode::NO_CONTENT
            );
        }
        let info = api.get("/api/info").await.1;
        assert_eq!(info["sessions"], 0);
        // A job counts as running until its model thread has returned, which can be just
        // after its requester got the answer (seen with the machine loaded: `running` 1
        // when read right after the last reply): wait for the threads, briefly.
        let idle = |info: &Value| {
            (
                info["queue"]["waiting"].as_u64(),
                info["queue"]["running"].as_u64(),
            )
        };
        let mut queue = idle(&info);
        let deadline = Instant::now() + Duration::from_secs(10);
        while queue != (Some(0), Some(0)) && Instant::now() < deadline {
            tokio::time::sleep(Duration::from_millis(20)).await;
            queue = idle(&api.get("/api/info").await.1);
        }
        assert_eq!(queue, (Some(0), Some(0)));
        rss.push(support::rss_kb());
    }
    println!("memory (resident, kB) after each round: {rss:?}");
    // The first rounds warm the allocator's pools; after that identical rounds must
    // not keep growing (every session was deleted).
    let (warm, last) = (rss[rss.len() - 2], rss[rss.len() - 1]);
    assert!(
        last < warm + 32 * 1024,
        "memory grew by {} kB between identical rounds",
        last.saturating_sub(warm)
    );
    s.stop().await;
}
