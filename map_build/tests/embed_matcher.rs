#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! EmbeddingMatcher with the real ONNX Runtime and all-MiniLM-L6-v2 from the models
//! cache. `scripts/setup.sh` fetches them (CI runs it first); without them these tests
//! fail with a message saying so.

use std::path::Path;
use std::sync::OnceLock;
use std::time::Instant;

use map_build::embed::{
    EmbedError, EmbeddingMatcher, TextEncoder, TextEncoderOptions, DEFAULT_EMBEDDING_THRESHOLD,
};
use map_core::{IvlMap, NameMatcher, ObjectOrder, Pose, QueryError, Scene};

fn matcher() -> &'static EmbeddingMatcher {
    static M: OnceLock<EmbeddingMatcher> = OnceLock::new();
    M.get_or_init(|| EmbeddingMatcher::minilm(None).unwrap_or_else(|e| panic!("{e}")))
}

const HOUSEHOLD: &[&str] = &[
    "sofa",
    "table",
    "chair",
    "fridge",
    "television",
    "bed",
    "cabinet",
    "plant",
    "toilet",
    "sink",
    "lamp",
    "counter",
    "bedside table",
    "stool",
    "shelf",
    "bathtub",
];

#[test]
fn lexical_matches_win_with_their_scores() {
    let m = matcher();
    for (q, want, score) in [
        ("couch", "sofa", 1.0),
        ("settee", "sofa", 1.0),
        ("Couches", "sofa", 1.0),
        ("refrigerator", "fridge", 1.0),
        ("the TV", "television", 1.0),
        // a compound names its head word, a little less surely (LexicalMatcher's 0.8)
        ("dining table", "table", 0.8),
        ("coffee table", "table", 0.8),
        ("bar stools", "stool", 1.0),
        ("a Tub", "bathtub", 1.0),
    ] {
        assert_eq!(
            m.try_best(q, HOUSEHOLD).unwrap(),
            Some((want, score)),
            "{q}"
        );
        assert_eq!(m.best(q, HOUSEHOLD), Some(want), "{q}");
        assert_eq!(m.score(q, want), score, "{q}");
    }
    // "settee" is far from "sofa" for MiniLM (0.32): the lexical table decides.
    assert!(m.similarity("settee", "sofa").unwrap() < DEFAULT_EMBEDDING_THRESHOLD);
}

#[test]
fn embeddings_find_names_the_synonym_table_lacks() {
    let m = matcher();
    for (q, want) in [
        ("nightstand", "bedside table"),
        ("freezer", "fridge"),
        ("seat", "chair"),
        ("armchair", "chair"), // sofa is 0.63: above the threshold, below chair's 0.73
    ] {
        let got = m.try_best(q, HOUSEHOLD).unwrap();
        println!("{q:>12} -> {got:?}");
        let (label, score) = got.unwrap_or_else(|| panic!("{q}: no match"));
        assert_eq!(label, want, "{q}");
        assert!(
            (DEFAULT_EMBEDDING_THRESHOLD..=1.0).contains(&score),
            "{q}: {score}"
        );
        assert_eq!(m.best(q, HOUSEHOLD), Some(want), "{q}");
    }
}

#[test]
fn unrelated_words_and_near_misses_match_nothing() {
    let m = matcher();
    for q in [
        "spaceship",
        "elephant",
        "car",
        "galaxy",
        "guitar",
        "pizza",
        "computer",
        "pillow",
        "",
        "   ",
    ] {
        let got = m.try_best(q, HOUSEHOLD).unwrap();
        assert_eq!(got, None, "{q:?}");
        assert_eq!(m.best(q, HOUSEHOLD), None, "{q:?}");
        if !q.trim().is_empty() {
            for l in HOUSEHOLD {
                let s = m.score(q, l);
                assert!(s < m.threshold(), "{q} vs {l}: {s}");
            }
        }
    }
    assert_eq!(m.try_best("sofa", &[]).unwrap(), None);
}

#[test]
fn cosine_is_symmetric_and_high_for_the_same_name() {
    let m = matcher();
    let ab = m.similarity("nightstand", "bedside table").unwrap();
    let ba = m.similarity("bedside table", "nightstand").unwrap();
    assert!((ab - ba).abs() < 1e-6, "{ab} {ba}");
    let same = m.similarity("Sofa", "the sofa").unwrap();
    assert!((same - 1.0).abs() < 1e-4, "{same}");
}

#[test]
fn a_higher_threshold_drops_weaker_matches() {
    let strict = EmbeddingMatcher::new(TextEncoder::minilm(None).unwrap()).with_threshold(0.7);
    assert_eq!(strict.threshold(), 0.7);
    // freezer/fridge is 0.66: kept at the default, dropped at 0.7
    assert_eq!(matcher().best("freezer", HOUSEHOLD), Some("fridge"));
    assert_eq!(strict.best("freezer", HOUSEHOLD), None);
    // lexical matches do not depend on the cosine threshold
    assert_eq!(strict.best("couch", HOUSEHOLD), Some("sofa"));
}

#[test]
fn map_queries_use_the_matcher() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/scenes/flat-a.scene.json");
    let scene = Scene::from_path(&path).unwrap();
    let map = IvlMap::from_scene(&scene);
    let robot = Pose::new(1.0, 1.0, 0.0);
    let m = matcher();
    let via_embedding = map
        .get_obj_attributes_with(m, "freezer", 0, None, ObjectOrder::NearToFar, robot)
        .unwrap();
    assert_eq!(via_embedding.label, "fridge");
    let lexical = map
        .get_obj_attributes_with(m, "settee", 0, None, ObjectOrder::NearToFar, robot)
        .unwrap();
    assert_eq!(lexical.label, "sofa");
    // the lexical matcher alone does not know "freezer"
    assert!(map
        .get_obj_attributes("freezer", 0, None, ObjectOrder::NearToFar, robot)
        .is_err());
    let err = map
        .get_obj_attributes_with(m, "spaceship", 0, None, ObjectOrder::NearToFar, robot)
        .unwrap_err();
    assert!(matches!(err, QueryError::UnknownObject { .. }), "{err:?}");
    assert_eq!(
        map.find_region_with(m, "lounge").unwrap().name,
        "living room"
    );
}

#[test]
fn missing_files_say_to_run_setup() {
    let dir = tempfile::tempdir().unwrap();
    let nothing = dir.path().join("nothing.onnx");
    let err = TextEncoder::new(&nothing, &nothing, &TextEncoderOptions::default()).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, EmbedError::Missing { .. }), "{err:?}");
    assert!(
        msg.contains("nothing.onnx") && msg.contains("scripts/setup.sh"),
        "{msg}"
    );

    let lib = dir.path().join("libonnxruntime.so");
    let err = map_build::embed::ort_library_path(Some(&lib)).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("ONNX Runtime library") && msg.contains("scripts/setup.sh"),
        "{msg}"
    );
}

#[test]
fn ort_loads_once_per_process() {
    let _ = matcher(); // ONNX Runtime loaded from the models cache
    let dir = tempfile::tempdir().unwrap();
    let other = dir.path().join("libonnxruntime.so.1.31.1");
    std::fs::copy(map_build::embed::ort_library_path(None).unwrap(), &other).unwrap();
    let err = EmbeddingMatcher::minilm(Some(&other)).unwrap_err();
    assert!(
        matches!(err, EmbedError::OrtAlreadyLoaded { .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("already loaded"), "{err}");
    // the same file again is fine
    let same = map_build::embed::ort_library_path(None).unwrap();
    assert!(TextEncoder::minilm(Some(&same)).is_ok());
}

/// Model load time and per-name embedding latency (printed; `--nocapture` shows them).
#[test]
fn minilm_load_and_latency() {
    let _ = matcher(); // ONNX Runtime itself loaded once
    let t = Instant::now();
    let enc = TextEncoder::minilm(None).unwrap();
    let load = t.elapsed();
    let names = [
        "sofa",
        "table",
        "chair",
        "fridge",
        "television",
        "bed",
        "cabinet",
        "plant",
        "toilet",
        "sink",
        "lamp",
        "counter",
        "bedside table",
        "stool",
        "shelf",
        "bathtub",
        "nightstand",
        "freezer",
        "dining table",
        "refrigerator",
        "a small wooden stool",
    ];
    let _ = enc.embed_one("warm up").unwrap();
    let mut times: Vec<f64> = names
        .iter()
        .map(|n| {
            let t = Instant::now();
            let v = enc.embed_one(n).unwrap();
            assert_eq!(v.len(), 384);
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    let t = Instant::now();
    let all = enc.embed(&names).unwrap();
    let batch = t.elapsed().as_secs_f64() * 1e3;
    assert_eq!(all.len(), names.len());
    println!(
        "MiniLM int8: session + tokenizer load {:.0} ms; per name median {:.2} ms (max {:.2}); \
         {} names in one batch {:.1} ms",
        load.as_secs_f64() * 1e3,
        times[times.len() / 2],
        times[times.len() - 1],
        names.len(),
        batch
    );
}
