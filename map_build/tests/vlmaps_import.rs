#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! VLMaps legacy map files (obstacles.npy, color_top_down_1.npy, grid_lseg_1.npy,
//! weight_lseg_1.npy, grid_1_gt.npy) land on the ivlmap grid where VLMaps put them.

use std::path::{Path, PathBuf};
use std::process::Command;

use npyz::WriterBuilder;

use map_build::reconstruct::{
    import_vlmaps_legacy, vlmaps_grid_frame, write_vlmaps_legacy, TopDownMaps, VlmapsCrop,
    VlmapsImportOptions,
};
use map_core::npy::write_npy;
use map_core::{Cell, Grid, Point};

const GS: usize = 40;
const CS: f64 = 0.05;
const DIM: usize = 8;
/// The occupied cell in VLMaps' indexing, and a second one further out.
const OCC: (usize, usize) = (12, 25);
const OCC2: (usize, usize) = (30, 8);

/// Write a C-order array of any shape with npyz (what np.save writes).
fn save<T: npyz::AutoSerialize + Copy>(path: &Path, shape: &[u64], data: &[T]) {
    let mut buf = Vec::new();
    let mut w = npyz::WriteOptions::new()
        .default_dtype()
        .shape(shape)
        .writer(&mut buf)
        .begin_nd()
        .unwrap();
    w.extend(data.iter().copied()).unwrap();
    w.finish().unwrap();
    std::fs::write(path, buf).unwrap();
}

fn feature(r: usize, c: usize, k: usize) -> f32 {
    (r * 1000 + c * 10 + k) as f32
}

/// A legacy map folder: everything free but two cells, distinct colours and features.
fn write_legacy(dir: &Path) {
    let mut obs = Grid::new(GS, GS, 1u8);
    obs.set(Cell::new(OCC.0, OCC.1), 0);
    obs.set(Cell::new(OCC2.0, OCC2.1), 0);
    write_npy(dir.join("obstacles.npy"), &obs).unwrap();
    let mut rgb = vec![0u8; GS * GS * 3];
    for r in 0..GS {
        for c in 0..GS {
            let i = (r * GS + c) * 3;
            rgb[i..i + 3].copy_from_slice(&[r as u8, c as u8, 7]);
        }
    }
    save(
        &dir.join("color_top_down_1.npy"),
        &[GS as u64, GS as u64, 3],
        &rgb,
    );
    let mut feats = Vec::with_capacity(GS * GS * DIM);
    for r in 0..GS {
        for c in 0..GS {
            for k in 0..DIM {
                feats.push(feature(r, c, k));
            }
        }
    }
    save(
        &dir.join("grid_lseg_1.npy"),
        &[GS as u64, GS as u64, DIM as u64],
        &feats,
    );
    let weight: Vec<f64> = (0..GS * GS).map(|i| (i % 5) as f64).collect();
    save(
        &dir.join("weight_lseg_1.npy"),
        &[GS as u64, GS as u64],
        &weight,
    );
    let gt: Vec<i32> = (0..GS * GS).map(|i| (i % 40) as i32).collect();
    save(&dir.join("grid_1_gt.npy"), &[GS as u64, GS as u64], &gt);
}

/// World point of the centre of VLMaps cell (row, col) in the first-pose frame:
/// VLMaps puts (right x, forward y) in row gs/2 - int(y/cs), column gs/2 + int(x/cs).
fn vlmaps_cell_centre(row: usize, col: usize) -> Point {
    let half = (GS / 2) as f64;
    Point::new(
        (col as f64 - half + 0.5) * CS,
        (half - row as f64 + 0.5) * CS,
    )
}

#[test]
fn a_known_cell_lands_where_vlmaps_put_it() {
    let dir = tempfile::tempdir().unwrap();
    write_legacy(dir.path());
    let m = import_vlmaps_legacy(
        dir.path(),
        &VlmapsImportOptions {
            crop: VlmapsCrop::ObstacleBBox { margin: 2 },
            ..Default::default()
        },
    )
    .unwrap();
    // crop: rows 12..30 and columns 8..25 grown by 2
    assert_eq!((m.window.row0, m.window.col0), (10, 6));
    assert_eq!((m.window.rows, m.window.cols), (23, 22));
    assert_eq!((m.frame.rows, m.frame.cols), (23, 22));
    assert_eq!(m.mask_version, 1);
    assert_eq!(m.files.len(), 5);

    for &(r, c) in &[OCC, OCC2] {
        let cell = m.frame.cell_at(vlmaps_cell_centre(r, c)).unwrap();
        assert_eq!((cell.row + m.window.row0, cell.col + m.window.col0), (r, c));
        assert_eq!(m.obstacles.get(cell), Some(&true));
        assert_eq!(
            m.rgb.as_ref().unwrap().get(cell),
            Some(&[r as u8, c as u8, 7])
        );
        let f = m.features.as_ref().unwrap().cell(cell).unwrap();
        assert_eq!(
            f,
            (0..DIM)
                .map(|k| feature(r, c, k))
                .collect::<Vec<_>>()
                .as_slice()
        );
        assert_eq!(
            m.weight.as_ref().unwrap().get(cell),
            Some(&(((r * GS + c) % 5) as f32))
        );
        assert_eq!(
            m.gt_classes.as_ref().unwrap().get(cell),
            Some(&(((r * GS + c) % 40) as i32))
        );
    }
    assert_eq!(m.obstacles.as_slice().iter().filter(|&&o| o).count(), 2);
    assert_eq!(m.features.as_ref().unwrap().shape(), [23, 22, DIM]);
    // the embedding layer takes the features as they are
    let fm = m.features.clone().unwrap().into_feature_map().unwrap();
    assert_eq!((fm.rows(), fm.cols(), fm.dim()), (23, 22, DIM));
    let c = m.frame.cell_at(vlmaps_cell_centre(OCC.0, OCC.1)).unwrap();
    assert_eq!(fm.cell(c.row, c.col), m.features.as_ref().unwrap().cell(c));
    // north-east of the origin the frame is VLMaps' pos2grid_id exactly
    let p = Point::new(0.26, 0.41); // right 0.26, forward 0.41
    let full = vlmaps_grid_frame(GS, GS, CS).cell_at(p).unwrap();
    assert_eq!(
        (full.row, full.col),
        (GS / 2 - (0.41 / CS) as usize, GS / 2 + (0.26 / CS) as usize)
    );
}

#[test]
fn full_crop_and_origin_override() {
    let dir = tempfile::tempdir().unwrap();
    write_legacy(dir.path());
    let m = import_vlmaps_legacy(
        dir.path(),
        &VlmapsImportOptions {
            crop: VlmapsCrop::Full,
            features: false,
            origin: Some(Point::new(10.0, 20.0)),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(m.features.is_none());
    assert_eq!(m.frame.origin, Point::new(10.0, 20.0));
    let c = m.frame.cell_center(Cell::new(OCC.0, OCC.1));
    assert!((c.x - (10.0 + (OCC.1 as f64 + 0.5) * CS)).abs() < 1e-9);
    assert_eq!(m.obstacles.get(Cell::new(OCC.0, OCC.1)), Some(&true));

    let w = import_vlmaps_legacy(
        dir.path(),
        &VlmapsImportOptions {
            crop: VlmapsCrop::Window {
                row0: 30,
                col0: 8,
                rows: 1,
                cols: 1,
            },
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(w.obstacles.as_slice(), &[true]);
    assert_eq!(
        w.features.unwrap().data,
        (0..DIM).map(|k| feature(30, 8, k)).collect::<Vec<_>>()
    );
}

#[test]
fn wrong_shapes_and_dtypes_say_expected_and_found() {
    let dir = tempfile::tempdir().unwrap();
    write_legacy(dir.path());
    // colour stored as float
    save(
        &dir.path().join("color_top_down_1.npy"),
        &[GS as u64, GS as u64, 3],
        &vec![0.5f32; GS * GS * 3],
    );
    let e = import_vlmaps_legacy(dir.path(), &VlmapsImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("color_top_down_1.npy") && e.contains("uint8") && e.contains("<f4"),
        "{e}"
    );

    // features of the wrong grid size
    write_legacy(dir.path());
    save(
        &dir.path().join("grid_lseg_1.npy"),
        &[GS as u64 - 1, GS as u64, 4],
        &vec![0f32; (GS - 1) * GS * 4],
    );
    let e = import_vlmaps_legacy(
        dir.path(),
        &VlmapsImportOptions {
            crop: VlmapsCrop::Full,
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("grid_lseg_1.npy") && e.contains("(39, 40, 4)"),
        "{e}"
    );

    // features as integers
    save(
        &dir.path().join("grid_lseg_1.npy"),
        &[GS as u64, GS as u64, 2],
        &vec![0i32; GS * GS * 2],
    );
    let e = import_vlmaps_legacy(dir.path(), &VlmapsImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("grid_lseg_1.npy") && e.contains("float32") && e.contains("<i4"),
        "{e}"
    );

    // a 3-D obstacle map
    save(&dir.path().join("obstacles.npy"), &[2, 2, 2], &[1u8; 8]);
    let e = import_vlmaps_legacy(dir.path(), &VlmapsImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("obstacles.npy") && e.contains("(H, W)") && e.contains("(2, 2, 2)"),
        "{e}"
    );

    let empty = tempfile::tempdir().unwrap();
    let e = import_vlmaps_legacy(empty.path(), &VlmapsImportOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no obstacles.npy"), "{e}");
}

#[test]
fn written_legacy_files_read_back() {
    let frame = vlmaps_grid_frame(30, 20, CS);
    let mut maps = TopDownMaps {
        frame,
        rgb: Grid::new(30, 20, [1, 2, 3]),
        height: Grid::new(30, 20, 0.0),
        obstacles: Grid::new(30, 20, false),
        hits: Grid::new(30, 20, 1),
        obstacle_hits: Grid::new(30, 20, 0),
        frames: 1,
        points: 600,
    };
    maps.obstacles.set(Cell::new(4, 17), true);
    maps.rgb.set(Cell::new(4, 17), [200, 10, 20]);
    let dir = tempfile::tempdir().unwrap();
    let files = write_vlmaps_legacy(dir.path(), &maps, 1).unwrap();
    assert_eq!(files.len(), 2);
    let m = import_vlmaps_legacy(
        dir.path(),
        &VlmapsImportOptions {
            crop: VlmapsCrop::Full,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(m.frame, frame);
    assert_eq!(m.obstacles, maps.obstacles);
    assert_eq!(m.rgb.unwrap(), maps.rgb);
    assert!(m.features.is_none() && m.weight.is_none());
}

fn python() -> Option<PathBuf> {
    let home = std::env::var_os("HOME")?;
    let p = PathBuf::from(home).join(".cache/ivlmap/venv-bench/bin/python");
    let ok = Command::new(&p)
        .args(["-c", "import numpy"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    ok.then_some(p)
}

/// Files written by numpy itself, as VLMaps writes them (np.save of uint8, float32,
/// float64 arrays), including a Fortran-ordered colour array.
#[test]
fn files_written_by_numpy() {
    let Some(py) = python() else {
        eprintln!("skipped: no numpy at ~/.cache/ivlmap/venv-bench/bin/python");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let script = format!(
        r#"
import numpy as np
gs, cs = {GS}, {CS}
d = r"{dir}"
obstacles = np.ones((gs, gs), dtype=np.uint8)
color = np.zeros((gs, gs, 3), dtype=np.uint8)
grid = np.zeros((gs, gs, {DIM}), dtype=np.float32)
weight = np.zeros((gs, gs), dtype=float)
# VLMaps' legacy builder: x, y = pos2grid_id(gs, cs, p[0], p[2]); grid[y, x]
def pos2grid_id(gs, cs, xx, yy):
    x = int(gs / 2 + int(xx / cs))
    y = int(gs / 2 - int(yy / cs))
    return [x, y]
x, y = pos2grid_id(gs, cs, 0.33, 0.52)   # 0.33 m right, 0.52 m forward
obstacles[y, x] = 0
color[y, x] = [9, 99, 199]
grid[y, x] = np.arange({DIM}, dtype=np.float32) + 0.5
weight[y, x] = 3.0
np.save(d + "/obstacles.npy", obstacles)
np.save(d + "/color_top_down_1.npy", np.asfortranarray(color))
np.save(d + "/grid_lseg_1.npy", grid)
np.save(d + "/weight_lseg_1.npy", weight)
"#,
        dir = dir.path().display()
    );
    let out = Command::new(&py).args(["-c", &script]).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let m = import_vlmaps_legacy(dir.path(), &VlmapsImportOptions::default()).unwrap();
    let cell = m.frame.cell_at(Point::new(0.33, 0.52)).unwrap();
    assert_eq!(m.obstacles.get(cell), Some(&true));
    assert_eq!(m.obstacles.as_slice().iter().filter(|&&o| o).count(), 1);
    assert_eq!(m.rgb.as_ref().unwrap().get(cell), Some(&[9, 99, 199]));
    let f = m.features.as_ref().unwrap().cell(cell).unwrap();
    assert_eq!(
        f,
        (0..DIM)
            .map(|k| k as f32 + 0.5)
            .collect::<Vec<_>>()
            .as_slice()
    );
    assert_eq!(m.weight.as_ref().unwrap().get(cell), Some(&3.0));
}
