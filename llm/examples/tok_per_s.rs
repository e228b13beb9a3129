//! Tokens per second of [`LlamaCppBackend`] (the product code path: chat template,
//! tokenisation, the worker thread, sampling and detokenisation), measured the way
//! llama.cpp's `llama-bench` measures pp and tg, so that `bench/llama_bench.sh` can put the
//! two side by side.
//!
//! ```text
//! cargo run --release -p llm --example tok_per_s -- \
//!     --model ~/.cache/ivlmap/models/qwen2.5-coder-1.5b-instruct-q4_k_m.gguf \
//!     [--threads 2] [--n-prompt 512] [--n-gen 128] [--reps 3] [--n-ctx 8192] [--n-batch 512]
//!     [--no-warmup]
//! ```
//!
//! - pp: a chat prompt of exactly `n-prompt` tokens (a user message of repeated words, its
//!   length calibrated with two short requests), evaluated from an empty KV cache: the
//!   backend runs with `prefix_cache = false`, and every answer is checked to report 0
//!   cached prompt tokens. tok/s = `n-prompt` / [`Completion::prompt_ms`] (the decode calls,
//!   as llama-bench times them; `wall_ms` is the whole request).
//! - tg: a short prompt, then `n-gen` single-token decodes (the request asks for `n-gen` + 1
//!   tokens: the first is sampled from the prompt's logits), greedy, end-of-generation
//!   ignored (`ignore_eos`). tok/s = `n-gen` / [`Completion::generate_ms`], which includes
//!   sampling, detokenisation and stop checks of every token.
//! - Warm-up first (unless `--no-warmup`), like llama-bench: one full pp and one 1-token tg.
//!
//! Output: JSON lines on stdout, one per measurement (`{"test":"pp"|"tg","rep",..,"tok_s"}`)
//! and a last `{"summary":..}` line with the medians; progress on stderr.

use std::path::PathBuf;
use std::time::Instant;

use llm::{
    ChatMessage, Completion, CompletionRequest, LlamaCppBackend, LlamaCppConfig, LlmBackend,
};
use serde_json::json;

type BoxError = Box<dyn std::error::Error>;

/// A user message of `k` words, each one token for the usual BPE and SentencePiece
/// vocabularies (" the" is a pre-token of its own and a single token).
fn words(k: usize) -> Vec<ChatMessage> {
    let mut s = String::from("the");
    for _ in 1..k {
        s.push_str(" the");
    }
    vec![ChatMessage::user(s)]
}

fn ask(
    backend: &LlamaCppBackend,
    messages: Vec<ChatMessage>,
    max_tokens: u32,
) -> Result<(Completion, f64), BoxError> {
    let t0 = Instant::now();
    let c = backend.complete(&CompletionRequest::new(messages, max_tokens))?;
    let wall_ms = t0.elapsed().as_secs_f64() * 1e3;
    if c.cached_prompt_tokens != 0 {
        return Err(format!(
            "{} of {} prompt tokens came from the KV cache: the measurement is not fresh",
            c.cached_prompt_tokens, c.prompt_tokens
        )
        .into());
    }
    Ok((c, wall_ms))
}

/// The word count that makes the rendered prompt exactly `n_prompt` tokens.
fn calibrate(backend: &LlamaCppBackend, n_prompt: usize) -> Result<usize, BoxError> {
    let (one, _) = ask(backend, words(1), 1)?;
    let (nine, _) = ask(backend, words(9), 1)?;
    let (p1, p9) = (one.prompt_tokens as usize, nine.prompt_tokens as usize);
    if p9 != p1 + 8 {
        return Err(format!(
            "cannot calibrate the prompt length: 1 word gives {p1} tokens, 9 words give {p9} \
             (expected {}); this vocabulary merges repeated words",
            p1 + 8
        )
        .into());
    }
    if n_prompt < p1 {
        return Err(format!(
            "--n-prompt {n_prompt} is below the chat template's minimum of {p1} tokens"
        )
        .into());
    }
    Ok(n_prompt - (p1 - 1))
}

fn median(xs: &[f64]) -> f64 {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => (v[n / 2 - 1] + v[n / 2]) / 2.0,
    }
}

/// Tokens per second of the llama backend, measured like llama-bench.
#[derive(Debug, clap::Parser)]
struct Args {
    /// The GGUF file.
    #[arg(long)]
    model: PathBuf,
    /// CPU threads.
    #[arg(long, default_value_t = 2)]
    threads: u32,
    /// Prompt tokens per prompt-processing run (pp).
    #[arg(long, default_value_t = 512)]
    n_prompt: usize,
    /// Generated tokens per generation run (tg).
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(1..))]
    n_gen: u32,
    /// Repetitions of each.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u64).range(1..))]
    reps: u64,
    /// Context size (default: the product's).
    #[arg(long)]
    n_ctx: Option<u32>,
    /// Batch size (default: the product's).
    #[arg(long)]
    n_batch: Option<u32>,
    /// Skip the warm-up runs.
    #[arg(long)]
    no_warmup: bool,
}

fn main() -> Result<(), BoxError> {
    let Args {
        model,
        threads,
        n_prompt,
        n_gen,
        reps,
        n_ctx,
        n_batch,
        no_warmup,
    } = clap::Parser::parse();
    let reps = usize::try_from(reps)?;
    let warmup = !no_warmup;

    // The product defaults (n_ctx 8192, batch 512, ...), except: every prompt evaluated in
    // full, and generation of a fixed length.
    let mut cfg = LlamaCppConfig::new(&model);
    cfg.threads = threads;
    cfg.prefix_cache = false;
    cfg.ignore_eos = true;
    if let Some(n) = n_ctx {
        cfg.n_ctx = n;
    }
    if let Some(n) = n_batch {
        cfg.n_batch = n;
    }
    let t_load = Instant::now();
    let backend = LlamaCppBackend::new(cfg.clone())?;
    eprintln!(
        "tok_per_s: loaded {} in {:.1} s",
        model.display(),
        t_load.elapsed().as_secs_f64()
    );
    println!(
        "{}",
        json!({"config": {"model": backend.model(), "threads": cfg.threads, "n_ctx": cfg.n_ctx,
               "n_batch": cfg.n_batch, "n_prompt": n_prompt, "n_gen": n_gen, "reps": reps,
               "omp_wait_policy": std::env::var("OMP_WAIT_POLICY").ok()}})
    );

    let k = calibrate(&backend, n_prompt)?;
    let pp_prompt = || words(k);
    let tg_prompt = || {
        vec![ChatMessage::user(
            "Tell a long story about a robot that maps a house.",
        )]
    };
    if warmup {
        ask(&backend, pp_prompt(), 1)?;
        ask(&backend, tg_prompt(), 2)?;
    }

    let (mut pp, mut tg) = (Vec::new(), Vec::new());
    for rep in 0..reps {
        let (c, wall_ms) = ask(&backend, pp_prompt(), 1)?;
        if c.prompt_tokens as usize != n_prompt {
            return Err(format!(
                "the pp prompt has {} tokens, not {n_prompt}",
                c.prompt_tokens
            )
            .into());
        }
        let tok_s = n_prompt as f64 * 1e3 / c.prompt_ms;
        pp.push(tok_s);
        println!(
            "{}",
            json!({"test": "pp", "rep": rep, "n_tokens": n_prompt, "ms": c.prompt_ms,
                   "wall_ms": wall_ms, "tok_s": tok_s})
        );

        let (c, wall_ms) = ask(&backend, tg_prompt(), n_gen + 1)?;
        if c.completion_tokens != n_gen + 1 {
            return Err(format!(
                "generated {} tokens, not {} (context window too small?)",
                c.completion_tokens,
                n_gen + 1
            )
            .into());
        }
        let tok_s = f64::from(n_gen) * 1e3 / c.generate_ms;
        tg.push(tok_s);
        println!(
            "{}",
            json!({"test": "tg", "rep": rep, "n_tokens": n_gen, "prompt_tokens": c.prompt_tokens,
                   "ms": c.generate_ms, "wall_ms": wall_ms, "tok_s": tok_s})
        );
        eprintln!(
            "tok_per_s: rep {rep}: pp {:.2} tok/s, tg {tok_s:.2} tok/s",
            pp[rep]
        );
    }
    println!(
        "{}",
        json!({"summary": {"pp_median_tok_s": median(&pp), "tg_median_tok_s": median(&tg)}})
    );
    Ok(())
}
