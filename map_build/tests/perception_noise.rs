#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! Simulated perception noise on the example scenes: each kind does what it says,
//! at the rate it is given, reproducibly, and the map built from the result shows it.

use std::path::Path;

use map_build::perception::{
    build_map, BuildConfig, NoiseError, PerceptionInputs, PerceptionNoise,
};
use map_core::{IvlMap, Scene};

fn scene(name: &str) -> Scene {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../examples/scenes")
        .join(format!("{name}.scene.json"));
    Scene::from_path(p).unwrap()
}

fn only(kind: &str, rate: f64, seed: u64) -> PerceptionNoise {
    let mut n = PerceptionNoise::none(seed);
    match kind {
        "label_flip" => n.label_flip = rate,
        "fragment" => n.fragment = rate,
        "merge" => n.merge = rate,
        "drop" => n.drop = rate,
        "colour_shift" => n.colour_shift = rate,
        _ => panic!("{kind}"),
    }
    n
}

#[test]
fn zero_rates_change_nothing_and_seeds_reproduce() {
    let clean = PerceptionInputs::from_scene(&scene("flat-a"));
    let (same, log) = clean.with_noise(&PerceptionNoise::none(3)).unwrap();
    assert_eq!(same, clean);
    assert_eq!(log.flipped_cells, 0);
    assert!(log.dropped.is_empty() && log.merged.is_empty() && log.fragmented.is_empty());

    let a = clean
        .with_noise(&PerceptionNoise::uniform(0.2, 11))
        .unwrap();
    let b = clean
        .with_noise(&PerceptionNoise::uniform(0.2, 11))
        .unwrap();
    let c = clean
        .with_noise(&PerceptionNoise::uniform(0.2, 12))
        .unwrap();
    assert_eq!(a, b);
    assert_ne!(a.0, c.0);
}

#[test]
fn drop_removes_rate_times_n_masks_and_the_map_loses_them() {
    let clean = PerceptionInputs::from_scene(&scene("office-b"));
    let n = clean.masks.len();
    assert_eq!(n, 30);
    let (noisy, log) = clean.with_noise(&only("drop", 0.2, 5)).unwrap();
    assert_eq!(log.dropped.len(), 6);
    assert_eq!(noisy.masks.len(), n - 6);
    let built = build_map(&noisy, &BuildConfig::default()).unwrap();
    assert_eq!(built.map.instances.len(), n - 6);
    // The surviving masks are the others, in order.
    let kept: Vec<usize> = (0..n).filter(|i| !log.dropped.contains(i)).collect();
    for (out, &i) in noisy.masks.iter().zip(&kept) {
        assert_eq!(*out, clean.masks[i]);
    }
    // A higher rate with the same seed drops a superset.
    let (_, more) = clean.with_noise(&only("drop", 0.4, 5)).unwrap();
    assert!(log.dropped.iter().all(|i| more.dropped.contains(i)));
    assert_eq!(more.dropped.len(), 12);

    // 0.05 of 30 masks is 1.5: 1 or 2, 1.5 on average over seeds.
    let counts: Vec<usize> = (0..200)
        .map(|seed| {
            clean
                .with_noise(&only("drop", 0.05, seed))
                .unwrap()
                .1
                .dropped
                .len()
        })
        .collect();
    assert!(counts.iter().all(|&c| c == 1 || c == 2));
    let mean = counts.iter().sum::<usize>() as f64 / counts.len() as f64;
    assert!((mean - 1.5).abs() < 0.15, "{mean}");
}

#[test]
fn merge_joins_same_category_neighbours_within_the_radius() {
    let s = scene("office-b");
    let clean = PerceptionInputs::from_scene(&s);
    let (noisy, log) = clean.with_noise(&only("merge", 0.3, 2)).unwrap();
    assert!(!log.merged.is_empty());
    assert_eq!(noisy.masks.len(), clean.masks.len() - log.merged.len());
    let truth = IvlMap::from_scene(&s);
    for &(i, j) in &log.merged {
        let (a, b) = (&s.objects[i], &s.objects[j]);
        assert_eq!(a.category, b.category);
        let (pa, pb) = (
            truth.instance_by_id(a.id.0).unwrap().centroid,
            truth.instance_by_id(b.id.0).unwrap().centroid,
        );
        assert!(pa.dist(pb) <= 2.5 + 0.05, "{} {}", a.id.0, b.id.0);
        // The merged mask holds both objects' cells.
        let k = i
            - (0..i)
                .filter(|&x| log.merged.iter().any(|m| m.1 == x))
                .count();
        let m = &noisy.masks[k];
        assert_eq!(m.area(), clean.masks[i].area() + clean.masks[j].area());
    }
    let built = build_map(&noisy, &BuildConfig::default()).unwrap();
    assert_eq!(built.map.instances.len(), noisy.masks.len());
}

#[test]
fn fragment_splits_masks_in_two_and_both_parts_become_instances() {
    let clean = PerceptionInputs::from_scene(&scene("house-c"));
    let n = clean.masks.len();
    let (noisy, log) = clean.with_noise(&only("fragment", 0.1, 9)).unwrap();
    let want = 0.1 * n as f64;
    let got = log.fragmented.len() as f64;
    assert!(got == want.floor() || got == want.ceil(), "{got} of {want}");
    assert_eq!(noisy.masks.len(), n + log.fragmented.len());
    for (k, &i) in log.fragmented.iter().enumerate() {
        let (near, far) = (&noisy.masks[i], &noisy.masks[n + k]);
        assert_eq!(near.area() + far.area(), clean.masks[i].area());
        assert!(near.area() > 0 && far.area() > 0);
        assert!(near.intersection(far).is_empty());
    }
    let built = build_map(&noisy, &BuildConfig::default()).unwrap();
    assert_eq!(built.map.instances.len(), noisy.masks.len());
}

#[test]
fn label_flips_hit_the_rate_and_eq2_outvotes_them() {
    let s = scene("flat-a");
    let clean = PerceptionInputs::from_scene(&s);
    let object_cells = clean
        .labels
        .labels()
        .as_slice()
        .iter()
        .filter(|&&v| v != 0)
        .count() as f64;
    let (noisy, log) = clean.with_noise(&only("label_flip", 0.3, 4)).unwrap();
    let share = log.flipped_cells as f64 / object_cells;
    assert!((share - 0.3).abs() < 0.02, "{share}");
    // Each object label flips to one partner, never to itself or the background.
    for &(l, p) in &log.confusion {
        assert!(l != p && p != 0, "{l} -> {p}");
    }
    // 30% of pixels wrong: Eq. 2 still names every instance right.
    let built = build_map(&noisy, &BuildConfig::default()).unwrap();
    let truth = IvlMap::from_scene(&s);
    assert_eq!(built.map.instances.len(), truth.instances.len());
    for (k, inst) in built.map.instances.iter().enumerate() {
        assert_eq!(inst.label, s.objects[k].category.0, "mask {k}");
    }
    // 60%: the partner is now the majority and wins.
    let (noisy, _) = clean.with_noise(&only("label_flip", 0.6, 4)).unwrap();
    let built = build_map(&noisy, &BuildConfig::default()).unwrap();
    let wrong = built
        .map
        .instances
        .iter()
        .enumerate()
        .filter(|(k, i)| i.label != s.objects[*k].category.0)
        .count();
    assert!(wrong > built.map.instances.len() / 2, "{wrong}");
}

#[test]
fn colour_shifts_change_the_colour_words_of_the_shifted_objects_only() {
    let s = scene("flat-a");
    let clean = PerceptionInputs::from_scene(&s);
    let (noisy, log) = clean.with_noise(&only("colour_shift", 0.5, 1)).unwrap();
    assert_eq!(log.colour_shifted.len(), 15);
    let built = build_map(&noisy, &BuildConfig::default()).unwrap();
    let clean_built = build_map(&clean, &BuildConfig::default()).unwrap();
    let mut changed = 0;
    for (k, (a, b)) in built
        .map
        .instances
        .iter()
        .zip(&clean_built.map.instances)
        .enumerate()
    {
        if log.colour_shifted.contains(&k) {
            changed += usize::from(a.colour != b.colour);
        } else {
            assert_eq!(a.colour, b.colour, "object {k} was not shifted");
        }
    }
    // Most shifts land on another colour word (a few turn, e.g., brown to orange-brown
    // and stay brown).
    assert!(changed >= 10, "{changed} of 15 changed colour word");
}

#[test]
fn bad_rates_are_errors_naming_the_field() {
    let clean = PerceptionInputs::from_scene(&scene("flat-a"));
    let mut n = PerceptionNoise::none(0);
    n.merge = 1.5;
    let e = clean.with_noise(&n).unwrap_err();
    assert_eq!(
        e,
        NoiseError::Rate {
            field: "merge",
            value: 1.5
        }
    );
    assert_eq!(
        e.to_string(),
        "noise `merge` must be in [0, 1] (merge_radius_m: >= 0), got 1.5"
    );
    n.merge = f64::NAN;
    assert!(clean.with_noise(&n).is_err());
}
