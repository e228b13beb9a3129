//! # agent: the ivlmap language layer
//!
//! Instruction -> (object, ordinal, colour) tuples -> a checked Rhai plan, and chat
//! sessions. The model is reached only through [`llm::LlmBackend`]: this crate knows
//! no backend, no command line and no evaluation.
//!
//! - [`prompts`]: prompt templates (files in `prompts/`, variants overlay them) and the
//!   worked examples.
//! - [`tuples`]: the (object, ordinal, colour) notation of the answer's objects line.
//! - [`pipeline`]: what goes in and comes out ([`PlanContext`], [`PlanOptions`],
//!   [`Outcome`]) and the entry points [`plan_instruction`] and [`extract_tuples`].
//! - [`v2`]: the one-call language layer (typed answer, grammar from the registry and
//!   the map, worked examples, checks that re-ask and ask, never rewrite).
//! - [`session`]: a chat [`Session`]: what was visited reaches the model as named
//!   references.
//!
//! ```
//! // The paper's tuple form and JSON both parse; ordinals and colours are normalised.
//! let t = agent::tuples::parse_tuples("[(tables, third, Yellow), (sofa, last, none)]").unwrap();
//! assert_eq!((t[0].object.as_str(), t[0].ordinal, t[0].colour.as_deref()), ("table", Some(3), Some("yellow")));
//! assert_eq!((t[1].ordinal, t[1].colour.as_deref()), (Some(-1), None));
//! ```

#![warn(missing_docs)]

pub mod pipeline;
pub mod prompts;
pub mod session;
pub mod tuples;
pub mod v2;
mod words;

pub use pipeline::{
    extract_tuples, plan_instruction, LanguageError, Outcome, PlanContext, PlanOptions, PlanSource,
    PlannedInstruction, Timing,
};
pub use prompts::{PromptError, Prompts};
pub use session::{Session, Turn};
pub use tuples::Tuple;
