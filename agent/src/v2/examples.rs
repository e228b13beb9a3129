//! Worked examples: instruction -> answer pairs kept as a file in `prompts/`
//! (`worked_examples.txt`), and the few most similar to an instruction.
//!
//! The file is a list of blocks: a line `> instruction`, optionally a line `~ history`
//! (the conversation so far, as [`crate::Session::references`] writes it), then the
//! answer's lines (the objects line, `plan:`, the plan). `#` lines outside a block are
//! comments. Similarity
//! is the cosine of text embeddings (the MiniLM encoder, given by the caller through
//! [`Embedder`], so that this crate does not link ONNX Runtime); without an embedder it
//! is the cosine of word and character-trigram counts, which is what tests and a machine
//! without the MiniLM files get.

use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;

/// One worked example.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WorkedExample {
    /// What the person says.
    pub instruction: String,
    /// What the conversation so far holds (a `~ ` line under the instruction), for
    /// examples of chat references.
    pub history: Option<String>,
    /// The answer, as the model should write it.
    pub answer: String,
    /// 1-based line of the `>` line in its file.
    pub line: usize,
}

/// A malformed examples file.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{origin}, line {line}: {message}")]
pub struct ExamplesError {
    /// The file (or "built-in ...").
    pub origin: String,
    /// 1-based line.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

/// Reads an examples file (see the module docs).
///
/// # Errors
/// [`ExamplesError`] naming the line: answer text before any `>` line, or an instruction
/// with no answer.
pub fn parse_examples(text: &str, origin: &str) -> Result<Vec<WorkedExample>, ExamplesError> {
    let mut out: Vec<WorkedExample> = Vec::new();
    let err = |line: usize, message: &str| ExamplesError {
        origin: origin.to_string(),
        line,
        message: message.to_string(),
    };
    let mut current: Option<(usize, String, Option<String>, Vec<&str>)> = None;
    let finish = |c: Option<(usize, String, Option<String>, Vec<&str>)>,
                  out: &mut Vec<WorkedExample>|
     -> Result<(), ExamplesError> {
        if let Some((line, instruction, history, answer)) = c {
            let answer = answer.join("\n").trim().to_string();
            if answer.is_empty() {
                return Err(err(line, "an instruction with no answer after it"));
            }
            out.push(WorkedExample {
                instruction,
                history,
                answer,
                line,
            });
        }
        Ok(())
    };
    for (i, l) in text.lines().enumerate() {
        if let Some(instr) = l.strip_prefix("> ") {
            finish(current.take(), &mut out)?;
            current = Some((i + 1, instr.trim().to_string(), None, Vec::new()));
        } else if let Some((_, _, history, answer)) = current.as_mut() {
            if l.trim().is_empty() {
                continue;
            }
            match l.strip_prefix("~ ") {
                Some(h) if answer.is_empty() && history.is_none() => {
                    *history = Some(h.trim().to_string());
                }
                _ => answer.push(l),
            }
        } else if !(l.trim().is_empty() || l.starts_with('#')) {
            return Err(err(i + 1, "text before the first `> instruction` line"));
        }
    }
    finish(current, &mut out)?;
    Ok(out)
}

/// Why an embedder failed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("text embedding failed: {0}")]
pub struct EmbedFailure(pub String);

/// Something that turns texts into vectors (the MiniLM encoder in the binary).
pub trait Embedder: Send + Sync {
    /// One vector per text, all of one length.
    ///
    /// # Errors
    /// [`EmbedFailure`] with the encoder's message.
    fn embed(&self, texts: &[&str]) -> Result<Vec<Vec<f32>>, EmbedFailure>;
    /// A short name for logs ("all-MiniLM-L6-v2").
    fn name(&self) -> &str;
}

/// Examples with their vectors, ready to rank.
pub struct ExampleIndex {
    examples: Vec<WorkedExample>,
    vectors: Vec<Vec<f32>>,
    /// Word and trigram counts of each example's instruction (the fallback ranking),
    /// computed once.
    lexical: Vec<HashMap<String, f32>>,
    embedder: Option<Arc<dyn Embedder>>,
}

impl fmt::Debug for ExampleIndex {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ExampleIndex")
            .field("examples", &self.examples.len())
            .field("embedder", &self.embedder_name())
            .finish()
    }
}

/// Word and character-trigram counts of a text, as a sparse vector (lexical fallback).
fn lexical(text: &str) -> HashMap<String, f32> {
    let mut v = HashMap::new();
    let lower = text.to_lowercase();
    for w in crate::words::words(&lower) {
        let padded: Vec<char> = format!(" {w} ").chars().collect();
        for t in padded.windows(3) {
            *v.entry(t.iter().collect::<String>()).or_insert(0.0) += 0.5;
        }
        *v.entry(w).or_insert(0.0) += 1.0;
    }
    v
}

fn cosine_sparse(a: &HashMap<String, f32>, b: &HashMap<String, f32>) -> f32 {
    let dot: f32 = a.iter().filter_map(|(k, x)| b.get(k).map(|y| x * y)).sum();
    let n = |m: &HashMap<String, f32>| m.values().map(|x| x * x).sum::<f32>().sqrt();
    let d = n(a) * n(b);
    if d > 0.0 {
        dot / d
    } else {
        0.0
    }
}

fn cosine(a: &[f32], b: &[f32]) -> f32 {
    let dot: f32 = a.iter().zip(b).map(|(x, y)| x * y).sum();
    let n = |v: &[f32]| v.iter().map(|x| x * x).sum::<f32>().sqrt();
    let d = n(a) * n(b);
    if d > 0.0 {
        dot / d
    } else {
        0.0
    }
}

impl ExampleIndex {
    /// Ranks by word and trigram overlap (no embedder).
    #[must_use]
    pub fn lexical(examples: Vec<WorkedExample>) -> Self {
        Self {
            lexical: examples.iter().map(|e| lexical(&e.instruction)).collect(),
            examples,
            vectors: Vec::new(),
            embedder: None,
        }
    }

    /// Embeds every example's instruction once with `embedder`.
    ///
    /// # Errors
    /// [`EmbedFailure`] when the embedder fails or returns the wrong number of vectors.
    pub fn embedded(
        examples: Vec<WorkedExample>,
        embedder: Arc<dyn Embedder>,
    ) -> Result<Self, EmbedFailure> {
        let texts: Vec<&str> = examples.iter().map(|e| e.instruction.as_str()).collect();
        let vectors = if texts.is_empty() {
            Vec::new()
        } else {
            embedder.embed(&texts)?
        };
        if vectors.len() != examples.len() {
            return Err(EmbedFailure(format!(
                "{} vectors for {} examples",
                vectors.len(),
                examples.len()
            )));
        }
        Ok(Self {
            lexical: examples.iter().map(|e| lexical(&e.instruction)).collect(),
            examples,
            vectors,
            embedder: Some(embedder),
        })
    }

    /// The embedder's name, or "lexical".
    #[must_use]
    pub fn embedder_name(&self) -> &str {
        self.embedder.as_ref().map_or("lexical", |e| e.name())
    }

    /// Every example, in file order.
    #[must_use]
    pub fn examples(&self) -> &[WorkedExample] {
        &self.examples
    }

    /// The `k` examples most similar to `instruction`, least similar first (so that the
    /// most similar stands right before the instruction). An embedder failure falls back
    /// to the lexical ranking for this call (logged).
    #[must_use]
    pub fn nearest(&self, instruction: &str, k: usize) -> Vec<&WorkedExample> {
        let scores: Vec<f32> = match &self.embedder {
            Some(e) => match e.embed(&[instruction]) {
                Ok(v) if v.len() == 1 => self.vectors.iter().map(|x| cosine(x, &v[0])).collect(),
                Ok(_) | Err(_) => {
                    tracing::warn!("example retrieval: the embedder failed; ranking by words");
                    self.lexical_scores(instruction)
                }
            },
            None => self.lexical_scores(instruction),
        };
        let mut idx: Vec<usize> = (0..self.examples.len()).collect();
        idx.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]).then(a.cmp(&b)));
        idx.truncate(k);
        idx.reverse();
        idx.into_iter().map(|i| &self.examples[i]).collect()
    }

    fn lexical_scores(&self, instruction: &str) -> Vec<f32> {
        let q = lexical(instruction);
        self.lexical.iter().map(|e| cosine_sparse(&q, e)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::v2::answer::parse_answer;

    fn builtin() -> Vec<WorkedExample> {
        let p = crate::Prompts::builtin();
        let (text, origin) = p.worked_examples();
        parse_examples(text, origin).unwrap()
    }

    #[test]
    fn every_builtin_example_is_a_typed_plan_that_compiles() {
        let ex = builtin();
        assert!(ex.len() >= 25, "{}", ex.len());
        for e in &ex {
            let a = parse_answer(&e.answer)
                .unwrap_or_else(|err| panic!("example at line {}: {err}", e.line));
            // An empty objects line only where the plan picks no object ("go back to
            // where we started").
            let picks = a
                .plan
                .steps
                .iter()
                .any(|s| !s.targets().is_empty() || !s.objects().is_empty());
            assert!(!a.tuples.is_empty() || !picks, "line {}", e.line);
            // No example teaches a colour its instruction does not say.
            let known = crate::words::words(e.history.as_deref().unwrap_or_default());
            let unsaid = super::super::check::unsaid_colours(&e.instruction, &known, &a.plan);
            assert!(unsaid.is_empty(), "line {}: {unsaid:?}", e.line);
            let unsaid = super::super::check::unsaid_directions(&e.instruction, &a.plan);
            assert!(unsaid.is_empty(), "line {}: {unsaid:?}", e.line);
            let unsaid = super::super::check::unsaid_sizes(&e.instruction, None, &a.plan);
            assert!(unsaid.is_empty(), "line {}: {unsaid:?}", e.line);
            let unsaid = super::super::check::unsaid_far_ends(&e.instruction, &a.plan);
            assert!(unsaid.is_empty(), "line {}: {unsaid:?}", e.line);
            let in_chat = e.history.is_some();
            let unsaid = super::super::check::unsaid_ordinals(&e.instruction, &a.plan);
            assert!(unsaid.is_empty(), "line {}: {unsaid:?}", e.line);
            let unsaid = super::super::check::unsaid_regions(&e.instruction, &[], in_chat, &a.plan);
            assert!(unsaid.is_empty(), "line {}: {unsaid:?}", e.line);
            let unsaid =
                super::super::check::unsaid_exclusions(&e.instruction, &[], in_chat, &a.plan);
            assert!(unsaid.is_empty(), "line {}: {unsaid:?}", e.line);
            // A direction or a count says only of the objects of its clause; with no
            // map, a name is the last word of a name the plan picks.
            let single = |n: &str| map_core::matcher::singular(&map_core::matcher::normalise(n));
            let last = |n: &str| n.split(' ').next_back().map(single);
            let picked: Vec<String> = a
                .plan
                .steps
                .iter()
                .flat_map(|s| s.targets())
                .filter_map(|t| last(&t.name))
                .collect();
            let name_at = |w: &[String], j: usize| {
                let n = single(&w[j]);
                picked.contains(&n).then_some((n, 1))
            };
            for what in [
                super::super::check::SaidOf::Direction,
                super::super::check::SaidOf::Count,
            ] {
                let said = super::super::check::said_of(&e.instruction, what, name_at);
                let elsewhere =
                    super::super::check::said_of_others(said.as_deref(), what, &a.plan, last);
                assert!(elsewhere.is_empty(), "line {}: {elsewhere:?}", e.line);
            }
            // A pick counts only in the orders the words count in, and is picked near
            // only an object named with it ([`check::directions_said`],
            // [`check::anchors_said`]).
            let targets: Vec<_> = a.plan.steps.iter().flat_map(|s| s.targets()).collect();
            if let Some(orders) = super::super::check::directions_said(&e.instruction) {
                for t in &targets {
                    assert!(
                        !t.order.is_directional() || orders.contains(&t.order),
                        "line {}: {:?} not in {orders:?}",
                        e.line,
                        t.order
                    );
                }
            }
            let anchored: Vec<String> = targets
                .iter()
                .filter_map(|t| match t.near.as_deref() {
                    Some(planner_dsl::typed::Object::Pick(n)) => last(&n.name),
                    _ => None,
                })
                .collect();
            let named_at = |w: &[String], j: usize| {
                let n = single(&w[j]);
                (picked.contains(&n) || anchored.contains(&n)).then_some((n, 1))
            };
            if e.history.is_none() {
                let said = super::super::check::anchors_said_by(&e.instruction, named_at);
                for t in &targets {
                    let Some(planner_dsl::typed::Object::Pick(n)) = t.near.as_deref() else {
                        continue;
                    };
                    let (label, anchor) = (last(&t.name), last(&n.name));
                    assert!(
                        said.iter().any(|(l, a)| Some(l) == label.as_ref()
                            && anchor.as_ref().is_some_and(|x| a.contains(x))),
                        "line {}: {label:?} near {anchor:?}, said {said:?}",
                        e.line
                    );
                }
            }
            let from_end = super::super::check::counted_from_the_end(&a.plan);
            assert!(from_end.is_empty(), "line {}: {from_end:?}", e.line);
            // An example asked to come back moves back (the grammar then requires it).
            if super::super::check::return_said(&e.instruction) {
                assert!(
                    super::super::check::plan_returns(&a.plan),
                    "line {}",
                    e.line
                );
            }
            planner_dsl::Plan::compile(&a.plan.to_rhai())
                .unwrap_or_else(|err| panic!("example at line {}: {err}", e.line));
        }
    }

    #[test]
    fn malformed_files_name_the_line() {
        let e = parse_examples("# c\nobjects: []\n", "f.txt").unwrap_err();
        assert_eq!((e.line, e.origin.as_str()), (2, "f.txt"));
        let e = parse_examples("> go\n\n> again\nobjects: []\n", "f.txt").unwrap_err();
        assert_eq!(e.line, 1);
        assert!(e.to_string().contains("no answer"), "{e}");
    }

    #[test]
    fn lexical_ranking_puts_the_closest_last() {
        let idx = ExampleIndex::lexical(builtin());
        let got = idx.nearest("go to the penultimate chair", 3);
        assert_eq!(got.len(), 3);
        assert!(got[2].instruction.contains("penultimate"), "{got:?}");
    }

    struct Fixed;
    impl Embedder for Fixed {
        fn embed(&self, texts: &[&str]) -> Result<Vec<Vec<f32>>, EmbedFailure> {
            // A toy geometry: the vector says whether the text mentions "between".
            Ok(texts
                .iter()
                .map(|t| vec![f32::from(u8::from(t.contains("between"))), 1.0])
                .collect())
        }
        fn name(&self) -> &str {
            "fixed"
        }
    }

    #[test]
    fn an_embedder_ranks_by_cosine() {
        let idx = ExampleIndex::embedded(builtin(), Arc::new(Fixed)).unwrap();
        assert_eq!(idx.embedder_name(), "fixed");
        let got = idx.nearest("stop between them", 2);
        assert!(
            got.iter().all(|e| e.instruction.contains("between")),
            "{got:?}"
        );
    }
}
