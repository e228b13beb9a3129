//! The pipeline end to end: a real model (SmolLM2-135M GGUF) and a cassette recorded from it.
//!
//! Re-record the cassette after changing prompts:
//! `IVLMAP_RECORD=1 cargo test -p ivlmap-tests --release --test e2e language -- --nocapture`

use std::path::PathBuf;
use std::sync::Arc;

use agent::checks::check_script;
use agent::{plan_instruction, LanguageError, Outcome, PlanContext, PlanSource, Prompts};
use llm::replay::CassetteRecord;
use llm::{LlamaCppBackend, LlamaCppConfig, LlmBackend, Recording, ReplayBackend, Role};
use map_core::{IvlMap, Robot, Scene, SimRobot};
use planner_dsl::{Limits, Plan};

const INSTRUCTION: &str = "go to the second black chair and then face the tv";

fn flat_a() -> Arc<IvlMap> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/scenes/flat-a.scene.json"
    );
    Arc::new(IvlMap::from_scene(&Scene::from_path(path).unwrap()))
}

fn cassette() -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/e2e/cassettes/smollm2_plan.jsonl"
    ))
}

fn smol_path() -> Option<PathBuf> {
    ivlmap_tests::model(ivlmap_tests::SMOL)
}

/// The LLM path is forced (no template) so that step 2 and the repair loop run.
fn ctx<'a>(map: &'a IvlMap, robot: &'a SimRobot) -> PlanContext<'a> {
    let mut c = PlanContext::new(map).with_robot(robot);
    c.options.deterministic = false;
    c.options.plan_max_tokens = 160;
    c
}

/// Whatever the model did, the result is either a plan that validates, agrees with the
/// tuples and the map, and runs; or a clear error/question. Returns a short label.
fn judge(res: &Result<Outcome, LanguageError>, map: &Arc<IvlMap>) -> String {
    match res {
        Ok(Outcome::Plan(p)) => {
            let plan = Plan::compile(&p.script).expect("a returned plan validates");
            assert!(check_script(&p.script, &p.tuples, Some(map))
                .unwrap()
                .is_empty());
            let mut robot = SimRobot::new(map.clone());
            let out = planner_dsl::run(&plan, map, &mut robot, &Limits::default());
            assert!(out.error.is_none(), "{:?}", out.error);
            assert!(matches!(p.source, PlanSource::Llm { .. }));
            // One call for the tuples (two with the evidence re-ask), one per script.
            let step1 = p
                .timing
                .llm_calls
                .checked_sub(1 + p.attempts.len() as u32)
                .expect("every script came from a call");
            assert!((1..=2).contains(&step1), "{step1} tuple call(s)");
            format!("plan after {} attempt(s): {}", p.attempts.len(), p.script)
        }
        Ok(Outcome::Question(q)) => {
            assert!(q.ends_with('?'), "{q}");
            format!("question: {q}")
        }
        Ok(Outcome::Refusal(r)) => {
            assert!(r.contains("map has no"), "{r}");
            format!("refusal: {r}")
        }
        Err(LanguageError::InvalidPlan {
            attempts, errors, ..
        }) => {
            assert_eq!(*attempts, 3, "1 try + 2 repairs");
            assert!(!errors.is_empty());
            format!("invalid after {attempts}: {errors:?}")
        }
        Err(LanguageError::Tuples { answer, .. }) => format!("unreadable tuples: {answer:?}"),
        Err(e) => panic!("unexpected error: {e}"),
    }
}

#[test]
fn smollm2_instruction_in_checked_plan_or_clear_error_out() {
    let Some(model) = smol_path() else { return };
    let map = flat_a();
    let robot = SimRobot::new(map.clone());
    let mut cfg = LlamaCppConfig::new(model);
    cfg.n_ctx = 4096;
    let llama = LlamaCppBackend::new(cfg).unwrap();
    let backend: Box<dyn LlmBackend> = if std::env::var_os("IVLMAP_RECORD").is_some() {
        let _ = std::fs::remove_file(cassette());
        Box::new(Recording::new(llama, cassette()).unwrap())
    } else {
        Box::new(llama)
    };
    let res = plan_instruction(
        backend.as_ref(),
        &Prompts::builtin(),
        INSTRUCTION,
        &ctx(&map, &robot),
    );
    println!("{}", judge(&res, &map));
    assert_eq!(
        robot.trajectory().stops.len(),
        0,
        "planning never moves the robot"
    );
}

#[test]
fn repair_loop_replays_from_a_recorded_cassette() {
    let map = flat_a();
    let robot = SimRobot::new(map.clone());
    let replay = ReplayBackend::open(cassette()).unwrap();
    let records: Vec<CassetteRecord> = std::fs::read_to_string(cassette())
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let res = plan_instruction(
        &replay,
        &Prompts::builtin(),
        INSTRUCTION,
        &ctx(&map, &robot),
    );
    let label = judge(&res, &map);
    println!("{label}");
    // Step 1 is the tuple request and at most one evidence re-ask; step 2 starts with
    // the map summary.
    let is_plan = |r: &CassetteRecord| {
        r.request
            .messages
            .iter()
            .any(|m| m.role == Role::User && m.content.starts_with("Map: "))
    };
    let (plans, tuples): (Vec<&CassetteRecord>, Vec<&CassetteRecord>) =
        records.iter().partition(|r| is_plan(r));
    assert!(!tuples.is_empty() && tuples.len() <= 2, "{}", tuples.len());
    for r in tuples.iter().skip(1) {
        let last = r.request.messages.last().unwrap();
        assert!(
            last.content
                .starts_with("Check that list against the instruction"),
            "{}",
            last.content
        );
    }
    // Every plan request after the first is a repair: it replays the model's answer
    // and quotes positioned problems.
    for r in plans.iter().skip(1) {
        let msgs = &r.request.messages;
        let last = msgs.last().unwrap();
        assert_eq!(last.role, Role::User);
        assert!(
            last.content.starts_with("That script cannot be used:"),
            "{}",
            last.content
        );
        assert!(
            last.content.contains("line ")
                || last.content.contains("never uses")
                || last.content.contains("no script"),
            "{}",
            last.content
        );
        assert_eq!(msgs[msgs.len() - 2].role, Role::Assistant);
    }
    // The outcome matches how many plan exchanges were recorded.
    match &res {
        Ok(Outcome::Plan(p)) => assert_eq!(plans.len(), 1 + p.attempts.len()),
        Err(LanguageError::InvalidPlan { attempts, .. }) => {
            assert_eq!(plans.len() as u32, *attempts)
        }
        _ => assert!(plans.is_empty()),
    }
}
