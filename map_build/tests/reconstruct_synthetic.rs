#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! End to end: render RGB-D frames of examples/scenes/flat-a.scene.json along a
//! path, write them as a dataset folder (camera.json, poses.txt in VLMaps' Habitat
//! convention, rgb/*.png, depth/*.npy), read it back, reconstruct the bird's-eye
//! maps and compare them with the scene's own rasterised obstacle map.

use std::path::Path;

use map_build::reconstruct::{
    base_from_pose2d, reconstruct, Anchor, CameraInfo, Intrinsics, MapSpec, PoseConvention,
    ReconstructOptions, RgbdDataset, RgbdFrame, RgbdRenderer, SyntheticOptions, TopDownMaps,
};
use map_core::render::{colour_rgb, UNKNOWN_RGB};
use map_core::scene::SceneObject;
use map_core::{Cell, Grid, IvlMap, Pose, Scene};

const W: usize = 160;
const H: usize = 120;
const CAMERA_HEIGHT: f64 = 1.5;
const FLOOR_RGB: [u8; 3] = [128, 128, 128];

fn scene() -> Scene {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/scenes/flat-a.scene.json");
    Scene::from_path(p).unwrap()
}

/// Fridges and shelves stand taller than the robot (their tops are not seen).
fn object_height(o: &SceneObject) -> f64 {
    match o.category.0.as_str() {
        "fridge" | "shelf" => 1.8,
        "bed" => 0.5,
        "table" | "desk" => 0.75,
        _ => 0.8,
    }
}

/// A dozen base poses through the living room, dining room and kitchen.
fn path() -> Vec<Pose> {
    [
        (4.0, 3.0, 180.0),
        (4.0, 3.0, -90.0),
        (4.0, 3.0, 0.0),
        (3.0, 4.0, -135.0),
        (2.0, 3.8, 180.0),
        (5.0, 2.6, 90.0),
        (7.2, 2.7, 90.0),
        (8.6, 1.2, 0.0),
        (8.6, 4.6, 180.0),
        (10.5, 3.0, 90.0),
        (10.5, 3.0, 0.0),
        (10.5, 3.0, 180.0),
    ]
    .iter()
    .map(|&(x, y, h)| Pose::new(x, y, h))
    .collect()
}

fn camera(scene: &Scene, convention: PoseConvention) -> CameraInfo {
    CameraInfo {
        intrinsics: Intrinsics::from_hfov(W as u32, H as u32, 90.0),
        width: Some(W as u32),
        height: Some(H as u32),
        depth_scale: 1000.0,
        pose_convention: convention,
        camera_height: CAMERA_HEIGHT,
        anchor: Anchor::World,
        map: Some(MapSpec::Bounds {
            bounds: scene.bounds.0,
            cell_size: scene.cell_size.0,
        }),
    }
}

/// Render the path at the camera's size and write a dataset folder.
fn write_dataset(dir: &Path, scene: &Scene, cam: &CameraInfo, poses: &[Pose]) {
    let renderer = RgbdRenderer::new(scene, &SyntheticOptions::default(), object_height);
    let mut frames: Vec<RgbdFrame> = Vec::new();
    let mut records = Vec::new();
    let (w, h) = (cam.width.unwrap() as usize, cam.height.unwrap() as usize);
    for p in poses {
        let base = base_from_pose2d(*p, 0.0);
        let rec = cam.pose_convention.record_for_base(&base, CAMERA_HEIGHT);
        let fp = cam.pose_convention.to_world(&rec, CAMERA_HEIGHT);
        frames.push(renderer.render(&fp.camera, &cam.intrinsics, w, h));
        records.push(rec);
    }
    RgbdDataset::write(dir, cam, &frames, &records).unwrap();
}

/// Chebyshev distance from each cell to the nearest true cell is <= `r`.
fn near(truth: &Grid<bool>, c: Cell, r: usize) -> bool {
    let (r0, c0) = (c.row.saturating_sub(r), c.col.saturating_sub(r));
    (r0..=(c.row + r).min(truth.rows() - 1)).any(|rr| {
        (c0..=(c.col + r).min(truth.cols() - 1))
            .any(|cc| truth.get(Cell::new(rr, cc)) == Some(&true))
    })
}

struct Scores {
    observed: usize,
    tp: usize,
    fp: usize,
    fneg: usize,
    far_fp: usize,
}

impl Scores {
    fn iou(&self) -> f64 {
        self.tp as f64 / (self.tp + self.fp + self.fneg).max(1) as f64
    }
}

fn score(maps: &TopDownMaps, truth: &Grid<bool>) -> Scores {
    let mut s = Scores {
        observed: 0,
        tp: 0,
        fp: 0,
        fneg: 0,
        far_fp: 0,
    };
    for (c, &rec) in maps.obstacles.iter_cells() {
        let t = *truth.get(c).unwrap();
        if rec && !near(truth, c, 1) {
            s.far_fp += 1;
        }
        if !maps.observed(c) {
            continue;
        }
        s.observed += 1;
        match (rec, t) {
            (true, true) => s.tp += 1,
            (true, false) => s.fp += 1,
            (false, true) => s.fneg += 1,
            (false, false) => {}
        }
    }
    s
}

#[test]
fn reconstructed_obstacles_and_colours_match_the_scene() {
    let scene = scene();
    let truth_map = IvlMap::from_scene(&scene);
    let dir = tempfile::tempdir().unwrap();
    let cam = camera(&scene, PoseConvention::HabitatBase);
    write_dataset(dir.path(), &scene, &cam, &path());

    // the files are real: VLMaps' layout plus camera.json
    assert!(dir.path().join("rgb/000011.png").is_file());
    assert!(dir.path().join("depth/000011.npy").is_file());
    let poses_txt = std::fs::read_to_string(dir.path().join("poses.txt")).unwrap();
    assert_eq!(poses_txt.lines().count(), 12);
    assert!(poses_txt.lines().all(|l| l.split('\t').count() == 7));

    let ds = RgbdDataset::open(dir.path()).unwrap();
    assert_eq!(ds.camera, cam);
    let opts = ReconstructOptions {
        stride: 2,
        ..Default::default()
    };
    let maps = reconstruct(&ds, &opts).unwrap();
    assert_eq!(maps.frame, truth_map.frame);
    assert_eq!(maps.frames, 12);

    // obstacles over the observed cells
    let s = score(&maps, &truth_map.obstacles);
    let obstacles = maps.obstacles.as_slice().iter().filter(|&&o| o).count();
    eprintln!(
        "observed {} cells, {} reconstructed obstacles: tp {} fp {} fn {} IoU {:.3}, {} more than 1 cell from a true obstacle",
        s.observed, obstacles, s.tp, s.fp, s.fneg, s.iou(), s.far_fp
    );
    assert!(s.observed > 6000, "only {} cells observed", s.observed);
    assert!(s.tp > 1000, "{} true positives", s.tp);
    assert!(s.iou() >= 0.8, "IoU {:.3} over observed cells", s.iou());
    assert_eq!(
        s.far_fp, 0,
        "reconstructed obstacles away from any true one"
    );

    // top-down colour and height under objects lower than the robot: the cells whose
    // 3x3 neighbourhood is all the same instance see the object's top
    let (mut checked, mut right, mut objects_seen) = (0, 0, 0);
    for o in &scene.objects {
        let h = object_height(o);
        if h >= CAMERA_HEIGHT {
            continue;
        }
        let want = o
            .colour
            .as_ref()
            .and_then(|c| colour_rgb(&c.0))
            .unwrap_or(UNKNOWN_RGB);
        let mut n = 0;
        for (c, &id) in truth_map.instance.iter_cells() {
            if id != o.id.0 || !maps.observed(c) || c.row == 0 || c.col == 0 {
                continue;
            }
            let interior = (c.row - 1..=c.row + 1).all(|r| {
                (c.col - 1..=c.col + 1)
                    .all(|cc| truth_map.instance.get(Cell::new(r, cc)) == Some(&o.id.0))
            });
            if !interior {
                continue;
            }
            n += 1;
            checked += 1;
            let rgb = *maps.rgb.get(c).unwrap();
            let z = f64::from(*maps.height.get(c).unwrap());
            if rgb == want && (z - h).abs() < 0.02 {
                right += 1;
            }
        }
        if n > 0 {
            objects_seen += 1;
        }
    }
    eprintln!("object tops: {right}/{checked} cells right over {objects_seen} objects");
    assert!(objects_seen >= 10, "only {objects_seen} object tops seen");
    assert!(
        checked >= 300 && right as f64 >= 0.98 * checked as f64,
        "{right}/{checked}"
    );

    // floor: observed cells two or more cells from any obstacle are grey at height 0
    let (mut floor, mut floor_right) = (0, 0);
    for (c, &t) in truth_map.obstacles.iter_cells() {
        if t || !maps.observed(c) || near(&truth_map.obstacles, c, 2) {
            continue;
        }
        floor += 1;
        if maps.rgb.get(c) == Some(&FLOOR_RGB) && maps.height.get(c).unwrap().abs() < 1e-3 {
            floor_right += 1;
        }
    }
    eprintln!("floor: {floor_right}/{floor} cells grey at height 0");
    assert!(
        floor > 2000 && floor_right == floor,
        "{floor_right}/{floor}"
    );

    // B as an image: unobserved cells get the given colour
    let img = maps.rgb_image([255, 255, 255]);
    assert_eq!(
        (img.width() as usize, img.height() as usize),
        (maps.frame.cols, maps.frame.rows)
    );
    let cropped = maps.crop_to_observed(2).unwrap();
    assert_eq!(cropped.observed_count(), maps.observed_count());
    assert!(cropped.frame.rows < maps.frame.rows || cropped.frame.cols < maps.frame.cols);
}

/// Paper's real-robot poses (ros_base), 16-bit millimetre depth PNGs: the same
/// geometry comes back.
#[test]
fn ros_poses_and_png_depth_give_the_same_map() {
    let scene = scene();
    let truth = IvlMap::from_scene(&scene).obstacles;
    let dir = tempfile::tempdir().unwrap();
    let cam = camera(&scene, PoseConvention::RosBase);
    let poses: Vec<Pose> = path().into_iter().step_by(3).collect();
    write_dataset(dir.path(), &scene, &cam, &poses);
    // replace the float depth with 16-bit millimetre PNGs
    for e in std::fs::read_dir(dir.path().join("depth")).unwrap() {
        let p = e.unwrap().path();
        let d = map_build::reconstruct::read_depth(&p, 1000.0).unwrap();
        map_build::reconstruct::write_depth_png(p.with_extension("png"), &d, 1000.0).unwrap();
        std::fs::remove_file(&p).unwrap();
    }
    let ds = RgbdDataset::open(dir.path()).unwrap();
    assert!(ds.frames[0].depth.extension().unwrap() == "png");
    let maps = reconstruct(
        &ds,
        &ReconstructOptions {
            stride: 2,
            ..Default::default()
        },
    )
    .unwrap();
    let s = score(&maps, &truth);
    eprintln!(
        "ros_base + png: observed {} IoU {:.3}, {} far",
        s.observed,
        s.iou(),
        s.far_fp
    );
    assert!(s.observed > 2000 && s.iou() >= 0.8 && s.far_fp == 0);
}

#[test]
fn dataset_errors_name_the_file() {
    let scene = scene();
    let dir = tempfile::tempdir().unwrap();
    let cam = camera(&scene, PoseConvention::HabitatBase);
    let mut small = cam.clone();
    small.width = Some(32);
    small.height = Some(24);
    small.intrinsics = Intrinsics::from_hfov(32, 24, 90.0);
    let poses: Vec<Pose> = path().into_iter().take(2).collect();
    write_dataset(dir.path(), &scene, &small, &poses);

    // one pose too many
    let pt = dir.path().join("poses.txt");
    let text = std::fs::read_to_string(&pt).unwrap();
    std::fs::write(&pt, format!("{text}0 0 0 0 0 0 1\n")).unwrap();
    let e = RgbdDataset::open(dir.path()).unwrap_err().to_string();
    assert!(
        e.contains("poses.txt") && e.contains("3 poses") && e.contains("2 frames"),
        "{e}"
    );

    // a bad line
    std::fs::write(&pt, format!("{text}1 2 3\n")).unwrap();
    let e = RgbdDataset::open(dir.path()).unwrap_err().to_string();
    assert!(e.contains("poses.txt line 3: expected 7 numbers"), "{e}");
    std::fs::write(&pt, &text).unwrap();

    // an unpaired depth frame
    std::fs::copy(
        dir.path().join("depth/000001.npy"),
        dir.path().join("depth/000005.npy"),
    )
    .unwrap();
    let e = RgbdDataset::open(dir.path()).unwrap_err().to_string();
    assert!(
        e.contains("depth/000005.npy has no matching rgb/000005.png"),
        "{e}"
    );
    std::fs::remove_file(dir.path().join("depth/000005.npy")).unwrap();

    // camera.json disagreeing with the images
    let mut wrong = small.clone();
    wrong.width = Some(64);
    wrong.height = Some(48);
    wrong.write(dir.path().join("camera.json")).unwrap();
    let ds = RgbdDataset::open(dir.path()).unwrap();
    let e = ds.load_frame(0).unwrap_err().to_string();
    assert!(
        e.contains("000000.png") && e.contains("32x24") && e.contains("width 64"),
        "{e}"
    );

    // a malformed camera.json field
    std::fs::write(
        dir.path().join("camera.json"),
        "{\"format\": \"ivlmap-rgbd/1\",\n \"camera_height\": \"high\", \"hfov_deg\": 90}",
    )
    .unwrap();
    let e = RgbdDataset::open(dir.path()).unwrap_err().to_string();
    assert!(
        e.contains("camera.json:2") && e.contains("camera_height"),
        "{e}"
    );
}
