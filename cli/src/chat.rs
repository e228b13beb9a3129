//! The chat loop of `ivlmap chat`: each instruction is planned (tuples and script shown),
//! executed on the robot (the simulator, or a real one with `--robot nav2`; trace and
//! path length shown), and remembered for follow-ups. Lines starting with `:` are
//! commands. The loop is driven line by line ([`Chat::handle`]), so the binary can feed
//! it from a terminal editor or a pipe.
//!
//! Plans are always made and previewed on the simulator: with a real robot, on a
//! simulator put at the robot's pose just read. Undo on a real robot cannot drive it
//! back: it forgets the last instruction from the conversation, and the robot stays
//! where it is (its trajectory keeps what it really drove).

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
  :undo                    undo the last instruction (simulator: robot and history;
                           a real robot stays where it is, only the history forgets)
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

/// The robot a chat drives.
enum ChatRobot {
    /// The simulator: undo puts it back.
    Sim(SimRobot),
    /// A real robot; `sim` plans and previews from its pose.
    Real {
        robot: Box<dyn Robot>,
        sim: SimRobot,
    },
}

impl ChatRobot {
    fn robot(&self) -> &dyn Robot {
        match self {
            ChatRobot::Sim(s) => s,
            ChatRobot::Real { robot, .. } => robot.as_ref(),
        }
    }

    fn robot_mut(&mut self) -> &mut dyn Robot {
        match self {
            ChatRobot::Sim(s) => s,
            ChatRobot::Real { robot, .. } => robot.as_mut(),
        }
    }

    /// The simulator to plan and preview on: the chat's own, or one at the real
    /// robot's pose read now.
    fn planning_sim(&mut self) -> SimRobot {
        match self {
            ChatRobot::Sim(s) => s.clone(),
            ChatRobot::Real { robot, sim } => {
                sim.reset_to(robot.current_pose());
                // the stops it made, for what "the chair you visited first" counts over
                sim.trajectory_mut()
                    .stops
                    .clone_from(&robot.trajectory().stops);
                sim.clone()
            }
        }
    }
}

/// A chat session on one map.
pub struct Chat {
    map: Arc<IvlMap>,
    robot: ChatRobot,
    session: Session,
    /// Earlier conversations, with the simulator as it was (none for a real robot).
    undo: Vec<(Option<SimRobot>, Session)>,
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
        Self::on(map, ChatRobot::Sim(robot), choice, prompts)
    }

    /// A chat driving a real robot (connected); plans and previews stay on the
    /// simulator, put at the robot's pose.
    #[must_use]
    pub fn with_real_robot(
        map: Arc<IvlMap>,
        mut real: Box<dyn Robot>,
        choice: BackendChoice,
        prompts: Prompts,
    ) -> Chat {
        let sim = SimRobot::with_pose(map.clone(), real.current_pose());
        Self::on(map, ChatRobot::Real { robot: real, sim }, choice, prompts)
    }

    fn on(map: Arc<IvlMap>, robot: ChatRobot, choice: BackendChoice, prompts: Prompts) -> Chat {
        let session = Session::new(robot.robot().pose());
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
                    let p = self.robot.robot_mut().current_pose();
                    let robot = self.robot.robot();
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
                        robot.trajectory().stops.len(),
                        robot.trajectory().length_m
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
            Some((sim, session)) => {
                self.session = session;
                if let (Some(sim), ChatRobot::Sim(robot)) = (sim, &mut self.robot) {
                    *robot = sim;
                    let p = robot.pose();
                    let _ = writeln!(
                        out,
                        "undone; back at ({:.2}, {:.2})",
                        p.position.x, p.position.y
                    );
                } else {
                    let p = self.robot.robot_mut().current_pose();
                    let _ = writeln!(
                        out,
                        "undone: the last instruction is forgotten; the real robot is not \
                         driven back and stays at ({:.2}, {:.2})",
                        p.position.x, p.position.y
                    );
                }
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
        render_map(&self.map, Some(self.robot.robot().trajectory()), &path)?;
        let _ = writeln!(out, "wrote {}", path.display());
        Ok(())
    }

    fn save(&mut self, arg: &str, out: &mut dyn Write) -> Result<(), CliError> {
        if arg.is_empty() {
            return Err(CliError::Input(
                ":save needs a file name, e.g. :save trajectory.json".into(),
            ));
        }
        crate::error::write_json(Path::new(arg), self.robot.robot().trajectory())?;
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
        let robot = self.robot.planning_sim();
        let prompts = self.prompts.clone();
        let session = self.session.clone();
        let backend = self.backend()?;
        let ctx = PlanContext::new(&map).with_robot(&robot);
        let outcome = session.plan(backend, &prompts, instr, &ctx)?;
        let planned: Box<PlannedInstruction> = match outcome {
            Outcome::Plan(p) => p,
            Outcome::Question(q) => {
                let _ = writeln!(out, "? {q}");
                // The next line may answer it.
                self.session.not_done(instr, &q);
                return Ok(());
            }
            Outcome::Refusal(r) => {
                let _ = writeln!(out, "cannot do that: {r}");
                self.session.not_done(instr, &r);
                return Ok(());
            }
        };
        let _ = writeln!(out, "tuples: {}", tuples_paper_form(&planned.tuples));
        let _ = writeln!(out, "script:");
        for l in planned.script.lines() {
            let _ = writeln!(out, "  {l}");
        }
        if preview {
            let dry = dry_run(&planned.plan, &map, &robot, &self.limits);
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
        let kept = match &self.robot {
            ChatRobot::Sim(s) => Some(s.clone()),
            ChatRobot::Real { .. } => None,
        };
        let real = kept.is_none();
        self.undo.push((kept, self.session.clone()));
        let robot = self.robot.robot_mut();
        let before = robot.trajectory().length_m;
        let run = self.session.execute(&planned, &map, robot, &self.limits);
        let _ = writeln!(out, "trace:");
        print_trace(out, &run);
        let p = robot.pose();
        let _ = writeln!(
            out,
            "path {:.2} m (total {:.2} m); now at ({:.2}, {:.2}) heading {:.0}°",
            robot.trajectory().length_m - before,
            robot.trajectory().length_m,
            p.position.x,
            p.position.y,
            p.heading
        );
        if let Some(e) = run.error {
            if real {
                let _ = writeln!(out, "error: {e} (the robot stopped there)");
            } else {
                let _ = writeln!(out, "error: {e} (stopped there; :undo to go back)");
            }
        }
        Ok(())
    }
}
