#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! `ivlmap noise-study` with the real binary: noiseless perception reproduces the
//! reference plans' perfect score, noise costs the ordinal/colour plans, the same
//! seeds give the same report, and bad rates, kinds and suites are one-line errors.

mod support;
use support::{ivlmap, repo, text};

use serde_json::Value;

fn row<'a>(study: &'a Value, rate: f64, method: &str) -> &'a Value {
    study["rows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["rate"].as_f64() == Some(rate) && r["method"] == method)
        .unwrap_or_else(|| panic!("no row {rate} {method}"))
}

#[test]
fn noiseless_maps_keep_the_reference_score_and_noise_lowers_it_reproducibly() {
    let d = tempfile::tempdir().unwrap();
    let run = |name: &str| {
        let r = d.path().join(name);
        let o = ivlmap(&[
            "noise-study",
            "examples/suites/office-b.nav.jsonl",
            "--noise",
            "0,0.3",
            "--seed",
            "3",
            "--seeds",
            "2",
            "--report",
            r.to_str().unwrap(),
        ]);
        let (out, err) = text(&o);
        assert!(o.status.success(), "{err}\n{out}");
        (out, std::fs::read_to_string(&r).unwrap())
    };
    let (out, report) = run("a.json");
    let (out2, report2) = run("b.json");
    assert_eq!(report, report2, "same seeds, same study");
    assert_eq!(
        out.replace("b.json", "a.json"),
        out2.replace("b.json", "a.json")
    );
    assert!(
        out.contains("(8 tasks)") && out.contains("seeds [3, 4]"),
        "{out}"
    );
    assert!(
        out.contains("| 0 | 1.000 | 1.000 | 1.000 | 1.000 | 1.000 |"),
        "{out}"
    );

    let study: Value = serde_json::from_str(&report).unwrap();
    assert_eq!(study["tasks"], 8);
    let clean = row(&study, 0.0, "ivlmap");
    assert_eq!(clean["T"], serde_json::json!([1.0, 1.0, 1.0, 1.0]));
    let noisy = row(&study, 0.3, "ivlmap");
    assert!(noisy["T"][3].as_f64().unwrap() < 0.8, "{noisy}");
    assert_eq!(noisy["per_seed"].as_array().unwrap().len(), 2);
    // VLMaps ignores ordinals and colours: below the reference even without noise.
    let vl = row(&study, 0.0, "vlmap");
    assert!(vl["T"][3].as_f64().unwrap() < 0.5, "{vl}");
    let e = &study["effects"][1];
    assert_eq!(e["rate"], 0.3);
    assert_eq!(e["dropped"], 9.0); // 0.3 of 30 masks
    assert_eq!(study["effects"][0]["instances"], 30.0);
}

#[test]
fn one_kind_at_a_time() {
    // Per-pixel label flips are outvoted by Eq. 2: no change at 30%.
    let o = ivlmap(&[
        "noise-study",
        "examples/suites/flat-a.nav.jsonl",
        "--noise",
        "0.3",
        "--seeds",
        "1",
        "--kinds",
        "label_flip",
    ]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(out.contains("kinds label_flip, seeds [0]"), "{out}");
    assert!(
        out.contains("| 0.3 | 1.000 | 1.000 | 1.000 | 1.000 | 1.000 |"),
        "{out}"
    );
}

#[test]
fn bad_rates_kinds_and_suites_are_one_line_errors() {
    let err = |args: &[&str]| {
        let o = ivlmap(args);
        let (out, err) = text(&o);
        assert_eq!(o.status.code(), Some(2), "{out}\n{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        err.trim().to_string()
    };
    let suite = "examples/suites/flat-a.nav.jsonl";
    assert_eq!(
        err(&["noise-study", suite, "--kinds", "blur"]),
        "ivlmap: error: unknown noise kind \"blur\"; the kinds are label_flip, fragment, merge, drop, colour_shift"
    );
    assert_eq!(
        err(&["noise-study", suite, "--noise", "0,1.5"]),
        "ivlmap: error: noise rate 1.5 is not in [0, 1]"
    );
    assert_eq!(
        err(&["noise-study", suite, "--seeds", "0"]),
        "ivlmap: error: --seeds must be at least 1"
    );
    // a task without a reference plan
    let d = tempfile::tempdir().unwrap();
    let s = d.path().join("x.nav.jsonl");
    let scene = repo().join("examples/scenes/flat-a.scene.json");
    std::fs::write(
        &s,
        format!(
            "{}\n",
            serde_json::json!({"id": "t1", "scene": scene, "instruction": "go to the sofa", "subgoals": [{"object": 1}]})
        ),
    )
    .unwrap();
    assert_eq!(
        err(&["noise-study", s.to_str().unwrap()]),
        "ivlmap: error: task t1 (line 1) has no \"reference\" plan"
    );
}
