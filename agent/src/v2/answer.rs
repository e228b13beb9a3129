//! The one-call answer: the objects line, then `plan:` and the plan.
//!
//! ```text
//! objects: [(chair, 3, None), (sofa, None, red)]
//! plan:
//! move_to_object(get_obj("chair", #{ordinal: 3}));
//! move_to_left(get_obj("sofa", #{colour: "red"}));
//! ```
//!
//! Under the grammar ([`super::grammar`]) a local model writes exactly this; a remote
//! model may wrap the plan in a code fence or add a sentence, which is tolerated where it
//! is unambiguous and otherwise an error naming the line.

use planner_dsl::typed::{TypedError, TypedPlan};

use crate::tuples::{parse_tuples, Tuple, TupleParseError};

/// An answer read into its two parts.
#[derive(Debug, Clone, PartialEq)]
pub struct Answer {
    /// The objects line's tuples.
    pub tuples: Vec<Tuple>,
    /// The plan, typed.
    pub plan: TypedPlan,
}

/// Why an answer could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AnswerError {
    /// No line starts with `objects:`.
    #[error("the answer has no `objects:` line")]
    NoObjects,
    /// The objects line is not a tuple list.
    #[error("line {line} (objects): {source}")]
    Objects {
        /// 1-based line of the answer.
        line: usize,
        /// Why.
        source: TupleParseError,
    },
    /// No `plan:` line follows the objects.
    #[error("the answer has no `plan:` part after the objects line")]
    NoPlan,
    /// The plan is not a straight-line plan of library calls.
    #[error("in the plan (which starts on line {first_line} of the answer), {source}")]
    Plan {
        /// 1-based line of the answer where the plan's line 1 is.
        first_line: usize,
        /// Why, with the line and column within the plan.
        source: TypedError,
    },
}

/// The objects line's text (after `objects:`) and its 1-based line, if there is one.
#[must_use]
pub fn objects_part(text: &str) -> Option<(usize, &str)> {
    text.lines().enumerate().find_map(|(i, l)| {
        let l = l.trim_start();
        l.strip_prefix("objects:")
            .or_else(|| l.strip_prefix("Objects:"))
            .map(|rest| (i + 1, rest.trim()))
    })
}

/// The plan's text (the lines after `plan:`, code fences dropped) and the 1-based line of
/// the answer where it starts.
#[must_use]
pub fn plan_part(text: &str) -> Option<(usize, String)> {
    let lines: Vec<&str> = text.lines().collect();
    let at = lines.iter().position(|l| {
        let t = l.trim().to_ascii_lowercase();
        t == "plan:" || t.starts_with("plan:")
    })?;
    let mut first = at + 2;
    let mut out = Vec::new();
    // Anything after "plan:" on its own line counts as the plan's first line.
    let after = lines[at].trim().get(5..).unwrap_or("").trim();
    if !after.is_empty() {
        out.push(after);
        first = at + 1;
    }
    let mut fenced = false;
    for l in &lines[at + 1..] {
        let t = l.trim();
        if t.starts_with("```") {
            if fenced {
                break;
            }
            fenced = true;
            if out.is_empty() {
                first += 1;
            }
            continue;
        }
        out.push(l);
    }
    Some((first, out.join("\n")))
}

/// Reads an answer.
///
/// # Errors
/// [`AnswerError`] naming the part, and the line and column where it can.
///
/// ```
/// let a = agent::v2::answer::parse_answer(
///     "objects: [(chair, 3, None)]\nplan:\nmove_to_object(get_obj(\"chair\", #{ordinal: 3}));\n",
/// )
/// .unwrap();
/// assert_eq!(a.tuples[0].ordinal, Some(3));
/// assert_eq!(a.plan.steps.len(), 1);
/// ```
pub fn parse_answer(text: &str) -> Result<Answer, AnswerError> {
    let (line, objects) = objects_part(text).ok_or(AnswerError::NoObjects)?;
    let tuples = parse_tuples(objects).map_err(|source| AnswerError::Objects { line, source })?;
    let (first_line, plan) = plan_part(text).ok_or(AnswerError::NoPlan)?;
    let plan =
        TypedPlan::parse(&plan).map_err(|source| AnswerError::Plan { first_line, source })?;
    Ok(Answer { tuples, plan })
}

#[cfg(test)]
mod tests {
    use super::*;
    use planner_dsl::typed::{Object, Step};

    #[test]
    fn reads_both_parts() {
        let a = parse_answer(
            "objects: [(couch, None, red), (kitchen, None, None)]\nplan:\nmove_to_left(get_obj(\"sofa\", #{colour: \"red\"}));\nmove_to_object(\"kitchen\");\n",
        )
        .unwrap();
        assert_eq!(a.tuples.len(), 2);
        assert_eq!(a.tuples[0].object, "couch");
        assert_eq!(a.plan.steps[1], Step::GoTo(Object::Name("kitchen".into())));
    }

    #[test]
    fn a_fenced_plan_and_prose_are_tolerated() {
        let a = parse_answer(
            "Sure.\nobjects: [(chair, 2, None)]\nplan:\n```rhai\nmove_to_object(get_obj(\"chair\", #{ordinal: 2}));\n```\nDone.",
        )
        .unwrap();
        assert_eq!(a.plan.steps.len(), 1);
    }

    #[test]
    fn errors_name_the_part_and_line() {
        assert_eq!(
            parse_answer("plan:\nturn(90);"),
            Err(AnswerError::NoObjects)
        );
        assert_eq!(
            parse_answer("objects: [(chair, 2, None)]\n"),
            Err(AnswerError::NoPlan)
        );
        let e = parse_answer(
            "objects: [(chair, 2, None)]\nplan:\nturn(90);\nfor i in 0..2 { turn(1); }\n",
        )
        .unwrap_err();
        match &e {
            AnswerError::Plan { first_line, source } => {
                assert_eq!(*first_line, 3);
                assert!(
                    source.to_string().starts_with("line 2, column 1"),
                    "{source}"
                );
            }
            other => panic!("{other:?}"),
        }
        assert!(e.to_string().contains("starts on line 3"), "{e}");
        let e = parse_answer("x\nobjects: nothing\nplan:\nturn(1);").unwrap_err();
        assert!(matches!(e, AnswerError::Objects { line: 2, .. }), "{e:?}");
    }
}
