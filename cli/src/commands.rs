//! `ivlmap chat`, `run`, `plan` and `map`: each builds its parts and runs them.

use std::io::{BufRead, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;

use agent::tuples::tuples_paper_form;
use agent::{Outcome, PlanContext, PlanOptions, Prompts};
use llm::LlmBackend;

use crate::args::MapCommand;
use crate::backend::{open_backend, BackendChoice};
use crate::chat::{Chat, ChatFlow, CHAT_HELP};
use crate::error::{write_json, CliError};
use crate::mapinfo::{inspect_table, load_map, render_map};
use crate::mission::{load_mission, run_mission};
use crate::robot::{open_real, open_robot, RobotArgs};

pub(crate) fn chat(
    scene: &Path,
    choice: BackendChoice,
    prompts: Prompts,
    robot_args: &RobotArgs,
) -> Result<ExitCode, CliError> {
    let map = Arc::new(load_map(scene)?);
    let mut chat = match open_real(robot_args, &map)? {
        Some(real) => Chat::with_real_robot(map.clone(), real, choice, prompts),
        None => Chat::new(map.clone(), choice, prompts),
    };
    let stdout = std::io::stdout();
    if std::io::stdin().is_terminal() {
        println!(
            "ivlmap chat on {:?} ({} instances), robot {}. :help for commands.",
            map.name,
            map.instances.len(),
            robot_args.robot.name()
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

pub(crate) fn history_file() -> Option<PathBuf> {
    std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/ivlmap/chat_history"))
}

pub(crate) fn run(
    mission_path: &Path,
    scene: Option<PathBuf>,
    trajectory: Option<PathBuf>,
    png: Option<PathBuf>,
    choice: &BackendChoice,
    prompts: &Prompts,
    robot_args: &RobotArgs,
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
    let mut robot = open_robot(robot_args, &map)?;
    let mut out = std::io::stdout();
    let report = run_mission(
        &mission,
        mission_path,
        &map,
        robot.as_mut(),
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

pub(crate) fn plan(
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

pub(crate) fn map_cmd(cmd: MapCommand) -> Result<ExitCode, CliError> {
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
        MapCommand::Build(args) => crate::mapbuild::map_build(&args)?,
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
