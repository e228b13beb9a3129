//! Whether the prefix cache changes an answer: every request of a cassette answered by a
//! backend that keeps prompt prefixes (in the cassette's order, so later requests reuse
//! earlier ones) and by one that evaluates every prompt from an empty cache. Greedy
//! decoding, so equal computations give equal answers.
//!
//! ```text
//! cargo run -p llm --example cache_agreement -- --model M.gguf --cassette C.jsonl [--n-ctx 8192]
//! ```

use std::path::PathBuf;

use clap::Parser;
use llm::replay::CassetteRecord;
use llm::{LlamaCppBackend, LlamaCppConfig, LlmBackend};

#[derive(Parser)]
struct Args {
    #[arg(long)]
    model: PathBuf,
    #[arg(long)]
    cassette: PathBuf,
    #[arg(long, default_value_t = 8192)]
    n_ctx: u32,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a = Args::parse();
    let records: Vec<CassetteRecord> = std::fs::read_to_string(&a.cassette)?
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(serde_json::from_str)
        .collect::<Result<_, _>>()?;
    let backend = |cache: bool| {
        let mut cfg = LlamaCppConfig::new(&a.model);
        cfg.n_ctx = a.n_ctx;
        cfg.prefix_cache = cache;
        LlamaCppBackend::new(cfg)
    };
    let warm = backend(true)?;
    let cold = backend(false)?;
    let mut same = 0;
    for (i, r) in records.iter().enumerate() {
        let w = warm.complete(&r.request)?;
        let c = cold.complete(&r.request)?;
        let eq = w.text == c.text;
        same += usize::from(eq);
        println!(
            "{i}: {} cached {}/{} prompt {:.0} ms vs {:.0} ms cold",
            if eq { "same" } else { "DIFFERENT" },
            w.cached_prompt_tokens,
            w.prompt_tokens,
            w.prompt_ms,
            c.prompt_ms
        );
        if !eq {
            println!("   warm: {:?}\n   cold: {:?}", w.text, c.text);
        }
    }
    println!("same answers: {same}/{}", records.len());
    Ok(())
}
