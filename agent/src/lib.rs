//! # agent: the ivlmap language layer
//!
//! Turns an instruction into (object, ordinal, colour) tuples and a checked Rhai plan.
//!
//! - LLM backends behind [`LlmBackend`]: [`LlamaCppBackend`] (any local GGUF through
//!   llama.cpp, with a multi-slot prefix cache and GBNF grammars), [`OpenAiBackend`]
//!   (any OpenAI-compatible server) and [`ReplayBackend`] / [`Recording`] (cassettes).
//! - The language layer: [`Prompts`] (templates in `prompts/`, variants as folders),
//!   [`extract_tuples`], [`plan_instruction`] (validation with planner_dsl, checks
//!   against the tuples and the map, a bounded repair loop) and chat [`Session`]s.
//! - Evaluation of extraction and navigation suites, and the `ivlmap` binary's parts.
//!
//! ```
//! // The paper's tuple form and JSON both parse; ordinals and colours are normalised.
//! let t = agent::parse_tuples("[(tables, third, Yellow), (sofa, last, none)]").unwrap();
//! assert_eq!((t[0].object.as_str(), t[0].ordinal, t[0].colour.as_deref()), ("table", Some(3), Some("yellow")));
//! assert_eq!((t[1].ordinal, t[1].colour.as_deref()), (Some(-1), None));
//! ```

mod backend;
mod cli;
mod eval;
mod language;

pub use backend::{
    render_chat_template, CassetteRecord, ChatMessage, Completion, CompletionRequest, FinishReason,
    LlamaCppBackend, LlamaCppConfig, LlmBackend, LlmError, OpenAiBackend, OpenAiConfig, Recording,
    ReplayBackend, Role, FALLBACK_CHAT_TEMPLATE,
};
pub use cli::{
    default_model_path, inspect_table, load_map, load_mission, open_backend, overlay_stops,
    render_map, run_mission, write_json, BackendChoice, Chat, ChatFlow, CliError, Mission,
    MissionReport, CHAT_HELP, DEFAULT_MODEL_FILE,
};
pub use cli::{map_build, MapBuildArgs, TOPDOWN_PNG};
pub use eval::{
    load_extract_suite, load_nav_suite, nav_scores, percentile, reached, run_extract, run_nav,
    run_task, satisfies, summarise, summary_table, vlmap_script, CaseResult, ExtractCase, Method,
    NavScores, NavTask, Report, Subgoal, SuiteError, SuiteKind, Summary, SUCCESS_RADIUS_M,
};
pub use eval::{
    noise_study, noise_study_cli, noise_table, reference_tuples, NoiseEffects, NoiseRow,
    NoiseStudy, NoiseStudyArgs, NoiseStudyOptions, NOISE_KINDS,
};
pub use language::{
    align_script, check_script, extract_code, extract_tuples, extract_tuples_in,
    extract_tuples_with, library_calls, missing_evidence, normalise_colour, normalise_object,
    normalise_order, parse_ordinal, parse_ordinal_with_order, parse_tuples, plan_instruction,
    pythonic_fixups, reconcile_tuples, same_tuples, scene_summary, simple_goto_script,
    tuple_grammar, tuples_paper_form, Arg, Finding, FindingKind, Fix, LanguageError, Lexicon,
    LibCall, Outcome, PlanContext, PlanOptions, PlanSource, PlannedInstruction, Pos, PromptError,
    Prompts, Session, Timing, Tuple, TupleFix, TupleParseError, Turn, TEMPLATE_NAMES,
};
