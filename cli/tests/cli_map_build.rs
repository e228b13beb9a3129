#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! `ivlmap map build` with the real binary on inputs written with map_core's own
//! writers: perception outputs (SAM masks, a label map, top-down RGB, obstacles)
//! from a scene's perfect perception, an RGB-D dataset rendered from a scene, and a
//! VLMaps legacy map whose cells hold MiniLM embeddings (labelled by P = Q x E^T with
//! the real encoder); then malformed inputs, each one line naming the file.

mod support;
use support::{ivlmap, repo, text};

use std::path::{Path, PathBuf};
use std::process::Output;

use map_build::embed::{
    models_dir, TextEncoder, TextEncoderOptions, MINILM_MODEL_FILE, MINILM_TOKENIZER_FILE,
};
use map_build::perception::{
    build_map, write_sam_masks, BuildConfig, Mask, PerceptionInputs, SamMask, SegmentationForm,
};
use map_build::reconstruct::{
    base_from_pose2d, write_rgb_png, write_vlmaps_legacy, Anchor, CameraInfo, Intrinsics, MapSpec,
    PoseConvention, RgbdDataset, RgbdFrame, RgbdRenderer, SyntheticOptions, TopDownMaps,
};
use map_core::npy::write_npy;
use map_core::{Cell, Grid, GridFrame, IvlMap, Pose, Scene};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// An n-D .npy of any element type numpy knows (`write_npy` does 2-D layers only).
fn write_nd<T: npyz::AutoSerialize>(path: &Path, shape: &[u64], data: Vec<T>) {
    use npyz::WriterBuilder;
    let mut w = npyz::WriteOptions::new()
        .default_dtype()
        .shape(shape)
        .writer(std::fs::File::create(path).unwrap())
        .begin_nd()
        .unwrap();
    w.extend(data).unwrap();
    w.finish().unwrap();
}

fn scene(name: &str) -> Scene {
    Scene::from_path(repo().join(format!("examples/scenes/{name}.scene.json"))).unwrap()
}

/// Perception output files of a scene's perfect perception, plus two masks that
/// must be dropped (a floor patch, a 2-cell speck).
struct Files {
    masks: PathBuf,
    labels: PathBuf,
    cats: PathBuf,
    rgb: PathBuf,
    obstacles: PathBuf,
}

fn write_perception(dir: &Path, inputs: &PerceptionInputs, extra: &[Mask]) -> Files {
    let f = Files {
        masks: dir.join("masks.json"),
        labels: dir.join("labels.npy"),
        cats: dir.join("cats.txt"),
        rgb: dir.join("topdown.png"),
        obstacles: dir.join("obstacles.npy"),
    };
    let sam: Vec<SamMask> = inputs
        .masks
        .iter()
        .chain(extra)
        .cloned()
        .map(SamMask::from_mask)
        .collect();
    write_sam_masks(&f.masks, &sam, SegmentationForm::CompressedRle).unwrap();
    write_npy(&f.labels, inputs.labels.labels()).unwrap();
    std::fs::write(
        &f.cats,
        format!("# categories\n{}\n", inputs.labels.categories().join("\n")),
    )
    .unwrap();
    write_rgb_png(&f.rgb, inputs.rgb.as_ref().unwrap()).unwrap();
    write_npy(&f.obstacles, &inputs.obstacles).unwrap();
    f
}

/// A square of `n` x `n` floor cells (label 0, free) somewhere in the map.
fn floor_patch(inputs: &PerceptionInputs, n: usize) -> Mask {
    let (rows, cols) = (inputs.frame.rows, inputs.frame.cols);
    let l = inputs.labels.labels();
    for r0 in (0..rows - n).step_by(n) {
        for c0 in (0..cols - n).step_by(n) {
            let cells: Vec<Cell> = (r0..r0 + n)
                .flat_map(|r| (c0..c0 + n).map(move |c| Cell::new(r, c)))
                .collect();
            if cells
                .iter()
                .all(|&c| l.get(c) == Some(&0) && inputs.obstacles.get(c) == Some(&false))
            {
                return Mask::from_cells(rows, cols, cells);
            }
        }
    }
    panic!("no floor patch");
}

#[test]
fn perception_outputs_build_the_map_that_inspect_and_scene_options_read() {
    let d = tempfile::tempdir().unwrap();
    let sc = scene("office-b");
    let inputs = PerceptionInputs::from_scene(&sc);
    let (rows, cols) = (inputs.frame.rows, inputs.frame.cols);
    let patch = floor_patch(&inputs, 8);
    let speck = Mask::from_cells(rows, cols, [Cell::new(0, 0), Cell::new(0, 1)]);
    let f = write_perception(d.path(), &inputs, &[patch.clone(), speck.clone()]);
    let out = d.path().join("office-map");
    let b = sc.bounds.0;
    let origin = format!("{},{}", b[0], b[1]);
    let o = ivlmap(&[
        "map",
        "build",
        "--sam",
        s(&f.masks),
        "--labels",
        s(&f.labels),
        "--categories",
        s(&f.cats),
        "--rgb",
        s(&f.rgb),
        "--obstacles",
        s(&f.obstacles),
        "--origin",
        &origin,
        "--out",
        s(&out),
    ]);
    let (stdout, err) = text(&o);
    assert!(o.status.success(), "{err}\n{stdout}");

    // The same build in-process: the summary's counts and the saved map agree with it.
    let mut all = inputs.clone();
    all.masks.extend([patch, speck]);
    let want = build_map(&all, &BuildConfig::default()).unwrap();
    assert_eq!(want.map.instances.len(), sc.objects.len());
    assert!(
        stdout.contains(&format!(
            "{} masks: {} instances kept, 2 dropped",
            sc.objects.len() + 2,
            sc.objects.len()
        )),
        "{stdout}"
    );
    assert!(
        stdout.contains("dropped by reason: no object label 1, too small 1"),
        "{stdout}"
    );
    assert!(
        stdout.contains(&format!(
            "  dropped mask {}: no object label: background label 0 covers 1.000 of it",
            sc.objects.len()
        )),
        "{stdout}"
    );
    assert!(
        stdout.contains(&format!(
            "  dropped mask {}: too small: 2 pixels, fewer than 4",
            sc.objects.len() + 1
        )),
        "{stdout}"
    );
    assert!(stdout.contains("instances by category: "), "{stdout}");
    assert!(stdout.contains("chair 11"), "{stdout}");
    assert!(out.join("topdown.png").is_file());

    let saved = IvlMap::load(&out).unwrap();
    assert_eq!(saved.name, "office-map");
    assert_eq!(saved.instance, want.map.instance);
    assert_eq!(saved.obstacles, inputs.obstacles);
    assert_eq!(saved.frame.rows, sc_frame(&sc).rows);
    assert!((saved.frame.origin.x - sc_frame(&sc).origin.x).abs() < 1e-9);
    assert!((saved.frame.origin.y - sc_frame(&sc).origin.y).abs() < 1e-9);
    for (k, o) in sc.objects.iter().enumerate() {
        let i = saved.instance_by_id(k as u32 + 1).unwrap();
        assert_eq!(i.label, o.category.0, "object {}", o.id.0);
        assert_eq!(
            i.colour,
            o.colour.as_ref().map(|c| c.0.clone()),
            "object {}",
            o.id.0
        );
    }

    // The folder is a map like any other: inspect and a reference plan run on it.
    let o = ivlmap(&["map", "inspect", s(&out)]);
    let (stdout, err) = text(&o);
    assert!(o.status.success(), "{err}");
    assert!(stdout.contains("30 instances"), "{stdout}");
    let mission = d.path().join("go.rhai");
    std::fs::write(
        &mission,
        "agent.move_to_object(agent.get_obj_attributes(\"table\", 3, \"yellow\", \"west_to_east\"));\n",
    )
    .unwrap();
    let o = ivlmap(&["run", s(&mission), "--scene", s(&out)]);
    let (_, err) = text(&o);
    assert!(o.status.success(), "{err}");
}

fn sc_frame(sc: &Scene) -> GridFrame {
    GridFrame::from_bounds(sc.bounds.0, sc.cell_size.0)
}

#[test]
fn labels_of_any_integer_dtype_and_no_sam_give_connected_regions() {
    let d = tempfile::tempdir().unwrap();
    let sc = scene("flat-a");
    let inputs = PerceptionInputs::from_scene(&sc);
    let f = write_perception(d.path(), &inputs, &[]);
    // numpy's argmax gives int64: write the labels so
    let l = inputs.labels.labels();
    let wide: Vec<i64> = l.as_slice().iter().map(|&v| i64::from(v)).collect();
    write_nd(&f.labels, &[l.rows() as u64, l.cols() as u64], wide);
    let out = d.path().join("flat");
    let o = ivlmap(&[
        "map",
        "build",
        "--labels",
        s(&f.labels),
        "--categories",
        s(&f.cats),
        "--out",
        s(&out),
    ]);
    let (stdout, err) = text(&o);
    assert!(o.status.success(), "{err}\n{stdout}");
    assert!(
        stdout.contains("note: no --sam: instances are the connected regions of each category"),
        "{stdout}"
    );
    assert!(
        stdout.contains(
            "note: no --obstacles: every cell labelled with an object category is an obstacle"
        ),
        "{stdout}"
    );
    let saved = IvlMap::load(&out).unwrap();
    // Objects of one category that touch become one region; every region is an instance.
    let truth = IvlMap::from_scene(&sc);
    assert!(saved.instances.len() <= truth.instances.len());
    assert!(
        saved.instances.len() >= truth.instances.len() - 4,
        "{}",
        saved.instances.len()
    );
    for i in &saved.instances {
        assert!(i.colour.is_none(), "no --rgb: no colours");
        let t = truth.instance_at(i.centroid).map(|t| t.label.clone());
        assert_eq!(t.as_deref(), Some(i.label.as_str()), "{i:?}");
    }
    assert!(!out.join("topdown.png").exists());
}

/// A 6 x 4 m room: a red sofa and a blue chair.
fn room() -> Scene {
    Scene::from_json_str(
        r#"{"format": "ivlmap-scene/1", "name": "room", "bounds": [0, 0, 6, 4],
        "walls": [{"from": [0, 0], "to": [6, 0]}, {"from": [6, 0], "to": [6, 4]},
                  {"from": [6, 4], "to": [0, 4]}, {"from": [0, 4], "to": [0, 0]}],
        "objects": [{"id": 1, "category": "sofa", "colour": "red", "center": [2.0, 2.6], "size": [1.6, 0.8]},
                    {"id": 2, "category": "chair", "colour": "blue", "center": [4.5, 1.2], "size": [0.6, 0.6]}],
        "robot": {"pose": [1.0, 1.0, 90], "radius": 0.2}}"#,
        "room.scene.json",
    )
    .unwrap()
}

fn write_rgbd(dir: &Path, sc: &Scene) {
    let (w, h, cam_h) = (80usize, 60usize, 1.5);
    let cam = CameraInfo {
        intrinsics: Intrinsics::from_hfov(w as u32, h as u32, 90.0),
        width: Some(w as u32),
        height: Some(h as u32),
        depth_scale: 1000.0,
        pose_convention: PoseConvention::HabitatBase,
        camera_height: cam_h,
        anchor: Anchor::World,
        map: Some(MapSpec::Bounds {
            bounds: sc.bounds.0,
            cell_size: sc.cell_size.0,
        }),
    };
    let renderer = RgbdRenderer::new(sc, &SyntheticOptions::default(), |_| 0.8);
    let (mut frames, mut records): (Vec<RgbdFrame>, Vec<_>) = (Vec::new(), Vec::new());
    for (x, y, hd) in [
        (1.0, 1.0, 90.0),
        (1.0, 1.0, 30.0),
        (3.0, 1.0, 0.0),
        (3.0, 1.0, 90.0),
        (5.0, 3.2, -90.0),
        (5.0, 3.2, 180.0),
        (3.5, 3.5, -90.0),
    ] {
        let base = base_from_pose2d(Pose::new(x, y, hd), 0.0);
        let rec = cam.pose_convention.record_for_base(&base, cam_h);
        let fp = cam.pose_convention.to_world(&rec, cam_h);
        frames.push(renderer.render(&fp.camera, &cam.intrinsics, w, h));
        records.push(rec);
    }
    RgbdDataset::write(dir, &cam, &frames, &records).unwrap();
}

#[test]
fn rgbd_dataset_builds_obstacles_and_colour_then_instances_with_sam() {
    let d = tempfile::tempdir().unwrap();
    let sc = room();
    let ds = d.path().join("room-rgbd");
    write_rgbd(&ds, &sc);

    let bare = d.path().join("bare");
    let o = ivlmap(&["map", "build", "--rgbd", s(&ds), "--out", s(&bare)]);
    let (stdout, err) = text(&o);
    assert!(o.status.success(), "{err}\n{stdout}");
    assert!(
        stdout.contains(&format!("from RGB-D dataset {}", ds.display())),
        "{stdout}"
    );
    assert!(stdout.contains("note: reconstructed 7 frames"), "{stdout}");
    assert!(
        stdout.contains("note: no label map: obstacles and top-down colour only, no instances"),
        "{stdout}"
    );
    assert!(
        stdout.contains("0 masks: 0 instances kept, 0 dropped"),
        "{stdout}"
    );
    let m = IvlMap::load(&bare).unwrap();
    assert!(m.instances.is_empty());
    let truth = IvlMap::from_scene(&sc);
    assert_eq!(m.frame, truth.frame);
    // the reconstruction saw the sofa as an obstacle; the robot starts at the first pose
    let sofa: Vec<Cell> = truth
        .instance
        .iter_cells()
        .filter(|(_, &id)| id == 1)
        .map(|(c, _)| c)
        .collect();
    let png = map_build::reconstruct::read_rgb_png(bare.join("topdown.png")).unwrap();
    let red = map_core::render::colour_rgb("red").unwrap();
    let seen = sofa
        .iter()
        .filter(|&&c| m.obstacles.get(c) == Some(&true))
        .count();
    let red_cells = sofa.iter().filter(|&&c| png.get(c) == Some(&red)).count();
    // the views see part of the sofa (80 of its 512 cells here), red on top
    assert!(
        seen >= 40 && red_cells >= 40,
        "sofa {} cells: {seen} obstacles, {red_cells} red",
        sofa.len()
    );
    assert!(
        (m.start_pose.position.x - 1.0).abs() < 1e-6 && (m.start_pose.heading - 90.0).abs() < 1e-6
    );
    assert_eq!((png.rows(), png.cols()), (m.frame.rows, m.frame.cols));

    // With SAM masks and a label map on the reconstruction's grid: instances, their
    // colours from the reconstructed top-down RGB.
    let inputs = PerceptionInputs::from_scene(&sc);
    let f = write_perception(d.path(), &inputs, &[]);
    let full = d.path().join("full");
    let o = ivlmap(&[
        "map",
        "build",
        "--rgbd",
        s(&ds),
        "--sam",
        s(&f.masks),
        "--labels",
        s(&f.labels),
        "--categories",
        s(&f.cats),
        "--out",
        s(&full),
    ]);
    let (stdout, err) = text(&o);
    assert!(o.status.success(), "{err}\n{stdout}");
    assert!(
        stdout.contains("2 masks: 2 instances kept, 0 dropped"),
        "{stdout}"
    );
    assert!(
        stdout.contains("instance cells were not obstacles and are now (objects are obstacles)"),
        "{stdout}"
    );
    let m = IvlMap::load(&full).unwrap();
    let got: Vec<(String, Option<String>)> = m
        .instances
        .iter()
        .map(|i| (i.label.clone(), i.colour.clone()))
        .collect();
    assert_eq!(
        got,
        [
            ("sofa".to_string(), Some("red".to_string())),
            ("chair".to_string(), Some("blue".to_string()))
        ]
    );
}

fn minilm() -> (PathBuf, PathBuf) {
    let dir = models_dir().unwrap();
    (dir.join(MINILM_MODEL_FILE), dir.join(MINILM_TOKENIZER_FILE))
}

/// A VLMaps legacy folder of the room: obstacles and colour from map_core's writer,
/// features = the MiniLM embedding of each cell's category ("other" on the floor,
/// zeros where unobserved).
fn write_vlmaps(dir: &Path, sc: &Scene) -> IvlMap {
    let truth = IvlMap::from_scene(sc);
    let inputs = PerceptionInputs::from_scene(sc);
    let (rows, cols) = (truth.frame.rows, truth.frame.cols);
    let maps = TopDownMaps {
        frame: truth.frame,
        rgb: inputs.rgb.clone().unwrap(),
        height: Grid::new(rows, cols, 0.0),
        obstacles: truth.obstacles.clone(),
        hits: Grid::new(rows, cols, 1),
        obstacle_hits: Grid::new(rows, cols, 0),
        frames: 1,
        points: 0,
    };
    write_vlmaps_legacy(dir, &maps, 1).unwrap();
    let (model, tok) = minilm();
    let enc = TextEncoder::new(&model, &tok, &TextEncoderOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    let names = ["other", "sofa", "chair"];
    let e = enc.embed(&names).unwrap();
    let dim = e.dim();
    let mut data = Vec::with_capacity(rows * cols * dim);
    for (c, &cat) in truth.category.iter_cells() {
        // the outermost ring unobserved
        let edge = c.row == 0 || c.col == 0 || c.row + 1 == rows || c.col + 1 == cols;
        let k = if cat == 0 {
            0
        } else {
            names
                .iter()
                .position(|n| *n == truth.categories[cat as usize - 1])
                .unwrap()
        };
        if edge {
            data.extend(std::iter::repeat_n(0f32, dim));
        } else {
            data.extend_from_slice(e.row(k).unwrap());
        }
    }
    write_nd(
        &dir.join("grid_lseg_1.npy"),
        &[rows as u64, cols as u64, dim as u64],
        data,
    );
    truth
}

#[test]
fn vlmaps_map_labelled_by_the_text_encoder() {
    let d = tempfile::tempdir().unwrap();
    let sc = room();
    let vl = d.path().join("vlmaps");
    write_vlmaps(&vl, &sc);
    let cats = d.path().join("cats.txt");
    std::fs::write(&cats, "other\nsofa\nchair\n").unwrap();
    let (model, tok) = minilm();

    // Without an encoder: obstacles and colour only.
    let bare = d.path().join("bare");
    let o = ivlmap(&["map", "build", "--vlmaps", s(&vl), "--out", s(&bare)]);
    let (stdout, err) = text(&o);
    assert!(o.status.success(), "{err}\n{stdout}");
    assert!(
        stdout.contains(
            "note: VLMaps map version 1: kept rows 0..80, cols 0..120 of the 80 x 120 grid"
        ),
        "{stdout}"
    );
    assert!(stdout.contains("0 instances kept"), "{stdout}");
    assert!(IvlMap::load(&bare).unwrap().instances.is_empty());

    let out = d.path().join("labelled");
    let o = ivlmap(&[
        "map",
        "build",
        "--vlmaps",
        s(&vl),
        "--clip-text-encoder",
        s(&model),
        "--clip-tokenizer",
        s(&tok),
        "--categories",
        s(&cats),
        "--out",
        s(&out),
    ]);
    let (stdout, err) = text(&o);
    assert!(o.status.success(), "{err}\n{stdout}");
    assert!(
        stdout.contains(&format!(
            "note: labelled {} observed cells with {} by P = Q x E^T over 3 categories",
            78 * 118,
            model.display()
        )),
        "{stdout}"
    );
    assert!(
        stdout.contains("2 masks: 2 instances kept, 0 dropped"),
        "{stdout}"
    );
    let m = IvlMap::load(&out).unwrap();
    let got: Vec<(&str, Option<&str>)> = m
        .instances
        .iter()
        .map(|i| (i.label.as_str(), i.colour.as_deref()))
        .collect();
    assert_eq!(got, [("sofa", Some("red")), ("chair", Some("blue"))]);
}

fn one_line_error(o: &Output) -> String {
    let (stdout, err) = text(o);
    assert_eq!(o.status.code(), Some(2), "{stdout}\n{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    err.trim().to_string()
}

#[test]
fn malformed_inputs_are_one_line_errors_naming_the_file() {
    let d = tempfile::tempdir().unwrap();
    let sc = room();
    let inputs = PerceptionInputs::from_scene(&sc);
    let f = write_perception(d.path(), &inputs, &[]);
    let out = d.path().join("out");
    let build = |extra: &[&str]| {
        let mut a = vec!["map", "build", "--out", s(&out)];
        a.extend_from_slice(extra);
        ivlmap(&a)
    };
    let base = |labels: &Path, cats: &Path| {
        vec![
            "--labels".to_string(),
            s(labels).to_string(),
            "--categories".to_string(),
            s(cats).to_string(),
        ]
    };
    let run = |args: Vec<String>| {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        build(&a)
    };

    // nothing to build from
    assert_eq!(
        one_line_error(&build(&[])),
        "ivlmap: error: nothing to build from: give --labels LABELS.npy --categories CATS.txt [--sam MASKS.json] (perception outputs), --rgbd DATASET_DIR or --vlmaps DIR"
    );

    // a category twice
    let dup = d.path().join("dup.txt");
    std::fs::write(&dup, "other\nsofa\n\nsofa\n").unwrap();
    assert_eq!(
        one_line_error(&run(base(&f.labels, &dup))),
        format!(
            "ivlmap: error: {}:4: category \"sofa\" is already on line 2",
            dup.display()
        )
    );

    // a label beyond the category list
    let mut l = inputs.labels.labels().clone();
    l.set(Cell::new(3, 5), 7);
    let bad = d.path().join("bad_labels.npy");
    write_npy(&bad, &l).unwrap();
    assert_eq!(
        one_line_error(&run(base(&bad, &f.cats))),
        format!(
            "ivlmap: error: {}: cell (row 3, col 5) holds label 7, but {} has 3 categories (labels 0..2)",
            bad.display(),
            f.cats.display()
        )
    );

    // a label map that is not 2-D
    let cube = d.path().join("cube.npy");
    write_nd(&cube, &[2, 3, 4], vec![0u16; 24]);
    assert_eq!(
        one_line_error(&run(base(&cube, &f.cats))),
        format!(
            "ivlmap: error: {}: expected a 2-D array (H, W), found shape [2, 3, 4]",
            cube.display()
        )
    );

    // not a .npy at all
    let junk = d.path().join("junk.npy");
    std::fs::write(&junk, "hello").unwrap();
    let e = one_line_error(&run(base(&junk, &f.cats)));
    assert!(
        e.starts_with(&format!(
            "ivlmap: error: {}: not a .npy file: ",
            junk.display()
        )),
        "{e}"
    );

    // masks of another size
    let small: Vec<SamMask> = vec![SamMask::from_mask(Mask::from_cells(
        10,
        12,
        [Cell::new(1, 1)],
    ))];
    let small_path = d.path().join("small.json");
    write_sam_masks(&small_path, &small, SegmentationForm::Rle).unwrap();
    let mut a = base(&f.labels, &f.cats);
    a.extend(["--sam".to_string(), s(&small_path).to_string()]);
    assert_eq!(
        one_line_error(&run(a)),
        format!(
            "ivlmap: error: {}: the masks' size is 10 x 12 (rows x cols), but the map grid from perception outputs ({}) is 80 x 120",
            small_path.display(),
            f.labels.display()
        )
    );

    // a mask that does not decode: the reader names file, line, mask and field
    let broken = d.path().join("broken.json");
    std::fs::write(
        &broken,
        "[{\"segmentation\": {\"size\": [80, 120], \"counts\": [5, 3]}},\n {\"segmentation\": {\"size\": [80, 120], \"counts\": \"!!\"}}]",
    )
    .unwrap();
    let mut a = base(&f.labels, &f.cats);
    a.extend(["--sam".to_string(), s(&broken).to_string()]);
    let e = one_line_error(&run(a));
    assert!(
        e.starts_with(&format!("ivlmap: error: {}", broken.display())),
        "{e}"
    );
    assert!(
        e.contains("mask 0") && e.contains("segmentation.counts"),
        "{e}"
    );

    // an RGB image of another size
    let tiny = d.path().join("tiny.png");
    write_rgb_png(&tiny, &Grid::new(4, 5, [1u8, 2, 3])).unwrap();
    let mut a = base(&f.labels, &f.cats);
    a.extend(["--rgb".to_string(), s(&tiny).to_string()]);
    assert_eq!(
        one_line_error(&run(a)),
        format!(
            "ivlmap: error: {}: RGB image is 4 x 5 (rows x cols), but the map grid from perception outputs ({}) is 80 x 120",
            tiny.display(),
            f.labels.display()
        )
    );

    // an RGB-D folder without camera.json; a VLMaps folder without obstacles.npy
    let empty = d.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let e = one_line_error(&build(&["--rgbd", s(&empty)]));
    assert!(
        e.contains(&empty.join("camera.json").display().to_string()),
        "{e}"
    );
    let e = one_line_error(&build(&["--vlmaps", s(&empty)]));
    assert!(
        e.contains(&empty.display().to_string()) && e.contains("obstacles.npy"),
        "{e}"
    );
    assert!(!out.exists(), "nothing written on errors");
}
