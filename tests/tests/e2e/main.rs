//! End-to-end: an instruction in, a trajectory out, through the real parts.
//!
//! - [`language`]: the language layer with the real llama.cpp and SmolLM2, and the
//!   same exchanges replayed from a cassette recorded from it.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests

mod language;
