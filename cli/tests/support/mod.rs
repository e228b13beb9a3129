//! What the CLI tests share: the workspace's test helpers, and the real `ivlmap`
//! binary of this crate.
#![allow(dead_code, unused_imports)] // each test file uses some of them

use std::process::Output;

pub use ivlmap_tests::{repo, text};

/// `ivlmap chat --scene examples/scenes/flat-a.scene.json ARGS` from the repository
/// root with `input` on stdin: (exit code, stdout, stderr).
pub fn chat(input: &str, args: &[&str]) -> (Option<i32>, String, String) {
    use std::io::Write as _;
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_ivlmap"))
        .args(["chat", "--scene", "examples/scenes/flat-a.scene.json"])
        .args(args)
        .current_dir(repo())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("ivlmap starts");
    if let Some(mut stdin) = child.stdin.take() {
        stdin
            .write_all(input.as_bytes())
            .expect("stdin takes the input");
    }
    let o = child.wait_with_output().expect("ivlmap ends");
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stdout).to_string(),
        String::from_utf8_lossy(&o.stderr).to_string(),
    )
}

/// Runs the real `ivlmap` binary from the repository root (see
/// [`ivlmap_tests::run_binary`]).
pub fn ivlmap(args: &[&str]) -> Output {
    ivlmap_tests::run_binary(env!("CARGO_BIN_EXE_ivlmap"), args)
}
