//! A compiled and validated plan.

use crate::engine;
use crate::error::{PlanError, Span};
use crate::limits::Limits;
use crate::registry::FORBIDDEN;
use crate::validate::{validate, CallSite};
use rhai::AST;

/// A script that compiled and passed validation: it calls only the robot function
/// library, `say`, the allowed builtins and functions it defines itself. Compile
/// once, run many times.
#[derive(Debug, Clone)]
pub struct Plan {
    source: String,
    ast: AST,
    calls: Vec<CallSite>,
}

impl Plan {
    /// Compiles and validates `source` under the default [`Limits`].
    ///
    /// ```
    /// use planner_dsl::{Plan, PlanError};
    /// let plan = Plan::compile("let t = agent.get_obj_attributes(\"table\", 3, \"yellow\");\nagent.face(t);")?;
    /// assert_eq!(plan.library_calls().len(), 2);
    /// let err = Plan::compile("agent.fly(1);\nsleep(5);").unwrap_err();
    /// assert_eq!(err.spans().len(), 2); // every violation, each with line and column
    /// # Ok::<(), PlanError>(())
    /// ```
    pub fn compile(source: &str) -> Result<Plan, PlanError> {
        Self::compile_in(engine::default_compiler(), &Limits::default(), source)
    }

    /// Compiles and validates `source` under `limits` (parse-time limits such as
    /// expression depth and the number of script functions apply here).
    pub fn compile_with(source: &str, limits: &Limits) -> Result<Plan, PlanError> {
        Self::compile_in(&engine::sandbox(limits), limits, source)
    }

    fn compile_in(engine: &rhai::Engine, limits: &Limits, source: &str) -> Result<Plan, PlanError> {
        if source.len() > limits.max_source_bytes {
            return Err(PlanError::TooLong {
                bytes: source.len(),
                limit: limits.max_source_bytes,
            });
        }
        let ast = engine
            .compile_with_scope(&engine::compile_scope(), source)
            .map_err(|e| {
                let mut message = e.err_type().to_string();
                if let rhai::ParseErrorType::Reserved(word) = e.err_type() {
                    if let Some((_, why)) = FORBIDDEN.iter().find(|(n, _)| n == word) {
                        message = format!("{message}: {why}");
                    }
                }
                let span = Span::from_position(e.position());
                let line = source
                    .lines()
                    .nth(span.line.saturating_sub(1))
                    .unwrap_or("");
                if let Some(hint) = python_hint(&message, line) {
                    message = format!("{message}; {hint}");
                }
                PlanError::Syntax { span, message }
            })?;
        let calls =
            validate(source, &ast).map_err(|violations| PlanError::Rejected { violations })?;
        Ok(Plan {
            source: source.to_string(),
            ast,
            calls,
        })
    }

    /// The script text.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Every library call written in the script, in source order.
    pub fn library_calls(&self) -> &[CallSite] {
        &self.calls
    }

    pub(crate) fn ast(&self) -> &AST {
        &self.ast
    }
}

/// A hint for common Python habits in LLM-written scripts, from the parse error and
/// the offending line.
fn python_hint(message: &str, line: &str) -> Option<&'static str> {
    let line = line.trim_end();
    if message.starts_with("Invalid character: '") {
        Some("strings use double quotes in Rhai: \"table\"")
    } else if message.contains("Expecting '{'") && (line.ends_with(':') || line.contains(" range("))
    {
        Some("Rhai blocks use braces, not ':' and indentation: `for i in 0..8 { agent.turn(90); }`")
    } else if message.contains("Expecting ';'") {
        Some("end each statement with ';' (one call per statement)")
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn syntax(src: &str) -> (Span, String) {
        match Plan::compile(src) {
            Err(PlanError::Syntax { span, message }) => (span, message),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn python_habits_get_hints() {
        let (span, m) = syntax("agent.get_obj_attributes('table', 3, 'yellow')");
        assert_eq!(span, Span { line: 1, col: 26 });
        assert!(
            m.ends_with("strings use double quotes in Rhai: \"table\""),
            "{m}"
        );
        let (span, m) = syntax("let x = 1;\nfor i in range(8):\n    agent.turn(90)");
        assert_eq!(span.line, 2);
        assert!(m.contains("for i in 0..8 {"), "{m}");
        let (_, m) = syntax("let obj_attr = 1;\nagent.face(obj_attr), agent.turn(-90)");
        assert!(m.contains("end each statement with ';'"), "{m}");
    }
}
