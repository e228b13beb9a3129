//! Time-to-plan: wall time from an instruction to a checked plan (or a question or
//! refusal), through [`plan_instruction`] with a local GGUF, with and without the prefix
//! cache, measured side by side in one run.
//!
//! ```text
//! cargo run --release -p eval --example time_to_plan -- \
//!     --model ~/.cache/ivlmap/models/qwen2.5-coder-1.5b-instruct-q4_k_m.gguf \
//!     [--threads 2] [--limit 24] [--uncached-limit 6] \
//!     [--suite examples/suites/flat-a.nav.jsonl]... [--fast-forward-side]
//! ```
//!
//! Instructions: every clause of the navigation suites' tasks ("go to the second white
//! desk from the west", one subgoal each, as a person chatting would say them), planned
//! on the task's scene from the task's start pose, then every whole four-subgoal task.
//! Each instruction is planned by two backends holding the same GGUF: prefix cache on
//! (4 slots; warmed with one instruction first, as in a chat session) and off (every
//! request evaluates its whole prompt). The uncached side takes the first
//! `--uncached-limit` instructions of each kind only (it costs the whole prompt each
//! time); the two sides alternate which goes first.
//!
//! With `--fast-forward-side` the second backend keeps the prefix cache and fast-forwards
//! the grammar's forced tokens instead (`LlamaCppConfig::fast_forward`), every instruction
//! on both sides.
//!
//! Output: one JSON line per plan on stdout, then a Markdown table of p50/p95 per kind
//! and cache mode, with mean prompt tokens, cached prompt tokens, LLM calls and how many
//! plans needed the re-ask.

use std::path::PathBuf;
use std::time::Instant;

use agent::{plan_instruction, Outcome, PlanContext, PlanSource, Prompts};
use eval::report::percentile;
use eval::suite::load_nav_suite;
use llm::{LlamaCppBackend, LlamaCppConfig, LlmBackend};
use map_core::SimRobot;
use serde_json::json;

type BoxError = Box<dyn std::error::Error>;

/// One task's clauses: "go to A, then the B, then C" -> ["go to A", "go to the B", ...].
fn clauses(instruction: &str) -> Vec<String> {
    let mut out = Vec::new();
    for part in instruction.split(", ") {
        let p = part.trim();
        let p = p.strip_prefix("then ").unwrap_or(p);
        let p = p.strip_prefix("and ").unwrap_or(p);
        if p.is_empty() {
            continue;
        }
        let starts_with_verb = p.split_whitespace().next().is_some_and(|w| {
            matches!(
                w,
                "go" | "stop" | "walk" | "head" | "move" | "drive" | "navigate" | "face" | "turn"
            )
        });
        out.push(if starts_with_verb {
            p.to_string()
        } else if p.starts_with("to ") {
            format!("go {p}")
        } else {
            format!("go to {p}")
        });
    }
    out
}

#[derive(Default)]
struct Side {
    ms: Vec<u64>,
    prompt_tokens: u64,
    cached_tokens: u64,
    llm_calls: u64,
    reasked: u64,
    plans: u64,
}

impl Side {
    fn row(&self, label: &str) -> String {
        let n = self.ms.len().max(1) as f64;
        format!(
            "| {label} | {} | {:.2} | {:.2} | {:.0} | {:.0} | {:.2} | {}/{} |",
            self.ms.len(),
            percentile(&self.ms, 50.0) as f64 / 1000.0,
            percentile(&self.ms, 95.0) as f64 / 1000.0,
            self.prompt_tokens as f64 / n,
            self.cached_tokens as f64 / n,
            self.llm_calls as f64 / n,
            self.reasked,
            self.plans,
        )
    }
}

fn plan_once(
    backend: &dyn LlmBackend,
    prompts: &Prompts,
    instruction: &str,
    map: &map_core::IvlMap,
    robot: &SimRobot,
) -> Result<(f64, serde_json::Value, Option<agent::Timing>, bool), BoxError> {
    let ctx = PlanContext::new(map).with_robot(robot);
    let t0 = Instant::now();
    let out = plan_instruction(backend, prompts, instruction, &ctx);
    let ms = t0.elapsed().as_secs_f64() * 1000.0;
    let (kind, timing, reasked, script) = match &out {
        Ok(Outcome::Plan(p)) => (
            "plan",
            Some(p.timing),
            matches!(p.source, PlanSource::Llm { repairs } if repairs > 0),
            Some(p.script.clone()),
        ),
        Ok(Outcome::Question(_)) => ("question", None, false, None),
        Ok(Outcome::Refusal(_)) => ("refusal", None, false, None),
        Err(_) => ("error", None, false, None),
    };
    let v = json!({"instruction": instruction, "ms": ms, "outcome": kind, "reasked": reasked, "script": script,
        "llm_calls": timing.map(|t| t.llm_calls), "prompt_tokens": timing.map(|t| t.prompt_tokens),
        "cached_prompt_tokens": timing.map(|t| t.cached_prompt_tokens),
        "completion_tokens": timing.map(|t| t.completion_tokens),
        "prompt_ms": timing.map(|t| t.prompt_ms), "generate_ms": timing.map(|t| t.generate_ms)});
    Ok((ms, v, timing, reasked))
}

fn record(side: &mut Side, ms: f64, timing: Option<agent::Timing>, reasked: bool) {
    side.ms.push(ms.round() as u64);
    if let Some(t) = timing {
        side.plans += 1;
        side.prompt_tokens += t.prompt_tokens;
        side.cached_tokens += t.cached_prompt_tokens;
        side.llm_calls += u64::from(t.llm_calls);
        side.reasked += u64::from(reasked);
    }
}

/// Time to plan, prefix cache on and off side by side.
#[derive(Debug, clap::Parser)]
struct Args {
    /// The GGUF file.
    #[arg(long)]
    model: PathBuf,
    /// CPU threads.
    #[arg(long, default_value_t = 2)]
    threads: u32,
    /// At most this many instructions of each kind (clauses, whole tasks).
    #[arg(long, default_value_t = usize::MAX)]
    limit: usize,
    /// At most this many of each kind uncached (each costs the whole prompt).
    #[arg(long, default_value_t = 6)]
    uncached_limit: usize,
    /// Navigation suites (default: the three public ones).
    #[arg(long = "suite")]
    suites: Vec<PathBuf>,
    /// Compare fast-forward instead of the prefix cache: the second side keeps the
    /// prefix cache and decodes the grammar's forced tokens in one batch.
    #[arg(long)]
    fast_forward_side: bool,
}

fn main() -> Result<(), BoxError> {
    let Args {
        model,
        threads,
        limit,
        uncached_limit,
        mut suites,
        fast_forward_side,
    } = clap::Parser::parse();
    if suites.is_empty() {
        for s in ["flat-a", "office-b", "house-c"] {
            suites.push(PathBuf::from(format!("examples/suites/{s}.nav.jsonl")));
        }
    }
    let mut tasks = Vec::new();
    for s in &suites {
        tasks.extend(load_nav_suite(s)?);
    }
    // Clauses first (interleaved across scenes so a --limit sees all three), then tasks.
    let mut single: Vec<(usize, String)> = Vec::new();
    let per_task: Vec<Vec<String>> = tasks.iter().map(|t| clauses(&t.instruction)).collect();
    let most = per_task.iter().map(Vec::len).max().unwrap_or(0);
    for j in 0..most {
        for (i, cs) in per_task.iter().enumerate() {
            if let Some(c) = cs.get(j) {
                single.push((i, c.clone()));
            }
        }
    }
    single.truncate(limit);
    let whole: Vec<(usize, String)> = tasks
        .iter()
        .enumerate()
        .map(|(i, t)| (i, t.instruction.clone()))
        .take(limit)
        .collect();

    let mut cfg = LlamaCppConfig::new(&model);
    cfg.threads = threads;
    let cached = LlamaCppBackend::new(cfg.clone())?;
    if fast_forward_side {
        cfg.fast_forward = true;
    } else {
        cfg.prefix_cache = false;
        cfg.n_slots = 1;
    }
    let uncached = LlamaCppBackend::new(cfg)?;
    let other = if fast_forward_side {
        "fast-forward"
    } else {
        "prefix cache off"
    };
    let prompts = Prompts::builtin();

    // Warm-up: the first instruction of a chat session fills the cache with the shared
    // prefixes (steps 1 and 2); both sides pay their model load here.
    {
        let t = &tasks[0];
        let robot = SimRobot::with_pose(t.map.clone(), t.start);
        for b in [&cached, &uncached] {
            plan_once(b, &prompts, "go to the tv", &t.map, &robot)?;
            plan_once(
                b,
                &prompts,
                "stop between the sofa and the tv",
                &t.map,
                &robot,
            )?;
        }
    }

    let mut rows = Vec::new();
    for (kind, list) in [("one subgoal", &single), ("four subgoals", &whole)] {
        let (mut on, mut off) = (Side::default(), Side::default());
        for (n, (i, instruction)) in list.iter().enumerate() {
            let t = &tasks[*i];
            let robot = SimRobot::with_pose(t.map.clone(), t.start);
            let with_off = fast_forward_side || n < uncached_limit;
            let order: &[bool] = if n % 2 == 0 {
                &[true, false]
            } else {
                &[false, true]
            };
            for &use_cache in order {
                if !use_cache && !with_off {
                    continue;
                }
                let b = if use_cache { &cached } else { &uncached };
                let (ms, mut v, timing, reasked) =
                    plan_once(b, &prompts, instruction, &t.map, &robot)?;
                v["kind"] = json!(kind);
                v["prefix_cache"] = json!(use_cache);
                println!("{v}");
                record(
                    if use_cache { &mut on } else { &mut off },
                    ms,
                    timing,
                    reasked,
                );
                eprintln!(
                    "{kind} #{n} cache={use_cache}: {:.2} s  {instruction}",
                    ms / 1000.0
                );
            }
        }
        rows.push(on.row(&format!("{kind}, prefix cache on")));
        rows.push(off.row(&format!("{kind}, {other}")));
    }
    println!(
        "\nmodel {}, {threads} threads\n",
        model.file_name().unwrap_or_default().to_string_lossy()
    );
    println!("| instructions | n | p50 s | p95 s | prompt tok | cached tok | LLM calls | re-asked plans |");
    println!("|---|---|---|---|---|---|---|---|");
    for r in rows {
        println!("{r}");
    }
    Ok(())
}
