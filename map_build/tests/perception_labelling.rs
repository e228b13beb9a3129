//! Eq. 2: numpy.unique semantics, scores and their order, every drop reason, label
//! map validation, and agreement with a straightforward reference on random inputs.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::collections::BTreeMap;

use map_build::perception::{
    eq2_scores, label_masks, unique_labels, DropReason, LabelConfig, LabelMap, LabelScore, Mask,
    PerceptionError,
};
use map_core::{Cell, Grid};
use proptest::prelude::*;

fn cats(n: usize) -> Vec<String> {
    (0..n).map(|i| format!("c{i}")).collect()
}

/// A label map from rows of digits.
fn labels(rows: &[&str]) -> Grid<u16> {
    let cols = rows[0].len();
    let data = rows
        .iter()
        .flat_map(|r| r.bytes().map(|b| u16::from(b - b'0')))
        .collect();
    Grid::from_vec(rows.len(), cols, data).unwrap()
}

fn mask(rows: &[&str]) -> Mask {
    let cols = rows[0].len();
    let data = rows
        .iter()
        .flat_map(|r| r.bytes().map(|b| b == b'#'))
        .collect();
    Mask::from_grid(&Grid::from_vec(rows.len(), cols, data).unwrap())
}

#[test]
fn unique_counts_and_scores_follow_numpy_and_eq2() {
    let map = LabelMap::new(labels(&["11220", "11223", "33333", "00000"]), cats(4)).unwrap();
    let m = mask(&["####.", "####.", "##...", "....."]);
    // labels under the mask: 1 1 2 2 / 1 1 2 2 / 3 3 -> sorted by label
    assert_eq!(
        unique_labels(&map, &m).unwrap(),
        vec![(1, 4), (2, 4), (3, 2)]
    );
    let s = eq2_scores(&[(1, 4), (2, 4), (3, 2)], 10);
    assert_eq!(
        s,
        vec![
            LabelScore {
                label: 1,
                count: 4,
                score: 0.4
            },
            LabelScore {
                label: 2,
                count: 4,
                score: 0.4
            },
            LabelScore {
                label: 3,
                count: 2,
                score: 0.2
            },
        ]
    );
    // ties keep the smaller label first; order is by count, not label
    let s = eq2_scores(&[(0, 1), (5, 3), (7, 3), (9, 2)], 9);
    assert_eq!(s.iter().map(|x| x.label).collect::<Vec<_>>(), [5, 7, 9, 0]);
    let total: f64 = s.iter().map(|x| x.score).sum();
    assert!((total - 1.0).abs() < 1e-12);
}

#[test]
fn masks_get_the_best_object_label_or_a_reason() {
    let map = LabelMap::new(
        labels(&[
            "1111000000",
            "1112000330",
            "1111000330",
            "0000000000",
            "4400000000",
            "0000005555",
        ]),
        cats(6),
    )
    .unwrap();
    let masks = vec![
        // 0: mostly 1 with a 2 -> label 1, score 11/12
        mask(&[
            "####......",
            "####......",
            "####......",
            "..........",
            "..........",
            "..........",
        ]),
        // 1: floor only -> no object label
        mask(&[
            "....###...",
            "....###...",
            "..........",
            "..........",
            "..........",
            "..........",
        ]),
        // 2: 3 covers 4 of 16 cells = 0.25 < 0.3 -> low score
        mask(&[
            "..........",
            ".....####.",
            ".....####.",
            ".....####.",
            ".....####.",
            "..........",
        ]),
        // 3: 3 cells < min_area 4 -> too small
        mask(&[
            "..........",
            "..........",
            "..........",
            "..........",
            "##........",
            "#.........",
        ]),
        // 4: background first (0.5), the object second (0.5 ties break to label 0),
        //    label 5 still in the top 3 -> kept with score 0.5
        mask(&[
            "..........",
            "..........",
            "..........",
            "..........",
            "......####",
            "......####",
        ]),
        // 5: empty
        Mask::empty(6, 10),
    ];
    let cfg = LabelConfig::default();
    assert_eq!((cfg.top_k, cfg.min_score, cfg.min_area), (3, 0.3, 4));
    let out = label_masks(&map, &masks, &cfg).unwrap();
    assert_eq!(out.kept.iter().map(|k| k.mask).collect::<Vec<_>>(), [0, 4]);
    let k0 = &out.kept[0];
    assert_eq!((k0.label, k0.area), (1, 12));
    assert!((k0.score - 11.0 / 12.0).abs() < 1e-12);
    assert_eq!(k0.top_k.len(), 2);
    let k4 = &out.kept[1];
    assert_eq!((k4.label, k4.score), (5, 0.5));
    assert_eq!(k4.top_k[0].label, 0);

    let reasons: Vec<(usize, &DropReason)> =
        out.dropped.iter().map(|d| (d.mask, &d.reason)).collect();
    assert!(matches!(
        reasons[0],
        (
            1,
            DropReason::NoObjectLabel {
                best: Some(LabelScore {
                    label: 0,
                    count: 6,
                    ..
                })
            }
        )
    ));
    assert!(matches!(
        reasons[1],
        (
            2,
            DropReason::LowScore {
                best: LabelScore {
                    label: 3,
                    count: 4,
                    ..
                },
                ..
            }
        )
    ));
    assert!(matches!(
        reasons[2],
        (
            3,
            DropReason::TooSmall {
                area: 3,
                min_area: 4
            }
        )
    ));
    assert!(matches!(
        reasons[3],
        (5, DropReason::TooSmall { area: 0, .. })
    ));
    assert_eq!(
        out.dropped[1].reason.to_string(),
        "low score: best object label 3 covers 0.250, below 0.3"
    );

    // top_k = 1: mask 4's best label is background, so it is dropped
    let k1 = LabelConfig {
        top_k: 1,
        ..LabelConfig::default()
    };
    let out = label_masks(&map, &masks, &k1).unwrap();
    assert!(out
        .dropped
        .iter()
        .any(|d| d.mask == 4 && matches!(d.reason, DropReason::NoObjectLabel { .. })));
    // no background at all: the floor mask is labelled "c0" with score 1
    let nobg = LabelConfig {
        background: vec![],
        ..LabelConfig::default()
    };
    let out = label_masks(&map, &masks, &nobg).unwrap();
    let floor = out.kept.iter().find(|k| k.mask == 1).unwrap();
    assert_eq!((floor.label, floor.score), (0, 1.0));
}

#[test]
fn label_maps_and_masks_are_checked() {
    let e = LabelMap::new(labels(&["012", "340"]), cats(4)).unwrap_err();
    assert!(matches!(
        e,
        PerceptionError::LabelOutOfRange { value: 4, .. }
    ));
    assert_eq!(
        e.to_string(),
        "label map: cell (row 1, col 1) holds label 4, but there are only 4 categories (labels 0..4)"
    );
    let map = LabelMap::new(labels(&["012", "320"]), cats(4)).unwrap();
    assert_eq!(map.name(2), Some("c2"));
    assert_eq!(map.label_of("c3"), Some(3));
    let masks = vec![Mask::empty(2, 3), Mask::empty(3, 2)];
    let e = label_masks(&map, &masks, &LabelConfig::default()).unwrap_err();
    assert_eq!(e.to_string(), "mask 1 is 3x2, but the map frame is 2x3");
}

/// (label, score, top k (label, count)) of a kept mask.
type Decision = (u16, f64, Vec<(u16, u64)>);

/// Eq. 2 written the obvious way, cell by cell, as the check.
fn reference(labels: &Grid<u16>, m: &Mask, cfg: &LabelConfig) -> Result<Decision, &'static str> {
    let mut counts: BTreeMap<u16, u64> = BTreeMap::new();
    let mut area = 0u64;
    for r in 0..labels.rows() {
        for c in 0..labels.cols() {
            if m.contains(Cell::new(r, c)) {
                *counts
                    .entry(*labels.get(Cell::new(r, c)).unwrap())
                    .or_default() += 1;
                area += 1;
            }
        }
    }
    if area < cfg.min_area || area == 0 {
        return Err("small");
    }
    let mut v: Vec<(u16, u64)> = counts.into_iter().collect();
    v.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    v.truncate(cfg.top_k);
    let best = v
        .iter()
        .find(|(l, _)| !cfg.background.contains(l))
        .ok_or("bg")?;
    let score = best.1 as f64 / area as f64;
    if score < cfg.min_score {
        return Err("low");
    }
    Ok((best.0, score, v))
}

proptest! {
    #[test]
    fn agrees_with_a_cell_by_cell_reference(
        rows in 1usize..14,
        cols in 1usize..14,
        ncat in 1usize..6,
        cells in proptest::collection::vec(0u16..6, 196),
        masks in proptest::collection::vec(proptest::collection::vec(any::<bool>(), 196), 1..6),
        top_k in 1usize..4,
        min_score in 0.0f64..0.8,
    ) {
        let n = rows * cols;
        let data: Vec<u16> = cells[..n].iter().map(|&v| v % ncat as u16).collect();
        let grid = Grid::from_vec(rows, cols, data).unwrap();
        let map = LabelMap::new(grid.clone(), cats(ncat)).unwrap();
        let ms: Vec<Mask> = masks
            .iter()
            .map(|b| Mask::from_grid(&Grid::from_vec(rows, cols, b[..n].to_vec()).unwrap()))
            .collect();
        let cfg = LabelConfig { top_k, min_score, min_area: 2, ..LabelConfig::default() };
        let out = label_masks(&map, &ms, &cfg).unwrap();
        prop_assert_eq!(out.kept.len() + out.dropped.len(), ms.len());
        for (i, m) in ms.iter().enumerate() {
            let want = reference(&grid, m, &cfg);
            match (out.kept.iter().find(|k| k.mask == i), want) {
                (Some(k), Ok((label, score, top))) => {
                    prop_assert_eq!(k.label, label);
                    prop_assert_eq!(k.score, score);
                    let got: Vec<(u16, u64)> = k.top_k.iter().map(|s| (s.label, s.count)).collect();
                    prop_assert_eq!(got, top);
                }
                (None, Err(why)) => {
                    let d = out.dropped.iter().find(|d| d.mask == i).unwrap();
                    let ok = matches!(
                        (&d.reason, why),
                        (DropReason::TooSmall { .. }, "small")
                            | (DropReason::NoObjectLabel { .. }, "bg")
                            | (DropReason::LowScore { .. }, "low")
                    );
                    prop_assert!(ok, "{:?} vs {}", d.reason, why);
                }
                (k, w) => prop_assert!(false, "mask {}: {:?} vs {:?}", i, k, w),
            }
        }
    }
}
