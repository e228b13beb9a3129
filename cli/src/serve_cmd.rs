//! `ivlmap serve`: the web chat and the HTTP API (formats.md, "HTTP API"), served by
//! the `server` crate on a tokio runtime. The backend opens before the server listens,
//! so a missing model is reported at once; so is the robot (`--robot nav2` connects
//! first: one real robot, driven by one session at a time, see `server::robot`).

use std::io::Write as _;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use agent::Prompts;
use llm::LlmBackend;
use server::{ServeConfig, ServeError, Server, Service, SharedRobot};

use crate::args::ServeArgs;
use crate::backend::open_backend;
use crate::error::CliError;
use crate::mapinfo::load_map;

pub(crate) fn serve(args: &ServeArgs, prompts: Prompts) -> Result<ExitCode, CliError> {
    let Some(path) = args.scene.as_ref().or(args.map.as_ref()) else {
        return Err(CliError::Input(
            "give --scene FILE.scene.json or --map DIR".into(),
        ));
    };
    let map = Arc::new(load_map(path)?);
    let options = args.backend.model_args.plan_options();
    let prompts = crate::retrieval::with_retrieval(prompts, &options);
    let backend: Arc<dyn LlmBackend> = Arc::from(open_backend(&args.backend.choice())?);
    let workers = args
        .workers
        .unwrap_or(if backend.name() == "llama" { 1 } else { 4 });
    let config = ServeConfig {
        addr: args.addr.clone(),
        token: args.token.clone(),
        workers,
        session_ttl: Duration::from_secs(args.session_minutes.max(1) * 60),
        max_sessions: args.max_sessions,
        ..ServeConfig::default()
    };
    let mut service = Service::new(map.clone(), backend.clone());
    service.prompts = prompts;
    service.options = options;
    service.robot = crate::robot::open_real(&args.robot, &map)?
        .map(|r| Arc::new(SharedRobot::new(args.robot.robot.name(), r)));
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .map_err(|e| CliError::Failed(format!("cannot start the async runtime: {e}")))?;
    runtime.block_on(async move {
        let server = Server::bind(config, service).await.map_err(|e| match e {
            ServeError::TokenRequired { .. } | ServeError::Config { .. } => {
                CliError::Input(e.to_string())
            }
            other => CliError::Failed(other.to_string()),
        })?;
        println!(
            "ivlmap serve: map {:?} ({} instances), backend {} ({}), {workers} worker(s), robot {}",
            map.name,
            map.instances.len(),
            backend.name(),
            backend.model(),
            args.robot.robot.name()
        );
        println!(
            "open {} in a browser (Ctrl-C stops){}",
            server.url(),
            if args.token.is_some() {
                "; the page asks for the token"
            } else {
                ""
            }
        );
        let _ = std::io::stdout().flush();
        server
            .run_until(async {
                if tokio::signal::ctrl_c().await.is_err() {
                    // No Ctrl-C handler here: serve until killed.
                    std::future::pending::<()>().await;
                }
            })
            .await
            .map_err(|e| CliError::Failed(e.to_string()))
    })?;
    Ok(ExitCode::SUCCESS)
}
