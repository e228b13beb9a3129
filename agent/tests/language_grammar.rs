//! Grammar-constrained decoding with the real llama.cpp and a real GGUF (SmolLM2-135M, the
//! weakest model we ship): under the tuple grammar every step-1 answer parses, and under
//! the script grammar (generated from planner_dsl's registry) a step-2 answer calls
//! nothing outside the function library, even when the model would ramble.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use agent::pipeline::extract_tuples_with;
use agent::script::extract_code;
use agent::{PlanOptions, Prompts, Tuple};
use llm::{CompletionRequest, LlamaCppBackend, LlamaCppConfig, LlmBackend};
use planner_dsl::{Plan, PlanError, ViolationKind};

fn smol() -> LlamaCppBackend {
    let p = ivlmap_tests::models_dir().join(ivlmap_tests::SMOL);
    assert!(
        p.is_file(),
        "{} is absent: run scripts/setup.sh (it fetches the models)",
        p.display()
    );
    let mut cfg = LlamaCppConfig::new(p);
    cfg.n_ctx = 4096;
    LlamaCppBackend::new(cfg).unwrap()
}

#[test]
fn tuple_grammar_makes_every_answer_readable() {
    let backend = smol();
    let prompts = Prompts::builtin();
    let options = PlanOptions::default();
    assert!(options.tuple_grammar, "on by default");
    for instruction in [
        "go to the second yellow table from the west",
        "stop on the west side of the black table, then face the tv",
        "walk to the easternmost plant and then the kitchen",
        "turn around",
    ] {
        let (tuples, _) = extract_tuples_with(&backend, &prompts, instruction, None, &options)
            .unwrap_or_else(|e| panic!("{instruction}: {e}"));
        for t in &tuples {
            if let Some(c) = &t.colour {
                assert!(
                    map_core::matcher::is_colour_word(c),
                    "{instruction}: colour {c:?}"
                );
            }
            assert!(
                t.ordinal.is_none_or(|k| k >= 1 || k == -1),
                "{instruction}: {t:?}"
            );
            let _ = Tuple::object_order(t);
        }
    }
}

#[test]
fn script_grammar_admits_only_library_calls() {
    let backend = smol();
    let prompts = Prompts::builtin();
    let tuples = vec![Tuple::new("chair", Some(2), Some("black"))];
    let messages = prompts
        .plan_messages(
            "go to the second black chair and then face the tv",
            &tuples,
            None,
            None,
        )
        .unwrap();
    let mut req = CompletionRequest::new(messages, 120);
    req.grammar = Some(planner_dsl::script_grammar());
    let c = backend.complete(&req).unwrap();
    assert!(c.text.starts_with("```rhai\n"), "{:?}", c.text);
    let code = extract_code(&c.text);
    match Plan::compile(&code) {
        Ok(_) => {}
        // Arity or argument mistakes are the validator's to catch; calls outside the
        // library cannot be written at all.
        Err(PlanError::Rejected { violations }) => {
            for v in violations {
                assert!(
                    !matches!(
                        v.kind,
                        ViolationKind::UnknownFunction { .. } | ViolationKind::Forbidden { .. }
                    ),
                    "{v}\n{code}"
                );
            }
        }
        // A script cut off by the token budget may end mid-statement.
        Err(PlanError::Syntax { .. }) => assert_eq!(c.completion_tokens, 120, "{code}"),
        Err(e) => panic!("{e}\n{code}"),
    }
}
