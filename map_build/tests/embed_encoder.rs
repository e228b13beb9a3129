#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! TextEncoder on the real ONNX Runtime with all-MiniLM-L6-v2 standing in for a
//! user's CLIP text encoder (same path: token ids in, embeddings out), and the
//! labelling `P = Q E^T` with E from the encoder. Needs `scripts/setup.sh`.

use std::sync::OnceLock;

use map_build::embed::{
    label_cells, models_dir, EmbedError, FeatureMap, TextEncoder, TextEncoderOptions,
    MINILM_MODEL_FILE, MINILM_TOKENIZER_FILE,
};

fn encoder() -> &'static TextEncoder {
    static E: OnceLock<TextEncoder> = OnceLock::new();
    E.get_or_init(|| TextEncoder::minilm(None).unwrap_or_else(|e| panic!("{e}")))
}

fn cache_files() -> (std::path::PathBuf, std::path::PathBuf) {
    let d = models_dir().unwrap();
    (d.join(MINILM_MODEL_FILE), d.join(MINILM_TOKENIZER_FILE))
}

fn dot(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[test]
fn rows_are_unit_length_and_in_order() {
    let enc = encoder();
    assert_eq!(enc.dim(), Some(384));
    let texts = ["sofa", "a big wooden dining table", "fridge", "television"];
    let e = enc.embed(&texts).unwrap();
    assert_eq!((e.len(), e.dim()), (4, 384));
    for (i, text) in texts.iter().enumerate() {
        let r = e.row(i).unwrap();
        let n = dot(r, r).sqrt();
        assert!((n - 1.0).abs() < 1e-4, "row {i}: norm {n}");
        // each row is that text's own embedding
        let alone = enc.embed_one(text).unwrap();
        let c = dot(r, &alone);
        assert!(c > 0.9999, "row {i}: {c}");
    }
    assert!(e.row(4).is_none());
    let empty = enc.embed(&[]).unwrap();
    assert_eq!((empty.len(), empty.dim()), (0, 384));
}

#[test]
fn padding_does_not_change_embeddings() {
    // Short texts padded to the longest in the batch: the attention mask keeps the
    // padding out of the mean, so batched and single results agree.
    let enc = encoder();
    let long = "a tall grey bookshelf full of old books next to the window";
    let batched = enc.embed(&["tv", long]).unwrap();
    let tv = enc.embed_one("tv").unwrap();
    let max_diff = batched
        .row(0)
        .unwrap()
        .iter()
        .zip(&tv)
        .map(|(a, b)| (a - b).abs())
        .fold(0f32, f32::max);
    assert!(max_diff < 1e-4, "{max_diff}");
}

#[test]
fn batches_split_the_same_way() {
    let (model, tok) = cache_files();
    let small = TextEncoder::new(
        &model,
        &tok,
        &TextEncoderOptions {
            batch: 2,
            ..TextEncoderOptions::default()
        },
    )
    .unwrap();
    let texts = ["bed", "sink", "toilet", "lamp", "counter"];
    let a = small.embed(&texts).unwrap();
    let b = encoder().embed(&texts).unwrap();
    assert_eq!(a.len(), 5);
    for i in 0..5 {
        let c = dot(a.row(i).unwrap(), b.row(i).unwrap());
        assert!(c > 0.9999, "row {i}: {c}");
    }
}

#[test]
fn meaning_shows_in_the_cosines() {
    let e = encoder().embed(&["tv", "television", "spaceship"]).unwrap();
    let tv_television = dot(e.row(0).unwrap(), e.row(1).unwrap());
    let tv_spaceship = dot(e.row(0).unwrap(), e.row(2).unwrap());
    assert!(tv_television > 0.9, "{tv_television}");
    assert!(tv_spaceship < 0.5, "{tv_spaceship}");
}

#[test]
fn outputs_are_chosen_by_name_or_rejected() {
    let (model, tok) = cache_files();
    let named = TextEncoder::new(
        &model,
        &tok,
        &TextEncoderOptions {
            output: Some("last_hidden_state".into()),
            ..TextEncoderOptions::default()
        },
    )
    .unwrap();
    let v = named.embed_one("chair").unwrap();
    assert!(dot(&v, &encoder().embed_one("chair").unwrap()) > 0.9999);

    let err = TextEncoder::new(
        &model,
        &tok,
        &TextEncoderOptions {
            output: Some("text_embeds".into()),
            ..TextEncoderOptions::default()
        },
    )
    .unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, EmbedError::Model { .. }), "{err:?}");
    assert!(
        msg.contains(MINILM_MODEL_FILE)
            && msg.contains("text_embeds")
            && msg.contains("last_hidden_state"),
        "{msg}"
    );
}

#[test]
fn broken_model_and_tokenizer_files_are_errors_naming_them() {
    let (model, tok) = cache_files();
    let dir = tempfile::tempdir().unwrap();
    let junk_model = dir.path().join("junk.onnx");
    std::fs::write(&junk_model, b"not a protobuf").unwrap();
    let err = TextEncoder::new(&junk_model, &tok, &TextEncoderOptions::default()).unwrap_err();
    assert!(matches!(err, EmbedError::Model { .. }), "{err:?}");
    assert!(err.to_string().contains("junk.onnx"), "{err}");

    let junk_tok = dir.path().join("tokenizer.json");
    std::fs::write(&junk_tok, b"{\"model\": 3}").unwrap();
    let err = TextEncoder::new(&model, &junk_tok, &TextEncoderOptions::default()).unwrap_err();
    assert!(matches!(err, EmbedError::Tokenizer { .. }), "{err:?}");
    assert!(err.to_string().contains("tokenizer.json"), "{err}");
}

#[test]
fn feature_map_labelled_with_encoded_categories() {
    // The CLIP path with MiniLM as the text encoder: E from the category list, Q made
    // of the encoder's own embeddings of other words for the same things.
    let enc = encoder();
    let categories = enc.embed(&["sofa", "table", "fridge"]).unwrap();
    let cells = ["couch", "dining table", "refrigerator"];
    let q = enc.embed(&cells).unwrap();
    let mut data = q.as_slice().to_vec();
    data.extend(std::iter::repeat_n(0.0, 384)); // an unobserved cell
    let fm = FeatureMap::new(2, 2, 384, data).unwrap();
    let out = label_cells(&fm, &categories).unwrap();
    assert_eq!(out.labels.as_slice(), &[1, 2, 3, 0]);
    for (i, &s) in out.scores.as_slice()[..3].iter().enumerate() {
        let want = dot(q.row(i).unwrap(), categories.row(i).unwrap());
        assert!((s - want).abs() < 1e-5, "cell {i}: {s} vs {want}");
        assert!(s > 0.6, "cell {i}: {s}");
    }
    assert_eq!(out.scores.as_slice()[3], 0.0);
}

/// Protocol-buffer writer, just enough for a hand-made ONNX model.
fn varint(out: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        out.push((v as u8) | 0x80);
        v >>= 7;
    }
    out.push(v as u8);
}
fn field_int(out: &mut Vec<u8>, field: u64, v: u64) {
    varint(out, field << 3);
    varint(out, v);
}
fn field_bytes(out: &mut Vec<u8>, field: u64, bytes: &[u8]) {
    varint(out, (field << 3) | 2);
    varint(out, bytes.len() as u64);
    out.extend_from_slice(bytes);
}

/// ValueInfoProto: a tensor of `elem_type` with dims ("batch" symbolic, numbers fixed).
fn value_info(name: &str, elem_type: u64, dims: &[Result<u64, &str>]) -> Vec<u8> {
    let mut shape = Vec::new();
    for d in dims {
        let mut dim = Vec::new();
        match d {
            Ok(n) => field_int(&mut dim, 1, *n),
            Err(p) => field_bytes(&mut dim, 2, p.as_bytes()),
        }
        field_bytes(&mut shape, 1, &dim);
    }
    let mut tensor = Vec::new();
    field_int(&mut tensor, 1, elem_type);
    field_bytes(&mut tensor, 2, &shape);
    let mut ty = Vec::new();
    field_bytes(&mut ty, 1, &tensor);
    let mut vi = Vec::new();
    field_bytes(&mut vi, 1, name.as_bytes());
    field_bytes(&mut vi, 2, &ty);
    vi
}

/// An ONNX model standing in for a CLIP text encoder exported with a fixed context:
/// one int32 input "tokens" (batch, 8), output "text_embeds" = Cast(tokens, float),
/// (batch, 8). Its "embedding" is the padded token ids themselves.
fn fixed_length_model() -> Vec<u8> {
    const INT32: u64 = 6;
    const FLOAT: u64 = 1;
    let mut attr = Vec::new();
    field_bytes(&mut attr, 1, b"to");
    field_int(&mut attr, 3, FLOAT);
    field_int(&mut attr, 20, 2); // AttributeType INT
    let mut node = Vec::new();
    field_bytes(&mut node, 1, b"tokens");
    field_bytes(&mut node, 2, b"text_embeds");
    field_bytes(&mut node, 4, b"Cast");
    field_bytes(&mut node, 5, &attr);
    let mut graph = Vec::new();
    field_bytes(&mut graph, 1, &node);
    field_bytes(&mut graph, 2, b"fixed_length_text_encoder");
    field_bytes(
        &mut graph,
        11,
        &value_info("tokens", INT32, &[Err("batch"), Ok(8)]),
    );
    field_bytes(
        &mut graph,
        12,
        &value_info("text_embeds", FLOAT, &[Err("batch"), Ok(8)]),
    );
    let mut opset = Vec::new();
    field_bytes(&mut opset, 1, b"");
    field_int(&mut opset, 2, 13);
    let mut model = Vec::new();
    field_int(&mut model, 1, 8); // ir_version
    field_bytes(&mut model, 8, &opset);
    field_bytes(&mut model, 7, &graph);
    model
}

#[test]
fn fixed_length_int32_pooled_encoder_pads_and_truncates() {
    let (_, tok) = cache_files();
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("fixed.onnx");
    std::fs::write(&model, fixed_length_model()).unwrap();
    let enc = TextEncoder::new(&model, &tok, &TextEncoderOptions::default()).unwrap();
    assert_eq!(enc.dim(), Some(8));
    let long = "one two three four five six seven eight nine ten";
    let e = enc.embed(&["sofa", long]).unwrap();
    assert_eq!((e.len(), e.dim()), (2, 8));
    let unit = |v: [f32; 8]| {
        let n = dot(&v, &v).sqrt();
        v.map(|x| x / n)
    };
    // [CLS] sofa [SEP], then padding (id 0) to the model's fixed 8
    let sofa = unit([101.0, 10682.0, 102.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    for (got, want) in e.row(0).unwrap().iter().zip(&sofa) {
        assert!((got - want).abs() < 1e-6, "{:?}", e.row(0));
    }
    // truncated to 8 tokens by the tokenizer, so still [CLS] ... [SEP]
    let row = e.row(1).unwrap();
    let scale = 101.0 / row[0];
    let ids: Vec<u32> = row.iter().map(|x| (x * scale).round() as u32).collect();
    assert_eq!((ids[0], ids[7]), (101, 102), "{ids:?}");
    assert!(ids.iter().all(|&i| i != 0), "{ids:?}");
}
