//! # agent: the ivlmap language layer (work in progress)
//!
//! LLM backends: [`LlmBackend`] with [`LlamaCppBackend`] (local GGUF via llama.cpp),
//! [`OpenAiBackend`] (any OpenAI-compatible server) and [`ReplayBackend`] / [`Recording`]
//! (cassettes).

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
pub use eval::{
    load_extract_suite, load_nav_suite, nav_scores, percentile, reached, run_extract, run_nav,
    run_task, satisfies, summarise, summary_table, vlmap_script, CaseResult, ExtractCase, Method,
    NavScores, NavTask, Report, Subgoal, SuiteError, SuiteKind, Summary, SUCCESS_RADIUS_M,
};
pub use language::{
    check_script, extract_code, extract_tuples, library_calls, normalise_colour, normalise_object,
    parse_ordinal, parse_tuples, plan_instruction, pythonic_fixups, same_tuples, scene_summary,
    simple_goto_script, tuples_paper_form, Arg, Finding, FindingKind, LanguageError, LibCall,
    Outcome, PlanContext, PlanOptions, PlanSource, PlannedInstruction, Pos, PromptError, Prompts,
    Session, Timing, Tuple, TupleParseError, Turn, TEMPLATE_NAMES,
};
