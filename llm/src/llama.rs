//! The local backend: a GGUF model run in-process by llama.cpp (llama-cpp-2).
//!
//! One worker thread owns the model and its context (`LlamaContext` is not `Sync` and
//! borrows the model); callers talk to it through a channel and wait for the reply, so
//! [`LlamaCppBackend`] is `Send + Sync` and requests are served one at a time.
//!
//! Prefix caching: the KV cache holds several token sequences ("slots", llama.cpp sequence
//! ids `0..n_slots`, like llama-server's slots) in one unified cache, and the worker
//! remembers the tokens of each. Each request's prompt is tokenized in full and goes to the
//! slot sharing the longest common prefix with it (else the least recently used slot); that
//! slot keeps the common prefix, drops the rest, and only the new tokens are evaluated.
//! Requests that alternate between different long few-shot prefixes (tuple extraction and
//! plan generation) therefore each pay for their prefix once. When the cache cannot hold a
//! new prompt plus its answer, least recently used slots are emptied first.
//!
//! Chat template: the model's own (from its GGUF metadata), rendered by llama.cpp's
//! `llama_chat_apply_template`, which recognises the common template families (ChatML,
//! Llama-2/3, Mistral, Gemma, Phi, ...). A model without a template gets ChatML
//! (`<|im_start|>role\ncontent<|im_end|>\n` per message, then `<|im_start|>assistant\n`).
//! [`LlamaCppConfig::chat_template`] overrides both (a llama.cpp template name such as
//! `"chatml"`, `"llama2"`, `"llama3"`, or a Jinja template string llama.cpp can identify).

use std::num::NonZeroU32;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, Sender, SyncSender};
use std::sync::OnceLock;
use std::thread::JoinHandle;
use std::time::Instant;

use llama_cpp_2::context::params::LlamaContextParams;
use llama_cpp_2::context::LlamaContext;
use llama_cpp_2::llama_backend::LlamaBackend as LlamaRuntime;
use llama_cpp_2::llama_batch::LlamaBatch;
use llama_cpp_2::model::params::LlamaModelParams;
use llama_cpp_2::model::{LlamaChatMessage, LlamaChatTemplate, LlamaModel};
use llama_cpp_2::sampling::LlamaSampler;
use llama_cpp_2::token::LlamaToken;
use llama_cpp_2::{ChatTemplateError, LogOptions};

use super::{ChatMessage, Completion, CompletionRequest, FinishReason, LlmBackend, LlmError, Role};

mod disk_cache;
use self::disk_cache::DiskCache;

/// The template used when a model carries none (llama.cpp's built-in ChatML).
pub const FALLBACK_CHAT_TEMPLATE: &str = "chatml";

/// llama.cpp's `LLAMA_MAX_SEQ`: the most sequences (slots) one context can hold.
const MAX_SLOTS: u32 = 256;

/// Settings of the local llama.cpp backend.
#[derive(Debug, Clone, PartialEq)]
pub struct LlamaCppConfig {
    /// The GGUF file.
    pub model_path: PathBuf,
    /// CPU threads for generation and prompt processing (default 2).
    pub threads: u32,
    /// KV cache size in tokens, shared by all slots; one request's prompt plus answer must
    /// fit in it (default 8192).
    pub n_ctx: u32,
    /// Tokens evaluated per llama.cpp batch while reading the prompt (default 512).
    pub n_batch: u32,
    /// Top-k for temperature sampling (ignored when greedy; default 40).
    pub top_k: i32,
    /// Top-p for temperature sampling (ignored when greedy; default 0.95).
    pub top_p: f32,
    /// Seed for temperature sampling when a request gives none (default 42).
    pub seed: u32,
    /// Overrides the model's chat template: a llama.cpp template name ("chatml", "llama2",
    /// "llama3", ...) or a template string. `None`: the model's own, else ChatML.
    pub chat_template: Option<String>,
    /// Reuse the KV cache for a prompt prefix shared with an earlier request (default on).
    pub prefix_cache: bool,
    /// Prompt prefixes kept in the KV cache at once (llama.cpp sequences; default 4).
    pub n_slots: u32,
    /// Keep generating past end-of-generation tokens, to `max_tokens` (default off; for
    /// fixed-length throughput measurements like llama-bench's).
    pub ignore_eos: bool,
    /// With a Lark grammar, decode the bytes the grammar forces in one batch instead of
    /// sampling them token by token (default off). llama-cpp-2's token environment is not
    /// a canonical tokenizer, so the forced bytes are tokenized on their own, and their
    /// last token is held back (sampled), since the model may merge it with what follows.
    /// Without that hold-back, measured with Qwen 1.5B on the v2 answer, the boundaries
    /// derailed the model ("move_to_object(choose_object_by)") where sampling gave a
    /// correct plan; with it, the time to plan is the same as sampling (one subgoal p50
    /// 4.92 s against 5.08 s, `time_to_plan --fast-forward-side`), so it stays off.
    pub fast_forward: bool,
    /// A folder for the prompt cache on disk: snapshots of long prompt prefixes (at least
    /// 512 tokens shared by two requests) that a later process reads back instead of
    /// evaluating them again, at most 8 per model. `None` (the default): nothing is
    /// written.
    pub prompt_cache_dir: Option<PathBuf>,
    /// llama.cpp's fused (flash) attention kernel: `Some(true)` on, `Some(false)` off,
    /// `None` (the default) llama.cpp's own choice, which is on for a CPU. Off is faster
    /// here, measured side by side (default model, 2 threads, 11 held-out v2 tasks after
    /// a 4,100-token cached prefix, two runs each, alternating): a generated token took
    /// 102-110 ms against 126-130 ms, a new prompt token 26-29 ms against 46-47 ms, a
    /// task's p50 12.9-14.0 s against 16.2-16.9 s. But off, a greedy answer can depend on
    /// what the prefix cache held (`alternating_prefixes_each_keep_their_cache` in
    /// `tests/backend_llama.rs` fails: a prompt read back from the cache and the same
    /// prompt evaluated from scratch gave two answers; with the kernel on it passes), so
    /// the default stays llama.cpp's choice and off is for who wants the speed.
    pub flash_attention: Option<bool>,
}

impl LlamaCppConfig {
    /// Defaults for `model_path`: 2 threads, 8192-token context, batch 512, prefix cache on
    /// with 4 slots.
    pub fn new(model_path: impl Into<PathBuf>) -> Self {
        Self {
            model_path: model_path.into(),
            threads: 2,
            n_ctx: 8192,
            n_batch: 512,
            top_k: 40,
            top_p: 0.95,
            seed: 42,
            chat_template: None,
            prefix_cache: true,
            fast_forward: false,
            n_slots: 4,
            ignore_eos: false,
            prompt_cache_dir: None,
            flash_attention: None,
        }
    }
}

/// llama.cpp's process-wide initialisation (allowed once per process), with its logs routed
/// into `tracing`.
fn runtime() -> Result<&'static LlamaRuntime, LlmError> {
    static RUNTIME: OnceLock<Result<LlamaRuntime, String>> = OnceLock::new();
    RUNTIME
        .get_or_init(|| {
            llama_cpp_2::send_logs_to_tracing(LogOptions::default());
            LlamaRuntime::init().map_err(|e| e.to_string())
        })
        .as_ref()
        .map_err(|e| LlmError::ModelLoad {
            path: PathBuf::new(),
            reason: format!("llama.cpp backend initialisation failed: {e}"),
        })
}

fn load_model(path: &Path, vocab_only: bool) -> Result<LlamaModel, LlmError> {
    let fail = |reason: String| LlmError::ModelLoad {
        path: path.to_path_buf(),
        reason,
    };
    // llama-cpp-2 debug-asserts that the file exists: check first, with a clear message.
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => {}
        Ok(_) => return Err(fail("not a file".into())),
        Err(e) => {
            return Err(fail(format!(
                "{e} (fetch models with scripts/fetch-models.sh)"
            )))
        }
    }
    let rt = runtime()?;
    let params = LlamaModelParams::default().with_vocab_only(vocab_only);
    LlamaModel::load_from_file(rt, path, &params).map_err(|e| {
        fail(format!(
            "llama.cpp could not load it ({e}): not a GGUF file, a truncated download, or an \
             architecture this llama.cpp does not know; its log (tracing target llama.cpp) says which"
        ))
    })
}

fn resolve_template(
    model: &LlamaModel,
    override_: Option<&str>,
) -> Result<LlamaChatTemplate, LlmError> {
    let bad = |e: std::ffi::NulError| LlmError::ChatTemplate {
        message: format!("template contains a NUL byte: {e}"),
    };
    if let Some(t) = override_ {
        return LlamaChatTemplate::new(t).map_err(bad);
    }
    match model.chat_template(None) {
        Ok(t) => Ok(t),
        Err(ChatTemplateError::MissingTemplate) => {
            tracing::info!("model has no chat template; using ChatML");
            LlamaChatTemplate::new(FALLBACK_CHAT_TEMPLATE).map_err(bad)
        }
        Err(e) => Err(LlmError::ChatTemplate {
            message: format!("cannot read the model's chat template: {e}"),
        }),
    }
}

fn render(
    model: &LlamaModel,
    template: &LlamaChatTemplate,
    messages: &[ChatMessage],
) -> Result<String, LlmError> {
    // A final assistant message is the beginning of the answer: the turn is opened
    // after the messages before it and that text follows, unclosed.
    let (messages, prefill) = match messages.split_last() {
        Some((last, rest)) if last.role == Role::Assistant && !rest.is_empty() => {
            (rest, Some(last.content.as_str()))
        }
        _ => (messages, None),
    };
    let chat = messages
        .iter()
        .enumerate()
        .map(|(i, m)| {
            LlamaChatMessage::new(m.role.as_str().to_string(), m.content.clone()).map_err(|e| {
                LlmError::InvalidRequest {
                    message: format!("message {i} contains a NUL byte: {e}"),
                }
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut prompt = model
        .apply_chat_template(template, &chat, true)
        .map_err(|e| LlmError::ChatTemplate {
            message: format!(
                "llama.cpp cannot apply this chat template ({e}); it only knows the common \
                 families: set chat_template to one of its names, e.g. \"chatml\" or \"llama2\""
            ),
        })?;
    if let Some(p) = prefill {
        prompt.push_str(p);
    }
    Ok(prompt)
}

/// Renders `messages` with `template` (a llama.cpp template name or template string) using
/// the tokenizer of the GGUF at `gguf` (loaded vocabulary-only: no weights are read), the
/// way [`LlamaCppBackend`] would render its prompt, including the assistant turn's opening.
///
/// # Errors
/// [`LlmError::ModelLoad`], [`LlmError::ChatTemplate`], [`LlmError::InvalidRequest`].
pub fn render_chat_template(
    gguf: &Path,
    template: &str,
    messages: &[ChatMessage],
) -> Result<String, LlmError> {
    let model = load_model(gguf, true)?;
    let template = resolve_template(&model, Some(template))?;
    render(&model, &template, messages)
}

enum Job {
    Complete {
        req: CompletionRequest,
        reply: SyncSender<Result<Completion, LlmError>>,
    },
    Render {
        messages: Vec<ChatMessage>,
        reply: SyncSender<Result<String, LlmError>>,
    },
}

/// A local GGUF model served by llama.cpp on a dedicated worker thread.
#[derive(Debug)]
pub struct LlamaCppBackend {
    model_name: String,
    config: LlamaCppConfig,
    tx: Option<Sender<Job>>,
    worker: Option<JoinHandle<()>>,
}

impl LlamaCppBackend {
    /// Loads the model and creates its context on a new worker thread; returns once both are
    /// ready.
    ///
    /// # Errors
    /// [`LlmError::ModelLoad`] (missing or unreadable file, context allocation failure),
    /// [`LlmError::ChatTemplate`], [`LlmError::Config`] (zero threads/context/batch/slots,
    /// or more slots than llama.cpp's limit of 256 sequences).
    pub fn new(config: LlamaCppConfig) -> Result<Self, LlmError> {
        if config.threads == 0 || config.n_ctx == 0 || config.n_batch == 0 || config.n_slots == 0 {
            return Err(LlmError::Config {
                message: format!(
                    "threads ({}), n_ctx ({}), n_batch ({}) and n_slots ({}) must all be at least 1",
                    config.threads, config.n_ctx, config.n_batch, config.n_slots
                ),
            });
        }
        if config.n_slots > MAX_SLOTS {
            return Err(LlmError::Config {
                message: format!(
                    "n_slots ({}) exceeds llama.cpp's limit of {MAX_SLOTS} sequences",
                    config.n_slots
                ),
            });
        }
        let model_name = config
            .model_path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| config.model_path.display().to_string());
        let (tx, rx) = mpsc::channel::<Job>();
        let (ready_tx, ready_rx) = mpsc::sync_channel::<Result<(), LlmError>>(1);
        let worker_cfg = config.clone();
        let worker = std::thread::Builder::new()
            .name("llama-worker".into())
            .spawn(move || worker_main(worker_cfg, ready_tx, rx))
            .map_err(|e| LlmError::Worker {
                message: format!("cannot spawn the worker thread: {e}"),
            })?;
        match ready_rx.recv() {
            Ok(Ok(())) => Ok(Self {
                model_name,
                config,
                tx: Some(tx),
                worker: Some(worker),
            }),
            Ok(Err(e)) => {
                let _ = worker.join();
                Err(e)
            }
            Err(_) => {
                let _ = worker.join();
                Err(LlmError::Worker {
                    message: "the worker thread ended while loading the model".into(),
                })
            }
        }
    }

    /// The configuration it was built with.
    #[must_use]
    pub fn config(&self) -> &LlamaCppConfig {
        &self.config
    }

    /// The prompt text this backend would feed the model for `messages` (chat template
    /// applied, assistant turn opened).
    ///
    /// # Errors
    /// [`LlmError::ChatTemplate`], [`LlmError::InvalidRequest`], [`LlmError::Worker`].
    pub fn render_prompt(&self, messages: &[ChatMessage]) -> Result<String, LlmError> {
        let (reply, rx) = mpsc::sync_channel(1);
        self.send(Job::Render {
            messages: messages.to_vec(),
            reply,
        })?;
        rx.recv().map_err(|_| worker_gone())?
    }

    fn send(&self, job: Job) -> Result<(), LlmError> {
        self.tx
            .as_ref()
            .ok_or_else(worker_gone)?
            .send(job)
            .map_err(|_| worker_gone())
    }
}

fn worker_gone() -> LlmError {
    LlmError::Worker {
        message: "the llama.cpp worker thread has stopped (see earlier errors or a panic \
                  message); create a new backend"
            .into(),
    }
}

impl LlmBackend for LlamaCppBackend {
    fn name(&self) -> &str {
        "llama"
    }

    fn model(&self) -> &str {
        &self.model_name
    }

    fn complete(&self, req: &CompletionRequest) -> Result<Completion, LlmError> {
        req.validate()?;
        let (reply, rx) = mpsc::sync_channel(1);
        self.send(Job::Complete {
            req: req.clone(),
            reply,
        })?;
        rx.recv().map_err(|_| worker_gone())?
    }
}

impl Drop for LlamaCppBackend {
    fn drop(&mut self) {
        drop(self.tx.take());
        if let Some(w) = self.worker.take() {
            let _ = w.join();
        }
    }
}

fn worker_main(cfg: LlamaCppConfig, ready: SyncSender<Result<(), LlmError>>, rx: Receiver<Job>) {
    let setup = || -> Result<(LlamaModel, LlamaChatTemplate), LlmError> {
        let model = load_model(&cfg.model_path, false)?;
        let template = resolve_template(&model, cfg.chat_template.as_deref())?;
        Ok((model, template))
    };
    let (model, template) = match setup() {
        Ok(x) => x,
        Err(e) => {
            let _ = ready.send(Err(e));
            return;
        }
    };
    let rt = match runtime() {
        Ok(rt) => rt,
        Err(e) => {
            let _ = ready.send(Err(e));
            return;
        }
    };
    let threads = i32::try_from(cfg.threads).unwrap_or(i32::MAX);
    // One unified KV buffer shared by all slots: every slot can use the whole n_ctx (a
    // non-unified cache would split it into n_ctx / n_slots per sequence).
    let params = LlamaContextParams::default()
        .with_n_ctx(NonZeroU32::new(cfg.n_ctx))
        .with_n_seq_max(cfg.n_slots)
        .with_kv_unified(true)
        .with_n_batch(cfg.n_batch)
        .with_n_ubatch(cfg.n_batch)
        .with_n_threads(threads)
        .with_n_threads_batch(threads)
        .with_flash_attention_policy(flash_attention_policy(cfg.flash_attention));
    let ctx = match model.new_context(rt, params) {
        Ok(ctx) => ctx,
        Err(e) => {
            let _ = ready.send(Err(LlmError::ModelLoad {
                path: cfg.model_path.clone(),
                reason: format!(
                    "cannot create a {}-token context ({e}); try a smaller n_ctx",
                    cfg.n_ctx
                ),
            }));
            return;
        }
    };
    let n_slots = if cfg.prefix_cache { cfg.n_slots } else { 1 };
    let mut worker = Worker {
        model: &model,
        ctx,
        template,
        slots: (0..n_slots).map(|_| Slot::default()).collect(),
        clock: 0,
        cfg: &cfg,
        llg: None,
        disk: if cfg.prefix_cache {
            cfg.prompt_cache_dir
                .as_deref()
                .and_then(|d| DiskCache::open(d, &cfg.model_path, &snapshot_settings(&cfg)))
        } else {
            None
        },
    };
    if ready.send(Ok(())).is_err() {
        return;
    }
    for job in rx {
        match job {
            Job::Complete { req, reply } => {
                let _ = reply.send(worker.complete(&req));
            }
            Job::Render { messages, reply } => {
                let _ = reply.send(render(worker.model, &worker.template, &messages));
            }
        }
    }
}

/// One llama.cpp sequence of the KV cache.
#[derive(Default)]
struct Slot {
    /// The tokens whose keys/values are in the KV cache for this sequence, in position order.
    tokens: Vec<LlamaToken>,
    /// `Worker::clock` when a request last used it (0: never).
    last_used: u64,
}

struct Worker<'m> {
    model: &'m LlamaModel,
    ctx: LlamaContext<'m>,
    template: LlamaChatTemplate,
    /// Slot `i` is llama.cpp sequence id `i`.
    slots: Vec<Slot>,
    /// Counts requests, for least-recently-used choices.
    clock: u64,
    cfg: &'m LlamaCppConfig,
    /// llguidance's grammar compiler for this model's vocabulary, built on the first
    /// request with a Lark grammar (walking the vocabulary once).
    llg: Option<llguidance::ParserFactory>,
    /// The prompt cache on disk, when configured.
    disk: Option<DiskCache>,
}

/// The slot for a prompt and the length of the prefix it already holds: the slot with the
/// longest common prefix, if that prefix is worth keeping (at least half of the slot's
/// tokens or half of the prompt); otherwise the least recently used slot, so that a prompt
/// with a different prefix does not overwrite a useful one. Ties go to the least recently
/// used slot.
fn choose_slot(slots: &[Slot], tokens: &[LlamaToken]) -> (usize, usize) {
    let lcp = |s: &Slot| {
        s.tokens
            .iter()
            .zip(tokens)
            .take_while(|(a, b)| a == b)
            .count()
    };
    let lru = slots
        .iter()
        .enumerate()
        .min_by_key(|(_, s)| s.last_used)
        .map_or(0, |(i, _)| i);
    let best = slots
        .iter()
        .enumerate()
        .map(|(i, s)| (i, lcp(s)))
        .max_by(|(i, a), (j, b)| {
            a.cmp(b)
                .then_with(|| slots[*j].last_used.cmp(&slots[*i].last_used))
        });
    match best {
        Some((i, n)) if n > 0 && (2 * n >= slots[i].tokens.len() || 2 * n >= tokens.len()) => {
            (i, n)
        }
        _ => (lru, slots.get(lru).map_or(0, lcp)),
    }
}

/// The sampler chain of a request, and for a Lark grammar a second matcher that follows
/// the sampled tokens: to check that the grammar still holds them, and to find the
/// tokens the grammar forces (fast-forward).
struct Sampling {
    chain: LlamaSampler,
    /// A clone of the Lark matcher that follows every token the chain samples. llama-cpp-2's
    /// llguidance sampler masks nothing once its matcher fails (llguidance runs out of
    /// lexer fuel on a costly regular expression, "too many expressions constructed"),
    /// and the rest of the answer is then sampled without the grammar; the follower fails
    /// on the same token, and the request fails with [`LlmError::GrammarNotHeld`] instead of
    /// returning an answer the grammar never held.
    follower: Option<llguidance::Matcher>,
}

impl Worker<'_> {
    fn lark_matcher(&mut self, lark: &str) -> Result<llguidance::Matcher, LlmError> {
        let bad = |what: &str, e: String| LlmError::Grammar {
            message: format!("llguidance {what}: {e}"),
        };
        if self.llg.is_none() {
            let env = LlamaSampler::llguidance_tok_env(self.model);
            self.llg = Some(
                llguidance::ParserFactory::new_simple(&env)
                    .map_err(|e| bad("cannot read this model's vocabulary", e.to_string()))?,
            );
        }
        let factory = self
            .llg
            .as_ref()
            .ok_or_else(|| bad("is not ready", String::new()))?;
        let grammar = llguidance::api::TopLevelGrammar::from_lark(lark.to_string());
        let parser = factory
            .create_parser(grammar)
            .map_err(|e| bad("rejected the Lark grammar", e.to_string()))?;
        let m = llguidance::Matcher::new(Ok(parser));
        match m.get_error() {
            Some(e) => Err(bad("rejected the Lark grammar", e)),
            None => Ok(m),
        }
    }

    fn sampler(&mut self, req: &CompletionRequest) -> Result<Sampling, LlmError> {
        let mut chain = Vec::new();
        let mut follower = None;
        if let Some(lark) = &req.lark {
            let m = self.lark_matcher(lark)?;
            follower = Some(m.deep_clone());
            chain.push(LlamaSampler::from(m));
        }
        let grammar = match (&req.grammar, &req.json_schema) {
            _ if !chain.is_empty() => None,
            (Some(g), _) => Some(g.clone()),
            (None, Some(schema)) => Some(
                llama_cpp_2::json_schema_to_grammar(&schema.to_string()).map_err(|e| {
                    LlmError::Grammar {
                        message: format!("cannot convert json_schema to a grammar: {e}"),
                    }
                })?,
            ),
            (None, None) => None,
        };
        if let Some(g) = grammar {
            let s =
                LlamaSampler::grammar(self.model, &g, "root").map_err(|e| LlmError::Grammar {
                    message: format!(
                        "llama.cpp rejected the GBNF grammar ({e}); it needs a `root` rule and \
                     valid GBNF (the parse error is in the tracing log, target llama.cpp)"
                    ),
                })?;
            chain.push(s);
        }
        if req.temperature <= 0.0 {
            chain.push(LlamaSampler::greedy());
        } else {
            chain.push(LlamaSampler::top_k(self.cfg.top_k));
            chain.push(LlamaSampler::top_p(self.cfg.top_p, 1));
            chain.push(LlamaSampler::temp(req.temperature));
            chain.push(LlamaSampler::dist(req.seed.unwrap_or(self.cfg.seed)));
        }
        Ok(Sampling {
            chain: LlamaSampler::chain_simple(chain),
            follower,
        })
    }

    fn reset_cache(&mut self) {
        self.ctx.clear_kv_cache();
        for s in &mut self.slots {
            s.tokens.clear();
        }
    }

    /// Empties slot `i` (its whole sequence); empties every slot if llama.cpp refuses.
    fn clear_slot(&mut self, i: usize) {
        let cleared = u32::try_from(i)
            .ok()
            .and_then(|seq| self.ctx.clear_kv_cache_seq(Some(seq), None, None).ok());
        if cleared == Some(true) {
            if let Some(s) = self.slots.get_mut(i) {
                s.tokens.clear();
            }
        } else {
            self.reset_cache();
        }
    }

    /// Empties least recently used slots other than `slot` until `need` more cells fit.
    fn make_room(&mut self, slot: usize, need: usize) {
        let n_ctx = self.ctx.n_ctx() as usize;
        loop {
            let used: usize = self.slots.iter().map(|s| s.tokens.len()).sum();
            if used + need <= n_ctx {
                break;
            }
            let victim = self
                .slots
                .iter()
                .enumerate()
                .filter(|(i, s)| *i != slot && !s.tokens.is_empty())
                .min_by_key(|(_, s)| s.last_used)
                .map(|(i, _)| i);
            match victim {
                Some(v) => self.clear_slot(v),
                // Nothing else to empty: the caller checked that the request fits n_ctx.
                None => break,
            }
        }
    }

    /// Reads into `slot` the disk snapshot sharing more of `tokens` than the slot's
    /// `common` prefix does; returns the new common prefix (`common` when none is read).
    fn load_from_disk(
        &mut self,
        slot: usize,
        seq: i32,
        tokens: &[LlamaToken],
        common: usize,
    ) -> usize {
        let Some((kv, n, len)) = self
            .disk
            .as_ref()
            .and_then(|d| d.best(tokens))
            .filter(|(_, n)| *n > common)
            .map(|(e, n)| (e.kv.clone(), n, e.tokens.len()))
        else {
            return common;
        };
        if len >= self.ctx.n_ctx() as usize {
            return common;
        }
        self.clear_slot(slot);
        self.make_room(slot, len);
        match self.ctx.state_seq_load_file(&kv, seq, len) {
            Ok((loaded, _)) if loaded.len() == len => {
                tracing::debug!(file = %kv.display(), tokens = len, shared = n, "prompt cache: prefix read from disk");
                if let Some(s) = self.slots.get_mut(slot) {
                    s.tokens = loaded;
                }
                n
            }
            other => {
                tracing::warn!(file = %kv.display(), error = ?other.err(), "prompt cache: llama.cpp would not load this snapshot; deleting it");
                self.clear_slot(slot);
                if let Some(d) = self.disk.as_mut() {
                    d.discard(&kv);
                }
                0
            }
        }
    }

    /// Writes the slot's sequence to disk when it holds a long prefix (the one this request
    /// shares with an earlier one) that no snapshot covers yet.
    fn save_to_disk(&mut self, slot: usize, seq: i32, tokens: &[LlamaToken]) {
        let Some(s) = self.slots.get(slot) else {
            return;
        };
        let n = s.tokens.len();
        let Some(d) = self.disk.as_ref().filter(|d| d.wants(tokens, n)) else {
            return;
        };
        let path = d.next_path();
        match self.ctx.state_seq_save_file(&path, seq, &s.tokens) {
            Ok(bytes) => {
                tracing::debug!(file = %path.display(), tokens = n, bytes, "prompt cache: prefix written to disk");
                let held = s.tokens.clone();
                if let Some(d) = self.disk.as_mut() {
                    d.add(path, &held);
                }
            }
            Err(e) => {
                tracing::warn!(file = %path.display(), error = %e, "prompt cache: cannot write a snapshot");
                let _ = std::fs::remove_file(&path);
            }
        }
    }

    fn decode(&mut self, batch: &mut LlamaBatch<'_>) -> Result<(), LlmError> {
        self.ctx.decode(batch).map_err(|e| {
            self.reset_cache();
            LlmError::Decode {
                message: e.to_string(),
            }
        })
    }

    fn complete(&mut self, req: &CompletionRequest) -> Result<Completion, LlmError> {
        let model: &LlamaModel = self.model;
        let prompt = render(model, &self.template, &req.messages)?;
        let vocab = model.vocab();
        let mut tokens = vocab.tokenize(prompt.as_bytes(), true, true);
        // Templates that spell out BOS plus a tokenizer that adds one would double it.
        if tokens.len() >= 2 && tokens[0] == vocab.bos() && tokens[1] == vocab.bos() {
            tokens.remove(0);
        }
        let n_ctx = self.ctx.n_ctx() as usize;
        if tokens.is_empty() {
            return Err(LlmError::InvalidRequest {
                message: "the rendered prompt has no tokens".into(),
            });
        }
        if tokens.len() >= n_ctx {
            return Err(LlmError::ContextOverflow {
                prompt_tokens: tokens.len(),
                n_ctx: self.ctx.n_ctx(),
            });
        }
        // Build the sampler first: a bad grammar fails before the cache is touched.
        let Sampling {
            chain: mut sampler,
            mut follower,
        } = self.sampler(req)?;

        let max_new = (req.max_tokens as usize).min(n_ctx - tokens.len());

        // Pick the slot holding the longest useful common prefix and keep that prefix;
        // always evaluate at least one token so that there are fresh logits to sample from.
        self.clock += 1;
        let (slot, common) = if self.cfg.prefix_cache {
            choose_slot(&self.slots, &tokens)
        } else {
            (0, 0)
        };
        let seq = i32::try_from(slot).map_err(|_| LlmError::Decode {
            message: format!("slot {slot} does not fit llama.cpp's sequence ids"),
        })?;
        let common = self.load_from_disk(slot, seq, &tokens, common.min(tokens.len() - 1));
        let mut keep = common.min(tokens.len() - 1);
        let held = self.slots.get(slot).map_or(0, |s| s.tokens.len());
        if keep < held {
            let removed = u32::try_from(keep).ok().and_then(|p0| {
                self.ctx
                    .clear_kv_cache_seq(Some(seq.unsigned_abs()), Some(p0), None)
                    .ok()
            });
            if removed != Some(true) {
                // Some memory types (recurrent models) cannot drop a suffix: start over.
                self.clear_slot(slot);
                keep = 0;
            }
        }
        if let Some(s) = self.slots.get_mut(slot) {
            s.tokens.truncate(keep);
            s.last_used = self.clock;
        }
        // The slots share one KV buffer of n_ctx cells: make room for the rest of the prompt
        // and the longest answer by emptying least recently used slots.
        self.make_room(slot, tokens.len() - keep + max_new);
        // `clear_slot` may have fallen back to emptying everything.
        if self.slots.get(slot).map_or(0, |s| s.tokens.len()) < keep {
            keep = 0;
        }
        // The slot now holds exactly the prefix this prompt shares with what it held.
        self.save_to_disk(slot, seq, &tokens);

        let t_prompt = Instant::now();
        let n_batch = (self.ctx.n_batch() as usize).max(1);
        let mut batch = LlamaBatch::new(n_batch, 1);
        let mut last_idx = 0;
        for (ci, chunk) in tokens[keep..].chunks(n_batch).enumerate() {
            batch.clear();
            let base = keep + ci * n_batch;
            for (j, &tok) in chunk.iter().enumerate() {
                let pos = base + j;
                add(&mut batch, tok, pos, seq, pos + 1 == tokens.len())?;
            }
            self.decode(&mut batch)?;
            if let Some(s) = self.slots.get_mut(slot) {
                s.tokens.extend_from_slice(chunk);
            }
            last_idx = batch.n_tokens() - 1;
        }
        let prompt_ms = t_prompt.elapsed().as_secs_f64() * 1e3;
        // A long prefix shared with a recent prompt that the KV cache no longer held (this
        // request evaluated it again): the slot now holds the whole prompt; keep it on disk.
        let shared = self.disk.as_mut().map_or(0, |d| d.asked_before(&tokens));
        if shared >= keep + disk_cache::MIN_TOKENS {
            self.save_to_disk(slot, seq, &tokens);
        }

        let t_gen = Instant::now();
        let max_stop = req.stop.iter().map(String::len).max().unwrap_or(0);
        let mut out: Vec<u8> = Vec::new();
        let mut n_gen = 0usize;
        let mut n_forced = 0usize;
        let mut pos = tokens.len();
        let finish = loop {
            if n_gen >= max_new {
                break FinishReason::Length;
            }
            // `sample` also accepts the token into every sampler of the chain (grammar
            // included); accepting it again would corrupt the grammar state.
            let tok = sampler.sample(&self.ctx, last_idx);
            if !self.cfg.ignore_eos && vocab.is_eog(tok) {
                break FinishReason::Stop;
            }
            n_gen += 1;
            let before = out.len();
            out.extend_from_slice(&vocab.token_to_piece(tok, false, None));
            if let Some(cut) = find_stop(&out, before, max_stop, &req.stop) {
                out.truncate(cut);
                break FinishReason::Stop;
            }
            if n_gen >= max_new {
                break FinishReason::Length;
            }
            // Fast-forward: the tokens the grammar forces after this one are not sampled
            // one by one; they join this token in one batch.
            // llama-cpp-2's token environment is not a canonical tokenizer, so llguidance
            // gives the forced bytes; they are tokenized here with the model's vocabulary.
            let mut forced: Vec<LlamaToken> = Vec::new();
            // (A matcher that has finished its grammar takes no more tokens; the sampler's
            // own matcher skips them too.)
            if let Some(m) = follower
                .as_mut()
                .filter(|m| m.is_error() || !m.is_stopped())
            {
                if m.consume_token(tok.0.cast_unsigned()).is_err() {
                    let why = m.get_error().unwrap_or_default();
                    let why = why.lines().next().unwrap_or_default();
                    return Err(LlmError::GrammarNotHeld {
                        after_bytes: out.len(),
                        reason: why.to_string(),
                    });
                }
                if self.cfg.fast_forward {
                    let room = (max_new - n_gen).min(n_batch.saturating_sub(1));
                    let bytes = m.compute_ff_bytes();
                    if !bytes.is_empty() {
                        forced = vocab.tokenize(&bytes, false, false);
                        // The last token of the forced bytes may be one the model would
                        // merge with what follows (`("` before `sofa`, Qwen's BPE joins
                        // punctuation runs): it is held back and sampled, so every token
                        // boundary fast-forwarded is one the forced text itself ends.
                        forced.pop();
                        forced.truncate(room);
                        let ids: Vec<u32> = forced.iter().map(|t| t.0.cast_unsigned()).collect();
                        // Only the forced tokens the grammar takes as tokenized here go
                        // ahead; the rest are sampled.
                        let taken = m.try_consume_tokens(&ids).unwrap_or(0);
                        forced.truncate(taken);
                    }
                }
            }
            batch.clear();
            let step: Vec<LlamaToken> =
                std::iter::once(tok).chain(forced.iter().copied()).collect();
            for (j, &t) in step.iter().enumerate() {
                add(&mut batch, t, pos + j, seq, j + 1 == step.len())?;
            }
            self.decode(&mut batch)?;
            if let Some(s) = self.slots.get_mut(slot) {
                s.tokens.extend_from_slice(&step);
            }
            pos += step.len();
            last_idx = batch.n_tokens() - 1;
            let mut stopped = false;
            for &t in &step[1..] {
                sampler.accept(t);
                n_gen += 1;
                n_forced += 1;
                let before = out.len();
                out.extend_from_slice(&vocab.token_to_piece(t, false, None));
                if let Some(cut) = find_stop(&out, before, max_stop, &req.stop) {
                    out.truncate(cut);
                    stopped = true;
                    break;
                }
            }
            if stopped {
                break FinishReason::Stop;
            }
        };
        let generate_ms = t_gen.elapsed().as_secs_f64() * 1e3;
        Ok(Completion {
            text: String::from_utf8_lossy(&out).into_owned(),
            prompt_tokens: count(tokens.len()),
            cached_prompt_tokens: count(keep),
            completion_tokens: count(n_gen),
            prompt_ms,
            generate_ms,
            finish_reason: finish,
            forced_tokens: count(n_forced),
        })
    }
}

/// The settings a prompt-cache snapshot is read back under: the thread count and batch
/// size (llama.cpp's sums run in another order under others), and flash attention (the
/// values are laid out differently with and without it; llama.cpp refuses the other's).
fn snapshot_settings(cfg: &LlamaCppConfig) -> String {
    let fa = match cfg.flash_attention {
        Some(true) => "-fa",
        Some(false) => "-nofa",
        None => "",
    };
    format!("t{}-b{}{fa}", cfg.threads, cfg.n_batch)
}

/// llama.cpp's flash-attention policy for [`LlamaCppConfig::flash_attention`].
fn flash_attention_policy(on: Option<bool>) -> llama_cpp_sys_2::llama_flash_attn_type {
    match on {
        Some(true) => llama_cpp_sys_2::LLAMA_FLASH_ATTN_TYPE_ENABLED,
        Some(false) => llama_cpp_sys_2::LLAMA_FLASH_ATTN_TYPE_DISABLED,
        None => llama_cpp_sys_2::LLAMA_FLASH_ATTN_TYPE_AUTO,
    }
}

fn count(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

fn add(
    batch: &mut LlamaBatch<'_>,
    tok: LlamaToken,
    pos: usize,
    seq: i32,
    logits: bool,
) -> Result<(), LlmError> {
    let pos = i32::try_from(pos).map_err(|_| LlmError::Decode {
        message: format!("position {pos} does not fit llama.cpp's i32"),
    })?;
    batch
        .add(tok, pos, &[seq], logits)
        .map_err(|e| LlmError::Decode {
            message: format!("cannot add a token to the batch: {e}"),
        })
}

/// The byte offset where the earliest stop string starts, looking only at matches that end
/// in the bytes appended since `before`.
fn find_stop(out: &[u8], before: usize, max_stop: usize, stops: &[String]) -> Option<usize> {
    let from = before.saturating_sub(max_stop.saturating_sub(1));
    stops
        .iter()
        .filter_map(|s| {
            let s = s.as_bytes();
            out[from..]
                .windows(s.len())
                .position(|w| w == s)
                .map(|p| from + p)
        })
        .min()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_snapshot_is_read_back_only_under_the_attention_kernel_that_wrote_it() {
        let mut cfg = LlamaCppConfig::new("m.gguf");
        // llama.cpp's own choice (the default) keeps the folder snapshots had before.
        assert_eq!(cfg.flash_attention, None);
        assert_eq!(snapshot_settings(&cfg), "t2-b512");
        cfg.flash_attention = Some(false);
        assert_eq!(snapshot_settings(&cfg), "t2-b512-nofa");
        cfg.flash_attention = Some(true);
        cfg.threads = 4;
        assert_eq!(snapshot_settings(&cfg), "t4-b512-fa");
        assert_eq!(
            flash_attention_policy(Some(false)),
            llama_cpp_sys_2::LLAMA_FLASH_ATTN_TYPE_DISABLED
        );
        assert_eq!(
            flash_attention_policy(None),
            llama_cpp_sys_2::LLAMA_FLASH_ATTN_TYPE_AUTO
        );
    }

    #[test]
    fn find_stop_sees_strings_spanning_pieces() {
        let stops = vec!["```".to_string(), "END".to_string()];
        let out = b"let x = 1;\n``";
        assert_eq!(find_stop(out, 10, 3, &stops), None);
        let out = b"let x = 1;\n```\n";
        assert_eq!(find_stop(out, 13, 3, &stops), Some(11));
        assert_eq!(find_stop(b"xEND", 1, 3, &stops), Some(1));
    }

    fn slot(tokens: &[i32], last_used: u64) -> Slot {
        Slot {
            tokens: tokens.iter().map(|&t| LlamaToken::new(t)).collect(),
            last_used,
        }
    }

    #[test]
    fn slot_choice_prefers_long_prefixes_then_least_recently_used() {
        let toks = |v: &[i32]| v.iter().map(|&t| LlamaToken::new(t)).collect::<Vec<_>>();
        let slots = vec![
            slot(&[1, 2, 3, 4, 5, 6], 3),
            slot(&[1, 9, 9, 9, 9, 9], 2),
            slot(&[], 0),
        ];
        // Longest common prefix wins.
        assert_eq!(choose_slot(&slots, &toks(&[1, 2, 3, 4, 7])), (0, 4));
        // A one-token header in common is not worth overwriting slot 1: the empty slot.
        assert_eq!(choose_slot(&slots, &toks(&[1, 8, 8, 8, 8, 8])), (2, 0));
        // Nothing in common: the least recently used slot (the empty one).
        assert_eq!(choose_slot(&slots, &toks(&[5, 5])), (2, 0));
        // No empty slot: least recently used is slot 1.
        let full = vec![slot(&[1, 2, 3], 5), slot(&[4, 5], 1), slot(&[6], 3)];
        assert_eq!(choose_slot(&full, &toks(&[7, 7])), (1, 0));
        // Equal prefixes: the least recently used of them.
        let tie = vec![slot(&[1, 2], 5), slot(&[1, 2], 4)];
        assert_eq!(choose_slot(&tie, &toks(&[1, 2, 3])), (1, 2));
    }

    #[test]
    fn zero_sizes_are_config_errors() {
        let mut cfg = LlamaCppConfig::new("/nonexistent.gguf");
        cfg.threads = 0;
        let err = LlamaCppBackend::new(cfg).unwrap_err();
        assert!(matches!(err, LlmError::Config { .. }), "{err}");
    }
}
