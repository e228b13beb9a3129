//! Shared by the DDS tests: the network namespace and venv helpers (`netns`), and a
//! Nav2 stand-in written with ros2-client's action server (`standin`).
#![allow(dead_code)]

pub mod netns;
pub mod standin;

pub use netns::*;
