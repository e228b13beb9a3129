//! Prompt templates: plain files rendered with minijinja.
//!
//! The default set lives in the repository's `prompts/` folder and is also compiled into
//! the binary ([`Prompts::builtin`]). A variant is a folder holding some of the same files:
//! [`Prompts::load`] starts from the built-in set and overlays the folder's files, so a
//! variant only contains what it changes. [`Prompts::load_variant`] overlays a variant onto
//! a default folder on disk.
//!
//! Templates and what they receive:
//! - `v2_system.md.j2`: the system message: `functions` (the typed plan's step functions
//!   and `get_obj`, generated from planner_dsl's registry, never copied by hand).
//! - `v2_request.md.j2`: the user message (also for each worked example): `instruction`,
//!   `history` (the session's named references), `scene` (the map's summary, when it is
//!   not in the system message).
//! - `v2_reask.md.j2`: the one re-ask, appended to the request: `findings`.
//! - `worked_examples.txt` (not a template): instruction -> answer pairs.
//!
//! The system message and the worked examples are identical for every instruction and
//! every map, so a backend with prefix caching reuses them; everything that varies (the
//! scene, the history, the instruction) is in the final user message.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use minijinja::value::Serde;
use minijinja::{Environment, UndefinedBehavior, Value};

use llm::ChatMessage;

/// The template files every prompt set has.
pub const TEMPLATE_NAMES: &[&str] = &["v2_system.md.j2", "v2_request.md.j2", "v2_reask.md.j2"];

/// The worked examples of the one-call answer (not a template: `> instruction` lines each
/// followed by its answer; see [`crate::v2::examples`]). A variant folder may hold its own.
pub const WORKED_EXAMPLES: &str = "worked_examples.txt";

const BUILTIN: &[(&str, &str)] = &[
    (
        "v2_system.md.j2",
        include_str!("../../prompts/v2_system.md.j2"),
    ),
    (
        "v2_request.md.j2",
        include_str!("../../prompts/v2_request.md.j2"),
    ),
    (
        "v2_reask.md.j2",
        include_str!("../../prompts/v2_reask.md.j2"),
    ),
    (
        WORKED_EXAMPLES,
        include_str!("../../prompts/worked_examples.txt"),
    ),
];

/// A prompt file that could not be read or rendered.
#[derive(Debug, thiserror::Error)]
pub enum PromptError {
    /// The worked examples file is malformed.
    #[error(transparent)]
    Examples(#[from] crate::v2::examples::ExamplesError),
    /// The embedder given for example retrieval failed.
    #[error(transparent)]
    Embed(#[from] crate::v2::examples::EmbedFailure),
    /// A folder or file could not be read.
    #[error("prompt folder {}: {message}", path.display())]
    Io {
        /// The folder or file.
        path: PathBuf,
        /// What failed.
        message: String,
    },
    /// A file is not one of the known templates (likely a typo in its name).
    #[error("{}: not a prompt template name; expected one of {}", path.display(), TEMPLATE_NAMES.join(", "))]
    UnknownFile {
        /// The file.
        path: PathBuf,
    },
    /// A template failed to parse or render.
    #[error("prompt template {origin}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Template {
        /// Where the template came from (a file path or "built-in name").
        origin: String,
        /// The line in the template, when minijinja knows it.
        line: Option<usize>,
        /// minijinja's message.
        message: String,
    },
}

/// A set of prompt templates (the built-in defaults, possibly overlaid by folders).
#[derive(Debug, Clone)]
pub struct Prompts {
    templates: BTreeMap<String, (String, String)>,
    label: String,
    /// The worked examples ranked by an embedder, when one was given.
    index: Option<std::sync::Arc<crate::v2::examples::ExampleIndex>>,
}

impl Default for Prompts {
    fn default() -> Self {
        Self::builtin()
    }
}

/// One function of the library as templates see it.
impl Prompts {
    /// The default templates compiled into the crate (the repository's `prompts/`).
    #[must_use]
    pub fn builtin() -> Self {
        let templates = BUILTIN
            .iter()
            .map(|(n, s)| {
                (
                    (*n).to_string(),
                    ((*s).to_string(), format!("built-in {n}")),
                )
            })
            .collect();
        Self {
            templates,
            label: "builtin".into(),
            index: None,
        }
    }

    /// The built-in set overlaid with the template files in `dir` (a full prompt folder or
    /// a variant holding only some files).
    ///
    /// # Errors
    /// [`PromptError`] when the folder cannot be read, holds a `.j2` file with an unknown
    /// name, or a template does not parse.
    pub fn load(dir: impl AsRef<Path>) -> Result<Self, PromptError> {
        Self::builtin().overlay(dir)
    }

    /// `default_dir`'s templates (over the built-in set), then `variant_dir`'s on top.
    ///
    /// # Errors
    /// As [`Prompts::load`], for either folder.
    pub fn load_variant(
        default_dir: impl AsRef<Path>,
        variant_dir: impl AsRef<Path>,
    ) -> Result<Self, PromptError> {
        Self::load(default_dir)?.overlay(variant_dir)
    }

    /// This set with the template files of `dir` replacing those of the same name.
    ///
    /// # Errors
    /// As [`Prompts::load`].
    pub fn overlay(mut self, dir: impl AsRef<Path>) -> Result<Self, PromptError> {
        let dir = dir.as_ref();
        let io = |path: &Path, e: std::io::Error| PromptError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
            .map_err(|e| io(dir, e))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.extension().is_some_and(|x| x == "j2")
                    || p.file_name().is_some_and(|n| n == WORKED_EXAMPLES)
            })
            .collect();
        entries.sort();
        for path in entries {
            let name = path
                .file_name()
                .map(|n| n.to_string_lossy().to_string())
                .unwrap_or_default();
            if !TEMPLATE_NAMES.contains(&name.as_str()) && name != WORKED_EXAMPLES {
                return Err(PromptError::UnknownFile { path });
            }
            let text = std::fs::read_to_string(&path).map_err(|e| io(&path, e))?;
            self.templates
                .insert(name, (text, path.display().to_string()));
        }
        self.label = dir.display().to_string();
        self.index = None;
        self.check()?;
        Ok(self)
    }

    /// A short description of where the set came from ("builtin" or the last folder).
    #[must_use]
    pub fn label(&self) -> &str {
        &self.label
    }

    /// The source text of a template.
    #[must_use]
    pub fn source(&self, name: &str) -> Option<&str> {
        self.templates.get(name).map(|(s, _)| s.as_str())
    }

    /// Where a template came from (a file path, or "built-in NAME").
    #[must_use]
    pub fn origin(&self, name: &str) -> Option<&str> {
        self.templates.get(name).map(|(_, o)| o.as_str())
    }

    /// Parses every template (so that a broken variant fails at load time).
    fn check(&self) -> Result<(), PromptError> {
        for name in self.templates.keys().filter(|n| *n != WORKED_EXAMPLES) {
            self.env(name)?;
        }
        self.worked_example_list()?;
        Ok(())
    }

    fn template_error(&self, name: &str, e: &minijinja::Error) -> PromptError {
        let mut message = e.to_string();
        let mut src = std::error::Error::source(e);
        while let Some(s) = src {
            message.push_str(&format!(": {s}"));
            src = s.source();
        }
        PromptError::Template {
            origin: self.origin(name).unwrap_or(name).to_string(),
            line: e.line(),
            message,
        }
    }

    fn env(&self, name: &str) -> Result<Environment<'static>, PromptError> {
        let mut env = Environment::new();
        env.set_undefined_behavior(UndefinedBehavior::SemiStrict);
        let (src, _) = self
            .templates
            .get(name)
            .ok_or_else(|| PromptError::Template {
                origin: name.to_string(),
                line: None,
                message: "no such template".into(),
            })?;
        env.add_template_owned(name.to_string(), src.clone())
            .map_err(|e| self.template_error(name, &e))?;
        Ok(env)
    }

    /// Renders one template with `ctx` (a minijinja value, e.g. from `minijinja::context!`).
    /// Trailing whitespace is trimmed.
    ///
    /// # Errors
    /// [`PromptError::Template`] with the template's origin and line.
    pub fn render(&self, name: &str, ctx: Value) -> Result<String, PromptError> {
        let env = self.env(name)?;
        let tmpl = env
            .get_template(name)
            .map_err(|e| self.template_error(name, &e))?;
        let out = tmpl
            .render(ctx)
            .map_err(|e| self.template_error(name, &e))?;
        Ok(out.trim_end().to_string())
    }

    /// The worked examples, read.
    ///
    /// # Errors
    /// [`PromptError::Examples`] naming the file and line.
    pub fn worked_example_list(
        &self,
    ) -> Result<Vec<crate::v2::examples::WorkedExample>, PromptError> {
        let (text, origin) = self.worked_examples();
        Ok(crate::v2::examples::parse_examples(text, origin)?)
    }

    /// This set with its worked examples ranked by `embedder` (embedded once, here).
    ///
    /// # Errors
    /// [`PromptError::Examples`], or [`PromptError::Embed`] when the embedder fails.
    pub fn with_embedder(
        mut self,
        embedder: std::sync::Arc<dyn crate::v2::examples::Embedder>,
    ) -> Result<Self, PromptError> {
        let idx =
            crate::v2::examples::ExampleIndex::embedded(self.worked_example_list()?, embedder)?;
        self.index = Some(std::sync::Arc::new(idx));
        Ok(self)
    }

    /// The worked examples ready to rank: embedded when [`Prompts::with_embedder`] was
    /// called, else ranked by words.
    ///
    /// # Errors
    /// [`PromptError::Examples`].
    pub fn example_index(
        &self,
    ) -> Result<std::sync::Arc<crate::v2::examples::ExampleIndex>, PromptError> {
        match &self.index {
            Some(i) => Ok(i.clone()),
            None => Ok(std::sync::Arc::new(
                crate::v2::examples::ExampleIndex::lexical(self.worked_example_list()?),
            )),
        }
    }

    /// The worked examples' text and where it came from (see [`crate::v2::examples`]).
    #[must_use]
    pub fn worked_examples(&self) -> (&str, &str) {
        self.templates
            .get(WORKED_EXAMPLES)
            .map_or(("", "none"), |(s, o)| (s.as_str(), o.as_str()))
    }

    /// The one-call answer's system message: `v2_system` with the step functions
    /// (generated from the registry), then `scene` (a summary of the map), so that the
    /// whole message is the same for every instruction on one map.
    ///
    /// # Errors
    /// [`PromptError::Template`].
    pub fn v2_system(&self, scene: Option<&str>) -> Result<String, PromptError> {
        let mut names = vec![planner_dsl::typed::PICK_FUNCTION];
        names.extend_from_slice(planner_dsl::typed::STEP_FUNCTIONS);
        let mut functions = String::new();
        for f in names.iter().filter_map(|n| planner_dsl::lookup(n)) {
            functions.push_str(&format!("# {}.\n{}\n", f.doc, f.signature()));
        }
        let sys = self.render(
            "v2_system.md.j2",
            minijinja::context! { functions => functions.trim_end() },
        )?;
        Ok(match scene {
            Some(s) => format!("{sys}\nThe map here: {s}."),
            None => sys,
        })
    }

    /// The one-call request for `instruction` (with a summary of the conversation, and
    /// the map's summary when it is not in the system message).
    ///
    /// # Errors
    /// [`PromptError::Template`].
    pub fn v2_request(
        &self,
        instruction: &str,
        history: Option<&str>,
        scene: Option<&str>,
    ) -> Result<ChatMessage, PromptError> {
        Ok(ChatMessage::user(self.render(
            "v2_request.md.j2",
            minijinja::context! { instruction => instruction.trim(), history => history, scene => scene },
        )?))
    }

    /// The targeted re-ask: what the checks found, in words the model can act on.
    ///
    /// # Errors
    /// [`PromptError::Template`].
    pub fn v2_reask(&self, findings: &[String]) -> Result<ChatMessage, PromptError> {
        Ok(ChatMessage::user(self.render(
            "v2_reask.md.j2",
            minijinja::context! { findings => Value::from(Serde(findings)) },
        )?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_set_is_complete_and_renders() {
        let p = Prompts::builtin();
        for n in TEMPLATE_NAMES {
            assert!(p.source(n).is_some(), "{n}");
        }
        let sys = p.v2_system(Some("objects: sofa (1 red)")).unwrap();
        for f in planner_dsl::typed::STEP_FUNCTIONS {
            let f = planner_dsl::lookup(f).unwrap();
            assert!(sys.contains(&f.signature()), "{} missing", f.name);
        }
        assert!(
            sys.ends_with("The map here: objects: sofa (1 red)."),
            "{sys}"
        );
        let m = p
            .v2_request("go to the red sofa", Some("visited so far: sofa 2"), None)
            .unwrap();
        assert!(m.content.contains("go to the red sofa"), "{}", m.content);
        assert!(
            m.content.contains("visited so far: sofa 2"),
            "{}",
            m.content
        );
    }

    #[test]
    fn reask_lists_findings() {
        let m = Prompts::builtin()
            .v2_reask(&["the plan visits no table".into(), "x".into()])
            .unwrap();
        assert!(
            m.content.contains("the plan visits no table"),
            "{}",
            m.content
        );
        assert!(m.content.contains("x"), "{}", m.content);
    }
}
