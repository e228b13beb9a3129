//! Eq. 2 benchmark, Rust side (the numpy side is `bench/eq2_numpy.py`; run both
//! with `bench/eq2_compare.sh`).
//!
//! ```text
//! eq2_bench gen DIR [--seed N] [--size N] [--masks N]
//!     writes DIR/labels.npy (u16 label map, 1000 x 1000 by default),
//!            DIR/masks.json (SAM output, compressed COCO RLE, 200 masks),
//!            DIR/config.json (categories and the Eq. 2 thresholds)
//! eq2_bench run DIR [--reps N] [--numpy DIR/numpy_result.json]
//!     times label_masks on the decoded masks (median of N runs after a warm-up),
//!     writes DIR/rust_result.json, and with --numpy checks that both sides give the
//!     same label, score and top k for every mask and prints the times side by side
//! ```
//!
//! The scene: a label map of 180 objects (rectangles and ellipses of 22 categories)
//! on background label 0, walls (label 1) around rooms, and 15% of the cells
//! relabelled at random (LSeg's noise); masks as SAM gives them: one per object with
//! a ragged margin, parts of objects, large regions holding many objects, and
//! patches of bare floor.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use map_build::perception::{
    label_masks, read_sam_masks, write_sam_masks, DropReason, LabelConfig, LabelMap, Labelling,
    Mask, SamMask, SegmentationForm,
};
use map_core::npy::{read_npy, write_npy};
use map_core::{Cell, Grid};
use serde::{Deserialize, Serialize};

/// SplitMix64: deterministic inputs from a seed (bench input generation only).
struct Rng(u64);
impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn f(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: i64, hi: i64) -> i64 {
        lo + (self.next_u64() % (hi - lo) as u64) as i64
    }
}

#[derive(Serialize, Deserialize)]
struct BenchConfig {
    rows: usize,
    cols: usize,
    categories: Vec<String>,
    background: Vec<u16>,
    top_k: usize,
    min_score: f64,
    min_area: u64,
}

impl BenchConfig {
    fn label_config(&self) -> LabelConfig {
        LabelConfig {
            background: self.background.clone(),
            top_k: self.top_k,
            min_score: self.min_score,
            min_area: self.min_area,
        }
    }
}

#[derive(Serialize, Deserialize, PartialEq, Debug, Clone)]
struct MaskResult {
    mask: usize,
    area: u64,
    /// "kept", "TooSmall", "NoObjectLabel" or "LowScore".
    outcome: String,
    label: Option<u16>,
    score: Option<f64>,
    /// [label, count] pairs, best first.
    top_k: Vec<(u16, u64)>,
}

#[derive(Serialize, Deserialize)]
struct ResultFile {
    results: Vec<MaskResult>,
    /// Named timings in milliseconds (medians).
    times_ms: std::collections::BTreeMap<String, f64>,
    #[serde(default)]
    reps: usize,
}

/// Eq. 2 labelling benchmark inputs and runs.
#[derive(Debug, clap::Parser)]
enum Cmd {
    /// Write a synthetic label map and masks into DIR.
    Gen {
        dir: PathBuf,
        #[arg(long, default_value_t = 7)]
        seed: u64,
        #[arg(long, default_value_t = 1000)]
        size: usize,
        #[arg(long = "masks", default_value_t = 200)]
        n_masks: usize,
    },
    /// Label DIR's masks, write DIR/rust_result.json, and compare with numpy's result.
    Run {
        dir: PathBuf,
        #[arg(long, default_value_t = 21)]
        reps: usize,
        #[arg(long)]
        numpy: Option<PathBuf>,
    },
}

fn main() {
    match clap::Parser::parse() {
        Cmd::Gen {
            dir,
            seed,
            size,
            n_masks,
        } => generate(&dir, seed, size, n_masks),
        Cmd::Run { dir, reps, numpy } => run(&dir, reps, numpy),
    }
}

#[derive(Clone, Copy)]
struct Shape {
    r0: i64,
    c0: i64,
    h: i64,
    w: i64,
    ellipse: bool,
}

impl Shape {
    fn contains(&self, r: i64, c: i64) -> bool {
        if r < self.r0 || c < self.c0 || r >= self.r0 + self.h || c >= self.c0 + self.w {
            return false;
        }
        if !self.ellipse {
            return true;
        }
        let (cy, cx) = (
            self.r0 as f64 + self.h as f64 / 2.0,
            self.c0 as f64 + self.w as f64 / 2.0,
        );
        let (dy, dx) = (
            (r as f64 + 0.5 - cy) / (self.h as f64 / 2.0),
            (c as f64 + 0.5 - cx) / (self.w as f64 / 2.0),
        );
        dy * dy + dx * dx <= 1.0
    }
    fn grown(&self, by: i64) -> Shape {
        Shape {
            r0: self.r0 - by,
            c0: self.c0 - by,
            h: self.h + 2 * by,
            w: self.w + 2 * by,
            ..*self
        }
    }
    fn cells(&self, n: usize) -> impl Iterator<Item = Cell> + '_ {
        let n = n as i64;
        (self.r0.max(0)..(self.r0 + self.h).min(n)).flat_map(move |r| {
            (self.c0.max(0)..(self.c0 + self.w).min(n))
                .filter(move |&c| self.contains(r, c))
                .map(move |c| Cell::new(r as usize, c as usize))
        })
    }
}

fn generate(dir: &Path, seed: u64, n: usize, n_masks: usize) {
    std::fs::create_dir_all(dir).unwrap();
    let mut rng = Rng(seed);
    let mut categories = vec!["other".to_string(), "wall".to_string()];
    for name in [
        "chair", "table", "sofa", "bed", "cabinet", "shelf", "tv", "plant", "lamp", "sink",
        "toilet", "bathtub", "counter", "stool", "desk", "armchair", "fridge", "oven", "bench",
        "piano", "rug", "box",
    ] {
        categories.push(name.to_string());
    }
    let ncat = categories.len() as u16;
    let mut labels = Grid::new(n, n, 0u16);
    // walls: a 4 x 4 grid of rooms, 3 cells thick
    let room = n / 4;
    for k in 0..=4 {
        let at = (k * room).min(n - 3);
        for t in 0..3 {
            for i in 0..n {
                labels.set(Cell::new(at + t, i), 1);
                labels.set(Cell::new(i, at + t), 1);
            }
        }
    }
    // objects
    let mut objects: Vec<(Shape, u16)> = Vec::new();
    while objects.len() < 180 {
        let h = rng.range(10, 80);
        let w = rng.range(10, 80);
        let s = Shape {
            r0: rng.range(5, n as i64 - h - 5),
            c0: rng.range(5, n as i64 - w - 5),
            h,
            w,
            ellipse: rng.f() < 0.4,
        };
        let overlaps = objects.iter().any(|(o, _)| {
            s.r0 < o.r0 + o.h + 2
                && o.r0 < s.r0 + s.h + 2
                && s.c0 < o.c0 + o.w + 2
                && o.c0 < s.c0 + s.w + 2
        });
        if overlaps {
            continue;
        }
        let label = rng.range(2, i64::from(ncat)) as u16;
        for c in s.cells(n) {
            labels.set(c, label);
        }
        objects.push((s, label));
    }
    // LSeg noise: 15% of cells get a random label
    for v in labels.as_mut_slice() {
        if rng.f() < 0.15 {
            *v = rng.range(0, i64::from(ncat)) as u16;
        }
    }
    write_npy(dir.join("labels.npy"), &labels).unwrap();

    // masks
    let mut masks: Vec<Mask> = Vec::new();
    let ragged = |rng: &mut Rng, s: &Shape| -> Mask {
        // the object grown by 0..3 cells, with a few cells of the rim dropped
        let g = s.grown(rng.range(0, 4));
        let keep: Vec<Cell> = g
            .cells(n)
            .filter(|c| {
                let inner = s.contains(c.row as i64, c.col as i64);
                inner || rng.f() < 0.7
            })
            .collect();
        Mask::from_cells(n, n, keep)
    };
    for (s, _) in objects.iter().take(150) {
        masks.push(ragged(&mut rng, s));
    }
    for (s, _) in objects.iter().skip(150).take(20) {
        // a part: the northern or western half
        let part = if rng.f() < 0.5 {
            Shape { h: s.h / 2, ..*s }
        } else {
            Shape { w: s.w / 2, ..*s }
        };
        masks.push(Mask::from_cells(n, n, part.cells(n)));
    }
    for _ in 0..15 {
        // a region: a large rectangle or ellipse holding several objects
        let h = rng.range(100, 400);
        let w = rng.range(100, 400);
        let s = Shape {
            r0: rng.range(0, n as i64 - h),
            c0: rng.range(0, n as i64 - w),
            h,
            w,
            ellipse: rng.f() < 0.5,
        };
        masks.push(Mask::from_cells(n, n, s.cells(n)));
    }
    while masks.len() < n_masks {
        // bare floor, or a speck
        let (h, w) = if rng.f() < 0.3 {
            (1, rng.range(1, 4))
        } else {
            (rng.range(8, 40), rng.range(8, 40))
        };
        let s = Shape {
            r0: rng.range(0, n as i64 - h),
            c0: rng.range(0, n as i64 - w),
            h,
            w,
            ellipse: false,
        };
        masks.push(Mask::from_cells(n, n, s.cells(n)));
    }
    masks.truncate(n_masks);
    let sam: Vec<SamMask> = masks
        .into_iter()
        .enumerate()
        .map(|(i, m)| SamMask {
            predicted_iou: Some(0.9 + 0.0001 * i as f64),
            stability_score: Some(0.95),
            crop_box: Some([0.0, 0.0, n as f64, n as f64]),
            ..SamMask::from_mask(m)
        })
        .collect();
    write_sam_masks(
        dir.join("masks.json"),
        &sam,
        SegmentationForm::CompressedRle,
    )
    .unwrap();
    let cfg = LabelConfig::default();
    let bc = BenchConfig {
        rows: n,
        cols: n,
        categories,
        background: cfg.background,
        top_k: cfg.top_k,
        min_score: cfg.min_score,
        min_area: cfg.min_area,
    };
    std::fs::write(
        dir.join("config.json"),
        serde_json::to_string_pretty(&bc).unwrap(),
    )
    .unwrap();
    let total: u64 = sam.iter().map(|m| m.segmentation.area()).sum();
    println!(
        "wrote {}: labels {n}x{n}, {} masks ({} pixels in all, largest {})",
        dir.display(),
        sam.len(),
        total,
        sam.iter().map(|m| m.segmentation.area()).max().unwrap_or(0)
    );
}

fn results_of(l: &Labelling, masks: &[Mask]) -> Vec<MaskResult> {
    let mut out: Vec<MaskResult> = Vec::new();
    for k in &l.kept {
        out.push(MaskResult {
            mask: k.mask,
            area: k.area,
            outcome: "kept".into(),
            label: Some(k.label),
            score: Some(k.score),
            top_k: k.top_k.iter().map(|s| (s.label, s.count)).collect(),
        });
    }
    for d in &l.dropped {
        let (outcome, label, score) = match &d.reason {
            DropReason::TooSmall { .. } => ("TooSmall", None, None),
            DropReason::NoObjectLabel { .. } => ("NoObjectLabel", None, None),
            DropReason::LowScore { best, .. } => ("LowScore", Some(best.label), Some(best.score)),
            DropReason::Covered { .. } => ("Covered", None, None),
        };
        out.push(MaskResult {
            mask: d.mask,
            area: masks[d.mask].area(),
            outcome: outcome.into(),
            label,
            score,
            top_k: Vec::new(),
        });
    }
    out.sort_by_key(|r| r.mask);
    out
}

fn median(mut v: Vec<Duration>) -> f64 {
    v.sort();
    v[v.len() / 2].as_secs_f64() * 1e3
}

fn run(dir: &Path, reps: usize, numpy: Option<PathBuf>) {
    let cfg: BenchConfig =
        serde_json::from_str(&std::fs::read_to_string(dir.join("config.json")).unwrap()).unwrap();
    let t = Instant::now();
    let labels: Grid<u16> = read_npy(dir.join("labels.npy")).unwrap();
    let load_labels = t.elapsed();
    let t = Instant::now();
    let sam = read_sam_masks(dir.join("masks.json")).unwrap();
    let decode = t.elapsed();
    let masks: Vec<Mask> = sam.into_iter().map(|m| m.segmentation).collect();
    let map = LabelMap::new(labels, cfg.categories.clone()).unwrap();
    let lc = cfg.label_config();

    // warm-up, then the median of `reps` runs
    let first = label_masks(&map, &masks, &lc).unwrap();
    let mut times = Vec::with_capacity(reps);
    for _ in 0..reps {
        let t = Instant::now();
        let l = label_masks(&map, &masks, &lc).unwrap();
        times.push(t.elapsed());
        assert_eq!(l, first);
    }
    let eq2 = median(times);

    // the same from dense boolean masks (numpy's input form): runs extraction included
    let dense: Vec<Grid<bool>> = masks.iter().map(Mask::to_grid).collect();
    let mut times = Vec::with_capacity(reps.min(7));
    for _ in 0..reps.min(7) {
        let t = Instant::now();
        let ms: Vec<Mask> = dense.iter().map(Mask::from_grid).collect();
        let l = label_masks(&map, &ms, &lc).unwrap();
        times.push(t.elapsed());
        assert_eq!(l, first);
    }
    let eq2_dense = median(times);
    drop(dense);

    let results = results_of(&first, &masks);
    let mut times_ms = std::collections::BTreeMap::new();
    times_ms.insert("eq2".to_string(), eq2);
    times_ms.insert("eq2_from_dense".to_string(), eq2_dense);
    times_ms.insert("decode_masks_json".to_string(), decode.as_secs_f64() * 1e3);
    times_ms.insert(
        "read_labels_npy".to_string(),
        load_labels.as_secs_f64() * 1e3,
    );
    let out = ResultFile {
        results: results.clone(),
        times_ms,
        reps,
    };
    std::fs::write(
        dir.join("rust_result.json"),
        serde_json::to_string(&out).unwrap(),
    )
    .unwrap();

    let kept = results.iter().filter(|r| r.outcome == "kept").count();
    let total_px: u64 = masks.iter().map(Mask::area).sum();
    println!(
        "Eq. 2 on a {}x{} label map, {} masks ({} mask pixels), {} kept; median of {reps} runs",
        cfg.rows,
        cfg.cols,
        masks.len(),
        total_px,
        kept
    );
    println!("rust  label_masks (masks as runs)           {eq2:10.3} ms");
    println!("rust  dense bool masks -> runs + label_masks {eq2_dense:9.3} ms");
    println!(
        "rust  decode masks.json (compressed RLE)     {:9.3} ms",
        decode.as_secs_f64() * 1e3
    );

    let Some(np) = numpy else {
        return;
    };
    let theirs: ResultFile = serde_json::from_str(&std::fs::read_to_string(&np).unwrap()).unwrap();
    let mut same = 0;
    let mut diffs = Vec::new();
    for (a, b) in results.iter().zip(&theirs.results) {
        if a == b {
            same += 1;
        } else {
            diffs.push((a.clone(), b.clone()));
        }
    }
    let t = &theirs.times_ms;
    let full = t["eq2_full_frame"];
    let crop = t["eq2_bbox_crop"];
    println!(
        "numpy full-frame boolean masks (paper style) {full:9.3} ms   rust is {:6.1}x faster",
        full / eq2
    );
    println!(
        "numpy bbox-cropped boolean masks             {crop:9.3} ms   rust is {:6.1}x faster",
        crop / eq2
    );
    if let Some(d) = t.get("decode_masks_json") {
        println!(
            "numpy decode masks.json                      {d:9.3} ms ({})",
            if t.contains_key("pycocotools") {
                "pycocotools"
            } else {
                "pure-Python RLE strings + np.repeat"
            }
        );
    }
    println!(
        "results identical for {same}/{} masks (label, score bit-for-bit, top {} counts, outcome)",
        results.len(),
        cfg.top_k
    );
    if !diffs.is_empty() || theirs.results.len() != results.len() {
        for (a, b) in diffs.iter().take(5) {
            eprintln!("rust  {a:?}\nnumpy {b:?}");
        }
        eprintln!("MISMATCH");
        std::process::exit(1);
    }
    if full / eq2 < 10.0 {
        eprintln!("note: below the 10x goal against numpy's full-frame masks");
    }
}
