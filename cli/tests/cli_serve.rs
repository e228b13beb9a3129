//! `ivlmap serve` as a user starts it: the README's command prints the address, and the
//! page and the API answer there; off loopback without a token it refuses to start.
//! (The API itself is tested in server/tests/.)

#![allow(clippy::unwrap_used, clippy::expect_used)] // tests

mod support;
use support::{ivlmap, repo, text};

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn empty_cassette(dir: &tempfile::TempDir) -> String {
    let p = dir.path().join("empty.jsonl");
    std::fs::write(&p, "").unwrap();
    p.display().to_string()
}

/// `GET path` over plain HTTP/1.1: (status line, body).
fn get(addr: &str, path: &str) -> (String, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    let status = out.lines().next().unwrap_or_default().to_string();
    let body = out
        .split_once("\r\n\r\n")
        .map(|(_, b)| b.to_string())
        .unwrap_or_default();
    (status, body)
}

#[test]
fn serve_prints_its_address_and_serves_the_page_and_the_api() {
    let d = tempfile::tempdir().unwrap();
    let cassette = empty_cassette(&d);
    let mut child = Command::new(env!("CARGO_BIN_EXE_ivlmap"))
        .args([
            "serve",
            "--scene",
            "examples/scenes/flat-a.scene.json",
            "--addr",
            "127.0.0.1:0",
            "--backend",
            "replay",
            "--cassette",
            &cassette,
        ])
        .current_dir(repo())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let t0 = Instant::now();
    let mut addr = None;
    let mut said = String::new();
    while addr.is_none() && t0.elapsed() < Duration::from_secs(30) {
        let Some(Ok(line)) = lines.next() else { break };
        said.push_str(&line);
        said.push('\n');
        addr = line
            .split_whitespace()
            .find_map(|w| w.strip_prefix("http://"))
            .map(|a| a.trim_end_matches('/').to_string());
    }
    let addr = addr.unwrap_or_else(|| {
        let _ = child.kill();
        panic!("no address printed: {said}")
    });
    assert!(said.contains("flat-a") && said.contains("replay"), "{said}");
    let (status, body) = get(&addr, "/");
    assert!(status.contains("200"), "{status}");
    assert!(body.contains("<canvas id=\"map\""), "{body}");
    let (status, body) = get(&addr, "/api/info");
    assert!(status.contains("200"), "{status}");
    assert!(body.contains("\"backend\":\"replay\""), "{body}");
    let _ = child.kill();
    let _ = child.wait();
}

#[test]
fn serve_refuses_a_public_address_without_a_token() {
    let d = tempfile::tempdir().unwrap();
    let cassette = empty_cassette(&d);
    let o = ivlmap(&[
        "serve",
        "--scene",
        "examples/scenes/flat-a.scene.json",
        "--addr",
        "0.0.0.0:0",
        "--backend",
        "replay",
        "--cassette",
        &cassette,
    ]);
    let (_, err) = text(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--token") && err.contains("0.0.0.0"), "{err}");
    // Neither a scene nor a map: a usage error.
    let o = ivlmap(&["serve"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).1.contains("--scene"), "{}", text(&o).1);
}
