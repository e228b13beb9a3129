//! `ivlmap map build`: a saved map folder (the `ivlmap-map/1` folder that `map
//! inspect`, `map render` and every `--scene` option read) built from what a
//! perception stack produces, with a summary of the instances kept and the masks
//! dropped (and why). Three sources of the base layers:
//!
//! - perception outputs: `--labels LABELS.npy --categories cats.txt` (the per-pixel
//!   argmax of the pixel-text similarity and its category list), `--sam MASKS.json`
//!   (SAM's masks), optional `--rgb TOPDOWN.png|.npy` (the paper's B, for colours)
//!   and `--obstacles OBST.npy`; the grid is the label map's, `--cell-size` metres a
//!   cell, its south-west corner at `--origin` (default 0, 0);
//! - `--rgbd DATASET_DIR`: the bird's-eye reconstruction (Eq. 1) gives the grid,
//!   obstacles and top-down colour; `--sam`/`--labels`/`--categories` on that grid
//!   add instances, otherwise the map has obstacles and colour only;
//! - `--vlmaps DIR`: a VLMaps legacy map folder; with `--clip-text-encoder`,
//!   `--clip-tokenizer` and `--categories`, each cell is labelled by `P = Q x E^T`
//!   (its LSeg/CLIP feature against the category embeddings).
//!
//! Instances come from `--sam` masks labelled by Eq. 2; without `--sam` but with a
//! label map, from the connected regions (8-neighbour) of each object category.
//! Files other than the map's own: `topdown.png`, the top-down colour, whenever
//! there is one.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use map_build::embed::{label_cells, TextEncoder, TextEncoderOptions};
use map_build::perception::{
    build_map, read_sam_masks, BuildConfig, BuiltMap, DropReason, LabelConfig, LabelMap, Mask,
    PerceptionInputs, DEFAULT_ROBOT_RADIUS_M,
};
use map_build::reconstruct::{
    import_vlmaps_legacy, pose2d_from_base, read_rgb_png, reconstruct, write_rgb_png,
    ReconstructOptions, RgbdDataset, VlmapsImportOptions,
};
use map_core::npy::NdData;
use map_core::{Cell, Grid, GridFrame, Point, Pose};

use crate::error::CliError;

/// The top-down colour written beside the map files.
pub const TOPDOWN_PNG: &str = "topdown.png";

/// Arguments of `ivlmap map build`.
#[derive(Debug, clap::Args)]
pub struct MapBuildArgs {
    /// The map folder to write (created; map files in it are overwritten).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// SAM masks (JSON list; COCO RLE or boolean rows), one per instance candidate.
    #[arg(long, value_name = "MASKS.json")]
    pub sam: Option<PathBuf>,
    /// Per-pixel category label map (2-D integer .npy; value k = line k of --categories).
    #[arg(long, value_name = "LABELS.npy", requires = "categories")]
    pub labels: Option<PathBuf>,
    /// Category names, one a line (blank lines and `#` comments skipped); the first is
    /// the background ("other") unless --background says otherwise.
    #[arg(long, value_name = "CATS.txt")]
    pub categories: Option<PathBuf>,
    /// Top-down colour image (the paper's B): PNG, or a uint8 (H, W, 3) .npy.
    #[arg(long, value_name = "TOPDOWN.png|.npy", conflicts_with_all = ["rgbd", "vlmaps"])]
    pub rgb: Option<PathBuf>,
    /// Obstacle layer (2-D .npy, bool or numbers; non-zero = occupied). Default: every
    /// cell labelled with an object category.
    #[arg(long, value_name = "OBST.npy", conflicts_with_all = ["rgbd", "vlmaps"])]
    pub obstacles: Option<PathBuf>,
    /// An RGB-D dataset folder (ivlmap-rgbd/1: camera.json, poses.txt, rgb/, depth/).
    #[arg(long, value_name = "DATASET_DIR", conflicts_with = "vlmaps")]
    pub rgbd: Option<PathBuf>,
    /// A VLMaps legacy map folder (obstacles.npy, color_top_down_1.npy, grid_lseg_1.npy).
    #[arg(long, value_name = "DIR", conflicts_with = "labels")]
    pub vlmaps: Option<PathBuf>,
    /// ONNX text encoder whose embeddings match the VLMaps features (CLIP's text tower).
    #[arg(
        long,
        value_name = "MODEL.onnx",
        requires_all = ["vlmaps", "clip_tokenizer", "categories"]
    )]
    pub clip_text_encoder: Option<PathBuf>,
    /// The encoder's tokenizer.json.
    #[arg(long, value_name = "tokenizer.json", requires = "clip_text_encoder")]
    pub clip_tokenizer: Option<PathBuf>,
    /// Category names that are no object (comma-separated; default: the first category).
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    pub background: Vec<String>,
    /// Perception outputs: metres per cell.
    #[arg(long, default_value_t = 0.05, conflicts_with_all = ["rgbd"])]
    pub cell_size: f64,
    /// Perception outputs: world position (x, y) of the grid's south-west corner.
    #[arg(long, value_name = "X,Y", value_delimiter = ',', conflicts_with_all = ["rgbd", "vlmaps"])]
    pub origin: Option<Vec<f64>>,
    /// Eq. 2: lowest share of a mask's pixels the category label must cover.
    #[arg(long, default_value_t = 0.3)]
    pub min_score: f64,
    /// Eq. 2: fewest pixels a mask (and its visible part) must have.
    #[arg(long, default_value_t = 4)]
    pub min_area: u64,
    /// The map's name (default: the output folder's name).
    #[arg(long)]
    pub name: Option<String>,
    /// Robot start pose (heading in compass degrees; default: the first camera pose for
    /// --rgbd, the VLMaps origin for --vlmaps, else the centre of the map).
    #[arg(long, value_name = "X,Y,HEADING", value_delimiter = ',')]
    pub start: Option<Vec<f64>>,
    /// Robot radius, metres.
    #[arg(long, default_value_t = DEFAULT_ROBOT_RADIUS_M)]
    pub robot_radius: f64,
}

/// Base layers from one of the three sources.
struct Base {
    what: String,
    frame: GridFrame,
    obstacles: Option<Grid<bool>>,
    rgb: Option<Grid<[u8; 3]>>,
    rgb_observed: Option<Grid<bool>>,
    start: Option<Pose>,
    /// A label map already made (the encoder's), with its background labels.
    labels: Option<(LabelMap, Vec<u16>, String)>,
    /// Full-grid size a mask file may have, and the window of it the map keeps.
    crop: Option<(usize, usize, usize, usize)>,
    notes: Vec<String>,
}

/// Runs `ivlmap map build`: reads the inputs, builds the map, saves the folder and
/// prints the summary on stdout.
///
/// # Errors
/// [`CliError::Input`] naming the file (and line, field or cell) of a bad input;
/// [`CliError::Output`] when the folder cannot be written.
pub fn map_build(args: &MapBuildArgs) -> Result<(), CliError> {
    if !(args.cell_size.is_finite() && args.cell_size > 0.0) {
        return Err(CliError::Input(format!(
            "--cell-size must be a positive number of metres, got {}",
            args.cell_size
        )));
    }
    if !(0.0..=1.0).contains(&args.min_score) {
        return Err(CliError::Input(format!(
            "--min-score must be in [0, 1], got {}",
            args.min_score
        )));
    }
    if let Some(o) = args.origin.as_deref().filter(|o| o.len() != 2) {
        return Err(CliError::Input(format!(
            "--origin takes X,Y (two numbers), got {} numbers",
            o.len()
        )));
    }
    if let Some(p) = args.start.as_deref().filter(|p| p.len() != 3) {
        return Err(CliError::Input(format!(
            "--start takes X,Y,HEADING (three numbers), got {} numbers",
            p.len()
        )));
    }
    let categories = args
        .categories
        .as_deref()
        .map(read_categories)
        .transpose()?;
    let base = if let Some(dir) = &args.rgbd {
        rgbd_base(dir)?
    } else if let Some(dir) = &args.vlmaps {
        vlmaps_base(args, dir, categories.as_deref())?
    } else if let Some(labels) = &args.labels {
        perception_base(args, labels)?
    } else {
        return Err(CliError::Input(
            "nothing to build from: give --labels LABELS.npy --categories CATS.txt [--sam MASKS.json] (perception outputs), --rgbd DATASET_DIR or --vlmaps DIR".into(),
        ));
    };
    if args.sam.is_some() && args.labels.is_none() && base.labels.is_none() {
        return Err(CliError::Input(
            "--sam needs a label map to name the masks: give --labels LABELS.npy --categories CATS.txt (or, with --vlmaps, --clip-text-encoder)".into(),
        ));
    }

    // The label map: from a file on the base grid, or the encoder's.
    let labelled: Option<(LabelMap, Vec<u16>, String)> = match (&args.labels, categories) {
        (Some(path), Some(cats)) => {
            let bg = background_labels(&args.background, &cats, 0, args)?;
            let grid = read_labels(path, cats.len(), args)?;
            check_frame(path, "label map", grid.rows(), grid.cols(), &base)?;
            let map = LabelMap::new(grid, cats).map_err(|e| at(path, e))?;
            Some((map, bg, path.display().to_string()))
        }
        _ => base.labels.clone(),
    };

    let frame = base.frame;
    let mut notes = base.notes.clone();
    let obstacles = match (&base.obstacles, &labelled) {
        (Some(o), _) => o.clone(),
        (None, Some((l, bg, _))) => {
            notes.push(
                "no --obstacles: every cell labelled with an object category is an obstacle".into(),
            );
            l.labels().map(|v| !bg.contains(v))
        }
        (None, None) => Grid::new(frame.rows, frame.cols, false),
    };

    let name = args.name.clone().unwrap_or_else(|| {
        args.out
            .file_name()
            .map_or_else(|| "map".to_string(), |n| n.to_string_lossy().to_string())
    });

    let (label_map, background, label_source) = match labelled {
        Some(l) => l,
        None => {
            // Obstacles and colour only.
            let mut inputs = PerceptionInputs::new(
                name.clone(),
                frame,
                obstacles,
                LabelMap::new(Grid::new(frame.rows, frame.cols, 0), vec!["other".into()])
                    .map_err(CliError::input)?,
                Vec::new(),
            );
            finish_inputs(&mut inputs, &base, args);
            let built = build_map(&inputs, &BuildConfig::default()).map_err(CliError::input)?;
            notes.push("no label map: obstacles and top-down colour only, no instances".into());
            return save_and_report(args, &base, &notes, &built, 0);
        }
    };

    let masks: Vec<Mask> = match &args.sam {
        Some(path) => {
            let sam = read_sam_masks(path).map_err(CliError::input)?;
            let mut out = Vec::with_capacity(sam.len());
            for m in sam {
                out.push(fit_mask(path, m.segmentation, &base)?);
            }
            out
        }
        None => {
            let (masks, small) = regions(label_map.labels(), &background, args.min_area);
            notes.push(format!(
                "no --sam: instances are the connected regions of each category in {label_source} ({} regions, {small} smaller than {} cells ignored)",
                masks.len(),
                args.min_area
            ));
            masks
        }
    };
    let n_masks = masks.len();
    let mut inputs = PerceptionInputs::new(name, frame, obstacles, label_map, masks);
    finish_inputs(&mut inputs, &base, args);
    let config = BuildConfig {
        labelling: LabelConfig {
            background,
            min_score: args.min_score,
            min_area: args.min_area,
            ..LabelConfig::default()
        },
        ..BuildConfig::default()
    };
    let mut built = build_map(&inputs, &config).map_err(CliError::input)?;
    // Objects are obstacles (a saved map's instance cells must be occupied): cells of
    // an instance that the obstacle layer missed (unseen sides, a partial scan) join it.
    let m = &mut built.map;
    let mut added = 0usize;
    for (o, &id) in m
        .obstacles
        .as_mut_slice()
        .iter_mut()
        .zip(m.instance.as_slice())
    {
        if id != 0 && !*o {
            *o = true;
            added += 1;
        }
    }
    if added > 0 {
        notes.push(format!(
            "{added} instance cells were not obstacles and are now (objects are obstacles)"
        ));
    }
    save_and_report(args, &base, &notes, &built, n_masks)
}

fn finish_inputs(inputs: &mut PerceptionInputs, base: &Base, args: &MapBuildArgs) {
    inputs.rgb.clone_from(&base.rgb);
    inputs.rgb_observed.clone_from(&base.rgb_observed);
    inputs.robot_radius = args.robot_radius;
    if let Some(p) = base.start {
        inputs.start_pose = p;
    }
    if let Some(s) = &args.start {
        if let [x, y, h] = s[..] {
            inputs.start_pose = Pose::new(x, y, h);
        }
    }
}

fn save_and_report(
    args: &MapBuildArgs,
    base: &Base,
    notes: &[String],
    built: &BuiltMap,
    n_masks: usize,
) -> Result<(), CliError> {
    let out = &args.out;
    built.map.save(out).map_err(|e| CliError::output(out, e))?;
    let mut files =
        "map.json, instances.json, obstacles.npy, category.npy, instance.npy, colour.npy"
            .to_string();
    if let Some(rgb) = &base.rgb {
        let p = out.join(TOPDOWN_PNG);
        // unobserved cells (RGB-D) in white, as SAM should see the image
        let mut img = rgb.clone();
        if let Some(seen) = &base.rgb_observed {
            for (px, &s) in img.as_mut_slice().iter_mut().zip(seen.as_slice()) {
                if !s {
                    *px = [255, 255, 255];
                }
            }
        }
        write_rgb_png(&p, &img).map_err(|e| CliError::output(&p, e))?;
        files.push_str(", ");
        files.push_str(TOPDOWN_PNG);
    }
    print!("{}", summary(base, notes, built, n_masks));
    println!("saved to {} ({files})", out.display());
    Ok(())
}

/// The summary printed by `map build`.
fn summary(base: &Base, notes: &[String], built: &BuiltMap, n_masks: usize) -> String {
    let m = &built.map;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "built map {:?} from {}: {} x {} cells of {:.3} m, bounds {:?}",
        m.name,
        base.what,
        m.frame.cols,
        m.frame.rows,
        m.frame.cell_size,
        m.frame.bounds()
    );
    for n in notes {
        let _ = writeln!(s, "  note: {n}");
    }
    let _ = writeln!(
        s,
        "{} masks: {} instances kept, {} dropped",
        n_masks,
        built.kept.len(),
        built.dropped.len()
    );
    if !m.instances.is_empty() {
        let counts: Vec<String> = m
            .label_counts()
            .iter()
            .map(|(l, n)| format!("{l} {n}"))
            .collect();
        let _ = writeln!(s, "instances by category: {}", counts.join(", "));
    }
    if !built.dropped.is_empty() {
        let mut by_kind: BTreeMap<&str, usize> = BTreeMap::new();
        for d in &built.dropped {
            *by_kind.entry(reason_kind(&d.reason)).or_default() += 1;
        }
        let kinds: Vec<String> = by_kind.iter().map(|(k, n)| format!("{k} {n}")).collect();
        let _ = writeln!(s, "dropped by reason: {}", kinds.join(", "));
        const SHOWN: usize = 40;
        for d in built.dropped.iter().take(SHOWN) {
            let _ = writeln!(s, "  dropped mask {}: {}", d.mask, d.reason);
        }
        if built.dropped.len() > SHOWN {
            let _ = writeln!(s, "  ... and {} more", built.dropped.len() - SHOWN);
        }
    }
    s
}

fn reason_kind(r: &DropReason) -> &'static str {
    match r {
        DropReason::TooSmall { .. } => "too small",
        DropReason::NoObjectLabel { .. } => "no object label",
        DropReason::LowScore { .. } => "low score",
        DropReason::Covered { .. } => "covered",
    }
}

fn at(path: &Path, e: impl std::fmt::Display) -> CliError {
    CliError::Input(format!("{}: {e}", path.display()))
}

/// The category list: one name a line, trimmed; blank lines and `#` comments skipped.
fn read_categories(path: &Path) -> Result<Vec<String>, CliError> {
    let text = std::fs::read_to_string(path).map_err(|e| at(path, e))?;
    let mut out: Vec<String> = Vec::new();
    let mut first_line: Vec<usize> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let name = line.trim();
        if name.is_empty() || name.starts_with('#') {
            continue;
        }
        if let Some(k) = out.iter().position(|c| c == name) {
            return Err(CliError::Input(format!(
                "{}:{}: category {name:?} is already on line {}",
                path.display(),
                i + 1,
                first_line[k]
            )));
        }
        out.push(name.to_string());
        first_line.push(i + 1);
    }
    if out.is_empty() {
        return Err(CliError::Input(format!(
            "{}: no categories (one name a line)",
            path.display()
        )));
    }
    if out.len() > usize::from(u16::MAX) {
        return Err(CliError::Input(format!(
            "{}: {} categories, at most {} fit a u16 label layer",
            path.display(),
            out.len(),
            u16::MAX
        )));
    }
    Ok(out)
}

/// Background labels: `--background` names looked up in `cats` (label = index +
/// `shift`), or the first category.
fn background_labels(
    names: &[String],
    cats: &[String],
    shift: u16,
    args: &MapBuildArgs,
) -> Result<Vec<u16>, CliError> {
    if names.is_empty() {
        return Ok(vec![shift]);
    }
    names
        .iter()
        .map(|n| {
            cats.iter()
                .position(|c| c == n.trim())
                .and_then(|i| u16::try_from(i).ok())
                .map(|i| i + shift)
                .ok_or_else(|| {
                    CliError::Input(format!(
                        "--background: {n:?} is not in {}",
                        args.categories
                            .as_deref()
                            .map_or_else(String::new, |p| p.display().to_string())
                    ))
                })
        })
        .collect()
}

fn check_frame(
    path: &Path,
    what: &str,
    rows: usize,
    cols: usize,
    base: &Base,
) -> Result<(), CliError> {
    let f = base.frame;
    if (rows, cols) == (f.rows, f.cols) {
        return Ok(());
    }
    Err(CliError::Input(format!(
        "{}: {what} is {rows} x {cols} (rows x cols), but the map grid from {} is {} x {}",
        path.display(),
        base.what,
        f.rows,
        f.cols
    )))
}

/// A mask on the map grid: as is, or cut out of VLMaps' full grid.
fn fit_mask(path: &Path, m: Mask, base: &Base) -> Result<Mask, CliError> {
    let f = base.frame;
    if (m.rows(), m.cols()) == (f.rows, f.cols) {
        return Ok(m);
    }
    if let Some((full_rows, full_cols, row0, col0)) = base.crop {
        if (m.rows(), m.cols()) == (full_rows, full_cols) {
            let cells = m.cells().filter_map(|c| {
                let (r, k) = (c.row.checked_sub(row0)?, c.col.checked_sub(col0)?);
                (r < f.rows && k < f.cols).then_some(Cell::new(r, k))
            });
            return Ok(Mask::from_cells(f.rows, f.cols, cells));
        }
    }
    check_frame(path, "the masks' size", m.rows(), m.cols(), base)?;
    Ok(m)
}

/// Connected regions (8-neighbour) of each non-background label with at least
/// `min_area` cells, and how many smaller ones were left out. A breadth-first fill
/// written here: the one step it needs does not justify an image-processing crate.
fn regions(labels: &Grid<u16>, background: &[u16], min_area: u64) -> (Vec<Mask>, usize) {
    let (rows, cols) = (labels.rows(), labels.cols());
    let v = labels.as_slice();
    let mut seen = vec![false; v.len()];
    let mut out = Vec::new();
    let mut small = 0;
    let mut queue = std::collections::VecDeque::new();
    for start in 0..v.len() {
        if seen[start] || background.contains(&v[start]) {
            continue;
        }
        let l = v[start];
        let mut cells = vec![start];
        seen[start] = true;
        queue.push_back(start);
        while let Some(i) = queue.pop_front() {
            let (r, c) = (i / cols, i % cols);
            for dr in -1isize..=1 {
                for dc in -1isize..=1 {
                    let (rr, cc) = (r as isize + dr, c as isize + dc);
                    if rr < 0 || cc < 0 || rr >= rows as isize || cc >= cols as isize {
                        continue;
                    }
                    let j = rr as usize * cols + cc as usize;
                    if !seen[j] && v[j] == l {
                        seen[j] = true;
                        cells.push(j);
                        queue.push_back(j);
                    }
                }
            }
        }
        if (cells.len() as u64) < min_area.max(1) {
            small += 1;
            continue;
        }
        out.push(Mask::from_cells(
            rows,
            cols,
            cells.into_iter().map(|i| Cell::new(i / cols, i % cols)),
        ));
    }
    (out, small)
}

/// Base layers of perception outputs: the label map's grid, optional obstacles and RGB.
fn perception_base(args: &MapBuildArgs, labels: &Path) -> Result<Base, CliError> {
    let (rows, cols) = npy_2d_shape(labels)?;
    let cs = args.cell_size;
    let (x0, y0) = match args.origin.as_deref() {
        Some([x, y]) => (*x, *y),
        _ => (0.0, 0.0),
    };
    let frame = GridFrame {
        origin: Point::new(x0, y0 + rows as f64 * cs),
        cell_size: cs,
        rows,
        cols,
    };
    let mut base = Base {
        what: format!("perception outputs ({})", labels.display()),
        frame,
        obstacles: None,
        rgb: None,
        rgb_observed: None,
        start: None,
        labels: None,
        crop: None,
        notes: Vec::new(),
    };
    if let Some(p) = &args.obstacles {
        let g = read_number_grid(p)?;
        check_frame(p, "obstacle layer", g.rows(), g.cols(), &base)?;
        base.obstacles = Some(g.map(|&v| v != 0.0));
    }
    if let Some(p) = &args.rgb {
        let g = read_rgb(p)?;
        check_frame(p, "RGB image", g.rows(), g.cols(), &base)?;
        base.rgb = Some(g);
    }
    Ok(base)
}

/// Base layers of an RGB-D dataset's reconstruction.
fn rgbd_base(dir: &Path) -> Result<Base, CliError> {
    let ds = RgbdDataset::open(dir).map_err(CliError::input)?;
    let maps = reconstruct(&ds, &ReconstructOptions::default()).map_err(CliError::input)?;
    let start = ds
        .world_poses()
        .frames
        .first()
        .map(|f| pose2d_from_base(&f.base));
    let observed = maps.hits.map(|&h| h > 0);
    Ok(Base {
        what: format!("RGB-D dataset {}", dir.display()),
        frame: maps.frame,
        notes: vec![format!(
            "reconstructed {} frames, {} points; {} of {} cells observed",
            maps.frames,
            maps.points,
            maps.observed_count(),
            maps.frame.rows * maps.frame.cols
        )],
        obstacles: Some(maps.obstacles),
        rgb: Some(maps.rgb),
        rgb_observed: Some(observed),
        start,
        labels: None,
        crop: None,
    })
}

/// Base layers of a VLMaps legacy map, labelled by the text encoder when given.
fn vlmaps_base(args: &MapBuildArgs, dir: &Path, cats: Option<&[String]>) -> Result<Base, CliError> {
    let encoder = match (&args.clip_text_encoder, &args.clip_tokenizer) {
        (Some(m), Some(t)) => Some((m, t)),
        _ => None,
    };
    let opts = VlmapsImportOptions {
        cell_size: args.cell_size,
        features: encoder.is_some(),
        ..VlmapsImportOptions::default()
    };
    let legacy = import_vlmaps_legacy(dir, &opts).map_err(CliError::input)?;
    let w = legacy.window;
    let mut notes = vec![format!(
        "VLMaps map version {}: kept rows {}..{}, cols {}..{} of the {} x {} grid",
        legacy.mask_version,
        w.row0,
        w.row0 + w.rows,
        w.col0,
        w.col0 + w.cols,
        w.full_rows,
        w.full_cols
    )];
    let origin = Point::new(0.0, 0.0);
    let start = legacy
        .frame
        .cell_at(origin)
        .is_some()
        .then(|| Pose::new(0.0, 0.0, 0.0));
    let labels = match (encoder, cats) {
        (Some((model, tok)), Some(cats)) => {
            let feat_path = legacy
                .files
                .iter()
                .find(|p| {
                    p.file_name()
                        .is_some_and(|n| n.to_string_lossy().starts_with("grid_lseg"))
                })
                .cloned();
            let Some(features) = legacy.features.clone() else {
                return Err(CliError::Input(format!(
                    "{}: no grid_lseg_{}.npy: the encoder needs the per-cell features",
                    dir.display(),
                    legacy.mask_version
                )));
            };
            let feat_path = feat_path.unwrap_or_else(|| dir.join("grid_lseg_1.npy"));
            let q = features.into_feature_map().map_err(|e| at(&feat_path, e))?;
            let enc = TextEncoder::new(model, tok, &TextEncoderOptions::default())
                .map_err(CliError::input)?;
            let names: Vec<&str> = cats.iter().map(String::as_str).collect();
            let e = enc.embed(&names).map_err(CliError::input)?;
            let out = label_cells(&q, &e).map_err(|err| at(&feat_path, err))?;
            // 0 = unobserved, k + 1 = category k.
            let mut all = vec!["(unobserved)".to_string()];
            all.extend(cats.iter().cloned());
            let mut bg = vec![0u16];
            bg.extend(background_labels(&args.background, cats, 1, args)?);
            let observed = out.labels.as_slice().iter().filter(|&&v| v != 0).count();
            notes.push(format!(
                "labelled {observed} observed cells with {} by P = Q x E^T over {} categories",
                model.display(),
                cats.len()
            ));
            let map = LabelMap::new(out.labels, all).map_err(|e| at(&feat_path, e))?;
            Some((map, bg, feat_path.display().to_string()))
        }
        _ => None,
    };
    Ok(Base {
        what: format!("VLMaps map {}", dir.display()),
        frame: legacy.frame,
        obstacles: Some(legacy.obstacles),
        rgb: legacy.rgb,
        rgb_observed: None,
        start,
        labels,
        crop: Some((w.full_rows, w.full_cols, w.row0, w.col0)),
        notes,
    })
}

// ---- .npy reading (map_core::npy: any integer, float or bool dtype; C or Fortran order) ----

/// An n-D array's shape and its values as f64 (integers up to 2^53 exactly).
struct NdValues {
    shape: Vec<usize>,
    dtype: String,
    values: Vec<f64>,
    integer: bool,
}

fn read_nd(path: &Path) -> Result<NdValues, CliError> {
    let arr = map_core::npy::read_array(path).map_err(CliError::input)?;
    let integer = !matches!(arr.data, NdData::F32(_) | NdData::F64(_));
    Ok(NdValues {
        values: arr.to_f64(),
        shape: arr.shape,
        dtype: arr.dtype,
        integer,
    })
}

fn npy_2d_shape(path: &Path) -> Result<(usize, usize), CliError> {
    match map_core::npy::nd::read_shape(path).map_err(CliError::input)?[..] {
        [r, c] => Ok((r, c)),
        ref s => Err(at(
            path,
            format!("expected a 2-D array (H, W), found shape {s:?}"),
        )),
    }
}

fn read_number_grid(path: &Path) -> Result<Grid<f64>, CliError> {
    let nd = read_nd(path)?;
    match nd.shape[..] {
        [r, c] => Grid::from_vec(r, c, nd.values).ok_or_else(|| at(path, "shape mismatch")),
        _ => Err(at(
            path,
            format!("expected a 2-D array (H, W), found shape {:?}", nd.shape),
        )),
    }
}

/// The label map: integers (or integral floats) in `0..n`.
fn read_labels(path: &Path, n: usize, args: &MapBuildArgs) -> Result<Grid<u16>, CliError> {
    let nd = read_nd(path)?;
    let [rows, cols] = nd.shape[..] else {
        return Err(at(
            path,
            format!(
                "expected a 2-D label map (H, W), found shape {:?}",
                nd.shape
            ),
        ));
    };
    let cats = args
        .categories
        .as_deref()
        .map_or_else(String::new, |p| p.display().to_string());
    let mut out = Vec::with_capacity(nd.values.len());
    for (i, &v) in nd.values.iter().enumerate() {
        if v.fract() != 0.0 || v < 0.0 || v >= n as f64 {
            let what = if nd.integer || v.fract() == 0.0 {
                format!("label {v}")
            } else {
                format!("{v}, not a whole number (dtype {})", nd.dtype)
            };
            return Err(CliError::Input(format!(
                "{}: cell (row {}, col {}) holds {what}, but {cats} has {n} categories (labels 0..{})",
                path.display(),
                i / cols.max(1),
                i % cols.max(1),
                n.saturating_sub(1)
            )));
        }
        out.push(v as u16);
    }
    Grid::from_vec(rows, cols, out).ok_or_else(|| at(path, "shape mismatch"))
}

/// A top-down colour image: PNG, or a uint8 (H, W, 3|4) .npy.
fn read_rgb(path: &Path) -> Result<Grid<[u8; 3]>, CliError> {
    let is_npy = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"));
    if !is_npy {
        return read_rgb_png(path).map_err(CliError::input);
    }
    let nd = read_nd(path)?;
    let (rows, cols, ch) = match nd.shape[..] {
        [r, c, ch @ (3 | 4)] if nd.dtype.ends_with("u1") => (r, c, ch),
        _ => {
            return Err(at(
                path,
                format!(
                    "expected a uint8 image of shape (H, W, 3), found {:?} of {}",
                    nd.shape, nd.dtype
                ),
            ))
        }
    };
    let px: Vec<[u8; 3]> = nd
        .values
        .chunks(ch)
        .map(|p| [p[0] as u8, p[1] as u8, p[2] as u8])
        .collect();
    Grid::from_vec(rows, cols, px).ok_or_else(|| at(path, "shape mismatch"))
}
