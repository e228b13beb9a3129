//! `ivlmap`: talk to a (simulated) robot on an instance-level semantic map, run
//! missions, and evaluate prompts and models on suites. See `ivlmap --help`.
//!
//! Exit status: 0 success; 1 a plan, mission or backend failed; 2 bad usage or a
//! missing/malformed input file.

use std::io::{BufRead, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

use agent::{
    inspect_table, load_extract_suite, load_map, load_mission, load_nav_suite, open_backend,
    render_map, run_extract, run_mission, run_nav, summary_table, tuples_paper_form, write_json,
    BackendChoice, Chat, ChatFlow, CliError, LlmBackend, Method, Outcome, PlanContext, PlanOptions,
    Prompts, Report, SuiteKind, CHAT_HELP,
};
use clap::{Args, Parser, Subcommand, ValueEnum};

#[derive(Debug, Parser)]
#[command(
    name = "ivlmap",
    version,
    about = "Language to robot plans on an instance-level semantic map (IVLMap)"
)]
struct Cli {
    /// More log output on stderr (-v info, -vv debug, -vvv trace); RUST_LOG overrides.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Chat with the robot: each instruction is planned, shown and executed.
    Chat {
        /// Scene file (.scene.json) or saved map folder.
        #[arg(long)]
        scene: PathBuf,
        #[command(flatten)]
        backend: BackendArgs,
        /// Prompt folder (a variant overlaying the built-in templates).
        #[arg(long)]
        prompts: Option<PathBuf>,
    },
    /// Run a mission unattended: a .rhai plan or a list of instructions (one per line, # comments).
    Run {
        /// The mission file.
        mission: PathBuf,
        /// Scene file or map folder (default: the mission's `scene:` header comment).
        #[arg(long)]
        scene: Option<PathBuf>,
        /// Write the trajectory JSON here (also when the mission fails part-way).
        #[arg(long)]
        trajectory: Option<PathBuf>,
        /// Draw the map with the trajectory to this PNG.
        #[arg(long)]
        png: Option<PathBuf>,
        #[command(flatten)]
        backend: BackendArgs,
        /// Prompt folder (a variant overlaying the built-in templates).
        #[arg(long)]
        prompts: Option<PathBuf>,
    },
    /// Show the tuples and the script for an instruction; run nothing.
    Plan {
        /// The instruction.
        instruction: String,
        /// Scene file or map folder.
        #[arg(long)]
        scene: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        backend: BackendArgs,
        /// Prompt folder (a variant overlaying the built-in templates).
        #[arg(long)]
        prompts: Option<PathBuf>,
    },
    /// Evaluate an extraction (.extract.jsonl) or navigation (.nav.jsonl) suite.
    Eval {
        /// The suite file.
        suite: PathBuf,
        /// Backend(s); several give a side-by-side table.
        #[arg(long = "backend", value_name = "B", default_value = "llama")]
        backends: Vec<String>,
        #[command(flatten)]
        model_args: ModelArgs,
        /// Prompt variant folder(s); several give a side-by-side table (default: built-in).
        #[arg(long = "prompts", value_name = "DIR")]
        prompts: Vec<PathBuf>,
        /// Write the report JSON here (with several runs: FILE's stem plus the run's label).
        #[arg(long)]
        report: PathBuf,
        /// Navigation: run a baseline instead of ivlmap (vlmap: nearest instance of each
        /// category, as VLMaps; reference: each task's hand-written plan, no model).
        #[arg(long, value_enum)]
        baseline: Option<Baseline>,
    },
    /// Map tools: inspect, render, save.
    Map {
        #[command(subcommand)]
        command: MapCommand,
    },
    /// Navigation under simulated perception noise: reference plans (ivlmap) and the
    /// VLMaps baseline on maps built from corrupted perception, scored on the true scene.
    NoiseStudy(agent::NoiseStudyArgs),
}

#[derive(Debug, Subcommand)]
enum MapCommand {
    /// Print the instance table (id, label, k/n, colour, area, centroid) and regions.
    Inspect {
        /// Scene file or saved map folder.
        map: PathBuf,
    },
    /// Draw the map (optionally with a trajectory) to a PNG.
    Render {
        /// Scene file or saved map folder.
        map: PathBuf,
        /// The PNG to write.
        #[arg(long)]
        out: PathBuf,
        /// A trajectory JSON (from `ivlmap run --trajectory`) to draw on top.
        #[arg(long)]
        trajectory: Option<PathBuf>,
    },
    /// Rasterise a scene and save the map folder (map.json, instances.json, .npy layers).
    Save {
        /// Scene file.
        scene: PathBuf,
        /// The folder to write.
        #[arg(long)]
        out: PathBuf,
    },
    /// Build a map folder from perception outputs (SAM masks + label map), an RGB-D
    /// dataset or a VLMaps map, and print what was kept and dropped.
    Build(Box<agent::MapBuildArgs>),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Baseline {
    /// VLMaps: the nearest instance of each mentioned category (no ordinals, no colours).
    Vlmap,
    /// The suite's hand-written reference plans (no model).
    Reference,
}

#[derive(Debug, Args)]
struct BackendArgs {
    /// LLM backend: llama (local GGUF), openai (OpenAI-compatible server), replay (cassette).
    #[arg(long, default_value = "llama")]
    backend: String,
    #[command(flatten)]
    model_args: ModelArgs,
}

impl BackendArgs {
    fn choice(&self) -> BackendChoice {
        self.model_args.choice(&self.backend)
    }
}

/// Backend settings shared by every command that talks to a model.
#[derive(Debug, Args)]
struct ModelArgs {
    /// llama: GGUF file (default ~/.cache/ivlmap/models/qwen2.5-coder-1.5b-instruct-q4_k_m.gguf,
    /// IVLMAP_MODELS overrides the folder); openai: model id.
    #[arg(long)]
    model: Option<String>,
    /// openai: server base URL (else IVLMAP_BASE_URL; key from IVLMAP_API_KEY).
    #[arg(long)]
    base_url: Option<String>,
    /// replay: the cassette to answer from.
    #[arg(long)]
    cassette: Option<PathBuf>,
    /// Record every request and answer to this cassette.
    #[arg(long)]
    record: Option<PathBuf>,
    /// llama: CPU threads.
    #[arg(long)]
    threads: Option<u32>,
    /// Grammar-constrained decoding (llama; an openai server gets the grammar only if it
    /// takes one): `tuples` holds step 1 to the tuple notation, `script` holds step 2 to
    /// calls of the function library.
    #[arg(long, value_enum, default_value_t = Grammar::Tuples)]
    grammar: Grammar,
    /// Use step 1's tuples as the model wrote them: no re-ask on missed words and no
    /// reconciliation with the instruction's words (measures the model alone).
    #[arg(long)]
    raw_tuples: bool,
}

/// Which steps decode under a GBNF grammar.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Grammar {
    /// Neither.
    None,
    /// Step 1 (tuples).
    Tuples,
    /// Step 2 (scripts).
    Script,
    /// Both.
    Both,
}

impl ModelArgs {
    fn choice(&self, backend: &str) -> BackendChoice {
        BackendChoice {
            name: backend.to_string(),
            model: self.model.clone(),
            base_url: self.base_url.clone(),
            cassette: self.cassette.clone(),
            record: self.record.clone(),
            threads: self.threads,
        }
    }

    fn plan_options(&self) -> PlanOptions {
        PlanOptions {
            tuple_grammar: matches!(self.grammar, Grammar::Tuples | Grammar::Both),
            script_grammar: matches!(self.grammar, Grammar::Script | Grammar::Both),
            tuple_check: !self.raw_tuples,
            reconcile: !self.raw_tuples,
            ..PlanOptions::default()
        }
    }
}

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
        } => chat(&scene, backend.choice(), prompts(p.as_deref())?),
        Command::Run {
            mission,
            scene,
            trajectory,
            png,
            backend,
            prompts: p,
        } => run(
            &mission,
            scene,
            trajectory,
            png,
            &backend.choice(),
            &prompts(p.as_deref())?,
        ),
        Command::Plan {
            instruction,
            scene,
            json,
            backend,
            prompts: p,
        } => plan(
            &instruction,
            &scene,
            json,
            &backend.choice(),
            &prompts(p.as_deref())?,
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
            eval(
                &suite,
                &choices,
                &p,
                &report,
                baseline,
                &model_args.plan_options(),
            )
        }
        Command::Map { command } => map_cmd(command),
        Command::NoiseStudy(args) => agent::noise_study_cli(&args).map(|()| ExitCode::SUCCESS),
    }
}

fn chat(scene: &Path, choice: BackendChoice, prompts: Prompts) -> Result<ExitCode, CliError> {
    let map = Arc::new(load_map(scene)?);
    let mut chat = Chat::new(map.clone(), choice, prompts);
    let stdout = std::io::stdout();
    if std::io::stdin().is_terminal() {
        println!(
            "ivlmap chat on {:?} ({} instances). :help for commands.",
            map.name,
            map.instances.len()
        );
        let mut editor = rustyline::DefaultEditor::new()
            .map_err(|e| CliError::Failed(format!("cannot start the line editor: {e}")))?;
        let history = history_file();
        if let Some(h) = &history {
            let _ = editor.load_history(h);
        }
        loop {
            match editor.readline("ivlmap> ") {
                Ok(line) => {
                    if !line.trim().is_empty() {
                        let _ = editor.add_history_entry(line.as_str());
                    }
                    if chat.handle(&line, &mut stdout.lock()) == ChatFlow::Quit {
                        break;
                    }
                }
                Err(rustyline::error::ReadlineError::Interrupted) => continue,
                Err(rustyline::error::ReadlineError::Eof) => break,
                Err(e) => return Err(CliError::Failed(format!("reading input: {e}"))),
            }
        }
        if let Some(h) = &history {
            if let Some(dir) = h.parent() {
                let _ = std::fs::create_dir_all(dir);
            }
            let _ = editor.save_history(h);
        }
    } else {
        // Not a terminal: read instructions line by line (pipes, tests), echoing them.
        let stdin = std::io::stdin();
        for line in stdin.lock().lines() {
            let line = line.map_err(|e| CliError::Failed(format!("reading stdin: {e}")))?;
            let mut out = stdout.lock();
            if !line.trim().is_empty() {
                let _ = writeln!(out, "ivlmap> {}", line.trim());
            }
            if chat.handle(&line, &mut out) == ChatFlow::Quit {
                break;
            }
        }
    }
    let _ = CHAT_HELP;
    Ok(ExitCode::SUCCESS)
}

fn history_file() -> Option<PathBuf> {
    std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/ivlmap/chat_history"))
}

fn run(
    mission_path: &Path,
    scene: Option<PathBuf>,
    trajectory: Option<PathBuf>,
    png: Option<PathBuf>,
    choice: &BackendChoice,
    prompts: &Prompts,
) -> Result<ExitCode, CliError> {
    let (mission, header_scene) = load_mission(mission_path)?;
    let scene = scene.or(header_scene).ok_or_else(|| {
        CliError::Input(format!(
            "{}: no scene: give --scene FILE or a `scene: FILE` header comment in the mission",
            mission_path.display()
        ))
    })?;
    let map = Arc::new(load_map(&scene)?);
    let backend = if mission.needs_backend() {
        Some(open_backend(choice)?)
    } else {
        None
    };
    let mut out = std::io::stdout();
    let report = run_mission(
        &mission,
        mission_path,
        &map,
        backend.as_deref().map(|b| b as &dyn LlmBackend),
        prompts,
        &mut out,
    );
    if let Some(t) = &trajectory {
        write_json(t, &report.trajectory)?;
        println!("trajectory written to {}", t.display());
    }
    if let Some(p) = &png {
        render_map(&map, Some(&report.trajectory), p)?;
        println!("map written to {}", p.display());
    }
    match report.error {
        Some(e) => Err(CliError::Failed(e)),
        None => Ok(ExitCode::SUCCESS),
    }
}

fn plan(
    instruction: &str,
    scene: &Path,
    json: bool,
    choice: &BackendChoice,
    prompts: &Prompts,
    options: PlanOptions,
) -> Result<ExitCode, CliError> {
    let map = load_map(scene)?;
    let backend = open_backend(choice)?;
    let robot = map_core::SimRobot::new(Arc::new(map.clone()));
    let mut ctx = PlanContext::new(&map).with_robot(&robot);
    ctx.options = options;
    let outcome = agent::plan_instruction(backend.as_ref(), prompts, instruction, &ctx)?;
    match outcome {
        Outcome::Plan(p) => {
            if json {
                let v = serde_json::json!({"instruction": p.instruction, "tuples": p.tuples, "script": p.script, "source": p.source, "timing": p.timing});
                println!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
            } else {
                println!("tuples: {}", tuples_paper_form(&p.tuples));
                println!("script:\n{}", p.script.trim_end());
            }
            Ok(ExitCode::SUCCESS)
        }
        Outcome::Question(q) => {
            if json {
                println!(
                    "{}",
                    serde_json::json!({"instruction": instruction, "question": q})
                );
            } else {
                println!("? {q}");
            }
            Ok(ExitCode::from(1))
        }
        Outcome::Refusal(r) => {
            if json {
                println!(
                    "{}",
                    serde_json::json!({"instruction": instruction, "refusal": r})
                );
            } else {
                println!("cannot do that: {r}");
            }
            Ok(ExitCode::from(1))
        }
    }
}

fn progress(len: usize, label: &str) -> indicatif::ProgressBar {
    let pb = indicatif::ProgressBar::new(len as u64);
    let style = indicatif::ProgressStyle::with_template(
        "{prefix} [{bar:30}] {pos}/{len} {msg} ({elapsed}, eta {eta})",
    )
    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
    .progress_chars("=> ");
    pb.set_style(style);
    pb.set_prefix(label.to_string());
    pb
}

fn eval(
    suite: &Path,
    choices: &[BackendChoice],
    prompt_dirs: &[PathBuf],
    report_path: &Path,
    baseline: Option<Baseline>,
    plan_options: &PlanOptions,
) -> Result<ExitCode, CliError> {
    let kind = SuiteKind::from_path(suite).map_err(CliError::input)?;
    let variants: Vec<(String, Prompts)> = if prompt_dirs.is_empty() {
        vec![("builtin".into(), Prompts::builtin())]
    } else {
        prompt_dirs
            .iter()
            .map(|d| {
                Ok((
                    d.display().to_string(),
                    Prompts::load(d).map_err(CliError::input)?,
                ))
            })
            .collect::<Result<_, CliError>>()?
    };
    let method = match baseline {
        None => Method::Ivlmap,
        Some(Baseline::Vlmap) => Method::Vlmap,
        Some(Baseline::Reference) => Method::Reference,
    };
    if kind == SuiteKind::Extract && baseline.is_some() {
        return Err(CliError::Input(
            "--baseline applies to navigation suites (.nav.jsonl) only".into(),
        ));
    }
    let suite_name = suite.file_name().map_or_else(
        || suite.display().to_string(),
        |n| n.to_string_lossy().to_string(),
    );
    let (extract_cases, nav_tasks) = match kind {
        SuiteKind::Extract => (
            load_extract_suite(suite).map_err(CliError::input)?,
            Vec::new(),
        ),
        SuiteKind::Nav => (Vec::new(), load_nav_suite(suite).map_err(CliError::input)?),
    };
    let n = extract_cases.len() + nav_tasks.len();
    let mut reports = Vec::new();
    // The reference method needs no model: one run, no backend.
    let backend_runs: Vec<Option<&BackendChoice>> = if method == Method::Reference {
        vec![None]
    } else {
        choices.iter().map(Some).collect()
    };
    for choice in backend_runs {
        let backend = match choice {
            Some(c) => Some(open_backend(c)?),
            None => None,
        };
        let (bname, model) = match &backend {
            Some(b) => (b.name().to_string(), b.model().to_string()),
            None => ("none".to_string(), "none".to_string()),
        };
        for (label, prompts) in &variants {
            let pb = progress(n, &format!("{} {bname} {label}", method.name()));
            let mut tick = |c: &agent::CaseResult| {
                pb.set_message(format!("{} {}", c.id, if c.ok { "ok" } else { "miss" }));
                pb.inc(1);
            };
            let cases = match kind {
                SuiteKind::Extract => match &backend {
                    Some(b) => {
                        run_extract(&extract_cases, b.as_ref(), prompts, plan_options, &mut tick)
                    }
                    None => Vec::new(),
                },
                SuiteKind::Nav => run_nav(
                    &nav_tasks,
                    method,
                    backend.as_deref().map(|b| b as &dyn LlmBackend),
                    prompts,
                    plan_options,
                    &mut tick,
                ),
            };
            pb.finish_and_clear();
            let m = (kind == SuiteKind::Nav).then(|| method.name().to_string());
            reports.push(Report::new(
                suite_name.clone(),
                bname.clone(),
                model.clone(),
                label.clone(),
                m,
                cases,
            ));
        }
    }
    let paths = report_paths(report_path, &reports);
    for (r, p) in reports.iter().zip(&paths) {
        r.write(p).map_err(|e| CliError::output(p, e))?;
    }
    print!("{}", summary_table(&reports));
    for p in &paths {
        println!("report: {}", p.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// One run: the path as given; several: `<stem>.<n>-<label>.json` beside it.
fn report_paths(path: &Path, reports: &[Report]) -> Vec<PathBuf> {
    if reports.len() <= 1 {
        return vec![path.to_path_buf()];
    }
    let stem = path
        .file_stem()
        .map_or_else(|| "report".to_string(), |s| s.to_string_lossy().to_string());
    let dir = path.parent().unwrap_or_else(|| Path::new(""));
    reports
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let tail = Path::new(&r.prompts)
                .file_name()
                .map_or_else(|| r.prompts.clone(), |f| f.to_string_lossy().to_string());
            let label: String = format!("{}-{}", r.backend, tail)
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
            dir.join(format!("{stem}.{}-{label}.json", i + 1))
        })
        .collect()
}

fn map_cmd(cmd: MapCommand) -> Result<ExitCode, CliError> {
    match cmd {
        MapCommand::Inspect { map } => {
            let m = load_map(&map)?;
            print!("{}", inspect_table(&m));
        }
        MapCommand::Render {
            map,
            out,
            trajectory,
        } => {
            let m = load_map(&map)?;
            let t: Option<map_core::Trajectory> = match &trajectory {
                Some(p) => {
                    let text = std::fs::read_to_string(p).map_err(|e| {
                        CliError::Input(format!("{}: cannot read trajectory: {e}", p.display()))
                    })?;
                    Some(serde_json::from_str(&text).map_err(|e| {
                        CliError::Input(format!(
                            "{}:{}: not a trajectory file: {e}",
                            p.display(),
                            e.line()
                        ))
                    })?)
                }
                None => None,
            };
            render_map(&m, t.as_ref(), &out)?;
            println!("wrote {}", out.display());
        }
        MapCommand::Build(args) => agent::map_build(&args)?,
        MapCommand::Save { scene, out } => {
            let m = load_map(&scene)?;
            m.save(&out).map_err(|e| CliError::output(&out, e))?;
            println!(
                "saved map {:?} ({} instances) to {}",
                m.name,
                m.instances.len(),
                out.display()
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}
