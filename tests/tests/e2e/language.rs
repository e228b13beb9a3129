//! The language layer end to end: a real model (SmolLM2-135M GGUF) and a cassette
//! recorded from it.
//!
//! Re-record the cassette after changing prompts:
//! `IVLMAP_RECORD=1 cargo test -p ivlmap-tests --release --test e2e language -- --nocapture`

use std::path::PathBuf;
use std::sync::Arc;

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

/// A short answer budget and the three most similar worked examples (a short prompt
/// for the small model).
fn ctx<'a>(map: &'a IvlMap, robot: &'a SimRobot) -> PlanContext<'a> {
    let mut c = PlanContext::new(map).with_robot(robot);
    c.options.plan_max_tokens = 160;
    c.options.examples = Some(3);
    c
}

/// Whatever the model did, the result is either a plan that validates and runs, or a
/// question or refusal. Returns a short label.
fn judge(res: &Result<Outcome, LanguageError>, map: &Arc<IvlMap>) -> String {
    match res {
        Ok(Outcome::Plan(p)) => {
            let plan = Plan::compile(&p.script).expect("a returned plan validates");
            let mut robot = SimRobot::new(map.clone());
            let out = planner_dsl::run(&plan, map, &mut robot, &Limits::default());
            assert!(out.error.is_none(), "{:?}", out.error);
            let PlanSource::Llm { repairs } = p.source;
            // One call per answer: the first and, when the checks found something, the
            // re-ask.
            assert_eq!(p.timing.llm_calls, 1 + repairs);
            assert_eq!(p.attempts.len() as u32, 1 + repairs);
            format!("plan after {} answer(s): {}", p.attempts.len(), p.script)
        }
        Ok(Outcome::Question(q)) => {
            assert!(q.ends_with('?'), "{q}");
            format!("question: {q}")
        }
        Ok(Outcome::Refusal(r)) => {
            assert!(r.starts_with("I can't do that"), "{r}");
            format!("refusal: {r}")
        }
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
fn reask_replays_from_a_recorded_cassette() {
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
    // One request, at most one re-ask (the same request with what the checks found
    // appended to its last message; the first answer is not replayed to the model), the
    // first request with its worked examples reversed (greedy), and at most one redraw
    // (the default): the re-ask's request, sampled with seed 1.
    assert!((1..=4).contains(&records.len()), "{}", records.len());
    let first = &records[0].request.messages;
    assert_eq!(first.last().unwrap().role, Role::User);
    assert!(first.last().unwrap().content.ends_with(INSTRUCTION));
    if let Some(second) = records.get(1) {
        let m = &second.request.messages;
        assert_eq!(m.len(), first.len());
        assert_eq!(m[..m.len() - 1], first[..first.len() - 1]);
        let last = &m.last().unwrap().content;
        assert!(
            last.starts_with(first.last().unwrap().content.as_str())
                && last.contains("Before you answer, note what a first answer got wrong:"),
            "{last}"
        );
    }
    if let Some(third) = records.get(2) {
        let (second, third) = (&records[1].request, &third.request);
        let n = first.len();
        assert_eq!(third.messages.len(), n);
        assert_eq!(third.messages[0], first[0]);
        assert_eq!(third.messages[n - 1], first[n - 1]);
        assert_eq!(third.messages[1], first[n - 3]);
        assert_eq!(third.lark, second.lark);
        assert!(third.temperature == 0.0 && third.seed.is_none());
    }
    if let Some(fourth) = records.get(3) {
        let (second, fourth) = (&records[1].request, &fourth.request);
        assert_eq!(fourth.messages, second.messages);
        assert_eq!(fourth.lark, second.lark);
        assert!(fourth.temperature > 0.0 && second.temperature == 0.0);
        assert_eq!(fourth.seed, Some(1));
    }
    // The outcome matches how many answers were recorded.
    match &res {
        Ok(Outcome::Plan(p)) => assert_eq!(records.len(), p.attempts.len()),
        _ => assert_eq!(
            records.len(),
            4,
            "a question comes after the re-ask, the reversed examples' answer and the redraw"
        ),
    }
}
