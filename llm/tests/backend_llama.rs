//! The llama.cpp backend against a real GGUF (SmolLM2-135M-Instruct by default).
//!
//! The model comes from `$IVLMAP_MODELS` or `~/.cache/ivlmap/models` (scripts/fetch-models.sh).
//! Tests run one at a time (a shared lock) so that the timing test measures something.
//! `IVLMAP_BENCH_MODEL=<file name or path>` makes the timing test use another model, e.g.
//! `IVLMAP_BENCH_MODEL=qwen2.5-coder-1.5b-instruct-q4_k_m.gguf cargo test -p llm --release
//!  --test backend_llama prefix_cache_speedup -- --nocapture`.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test helpers

use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

use llm::llama::render_chat_template;
use llm::{
    ChatMessage, CompletionRequest, FinishReason, LlamaCppBackend, LlamaCppConfig, LlmBackend,
    LlmError,
};

use ivlmap_tests::{model, SMOL};

fn serial() -> MutexGuard<'static, ()> {
    static LOCK: Mutex<()> = Mutex::new(());
    LOCK.lock().unwrap_or_else(|e| e.into_inner())
}

fn smol(n_ctx: u32) -> Option<LlamaCppBackend> {
    let path = model(SMOL)?;
    let mut cfg = LlamaCppConfig::new(path);
    cfg.n_ctx = n_ctx;
    Some(LlamaCppBackend::new(cfg).unwrap())
}

fn ask(system: &str, user: &str, max_tokens: u32) -> CompletionRequest {
    CompletionRequest::new(
        vec![ChatMessage::system(system), ChatMessage::user(user)],
        max_tokens,
    )
}

/// A few-shot prompt of roughly 600 tokens, the shape the language layer sends.
fn few_shot_prefix() -> String {
    let mut s = String::from(
        "You turn a robot navigation instruction into a list of (object, colour, ordinal, \
         relation) tuples. Use \"\" for a missing colour and 0 for a missing ordinal. Answer \
         with the list only.\n\nExamples:\n",
    );
    let objects = [
        ("table", "yellow"),
        ("sofa", "black"),
        ("chair", "red"),
        ("counter", "white"),
        ("cabinet", "brown"),
        ("bed", "blue"),
        ("sink", "grey"),
        ("shelf", "green"),
    ];
    for (i, (a, ca)) in objects.iter().enumerate() {
        let (b, cb) = objects[(i + 3) % objects.len()];
        let k = i % 3 + 1;
        s.push_str(&format!(
            "Instruction: go to the {} {ca} {a}, then stop on the left of the {cb} {b}, and \
             finally turn to face the nearest {b} while keeping the {a} on your right.\n\
             Tuples: [(\"{a}\", \"{ca}\", {k}, \"goto\"), (\"{b}\", \"{cb}\", 0, \"left_of\"), \
             (\"{b}\", \"\", 0, \"face\"), (\"{a}\", \"\", 0, \"on_right\")]\n\n",
            ["first", "second", "third"][k - 1]
        ));
    }
    s
}

#[test]
fn completion_returns_text_and_counts() {
    let _g = serial();
    let Some(b) = smol(2048) else { return };
    assert_eq!(b.name(), "llama");
    assert_eq!(b.model(), SMOL);
    let c = b
        .complete(&ask(
            "You are a helpful assistant.",
            "Name three colours.",
            24,
        ))
        .unwrap();
    println!("{c:?}");
    assert!(!c.text.trim().is_empty(), "{c:?}");
    assert!(c.prompt_tokens > 5 && c.completion_tokens > 0, "{c:?}");
    assert_eq!(
        c.cached_prompt_tokens, 0,
        "first request cannot hit the cache"
    );
    assert!(c.completion_tokens <= 24);
}

#[test]
fn a_request_seed_picks_the_draw() {
    let _g = serial();
    let Some(b) = smol(2048) else { return };
    let draw = |seed: u32| {
        let mut r = ask(
            "You are a storyteller.",
            "Tell me a story about a robot.",
            24,
        );
        r.temperature = 1.0;
        r.seed = Some(seed);
        b.complete(&r).unwrap().text
    };
    let first = draw(1);
    assert_eq!(first, draw(1), "the same seed draws the same answer");
    assert!(
        (2..6).any(|s| draw(s) != first),
        "other seeds draw other answers"
    );
}

#[test]
fn max_tokens_cuts_generation_with_length_reason() {
    let _g = serial();
    let Some(b) = smol(2048) else { return };
    let c = b
        .complete(&ask(
            "You are a storyteller.",
            "Tell me a long story about a robot.",
            4,
        ))
        .unwrap();
    assert_eq!(c.completion_tokens, 4, "{c:?}");
    assert_eq!(c.finish_reason, FinishReason::Length);
}

#[test]
fn shared_prefix_is_cached_and_output_matches_a_fresh_backend() {
    let _g = serial();
    let Some(warm) = smol(4096) else { return };
    let prefix = few_shot_prefix();
    let a = ask(&prefix, "Instruction: go to the second red chair.", 40);
    let b = ask(
        &prefix,
        "Instruction: stop between the black sofa and the white counter.",
        40,
    );
    let first = warm.complete(&a).unwrap();
    let second = warm.complete(&b).unwrap();
    println!("first: {first:?}\nsecond: {second:?}");
    assert!(second.prompt_tokens > 400, "prefix is long: {second:?}");
    assert!(
        second.cached_prompt_tokens > 400 && second.cached_prompt_tokens < second.prompt_tokens,
        "the shared system prompt should come from the cache: {second:?}"
    );
    // The same request again: everything but the last prompt token is cached.
    let again = warm.complete(&b).unwrap();
    assert_eq!(again.cached_prompt_tokens, again.prompt_tokens - 1);
    assert_eq!(again.text, second.text);

    drop(warm);
    let fresh = smol(4096).unwrap();
    let cold = fresh.complete(&b).unwrap();
    assert_eq!(cold.cached_prompt_tokens, 0);
    assert_eq!(cold.prompt_tokens, second.prompt_tokens);
    assert_eq!(
        cold.text, second.text,
        "greedy output must not depend on the cache"
    );
}

/// Every `.kv` snapshot under the prompt cache folder `dir`.
fn snapshots(dir: &std::path::Path) -> Vec<PathBuf> {
    let mut v = Vec::new();
    for m in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        for f in std::fs::read_dir(m.path()).into_iter().flatten().flatten() {
            if f.path().extension().is_some_and(|x| x == "kv") {
                v.push(f.path());
            }
        }
    }
    v
}

#[test]
fn a_shared_prefix_is_saved_to_disk_and_a_new_backend_reads_it_back() {
    let _g = serial();
    let Some(path) = model(SMOL) else { return };
    let dir = std::env::temp_dir().join(format!("ivlmap-prompt-cache-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let with_disk = || {
        let mut cfg = LlamaCppConfig::new(&path);
        cfg.n_ctx = 4096;
        cfg.prompt_cache_dir = Some(dir.clone());
        LlamaCppBackend::new(cfg).unwrap()
    };
    let prefix = few_shot_prefix().repeat(2);
    let a = ask(&prefix, "Instruction: go to the second red chair.", 30);
    let b = ask(&prefix, "Instruction: face the white counter.", 30);
    let c = ask(
        &prefix,
        "Instruction: stop between the black sofa and the bed.",
        30,
    );

    // One process: the first request evaluates the prefix, the second shares it and
    // writes it.
    let first = with_disk();
    first.complete(&a).unwrap();
    assert!(snapshots(&dir).is_empty(), "one request shares nothing yet");
    let shared = first.complete(&b).unwrap().cached_prompt_tokens;
    assert!(shared > 1000, "{shared}");
    assert_eq!(snapshots(&dir).len(), 1);
    drop(first);

    // A new process reads the prefix back, and answers as if it had evaluated it.
    let second = with_disk();
    let warm = second.complete(&c).unwrap();
    assert_eq!(warm.cached_prompt_tokens, shared, "{warm:?}");
    assert_eq!(snapshots(&dir).len(), 1, "nothing new to save");
    drop(second);
    let cold = smol(4096).unwrap().complete(&c).unwrap();
    assert_eq!(cold.cached_prompt_tokens, 0);
    assert_eq!(
        warm.text, cold.text,
        "greedy output must not depend on the disk cache"
    );

    // A damaged snapshot is not used, and is deleted; the request is answered anyway.
    let kv = snapshots(&dir).remove(0);
    std::fs::write(&kv, b"not a llama.cpp state file").unwrap();
    let third = with_disk();
    let again = third.complete(&c).unwrap();
    assert_eq!(again.cached_prompt_tokens, 0);
    assert_eq!(again.text, cold.text);
    assert!(!kv.exists(), "the damaged snapshot is deleted");
    drop(third);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn two_long_prefixes_taking_turns_in_a_small_cache_are_kept_on_disk() {
    let _g = serial();
    let Some(path) = model(SMOL) else { return };
    let dir = std::env::temp_dir().join(format!("ivlmap-prompt-turns-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    // Room for one of the two prefixes at a time: each request evicts the other's slot.
    let mut cfg = LlamaCppConfig::new(&path);
    cfg.n_ctx = 2048;
    cfg.prompt_cache_dir = Some(dir.clone());
    let backend = LlamaCppBackend::new(cfg).unwrap();
    let p = few_shot_prefix().repeat(2);
    let q: String = p.lines().rev().collect::<Vec<_>>().join("\n");
    let (p1, q1, p2, q2, p3) = (
        ask(&p, "Instruction: go to the second red chair.", 8),
        ask(&q, "Instruction: go to the second red chair.", 8),
        ask(&p, "Instruction: face the white counter.", 8),
        ask(&q, "Instruction: face the white counter.", 8),
        ask(&p, "Instruction: stop by the bed.", 8),
    );
    let first = backend.complete(&p1).unwrap();
    assert!(first.prompt_tokens > 1000, "{first:?}");
    backend.complete(&q1).unwrap();
    assert!(snapshots(&dir).is_empty(), "no prompt was asked twice yet");
    // The first prefix again: evicted, so evaluated again, then written to disk.
    let again = backend.complete(&p2).unwrap();
    assert!(again.cached_prompt_tokens < 100, "{again:?}");
    assert_eq!(snapshots(&dir).len(), 1);
    backend.complete(&q2).unwrap();
    assert_eq!(snapshots(&dir).len(), 2);
    // The third time, the first prefix is read back from disk.
    let third = backend.complete(&p3).unwrap();
    assert!(third.cached_prompt_tokens > 1000, "{third:?}");
    assert_eq!(snapshots(&dir).len(), 2, "nothing new to save");
    drop(backend);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn grammar_forces_the_answer_set() {
    let _g = serial();
    let Some(b) = smol(2048) else { return };
    let mut req = ask(
        "Answer with one word.",
        "Is the sky green? Answer yes or no.",
        8,
    );
    req.grammar = Some(r#"root ::= "yes" | "no""#.into());
    let c = b.complete(&req).unwrap();
    assert!(c.text == "yes" || c.text == "no", "{c:?}");
    assert_eq!(c.finish_reason, FinishReason::Stop);

    // A grammar the model would never follow on its own.
    req.grammar = Some(r#"root ::= "zebra-" [0-9] [0-9] "!""#.into());
    req.max_tokens = 16;
    let c = b.complete(&req).unwrap();
    let t = c.text.as_bytes();
    assert!(
        c.text.len() == 9
            && c.text.starts_with("zebra-")
            && t[6].is_ascii_digit()
            && t[7].is_ascii_digit()
            && t[8] == b'!',
        "{c:?}"
    );
}

#[test]
fn a_lark_grammar_runs_under_llguidance_with_forced_tokens_fast_forwarded() {
    let _g = serial();
    let Some(path) = model(SMOL) else { return };
    let mut cfg = LlamaCppConfig::new(path);
    cfg.n_ctx = 2048;
    cfg.fast_forward = true;
    let b = LlamaCppBackend::new(cfg).unwrap();
    let mut req = ask(
        "Answer with one word.",
        "Is the sky green? Answer yes or no.",
        8,
    );
    req.lark = Some(r#"start: "yes" | "no""#.into());
    // The Lark grammar wins over a GBNF one that would admit something else.
    req.grammar = Some(r#"root ::= "maybe""#.into());
    let c = b.complete(&req).unwrap();
    assert!(c.text == "yes" || c.text == "no", "{c:?}");
    assert_eq!(c.finish_reason, FinishReason::Stop);

    // Long forced stretches (the literals) are decoded in batches, not sampled token by
    // token: the answer is whole, and its tokens are counted as generated.
    req.grammar = None;
    req.max_tokens = 120;
    req.lark = Some(
        r#"start: "objects: [(zebra, " /[1-9]/ ", None)]\nplan:\nmove_to_object(get_obj(\"zebra\"));""#.into(),
    );
    let c = b.complete(&req).unwrap();
    assert!(c.text.starts_with("objects: [(zebra, "), "{c:?}");
    assert!(
        c.text
            .ends_with(", None)]\nplan:\nmove_to_object(get_obj(\"zebra\"));"),
        "{c:?}"
    );
    assert!(c.completion_tokens >= 10, "{c:?}");
    // Only the first token, the digit and the last token of each forced stretch (held
    // back: the model may merge it with what follows) are sampled; the rest is forced.
    assert!(c.forced_tokens + 6 >= c.completion_tokens, "{c:?}");
    assert!(c.forced_tokens >= 10, "{c:?}");
    assert_eq!(c.finish_reason, FinishReason::Stop);

    // A malformed Lark grammar is a grammar error, and the backend keeps working.
    req.lark = Some("start: undefined_rule".into());
    assert!(matches!(b.complete(&req), Err(LlmError::Grammar { .. })));
    req.lark = None;
    assert!(b.complete(&req).is_ok());
}

/// `n` made-up five-letter words (a fixed sequence).
fn made_up_words(n: usize) -> Vec<String> {
    let mut x: u32 = 12345;
    (0..n)
        .map(|_| {
            (0..5)
                .map(|_| {
                    x = x.wrapping_mul(1_103_515_245).wrapping_add(12_345);
                    char::from(b'a' + u8::try_from((x >> 16) % 26).unwrap())
                })
                .collect()
        })
        .collect()
}

#[test]
fn a_lark_grammar_that_llguidance_cannot_hold_fails_the_request() {
    let _g = serial();
    let Some(b) = smol(2048) else { return };
    // A regular expression less many substrings costs llguidance more lexer fuel
    // than one step may spend ("too many expressions constructed"); llama-cpp-2's sampler
    // then masks nothing, and the model writes what it likes. The request fails instead
    // of returning what the grammar never held.
    // (Measured with llguidance 1.9: 20 words are held, 50 and 100 are not, 200 are
    // rejected when the grammar is built.)
    let words = made_up_words(80).join("|");
    let mut req = ask("Answer with a few words.", "Name some animals.", 24);
    req.lark = Some(format!(
        "start: \"animals: \" WORDS\nWORDS: /[a-z]{{1,12}}( [a-z]{{1,12}}){{0,5}}/ & ~/.*({words}).*/"
    ));
    match b.complete(&req) {
        Err(LlmError::GrammarNotHeld {
            after_bytes,
            reason,
        }) => {
            // "animals: " is forced, so the grammar held at least that much.
            assert!(after_bytes >= "animals: ".len(), "{after_bytes}");
            assert!(reason.contains("doesn't satisfy the grammar"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
    // The backend keeps working.
    req.lark = Some(r#"start: "animals: " /[a-z]{1,12}/"#.into());
    let c = b.complete(&req).unwrap();
    assert!(c.text.starts_with("animals: "), "{c:?}");
}

#[test]
fn json_schema_becomes_a_grammar() {
    let _g = serial();
    let Some(b) = smol(2048) else { return };
    let mut req = ask(
        "Answer in JSON.",
        "Is a sofa furniture? Give {\"answer\": \"yes\"|\"no\"}.",
        32,
    );
    req.json_schema = Some(serde_json::json!({
        "type": "object",
        "properties": {"answer": {"type": "string", "enum": ["yes", "no"]}},
        "required": ["answer"],
        "additionalProperties": false
    }));
    let c = b.complete(&req).unwrap();
    let v: serde_json::Value =
        serde_json::from_str(&c.text).unwrap_or_else(|e| panic!("{e}: {c:?}"));
    let ans = v["answer"].as_str().unwrap();
    assert!(ans == "yes" || ans == "no", "{c:?}");
}

#[test]
fn stop_strings_end_generation_and_are_cut() {
    let _g = serial();
    let Some(b) = smol(2048) else { return };
    let mut req = ask("Repeat after me.", "alpha beta gamma", 16);
    req.grammar = Some(r#"root ::= "alpha beta gamma delta""#.into());
    req.stop = vec![" gam".into(), "zzz".into()];
    let c = b.complete(&req).unwrap();
    assert_eq!(c.text, "alpha beta");
    assert_eq!(c.finish_reason, FinishReason::Stop);
}

#[test]
fn bad_grammar_is_an_error_and_the_backend_keeps_working() {
    let _g = serial();
    let Some(b) = smol(2048) else { return };
    let mut req = ask("Answer.", "Hi", 8);
    req.grammar = Some("root ::= undefined_rule".into());
    let err = b.complete(&req).unwrap_err();
    assert!(matches!(err, LlmError::Grammar { .. }), "{err}");
    req.grammar = Some("this is not gbnf".into());
    assert!(matches!(b.complete(&req), Err(LlmError::Grammar { .. })));
    req.grammar = None;
    assert!(b.complete(&req).is_ok());
}

#[test]
fn bad_paths_are_model_load_errors() {
    let _g = serial();
    let err = LlamaCppBackend::new(LlamaCppConfig::new("/nonexistent/model.gguf")).unwrap_err();
    match &err {
        LlmError::ModelLoad { path, .. } => {
            assert_eq!(path, &PathBuf::from("/nonexistent/model.gguf"))
        }
        other => panic!("expected ModelLoad, got {other}"),
    }
    assert!(err.to_string().contains("/nonexistent/model.gguf"), "{err}");

    let dir = tempfile::tempdir().unwrap();
    let junk = dir.path().join("junk.gguf");
    std::fs::write(&junk, "this is not a gguf file").unwrap();
    let err = LlamaCppBackend::new(LlamaCppConfig::new(&junk)).unwrap_err();
    assert!(matches!(err, LlmError::ModelLoad { .. }), "{err}");
    let err = LlamaCppBackend::new(LlamaCppConfig::new(dir.path())).unwrap_err();
    assert!(matches!(err, LlmError::ModelLoad { .. }), "{err}");
}

#[test]
fn prompt_longer_than_the_context_is_an_error() {
    let _g = serial();
    let Some(b) = smol(256) else { return };
    let long = "the yellow table is next to the black sofa. ".repeat(60);
    let err = b.complete(&ask("Summarise.", &long, 8)).unwrap_err();
    match err {
        LlmError::ContextOverflow {
            prompt_tokens,
            n_ctx,
        } => {
            assert_eq!(n_ctx, 256);
            assert!(prompt_tokens > 256);
        }
        other => panic!("expected ContextOverflow, got {other}"),
    }
    // Still usable for a prompt that fits.
    assert!(b.complete(&ask("Answer.", "Hi", 4)).is_ok());
}

#[test]
fn answer_is_bounded_by_the_context_window() {
    let _g = serial();
    // llama.cpp rounds the context up to a multiple of 256; ask for exactly 256.
    let Some(b) = smol(256) else { return };
    let long = "the yellow table is next to the black sofa. ".repeat(18);
    let c = b.complete(&ask("Continue the text.", &long, 1000)).unwrap();
    assert!(c.prompt_tokens > 150, "{c:?}");
    assert!(
        (c.prompt_tokens + c.completion_tokens) as usize <= 256,
        "{c:?}"
    );
}

#[test]
fn chat_templates_render() {
    let _g = serial();
    let Some(path) = model(SMOL) else { return };
    // The Llama-2-chat template as it ships in Hugging Face tokenizer configs.
    let llama2 = "{% if messages[0]['role'] == 'system' %}{% set loop_messages = messages[1:] %}{% set system_message = messages[0]['content'] %}{% else %}{% set loop_messages = messages %}{% set system_message = false %}{% endif %}{% for message in loop_messages %}{% if loop.index0 == 0 and system_message != false %}{% set content = '<<SYS>>\\n' + system_message + '\\n<</SYS>>\\n\\n' + message['content'] %}{% else %}{% set content = message['content'] %}{% endif %}{% if message['role'] == 'user' %}{{ bos_token + '[INST] ' + content.strip() + ' [/INST]' }}{% elif message['role'] == 'assistant' %}{{ ' '  + content.strip() + ' ' + eos_token }}{% endif %}{% endfor %}";
    let msgs = [
        ChatMessage::system("You drive a robot."),
        ChatMessage::user("Go to the sofa."),
    ];
    let p = render_chat_template(&path, llama2, &msgs).unwrap();
    println!("{p:?}");
    assert!(p.contains("[INST]") && p.contains("[/INST]"), "{p:?}");
    assert!(
        p.contains("<<SYS>>\nYou drive a robot.\n<</SYS>>\n\nGo to the sofa."),
        "{p:?}"
    );
    let p = render_chat_template(&path, "chatml", &msgs).unwrap();
    assert_eq!(
        p,
        "<|im_start|>system\nYou drive a robot.<|im_end|>\n<|im_start|>user\nGo to the sofa.<|im_end|>\n<|im_start|>assistant\n"
    );
    let err = render_chat_template(&path, "{{ no template llama.cpp knows }}", &msgs).unwrap_err();
    assert!(matches!(err, LlmError::ChatTemplate { .. }), "{err}");

    // The backend uses the model's own template (SmolLM2: ChatML).
    let b = smol(512).unwrap();
    let p = b.render_prompt(&msgs).unwrap();
    assert!(p.ends_with("<|im_start|>assistant\n"), "{p:?}");

    // A final assistant message begins the answer: the turn stays open after it.
    let mut begun = msgs.to_vec();
    begun.push(ChatMessage::assistant("objects: [(sofa"));
    let q = b.render_prompt(&begun).unwrap();
    assert_eq!(q, format!("{p}objects: [(sofa"));
    let p = render_chat_template(&path, "chatml", &begun).unwrap();
    assert!(
        p.ends_with("<|im_start|>assistant\nobjects: [(sofa"),
        "{p:?}"
    );
}

#[test]
fn a_begun_answer_is_continued_and_not_repeated() {
    let _g = serial();
    let Some(b) = smol(2048) else { return };
    let mut req = ask("Answer with one word.", "Is the sky green?", 8);
    req.grammar = Some(r#"root ::= [0-9] [0-9] "!""#.into());
    let plain = b.complete(&req).unwrap();
    req.messages.push(ChatMessage::assistant("answer: zebra-"));
    // What follows the begun text; the grammar holds only the continuation.
    let c = b.complete(&req).unwrap();
    // The begun text is part of the prompt, not of the answer.
    assert!(c.prompt_tokens > plain.prompt_tokens + 2, "{plain:?} {c:?}");
    let t = c.text.as_bytes();
    assert!(
        c.text.len() == 3 && t[0].is_ascii_digit() && t[1].is_ascii_digit() && t[2] == b'!',
        "{c:?}"
    );
}

#[test]
fn one_backend_serves_several_threads() {
    let _g = serial();
    let Some(b) = smol(2048) else { return };
    let b = Arc::new(b);
    let handles: Vec<_> = (0..3)
        .map(|i| {
            let b = Arc::clone(&b);
            std::thread::spawn(move || {
                b.complete(&ask("Be brief.", &format!("Count to {}.", i + 2), 12))
            })
        })
        .collect();
    for h in handles {
        let c = h.join().unwrap().unwrap();
        assert!(c.completion_tokens > 0);
    }
}

/// Prints prompt-processing and generation speed, with and without the prefix cache
/// (`IVLMAP_BENCH_THREADS` overrides the 2 threads).
#[test]
fn prefix_cache_speedup() {
    let _g = serial();
    let name = std::env::var("IVLMAP_BENCH_MODEL").unwrap_or_else(|_| SMOL.into());
    let Some(path) = model(&name) else { return };
    let prefix = few_shot_prefix();
    let instructions = [
        "Instruction: go to the third yellow table.",
        "Instruction: stop on the right of the black sofa, then face the red chair.",
        "Instruction: move between the white counter and the grey sink.",
        "Instruction: go to the nearest green shelf, then turn to face the blue bed.",
    ];
    let run = |cache: bool| {
        let mut cfg = LlamaCppConfig::new(&path);
        cfg.prefix_cache = cache;
        if let Some(t) = std::env::var("IVLMAP_BENCH_THREADS")
            .ok()
            .and_then(|t| t.parse().ok())
        {
            cfg.threads = t;
        }
        let b = LlamaCppBackend::new(cfg).unwrap();
        // Warm-up request (fills the cache for the cached run).
        b.complete(&ask(&prefix, "Instruction: go to the sofa.", 24))
            .unwrap();
        instructions
            .iter()
            .map(|i| b.complete(&ask(&prefix, i, 24)).unwrap())
            .collect::<Vec<_>>()
    };
    let cold = run(false);
    let warm = run(true);
    let sum = |v: &[llm::Completion], f: fn(&llm::Completion) -> f64| v.iter().map(f).sum::<f64>();
    let n = instructions.len() as f64;
    let cold_prompt = sum(&cold, |c| c.prompt_ms) / n;
    let warm_prompt = sum(&warm, |c| c.prompt_ms) / n;
    let cold_total = sum(&cold, |c| c.prompt_ms + c.generate_ms) / n;
    let warm_total = sum(&warm, |c| c.prompt_ms + c.generate_ms) / n;
    let pp = sum(&cold, |c| f64::from(c.prompt_tokens)) / sum(&cold, |c| c.prompt_ms) * 1e3;
    let tg = sum(&warm, |c| f64::from(c.completion_tokens)) / sum(&warm, |c| c.generate_ms) * 1e3;
    println!(
        "model {name}: prompt ~{} tokens ({} cached); per request: prompt {cold_prompt:.0} ms \
         without cache vs {warm_prompt:.0} ms with; total {cold_total:.0} ms vs {warm_total:.0} ms \
         ({:.1}x); prompt processing {pp:.0} tok/s, generation {tg:.1} tok/s",
        warm[0].prompt_tokens,
        warm[0].cached_prompt_tokens,
        cold_total / warm_total
    );
    // Evaluating the suffix in a smaller batch changes float summation order, so a near-tie
    // can flip a greedy choice; count rather than require identical answers here (the
    // shared-prefix test above checks one case exactly).
    let same = cold
        .iter()
        .zip(&warm)
        .filter(|(c, w)| c.text == w.text)
        .count();
    println!(
        "identical answers with and without the cache: {same}/{}",
        cold.len()
    );
    for w in &warm {
        assert!(w.cached_prompt_tokens > 400, "{w:?}");
    }
    assert!(
        warm_prompt < cold_prompt / 2.0,
        "cache should at least halve prompt time"
    );
}

/// A second few-shot prompt, different from [`few_shot_prefix`] from its first word: the
/// shape of the language layer's plan-generation prompt.
fn plan_prefix() -> String {
    let mut s = String::from(
        "Write a navigation plan for the robot as one call per line. Calls: goto(object), \
         left_of(object), right_of(object), between(a, b), face(object). Objects are written \
         as colour_name_ordinal. Answer with the plan only.\n\nExamples:\n",
    );
    let places = [
        ("kitchen", "fridge", "white"),
        ("office", "desk", "brown"),
        ("bedroom", "bed", "blue"),
        ("hall", "door", "black"),
        ("bathroom", "sink", "grey"),
        ("lounge", "sofa", "red"),
        ("studio", "easel", "green"),
    ];
    for (i, (room, obj, col)) in places.iter().enumerate() {
        let (_, other, ocol) = places[(i + 2) % places.len()];
        s.push_str(&format!(
            "Task: in the {room}, walk up to the {col} {obj}, pass between it and the {ocol} \
             {other}, then wait facing the {other}.\nPlan:\ngoto({col}_{obj}_1)\n\
             between({col}_{obj}_1, {ocol}_{other}_1)\nface({ocol}_{other}_1)\n\n"
        ));
    }
    s
}

fn smol_slots(n_ctx: u32, n_slots: u32) -> Option<LlamaCppBackend> {
    let path = model(SMOL)?;
    let mut cfg = LlamaCppConfig::new(path);
    cfg.n_ctx = n_ctx;
    cfg.n_slots = n_slots;
    Some(LlamaCppBackend::new(cfg).unwrap())
}

#[test]
fn alternating_prefixes_each_keep_their_cache() {
    let _g = serial();
    let Some(warm) = smol_slots(4096, 4) else {
        return;
    };
    let (pa, pb) = (few_shot_prefix(), plan_prefix());
    let a1 = ask(&pa, "Instruction: go to the second red chair.", 32);
    let b1 = ask(&pb, "Task: go to the black sofa.", 32);
    let a2 = ask(
        &pa,
        "Instruction: stop between the black sofa and the white counter.",
        32,
    );
    let b2 = ask(&pb, "Task: in the hall, face the third yellow table.", 32);
    let r_a1 = warm.complete(&a1).unwrap();
    let r_b1 = warm.complete(&b1).unwrap();
    let r_a2 = warm.complete(&a2).unwrap();
    let r_b2 = warm.complete(&b2).unwrap();
    println!("a1: {r_a1:?}\nb1: {r_b1:?}\na2: {r_a2:?}\nb2: {r_b2:?}");
    assert!(r_a1.prompt_tokens > 400 && r_b1.prompt_tokens > 400);
    assert_eq!(r_a1.cached_prompt_tokens, 0);
    assert!(
        r_b1.cached_prompt_tokens < 10,
        "B shares only the template header with A: {r_b1:?}"
    );
    // Everything up to the user message is shared: ~25 tokens of instruction differ.
    for (r, label) in [(&r_a2, "a2"), (&r_b2, "b2")] {
        assert!(
            r.cached_prompt_tokens + 40 >= r.prompt_tokens
                && r.cached_prompt_tokens < r.prompt_tokens,
            "{label} should reuse its own prefix: {r:?}"
        );
    }
    // The latest A request again (A's slot now holds it) hits all but the last prompt token.
    let again = warm.complete(&a2).unwrap();
    assert_eq!(again.cached_prompt_tokens, again.prompt_tokens - 1);
    assert_eq!(again.text, r_a2.text);

    drop(warm);
    let fresh = smol_slots(4096, 4).unwrap();
    let cold_a2 = fresh.complete(&a2).unwrap();
    let fresh = smol_slots(4096, 4).unwrap();
    let cold_b2 = fresh.complete(&b2).unwrap();
    assert_eq!(cold_a2.cached_prompt_tokens, 0);
    assert_eq!(cold_a2.prompt_tokens, r_a2.prompt_tokens);
    assert_eq!(
        cold_a2.text, r_a2.text,
        "greedy output must not depend on the cache"
    );
    assert_eq!(
        cold_b2.text, r_b2.text,
        "greedy output must not depend on the cache"
    );
}

#[test]
fn one_slot_loses_the_prefix_when_prompts_alternate() {
    let _g = serial();
    let Some(b) = smol_slots(4096, 1) else { return };
    let (pa, pb) = (few_shot_prefix(), plan_prefix());
    b.complete(&ask(&pa, "Instruction: go to the sofa.", 8))
        .unwrap();
    b.complete(&ask(&pb, "Task: go to the sofa.", 8)).unwrap();
    let c = b
        .complete(&ask(&pa, "Instruction: go to the bed.", 8))
        .unwrap();
    assert!(c.cached_prompt_tokens < 10, "{c:?}");
}

#[test]
fn full_cache_evicts_the_least_recently_used_slot() {
    let _g = serial();
    // Room for one few-shot prompt and its answer, not two.
    let Some(b) = smol_slots(1024, 4) else { return };
    let (pa, pb) = (few_shot_prefix(), plan_prefix());
    let a = ask(&pa, "Instruction: go to the second red chair.", 16);
    let first = b.complete(&a).unwrap();
    let other = b.complete(&ask(&pb, "Task: go to the sofa.", 16)).unwrap();
    assert!(
        first.prompt_tokens + other.prompt_tokens + 32 > 1024,
        "the two prompts must not fit together: {first:?} {other:?}"
    );
    // A's slot was emptied to make room for B: A starts over, with the same answer.
    let again = b.complete(&a).unwrap();
    assert!(again.cached_prompt_tokens < 10, "{again:?}");
    assert_eq!(again.text, first.text);
    // B was evicted in turn; a short prompt fits beside A and keeps it.
    b.complete(&ask("Answer.", "Hi", 4)).unwrap();
    let a_hit = b.complete(&a).unwrap();
    assert_eq!(
        a_hit.cached_prompt_tokens,
        a_hit.prompt_tokens - 1,
        "{a_hit:?}"
    );
}

#[test]
fn zero_or_too_many_slots_are_config_errors() {
    let Some(path) = model(SMOL) else { return };
    let mut cfg = LlamaCppConfig::new(path);
    cfg.n_slots = 0;
    let err = LlamaCppBackend::new(cfg.clone()).unwrap_err();
    assert!(matches!(err, LlmError::Config { .. }), "{err}");
    cfg.n_slots = 257;
    let err = LlamaCppBackend::new(cfg).unwrap_err();
    assert!(matches!(err, LlmError::Config { .. }), "{err}");
}

#[test]
fn ignore_eos_generates_exactly_max_tokens() {
    let _g = serial();
    let Some(path) = model(SMOL) else { return };
    let req = ask("You are terse.", "Say hi.", 64);
    let mut cfg = LlamaCppConfig::new(&path);
    cfg.n_ctx = 1024;
    let stops = LlamaCppBackend::new(cfg.clone())
        .unwrap()
        .complete(&req)
        .unwrap();
    assert_eq!(stops.finish_reason, FinishReason::Stop, "{stops:?}");
    assert!(stops.completion_tokens < 64, "{stops:?}");
    cfg.ignore_eos = true;
    let full = LlamaCppBackend::new(cfg).unwrap().complete(&req).unwrap();
    assert_eq!(full.completion_tokens, 64, "{full:?}");
    assert_eq!(full.finish_reason, FinishReason::Length);
    assert!(
        full.text.starts_with(&stops.text),
        "{stops:?} then {full:?}"
    );
}
