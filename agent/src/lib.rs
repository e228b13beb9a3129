//! # agent: the ivlmap language layer
//!
//! Instruction -> (object, ordinal, colour) tuples -> a checked Rhai plan, and chat
//! sessions. The model is reached only through [`llm::LlmBackend`]: this crate knows
//! no backend, no command line and no evaluation.
//!
//! - [`prompts`]: prompt templates (files in `prompts/`, variants overlay them).
//! - [`tuples`]: step 1's answer format, parsing and normalisation.
//! - [`script`]: the code block in step 2's answer, and Python-ism fixups.
//! - [`reconcile`]: step 1's tuples against the instruction's own words.
//! - [`evidence`]: ordinal, colour and counting words the tuples must account for.
//! - [`checks`]: agreement between the script, the tuples and the map.
//! - [`align`] and [`template`]: script alignment and plans for plain clauses.
//! - [`grammar`]: the GBNF grammar of step 1's answer.
//! - [`pipeline`]: [`extract_tuples`], [`plan_instruction`] (resolution against the map,
//!   deterministic plans for plain "go to X" sequences, the LLM path with a bounded repair
//!   loop).
//! - [`v2`]: the one-call language layer (typed answer, grammar from the registry and
//!   the map, retrieved worked examples, checks that re-ask and ask, never rewrite).
//! - [`session`]: a chat [`Session`] with history ("go back", "the other one").
//!
//! ```
//! // The paper's tuple form and JSON both parse; ordinals and colours are normalised.
//! let t = agent::tuples::parse_tuples("[(tables, third, Yellow), (sofa, last, none)]").unwrap();
//! assert_eq!((t[0].object.as_str(), t[0].ordinal, t[0].colour.as_deref()), ("table", Some(3), Some("yellow")));
//! assert_eq!((t[1].ordinal, t[1].colour.as_deref()), (Some(-1), None));
//! ```

#![warn(missing_docs)]

pub mod align;
pub mod checks;
pub mod evidence;
pub mod grammar;
pub mod pipeline;
pub mod prompts;
pub mod reconcile;
pub mod script;
pub mod session;
pub mod template;
pub mod tuples;
pub mod v2;
mod words;

pub use pipeline::{
    extract_tuples, plan_instruction, LanguageError, Outcome, Pipeline, PlanContext, PlanOptions,
    PlanSource, PlannedInstruction, Timing,
};
pub use prompts::{PromptError, Prompts};
pub use session::{Session, Turn};
pub use tuples::Tuple;
