//! Where the model files live and how ONNX Runtime is loaded (once per process).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use super::EmbedError;

/// Environment variable naming the ONNX Runtime shared library to load.
pub const ORT_LIB_ENV: &str = "IVLMAP_ORT_LIB";
/// The ONNX Runtime library's file name in the models cache.
pub const ORT_LIB_FILE: &str = "libonnxruntime.so.1.31.1";
/// all-MiniLM-L6-v2 (int8 ONNX)'s file name in the models cache.
pub const MINILM_MODEL_FILE: &str = "all-MiniLM-L6-v2.int8.onnx";
/// all-MiniLM-L6-v2's `tokenizer.json` in the models cache.
pub const MINILM_TOKENIZER_FILE: &str = "all-MiniLM-L6-v2.tokenizer.json";

/// The models cache ([`map_core::models::models_dir`]), or why there is none.
pub fn models_dir() -> Result<PathBuf, EmbedError> {
    map_core::models::models_dir().ok_or(EmbedError::NoModelsDir)
}

/// The ONNX Runtime library to load: `explicit` if given, else `$IVLMAP_ORT_LIB`,
/// else [`ORT_LIB_FILE`] in [`models_dir`]. The file must exist.
pub fn ort_library_path(explicit: Option<&Path>) -> Result<PathBuf, EmbedError> {
    let (path, origin) = match explicit {
        Some(p) => (p.to_path_buf(), "argument"),
        None => match std::env::var_os(ORT_LIB_ENV) {
            Some(p) if !p.is_empty() => (PathBuf::from(p), ORT_LIB_ENV),
            _ => (models_dir()?.join(ORT_LIB_FILE), "models cache"),
        },
    };
    if !path.is_file() {
        return Err(EmbedError::Missing {
            path,
            what: "ONNX Runtime library",
            origin,
        });
    }
    Ok(path)
}

/// A model or tokenizer file in the models cache, which must exist.
pub(crate) fn cached_file(name: &str, what: &'static str) -> Result<PathBuf, EmbedError> {
    let path = models_dir()?.join(name);
    if !path.is_file() {
        return Err(EmbedError::Missing {
            path,
            what,
            origin: "models cache",
        });
    }
    Ok(path)
}

/// The process's ONNX Runtime: the library it came from and the environment.
static ORT: Mutex<Option<(PathBuf, ort::environment::Environment)>> = Mutex::new(None);

/// Load ONNX Runtime from `lib` (first call) and return the process-wide environment.
/// ONNX Runtime cannot be unloaded: a later call naming another file is an error.
pub(crate) fn environment(lib: &Path) -> Result<ort::environment::Environment, EmbedError> {
    let canon = lib.canonicalize().unwrap_or_else(|_| lib.to_path_buf());
    // A panic elsewhere while holding the lock leaves the Option intact: keep going.
    let mut slot = ORT.lock().unwrap_or_else(|p| p.into_inner());
    if let Some((loaded, env)) = slot.as_ref() {
        if *loaded != canon {
            return Err(EmbedError::OrtAlreadyLoaded {
                loaded: loaded.clone(),
                asked: lib.to_path_buf(),
            });
        }
        return Ok(env.clone());
    }
    let load_err = |message: String| EmbedError::OrtLoad {
        path: lib.to_path_buf(),
        message,
    };
    let env = ort::init_from(&canon)
        .map_err(|e| load_err(e.to_string()))?
        .with_name("ivlmap")
        .build()
        .map_err(|e| load_err(e.to_string()))?;
    *slot = Some((canon, env.clone()));
    Ok(env)
}
