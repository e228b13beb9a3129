//! `ivlmap`: talk to a (simulated) robot on an instance-level semantic map, run
//! missions, and evaluate prompts and models on suites. See `ivlmap --help`.
//!
//! Exit status: 0 success; 1 a plan, mission or backend failed; 2 bad usage or a
//! missing/malformed input file.

mod args;
mod backend;
mod chat;
mod commands;
mod error;
mod eval_cmd;
mod mapbuild;
mod mapinfo;
mod mission;
mod noise_cmd;
mod retrieval;
mod robot;
mod serve_cmd;

use std::path::Path;
use std::process::ExitCode;

use agent::Prompts;
use clap::Parser;

use crate::args::{Cli, Command};
use crate::backend::BackendChoice;
use crate::error::CliError;

fn main() -> ExitCode {
    let cli = Cli::parse();
    init_logging(cli.verbose);
    match dispatch(cli.command) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("ivlmap: error: {e}");
            ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(1))
        }
    }
}

fn init_logging(verbose: u8) {
    // llama.cpp warns about harmless model quirks at load time: keep those for -v.
    let level = match verbose {
        0 => "warn,llama-cpp-2=error,llama.cpp=error",
        1 => "info",
        2 => "debug",
        _ => "trace",
    };
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(level));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .try_init();
}

fn prompts(dir: Option<&Path>) -> Result<Prompts, CliError> {
    match dir {
        Some(d) => Prompts::load(d).map_err(CliError::input),
        None => Ok(Prompts::builtin()),
    }
}

fn dispatch(cmd: Command) -> Result<ExitCode, CliError> {
    match cmd {
        Command::Chat {
            scene,
            backend,
            prompts: p,
            robot,
        } => commands::chat(&scene, backend.choice(), prompts(p.as_deref())?, &robot),
        Command::Run {
            mission,
            scene,
            trajectory,
            png,
            backend,
            prompts: p,
            robot,
        } => commands::run(
            &mission,
            scene,
            trajectory,
            png,
            &backend.choice(),
            &prompts(p.as_deref())?,
            &robot,
        ),
        Command::Plan {
            instruction,
            scene,
            json,
            backend,
            prompts: p,
        } => commands::plan(
            &instruction,
            &scene,
            json,
            &backend.choice(),
            &retrieval::with_retrieval(prompts(p.as_deref())?, &backend.model_args.plan_options()),
            backend.model_args.plan_options(),
        ),
        Command::Eval {
            suite,
            backends,
            model_args,
            prompts: p,
            report,
            baseline,
        } => {
            let choices: Vec<BackendChoice> =
                backends.iter().map(|b| model_args.choice(b)).collect();
            eval_cmd::eval(
                &suite,
                &choices,
                &p,
                &report,
                baseline,
                &model_args.plan_options(),
            )
        }
        Command::Map { command } => commands::map_cmd(command),
        Command::Serve(args) => serve_cmd::serve(&args, prompts(args.prompts.as_deref())?),
        Command::NoiseStudy(args) => noise_cmd::noise_study_cli(&args).map(|()| ExitCode::SUCCESS),
    }
}
