//! Planner benchmarks on the fixed 1000 x 1000 map of shared/bench (0.05 m cells,
//! already inflated) and its 50 start/goal pairs. Before timing, setup checks the
//! answers: the jump point search cost equals a Dijkstra optimum on a sample of
//! pairs, every path stays off obstacles, and the total smoothed length is at most 3%
//! above VLMaps' visibility-graph paths (each pair at most 5%) (bench/vlmaps_reference.json).

// A benchmark with a missing fixture or a wrong answer must stop loudly.
#![allow(clippy::expect_used, clippy::unwrap_used, clippy::panic)]

use std::hint::black_box;
use std::path::{Path, PathBuf};

use criterion::{criterion_group, criterion_main, Criterion};
use map_core::npy::read_npy;
use map_core::planner::line_of_sight;
use map_core::{Cell, Grid, GridPlanner};

#[path = "../tests/common/reference.rs"]
#[allow(dead_code)] // the bench uses the optimum only
mod reference;

fn bench_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/bench")
}

type Fixture = (Grid<bool>, Vec<(Cell, Cell)>, Vec<f64>, f64);

fn load() -> Fixture {
    let grid: Grid<u8> = read_npy(bench_dir().join("grid.npy")).expect("shared/bench/grid.npy");
    let q: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(bench_dir().join("queries.json")).expect("queries.json"),
    )
    .expect("queries.json is JSON");
    let cell = |v: &serde_json::Value| {
        Cell::new(
            v[0].as_u64().expect("row") as usize,
            v[1].as_u64().expect("col") as usize,
        )
    };
    let pairs = q["pairs"]
        .as_array()
        .expect("pairs")
        .iter()
        .map(|p| (cell(&p["start"]), cell(&p["goal"])))
        .collect();
    let cell_size = q["cell_size_m"].as_f64().unwrap_or(0.05);
    let reference: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../bench/vlmaps_reference.json"),
        )
        .expect("bench/vlmaps_reference.json"),
    )
    .expect("reference is JSON");
    let vl = reference["lengths_m"]
        .as_array()
        .expect("lengths_m")
        .iter()
        .map(|v| v.as_f64().expect("m"))
        .collect();
    (grid.map(|&v| v != 0), pairs, vl, cell_size)
}

fn check_answers(
    grid: &Grid<bool>,
    planner: &GridPlanner,
    pairs: &[(Cell, Cell)],
    vl: &[f64],
    cell_size: f64,
) {
    assert_eq!(
        pairs.len(),
        vl.len(),
        "reference lengths do not match the pairs"
    );
    let (mut ours, mut theirs) = (0.0, 0.0);
    for (k, (&(s, t), &v)) in pairs.iter().zip(vl).enumerate() {
        let p = planner.plan(s, t).expect("every bench pair is reachable");
        for w in p.waypoints.windows(2) {
            assert!(
                line_of_sight(grid, w[0], w[1]),
                "pair {k}: segment {w:?} crosses an obstacle"
            );
        }
        let len_m = p.smoothed_len * cell_size;
        // per pair a little slack: the octile-optimal grid path can lie in another
        // homotopy class than the Euclidean one; the 3% goal holds for the total
        assert!(
            len_m <= v * 1.05,
            "pair {k}: {len_m:.3} m > 1.05 x VLMaps {v:.3} m"
        );
        assert!(p.smoothed_len <= p.raw_len + 1e-9);
        if k % 10 == 0 {
            let opt = reference::dijkstra(grid, s, t).unwrap_or(f64::INFINITY);
            assert!(
                (p.raw_len - opt).abs() < 1e-6 * opt.max(1.0),
                "pair {k}: JPS {} != Dijkstra {opt}",
                p.raw_len
            );
        }
        ours += len_m;
        theirs += v;
    }
    assert!(
        ours <= theirs * 1.03,
        "total {ours:.2} m > 1.03 x VLMaps {theirs:.2} m"
    );
    eprintln!(
        "checked: total {ours:.2} m vs VLMaps {theirs:.2} m (ratio {:.4})",
        ours / theirs
    );
}

fn benches(c: &mut Criterion) {
    let (grid, pairs, vl, cell_size) = load();
    let planner = GridPlanner::new(grid.clone());
    check_answers(&grid, &planner, &pairs, &vl, cell_size);

    c.bench_function("grid_planner_new_1000x1000", |b| {
        b.iter(|| GridPlanner::new(black_box(grid.clone())))
    });
    c.bench_function("first_path_fresh_planner", |b| {
        b.iter(|| {
            let p = GridPlanner::new(black_box(grid.clone()));
            p.plan(pairs[0].0, pairs[0].1).map(|p| p.smoothed_len)
        })
    });
    let mut k = 0;
    c.bench_function("warm_query_round_robin_50_pairs", |b| {
        b.iter(|| {
            k = (k + 1) % pairs.len();
            planner
                .plan(black_box(pairs[k].0), black_box(pairs[k].1))
                .map(|p| p.smoothed_len)
        })
    });
    c.bench_function("all_50_queries", |b| {
        b.iter(|| {
            pairs
                .iter()
                .map(|&(s, t)| planner.plan(s, t).map(|p| p.smoothed_len).unwrap_or(0.0))
                .sum::<f64>()
        })
    });
}

criterion_group! {
    name = planner;
    config = Criterion::default().sample_size(20);
    targets = benches
}
criterion_main!(planner);
