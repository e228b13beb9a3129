//! What the server's tests share: the map, a real server on 127.0.0.1, a small JSON
//! client, an event-stream reader, and a cassette recorded from SmolLM2 through the
//! server itself (so the replayed requests are exactly the ones the server sends, and
//! a prompt change never leaves a stale cassette behind).

#![allow(dead_code)] // each test binary uses a part

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use llm::replay::CassetteRecord;
use llm::{LlamaCppBackend, LlamaCppConfig, LlmBackend, Recording, ReplayBackend};
use map_core::{IvlMap, Scene};
use reqwest::StatusCode;
use serde_json::{json, Value};
use server::{ServeConfig, Server, Service};
use tokio::sync::oneshot;

pub fn flat_a() -> Arc<IvlMap> {
    let path = ivlmap_tests::repo().join("examples/scenes/flat-a.scene.json");
    Arc::new(IvlMap::from_scene(&Scene::from_path(path).unwrap()))
}

/// A config on a free loopback port.
pub fn local() -> ServeConfig {
    ServeConfig {
        addr: "127.0.0.1:0".into(),
        ..ServeConfig::default()
    }
}

/// A server running on its own task until dropped.
pub struct Running {
    pub url: String,
    pub addr: SocketAddr,
    stop: Option<oneshot::Sender<()>>,
    task: Option<tokio::task::JoinHandle<()>>,
}

impl Running {
    pub fn api(&self) -> Api {
        Api::new(&self.url, None)
    }

    /// Stops it and waits for it to finish: even with event streams open, as soon as the
    /// model job running, if any, has finished (one whose requester timed out).
    pub async fn stop(mut self) {
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
        if let Some(t) = self.task.take() {
            tokio::time::timeout(Duration::from_secs(300), t)
                .await
                .expect("the server shuts down within 300 s")
                .unwrap();
        }
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
    }
}

pub async fn start(service: Service, config: ServeConfig) -> Running {
    let server = Server::bind(config, service).await.unwrap();
    let addr = server.local_addr();
    let url = server.url();
    let (tx, rx) = oneshot::channel::<()>();
    let task = tokio::spawn(async move {
        server
            .run_until(async {
                let _ = rx.await;
            })
            .await
            .unwrap();
    });
    Running {
        url,
        addr,
        stop: Some(tx),
        task: Some(task),
    }
}

/// The service that SmolLM2's recording and every replay of it answer with: flat-a, the
/// built-in prompts, and answers cut at 96 tokens (a replay must send the very requests
/// that were recorded, so both use this).
///
/// Each of [`SEQUENCES`]' instructions names one place, and a right answer to one is 30 to
/// 60 tokens. SmolLM2-135M often repeats a step until the limit: at the default 384 tokens,
/// about 45 ms a token and up to four draws an instruction, one such instruction held the
/// one worker for minutes, and 13 of 16 recorded instructions ended in 503 `timeout`.
pub fn smol_service(backend: Arc<dyn LlmBackend>) -> Service {
    let mut service = Service::new(flat_a(), backend);
    service.options.plan_max_tokens = 96;
    service
}

/// A server answering with [`smol_service`] on one worker.
pub async fn one_worker(backend: Arc<dyn LlmBackend>) -> Running {
    start(
        smol_service(backend),
        ServeConfig {
            workers: 1,
            ..local()
        },
    )
    .await
}

/// A JSON client for the API.
#[derive(Clone)]
pub struct Api {
    pub http: reqwest::Client,
    pub base: String,
    pub token: Option<String>,
}

impl Api {
    pub fn new(url: &str, token: Option<&str>) -> Self {
        Self {
            http: reqwest::Client::builder()
                .timeout(Duration::from_secs(600))
                .pool_max_idle_per_host(64)
                .build()
                .unwrap(),
            base: url.trim_end_matches('/').to_string(),
            token: token.map(str::to_string),
        }
    }

    pub fn url(&self, path: &str) -> String {
        format!("{}{path}", self.base)
    }

    fn auth(&self, r: reqwest::RequestBuilder) -> reqwest::RequestBuilder {
        match &self.token {
            Some(t) => r.bearer_auth(t),
            None => r,
        }
    }

    async fn done(r: reqwest::RequestBuilder) -> (StatusCode, Value) {
        let res = r.send().await.unwrap();
        let status = res.status();
        let bytes = res.bytes().await.unwrap();
        let v = if bytes.is_empty() {
            Value::Null
        } else {
            serde_json::from_slice(&bytes).unwrap_or_else(|e| {
                panic!(
                    "{status}: not JSON ({e}): {}",
                    String::from_utf8_lossy(&bytes)
                )
            })
        };
        (status, v)
    }

    pub async fn get(&self, path: &str) -> (StatusCode, Value) {
        Self::done(self.auth(self.http.get(self.url(path)))).await
    }

    pub async fn delete(&self, path: &str) -> (StatusCode, Value) {
        Self::done(self.auth(self.http.delete(self.url(path)))).await
    }

    pub async fn post(&self, path: &str, body: &Value) -> (StatusCode, Value) {
        Self::done(self.auth(self.http.post(self.url(path)).json(body))).await
    }

    pub async fn post_raw(&self, path: &str, body: Vec<u8>) -> (StatusCode, Value) {
        Self::done(
            self.auth(
                self.http
                    .post(self.url(path))
                    .header("content-type", "application/json")
                    .body(body),
            ),
        )
        .await
    }

    pub async fn session(&self) -> String {
        let (s, v) = self.post("/api/sessions", &json!({})).await;
        assert_eq!(s, StatusCode::CREATED, "{v}");
        v["id"].as_str().unwrap().to_string()
    }

    pub async fn say(&self, id: &str, text: &str, preview: bool) -> (StatusCode, Value) {
        self.post(
            &format!("/api/sessions/{id}/instructions"),
            &json!({"text": text, "preview": preview}),
        )
        .await
    }

    /// Opens the session's event stream and waits for its `open` event.
    pub async fn events(&self, id: &str) -> Events {
        let res = self
            .auth(
                self.http
                    .get(self.url(&format!("/api/sessions/{id}/events")))
                    // The stream stays open while a whole recording runs (measured over
                    // the client's 600 s on a loaded 2-core machine: the body read then
                    // failed and no event came back); each read has its own deadline.
                    .timeout(Duration::from_secs(3600)),
            )
            .send()
            .await
            .unwrap();
        assert_eq!(res.status(), StatusCode::OK);
        assert!(res
            .headers()
            .get("content-type")
            .and_then(|v| v.to_str().ok())
            .is_some_and(|v| v.starts_with("text/event-stream")));
        let mut ev = Events {
            res,
            buf: String::new(),
            seen: Vec::new(),
        };
        let first = ev.next(Duration::from_secs(10)).await.unwrap();
        assert_eq!(first.0, "open");
        ev
    }
}

/// A server-sent event stream.
pub struct Events {
    res: reqwest::Response,
    buf: String,
    pub seen: Vec<(String, Value)>,
}

impl Events {
    /// The next event, `None` when the stream ends or `wait` passes.
    pub async fn next(&mut self, wait: Duration) -> Option<(String, Value)> {
        let deadline = Instant::now() + wait;
        loop {
            if let Some(cut) = self.buf.find("\n\n") {
                let chunk: String = self.buf.drain(..cut + 2).collect();
                let mut name = "message".to_string();
                let mut data = String::new();
                for line in chunk.lines() {
                    if let Some(n) = line.strip_prefix("event:") {
                        name = n.trim().to_string();
                    } else if let Some(d) = line.strip_prefix("data:") {
                        data.push_str(d.trim());
                    }
                }
                if data.is_empty() {
                    continue; // a keep-alive comment
                }
                let ev = (name, serde_json::from_str(&data).unwrap());
                self.seen.push(ev.clone());
                return Some(ev);
            }
            let left = deadline.checked_duration_since(Instant::now())?;
            match tokio::time::timeout(left, self.res.chunk()).await {
                Ok(Ok(Some(bytes))) => self.buf.push_str(&String::from_utf8_lossy(&bytes)),
                _ => return None,
            }
        }
    }

    /// Events up to and including the `n`-th `done`.
    pub async fn until_done(&mut self, n: usize, wait: Duration) -> Vec<(String, Value)> {
        let deadline = Instant::now() + wait;
        let mut out = Vec::new();
        let mut dones = 0;
        while dones < n {
            let left = deadline.saturating_duration_since(Instant::now());
            let Some(ev) = self.next(left).await else {
                panic!("the event stream gave {dones} of {n} done events: {out:?}");
            };
            if ev.0 == "done" {
                dones += 1;
            }
            out.push(ev);
        }
        out
    }
}

/// The instruction sequences the recorded sessions say, one session per sequence.
pub const SEQUENCES: [[&str; 4]; 4] = [
    [
        "go to the red sofa",
        "go to the fridge",
        "go to the bed",
        "go back",
    ],
    [
        "go to the tv",
        "go to the kitchen",
        "go to the bathtub",
        "go to the black sofa",
    ],
    [
        "go to the counter",
        "go to the office",
        "go to the red sofa",
        "go back",
    ],
    [
        "go to the bathroom",
        "go to the white cabinet",
        "go to the fridge",
        "go to the tv",
    ],
];

/// What a reply must repeat exactly when the same session state meets the same answer:
/// status and code for failures; for answers the outcome, tuples, script, the calls
/// with their poses, the stops and the pose.
pub fn reply_key(status: StatusCode, v: &Value) -> Value {
    if status != StatusCode::OK {
        return json!({"status": status.as_u16(), "code": v["code"]});
    }
    let calls: Vec<Value> = v["trace"]
        .as_array()
        .map(|t| {
            t.iter()
                .map(|e| json!([e["function"], e["pose_after"]]))
                .collect()
        })
        .unwrap_or_default();
    json!({
        "status": 200,
        "instruction": v["instruction"],
        "outcome": v["outcome"],
        "tuples": v["tuples"],
        "script": v["script"],
        "question": v["question"],
        "error": v["error"],
        "calls": calls,
        "stops": v["trajectory"]["stops"],
        "pose": v["pose"],
    })
}

/// p50 and p95 of `ms`.
pub fn percentiles(ms: &mut [f64]) -> (f64, f64) {
    ms.sort_by(f64::total_cmp);
    let at = |q: f64| {
        let i = ((ms.len() as f64 - 1.0) * q).round() as usize;
        ms.get(i).copied().unwrap_or(f64::NAN)
    };
    (at(0.5), at(0.95))
}

/// The process's resident memory, kB (Linux).
pub fn rss_kb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmRSS:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|n| n.parse().ok())
        })
        .unwrap_or(0)
}

/// The SmolLM2 GGUF the tests run, or a failure that says how to fetch it.
pub fn smol() -> Option<PathBuf> {
    ivlmap_tests::model(ivlmap_tests::SMOL)
}

pub fn smol_backend(path: PathBuf) -> LlamaCppBackend {
    // The default prompt holds every worked example (~3,500 tokens): 8192 leaves room
    // for the request and the answer.
    let mut cfg = LlamaCppConfig::new(path);
    cfg.n_ctx = 8192;
    LlamaCppBackend::new(cfg).unwrap()
}

/// The product's default model, if fetched.
pub fn default_model() -> Option<PathBuf> {
    ivlmap_tests::model(ivlmap_tests::DEFAULT_MODEL)
}

/// The default model as the binary runs it: 2 threads, its prompt prefix read back from
/// the product's prompt cache on disk.
pub fn default_backend(path: PathBuf) -> LlamaCppBackend {
    let mut cfg = LlamaCppConfig::new(path);
    cfg.prompt_cache_dir = Some(ivlmap_tests::prompt_cache_dir());
    LlamaCppBackend::new(cfg).unwrap()
}

/// Says `texts` to session `id` one after another; its answers in order.
async fn say_in_order(api: &Api, id: &str, texts: &[&str]) -> Replies {
    let mut replies = Vec::new();
    for text in texts {
        replies.push(api.say(id, text, false).await);
    }
    replies
}

/// A session's answers: (status, body) per instruction.
pub type Replies = Vec<(StatusCode, Value)>;

/// A session's id, the sequence it said, and its answers.
pub type SessionRun = (String, usize, Replies);

/// Sessions run their sequences in parallel; each returns its (status, reply) per
/// instruction and each request's latency in ms.
pub async fn run_sessions(
    api: &Api,
    sessions: usize,
    seq: impl Fn(usize) -> usize,
) -> (Vec<SessionRun>, Vec<f64>) {
    let mut tasks = Vec::new();
    for i in 0..sessions {
        let api = api.clone();
        let k = seq(i);
        tasks.push(tokio::spawn(async move {
            let id = api.session().await;
            let mut replies = Vec::new();
            let mut ms = Vec::new();
            for text in SEQUENCES[k] {
                let t0 = Instant::now();
                replies.push(api.say(&id, text, false).await);
                ms.push(t0.elapsed().as_secs_f64() * 1000.0);
            }
            (id, k, replies, ms)
        }));
    }
    let mut out = Vec::new();
    let mut all_ms = Vec::new();
    for t in tasks {
        let (id, k, replies, ms) = t.await.unwrap();
        all_ms.extend(ms);
        out.push((id, k, replies));
    }
    (out, all_ms)
}

/// The cassette recorded from SmolLM2 through a real server (one worker, one session
/// per sequence, in parallel), one answer per request, and each sequence's replies from
/// it.
pub struct Recorded {
    pub cassette: PathBuf,
    pub replies: Vec<Replies>,
}

/// Records once per test process; `None` (with the reason printed) without SmolLM2.
pub fn recorded() -> Option<&'static Recorded> {
    static REC: OnceLock<Option<Recorded>> = OnceLock::new();
    REC.get_or_init(|| {
        let model = smol()?;
        // Its own runtime on its own thread: callers may be inside a runtime.
        std::thread::spawn(move || {
            tokio::runtime::Builder::new_multi_thread()
                .enable_all()
                .build()
                .unwrap()
                .block_on(record(model))
        })
        .join()
        .unwrap()
    })
    .as_ref()
}

async fn record(model: PathBuf) -> Option<Recorded> {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("serve");
    std::fs::create_dir_all(&dir).unwrap();
    let cassette = dir.join("smollm2-serve.jsonl");
    let _ = std::fs::remove_file(&cassette);
    let backend: Arc<dyn LlmBackend> =
        Arc::new(Recording::new(smol_backend(model), cassette.clone()).unwrap());
    let running = one_worker(backend).await;
    let api = running.api();
    // One listener sees the queue at work.
    let watch_id = api.session().await;
    let mut watch = api.events(&watch_id).await;
    let t0 = Instant::now();
    let watched = {
        let api = api.clone();
        let id = watch_id.clone();
        tokio::spawn(async move { say_in_order(&api, &id, &SEQUENCES[0]).await })
    };
    let (others, mut ms) = run_sessions(&api, SEQUENCES.len() - 1, |i| i + 1).await;
    let first = watched.await.unwrap();
    let wall = t0.elapsed().as_secs_f64();
    let events = watch
        .until_done(SEQUENCES[0].len(), Duration::from_secs(60))
        .await;
    let n = SEQUENCES.len() * SEQUENCES[0].len();
    let (p50, p95) = percentiles(&mut ms);
    println!(
        "load (real model, SmolLM2-135M Q4_1 on llama.cpp, 1 worker): {n} instructions from {} \
         sessions in parallel in {wall:.1} s: {:.2} instructions/s; latency p50 {p50:.0} ms, \
         p95 {p95:.0} ms (of the {} sessions without a listener)",
        SEQUENCES.len(),
        n as f64 / wall,
        SEQUENCES.len() - 1
    );
    // The watched session waited behind others at least once.
    let max_pos = events
        .iter()
        .filter(|(n, _)| n == "queued")
        .filter_map(|(_, d)| d["position"].as_u64())
        .max()
        .unwrap_or(0);
    println!("queue: the watched session saw position {max_pos} at most");
    let mut replies = vec![first];
    replies.extend(others.into_iter().map(|(_, _, r)| r));
    for (k, seq) in replies.iter().enumerate() {
        for (i, (status, v)) in seq.iter().enumerate() {
            println!(
                "  [{k}.{i}] {:?} -> {status} {} {}",
                SEQUENCES[k][i],
                v["outcome"].as_str().or(v["code"].as_str()).unwrap_or("?"),
                v["tuples_text"].as_str().unwrap_or("")
            );
        }
    }
    running.stop().await;
    let once = one_answer_per_request(&cassette);
    Some(Recorded {
        replies: replay_in_turn(&once).await,
        cassette: once,
    })
}

/// The cassette at `path` with the first answer to each request only, written beside it.
///
/// The same request can come back with another answer: the prefix cache evaluates the
/// rest of a prompt in another batch shape than a cold evaluation does, which changes
/// llama.cpp's sums, and SmolLM2-135M's greedy choice flips on that (measured with
/// `cargo run -p llm --example cache_agreement` on this test's recorded requests: 4 of 12
/// answers the same warm and cold). A replay then serves a request's answers in the order
/// sessions ask, which under load is not the recording's. With one answer per request,
/// a replay answers each session the same whatever the order.
fn one_answer_per_request(path: &std::path::Path) -> PathBuf {
    let text = std::fs::read_to_string(path).unwrap();
    let mut kept: Vec<CassetteRecord> = Vec::new();
    let mut out = String::new();
    let mut changed = 0;
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        let r: CassetteRecord = serde_json::from_str(line).unwrap();
        match kept.iter().find(|k| k.request == r.request) {
            Some(k) => changed += usize::from(k.response.text != r.response.text),
            None => {
                out.push_str(line);
                out.push('\n');
                kept.push(r);
            }
        }
    }
    println!(
        "cassette: {} requests, {changed} asked again with another answer (kept the first)",
        kept.len()
    );
    let once = path.with_file_name("smollm2-serve-once.jsonl");
    std::fs::write(&once, out).unwrap();
    once
}

/// Each sequence's replies from a replay of `cassette`, one session after another on one
/// worker: what every session saying that sequence must be answered, whatever the load.
async fn replay_in_turn(cassette: &std::path::Path) -> Vec<Replies> {
    let backend: Arc<dyn LlmBackend> = Arc::new(ReplayBackend::open(cassette).unwrap());
    let running = one_worker(backend).await;
    let api = running.api();
    let mut all = Vec::new();
    for seq in &SEQUENCES {
        let id = api.session().await;
        all.push(say_in_order(&api, &id, seq).await);
    }
    running.stop().await;
    all
}
