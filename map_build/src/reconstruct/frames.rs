//! RGB-D frames (colour PNG, depth `.npy` or 16-bit PNG) and the dataset folder
//! reader that pairs them with `poses.txt` and `camera.json`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nalgebra::Isometry3;

use super::camera::CameraInfo;
use super::poses::{read_poses_txt, world_poses, WorldPoses};
use super::ReconstructError;
use map_core::grid::Grid;
use map_core::npy::nd::{self as ndnpy, NdData};

/// One RGB-D frame: colour and depth of the same size (rows = image height).
#[derive(Debug, Clone, PartialEq)]
pub struct RgbdFrame {
    /// Colour image, row 0 = top of the image.
    pub rgb: Grid<[u8; 3]>,
    /// Depth along the optical axis in metres; 0 (or non-finite) = no reading.
    pub depth: Grid<f32>,
}

impl RgbdFrame {
    /// Image width in pixels.
    pub fn width(&self) -> usize {
        self.depth.cols()
    }

    /// Image height in pixels.
    pub fn height(&self) -> usize {
        self.depth.rows()
    }
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ReconstructError + '_ {
    move |source| ReconstructError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn image_err(path: &Path) -> impl FnOnce(image::ImageError) -> ReconstructError + '_ {
    move |source| ReconstructError::Image {
        path: path.to_path_buf(),
        source,
    }
}

fn decode(path: &Path) -> Result<image::DynamicImage, ReconstructError> {
    image::ImageReader::open(path)
        .map_err(io_err(path))?
        .with_guessed_format()
        .map_err(io_err(path))?
        .decode()
        .map_err(image_err(path))
}

/// Read a colour PNG (grey, RGB or RGBA; alpha dropped, 16-bit scaled to 8).
pub fn read_rgb_png(path: impl AsRef<Path>) -> Result<Grid<[u8; 3]>, ReconstructError> {
    let path = path.as_ref();
    let img = decode(path)?.to_rgb8();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let data: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    Grid::from_vec(h, w, data).ok_or_else(|| ReconstructError::Array {
        path: path.to_path_buf(),
        message: "decoded image has the wrong number of pixels".into(),
    })
}

/// Write a colour PNG.
pub fn write_rgb_png(path: impl AsRef<Path>, rgb: &Grid<[u8; 3]>) -> Result<(), ReconstructError> {
    let path = path.as_ref();
    let img = image::RgbImage::from_fn(rgb.cols() as u32, rgb.rows() as u32, |x, y| {
        image::Rgb(
            rgb.get(map_core::grid::Cell::new(y as usize, x as usize))
                .copied()
                .unwrap_or_default(),
        )
    });
    img.save_with_format(path, image::ImageFormat::Png)
        .map_err(image_err(path))
}

/// Read a depth image in metres: `.npy` of shape (H, W) or (H, W, 1) holding float
/// metres (float32/float64) or integer units (uint16, int32, ...) divided by
/// `depth_scale` (units per metre); or a 16-bit grey PNG divided by `depth_scale`.
pub fn read_depth(path: impl AsRef<Path>, depth_scale: f64) -> Result<Grid<f32>, ReconstructError> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("npy") => read_depth_npy(path, depth_scale),
        Some("png") => read_depth_png(path, depth_scale),
        _ => Err(ReconstructError::Array {
            path: path.to_path_buf(),
            message: "depth files must be .npy or 16-bit .png".into(),
        }),
    }
}

fn read_depth_npy(path: &Path, depth_scale: f64) -> Result<Grid<f32>, ReconstructError> {
    let arr = ndnpy::read_array(path)?;
    let (h, w) = match arr.shape[..] {
        [h, w] | [h, w, 1] => (h, w),
        _ => {
            return Err(ReconstructError::Array {
                path: path.to_path_buf(),
                message: format!(
                    "expected a depth array of shape (H, W) or (H, W, 1), found {} of {}",
                    arr.shape_str(),
                    arr.dtype
                ),
            })
        }
    };
    if matches!(arr.data, NdData::Bool(_)) {
        return Err(ReconstructError::Array {
            path: path.to_path_buf(),
            message: format!(
                "expected depth as float32/float64 metres or integer units, found dtype {}",
                arr.dtype
            ),
        });
    }
    let data: Vec<f32> = match arr.data {
        NdData::F32(v) => v,
        NdData::F64(v) => v.into_iter().map(|x| x as f32).collect(),
        _ => arr
            .to_f64()
            .into_iter()
            .map(|x| (x / depth_scale) as f32)
            .collect(),
    };
    Grid::from_vec(h, w, data).ok_or_else(|| ReconstructError::Array {
        path: path.to_path_buf(),
        message: "element count does not match the shape".into(),
    })
}

fn read_depth_png(path: &Path, depth_scale: f64) -> Result<Grid<f32>, ReconstructError> {
    let img = decode(path)?;
    let found = format!("{:?}", img.color());
    let image::DynamicImage::ImageLuma16(g) = img else {
        return Err(ReconstructError::Array {
            path: path.to_path_buf(),
            message: format!("a depth PNG must be 16-bit greyscale (L16), found {found}"),
        });
    };
    let (w, h) = (g.width() as usize, g.height() as usize);
    let data = g
        .pixels()
        .map(|p| (f64::from(p.0[0]) / depth_scale) as f32)
        .collect();
    Grid::from_vec(h, w, data).ok_or_else(|| ReconstructError::Array {
        path: path.to_path_buf(),
        message: "decoded image has the wrong number of pixels".into(),
    })
}

/// Write depth in metres as a float32 `(H, W)` `.npy` (VLMaps' form).
pub fn write_depth_npy(path: impl AsRef<Path>, depth: &Grid<f32>) -> Result<(), ReconstructError> {
    let path = path.as_ref();
    map_core::npy::write_npy(path, depth).map_err(|e| ReconstructError::Array {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// Write depth as a 16-bit PNG of `depth_scale` units per metre (0 = no reading;
/// depths beyond 65535 units are written as 0).
pub fn write_depth_png(
    path: impl AsRef<Path>,
    depth: &Grid<f32>,
    depth_scale: f64,
) -> Result<(), ReconstructError> {
    let path = path.as_ref();
    let px: Vec<u16> = depth
        .as_slice()
        .iter()
        .map(|&d| {
            let v = (f64::from(d) * depth_scale).round();
            if d.is_finite() && v > 0.0 && v <= 65535.0 {
                v as u16
            } else {
                0
            }
        })
        .collect();
    let img: image::ImageBuffer<image::Luma<u16>, Vec<u16>> =
        image::ImageBuffer::from_raw(depth.cols() as u32, depth.rows() as u32, px).ok_or_else(
            || ReconstructError::Array {
                path: path.to_path_buf(),
                message: "depth grid has the wrong number of pixels".into(),
            },
        )?;
    img.save_with_format(path, image::ImageFormat::Png)
        .map_err(image_err(path))
}

/// The files of one frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FrameFiles {
    /// The shared file stem, e.g. `000012`.
    pub stem: String,
    /// The colour PNG, `rgb/<stem>.png`.
    pub rgb: PathBuf,
    /// The depth file, `depth/<stem>.npy` or `.png`.
    pub depth: PathBuf,
}

/// An RGB-D dataset folder (layout in the module docs): frames paired by file stem
/// in sorted order, one pose per frame.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbdDataset {
    /// The dataset folder.
    pub root: PathBuf,
    /// Camera settings (from `camera.json`, or given by the caller).
    pub camera: CameraInfo,
    /// Each frame's files, in file-stem order.
    pub frames: Vec<FrameFiles>,
    /// `poses.txt` records, one per frame, as read (see [`RgbdDataset::world_poses`]).
    pub poses: Vec<Isometry3<f64>>,
}

impl RgbdDataset {
    /// Open a dataset folder with its `camera.json`.
    pub fn open(root: impl AsRef<Path>) -> Result<Self, ReconstructError> {
        let root = root.as_ref();
        let camera = CameraInfo::from_path(root.join("camera.json"))?;
        Self::open_with(root, camera)
    }

    /// Open a dataset folder with camera settings given by the caller (e.g.
    /// [`CameraInfo::vlmaps_habitat`] for a VLMaps dataset, which has no `camera.json`).
    pub fn open_with(root: impl AsRef<Path>, camera: CameraInfo) -> Result<Self, ReconstructError> {
        let root = root.as_ref().to_path_buf();
        let rgb = list_dir(&root.join("rgb"), &["png"])?;
        let depth = list_dir(&root.join("depth"), &["npy", "png"])?;
        let dataset_err = |message: String| ReconstructError::Dataset {
            path: root.clone(),
            message,
        };
        for (stem, p) in &depth {
            if !rgb.contains_key(stem) {
                return Err(dataset_err(format!(
                    "{} has no matching rgb/{stem}.png",
                    rel(&root, p)
                )));
            }
        }
        let mut frames = Vec::with_capacity(rgb.len());
        for (stem, p) in rgb {
            let Some(d) = depth.get(&stem) else {
                return Err(dataset_err(format!(
                    "{} has no matching depth/{stem}.npy (or .png)",
                    rel(&root, &p)
                )));
            };
            frames.push(FrameFiles {
                stem,
                rgb: p,
                depth: d.clone(),
            });
        }
        if frames.is_empty() {
            return Err(dataset_err("rgb/ holds no .png frames".into()));
        }
        let poses_path = root.join("poses.txt");
        let poses = read_poses_txt(&poses_path)?;
        if poses.len() != frames.len() {
            return Err(ReconstructError::Dataset {
                path: poses_path,
                message: format!(
                    "holds {} poses but rgb/ and depth/ hold {} frames (one pose per frame, in file-name order)",
                    poses.len(),
                    frames.len()
                ),
            });
        }
        Ok(Self {
            root,
            camera,
            frames,
            poses,
        })
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether there are no frames.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Base and camera poses in the map frame (convention and anchor from `camera`).
    pub fn world_poses(&self) -> WorldPoses {
        world_poses(
            &self.poses,
            self.camera.pose_convention,
            self.camera.camera_height,
            self.camera.anchor,
        )
    }

    /// Load frame `i`, checking that colour and depth sizes agree with each other
    /// and with `camera.json`.
    pub fn load_frame(&self, i: usize) -> Result<RgbdFrame, ReconstructError> {
        let f = self
            .frames
            .get(i)
            .ok_or_else(|| ReconstructError::Dataset {
                path: self.root.clone(),
                message: format!("no frame {i} (the dataset has {})", self.frames.len()),
            })?;
        let rgb = read_rgb_png(&f.rgb)?;
        let depth = read_depth(&f.depth, self.camera.depth_scale)?;
        if (rgb.rows(), rgb.cols()) != (depth.rows(), depth.cols()) {
            return Err(ReconstructError::Dataset {
                path: f.depth.clone(),
                message: format!(
                    "depth is {}x{} but {} is {}x{} (width x height)",
                    depth.cols(),
                    depth.rows(),
                    f.rgb.display(),
                    rgb.cols(),
                    rgb.rows()
                ),
            });
        }
        if let (Some(w), Some(h)) = (self.camera.width, self.camera.height) {
            if (rgb.cols(), rgb.rows()) != (w as usize, h as usize) {
                return Err(ReconstructError::Dataset {
                    path: f.rgb.clone(),
                    message: format!(
                        "image is {}x{} but camera.json says width {w}, height {h}",
                        rgb.cols(),
                        rgb.rows()
                    ),
                });
            }
        }
        Ok(RgbdFrame { rgb, depth })
    }

    /// Write a dataset folder: `camera.json`, `poses.txt`, `rgb/NNNNNN.png`,
    /// `depth/NNNNNN.npy` (float32 metres). `frames` and `poses` pair up in order.
    pub fn write(
        root: impl AsRef<Path>,
        camera: &CameraInfo,
        frames: &[RgbdFrame],
        poses: &[Isometry3<f64>],
    ) -> Result<(), ReconstructError> {
        let root = root.as_ref();
        if frames.len() != poses.len() {
            return Err(ReconstructError::Dataset {
                path: root.to_path_buf(),
                message: format!("{} frames but {} poses", frames.len(), poses.len()),
            });
        }
        for sub in ["rgb", "depth"] {
            let d = root.join(sub);
            std::fs::create_dir_all(&d).map_err(io_err(&d))?;
        }
        camera.write(root.join("camera.json"))?;
        super::poses::write_poses_txt(root.join("poses.txt"), poses)?;
        for (i, f) in frames.iter().enumerate() {
            write_rgb_png(root.join("rgb").join(format!("{i:06}.png")), &f.rgb)?;
            write_depth_npy(root.join("depth").join(format!("{i:06}.npy")), &f.depth)?;
        }
        Ok(())
    }
}

fn rel(root: &Path, p: &Path) -> String {
    p.strip_prefix(root).unwrap_or(p).display().to_string()
}

/// Files in `dir` with one of `exts`, keyed by stem (sorted). Two files with the
/// same stem are an error.
fn list_dir(dir: &Path, exts: &[&str]) -> Result<BTreeMap<String, PathBuf>, ReconstructError> {
    let mut out = BTreeMap::new();
    let entries = std::fs::read_dir(dir).map_err(io_err(dir))?;
    for e in entries {
        let e = e.map_err(io_err(dir))?;
        let p = e.path();
        let Some(ext) = p.extension().and_then(|x| x.to_str()) else {
            continue;
        };
        if !exts.contains(&ext.to_ascii_lowercase().as_str()) || !p.is_file() {
            continue;
        }
        let Some(stem) = p.file_stem().and_then(|s| s.to_str()).map(str::to_string) else {
            continue;
        };
        if let Some(prev) = out.insert(stem.clone(), p.clone()) {
            return Err(ReconstructError::Dataset {
                path: dir.to_path_buf(),
                message: format!(
                    "two files for frame {stem}: {} and {}",
                    prev.display(),
                    p.display()
                ),
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_forms_read_as_metres() {
        let dir = tempfile::tempdir().unwrap();
        let d = Grid::from_vec(2, 3, vec![0.0f32, 1.25, 2.5, 0.001, 3.0, 65.0]).unwrap();
        let npy = dir.path().join("d.npy");
        write_depth_npy(&npy, &d).unwrap();
        assert_eq!(read_depth(&npy, 1000.0).unwrap(), d);

        let png = dir.path().join("d.png");
        write_depth_png(&png, &d, 1000.0).unwrap();
        let back = read_depth(&png, 1000.0).unwrap();
        // 65 m is 65000 mm, still in range; 1 mm survives
        assert_eq!(back, d);

        let u16npy = dir.path().join("u.npy");
        ndnpy::write_array(&u16npy, &[1, 2], &[1500u16, 0]).unwrap();
        let g = read_depth(&u16npy, 1000.0).unwrap();
        assert_eq!(g.as_slice(), &[1.5, 0.0]);

        let bad = dir.path().join("rgb.npy");
        ndnpy::write_array(&bad, &[2, 2, 3], &[0u8; 12]).unwrap();
        let e = read_depth(&bad, 1000.0).unwrap_err().to_string();
        assert!(
            e.contains("rgb.npy") && e.contains("(2, 2, 3)") && e.contains("|u1"),
            "{e}"
        );
    }

    #[test]
    fn eight_bit_depth_png_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("d.png");
        let rgb = Grid::new(2, 2, [10u8, 10, 10]);
        write_rgb_png(&p, &rgb).unwrap();
        let e = read_depth(&p, 1000.0).unwrap_err().to_string();
        assert!(e.contains("16-bit") && e.contains("Rgb8"), "{e}");
    }
}
