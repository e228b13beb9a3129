//! The language layer: instruction -> (object, ordinal, colour) tuples -> a checked Rhai plan.
//!
//! - [`prompts`]: prompt templates (files in `prompts/`, variants overlay them).
//! - [`tuples`]: step 1's answer format, parsing and normalisation.
//! - [`script`]: the code block in step 2's answer, and Python-ism fixups.
//! - [`reconcile`]: step 1's tuples against the instruction's own words.
//! - [`checks`]: agreement between the script, the tuples and the map.
//! - [`pipeline`]: [`extract_tuples`], [`plan_instruction`] (resolution against the map,
//!   deterministic plans for plain "go to X" sequences, the LLM path with a bounded repair
//!   loop).
//! - [`session`]: a chat [`Session`] with history ("go back", "the other one").

mod align;
mod checks;
mod evidence;
mod grammar;
mod pipeline;
mod prompts;
mod reconcile;
mod script;
mod session;
mod template;
mod tuples;

pub use align::{align_script, Fix};
pub use checks::{check_script, library_calls, Arg, Finding, FindingKind, LibCall, Pos};
pub use evidence::missing_evidence;
pub use grammar::tuple_grammar;
pub use pipeline::{
    extract_tuples, extract_tuples_in, extract_tuples_with, plan_instruction, scene_summary,
    LanguageError, Outcome, PlanContext, PlanOptions, PlanSource, PlannedInstruction, Timing,
};
pub use prompts::{PromptError, Prompts, TEMPLATE_NAMES};
pub use reconcile::{reconcile_tuples, Lexicon, TupleFix};
pub use script::{extract_code, pythonic_fixups};
pub use session::{Session, Turn};
pub use template::simple_goto_script;
pub use tuples::{
    normalise_colour, normalise_object, normalise_order, parse_ordinal, parse_ordinal_with_order,
    parse_tuples, same_tuples, tuples_paper_form, Tuple, TupleParseError,
};
