//! Helpers shared by the agent's integration tests (`mod support;` in each file that
//! uses them): the repository root, the real `ivlmap` binary, and the models folder.
#![allow(dead_code, clippy::expect_used)] // each test file uses some of them

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root (where `examples/` is).
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Runs the real `ivlmap` binary from the repository root, without the environment
/// that would change its output (log filters, a remote backend's URL).
pub fn ivlmap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ivlmap"))
        .args(args)
        .current_dir(repo())
        .env_remove("RUST_LOG")
        .env_remove("IVLMAP_BASE_URL")
        .output()
        .expect("run ivlmap")
}

/// stdout and stderr as text.
pub fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).to_string(),
        String::from_utf8_lossy(&o.stderr).to_string(),
    )
}

/// The models folder the product reads (`$IVLMAP_MODELS`, else
/// `~/.cache/ivlmap/models`; see `scripts/fetch-models.sh`).
pub fn models_dir() -> PathBuf {
    map_core::models_dir().expect("HOME or IVLMAP_MODELS is set")
}

/// The SmolLM2 GGUF the tests run llama.cpp with.
pub const SMOL: &str = "SmolLM2-135M-Instruct.Q4_1.gguf";
