#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! `P = Q E^T` labelling of a feature map with E given directly (no ONNX Runtime),
//! and reading 3-D feature `.npy` files.

use std::path::Path;
use std::time::Instant;

use map_build::embed::{label_cells, EmbedError, Embeddings, FeatureMap};
use npyz::WriterBuilder;

/// Hand-computed: E rows e1 = (1, 0), e2 = (0, 1), e3 = (0.6, 0.8).
#[test]
fn hand_computed_labels_and_scores() {
    let e = Embeddings::new(3, 2, vec![1.0, 0.0, 0.0, 1.0, 0.6, 0.8]).unwrap();
    #[rustfmt::skip]
    let q = FeatureMap::new(2, 3, 2, vec![
        2.0, 0.0,   // P = (2, 0, 1.2)      -> 1, 2
        0.0, 0.0,   // unobserved           -> 0, 0
        0.5, 1.0,   // P = (0.5, 1, 1.1)    -> 3, 1.1
        -1.0, -1.0, // P = (-1, -1, -1.4)   -> tie, the lower: 1, -1
        0.0, 3.0,   // P = (0, 3, 2.4)      -> 2, 3
        3.0, 4.0,   // P = (3, 4, 5)        -> 3, 5
    ]).unwrap();
    let out = label_cells(&q, &e).unwrap();
    assert_eq!((out.labels.rows(), out.labels.cols()), (2, 3));
    assert_eq!(out.labels.as_slice(), &[1, 0, 3, 1, 2, 3]);
    let want = [2.0, 0.0, 1.1, -1.0, 3.0, 5.0];
    for (i, (&got, &w)) in out.scores.as_slice().iter().zip(&want).enumerate() {
        assert!((got - w).abs() < 1e-6, "cell {i}: {got} vs {w}");
    }
}

#[test]
fn embeddings_normalized_gives_unit_rows() {
    let e = Embeddings::new(2, 2, vec![3.0, 4.0, 0.0, 0.0])
        .unwrap()
        .normalised();
    assert_eq!(e.row(0).unwrap(), &[0.6, 0.8]);
    assert_eq!(e.row(1).unwrap(), &[0.0, 0.0]);
}

/// A tiny deterministic generator (xorshift), so the test needs no rand crate.
fn noise(seed: &mut u64) -> f32 {
    *seed ^= *seed << 13;
    *seed ^= *seed >> 7;
    *seed ^= *seed << 17;
    ((*seed >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
}

/// Plain per-cell loop: the definition, to check the blocked matrix product against.
fn reference(q: &FeatureMap, e: &Embeddings) -> (Vec<u16>, Vec<f32>) {
    let (mut labels, mut scores) = (Vec::new(), Vec::new());
    for r in 0..q.rows() {
        for c in 0..q.cols() {
            let cell = q.cell(r, c).unwrap();
            if cell.iter().all(|&x| x == 0.0) {
                labels.push(0);
                scores.push(0.0);
                continue;
            }
            let mut best = (0usize, f32::NEG_INFINITY);
            for k in 0..e.len() {
                let s: f32 = cell.iter().zip(e.row(k).unwrap()).map(|(a, b)| a * b).sum();
                if s > best.1 {
                    best = (k, s);
                }
            }
            labels.push(best.0 as u16 + 1);
            scores.push(best.1);
        }
    }
    (labels, scores)
}

fn random_map(rows: usize, cols: usize, dim: usize, seed: &mut u64) -> FeatureMap {
    let mut data: Vec<f32> = (0..rows * cols * dim).map(|_| noise(seed)).collect();
    // every 7th cell unobserved
    for cell in (0..rows * cols).step_by(7) {
        data[cell * dim..(cell + 1) * dim].fill(0.0);
    }
    FeatureMap::new(rows, cols, dim, data).unwrap()
}

#[test]
fn blocked_product_matches_the_definition_across_blocks() {
    // 70 x 70 = 4,900 cells: more than one block of 4,096, and a partial last block.
    let mut seed = 0x9e37_79b9_7f4a_7c15;
    let q = random_map(70, 70, 24, &mut seed);
    let e = Embeddings::new(5, 24, (0..5 * 24).map(|_| noise(&mut seed)).collect())
        .unwrap()
        .normalised();
    let out = label_cells(&q, &e).unwrap();
    let (labels, scores) = reference(&q, &e);
    let mut differing = 0;
    for i in 0..labels.len() {
        assert!(
            (out.scores.as_slice()[i] - scores[i]).abs() < 1e-4,
            "cell {i}: {} vs {}",
            out.scores.as_slice()[i],
            scores[i]
        );
        // summation order may flip a near-tie; the score must agree either way
        if out.labels.as_slice()[i] != labels[i] {
            differing += 1;
        }
    }
    assert!(differing <= 2, "{differing} labels differ");
    assert_eq!(out.labels.as_slice()[0], 0);
    assert_eq!(out.labels.as_slice()[7 * 100], 0);
    assert!(out.labels.as_slice().iter().all(|&l| l <= 5));
}

#[test]
fn shapes_are_checked() {
    let e = Embeddings::new(2, 3, vec![0.0; 6]).unwrap();
    let q = FeatureMap::new(1, 2, 4, vec![1.0; 8]).unwrap();
    let err = label_cells(&q, &e).unwrap_err();
    assert!(
        matches!(
            err,
            EmbedError::DimMismatch {
                features: 4,
                embeddings: 3
            }
        ),
        "{err:?}"
    );
    assert!(FeatureMap::new(2, 2, 3, vec![0.0; 11]).is_err());
    assert!(Embeddings::new(2, 3, vec![0.0; 5]).is_err());
    let many = Embeddings::new(70_000, 1, vec![1.0; 70_000]).unwrap();
    let one = FeatureMap::new(1, 1, 1, vec![1.0]).unwrap();
    assert!(matches!(
        label_cells(&one, &many),
        Err(EmbedError::TooManyCategories { count: 70_000 })
    ));
    // no categories: every cell 0
    let none = Embeddings::new(0, 4, vec![]).unwrap();
    let out = label_cells(&q, &none).unwrap();
    assert_eq!(out.labels.as_slice(), &[0, 0]);
}

fn write_npy<T: npyz::AutoSerialize + Copy>(
    path: &Path,
    shape: &[u64],
    order: npyz::Order,
    data: &[T],
) {
    let file = std::fs::File::create(path).unwrap();
    let mut w = npyz::WriteOptions::new()
        .default_dtype()
        .shape(shape)
        .order(order)
        .writer(file)
        .begin_nd()
        .unwrap();
    w.extend(data.iter().copied()).unwrap();
    w.finish().unwrap();
}

#[test]
fn feature_npy_files_read_in_c_and_fortran_order() {
    let dir = tempfile::tempdir().unwrap();
    let (rows, cols, dim) = (2usize, 3usize, 4usize);
    let value = |r: usize, c: usize, k: usize| (100 * r + 10 * c + k) as f32;
    let c_order: Vec<f32> = (0..rows)
        .flat_map(|r| (0..cols).flat_map(move |c| (0..dim).map(move |k| value(r, c, k))))
        .collect();
    // Fortran order: first index fastest
    let f_order: Vec<f32> = (0..dim)
        .flat_map(|k| (0..cols).flat_map(move |c| (0..rows).map(move |r| value(r, c, k))))
        .collect();
    let shape = [rows as u64, cols as u64, dim as u64];
    let pc = dir.path().join("c.npy");
    let pf = dir.path().join("f.npy");
    let p64 = dir.path().join("f64.npy");
    write_npy(&pc, &shape, npyz::Order::C, &c_order);
    write_npy(&pf, &shape, npyz::Order::Fortran, &f_order);
    let as_f64: Vec<f64> = c_order.iter().map(|&x| f64::from(x)).collect();
    write_npy(&p64, &shape, npyz::Order::C, &as_f64);
    let a = FeatureMap::read_npy(&pc).unwrap();
    let b = FeatureMap::read_npy(&pf).unwrap();
    let c = FeatureMap::read_npy(&p64).unwrap();
    assert_eq!((a.rows(), a.cols(), a.dim()), (rows, cols, dim));
    assert_eq!(a.as_slice(), c_order.as_slice());
    assert_eq!(a, b);
    assert_eq!(a, c);
    assert_eq!(a.cell(1, 2).unwrap(), &[120.0, 121.0, 122.0, 123.0]);
    assert!(a.cell(2, 0).is_none());
}

#[test]
fn bad_feature_files_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let two_d = dir.path().join("two_d.npy");
    write_npy(&two_d, &[2, 2], npyz::Order::C, &[1.0f32, 2.0, 3.0, 4.0]);
    let ints = dir.path().join("ints.npy");
    write_npy(&ints, &[1, 1, 2], npyz::Order::C, &[1i32, 2]);
    let cut = dir.path().join("cut.npy");
    write_npy(&cut, &[2, 2, 8], npyz::Order::C, &[0.5f32; 32]);
    let bytes = std::fs::read(&cut).unwrap();
    std::fs::write(&cut, &bytes[..bytes.len() - 20]).unwrap();
    for (p, what) in [
        (&two_d, "3-D"),
        (&ints, "<i4"),
        (&cut, ""),
        (&dir.path().join("absent.npy"), ""),
    ] {
        let err = FeatureMap::read_npy(p).unwrap_err();
        let msg = err.to_string();
        assert!(matches!(err, EmbedError::FeatureFile { .. }), "{err:?}");
        assert!(
            msg.contains(&*p.to_string_lossy()) && msg.contains(what),
            "{msg}"
        );
    }
}

/// Timing of the blocked product against the plain loop on a VLMaps-sized block
/// (`cargo test --release -p map_core --test embed_label -- --ignored --nocapture`).
#[test]
#[ignore]
fn timing_blocked_product_vs_loop() {
    let mut seed = 42;
    let (rows, cols, dim, cats) = (300, 300, 512, 20);
    let q = random_map(rows, cols, dim, &mut seed);
    let e = Embeddings::new(
        cats,
        dim,
        (0..cats * dim).map(|_| noise(&mut seed)).collect(),
    )
    .unwrap()
    .normalised();
    let t = Instant::now();
    let out = label_cells(&q, &e).unwrap();
    let blocked = t.elapsed();
    let t = Instant::now();
    let (labels, _) = reference(&q, &e);
    let plain = t.elapsed();
    let same = labels
        .iter()
        .zip(out.labels.as_slice())
        .filter(|(a, b)| a == b)
        .count();
    println!(
        "{rows}x{cols} cells x {dim}-d x {cats} categories: blocked {:.0} ms, plain loop {:.0} ms ({same} of {} labels agree)",
        blocked.as_secs_f64() * 1e3,
        plain.as_secs_f64() * 1e3,
        labels.len()
    );
}
