//! Open vocabulary with ONNX Runtime: sentence embeddings for name matching, and
//! CLIP-style labelling of a VLMaps feature map (the paper's `P = Q x E^T`).
//!
//! Everything here runs a real ONNX model through the `ort` crate with ONNX Runtime
//! loaded at run time (`load-dynamic`): nothing is downloaded at build or run time.
//! `scripts/setup.sh` (via `scripts/fetch-models.sh minilm onnxruntime`) puts the
//! files this module looks for into the models cache,
//! `${IVLMAP_MODELS:-$HOME/.cache/ivlmap/models}`:
//!
//! | file | what |
//! | --- | --- |
//! | [`MINILM_MODEL_FILE`] | all-MiniLM-L6-v2, int8 ONNX (384-d sentence embeddings) |
//! | [`MINILM_TOKENIZER_FILE`] | its `tokenizer.json` (BERT uncased WordPiece) |
//! | [`ORT_LIB_FILE`] | the ONNX Runtime 1.31 shared library |
//!
//! ONNX Runtime is loaded lazily, once per process, the first time a
//! [`TextEncoder`] (and so an [`EmbeddingMatcher`]) is built: the rest of map_core
//! never touches it. The library is, in order of precedence: the path given to the
//! constructor ([`TextEncoderOptions::ort_lib`]), the `IVLMAP_ORT_LIB` environment
//! variable ([`ORT_LIB_ENV`]), or [`ORT_LIB_FILE`] in the models cache
//! ([`ort_library_path`]). A missing file is an [`EmbedError`] that says to run
//! `scripts/setup.sh`.
//!
//! ## Name matching
//! [`EmbeddingMatcher`] implements [`NameMatcher`](map_core::matcher::NameMatcher): the
//! [`LexicalMatcher`](map_core::matcher::LexicalMatcher) decides first (same name, plural,
//! synonym table, "dining table" for "table"); only when it finds nothing do
//! mean-pooled, L2-normalised MiniLM embeddings decide, by cosine similarity between
//! the asked name and each label the map holds, at or above
//! [`DEFAULT_EMBEDDING_THRESHOLD`]. Label embeddings are cached.
//!
//! ```no_run
//! use map_core::NameMatcher;
//! use map_build::embed::EmbeddingMatcher;
//! let m = EmbeddingMatcher::minilm(None)?; // loads ORT + MiniLM from the models cache
//! let labels = ["chair", "fridge", "sofa", "bedside table"];
//! assert_eq!(m.best("couch", &labels), Some("sofa")); // synonym table, score 1
//! assert_eq!(m.best("nightstand", &labels), Some("bedside table")); // cosine 0.68
//! assert_eq!(m.best("spaceship", &labels), None);
//! // with the score: Some(("fridge", 0.655...))
//! let scored = m.try_best("freezer", &labels)?;
//! # Ok::<(), map_build::embed::EmbedError>(())
//! ```
//!
//! ## Labelling a feature map (paper Sec. III-B)
//! A [`TextEncoder`] runs any ONNX text encoder that takes token ids (`input_ids`,
//! optionally `attention_mask` and `token_type_ids`, int64 or int32) and returns
//! either pooled embeddings `(batch, D)` (a CLIP text encoder's `text_embeds`) or
//! token states `(batch, seq, D)`, which are mean-pooled over the attention mask
//! (sentence-transformers). Either way the rows come back L2-normalised.
//! [`TextEncoder::embed`] turns the category list into `E` (C x D); a
//! [`FeatureMap`] holds `Q` (H x W x D, e.g. VLMaps' `grid_lseg_1.npy`, read with
//! [`FeatureMap::read_npy`]); [`label_cells`] computes `P = Q E^T` per cell and keeps
//! the argmax as a [`Grid<u16>`](map_core::grid::Grid) in the map's convention (0 = none,
//! `k + 1` = category `k`) with the winning score. Cells whose features are all zero
//! (never observed) get label 0 and score 0.
//!
//! ```no_run
//! use map_build::embed::{label_cells, FeatureMap, TextEncoder, TextEncoderOptions};
//! let clip = TextEncoder::new("clip_text.onnx", "clip_tokenizer.json", &TextEncoderOptions::default())?;
//! let e = clip.embed(&["other", "sofa", "table", "chair"])?;
//! let q = FeatureMap::read_npy("grid_lseg_1.npy")?;
//! let out = label_cells(&q, &e)?;
//! println!("cell (10, 20) is category {}", out.labels.as_slice()[10 * out.labels.cols() + 20]);
//! # Ok::<(), map_build::embed::EmbedError>(())
//! ```

mod encoder;
mod label;
mod matcher;
mod runtime;

use std::path::PathBuf;

pub use self::encoder::{Embeddings, TextEncoder, TextEncoderOptions};
pub use self::label::{label_cells, CellLabels, FeatureMap};
pub use self::matcher::{EmbeddingMatcher, DEFAULT_EMBEDDING_THRESHOLD};
pub use self::runtime::{
    models_dir, ort_library_path, MINILM_MODEL_FILE, MINILM_TOKENIZER_FILE, ORT_LIB_ENV,
    ORT_LIB_FILE,
};

/// What setup step provides the missing files (repeated in several messages).
const SETUP_HINT: &str = "run scripts/setup.sh (or scripts/fetch-models.sh minilm onnxruntime)";

/// Why an encoder could not be built or run, or a feature map not labelled.
#[derive(Debug, thiserror::Error)]
pub enum EmbedError {
    /// A model, tokenizer or ONNX Runtime file is not where it was looked for.
    #[error("{path}: {what} not found ({origin}); {SETUP_HINT}")]
    Missing {
        /// The file that was looked for.
        path: PathBuf,
        /// "ONNX Runtime library", "ONNX model", "tokenizer.json".
        what: &'static str,
        /// Where the path came from: "argument", "IVLMAP_ORT_LIB", "models cache".
        origin: &'static str,
    },
    /// Neither `IVLMAP_MODELS` nor `HOME` is set, so there is no models cache.
    #[error("no models cache: set IVLMAP_MODELS or HOME; {SETUP_HINT}")]
    NoModelsDir,
    /// ONNX Runtime could not be loaded from the file.
    #[error("{path}: cannot load ONNX Runtime: {message}")]
    OrtLoad {
        /// The ONNX Runtime library file.
        path: PathBuf,
        /// What ONNX Runtime reported.
        message: String,
    },
    /// ONNX Runtime is already loaded from another file (it loads once per process).
    #[error("{asked}: ONNX Runtime is already loaded from {loaded} in this process")]
    OrtAlreadyLoaded {
        /// The library this process already loaded (canonicalised).
        loaded: PathBuf,
        /// The library this call asked for.
        asked: PathBuf,
    },
    /// The ONNX model could not be loaded, or its inputs/outputs are not a text encoder's.
    #[error("{path}: {message}")]
    Model {
        /// The ONNX model file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The tokenizer file could not be read or configured.
    #[error("{path}: tokenizer: {message}")]
    Tokenizer {
        /// The `tokenizer.json` file.
        path: PathBuf,
        /// What the tokenizer reported.
        message: String,
    },
    /// Tokenizing or running the model on a text failed.
    #[error("{path}: text {index} ({text:?}): {message}")]
    Encode {
        /// The ONNX model file.
        path: PathBuf,
        /// Position of the text in the list given to the encoder.
        index: usize,
        /// The text that failed.
        text: String,
        /// What the tokenizer reported.
        message: String,
    },
    /// Running the model failed, or it returned an output of an unexpected shape.
    #[error("{path}: run: {message}")]
    Run {
        /// The ONNX model file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A feature map file could not be read.
    #[error("{path}: {message}")]
    FeatureFile {
        /// The feature map file.
        path: PathBuf,
        /// Why it could not be read.
        message: String,
    },
    /// A matrix's data does not match its shape.
    #[error("{what}: {message}")]
    Shape {
        /// Which matrix: "embeddings", "feature map", "label grid".
        what: &'static str,
        /// The sizes that do not match.
        message: String,
    },
    /// Feature and embedding dimensions differ.
    #[error("feature map has {features}-d cells but the category embeddings are {embeddings}-d")]
    DimMismatch {
        /// Length of each cell's feature vector.
        features: usize,
        /// Length of each category embedding.
        embeddings: usize,
    },
    /// More categories than a `u16` label layer can name.
    #[error("{count} categories: at most 65535 fit in a u16 label layer")]
    TooManyCategories {
        /// Number of categories given.
        count: usize,
    },
}
