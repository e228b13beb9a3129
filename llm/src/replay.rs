//! Cassettes: record exchanges with any backend to a JSONL file ([`Recording`]) and answer
//! from it later without a model ([`ReplayBackend`]).
//!
//! One record per line:
//! `{"backend": "llama", "model": "x.gguf", "request": {CompletionRequest}, "response": {Completion}}`.
//! A request matches a record when it is equal in full (messages, max_tokens, temperature,
//! stop, grammar, json_schema). Several records for the same request are served in order;
//! once they run out the last one repeats.

use std::collections::HashMap;
use std::fs::OpenOptions;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use serde::{Deserialize, Serialize};

use super::{snippet, Completion, CompletionRequest, LlmBackend, LlmError};

/// One recorded exchange: a line of a cassette.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CassetteRecord {
    /// The backend that answered ("llama", "openai", ...).
    pub backend: String,
    /// The model that answered.
    pub model: String,
    /// What was asked.
    pub request: CompletionRequest,
    /// What came back.
    pub response: Completion,
}

/// Wraps a backend and appends every successful exchange to a cassette file (created if
/// missing). Errors are passed through and not recorded.
#[derive(Debug)]
pub struct Recording<B: LlmBackend> {
    inner: B,
    path: PathBuf,
    file: Mutex<std::fs::File>,
}

impl<B: LlmBackend> Recording<B> {
    /// Records `inner`'s exchanges to `path` (appending to an existing cassette).
    ///
    /// # Errors
    /// [`LlmError::CassetteIo`] if the file cannot be opened for appending.
    pub fn new(inner: B, path: impl Into<PathBuf>) -> Result<Self, LlmError> {
        let path = path.into();
        let file = OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .map_err(|e| io_err(&path, &format!("cannot open for appending: {e}")))?;
        Ok(Self {
            inner,
            path,
            file: Mutex::new(file),
        })
    }

    /// The wrapped backend.
    pub fn inner(&self) -> &B {
        &self.inner
    }

    /// The cassette file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl<B: LlmBackend> LlmBackend for Recording<B> {
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn model(&self) -> &str {
        self.inner.model()
    }

    fn complete(&self, req: &CompletionRequest) -> Result<Completion, LlmError> {
        let response = self.inner.complete(req)?;
        let record = CassetteRecord {
            backend: self.inner.name().to_string(),
            model: self.inner.model().to_string(),
            request: req.clone(),
            response,
        };
        let mut line = serde_json::to_string(&record)
            .map_err(|e| io_err(&self.path, &format!("cannot serialise a record: {e}")))?;
        line.push('\n');
        let mut file = self
            .file
            .lock()
            .map_err(|_| io_err(&self.path, "a previous write panicked"))?;
        // One write call per line: appends from several recorders stay whole lines.
        file.write_all(line.as_bytes())
            .and_then(|()| file.flush())
            .map_err(|e| io_err(&self.path, &format!("cannot append: {e}")))?;
        Ok(record.response)
    }
}

fn io_err(path: &Path, message: &str) -> LlmError {
    LlmError::CassetteIo {
        path: path.to_path_buf(),
        message: message.to_string(),
    }
}

/// Answers from a cassette.
#[derive(Debug)]
pub struct ReplayBackend {
    path: PathBuf,
    model: String,
    /// (1-based line, record)
    records: Vec<(usize, CassetteRecord)>,
    /// How many times each record index's request has been served.
    served: Mutex<HashMap<usize, usize>>,
}

impl ReplayBackend {
    /// Reads the cassette at `path`. Blank lines are skipped.
    ///
    /// # Errors
    /// [`LlmError::CassetteIo`] if it cannot be read, [`LlmError::CassetteParse`] naming the
    /// line of the first bad record.
    pub fn open(path: impl Into<PathBuf>) -> Result<Self, LlmError> {
        let path = path.into();
        let text = std::fs::read_to_string(&path).map_err(|e| io_err(&path, &e.to_string()))?;
        let mut records = Vec::new();
        for (i, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let rec: CassetteRecord =
                serde_json::from_str(line).map_err(|e| LlmError::CassetteParse {
                    path: path.clone(),
                    line: i + 1,
                    message: e.to_string(),
                })?;
            records.push((i + 1, rec));
        }
        let model = records
            .first()
            .map(|(_, r)| r.model.clone())
            .unwrap_or_default();
        Ok(Self {
            path,
            model,
            records,
            served: Mutex::new(HashMap::new()),
        })
    }

    /// Number of recorded exchanges.
    #[must_use]
    pub fn len(&self) -> usize {
        self.records.len()
    }

    /// Whether the cassette holds no exchange.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// The recorded exchanges, in the cassette's order.
    pub fn records(&self) -> impl Iterator<Item = &CassetteRecord> {
        self.records.iter().map(|(_, r)| r)
    }

    fn miss(&self, req: &CompletionRequest) -> LlmError {
        let detail = match self
            .records
            .iter()
            .max_by_key(|(_, r)| similarity(&r.request, req))
        {
            None => "the cassette is empty; record one with Recording".to_string(),
            Some((line, rec)) => format!(
                "{} recorded exchange(s); the nearest (line {line}) differs: {}",
                self.records.len(),
                first_difference(&rec.request, req)
            ),
        };
        LlmError::CassetteMiss {
            path: self.path.clone(),
            detail,
        }
    }
}

impl LlmBackend for ReplayBackend {
    fn name(&self) -> &str {
        "replay"
    }

    fn model(&self) -> &str {
        &self.model
    }

    fn complete(&self, req: &CompletionRequest) -> Result<Completion, LlmError> {
        let matching: Vec<usize> = self
            .records
            .iter()
            .enumerate()
            .filter(|(_, (_, r))| r.request == *req)
            .map(|(i, _)| i)
            .collect();
        let Some(&first) = matching.first() else {
            return Err(self.miss(req));
        };
        let mut served = self
            .served
            .lock()
            .map_err(|_| io_err(&self.path, "a previous replay panicked"))?;
        let n = served.entry(first).or_insert(0);
        let pick = matching[(*n).min(matching.len() - 1)];
        *n += 1;
        Ok(self.records[pick].1.response.clone())
    }
}

/// Ranks recorded requests by closeness: equal leading messages first, then how far the
/// first differing message agrees, then equal parameters.
fn similarity(a: &CompletionRequest, b: &CompletionRequest) -> (usize, usize, usize, usize) {
    let lead = a
        .messages
        .iter()
        .zip(&b.messages)
        .take_while(|(x, y)| x == y)
        .count();
    // How far the first differing message agrees.
    let chars = match (a.messages.get(lead), b.messages.get(lead)) {
        (Some(x), Some(y)) if x.role == y.role => x
            .content
            .chars()
            .zip(y.content.chars())
            .take_while(|(p, q)| p == q)
            .count(),
        _ => 0,
    };
    let same_len = usize::from(a.messages.len() == b.messages.len());
    let params = [
        a.max_tokens == b.max_tokens,
        a.temperature == b.temperature,
        a.stop == b.stop,
        a.grammar == b.grammar,
        a.json_schema == b.json_schema,
    ]
    .iter()
    .filter(|x| **x)
    .count();
    (lead, chars, same_len, params)
}

/// Says where `asked` first differs from `recorded`.
fn first_difference(recorded: &CompletionRequest, asked: &CompletionRequest) -> String {
    for (i, (r, a)) in recorded.messages.iter().zip(&asked.messages).enumerate() {
        if r.role != a.role {
            return format!("message {i}: role recorded {} vs asked {}", r.role, a.role);
        }
        if r.content != a.content {
            let at = r
                .content
                .chars()
                .zip(a.content.chars())
                .take_while(|(x, y)| x == y)
                .count();
            let tail = |s: &str| {
                snippet(
                    &s.chars().skip(at.saturating_sub(10)).collect::<String>(),
                    60,
                )
            };
            return format!(
                "message {i} ({}) content, from character {at}: recorded {:?} vs asked {:?}",
                a.role,
                tail(&r.content),
                tail(&a.content)
            );
        }
    }
    if recorded.messages.len() != asked.messages.len() {
        return format!(
            "message count: recorded {} vs asked {}",
            recorded.messages.len(),
            asked.messages.len()
        );
    }
    let mut diffs = Vec::new();
    if recorded.max_tokens != asked.max_tokens {
        diffs.push(format!(
            "max_tokens recorded {} vs asked {}",
            recorded.max_tokens, asked.max_tokens
        ));
    }
    if recorded.temperature != asked.temperature {
        diffs.push(format!(
            "temperature recorded {} vs asked {}",
            recorded.temperature, asked.temperature
        ));
    }
    if recorded.stop != asked.stop {
        diffs.push(format!(
            "stop recorded {:?} vs asked {:?}",
            recorded.stop, asked.stop
        ));
    }
    if recorded.grammar != asked.grammar {
        diffs.push("grammar differs".to_string());
    }
    if recorded.json_schema != asked.json_schema {
        diffs.push("json_schema differs".to_string());
    }
    if diffs.is_empty() {
        "nothing visible (identical request)".to_string()
    } else {
        diffs.join("; ")
    }
}
