//! Saving a map folder and loading it back, its errors, and that NumPy reads the
//! layers with the documented dtypes and shapes.

// Test helpers outside #[test] functions may unwrap and panic too.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::process::Command;

use map_core::npy::write_npy;
use map_core::persist::PersistError;
use map_core::{Grid, IvlMap, Scene};

fn scene_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../examples/scenes")
        .join(name)
}

fn flat_a() -> IvlMap {
    IvlMap::from_scene(&Scene::from_path(scene_path("flat-a.scene.json")).unwrap())
}

fn saved(map: &IvlMap) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    map.save(dir.path()).unwrap();
    dir
}

#[test]
fn every_example_scene_round_trips_exactly() {
    for name in [
        "flat-a.scene.json",
        "office-b.scene.json",
        "house-c.scene.json",
    ] {
        let map = IvlMap::from_scene(&Scene::from_path(scene_path(name)).unwrap());
        let dir = saved(&map);
        for f in [
            "map.json",
            "instances.json",
            "obstacles.npy",
            "category.npy",
            "instance.npy",
            "colour.npy",
        ] {
            assert!(dir.path().join(f).is_file(), "{name}: {f} not written");
        }
        let back = IvlMap::load(dir.path()).unwrap();
        assert_eq!(back, map, "{name}");
        // and saving the loaded map again gives the same files
        let dir2 = saved(&back);
        for f in ["map.json", "instances.json", "instance.npy"] {
            assert_eq!(
                std::fs::read(dir.path().join(f)).unwrap(),
                std::fs::read(dir2.path().join(f)).unwrap(),
                "{name}: {f}"
            );
        }
    }
}

#[test]
fn map_json_carries_the_format_tag_and_frame() {
    let map = flat_a();
    let dir = saved(&map);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("map.json")).unwrap())
            .unwrap();
    assert_eq!(v["format"], "ivlmap-map/1");
    assert_eq!(v["name"], "flat-a");
    assert_eq!(v["frame"]["rows"], map.frame.rows);
    assert_eq!(v["frame"]["cols"], map.frame.cols);
    assert_eq!(v["frame"]["cell_size"], 0.05);
    assert_eq!(v["frame"]["origin"][1], 9.0);
    let inst: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("instances.json")).unwrap())
            .unwrap();
    let first = &inst[0];
    for key in [
        "id",
        "label",
        "label_id",
        "num_of_same_class",
        "color",
        "area",
        "bbox",
        "area_m2",
        "bbox_m",
        "centroid",
        "contour",
    ] {
        assert!(
            first.get(key).is_some(),
            "instances.json lacks {key}: {first}"
        );
    }
}

fn rewrite(dir: &Path, file: &str, f: impl FnOnce(String) -> String) {
    let p = dir.join(file);
    let text = std::fs::read_to_string(&p).unwrap();
    std::fs::write(&p, f(text)).unwrap();
}

#[test]
fn a_missing_file_is_named() {
    let dir = saved(&flat_a());
    std::fs::remove_file(dir.path().join("colour.npy")).unwrap();
    let err = IvlMap::load(dir.path()).unwrap_err();
    assert!(err.to_string().contains("colour.npy"), "{err}");
    std::fs::remove_file(dir.path().join("map.json")).unwrap();
    let err = IvlMap::load(dir.path()).unwrap_err();
    assert!(matches!(err, PersistError::Io { .. }), "{err}");
    assert!(err.to_string().contains("map.json"), "{err}");
}

#[test]
fn an_unknown_format_is_refused() {
    let dir = saved(&flat_a());
    rewrite(dir.path(), "map.json", |t| {
        t.replace("ivlmap-map/1", "ivlmap-map/9")
    });
    let err = IvlMap::load(dir.path()).unwrap_err();
    assert!(matches!(err, PersistError::UnknownFormat { .. }), "{err}");
    assert!(err.to_string().contains("ivlmap-map/9"), "{err}");
}

#[test]
fn bad_json_reports_file_line_and_field() {
    let dir = saved(&flat_a());
    rewrite(dir.path(), "map.json", |t| {
        t.replace("\"robot_radius\": 0.2", "\"robot_radius\": \"wide\"")
    });
    let err = IvlMap::load(dir.path()).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("map.json:"), "{msg}");
    assert!(msg.contains("field `robot_radius`"), "{msg}");
    match err {
        PersistError::Json { at, .. } => assert!(at.line.unwrap() > 1, "{at:?}"),
        other => panic!("{other}"),
    }

    let dir = saved(&flat_a());
    rewrite(dir.path(), "instances.json", |t| {
        t.replacen("\"bbox\": [", "\"bbox\": [-", 1)
    });
    let msg = IvlMap::load(dir.path()).unwrap_err().to_string();
    assert!(msg.contains("instances.json:"), "{msg}");
    assert!(msg.contains("[0].bbox"), "{msg}");
}

#[test]
fn a_layer_of_the_wrong_shape_is_refused() {
    let map = flat_a();
    let dir = saved(&map);
    let small = Grid::new(map.frame.rows - 1, map.frame.cols, 0u16);
    write_npy(dir.path().join("category.npy"), &small).unwrap();
    let err = IvlMap::load(dir.path()).unwrap_err();
    assert!(matches!(err, PersistError::Shape { .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.contains("category.npy") && msg.contains("179x240"),
        "{msg}"
    );
}

#[test]
fn a_layer_of_the_wrong_dtype_is_refused() {
    let map = flat_a();
    let dir = saved(&map);
    write_npy(dir.path().join("obstacles.npy"), &map.category).unwrap(); // u16, not u8
    let err = IvlMap::load(dir.path()).unwrap_err();
    assert!(matches!(err, PersistError::Npy(_)), "{err}");
    assert!(err.to_string().contains("obstacles.npy"), "{err}");
}

#[test]
fn instance_ids_must_exist_in_the_table() {
    let map = flat_a();
    let dir = saved(&map);
    let mut u = map.instance.map(|&v| v as i32);
    let c = map.frame.cell_at(map.start_pose.position).unwrap();
    u.set(c, 999);
    write_npy(dir.path().join("instance.npy"), &u).unwrap();
    let err = IvlMap::load(dir.path()).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("instance.npy") && msg.contains("999"), "{msg}");
    assert!(msg.contains(&format!("[{}, {}]", c.row, c.col)), "{msg}");
}

#[test]
fn layers_must_agree_with_the_instance_table() {
    let map = flat_a();
    // a table row whose label is not a category
    let dir = saved(&map);
    rewrite(dir.path(), "instances.json", |t| {
        t.replacen("\"label\": \"sofa\"", "\"label\": \"piano\"", 1)
    });
    let msg = IvlMap::load(dir.path()).unwrap_err().to_string();
    assert!(
        msg.contains("instances.json") && msg.contains("piano"),
        "{msg}"
    );

    // an instance cell whose colour id is not the instance's colour
    let dir = saved(&map);
    let mut v = map.colour.clone();
    let sofa = map.instance_by_id(1).unwrap();
    let c = map.frame.cell_at(sofa.center()).unwrap();
    let wrong = if *v.get(c).unwrap() == 1 { 2 } else { 1 };
    v.set(c, wrong);
    write_npy(dir.path().join("colour.npy"), &v).unwrap();
    let msg = IvlMap::load(dir.path()).unwrap_err().to_string();
    assert!(
        msg.contains("colour.npy") && msg.contains("instance 1"),
        "{msg}"
    );

    // a duplicate id in the table
    let dir = saved(&map);
    rewrite(dir.path(), "instances.json", |t| {
        t.replacen("\"id\": 2,", "\"id\": 1,", 1)
    });
    let msg = IvlMap::load(dir.path()).unwrap_err().to_string();
    assert!(msg.contains("appears twice"), "{msg}");
}

/// NumPy reads every layer with the documented dtype and shape and the same values.
/// Skips (with a message) when python3 or numpy is missing; CI installs numpy.
#[test]
fn numpy_reads_the_layers() {
    let probe = Command::new("python3")
        .args(["-c", "import numpy"])
        .output();
    match probe {
        Ok(o) if o.status.success() => {}
        Ok(o) => {
            eprintln!(
                "SKIPPED numpy_reads_the_layers: numpy not importable: {}",
                String::from_utf8_lossy(&o.stderr).trim()
            );
            return;
        }
        Err(e) => {
            eprintln!("SKIPPED numpy_reads_the_layers: cannot run python3: {e}");
            return;
        }
    }
    let map = flat_a();
    let dir = saved(&map);
    let script = r#"
import json, sys, numpy as np
d = sys.argv[1]
out = {}
for name in ["obstacles", "category", "instance", "colour"]:
    a = np.load(f"{d}/{name}.npy")
    out[name] = {"dtype": a.dtype.name, "shape": list(a.shape), "sum": int(a.astype(np.int64).sum()),
                 "c_order": bool(a.flags["C_CONTIGUOUS"])}
u = np.load(f"{d}/instance.npy")
out["ids"] = sorted(int(x) for x in np.unique(u) if x != 0)
print(json.dumps(out))
"#;
    let o = Command::new("python3")
        .args(["-c", script, dir.path().to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let shape = serde_json::json!([map.frame.rows, map.frame.cols]);
    let sum = |s: &[u64]| s.iter().sum::<u64>();
    let want = [
        (
            "obstacles",
            "uint8",
            sum(&map
                .obstacles
                .as_slice()
                .iter()
                .map(|&b| u64::from(b))
                .collect::<Vec<_>>()),
        ),
        (
            "category",
            "uint16",
            sum(&map
                .category
                .as_slice()
                .iter()
                .map(|&x| u64::from(x))
                .collect::<Vec<_>>()),
        ),
        (
            "instance",
            "int32",
            sum(&map
                .instance
                .as_slice()
                .iter()
                .map(|&x| u64::from(x))
                .collect::<Vec<_>>()),
        ),
        (
            "colour",
            "uint8",
            sum(&map
                .colour
                .as_slice()
                .iter()
                .map(|&x| u64::from(x))
                .collect::<Vec<_>>()),
        ),
    ];
    for (name, dtype, total) in want {
        assert_eq!(v[name]["dtype"], dtype, "{name}: {v}");
        assert_eq!(v[name]["shape"], shape, "{name}: {v}");
        assert_eq!(v[name]["sum"], total, "{name}: {v}");
        assert_eq!(v[name]["c_order"], true, "{name}: {v}");
    }
    let mut ids: Vec<u32> = map.instances.iter().map(|i| i.id).collect();
    ids.sort();
    assert_eq!(v["ids"], serde_json::json!(ids));
}
