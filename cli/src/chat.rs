//! The chat loop of `ivlmap chat`: each instruction is planned (tuples and script shown),
//! executed on the simulated robot (trace and path length shown), and remembered for
//! follow-ups. Lines starting with `:` are commands. The loop is driven line by line
//! ([`Chat::handle`]), so the binary can feed it from a terminal editor or a pipe.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use map_core::{IvlMap, Robot, SimRobot};
use planner_dsl::{dry_run, Limits};

use crate::backend::{open_backend, BackendChoice};
use crate::error::CliError;
use crate::mapinfo::render_map;
use crate::mission::print_trace;
use agent::tuples::tuples_paper_form;
use agent::{Outcome, PlanContext, PlannedInstruction, Prompts, Session};
use llm::LlmBackend;

/// The commands the chat understands.
pub const CHAT_HELP: &str = "\
Type an instruction (\"go to the second red chair, then the kitchen\") or a command:
  :preview <instruction>   plan and dry-run it without moving the robot
  :undo                    undo the last instruction (robot and history)
  :render FILE.png         draw the map with the trajectory so far
  :save FILE.json          write the trajectory so far (formats.md)
  :where                   where the robot is
  :backend NAME            switch backend (llama, openai, replay)
  :model PATH              switch model (a GGUF file for llama, a model id for openai)
  :help                    this text
  :quit                    leave (also Ctrl-D)";

/// Whether to go on reading lines.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChatFlow {
    /// Read the next line.
    Continue,
    /// Leave.
    Quit,
}

/// A chat session on one map.
pub struct Chat {
    map: Arc<IvlMap>,
    robot: SimRobot,
    session: Session,
    undo: Vec<(SimRobot, Session)>,
    choice: BackendChoice,
    backend: Option<Box<dyn LlmBackend>>,
    prompts: Prompts,
    limits: Limits,
}

impl std::fmt::Debug for Chat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Chat")
            .field("map", &self.map.name)
            .field("backend", &self.choice)
            .field("turns", &self.session.turns().len())
            .finish_non_exhaustive()
    }
}

impl Chat {
    /// A chat on `map` with the robot at its start pose. The backend opens lazily, at
    /// the first instruction, so `:help` and friends work without a model.
    #[must_use]
    pub fn new(map: Arc<IvlMap>, choice: BackendChoice, prompts: Prompts) -> Chat {
        let robot = SimRobot::new(map.clone());
        let session = Session::new(robot.pose());
        Chat {
            map,
            robot,
            session,
            undo: Vec::new(),
            choice,
            backend: None,
            prompts,
            limits: Limits::default(),
        }
    }

    fn backend(&mut self) -> Result<&dyn LlmBackend, CliError> {
        if self.backend.is_none() {
            self.backend = Some(open_backend(&self.choice)?);
        }
        match &self.backend {
            Some(b) => Ok(b.as_ref()),
            None => Err(CliError::Failed("no backend".into())),
        }
    }

    /// Handles one line. Errors are reported on `out` and the chat goes on; only
    /// `:quit` ends it.
    pub fn handle(&mut self, line: &str, out: &mut dyn Write) -> ChatFlow {
        let line = line.trim();
        if line.is_empty() {
            return ChatFlow::Continue;
        }
        let result = if let Some(cmd) = line.strip_prefix(':') {
            let (name, arg) = cmd.split_once(char::is_whitespace).unwrap_or((cmd, ""));
            let arg = arg.trim();
            match name {
                "q" | "quit" | "exit" => return ChatFlow::Quit,
                "h" | "help" | "?" => {
                    let _ = writeln!(out, "{CHAT_HELP}");
                    Ok(())
                }
                "preview" => self.instruction(arg, true, out),
                "undo" => self.undo(out),
                "render" => self.render(arg, out),
                "save" => self.save(arg, out),
                "where" => {
                    let p = self.robot.pose();
                    let region = self
                        .map
                        .region_at(p.position)
                        .map_or("no region", |r| r.name.as_str());
                    let _ = writeln!(
                        out,
                        "at ({:.2}, {:.2}) heading {:.0}° in {region}; {} stop(s), path {:.2} m",
                        p.position.x,
                        p.position.y,
                        p.heading,
                        self.robot.trajectory().stops.len(),
                        self.robot.trajectory().length_m
                    );
                    Ok(())
                }
                "backend" => self.switch(Some(arg), None, out),
                "model" => self.switch(None, Some(arg), out),
                other => Err(CliError::Input(format!(
                    "unknown command :{other} (type :help)"
                ))),
            }
        } else {
            self.instruction(line, false, out)
        };
        if let Err(e) = result {
            let _ = writeln!(out, "error: {e}");
        }
        ChatFlow::Continue
    }

    fn switch(
        &mut self,
        name: Option<&str>,
        model: Option<&str>,
        out: &mut dyn Write,
    ) -> Result<(), CliError> {
        let mut choice = self.choice.clone();
        if let Some(n) = name {
            if n.is_empty() {
                return Err(CliError::Input(
                    ":backend needs a name: llama, openai or replay".into(),
                ));
            }
            choice.name = n.to_string();
        }
        if let Some(m) = model {
            if m.is_empty() {
                return Err(CliError::Input(":model needs a path or model id".into()));
            }
            choice.model = Some(m.to_string());
        }
        let backend = open_backend(&choice)?;
        let _ = writeln!(out, "now using {} ({})", backend.name(), backend.model());
        self.backend = Some(backend);
        self.choice = choice;
        Ok(())
    }

    fn undo(&mut self, out: &mut dyn Write) -> Result<(), CliError> {
        match self.undo.pop() {
            Some((robot, session)) => {
                self.robot = robot;
                self.session = session;
                let p = self.robot.pose();
                let _ = writeln!(
                    out,
                    "undone; back at ({:.2}, {:.2})",
                    p.position.x, p.position.y
                );
                Ok(())
            }
            None => Err(CliError::Input("nothing to undo".into())),
        }
    }

    fn render(&mut self, arg: &str, out: &mut dyn Write) -> Result<(), CliError> {
        if arg.is_empty() {
            return Err(CliError::Input(
                ":render needs a file name, e.g. :render map.png".into(),
            ));
        }
        let path = PathBuf::from(arg);
        render_map(&self.map, Some(self.robot.trajectory()), &path)?;
        let _ = writeln!(out, "wrote {}", path.display());
        Ok(())
    }

    fn save(&mut self, arg: &str, out: &mut dyn Write) -> Result<(), CliError> {
        if arg.is_empty() {
            return Err(CliError::Input(
                ":save needs a file name, e.g. :save trajectory.json".into(),
            ));
        }
        crate::error::write_json(Path::new(arg), self.robot.trajectory())?;
        let _ = writeln!(out, "wrote {arg}");
        Ok(())
    }

    fn instruction(
        &mut self,
        instr: &str,
        preview: bool,
        out: &mut dyn Write,
    ) -> Result<(), CliError> {
        if instr.is_empty() {
            return Err(CliError::Input(":preview needs an instruction".into()));
        }
        let map = self.map.clone();
        let robot = self.robot.clone();
        let prompts = self.prompts.clone();
        let session = self.session.clone();
        let backend = self.backend()?;
        let ctx = PlanContext::new(&map).with_robot(&robot);
        let outcome = session.plan(backend, &prompts, instr, &ctx)?;
        let planned: Box<PlannedInstruction> = match outcome {
            Outcome::Plan(p) => p,
            Outcome::Question(q) => {
                let _ = writeln!(out, "? {q}");
                return Ok(());
            }
            Outcome::Refusal(r) => {
                let _ = writeln!(out, "cannot do that: {r}");
                return Ok(());
            }
        };
        let _ = writeln!(out, "tuples: {}", tuples_paper_form(&planned.tuples));
        let _ = writeln!(out, "script:");
        for l in planned.script.lines() {
            let _ = writeln!(out, "  {l}");
        }
        if preview {
            let dry = dry_run(&planned.plan, &map, &self.robot, &self.limits);
            let _ = writeln!(out, "preview (the robot does not move):");
            print_trace(out, &dry.outcome);
            let _ = writeln!(
                out,
                "path {:.2} m, {} stop(s)",
                dry.trajectory.length_m,
                dry.trajectory.stops.len()
            );
            if let Some(e) = dry.outcome.error {
                let _ = writeln!(out, "error: {e}");
            }
            return Ok(());
        }
        self.undo.push((self.robot.clone(), self.session.clone()));
        let before = self.robot.trajectory().length_m;
        let run = self
            .session
            .execute(&planned, &map, &mut self.robot, &self.limits);
        let _ = writeln!(out, "trace:");
        print_trace(out, &run);
        let p = self.robot.pose();
        let _ = writeln!(
            out,
            "path {:.2} m (total {:.2} m); now at ({:.2}, {:.2}) heading {:.0}°",
            self.robot.trajectory().length_m - before,
            self.robot.trajectory().length_m,
            p.position.x,
            p.position.y,
            p.heading
        );
        if let Some(e) = run.error {
            let _ = writeln!(out, "error: {e} (stopped there; :undo to go back)");
        }
        Ok(())
    }
}
