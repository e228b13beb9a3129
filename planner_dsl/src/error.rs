//! Errors with script positions (1-based line and column), written for a person or
//! the repair loop to act on.

use serde::{Deserialize, Serialize};
use std::fmt;

/// A place in the script: 1-based line and column. Both are 0 when Rhai knows no
/// position (e.g. an error raised outside any statement).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct Span {
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub col: usize,
}

impl Span {
    /// The span of a Rhai position (0, 0 when it has none).
    #[must_use]
    pub fn from_position(pos: rhai::Position) -> Span {
        Span {
            line: pos.line().unwrap_or(0),
            col: pos.position().unwrap_or(0),
        }
    }

    /// Whether the position is known.
    pub fn is_known(&self) -> bool {
        self.line > 0
    }
}

impl fmt::Display for Span {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_known() {
            write!(f, "line {}, column {}", self.line, self.col)
        } else {
            f.write_str("unknown position")
        }
    }
}

/// What is wrong with one call or construct found by the validator.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, thiserror::Error)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ViolationKind {
    /// A function that is neither in the library, the allowed builtins, nor defined
    /// in the script.
    #[error("unknown function `{name}`{}", hint.as_ref().map(|h| format!(" ({h})")).unwrap_or_default())]
    UnknownFunction {
        /// Name as written.
        name: String,
        /// A suggestion (closest library name) or the reason it is missing.
        hint: Option<String>,
    },
    /// A function that is deliberately unavailable (eval, Fn, sleep, print...).
    #[error("`{name}` is not allowed: {reason}")]
    Forbidden {
        /// Name as written.
        name: String,
        /// Why, and what to use instead.
        reason: String,
    },
    /// A library function called with the wrong number of arguments.
    #[error("`{name}` takes {expected}, got {got}: {signature}")]
    WrongArity {
        /// Function name.
        name: String,
        /// Accepted arity in words ("1 to 4 arguments").
        expected: String,
        /// Number of arguments given.
        got: usize,
        /// The function's signature.
        signature: String,
    },
    /// A method call on something other than `agent` that is not an allowed builtin
    /// method, or a library function called on a value instead of `agent`.
    #[error("method `.{name}()` is not allowed here{}", hint.as_ref().map(|h| format!(" ({h})")).unwrap_or_default())]
    BadMethod {
        /// Method name.
        name: String,
        /// What to do instead.
        hint: Option<String>,
    },
    /// Closures and anonymous functions (`|x| ...`).
    #[error("anonymous functions (closures) are not allowed; define a named `fn` instead")]
    Closure,
    /// Assignment to an indexed element (`a[i] = v`, `m[k] = v`): Rhai does not
    /// check the size of the container there, so a loop could grow a map without
    /// bound.
    #[error("assigning to `x[...]` is not allowed; build arrays with push() and maps with `#{{...}}` or `m.key = value`")]
    IndexAssignment,
    /// A script function that redefines a library function or `agent`.
    #[error("`{name}` is reserved: {reason}")]
    Reserved {
        /// The name.
        name: String,
        /// Why.
        reason: String,
    },
}

/// One validator finding, at a place in the script.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, thiserror::Error)]
#[error("{span}: {kind}")]
pub struct Violation {
    /// Where.
    pub span: Span,
    /// What.
    pub kind: ViolationKind,
}

/// Why a script could not become a [`crate::Plan`]. Nothing ran; the robot did not
/// move.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, thiserror::Error)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PlanError {
    /// The script is not valid Rhai (or breaks a parse-time limit such as expression
    /// depth, or uses a disabled keyword).
    #[error("syntax error at {span}: {message}")]
    Syntax {
        /// Where.
        span: Span,
        /// Rhai's message.
        message: String,
    },
    /// The script is longer than [`crate::Limits::max_source_bytes`].
    #[error("the script is {bytes} bytes long; plans may be at most {limit} bytes")]
    TooLong {
        /// Script length.
        bytes: usize,
        /// The limit.
        limit: usize,
    },
    /// The script parses but calls things it may not; every violation is listed.
    #[error("plan rejected ({} problem{}):\n{}", violations.len(), if violations.len() == 1 { "" } else { "s" }, list(violations))]
    Rejected {
        /// All violations, in source order.
        violations: Vec<Violation>,
    },
}

fn list(v: &[Violation]) -> String {
    v.iter()
        .map(|x| format!("  {x}"))
        .collect::<Vec<_>>()
        .join("\n")
}

impl PlanError {
    /// All positions the error points at (one for a syntax error).
    pub fn spans(&self) -> Vec<Span> {
        match self {
            PlanError::Syntax { span, .. } => vec![*span],
            PlanError::TooLong { .. } => vec![Span { line: 1, col: 1 }],
            PlanError::Rejected { violations } => violations.iter().map(|v| v.span).collect(),
        }
    }
}

/// The class of a runtime failure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RuntimeErrorKind {
    /// A library call was given a bad argument (type, NaN, absurd value, wrong count).
    Argument,
    /// The map or robot refused: unknown object, ordinal past the count, no path...
    Map,
    /// The operation budget ran out (e.g. an endless loop).
    TooManyOperations,
    /// The script's wall-clock budget ran out.
    Deadline,
    /// Recursion went deeper than the call-level limit.
    CallDepth,
    /// A string, array or map grew past its limit.
    DataTooLarge,
    /// Too many variables alive at once.
    TooManyVariables,
    /// Too many robot function library calls.
    TooManyCalls,
    /// Any other script error (undefined variable, type mismatch, `throw`...).
    Script,
    /// The engine itself failed (a bug: please report it).
    Internal,
}

/// A failure while running: the plan stopped at `span`; the trace and trajectory up
/// to that point are kept.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, thiserror::Error)]
#[error("{span}: {}{message}", function.as_ref().map(|f| format!("{f}: ")).unwrap_or_default())]
pub struct RuntimeError {
    /// Where the plan stopped (the innermost call).
    pub span: Span,
    /// The library function that failed, if the failure was in one.
    pub function: Option<String>,
    /// The class of failure.
    pub kind: RuntimeErrorKind,
    /// The message (the map's own message for map failures).
    pub message: String,
}
