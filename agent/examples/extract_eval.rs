//! Extraction accuracy of a local GGUF model on an `*.extract.jsonl` suite.
//!
//! ```text
//! cargo run --release -p agent --example extract_eval -- \
//!     --model ~/.cache/ivlmap/models/qwen2.5-coder-1.5b-instruct-q4_k_m.gguf \
//!     --suite examples/suites/extract.extract.jsonl [--prompts DIR] [--limit N] [--threads 2]
//! ```
//! Prints one line per case (ok/MISS, latency, got vs expected) and a summary: exact-match
//! accuracy of the whole tuple list (objects compared with the map's synonyms, ordinals and
//! colours after normalisation) and p50/p95 latency.

use std::path::PathBuf;
use std::time::Instant;

use agent::{
    extract_tuples, same_tuples, tuples_paper_form, LlamaCppBackend, LlamaCppConfig, Prompts, Tuple,
};

#[derive(serde::Deserialize)]
struct Case {
    id: String,
    instruction: String,
    expected: Vec<Tuple>,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut model: Option<PathBuf> = None;
    let mut suite = PathBuf::from("examples/suites/extract.extract.jsonl");
    let mut prompts_dir: Option<PathBuf> = None;
    let mut limit = usize::MAX;
    let mut threads = 2u32;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut val = || args.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--model" => model = Some(PathBuf::from(val()?)),
            "--suite" => suite = PathBuf::from(val()?),
            "--prompts" => prompts_dir = Some(PathBuf::from(val()?)),
            "--limit" => limit = val()?.parse()?,
            "--threads" => threads = val()?.parse()?,
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    let model = model.ok_or("--model PATH is required")?;
    let prompts = match &prompts_dir {
        Some(d) => Prompts::load(d)?,
        None => Prompts::builtin(),
    };
    let text = std::fs::read_to_string(&suite)?;
    let mut cases = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let c: Case = serde_json::from_str(line)
            .map_err(|e| format!("{}:{}: {e}", suite.display(), i + 1))?;
        cases.push(c);
    }
    cases.truncate(limit);
    let mut cfg = LlamaCppConfig::new(&model);
    cfg.threads = threads;
    let t_load = Instant::now();
    let backend = LlamaCppBackend::new(cfg)?;
    eprintln!(
        "loaded {} in {:.1} s",
        model.display(),
        t_load.elapsed().as_secs_f64()
    );

    let mut ok = 0usize;
    let mut lat = Vec::new();
    let mut gen_tokens = 0u64;
    for c in &cases {
        let t0 = Instant::now();
        let res = extract_tuples(&backend, &prompts, &c.instruction, None);
        let ms = t0.elapsed().as_secs_f64() * 1000.0;
        lat.push(ms);
        let (good, got) = match &res {
            Ok((t, timing)) => {
                gen_tokens += timing.completion_tokens;
                (same_tuples(t, &c.expected), tuples_paper_form(t))
            }
            Err(e) => (false, format!("ERROR {e}")),
        };
        ok += usize::from(good);
        println!(
            "{} {:>4} {:>6.0} ms  {:<70} got {}  want {}",
            if good { "ok  " } else { "MISS" },
            c.id,
            ms,
            c.instruction,
            got,
            tuples_paper_form(&c.expected)
        );
    }
    lat.sort_by(f64::total_cmp);
    let pct = |p: f64| {
        lat.get(((lat.len() as f64 - 1.0) * p).round() as usize)
            .copied()
            .unwrap_or(0.0)
    };
    println!(
        "\n{} / {} exact ({:.1}%), p50 {:.0} ms, p95 {:.0} ms, {:.1} generated tokens/case, model {}, prompts {}",
        ok,
        cases.len(),
        100.0 * ok as f64 / cases.len().max(1) as f64,
        pct(0.5),
        pct(0.95),
        gen_tokens as f64 / cases.len().max(1) as f64,
        model.display(),
        prompts.label()
    );
    Ok(())
}
