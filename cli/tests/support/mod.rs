//! What the CLI tests share: the workspace's test helpers, and the real `ivlmap`
//! binary of this crate.
#![allow(dead_code, unused_imports)] // each test file uses some of them

use std::process::Output;

pub use ivlmap_tests::{repo, text};

/// Runs the real `ivlmap` binary from the repository root (see
/// [`ivlmap_tests::run_binary`]).
pub fn ivlmap(args: &[&str]) -> Output {
    ivlmap_tests::run_binary(env!("CARGO_BIN_EXE_ivlmap"), args)
}
