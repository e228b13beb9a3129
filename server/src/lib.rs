//! # server: `ivlmap serve`, a web chat with the live map and the HTTP API
//!
//! One process serves the page and the API of formats.md ("HTTP API"). Each session
//! has its own simulated robot and conversation (agent's [`agent::Session`]); the
//! model answers one instruction at a time (or `workers` at once) from a queue whose
//! position the page shows; a run's steps reach the page as server-sent events.
//!
//! - [`config`]: address, token, limits ([`ServeConfig`]).
//! - [`app`]: [`Service`] (map, backend, prompts, options) and [`Server`] (bind, run).
//! - [`sessions`]: the bounded session store, idle expiry, per-session events.
//! - [`queue`]: the first-come-first-served model queue with positions.
//! - [`robot`]: [`SharedRobot`], the one real robot (`--robot nav2`) a session drives
//!   at a time.
//! - [`reply`]: the instruction answer and the `step` events of a run.
//! - [`mapjson`]: `GET /api/map`, the map as the page draws it.
//! - [`describe`]: words that pick an instance out ("the second yellow table from the west").
//! - [`error`]: [`ServeError`] (cannot start) and [`ApiError`] (a failed request).
//!
//! Failed requests (4xx/5xx) leave their session exactly as it was: an instruction is
//! planned and run on copies, which replace the session's robot and history only when
//! everything worked. A plan that stops part-way is not a failed request: the robot
//! stays where it stopped (as in `ivlmap chat`), and undo goes back.
//!
//! With a real robot ([`Service::robot`]) plans and previews stay on the simulator (at
//! the robot's pose), execution drives the robot, one session at a time
//! ([`robot`]); a run on it cannot be taken back, so undo there only forgets the
//! instruction.
//!
//! ```no_run
//! # async fn demo() -> Result<(), server::ServeError> {
//! use std::sync::Arc;
//! use map_core::{IvlMap, Scene};
//! let scene = Scene::from_path("examples/scenes/flat-a.scene.json").expect("scene");
//! let map = Arc::new(IvlMap::from_scene(&scene));
//! let backend = Arc::new(llm::ReplayBackend::open("recorded.jsonl").expect("cassette"));
//! let server = server::Server::bind(server::ServeConfig::default(), server::Service::new(map, backend)).await?;
//! println!("open {}", server.url());
//! server.run().await
//! # }
//! ```

#![warn(missing_docs)]

pub mod app;
pub mod config;
pub mod describe;
pub mod error;
pub mod mapjson;
mod page;
pub mod queue;
pub mod reply;
pub mod robot;
mod routes;
pub mod sessions;

pub use app::{Server, Service};
pub use config::ServeConfig;
pub use error::{ApiError, ServeError};
pub use robot::SharedRobot;
