//! An ONNX text encoder (token ids in, one L2-normalised embedding per text out),
//! and the row-major embedding matrix it returns.

use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use ort::session::builder::GraphOptimizationLevel;
use ort::session::{Session, SessionInputValue};
use ort::value::{Tensor, TensorElementType, ValueType};
use tokenizers::Tokenizer;

use super::runtime::{cached_file, environment, ort_library_path};
use super::{EmbedError, MINILM_MODEL_FILE, MINILM_TOKENIZER_FILE};

/// A row-major matrix of embeddings: row `i` belongs to the `i`-th text.
#[derive(Debug, Clone, PartialEq)]
pub struct Embeddings {
    rows: usize,
    dim: usize,
    data: Vec<f32>,
}

impl Embeddings {
    /// `rows` x `dim` values, row-major. Used as given (see [`Embeddings::normalised`]).
    pub fn new(rows: usize, dim: usize, data: Vec<f32>) -> Result<Self, EmbedError> {
        if rows.checked_mul(dim) != Some(data.len()) {
            return Err(EmbedError::Shape {
                what: "embeddings",
                message: format!("{} values for {rows} rows of {dim}", data.len()),
            });
        }
        Ok(Embeddings { rows, dim, data })
    }

    /// Number of rows (texts, categories).
    pub fn len(&self) -> usize {
        self.rows
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.rows == 0
    }

    /// Length of each row.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Row `i`, if it exists.
    pub fn row(&self, i: usize) -> Option<&[f32]> {
        (i < self.rows).then(|| &self.data[i * self.dim..(i + 1) * self.dim])
    }

    /// All values, row-major.
    pub fn as_slice(&self) -> &[f32] {
        &self.data
    }

    /// The same rows scaled to unit length (all-zero rows stay zero).
    pub fn normalised(mut self) -> Self {
        if self.dim > 0 {
            for row in self.data.chunks_exact_mut(self.dim) {
                l2_normalize(row);
            }
        }
        self
    }
}

/// Scale `v` to unit length in place; a zero (or non-finite) vector is left alone.
pub(crate) fn l2_normalize(v: &mut [f32]) {
    let norm = v.iter().map(|x| x * x).sum::<f32>().sqrt();
    if norm > 0.0 && norm.is_finite() {
        v.iter_mut().for_each(|x| *x /= norm);
    }
}

/// How to build a [`TextEncoder`].
#[derive(Debug, Clone, PartialEq)]
pub struct TextEncoderOptions {
    /// ONNX Runtime library; `None` = `$IVLMAP_ORT_LIB`, else the models cache's.
    pub ort_lib: Option<PathBuf>,
    /// ONNX Runtime intra-op threads (0 = ONNX Runtime's default, all cores).
    pub threads: usize,
    /// Name of the model output to use; `None` = the first 2-D `(batch, D)` output
    /// (pooled, e.g. CLIP's `text_embeds`), else the first 3-D `(batch, seq, D)`
    /// output, mean-pooled over the attention mask.
    pub output: Option<String>,
    /// Texts per model run (bounds memory on long lists).
    pub batch: usize,
}

impl Default for TextEncoderOptions {
    fn default() -> Self {
        // One thread: a few short names per run are latency-bound, not compute-bound,
        // and the machines this runs on are small and shared.
        TextEncoderOptions {
            ort_lib: None,
            threads: 1,
            output: None,
            batch: 64,
        }
    }
}

/// Integer element type of a token input.
#[derive(Debug, Clone, Copy, PartialEq)]
enum IdType {
    I64,
    I32,
}

#[derive(Debug, Clone, PartialEq)]
struct TokenInput {
    name: String,
    ty: IdType,
}

/// An ONNX text encoder with its tokenizer: token ids in, embeddings out.
///
/// The model's inputs must be `input_ids` (or a single input of any name), plus
/// optionally `attention_mask` and `token_type_ids`, int64 or int32. A fixed
/// sequence length in the model (CLIP exports often fix 77) is padded to; otherwise
/// each batch is padded to its longest text. Thread-safe (runs are serialised).
pub struct TextEncoder {
    session: Mutex<Session>,
    tokenizer: Tokenizer,
    model_path: PathBuf,
    ids: TokenInput,
    mask: Option<TokenInput>,
    type_ids: Option<TokenInput>,
    /// Fixed sequence length the model demands, if any.
    fixed_len: Option<usize>,
    output: String,
    /// Output is `(batch, seq, D)`: mean-pool over the mask.
    mean_pool: bool,
    /// Embedding dimension, when the model declares it.
    declared_dim: Option<usize>,
    pad_id: u32,
    batch: usize,
}

impl std::fmt::Debug for TextEncoder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TextEncoder")
            .field("model_path", &self.model_path)
            .field("ids", &self.ids)
            .field("mask", &self.mask)
            .field("type_ids", &self.type_ids)
            .field("fixed_len", &self.fixed_len)
            .field("output", &self.output)
            .field("mean_pool", &self.mean_pool)
            .field("declared_dim", &self.declared_dim)
            .finish_non_exhaustive()
    }
}

fn id_type(path: &Path, name: &str, ty: &ValueType) -> Result<(IdType, Option<usize>), EmbedError> {
    let bad = |what: String| EmbedError::Model {
        path: path.to_path_buf(),
        message: format!("input {name:?}: {what}; a text encoder takes int64 or int32 token ids"),
    };
    let (elem, shape) = match ty {
        ValueType::Tensor { ty, shape, .. } => (*ty, shape),
        other => return Err(bad(format!("is {other:?}, not a tensor"))),
    };
    let idt = match elem {
        TensorElementType::Int64 => IdType::I64,
        TensorElementType::Int32 => IdType::I32,
        other => return Err(bad(format!("has element type {other:?}"))),
    };
    if shape.len() != 2 {
        return Err(bad(format!("has shape {shape:?}, not (batch, sequence)")));
    }
    let fixed = usize::try_from(shape[1]).ok().filter(|&n| n > 0);
    Ok((idt, fixed))
}

impl TextEncoder {
    /// Load an ONNX text encoder and its `tokenizer.json`. Loads ONNX Runtime first
    /// if this process has not yet (see the module docs for where it is found).
    pub fn new(
        model: impl AsRef<Path>,
        tokenizer: impl AsRef<Path>,
        options: &TextEncoderOptions,
    ) -> Result<Self, EmbedError> {
        let (model, tok_path) = (model.as_ref(), tokenizer.as_ref());
        for (p, what) in [(model, "ONNX model"), (tok_path, "tokenizer.json")] {
            if !p.is_file() {
                return Err(EmbedError::Missing {
                    path: p.to_path_buf(),
                    what,
                    origin: "argument",
                });
            }
        }
        let lib = ort_library_path(options.ort_lib.as_deref())?;
        let env = environment(&lib)?;
        let model_err = |message: String| EmbedError::Model {
            path: model.to_path_buf(),
            message,
        };

        let mut builder = Session::builder(&env)
            .map_err(|e| model_err(e.to_string()))?
            .with_optimization_level(GraphOptimizationLevel::Level3)
            .map_err(|e| model_err(e.to_string()))?
            .with_intra_op_spinning(false)
            .map_err(|e| model_err(e.to_string()))?;
        if options.threads > 0 {
            builder = builder
                .with_intra_threads(options.threads)
                .map_err(|e| model_err(e.to_string()))?;
        }
        let session = builder
            .commit_from_file(model)
            .map_err(|e| model_err(e.to_string()))?;

        // Inputs: token ids, and optionally the mask and token types.
        let mut ids = None;
        let (mut mask, mut type_ids) = (None, None);
        let mut fixed_len = None;
        let n_inputs = session.inputs().len();
        for input in session.inputs() {
            let name = input.name();
            let (ty, fixed) = id_type(model, name, input.dtype())?;
            let slot = match name {
                "attention_mask" => &mut mask,
                "token_type_ids" => &mut type_ids,
                "input_ids" => &mut ids,
                _ if n_inputs == 1 => &mut ids,
                _ => {
                    return Err(model_err(format!(
                        "input {name:?} is not one a text encoder takes \
                         (input_ids, attention_mask, token_type_ids)"
                    )))
                }
            };
            *slot = Some(TokenInput {
                name: name.to_string(),
                ty,
            });
            fixed_len = fixed_len.or(fixed);
        }
        let ids = ids.ok_or_else(|| model_err("no input_ids input".to_string()))?;

        // Output: the named one, else the first pooled (2-D), else the first 3-D.
        let outputs: Vec<(String, usize, Option<usize>, TensorElementType)> = session
            .outputs()
            .iter()
            .filter_map(|o| match o.dtype() {
                ValueType::Tensor { ty, shape, .. } => Some((
                    o.name().to_string(),
                    shape.len(),
                    shape.last().and_then(|&d| usize::try_from(d).ok()),
                    *ty,
                )),
                _ => None,
            })
            .collect();
        let names = || {
            outputs
                .iter()
                .map(|o| format!("{} (rank {})", o.0, o.1))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let chosen = match &options.output {
            Some(want) => outputs.iter().find(|o| o.0 == *want).ok_or_else(|| {
                model_err(format!("no tensor output {want:?}; outputs: {}", names()))
            })?,
            None => outputs
                .iter()
                .find(|o| o.1 == 2)
                .or_else(|| outputs.iter().find(|o| o.1 == 3))
                .ok_or_else(|| {
                    model_err(format!(
                        "no (batch, D) or (batch, seq, D) output; outputs: {}",
                        names()
                    ))
                })?,
        };
        if chosen.1 != 2 && chosen.1 != 3 {
            return Err(model_err(format!(
                "output {:?} has rank {}; expected (batch, D) or (batch, seq, D)",
                chosen.0, chosen.1
            )));
        }
        if chosen.3 != TensorElementType::Float32 {
            return Err(model_err(format!(
                "output {:?} has element type {:?}; only float32 is supported",
                chosen.0, chosen.3
            )));
        }
        let (output, mean_pool, declared_dim) = (chosen.0.clone(), chosen.1 == 3, chosen.2);

        // Tokenizer: padding is done here (to the batch's longest, or the model's
        // fixed length), truncation to what the model takes.
        let tok_err = |message: String| EmbedError::Tokenizer {
            path: tok_path.to_path_buf(),
            message,
        };
        let mut tok = Tokenizer::from_file(tok_path).map_err(|e| tok_err(e.to_string()))?;
        let pad_id = tok.get_padding().map_or(0, |p| p.pad_id);
        tok.with_padding(None);
        if let Some(n) = fixed_len {
            let mut t = tok.get_truncation().cloned().unwrap_or_default();
            t.max_length = n;
            tok.with_truncation(Some(t))
                .map_err(|e| tok_err(e.to_string()))?;
        }

        Ok(TextEncoder {
            session: Mutex::new(session),
            tokenizer: tok,
            model_path: model.to_path_buf(),
            ids,
            mask,
            type_ids,
            fixed_len,
            output,
            mean_pool,
            declared_dim,
            pad_id,
            batch: options.batch.max(1),
        })
    }

    /// all-MiniLM-L6-v2 (int8) from the models cache; `ort_lib` overrides where
    /// ONNX Runtime comes from. Fails with a message naming `scripts/setup.sh` when
    /// the files are missing.
    pub fn minilm(ort_lib: Option<&Path>) -> Result<Self, EmbedError> {
        let model = cached_file(MINILM_MODEL_FILE, "ONNX model")?;
        let tokenizer = cached_file(MINILM_TOKENIZER_FILE, "tokenizer.json")?;
        let options = TextEncoderOptions {
            ort_lib: ort_lib.map(Path::to_path_buf),
            ..TextEncoderOptions::default()
        };
        TextEncoder::new(model, tokenizer, &options)
    }

    /// The model file this encoder runs.
    pub fn model_path(&self) -> &Path {
        &self.model_path
    }

    /// The embedding dimension the model declares (`None` if dynamic).
    pub fn dim(&self) -> Option<usize> {
        self.declared_dim
    }

    /// Embed each text: one L2-normalised row per text, in order.
    pub fn embed(&self, texts: &[&str]) -> Result<Embeddings, EmbedError> {
        let mut data = Vec::new();
        let mut dim = self.declared_dim.unwrap_or(0);
        for (chunk_no, chunk) in texts.chunks(self.batch).enumerate() {
            let (d, rows) = self.embed_batch(chunk, chunk_no * self.batch)?;
            dim = d;
            data.extend(rows);
        }
        Embeddings::new(texts.len(), dim, data)
    }

    /// One embedding, L2-normalised.
    pub fn embed_one(&self, text: &str) -> Result<Vec<f32>, EmbedError> {
        Ok(self.embed_batch(&[text], 0)?.1)
    }

    /// Run one batch; returns (dim, row-major normalised embeddings).
    fn embed_batch(&self, texts: &[&str], first: usize) -> Result<(usize, Vec<f32>), EmbedError> {
        let n = texts.len();
        if n == 0 {
            return Ok((self.declared_dim.unwrap_or(0), Vec::new()));
        }
        let mut encoded = Vec::with_capacity(n);
        for (i, t) in texts.iter().enumerate() {
            let enc = self
                .tokenizer
                .encode_fast(*t, true)
                .map_err(|e| EmbedError::Encode {
                    path: self.model_path.clone(),
                    index: first + i,
                    text: t.to_string(),
                    message: e.to_string(),
                })?;
            encoded.push(enc);
        }
        let longest = encoded.iter().map(|e| e.len()).max().unwrap_or(0).max(1);
        let len = self.fixed_len.unwrap_or(longest);
        let mut ids = vec![i64::from(self.pad_id); n * len];
        let mut mask = vec![0i64; n * len];
        let mut types = vec![0i64; n * len];
        for (row, enc) in encoded.iter().enumerate() {
            let take = enc.len().min(len);
            let at = row * len;
            for (j, &id) in enc.get_ids()[..take].iter().enumerate() {
                ids[at + j] = i64::from(id);
                mask[at + j] = 1;
            }
            for (j, &t) in enc.get_type_ids()[..take].iter().enumerate() {
                types[at + j] = i64::from(t);
            }
        }

        let run_err = |message: String| EmbedError::Run {
            path: self.model_path.clone(),
            message,
        };
        let shape = [n as i64, len as i64];
        let tensor = |ty: IdType, v: &[i64]| -> Result<SessionInputValue<'static>, EmbedError> {
            Ok(match ty {
                IdType::I64 => Tensor::from_array((shape, v.to_vec()))
                    .map_err(|e| run_err(e.to_string()))?
                    .into(),
                IdType::I32 => {
                    let v32: Vec<i32> = v
                        .iter()
                        .map(|&x| i32::try_from(x).unwrap_or(i32::MAX))
                        .collect();
                    Tensor::from_array((shape, v32))
                        .map_err(|e| run_err(e.to_string()))?
                        .into()
                }
            })
        };
        let mut inputs: Vec<(Cow<'_, str>, SessionInputValue<'_>)> = Vec::with_capacity(3);
        inputs.push((
            Cow::from(self.ids.name.as_str()),
            tensor(self.ids.ty, &ids)?,
        ));
        if let Some(m) = &self.mask {
            inputs.push((Cow::from(m.name.as_str()), tensor(m.ty, &mask)?));
        }
        if let Some(t) = &self.type_ids {
            inputs.push((Cow::from(t.name.as_str()), tensor(t.ty, &types)?));
        }

        let mut session = self.session.lock().unwrap_or_else(|p| p.into_inner());
        let outputs = session.run(inputs).map_err(|e| run_err(e.to_string()))?;
        let value = outputs
            .get(&self.output)
            .ok_or_else(|| run_err(format!("no output {:?}", self.output)))?;
        let (oshape, values) = value
            .try_extract_tensor::<f32>()
            .map_err(|e| run_err(e.to_string()))?;
        let dims: Vec<usize> = oshape
            .iter()
            .map(|&d| usize::try_from(d).unwrap_or(0))
            .collect();
        if dims.iter().product::<usize>() != values.len() {
            return Err(run_err(format!(
                "output {:?} has shape {dims:?} but {} values",
                self.output,
                values.len()
            )));
        }

        let mut out;
        let dim;
        if self.mean_pool {
            if dims.len() != 3 || dims[0] != n || dims[1] != len || dims[2] == 0 {
                return Err(run_err(format!(
                    "output {:?} has shape {dims:?}; expected [{n}, {len}, D]",
                    self.output
                )));
            }
            dim = dims[2];
            out = vec![0f32; n * dim];
            for row in 0..n {
                let acc = &mut out[row * dim..(row + 1) * dim];
                let mut count = 0usize;
                for tok in 0..len {
                    if mask[row * len + tok] == 0 {
                        continue;
                    }
                    count += 1;
                    let h = &values[(row * len + tok) * dim..(row * len + tok + 1) * dim];
                    acc.iter_mut().zip(h).for_each(|(a, x)| *a += x);
                }
                if count > 0 {
                    let c = count as f32;
                    acc.iter_mut().for_each(|a| *a /= c);
                }
            }
        } else {
            if dims.len() != 2 || dims[0] != n || dims[1] == 0 {
                return Err(run_err(format!(
                    "output {:?} has shape {dims:?}; expected [{n}, D]",
                    self.output
                )));
            }
            dim = dims[1];
            out = values[..n * dim].to_vec();
        }
        for row in out.chunks_exact_mut(dim) {
            l2_normalize(row);
        }
        Ok((dim, out))
    }
}
