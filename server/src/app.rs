//! The server: what answers instructions ([`Service`]), binding and running
//! ([`Server`]), and the shared state the routes work on.

use std::future::Future;
use std::net::SocketAddr;
use std::sync::Arc;

use agent::{PlanOptions, Prompts};
use llm::LlmBackend;
use map_core::IvlMap;
use planner_dsl::Limits;
use tokio::net::TcpListener;

use crate::config::ServeConfig;
use crate::error::ServeError;
use crate::mapjson::{map_json, MapJson};
use crate::queue::ModelQueue;
use crate::sessions::SessionStore;

/// What answers instructions: the map, the model and how the language layer uses it.
pub struct Service {
    /// The map every session's robot lives on.
    pub map: Arc<IvlMap>,
    /// The model (shared by every session, reached through the queue).
    pub backend: Arc<dyn LlmBackend>,
    /// The prompts.
    pub prompts: Prompts,
    /// Language-layer knobs (worked examples, grammar, re-ask, ...).
    pub options: PlanOptions,
    /// Limits every script runs under.
    pub limits: Limits,
    /// A real robot that executes plans instead of each session's simulator (one
    /// session drives it at a time); `None`: every session has its own simulator.
    pub robot: Option<Arc<crate::robot::SharedRobot>>,
}

impl std::fmt::Debug for Service {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Service")
            .field("map", &self.map.name)
            .field("backend", &self.backend.name())
            .field("model", &self.backend.model())
            .field("examples", &self.options.examples)
            .field("robot", &self.robot.as_ref().map(|r| r.kind().to_string()))
            .finish_non_exhaustive()
    }
}

impl Service {
    /// A service on `map` answering with `backend`, the built-in prompts and default
    /// options and limits.
    #[must_use]
    pub fn new(map: Arc<IvlMap>, backend: Arc<dyn LlmBackend>) -> Self {
        Self {
            map,
            backend,
            prompts: Prompts::builtin(),
            options: PlanOptions::default(),
            limits: Limits::default(),
            robot: None,
        }
    }
}

/// Everything the routes share.
#[derive(Debug)]
pub(crate) struct AppState {
    pub(crate) config: ServeConfig,
    pub(crate) service: Arc<Service>,
    pub(crate) sessions: SessionStore,
    pub(crate) queue: ModelQueue,
    pub(crate) map_json: MapJson,
    /// Turns true when the server shuts down: event streams end, so that shutting down
    /// does not wait on pages that listen forever.
    pub(crate) closing: tokio::sync::watch::Sender<bool>,
}

/// A bound server: [`Server::bind`] then [`Server::run`].
#[derive(Debug)]
pub struct Server {
    listener: TcpListener,
    addr: SocketAddr,
    state: Arc<AppState>,
}

impl Server {
    /// Checks `config`, resolves and binds its address, and starts the model workers.
    ///
    /// # Errors
    /// [`ServeError::TokenRequired`] off loopback without a token, [`ServeError::Config`]
    /// for unusable limits, [`ServeError::Bind`] when the address cannot be had.
    pub async fn bind(config: ServeConfig, service: Service) -> Result<Server, ServeError> {
        let bind_err = |source| ServeError::Bind {
            addr: config.addr.clone(),
            source,
        };
        let addrs: Vec<SocketAddr> = tokio::net::lookup_host(config.addr.as_str())
            .await
            .map_err(bind_err)?
            .collect();
        let Some(first) = addrs.first().copied() else {
            return Err(bind_err(std::io::Error::new(
                std::io::ErrorKind::AddrNotAvailable,
                "the name resolves to no address",
            )));
        };
        for a in &addrs {
            config.check(*a)?;
        }
        let listener = TcpListener::bind(first).await.map_err(bind_err)?;
        let addr = listener.local_addr().map_err(bind_err)?;
        let queue = ModelQueue::new(config.workers, config.max_queue).map_err(bind_err)?;
        let sessions =
            SessionStore::new(service.map.clone(), config.max_sessions, config.session_ttl);
        let map_json = map_json(&service.map);
        Ok(Server {
            listener,
            addr,
            state: Arc::new(AppState {
                config,
                service: Arc::new(service),
                sessions,
                queue,
                map_json,
                closing: tokio::sync::watch::Sender::new(false),
            }),
        })
    }

    /// The address it listens on (with the port picked when 0 was asked).
    #[must_use]
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// `http://host:port/`.
    #[must_use]
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// Serves until the process ends.
    ///
    /// # Errors
    /// [`ServeError::Io`] when serving fails.
    pub async fn run(self) -> Result<(), ServeError> {
        self.run_until(std::future::pending()).await
    }

    /// Serves until `shutdown` completes, then finishes the requests in flight and the
    /// model jobs already running (those still waiting are dropped unrun).
    ///
    /// # Errors
    /// [`ServeError::Io`] when serving fails.
    pub async fn run_until(
        self,
        shutdown: impl Future<Output = ()> + Send + 'static,
    ) -> Result<(), ServeError> {
        let state = self.state.clone();
        let sweep = Arc::downgrade(&self.state);
        let every = (state.sessions.ttl() / 4).clamp(
            std::time::Duration::from_millis(200),
            std::time::Duration::from_secs(30),
        );
        let sweeper = tokio::spawn(async move {
            loop {
                tokio::time::sleep(every).await;
                let Some(s) = sweep.upgrade() else { break };
                let n = s.sessions.expire();
                if n > 0 {
                    tracing::info!("{n} idle session(s) expired");
                }
            }
        });
        let closing = state.closing.clone();
        let app = crate::routes::router(state.clone());
        let served = axum::serve(self.listener, app)
            .with_graceful_shutdown(async move {
                shutdown.await;
                let _ = closing.send(true);
            })
            .await;
        sweeper.abort();
        // A job whose requester timed out may still be running on a model thread: wait
        // for it, so that the process never exits while llama.cpp computes.
        let _ = tokio::task::spawn_blocking(move || state.queue.shutdown()).await;
        served.map_err(ServeError::Io)
    }
}
