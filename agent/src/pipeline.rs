//! The two-step pipeline: instruction -> tuples (step 1) -> resolution against the map ->
//! script (a deterministic template for plain "go to X" sequences, else the LLM, step 2)
//! -> validation, agreement checks and a dry run, with a bounded repair loop.

use std::time::Instant;

use map_core::{IvlMap, Pose, QueryError, SimRobot};
use planner_dsl::{Limits, Plan, PlanError};
use serde::Serialize;

use llm::{ChatMessage, Completion, CompletionRequest, LlmBackend, LlmError};

use crate::align::{align_script, Fix};
use crate::checks::check_script;
use crate::evidence::missing_evidence;
use crate::prompts::{PromptError, Prompts};
use crate::reconcile::{reconcile_tuples, Lexicon};
use crate::script::{extract_code, pythonic_fixups};
use crate::template::simple_goto_script;
use crate::tuples::{parse_tuples, Tuple, TupleParseError};

/// Everything that can stop the language layer (a question or refusal is not an error: see
/// [`Outcome`]).
#[derive(Debug, thiserror::Error)]
pub enum LanguageError {
    /// A prompt template failed.
    #[error(transparent)]
    Prompt(#[from] PromptError),
    /// The backend failed.
    #[error("LLM backend: {0}")]
    Backend(#[from] LlmError),
    /// Step 1's answer holds no usable tuples.
    #[error(
        "cannot read the objects from the model's answer: {source}; the answer was {answer:?}"
    )]
    Tuples {
        /// Why.
        source: TupleParseError,
        /// The model's answer.
        answer: String,
    },
    /// No valid, consistent script after the initial attempt and every repair.
    #[error("no valid plan after {attempts} attempt(s); last problems:\n{}\nlast script:\n{script}", errors.iter().map(|e| format!("  - {e}")).collect::<Vec<_>>().join("\n"))]
    InvalidPlan {
        /// Attempts made (1 + repairs).
        attempts: u32,
        /// The last attempt's problems, with positions.
        errors: Vec<String>,
        /// The last script.
        script: String,
    },
}

/// Time and tokens spent on LLM calls.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Timing {
    /// LLM requests made.
    pub llm_calls: u32,
    /// Prompt tokens over all requests.
    pub prompt_tokens: u64,
    /// Of those, reused from the KV cache.
    pub cached_prompt_tokens: u64,
    /// Generated tokens.
    pub completion_tokens: u64,
    /// Prompt processing, ms (as the backend reports).
    pub prompt_ms: f64,
    /// Generation, ms (as the backend reports).
    pub generate_ms: f64,
    /// Wall time of the whole step, ms.
    pub wall_ms: f64,
}

impl Timing {
    pub(crate) fn add(&mut self, c: &Completion) {
        self.llm_calls += 1;
        self.prompt_tokens += u64::from(c.prompt_tokens);
        self.cached_prompt_tokens += u64::from(c.cached_prompt_tokens);
        self.completion_tokens += u64::from(c.completion_tokens);
        self.prompt_ms += c.prompt_ms;
        self.generate_ms += c.generate_ms;
    }

    fn merge(&mut self, o: &Timing) {
        self.llm_calls += o.llm_calls;
        self.prompt_tokens += o.prompt_tokens;
        self.cached_prompt_tokens += o.cached_prompt_tokens;
        self.completion_tokens += o.completion_tokens;
        self.prompt_ms += o.prompt_ms;
        self.generate_ms += o.generate_ms;
    }
}

/// Knobs of the pipeline.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanOptions {
    /// Repair rounds after the first script (default 2).
    pub max_repairs: u32,
    /// Token budget of step 1 (default 96).
    pub extract_max_tokens: u32,
    /// Token budget of each step 2 request (default 384).
    pub plan_max_tokens: u32,
    /// Write the script without the LLM when the instruction is a plain sequence of
    /// "go to X" whose words agree with the tuples (default on).
    pub deterministic: bool,
    /// Dry-run a candidate plan on a copy of the robot (when one is given); a runtime
    /// error becomes repair feedback (default on).
    pub dry_run: bool,
    /// Render the scene summary into step 1's request too (default off: the suite's
    /// expected tuples use the instruction's own words).
    pub scene_in_extract: bool,
    /// Constrain step 1's answer with [`crate::grammar::tuple_grammar`] (backends that take GBNF:
    /// llama; default on).
    pub tuple_grammar: bool,
    /// Compare step 1's tuples with the instruction's ordinal, superlative, counting and
    /// colour words and ask once more when they miss some (default on; see
    /// [`crate::evidence::missing_evidence`]).
    pub tuple_check: bool,
    /// Reconcile step 1's tuples with the instruction's words: one tuple per mention in
    /// order of mention, ordinals, colours and orders as the words say (default on; see
    /// [`crate::reconcile::reconcile_tuples`]). Off, the model's tuples are used as it wrote them.
    pub reconcile: bool,
    /// Constrain step 2's scripts with [`planner_dsl::script_grammar`] (default off: see
    /// README, "Grammars", for what it costs and changes).
    pub script_grammar: bool,
    /// Which language layer plans (default [`Pipeline::V1`] until v2 wins on the
    /// held-out set; see README).
    pub pipeline: Pipeline,
    /// v2: worked examples shown per instruction, the most similar to it (default 3).
    pub examples: usize,
    /// v2: put every worked example in the static prefix instead (right after the
    /// system message, before the map's summary, which then opens the request), so a
    /// prefix-caching backend evaluates them once for every map and instruction; no
    /// retrieval (`examples` is ignored). Default off.
    pub all_examples: bool,
    /// v2: hold the answer to the grammar of [`crate::v2::grammar::answer_grammar`]
    /// (backends that take GBNF; default on).
    pub answer_grammar: bool,
    /// v2: send the grammar in Lark too, which the llama backend runs with llguidance
    /// instead of GBNF (default on; off measures GBNF).
    pub llguidance: bool,
}

/// Which language layer plans an instruction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Pipeline {
    /// Two steps (tuples, then a script), word tables, alignment and a repair loop.
    #[default]
    V1,
    /// One constrained call per instruction, typed checks, one re-ask, then a question
    /// ([`crate::v2`]).
    V2,
}

impl Default for PlanOptions {
    fn default() -> Self {
        Self {
            max_repairs: 2,
            extract_max_tokens: 96,
            plan_max_tokens: 384,
            deterministic: true,
            dry_run: true,
            scene_in_extract: false,
            tuple_grammar: true,
            tuple_check: true,
            reconcile: true,
            script_grammar: false,
            pipeline: Pipeline::default(),
            examples: 3,
            all_examples: false,
            answer_grammar: true,
            llguidance: true,
        }
    }
}

/// What a plan is made against.
#[derive(Debug, Clone)]
pub struct PlanContext<'a> {
    /// The map.
    pub map: &'a IvlMap,
    /// The robot whose copy dry-runs candidate plans (its pose is the start pose).
    pub robot: Option<&'a SimRobot>,
    /// The robot's pose (used when `robot` is `None`).
    pub pose: Pose,
    /// A summary of the conversation so far (see [`crate::Session`]).
    pub history: Option<String>,
    /// Object ids the conversation visited, which a v2 plan may name with
    /// `get_instance` (see [`crate::Session::references`]).
    pub references: Vec<u32>,
    /// Knobs.
    pub options: PlanOptions,
}

impl<'a> PlanContext<'a> {
    /// A context on `map` with the robot at the map's start pose, no dry run robot, no
    /// history, default options.
    #[must_use]
    pub fn new(map: &'a IvlMap) -> Self {
        Self {
            map,
            robot: None,
            pose: map.start_pose,
            history: None,
            references: Vec::new(),
            options: PlanOptions::default(),
        }
    }

    /// With a robot to dry-run candidate plans on (its pose becomes the pose).
    #[must_use]
    pub fn with_robot(mut self, robot: &'a SimRobot) -> Self {
        use map_core::Robot as _;
        self.pose = robot.pose();
        self.robot = Some(robot);
        self
    }

    pub(crate) fn pose(&self) -> Pose {
        use map_core::Robot as _;
        self.robot.map_or(self.pose, |r| r.pose())
    }
}

/// Where a plan's script came from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PlanSource {
    /// The LLM wrote it, after `repairs` rounds of feedback.
    Llm {
        /// Repair rounds used.
        repairs: u32,
    },
    /// Written from the tuples (a plain sequence of "go to X").
    Template,
    /// Resolved from the conversation ("go back", "the other one").
    History,
}

/// A checked plan for one instruction.
#[derive(Debug, Clone)]
pub struct PlannedInstruction {
    /// The instruction.
    pub instruction: String,
    /// The objects it mentions.
    pub tuples: Vec<Tuple>,
    /// The script (as compiled: after any Python-ism fixups).
    pub script: String,
    /// The compiled, validated plan.
    pub plan: Plan,
    /// Where the script came from.
    pub source: PlanSource,
    /// Time and tokens spent.
    pub timing: Timing,
    /// Every script the LLM wrote, in order (the last is `script` before fixups).
    pub attempts: Vec<String>,
    /// Object picks rewritten to agree with the tuples (see [`crate::align::align_script`]).
    pub fixes: Vec<Fix>,
}

/// What the language layer makes of an instruction.
#[derive(Debug, Clone)]
pub enum Outcome {
    /// A plan that compiled, agrees with the instruction and the map, and (when a robot was
    /// given) dry-ran without error.
    Plan(Box<PlannedInstruction>),
    /// The instruction is ambiguous or asks for something the map does not quite hold (an
    /// ordinal past the count, a colour no such object has): ask the user.
    Question(String),
    /// The instruction cannot be done here (an object the map does not hold).
    Refusal(String),
}

impl Outcome {
    /// The plan, if this is one.
    #[must_use]
    pub fn plan(&self) -> Option<&PlannedInstruction> {
        match self {
            Outcome::Plan(p) => Some(p),
            _ => None,
        }
    }
}

/// How many instances labelled `label` have each colour ("unknown colour" for none), in
/// the order the colours first appear.
pub(crate) fn colour_counts(map: &IvlMap, label: &str) -> Vec<(String, usize)> {
    let mut colours: Vec<(String, usize)> = Vec::new();
    for i in map.instances.iter().filter(|i| i.label == label) {
        let c = i.colour.clone().unwrap_or_else(|| "unknown colour".into());
        match colours.iter_mut().find(|(x, _)| *x == c) {
            Some((_, k)) => *k += 1,
            None => colours.push((c, 1)),
        }
    }
    colours
}

/// "2 black, 1 red".
pub(crate) fn colour_list(colours: &[(String, usize)]) -> String {
    colours
        .iter()
        .map(|(c, k)| format!("{k} {c}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `label` for one instance, its plural for more.
pub(crate) fn noun(label: &str, n: usize) -> String {
    if n == 1 {
        label.to_string()
    } else {
        map_core::matcher::plural(label)
    }
}

/// A one-line summary of what the map holds, for prompts: categories with their colours,
/// then regions. Sorted, so it is the same for every instruction on the scene.
#[must_use]
pub fn scene_summary(map: &IvlMap) -> String {
    let mut parts = Vec::new();
    for (label, n) in map.label_counts() {
        let mut colours = colour_counts(map, &label);
        colours.sort();
        parts.push(format!("{} ({})", noun(&label, n), colour_list(&colours)));
    }
    let mut s = format!("objects: {}", parts.join("; "));
    if !map.regions.is_empty() {
        let names: Vec<&str> = map.regions.iter().map(|r| r.name.as_str()).collect();
        s.push_str(&format!(". regions: {}", names.join(", ")));
    }
    s
}

/// Step 1: the (object, ordinal, colour) tuples of `instruction`, with the default
/// options (tuple grammar on).
///
/// # Errors
/// [`LanguageError::Prompt`], [`LanguageError::Backend`], or [`LanguageError::Tuples`] when
/// the answer holds no usable list.
pub fn extract_tuples(
    backend: &dyn LlmBackend,
    prompts: &Prompts,
    instruction: &str,
    scene_ctx: Option<&str>,
) -> Result<(Vec<Tuple>, Timing), LanguageError> {
    extract_tuples_with(
        backend,
        prompts,
        instruction,
        scene_ctx,
        &PlanOptions::default(),
    )
}

/// Step 1 with explicit options (token budget, tuple grammar), names reconciled against
/// the built-in [`Lexicon`].
///
/// # Errors
/// As [`extract_tuples`].
pub fn extract_tuples_with(
    backend: &dyn LlmBackend,
    prompts: &Prompts,
    instruction: &str,
    scene_ctx: Option<&str>,
    options: &PlanOptions,
) -> Result<(Vec<Tuple>, Timing), LanguageError> {
    extract_tuples_in(
        backend,
        prompts,
        instruction,
        scene_ctx,
        options,
        &Lexicon::builtin(),
    )
}

/// Step 1 with explicit options, reconciling the model's tuples with the instruction's
/// words (when [`PlanOptions::reconcile`]) using `lexicon` for mentions the model left
/// out ([`Lexicon::for_map`] when planning on a map).
///
/// # Errors
/// As [`extract_tuples`].
pub fn extract_tuples_in(
    backend: &dyn LlmBackend,
    prompts: &Prompts,
    instruction: &str,
    scene_ctx: Option<&str>,
    options: &PlanOptions,
    lexicon: &Lexicon,
) -> Result<(Vec<Tuple>, Timing), LanguageError> {
    if options.pipeline == Pipeline::V2 {
        return crate::v2::extract(backend, prompts, instruction, options);
    }
    let t0 = Instant::now();
    let settle = |tuples: Vec<Tuple>| {
        if !options.reconcile {
            return tuples;
        }
        let (tuples, fixes) = reconcile_tuples(instruction, &tuples, lexicon);
        for f in &fixes {
            tracing::debug!(fix = %f, "step 1 reconciled with the instruction's words");
        }
        tuples
    };
    let mut req = CompletionRequest::new(
        prompts.extract_messages(instruction, scene_ctx)?,
        options.extract_max_tokens,
    );
    req.stop = vec!["\nI:".into()];
    if options.tuple_grammar {
        req.grammar = Some(crate::grammar::tuple_grammar());
    }
    let c = backend.complete(&req)?;
    let mut timing = Timing::default();
    timing.add(&c);
    let mut tuples = settle(
        parse_tuples(&c.text).map_err(|source| LanguageError::Tuples {
            source,
            answer: c.text.clone(),
        })?,
    );
    if options.tuple_check {
        let missing = missing_evidence(instruction, &tuples);
        if !missing.is_empty() {
            // One more look, told what the words say; kept only if it misses less.
            tracing::debug!(
                ?missing,
                "tuples miss words of the instruction; asking again"
            );
            req.messages.push(ChatMessage::assistant(c.text.clone()));
            req.messages.push(ChatMessage::user(format!(
                "Check that list against the instruction: {}. Answer with the corrected list only, on one line.",
                missing.join("; ")
            )));
            let again = backend.complete(&req)?;
            timing.add(&again);
            if let Ok(t2) = parse_tuples(&again.text).map(settle) {
                // A shorter list "misses less" by dropping mentions: not a correction.
                if t2.len() >= tuples.len()
                    && missing_evidence(instruction, &t2).len() < missing.len()
                {
                    tuples = t2;
                }
            }
        }
    }
    timing.wall_ms = t0.elapsed().as_secs_f64() * 1000.0;
    Ok((tuples, timing))
}

/// Checks every tuple against the map before anything is planned: an object the map does
/// not hold is refused; an ordinal past the count or a colour no such object has becomes a
/// question. `None` when every tuple resolves.
fn resolve(tuples: &[Tuple], map: &IvlMap, pose: Pose) -> Option<Outcome> {
    for t in tuples {
        let k = t.ordinal.unwrap_or(0);
        match map.get_obj_attributes(&t.object, k, t.colour.as_deref(), t.object_order(), pose) {
            Ok(_) => {}
            Err(QueryError::UnknownObject { .. }) if map.find_region(&t.object).is_ok() => {}
            Err(e @ QueryError::UnknownObject { .. }) => {
                return Some(Outcome::Refusal(format!("I can't do that: {e}.")));
            }
            Err(
                e @ (QueryError::OrdinalPastCount { .. }
                | QueryError::NoSuchColour { .. }
                | QueryError::NotAColour { .. }),
            ) => {
                return Some(Outcome::Question(format!("{e}. Which one do you mean?")));
            }
            Err(e) => return Some(Outcome::Refusal(format!("I can't do that: {e}."))),
        }
    }
    None
}

/// The source line `line` (1-based) of `src`, for quoting in feedback.
fn quote_line(src: &str, line: usize) -> String {
    src.lines()
        .nth(line.wrapping_sub(1))
        .map(|l| format!(" (in `{}`)", l.trim()))
        .unwrap_or_default()
}

fn plan_error_messages(src: &str, e: &PlanError) -> Vec<String> {
    match e {
        PlanError::Syntax { span, message } => {
            vec![format!(
                "{span}: syntax error: {message}{}",
                quote_line(src, span.line)
            )]
        }
        PlanError::TooLong { .. } => vec![format!("{e}: write a shorter plan")],
        PlanError::Rejected { violations } => violations
            .iter()
            .map(|v| format!("{v}{}", quote_line(src, v.span.line)))
            .collect(),
    }
}

/// Compiles (with Python-ism fixups when the raw text does not compile), aligns the object
/// picks with the tuples ([`align_script`]), checks agreement with the tuples and the map,
/// and dry-runs. The plan and the rewrites made, or every problem found.
pub(crate) fn assess(
    raw: &str,
    tuples: &[Tuple],
    ctx: &PlanContext<'_>,
) -> Result<(String, Plan, Vec<Fix>), Vec<String>> {
    if raw.trim().is_empty() {
        return Err(vec![
            "no script found: answer with one ```rhai code block that calls the functions".into(),
        ]);
    }
    let (src, plan) = match Plan::compile(raw) {
        Ok(p) => (raw.to_string(), p),
        Err(e) => {
            let fixed = pythonic_fixups(raw);
            match Plan::compile(&fixed) {
                Ok(p) if fixed != raw => (fixed, p),
                _ => return Err(plan_error_messages(raw, &e)),
            }
        }
    };
    let (src, plan, fixes) = match align_script(&src, tuples, Some(ctx.map)) {
        (aligned, fixes) if !fixes.is_empty() => match Plan::compile(&aligned) {
            Ok(p) => (aligned, p, fixes),
            // Cannot happen for literal rewrites; keep the model's script if it does.
            Err(_) => (src, plan, Vec::new()),
        },
        _ => (src, plan, Vec::new()),
    };
    let findings = check_script(&src, tuples, Some(ctx.map)).map_err(|e| vec![e])?;
    if !findings.is_empty() {
        return Err(findings
            .iter()
            .map(|f| {
                let q = f.pos.map(|p| quote_line(&src, p.line)).unwrap_or_default();
                format!("{f}{q}")
            })
            .collect());
    }
    if ctx.options.dry_run {
        if let Some(robot) = ctx.robot {
            let d = planner_dsl::dry_run(&plan, ctx.map, robot, &Limits::default());
            if let Some(e) = d.outcome.error {
                return Err(vec![format!(
                    "running it fails at {e}{}",
                    quote_line(&src, e.span.line)
                )]);
            }
        }
    }
    Ok((src, plan, fixes))
}

/// Plans one instruction: step 1 (tuples), resolution against the map (a question or a
/// refusal when a tuple does not resolve: the robot never goes somewhere else instead),
/// then a deterministic script for plain "go to X" sequences or step 2 with up to
/// `max_repairs` rounds of positioned feedback.
///
/// # Errors
/// [`LanguageError`]: prompts, backend, unreadable tuples, or no valid consistent script
/// after the repairs ([`LanguageError::InvalidPlan`]).
pub fn plan_instruction(
    backend: &dyn LlmBackend,
    prompts: &Prompts,
    instruction: &str,
    ctx: &PlanContext<'_>,
) -> Result<Outcome, LanguageError> {
    if ctx.options.pipeline == Pipeline::V2 {
        return crate::v2::plan_instruction(backend, prompts, instruction, ctx);
    }
    let t0 = Instant::now();
    let scene = scene_summary(ctx.map);
    let extract_scene = ctx.options.scene_in_extract.then_some(scene.as_str());
    let (tuples, t1) = extract_tuples_in(
        backend,
        prompts,
        instruction,
        extract_scene,
        &ctx.options,
        &Lexicon::for_map(ctx.map),
    )?;
    if let Some(o) = resolve(&tuples, ctx.map, ctx.pose()) {
        return Ok(o);
    }
    plan_from_tuples(backend, prompts, instruction, tuples, ctx, &scene, t1, t0)
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn plan_from_tuples(
    backend: &dyn LlmBackend,
    prompts: &Prompts,
    instruction: &str,
    tuples: Vec<Tuple>,
    ctx: &PlanContext<'_>,
    scene: &str,
    mut timing: Timing,
    t0: Instant,
) -> Result<Outcome, LanguageError> {
    let done = |script: String,
                plan: Plan,
                source: PlanSource,
                timing: Timing,
                attempts: Vec<String>,
                tuples: Vec<Tuple>,
                fixes: Vec<Fix>| {
        let mut timing = timing;
        timing.wall_ms = t0.elapsed().as_secs_f64() * 1000.0;
        Outcome::Plan(Box::new(PlannedInstruction {
            instruction: instruction.to_string(),
            tuples,
            script,
            plan,
            source,
            timing,
            attempts,
            fixes,
        }))
    };
    if ctx.options.deterministic {
        if let Some(script) = simple_goto_script(instruction, &tuples, Some(ctx.map)) {
            if let Ok((src, plan, fixes)) = assess(&script, &tuples, ctx) {
                return Ok(done(
                    src,
                    plan,
                    PlanSource::Template,
                    timing,
                    Vec::new(),
                    tuples,
                    fixes,
                ));
            }
        }
    }
    let mut messages: Vec<ChatMessage> =
        prompts.plan_messages(instruction, &tuples, Some(scene), ctx.history.as_deref())?;
    let mut attempts = Vec::new();
    let mut last_errors = Vec::new();
    for round in 0..=ctx.options.max_repairs {
        let mut req = CompletionRequest::new(messages.clone(), ctx.options.plan_max_tokens);
        if ctx.options.script_grammar {
            req.grammar = Some(planner_dsl::script_grammar());
        }
        let c = backend.complete(&req)?;
        let mut t = Timing::default();
        t.add(&c);
        timing.merge(&t);
        let code = extract_code(&c.text);
        attempts.push(code.clone());
        match assess(&code, &tuples, ctx) {
            Ok((src, plan, fixes)) => {
                return Ok(done(
                    src,
                    plan,
                    PlanSource::Llm { repairs: round },
                    timing,
                    attempts,
                    tuples,
                    fixes,
                ));
            }
            Err(errors) => {
                tracing::debug!(round, ?errors, "plan rejected; asking for a repair");
                messages.push(ChatMessage::assistant(c.text.clone()));
                messages.push(prompts.repair_message(&errors)?);
                last_errors = errors;
            }
        }
    }
    Err(LanguageError::InvalidPlan {
        attempts: ctx.options.max_repairs + 1,
        errors: last_errors,
        script: attempts.pop().unwrap_or_default(),
    })
}
