//! The page in a real browser: Debian's chromium, headless, driven through
//! chromedriver with fantoccini, against the real server with the product's default model (Qwen2.5-Coder-1.5B). It
//! clicks an object on the map (its words go into the input), sends the instruction,
//! waits for the run, and checks that the chat shows the tuples, the script and the
//! trace and that the robot marker moved; then previews a second instruction (a dashed
//! path, the robot stays) and confirms it. Screenshots go under the cargo target
//! directory (`target/tmp/serve/browser-preview.png` and `browser.png`).
//!
//! chromium and chromium-driver come from `scripts/setup.sh` (apt); without them this
//! test fails and says so.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests

mod support;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::time::{Duration, Instant};

use fantoccini::actions::{InputSource, MouseActions, PointerAction, MOUSE_BUTTON_LEFT};
use fantoccini::{ClientBuilder, Locator};
use llm::LlmBackend;
use serde_json::{json, Value};
use server::Service;
use support::*;

const CHROMIUM: &str = "/usr/bin/chromium";
const CHROMEDRIVER: &str = "/usr/bin/chromedriver";

/// chromedriver on a free port, killed on drop.
struct Driver {
    child: Child,
    port: u16,
}

impl Drop for Driver {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn found(env: &str, default: &str) -> PathBuf {
    let p = std::env::var_os(env).map_or_else(|| PathBuf::from(default), PathBuf::from);
    assert!(
        p.is_file(),
        "{} is missing: the browser test needs Debian's chromium and chromium-driver \
         (run scripts/setup.sh, which installs them with apt; or set {env})",
        p.display()
    );
    p
}

async fn driver() -> Driver {
    let bin = found("IVLMAP_CHROMEDRIVER", CHROMEDRIVER);
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let child = Command::new(bin)
        .arg(format!("--port={port}"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start chromedriver");
    let d = Driver { child, port };
    let t0 = Instant::now();
    while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
        assert!(
            t0.elapsed() < Duration::from_secs(20),
            "chromedriver did not start"
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    d
}

async fn wait_js(c: &fantoccini::Client, script: &str, what: &str, limit: Duration) -> Value {
    let t0 = Instant::now();
    loop {
        let v = c.execute(script, vec![]).await.unwrap();
        if !(v.is_null() || v == json!(false) || v == json!("")) {
            return v;
        }
        assert!(
            t0.elapsed() < limit,
            "timed out after {limit:?} waiting for {what}"
        );
        tokio::time::sleep(Duration::from_millis(150)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn chat_in_a_real_browser_moves_the_robot_on_the_map() {
    let chromium = found("IVLMAP_CHROMIUM", CHROMIUM);
    let model = default_model()
        .expect("the default model is missing: run scripts/setup.sh (scripts/fetch-models.sh)");
    let backend: Arc<dyn LlmBackend> = Arc::new(default_backend(model));
    let running = start(Service::new(flat_a(), backend), local()).await;
    let driver = driver().await;

    let profile = tempfile::tempdir().unwrap();
    let args = vec![
        "--headless".to_string(),
        "--no-sandbox".into(),
        "--disable-gpu".into(),
        "--disable-quic".into(),
        "--no-first-run".into(),
        "--disable-background-networking".into(),
        "--disable-component-update".into(),
        "--disable-sync".into(),
        "--disable-dev-shm-usage".into(),
        "--hide-scrollbars".into(),
        "--window-size=1440,900".into(),
        format!("--user-data-dir={}", profile.path().display()),
    ];
    let mut caps = serde_json::Map::new();
    caps.insert(
        "goog:chromeOptions".into(),
        json!({"binary": chromium.display().to_string(), "args": args}),
    );
    let c = ClientBuilder::new(hyper_util::client::legacy::connect::HttpConnector::new())
        .capabilities(caps)
        .connect(&format!("http://127.0.0.1:{}", driver.port))
        .await
        .expect("a chromium session through chromedriver");

    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("serve");
    std::fs::create_dir_all(&dir).unwrap();
    let result = drive(&c, &running.url, &dir).await;
    let shot = c.screenshot().await;
    let _ = c.close().await;
    let path = dir.join("browser.png");
    if let Ok(png) = shot {
        std::fs::write(&path, png).unwrap();
        println!("screenshot: {}", path.display());
    }
    result.unwrap_or_else(|e| panic!("{e} (screenshot: {})", path.display()));
    assert!(Path::new(&path).is_file());
    running.stop().await;
}

/// The user's part; an error says what the page failed to show.
async fn drive(c: &fantoccini::Client, url: &str, dir: &Path) -> Result<(), String> {
    c.goto(url)
        .await
        .map_err(|e| format!("cannot open {url}: {e}"))?;
    // The page has drawn the map, made its session and opened its event stream.
    wait_js(
        c,
        "const m = document.getElementById('map'); return m.dataset.events === 'open' && m.dataset.pose;",
        "the page to start",
        Duration::from_secs(20),
    )
    .await;
    let start = pose(c).await?;
    let backend = c
        .find(Locator::Id("backend"))
        .await
        .map_err(|e| e.to_string())?
        .text()
        .await
        .map_err(|e| e.to_string())?;
    if !backend.contains("llama") || !backend.contains("qwen2.5-coder") {
        return Err(format!(
            "the header should name the backend and model: {backend:?}"
        ));
    }

    // Click the fridge on the canvas: its words go into the input.
    let (x, y) = {
        let v = c
            .execute(
                "const S = window.ivlmap; const f = S.map.instances.find(i => i.label === 'fridge');
                 const r = document.getElementById('map').getBoundingClientRect();
                 return [r.left + S.view.ox + f.centroid[0] * S.view.scale,
                         r.top + S.view.oy - f.centroid[1] * S.view.scale];",
                vec![],
            )
            .await
            .map_err(|e| e.to_string())?;
        (v[0].as_f64().unwrap_or(0.0), v[1].as_f64().unwrap_or(0.0))
    };
    let pointer = MouseActions::new("mouse".into())
        .then(PointerAction::MoveTo {
            duration: None,
            x: x.round(),
            y: y.round(),
        })
        .then(PointerAction::Down {
            button: MOUSE_BUTTON_LEFT,
        })
        .then(PointerAction::Up {
            button: MOUSE_BUTTON_LEFT,
        });
    c.perform_actions(pointer)
        .await
        .map_err(|e| e.to_string())?;
    let input = c
        .find(Locator::Id("input"))
        .await
        .map_err(|e| e.to_string())?;
    let typed = input
        .prop("value")
        .await
        .map_err(|e| e.to_string())?
        .unwrap_or_default();
    if typed != "go to the fridge" {
        return Err(format!(
            "clicking the fridge should put \"go to the fridge\" into the input, not {typed:?}"
        ));
    }
    // Send it.
    c.find(Locator::Id("send"))
        .await
        .map_err(|e| e.to_string())?
        .click()
        .await
        .map_err(|e| e.to_string())?;

    // Wait for the run to end and the robot to finish its drive.
    wait_js(
        c,
        "const o = document.querySelector('.turn .outcome'); return o && !window.ivlmap.animating && !window.ivlmap.busy ? o.className : null;",
        "the answer",
        // The first answer evaluates the prompt prefix when the prompt cache on disk does
        // not hold it yet (about 150 s on 2 threads); later runs read it back (~10 s).
        Duration::from_secs(400),
    )
    .await;
    let outcome = text_of(c, ".turn .outcome").await?;
    let tuples = text_of(c, ".turn .tuples").await?;
    let script = text_of(c, ".turn pre.script").await?;
    let trace = text_of(c, ".turn ol.trace").await?;
    println!("outcome: {outcome}\ntuples: {tuples}\nscript: {script}\ntrace: {trace}");
    if !outcome.starts_with("done") {
        return Err(format!("the run should be done, the page says {outcome:?}"));
    }
    if !tuples.contains("fridge") {
        return Err(format!("the tuples should name the fridge: {tuples:?}"));
    }
    if !script.contains("move_to") {
        return Err(format!("the script should move the robot: {script:?}"));
    }
    if !trace.contains("move_to") {
        return Err(format!("the trace should list the move: {trace:?}"));
    }
    let now = pose(c).await?;
    if now == start || now.is_empty() {
        return Err(format!(
            "the robot marker should have moved from {start}, it is at {now}"
        ));
    }
    let stops = c
        .execute(
            "return document.getElementById('map').dataset.stops",
            vec![],
        )
        .await
        .map_err(|e| e.to_string())?;
    if stops != json!("1") {
        return Err(format!("one numbered stop should be drawn, not {stops}"));
    }
    // Near the fridge (centre 11.35, 4.55).
    near(&now, [11.35, 4.55], 1.5, "the fridge")?;

    // Preview the next instruction: a dashed path, nothing moves; confirm runs it.
    let input = c
        .find(Locator::Id("input"))
        .await
        .map_err(|e| e.to_string())?;
    input
        .send_keys("go to the bed")
        .await
        .map_err(|e| e.to_string())?;
    c.find(Locator::Id("preview"))
        .await
        .map_err(|e| e.to_string())?
        .click()
        .await
        .map_err(|e| e.to_string())?;
    wait_js(
        c,
        "return document.querySelector('.outcome.preview .confirm') && !window.ivlmap.busy ? true : null",
        "the preview",
        Duration::from_secs(90),
    )
    .await;
    let preview = c
        .execute(
            "return window.ivlmap.preview ? window.ivlmap.preview.path.length : 0",
            vec![],
        )
        .await
        .map_err(|e| e.to_string())?;
    if preview.as_u64().unwrap_or(0) < 2 {
        return Err(format!(
            "the preview path should be drawn, it has {preview} points"
        ));
    }
    if pose(c).await? != now {
        return Err("a preview must not move the robot".into());
    }
    if let Ok(png) = c.screenshot().await {
        let p = dir.join("browser-preview.png");
        std::fs::write(&p, png).map_err(|e| e.to_string())?;
        println!("screenshot: {}", p.display());
    }
    c.execute(
        "document.querySelector('.outcome.preview .confirm').scrollIntoView()",
        vec![],
    )
    .await
    .map_err(|e| e.to_string())?;
    c.find(Locator::Css(".outcome.preview .confirm"))
        .await
        .map_err(|e| e.to_string())?
        .click()
        .await
        .map_err(|e| e.to_string())?;
    wait_js(
        c,
        "const o = document.querySelectorAll('.turn .outcome.done'); return o.length === 2 && !window.ivlmap.animating && !window.ivlmap.busy ? true : null",
        "the confirmed run",
        Duration::from_secs(60),
    )
    .await;
    let stops = c
        .execute(
            "return document.getElementById('map').dataset.stops",
            vec![],
        )
        .await
        .map_err(|e| e.to_string())?;
    if stops != json!("2") {
        return Err(format!("two numbered stops should be drawn, not {stops}"));
    }
    near(&pose(c).await?, [1.3, 7.6], 2.0, "the bed")
}

async fn pose(c: &fantoccini::Client) -> Result<String, String> {
    Ok(
        c.execute("return document.getElementById('map').dataset.pose", vec![])
            .await
            .map_err(|e| e.to_string())?
            .as_str()
            .unwrap_or_default()
            .to_string(),
    )
}

fn near(pose: &str, to: [f64; 2], within: f64, what: &str) -> Result<(), String> {
    let xy: Vec<f64> = pose.split(',').filter_map(|v| v.parse().ok()).collect();
    if xy.len() != 3 || (xy[0] - to[0]).hypot(xy[1] - to[1]) > within {
        return Err(format!("the robot should be by {what}, it is at {pose}"));
    }
    Ok(())
}

async fn text_of(c: &fantoccini::Client, css: &str) -> Result<String, String> {
    c.find(Locator::Css(css))
        .await
        .map_err(|e| format!("the page shows no {css}: {e}"))?
        .text()
        .await
        .map_err(|e| e.to_string())
}
