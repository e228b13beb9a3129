#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//! Our reconstruction with `anchor: first_frame` and VLMaps' grid puts every depth
//! point in the cell VLMaps' own mapping code would (`VLMapBuilder.
//! create_mobile_base_map`: `cvt_pose_vec2tf`, `base_transform`, `base2cam_tf`,
//! `depth2pc`, `base_pos2grid_id_3d`), transcribed below literally with nalgebra.

use std::collections::BTreeSet;

use map_build::reconstruct::{
    reconstruct, Anchor, CameraInfo, Intrinsics, MapSpec, PoseConvention, ReconstructOptions,
    RgbdDataset, RgbdFrame,
};
use map_core::Grid;
use nalgebra::{Matrix3, Matrix4, Quaternion, UnitQuaternion, Vector3, Vector4};

const GS: usize = 200;
const CS: f64 = 0.05;
const CAM_H: f64 = 1.5;
const W: usize = 64;
const H: usize = 48;

/// VLMaps `cvt_pose_vec2tf`: (px py pz qx qy qz qw) to a 4x4 matrix.
fn cvt_pose_vec2tf(v: &[f64; 7]) -> Matrix4<f64> {
    let q = UnitQuaternion::from_quaternion(Quaternion::new(v[6], v[3], v[4], v[5]));
    let mut t = q.to_homogeneous();
    t[(0, 3)] = v[0];
    t[(1, 3)] = v[1];
    t[(2, 3)] = v[2];
    t
}

/// VLMaps `Map._setup_transforms` with config/map_config/vlmaps.yaml.
fn vlmaps_transforms() -> (Matrix4<f64>, Matrix4<f64>) {
    let mut base2cam = Matrix4::identity();
    let rot = Matrix3::new(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0); // base2cam_rot
    base2cam.fixed_view_mut::<3, 3>(0, 0).copy_from(&rot);
    base2cam[(1, 3)] = CAM_H;
    let mut base_transform = Matrix4::identity();
    let rows = [[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]; // forward, left, up axes
    for (r, row) in rows.iter().enumerate() {
        for (c, &v) in row.iter().enumerate() {
            base_transform[(r, c)] = v;
        }
    }
    (base2cam, base_transform)
}

/// Python's int() on a float: truncation toward zero.
fn py_int(x: f64) -> i64 {
    x.trunc() as i64
}

/// VLMaps' (row, col, height) of pixel (u, v) at depth d in frame i.
fn vlmaps_cell(
    poses: &[[f64; 7]],
    i: usize,
    k: &Matrix3<f64>,
    u: usize,
    v: usize,
    d: f64,
) -> (i64, i64, i64) {
    let (base2cam, bt) = vlmaps_transforms();
    let bt_inv = bt.try_inverse().unwrap();
    let init_base = bt * cvt_pose_vec2tf(&poses[0]) * bt_inv;
    let base_pose = bt * cvt_pose_vec2tf(&poses[i]) * bt_inv;
    let tf = init_base.try_inverse().unwrap() * base_pose;
    let pc_transform = tf * bt * base2cam;
    // depth2pc: K^-1 (x + 0.5, y + 0.5, 1) * z
    let pc = k.try_inverse().unwrap() * Vector3::new(u as f64 + 0.5, v as f64 + 0.5, 1.0) * d;
    let p = pc_transform * Vector4::new(pc.x, pc.y, pc.z, 1.0);
    // base_pos2grid_id_3d
    let gs = GS as f64;
    let row = py_int(gs / 2.0 - py_int(p[0] / CS) as f64);
    let col = py_int(gs / 2.0 - py_int(p[1] / CS) as f64);
    let h = py_int(p[2] / CS);
    (row, col, h)
}

/// A tiny deterministic generator (no rand dependency needed for a test).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn cells_match_vlmaps_mobile_base_mapping() {
    // Habitat agent poses: floor at y = 0.7, yaws of 30, 100 and -60 degrees about y.
    let yaw_q = |deg: f64| {
        let h = deg.to_radians() / 2.0;
        [0.0, h.sin(), 0.0, h.cos()]
    };
    let mk = |p: [f64; 3], deg: f64| {
        let q = yaw_q(deg);
        [p[0], p[1], p[2], q[0], q[1], q[2], q[3]]
    };
    let poses = [
        mk([1.2, 0.7, -3.4], 30.0),
        mk([1.9, 0.7, -4.1], 100.0),
        mk([0.4, 0.7, -2.2], -60.0),
    ];
    let intr = Intrinsics::from_hfov(W as u32, H as u32, 90.0);
    let k = intr.k();

    // A few pixels per frame at random depths, kept when VLMaps keeps them (height
    // voxel in [1, vh - 1], i.e. well inside our floor margin .. camera height band)
    // and when they fall in distinct cells.
    let mut rng = Lcg(7);
    let mut frames = Vec::new();
    let mut expected: BTreeSet<(usize, usize)> = BTreeSet::new();
    let mut quadrants = [0usize; 4];
    for i in 0..poses.len() {
        let mut depth = Grid::new(H, W, 0.0f32);
        let mut n = 0;
        while n < 25 {
            let u = (rng.next() * W as f64) as usize;
            let v = H / 2 + 2 + (rng.next() * (H / 2 - 2) as f64) as usize;
            let d = 0.5 + rng.next() * 4.0;
            // the depth as stored (f32), so both sides see the same value
            let d = f64::from(d as f32);
            let (row, col, h) = vlmaps_cell(&poses, i, &k, u, v, d);
            let vh = (CAM_H / CS) as i64;
            let gs = GS as i64;
            if !(3..vh - 3).contains(&h)
                || !(1..gs - 1).contains(&row)
                || !(1..gs - 1).contains(&col)
            {
                continue;
            }
            let cell = (row as usize, col as usize);
            if expected.contains(&cell) || depth.get(map_core::Cell::new(v, u)) != Some(&0.0) {
                continue;
            }
            // VLMaps' truncation toward zero makes its centre row/column two cells
            // wide: south of / left of the origin its cells sit one closer to the
            // centre than ours (documented at vlmaps_grid_frame)
            let (mut r, mut c) = cell;
            let south = is_south(&poses, i, &k, u, v, d);
            let west = is_west(&poses, i, &k, u, v, d);
            if south {
                r += 1;
            }
            if west {
                c -= 1;
            }
            quadrants[usize::from(south) * 2 + usize::from(west)] += 1;
            if !expected.insert((r, c)) {
                continue;
            }
            depth.set(map_core::Cell::new(v, u), d as f32);
            n += 1;
        }
        frames.push(RgbdFrame {
            rgb: Grid::new(H, W, [200, 100, 50]),
            depth,
        });
    }
    assert!(
        quadrants.iter().all(|&q| q > 0),
        "points in every quadrant: {quadrants:?}"
    );

    let dir = tempfile::tempdir().unwrap();
    let cam = CameraInfo {
        intrinsics: intr,
        width: Some(W as u32),
        height: Some(H as u32),
        depth_scale: 1000.0,
        pose_convention: PoseConvention::HabitatBase,
        camera_height: CAM_H,
        anchor: Anchor::FirstFrame,
        map: Some(MapSpec::VlmapsGrid {
            grid_size: GS,
            cell_size: CS,
        }),
    };
    let records: Vec<_> = poses
        .iter()
        .map(|p| {
            map_build::reconstruct::parse_poses_txt(
                &p.map(|x| x.to_string()).join(" "),
                "p".as_ref(),
            )
            .unwrap()[0]
        })
        .collect();
    RgbdDataset::write(dir.path(), &cam, &frames, &records).unwrap();
    let ds = RgbdDataset::open(dir.path()).unwrap();
    let maps = reconstruct(
        &ds,
        &ReconstructOptions {
            stride: 1,
            max_depth: 10.0,
            ..Default::default()
        },
    )
    .unwrap();
    let got: BTreeSet<(usize, usize)> = maps
        .hits
        .iter_cells()
        .filter(|(_, &h)| h > 0)
        .map(|(c, _)| (c.row, c.col))
        .collect();
    assert_eq!(got.len(), 75);
    assert_eq!(got, expected);
    assert!(maps.obstacles.as_slice().iter().filter(|&&o| o).count() == 75);
}

/// Whether the point's forward coordinate in VLMaps' first-base frame is negative.
fn is_south(poses: &[[f64; 7]], i: usize, k: &Matrix3<f64>, u: usize, v: usize, d: f64) -> bool {
    base_point(poses, i, k, u, v, d).x < 0.0
}

/// Whether the point's left coordinate is positive (it lies left = west of the origin).
fn is_west(poses: &[[f64; 7]], i: usize, k: &Matrix3<f64>, u: usize, v: usize, d: f64) -> bool {
    base_point(poses, i, k, u, v, d).y > 0.0
}

fn base_point(
    poses: &[[f64; 7]],
    i: usize,
    k: &Matrix3<f64>,
    u: usize,
    v: usize,
    d: f64,
) -> Vector3<f64> {
    let (base2cam, bt) = vlmaps_transforms();
    let bt_inv = bt.try_inverse().unwrap();
    let init_base = bt * cvt_pose_vec2tf(&poses[0]) * bt_inv;
    let base_pose = bt * cvt_pose_vec2tf(&poses[i]) * bt_inv;
    let tf = init_base.try_inverse().unwrap() * base_pose;
    let pc = k.try_inverse().unwrap() * Vector3::new(u as f64 + 0.5, v as f64 + 0.5, 1.0) * d;
    let p = tf * bt * base2cam * Vector4::new(pc.x, pc.y, pc.z, 1.0);
    Vector3::new(p[0], p[1], p[2])
}
