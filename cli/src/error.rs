//! Why a command failed, its exit status, and writing JSON outputs.

use std::path::{Path, PathBuf};

/// Why a command failed. [`CliError::exit_code`] maps it to the process exit status.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// A file the command was given is missing, unreadable or malformed (exit 2).
    #[error("{0}")]
    Input(String),
    /// The LLM backend could not be opened or failed (exit 1).
    #[error(transparent)]
    Backend(#[from] llm::LlmError),
    /// The language layer failed (exit 1).
    #[error(transparent)]
    Language(#[from] agent::LanguageError),
    /// A mission or plan failed while running (exit 1); what was done is kept.
    #[error("{0}")]
    Failed(String),
    /// Writing an output failed (exit 1).
    #[error("{}: {message}", path.display())]
    Output {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

impl CliError {
    /// 2 for bad input files, 1 for everything else.
    #[must_use]
    pub fn exit_code(&self) -> i32 {
        match self {
            CliError::Input(_) => 2,
            _ => 1,
        }
    }

    /// An input error from any displayable error.
    pub fn input(e: impl std::fmt::Display) -> Self {
        CliError::Input(e.to_string())
    }

    /// An output error for `path`.
    pub fn output(path: &Path, e: impl std::fmt::Display) -> Self {
        CliError::Output {
            path: path.to_path_buf(),
            message: e.to_string(),
        }
    }
}

/// Writes `value` as pretty JSON to `path`.
///
/// # Errors
/// [`CliError::Output`] naming the file.
pub fn write_json(path: &Path, value: &impl serde::Serialize) -> Result<(), CliError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| CliError::output(path, e))?;
    std::fs::write(path, text + "\n")
        .map_err(|e| CliError::output(path, format!("cannot write: {e}")))
}
