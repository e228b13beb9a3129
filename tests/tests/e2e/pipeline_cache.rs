//! The prefix cache across the language pipeline's alternating prompts.

use std::sync::{Arc, Mutex};
use std::time::Instant;

use agent::{plan_instruction, PlanContext, Prompts};
use ivlmap_tests::model;
use llm::{Completion, CompletionRequest, LlamaCppBackend, LlamaCppConfig, LlmBackend, LlmError};

/// Passes requests to the real backend and adds up what it reports.
struct Tally<B> {
    inner: B,
    /// (requests, prompt tokens, cached prompt tokens, prompt ms)
    sums: Mutex<(u32, u64, u64, f64)>,
}

impl<B: LlmBackend> LlmBackend for Tally<B> {
    fn name(&self) -> &str {
        self.inner.name()
    }
    fn model(&self) -> &str {
        self.inner.model()
    }
    fn complete(&self, req: &CompletionRequest) -> Result<Completion, LlmError> {
        let c = self.inner.complete(req)?;
        let mut s = self.sums.lock().unwrap();
        s.0 += 1;
        s.1 += u64::from(c.prompt_tokens);
        s.2 += u64::from(c.cached_prompt_tokens);
        s.3 += c.prompt_ms;
        Ok(c)
    }
}

/// The language pipeline alternates tuple extraction and plan generation, two different
/// long prompts: with one slot each request misses the cache, with several both prefixes
/// stay cached. Prints the effect. A benchmark (minutes), and SmolLM2 rarely gets past tuple
/// extraction, so it uses qwen2.5-coder-0.5b (`IVLMAP_BENCH_MODEL` picks another):
/// `cargo test -p ivlmap-tests --release --test e2e pipeline -- --ignored --nocapture`.
#[test]
#[ignore = "benchmark: several minutes with a 0.5B model"]
fn pipeline_requests_hit_the_cache_with_several_slots() {
    let name = std::env::var("IVLMAP_BENCH_MODEL")
        .unwrap_or_else(|_| "qwen2.5-coder-0.5b-instruct-q4_k_m.gguf".into());
    let Some(path) = model(&name) else { return };
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/scenes/flat-a.scene.json"
    );
    let map = Arc::new(map_core::IvlMap::from_scene(
        &map_core::Scene::from_path(scene).unwrap(),
    ));
    let instructions = [
        "go to the second yellow table, then the black sofa",
        "go to the black sofa and face the tv",
        "stop between the first black chair and the yellow table",
    ];
    let run = |n_slots: u32| {
        let mut cfg = LlamaCppConfig::new(&path);
        cfg.n_slots = n_slots;
        let b = Tally {
            inner: LlamaCppBackend::new(cfg).unwrap(),
            sums: Mutex::new((0, 0, 0, 0.0)),
        };
        let mut ctx = PlanContext::new(&map);
        ctx.options.deterministic = false;
        ctx.options.plan_max_tokens = 96;
        ctx.options.max_repairs = 0;
        let t = Instant::now();
        for i in instructions {
            let r = plan_instruction(&b, &Prompts::builtin(), i, &ctx);
            // Whatever the model answers (plan or error); only the cache use is measured.
            println!("{i}: {}", if r.is_ok() { "ok" } else { "error" });
        }
        let wall = t.elapsed().as_secs_f64();
        let s = *b.sums.lock().unwrap();
        println!(
            "{name}, {n_slots} slot(s): {} requests, {} prompt tokens, {} cached ({:.0}%), \
             prompt {:.1} s, wall {wall:.1} s",
            s.0,
            s.1,
            s.2,
            100.0 * s.2 as f64 / s.1 as f64,
            s.3 / 1e3
        );
        s
    };
    let one = run(1);
    let four = run(4);
    assert!(one.0 >= 6 && four.0 >= 6, "two requests per instruction");
    assert!(
        one.2 * 10 < one.1,
        "one slot: alternating prompts miss: {one:?}"
    );
    // The first instruction fills both slots; the others reuse their prefixes.
    assert!(
        four.2 * 2 > four.1,
        "several slots: most prompt tokens come from the cache: {four:?}"
    );
}
