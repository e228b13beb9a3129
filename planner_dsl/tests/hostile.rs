//! The hostile corpus (tests/hostile/*.rhai, each naming its expected failure in a
//! `// expect: KIND` first line) plus generated cases (deep nesting, too many
//! variables or functions, huge literals). Each must end by itself, quickly, with
//! a clear error, and never move the robot when rejected before running.

mod common;

use common::world;
use map_core::Robot;
use planner_dsl::{run, Limits, Plan, PlanError, RuntimeErrorKind};
use std::time::{Duration, Instant};

/// Budget per hostile script (compile + validate + run), in any build profile.
const BUDGET: Duration = Duration::from_secs(1);

#[derive(Debug)]
struct Ended {
    kind: String,
    message: String,
    elapsed: Duration,
    moved: bool,
}

fn kind_name(k: RuntimeErrorKind) -> String {
    serde_json::to_value(k)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}

fn run_hostile(source: &str, limits: &Limits) -> Ended {
    let (map, mut robot) = world("flat-a");
    let start = Instant::now();
    let compiled = Plan::compile_with(source, limits);
    let (kind, message) = match compiled {
        Err(e @ PlanError::Syntax { .. }) => ("syntax".to_string(), e.to_string()),
        Err(e @ PlanError::TooLong { .. }) => ("too_long".to_string(), e.to_string()),
        Err(e @ PlanError::Rejected { .. }) => ("rejected".to_string(), e.to_string()),
        Ok(plan) => {
            let out = run(&plan, &map, &mut robot, limits);
            match out.error {
                Some(e) => (kind_name(e.kind), e.to_string()),
                None => ("ok".to_string(), String::new()),
            }
        }
    };
    let elapsed = start.elapsed();
    let moved = !robot.trajectory().stops.is_empty() || robot.trajectory().length_m > 0.0;
    Ended {
        kind,
        message,
        elapsed,
        moved,
    }
}

#[test]
fn hostile_corpus_ends_quickly_with_the_expected_error() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/hostile");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rhai"))
        .collect();
    files.sort();
    assert!(files.len() >= 40, "corpus has {} scripts", files.len());
    let mut worst = Duration::ZERO;
    let mut failures = Vec::new();
    for f in &files {
        let source = std::fs::read_to_string(f).unwrap();
        let expect = source
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("// expect: "))
            .unwrap_or_else(|| panic!("{} lacks an expect line", f.display()))
            .trim()
            .to_string();
        let ended = run_hostile(&source, &Limits::default());
        let name = f.file_name().unwrap().to_string_lossy().to_string();
        println!(
            "{name:40} {:>8.1} ms  {:20} {}",
            ended.elapsed.as_secs_f64() * 1e3,
            ended.kind,
            ended.message.lines().next().unwrap_or("")
        );
        worst = worst.max(ended.elapsed);
        if ended.kind != expect {
            failures.push(format!("{name}: expected {expect}, got {ended:?}"));
        }
        if ended.elapsed >= BUDGET {
            failures.push(format!("{name}: took {:?}", ended.elapsed));
        }
        if ended.message.trim().is_empty() {
            failures.push(format!("{name}: empty message"));
        }
        if matches!(expect.as_str(), "syntax" | "rejected") && ended.moved {
            failures.push(format!("{name}: rejected but the robot moved"));
        }
    }
    println!(
        "worst: {:.1} ms over {} scripts",
        worst.as_secs_f64() * 1e3,
        files.len()
    );
    // Bounded memory: the whole corpus runs in a small, fixed peak footprint.
    let peak_kb = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| {
                l.split_whitespace()
                    .nth(1)
                    .and_then(|v| v.parse::<u64>().ok())
            })
        });
    if let Some(peak_kb) = peak_kb {
        println!("peak RSS: {} MiB", peak_kb / 1024);
        assert!(peak_kb < 512 * 1024, "peak RSS {peak_kb} kB");
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn expect_kind(source: &str, limits: &Limits, kind: &str) -> Ended {
    let ended = run_hostile(source, limits);
    assert_eq!(ended.kind, kind, "{ended:?}");
    assert!(ended.elapsed < BUDGET, "{ended:?}");
    ended
}

#[test]
fn deep_nesting_is_refused_at_compile_time() {
    let l = Limits::default();
    let n = 2_000;
    for src in [
        format!("let x = {}1{};", "(".repeat(n), ")".repeat(n)),
        format!("let x = {}1{};", "[".repeat(n), "]".repeat(n)),
        format!("let x = {}1;", "- ".repeat(n)),
        format!("let x = {}true;", "! ".repeat(n)),
        format!("{}{}", "if true { ".repeat(n), "}".repeat(n)),
        format!("let x = {}1{};", "abs(".repeat(n), ")".repeat(n)),
        format!("let x = {}1{};", "#{a: ".repeat(n), "}".repeat(n)),
        format!("let x = 1{};", " + 1".repeat(12_000)),
    ] {
        let e = expect_kind(&src, &l, "syntax");
        assert!(
            e.message.contains("too deep") || e.message.contains("complexity"),
            "{}",
            e.message
        );
    }
}

#[test]
fn too_many_variables_functions_and_huge_literals() {
    let l = Limits::default();
    let vars: String = (0..400).map(|i| format!("let v{i} = {i};\n")).collect();
    expect_kind(&vars, &l, "too_many_variables");
    let fns: String = (0..100).map(|i| format!("fn f{i}() {{ {i} }}\n")).collect();
    let e = expect_kind(&fns, &l, "syntax");
    assert!(e.message.contains("functions"), "{}", e.message);
    let lit = format!("let s = \"{}\";", "x".repeat(20_000));
    let e = expect_kind(&lit, &l, "syntax");
    assert!(e.message.to_lowercase().contains("length"), "{}", e.message);
    let long = "agent.turn(1);\n".repeat(10_000);
    expect_kind(&long, &l, "too_long");
}

#[test]
fn wall_clock_deadline_stops_a_script_within_budget() {
    let limits = Limits {
        max_operations: u64::MAX,
        deadline: Duration::from_millis(50),
        ..Limits::default()
    };
    let e = expect_kind("let x = 0;\nloop { x += 1; }", &limits, "deadline");
    assert!(e.elapsed >= Duration::from_millis(50), "{e:?}");
    assert!(e.elapsed < Duration::from_millis(500), "{e:?}");
}

#[test]
fn library_time_does_not_count_against_the_script_deadline() {
    // A plan whose robot actions take longer than the deadline still completes:
    // the deadline is for the script's own work.
    let limits = Limits {
        deadline: Duration::from_millis(1),
        ..Limits::default()
    };
    let (map, mut robot) = world("flat-a");
    let plan =
        Plan::compile("agent.move_to_object(\"fridge\");\nagent.move_to_object(\"bed\");").unwrap();
    let out = run(&plan, &map, &mut robot, &limits);
    assert!(out.is_ok(), "{:?}", out.error);
    assert_eq!(robot.trajectory().stops.len(), 2);
}
