//! # ivlmap-tests: cross-crate end-to-end tests and the helpers every test crate shares
//!
//! The end-to-end tests (instruction in, trajectory out, across `llm`, `agent`,
//! `planner_dsl` and `map_core`) are one test binary, `tests/e2e/`, with a module per
//! area. This library holds what the workspace's integration tests share: the
//! repository root, the models folder, the real-binary runner.
#![warn(missing_docs)]
#![allow(clippy::expect_used)] // test helpers: a missing HOME is a broken test machine

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root (where `examples/` is).
#[must_use]
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map_or_else(|| PathBuf::from(".."), Path::to_path_buf)
}

/// Runs a real binary (`env!("CARGO_BIN_EXE_ivlmap")` in the test crate that owns it)
/// from the repository root, without the environment that would change its output
/// (log filters, a remote backend's URL).
#[must_use]
pub fn run_binary(bin: &str, args: &[&str]) -> Output {
    Command::new(bin)
        .args(args)
        .current_dir(repo())
        .env_remove("RUST_LOG")
        .env_remove("IVLMAP_BASE_URL")
        .output()
        .expect("run the binary")
}

/// stdout and stderr as text.
#[must_use]
pub fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).to_string(),
        String::from_utf8_lossy(&o.stderr).to_string(),
    )
}

/// The models folder the product reads (`$IVLMAP_MODELS`, else
/// `~/.cache/ivlmap/models`; see `scripts/fetch-models.sh`).
#[must_use]
pub fn models_dir() -> PathBuf {
    map_core::models::models_dir().expect("HOME or IVLMAP_MODELS is set")
}

/// The SmolLM2 GGUF the tests run llama.cpp with.
pub const SMOL: &str = "SmolLM2-135M-Instruct.Q4_1.gguf";

/// The product's default model (the binary's `DEFAULT_MODEL_FILE`), for the tests that
/// need an answer a person would accept, not only a well-formed one: SmolLM2-135M answers
/// "go to the fridge" with a colour nobody said, and the checks rightly turn that into a
/// question.
pub const DEFAULT_MODEL: &str = "qwen2.5-coder-1.5b-instruct-q4_k_m.gguf";

/// The product's prompt cache folder (`~/.cache/ivlmap/prompt-cache`, as the binary's
/// default): a test with the default model reads its prompt prefix back from there
/// instead of evaluating ~3,500 tokens again (about 10 s instead of 150 s on 2 threads).
#[must_use]
pub fn prompt_cache_dir() -> PathBuf {
    models_dir().parent().map_or_else(
        || models_dir().join("prompt-cache"),
        |p| p.join("prompt-cache"),
    )
}

/// A model file in the models folder (or an absolute path), or `None` with the reason
/// printed when it has not been fetched.
#[must_use]
pub fn model(name: &str) -> Option<PathBuf> {
    let p = PathBuf::from(name);
    let p = if p.is_absolute() {
        p
    } else {
        models_dir().join(name)
    };
    if p.is_file() {
        Some(p)
    } else {
        eprintln!(
            "SKIPPED: {} is absent; run scripts/fetch-models.sh",
            p.display()
        );
        None
    }
}
