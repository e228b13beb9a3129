//! Drawing a map (and a robot's run over it) as a PNG for people to look at.
//!
//! North is up (grid row 0 is the top row of the image), east is right. Layers, in
//! drawing order:
//! 1. white background; each named region's free cells get a faint tint so rooms
//!    read apart, and its outline is drawn dashed;
//! 2. walls (obstacle cells that belong to no instance) in dark slate grey;
//! 3. every instance's cells filled with its colour from [`colour_rgb`] (no colour
//!    or an unknown word: light grey), with a darker one-cell outline (a lighter one
//!    on very dark fills) so white and black objects stay visible;
//! 4. the path as a blue line, stops as numbered orange discs, the start pose as
//!    a hollow green triangle and the final pose as a filled red triangle, both
//!    pointing along the compass heading (0 = north = up);
//! 5. instance ids at each footprint's centre and region names, on white label
//!    boxes; below the map, when there are stops, a legend strip "1 call, 2 call...".
//!
//! Text uses the public-domain 8x8 bitmap font of the `font8x8` crate (its legacy
//! ASCII table), drawn at 1x or 2x.

use std::path::{Path, PathBuf};

use image::{Rgb, RgbImage};

use crate::geometry::{Point, Pose};
use crate::grid::Cell;
use crate::map::IvlMap;
use crate::robot::Trajectory;

/// What to draw on top of the map: a robot's path, its stops and its final pose.
#[derive(Debug, Clone, Copy, Default)]
pub struct RenderOverlay<'a> {
    /// The travelled path in world metres, drawn as a line.
    pub path: &'a [Point],
    /// Stops in order: where the robot stopped and what it was doing there (for
    /// a trajectory: the stop's `call`). Drawn as discs numbered from 1; the labels
    /// go into the legend strip.
    pub stops: &'a [(Pose, String)],
    /// The robot's final pose, drawn as a filled triangle pointing along its heading.
    pub final_pose: Option<Pose>,
}

/// How to draw.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    /// Pixels per grid cell; `None` picks one so the image is about 800-1200 px wide
    /// (see [`auto_scale`]). Values are clamped so neither side exceeds
    /// [`MAX_SIDE_PX`].
    pub scale: Option<u32>,
    /// Draw instance ids at footprint centres.
    pub ids: bool,
    /// Draw region tints, outlines and names.
    pub regions: bool,
    /// Draw the map's start pose (hollow triangle).
    pub start_pose: bool,
    /// Add the legend strip for stops under the map.
    pub legend: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            scale: None,
            ids: true,
            regions: true,
            start_pose: true,
            legend: true,
        }
    }
}

/// The largest image side [`render_rgb`] produces.
pub const MAX_SIDE_PX: u32 = 16_384;

/// Why a PNG could not be written.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Saving the PNG to `path` failed.
    #[error("{}: cannot write the PNG: {source}", path.display())]
    Write {
        /// The file that could not be written.
        path: PathBuf,
        /// The encoder or I/O error.
        #[source]
        source: image::ImageError,
    },
}

/// The colour words the renderer knows, with the RGB each is drawn in. Words
/// outside this table (and objects without a colour) are drawn light grey.
pub const PALETTE: &[(&str, [u8; 3])] = &[
    ("black", [28, 28, 28]),
    ("white", [250, 250, 250]),
    ("gray", [150, 150, 150]),
    ("grey", [150, 150, 150]),
    ("silver", [192, 196, 204]),
    ("red", [214, 39, 40]),
    ("orange", [255, 140, 26]),
    ("yellow", [245, 205, 30]),
    ("gold", [212, 175, 55]),
    ("green", [44, 160, 44]),
    ("blue", [31, 100, 200]),
    ("navy", [20, 40, 110]),
    ("cyan", [40, 200, 220]),
    ("teal", [0, 128, 128]),
    ("purple", [128, 60, 170]),
    ("violet", [150, 100, 220]),
    ("pink", [245, 140, 180]),
    ("magenta", [220, 40, 180]),
    ("brown", [140, 86, 50]),
    ("tan", [210, 180, 140]),
    ("beige", [230, 218, 180]),
    ("cream", [250, 240, 205]),
    ("chocolate", [110, 60, 25]),
];

/// Fill for instances without a colour or with a word not in [`PALETTE`].
pub const UNKNOWN_RGB: [u8; 3] = [205, 205, 205];
/// Walls.
pub const WALL_RGB: [u8; 3] = [64, 70, 82];
/// The path line.
pub const PATH_RGB: [u8; 3] = [30, 110, 240];
/// Stop discs.
pub const STOP_RGB: [u8; 3] = [255, 150, 20];
/// The final pose.
pub const FINAL_RGB: [u8; 3] = [220, 30, 60];
/// The start pose outline.
pub const START_RGB: [u8; 3] = [20, 140, 60];

const BACKGROUND: [u8; 3] = [255, 255, 255];
const TEXT: [u8; 3] = [0, 0, 0];
const REGION_LINE: [u8; 3] = [120, 130, 160];
const REGION_TINTS: [[u8; 3]; 6] = [
    [244, 248, 255],
    [255, 248, 238],
    [242, 252, 244],
    [252, 244, 252],
    [255, 253, 236],
    [240, 250, 252],
];

/// The RGB a colour word is drawn in, if the palette knows it (case-insensitive).
pub fn colour_rgb(word: &str) -> Option<[u8; 3]> {
    let w = word.trim().to_lowercase();
    PALETTE.iter().find(|(n, _)| *n == w).map(|(_, c)| *c)
}

/// The default pixels per cell: the largest integer scale that keeps the image at
/// most 1200 px wide (about 800-1200 px for maps of 200-1200 columns), at least 1.
pub fn auto_scale(cols: usize) -> u32 {
    (1200 / cols.max(1)).clamp(1, 64) as u32
}

/// Render and write a PNG.
pub fn render_png(
    map: &IvlMap,
    overlay: &RenderOverlay<'_>,
    opts: &RenderOptions,
    path: impl AsRef<Path>,
) -> Result<(), RenderError> {
    let path = path.as_ref();
    render_rgb(map, overlay, opts)
        .save_with_format(path, image::ImageFormat::Png)
        .map_err(|source| RenderError::Write {
            path: path.to_path_buf(),
            source,
        })
}

/// Render a map with a recorded trajectory (path, numbered stops, final pose).
pub fn render_trajectory_png(
    map: &IvlMap,
    trajectory: &Trajectory,
    opts: &RenderOptions,
    path: impl AsRef<Path>,
) -> Result<(), RenderError> {
    let path = path.as_ref();
    render_trajectory_rgb(map, trajectory, opts)
        .save_with_format(path, image::ImageFormat::Png)
        .map_err(|source| RenderError::Write {
            path: path.to_path_buf(),
            source,
        })
}

/// [`render_rgb`] with a recorded trajectory as the overlay.
#[must_use]
pub fn render_trajectory_rgb(
    map: &IvlMap,
    trajectory: &Trajectory,
    opts: &RenderOptions,
) -> RgbImage {
    let pts: Vec<Point> = trajectory.path.iter().map(|&p| Point::from(p)).collect();
    let stops: Vec<(Pose, String)> = trajectory
        .stops
        .iter()
        .map(|s| (Pose::new(s.pose[0], s.pose[1], s.pose[2]), s.call.clone()))
        .collect();
    let f = trajectory.final_pose;
    let overlay = RenderOverlay {
        path: &pts,
        stops: &stops,
        final_pose: Some(Pose::new(f[0], f[1], f[2])),
    };
    render_rgb(map, &overlay, opts)
}

/// Render to an RGB image: `cols * scale` by `rows * scale` pixels, plus a legend
/// strip underneath when there are stops and `opts.legend` is set.
pub fn render_rgb(map: &IvlMap, overlay: &RenderOverlay<'_>, opts: &RenderOptions) -> RgbImage {
    let (rows, cols) = (map.frame.rows, map.frame.cols);
    let max_scale = (MAX_SIDE_PX as usize / rows.max(cols).max(1)).max(1) as u32;
    let s = opts
        .scale
        .unwrap_or_else(|| auto_scale(cols))
        .clamp(1, max_scale);
    let (w, h) = (cols as u32 * s, rows as u32 * s);
    let text_k = if w >= 700 { 2 } else { 1 };
    let legend = if opts.legend && !overlay.stops.is_empty() {
        legend_lines(overlay.stops, w, text_k)
    } else {
        Vec::new()
    };
    let legend_h = if legend.is_empty() {
        0
    } else {
        legend.len() as u32 * (10 * text_k) + 8
    };
    let mut c = Canvas {
        img: RgbImage::from_pixel(w.max(1), (h + legend_h).max(1), Rgb(BACKGROUND)),
        s,
        map,
    };

    // 1-3: the cells
    let region_of: Vec<Option<usize>> = if opts.regions {
        (0..rows * cols)
            .map(|i| {
                let p = map.frame.cell_center(map.instance.cell_of(i));
                map.regions.iter().position(|r| r.polygon.contains(p))
            })
            .collect()
    } else {
        vec![None; rows * cols]
    };
    for r in 0..rows {
        for col in 0..cols {
            let cell = Cell::new(r, col);
            let i = r * cols + col;
            let id = map.instance.as_slice()[i];
            let rgb = if id != 0 {
                let fill = instance_fill(map, id);
                if is_boundary(map, cell, id) {
                    outline_of(fill)
                } else {
                    fill
                }
            } else if map.obstacles.as_slice()[i] {
                WALL_RGB
            } else if let Some(k) = region_of[i] {
                REGION_TINTS[k % REGION_TINTS.len()]
            } else {
                BACKGROUND
            };
            c.fill_cell(cell, rgb);
        }
    }
    if opts.regions {
        for reg in &map.regions {
            let v = reg.polygon.vertices();
            for k in 0..v.len() {
                let (a, b) = (c.px(v[k]), c.px(v[(k + 1) % v.len()]));
                c.dashed_line(a, b, REGION_LINE);
            }
        }
        // redraw walls over the outlines so the dashes show only in open boundaries
        for (cell, occ) in map.obstacles.iter_cells() {
            if *occ && map.instance.get(cell).copied() == Some(0) {
                c.fill_cell(cell, WALL_RGB);
            }
        }
    }

    // 4: the robot's run
    let lw = (s as f64 * 0.6).max(2.5);
    for seg in overlay.path.windows(2) {
        c.thick_line(c.px(seg[0]), c.px(seg[1]), lw, PATH_RGB);
    }
    if opts.start_pose {
        c.triangle(map.start_pose, START_RGB, false);
    }
    if let Some(p) = overlay.final_pose {
        c.triangle(p, FINAL_RGB, true);
    }
    let disc_r = (5.0 * text_k as f64).max(s as f64 * 2.0);
    for (k, (pose, _)) in overlay.stops.iter().enumerate() {
        let p = c.px(pose.position);
        c.disc(p, disc_r + 1.5, TEXT);
        c.disc(p, disc_r, STOP_RGB);
        let label = (k + 1).to_string();
        let tk = if label.len() > 1 { 1 } else { text_k };
        c.text_centered(p, &label, tk, TEXT, None);
    }

    // 5: labels
    if opts.ids {
        for inst in &map.instances {
            let p = c.px(inst.center());
            let label = inst.id.to_string();
            let fp = (inst.bbox[2].min(inst.bbox[3]) * s) as usize;
            let k = if fp >= label.len() * 16 + 6 {
                text_k
            } else {
                1
            };
            c.text_centered(p, &label, k, TEXT, Some(BACKGROUND));
        }
    }
    if opts.regions {
        for reg in &map.regions {
            c.region_name(reg, text_k);
        }
    }
    let mut y = h + 4;
    for line in &legend {
        c.text((4.0, y as f64), line, text_k, TEXT, None);
        y += 10 * text_k;
    }
    c.img
}

/// Legend entries "1 move_to_object" packed into lines that fit the width.
fn legend_lines(stops: &[(Pose, String)], width: u32, k: u32) -> Vec<String> {
    let max_chars = ((width.saturating_sub(8)) / (8 * k)).max(10) as usize;
    let mut lines = Vec::new();
    let mut cur = String::new();
    for (i, (_, call)) in stops.iter().enumerate() {
        let call: String = call
            .chars()
            .filter(|c| c.is_ascii_graphic() || *c == ' ')
            .collect();
        let item = format!("{} {}", i + 1, call.trim());
        if !cur.is_empty() && cur.len() + 3 + item.len() > max_chars {
            lines.push(std::mem::take(&mut cur));
        }
        if !cur.is_empty() {
            cur.push_str("   ");
        }
        cur.push_str(&item);
    }
    if !cur.is_empty() {
        lines.push(cur);
    }
    lines
}

fn instance_fill(map: &IvlMap, id: u32) -> [u8; 3] {
    map.instance_by_id(id)
        .and_then(|i| i.colour.as_deref())
        .and_then(colour_rgb)
        .unwrap_or(UNKNOWN_RGB)
}

/// The outline shade of a fill: darker, or lighter for fills that are nearly black.
fn outline_of(fill: [u8; 3]) -> [u8; 3] {
    let luma = 0.299 * fill[0] as f64 + 0.587 * fill[1] as f64 + 0.114 * fill[2] as f64;
    if luma < 60.0 {
        [150, 150, 150]
    } else {
        fill.map(|v| (v as f64 * 0.5) as u8)
    }
}

fn is_boundary(map: &IvlMap, cell: Cell, id: u32) -> bool {
    let (r, c) = (cell.row as isize, cell.col as isize);
    [(-1, 0), (1, 0), (0, -1), (0, 1)].iter().any(|(dr, dc)| {
        let (nr, nc) = (r + dr, c + dc);
        !map.instance.in_bounds(nr, nc)
            || map
                .instance
                .get(Cell::new(nr as usize, nc as usize))
                .copied()
                != Some(id)
    })
}

struct Canvas<'m> {
    img: RgbImage,
    /// pixels per cell
    s: u32,
    map: &'m IvlMap,
}

impl Canvas<'_> {
    /// Pixel coordinates (x right, y down; continuous) of a world point.
    fn px(&self, p: Point) -> (f64, f64) {
        let (r, c) = self.map.frame.to_grid_f(p);
        (c * self.s as f64, r * self.s as f64)
    }

    fn put(&mut self, x: i64, y: i64, rgb: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as u32) < self.img.width() && (y as u32) < self.img.height() {
            self.img.put_pixel(x as u32, y as u32, Rgb(rgb));
        }
    }

    fn fill_cell(&mut self, cell: Cell, rgb: [u8; 3]) {
        let s = self.s as i64;
        let (x0, y0) = (cell.col as i64 * s, cell.row as i64 * s);
        for y in y0..y0 + s {
            for x in x0..x0 + s {
                self.put(x, y, rgb);
            }
        }
    }

    fn rect(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, rgb: [u8; 3]) {
        for y in y0..y1 {
            for x in x0..x1 {
                self.put(x, y, rgb);
            }
        }
    }

    fn disc(&mut self, (cx, cy): (f64, f64), r: f64, rgb: [u8; 3]) {
        if !(cx.is_finite() && cy.is_finite()) {
            return;
        }
        let (x0, x1) = ((cx - r).floor() as i64, (cx + r).ceil() as i64);
        let (y0, y1) = ((cy - r).floor() as i64, (cy + r).ceil() as i64);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
                if dx * dx + dy * dy <= r * r {
                    self.put(x, y, rgb);
                }
            }
        }
    }

    fn thick_line(&mut self, a: (f64, f64), b: (f64, f64), width: f64, rgb: [u8; 3]) {
        let len = (b.0 - a.0).hypot(b.1 - a.1);
        if !len.is_finite() || len > 1e6 {
            return;
        }
        let n = (len * 2.0).ceil().max(1.0) as usize;
        for i in 0..=n {
            let t = i as f64 / n as f64;
            self.disc(
                (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t),
                width / 2.0,
                rgb,
            );
        }
    }

    fn dashed_line(&mut self, a: (f64, f64), b: (f64, f64), rgb: [u8; 3]) {
        let len = (b.0 - a.0).hypot(b.1 - a.1);
        if !len.is_finite() || len > 1e6 {
            return;
        }
        let n = len.ceil().max(1.0) as usize;
        for i in 0..=n {
            if (i / 6) % 2 == 1 {
                continue;
            }
            let t = i as f64 / n as f64;
            let (x, y) = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
            self.put(x.floor() as i64, y.floor() as i64, rgb);
        }
    }

    /// A robot pose as an isosceles triangle whose tip points along the heading.
    fn triangle(&mut self, pose: Pose, rgb: [u8; 3], filled: bool) {
        let c = self.px(pose.position);
        if !(c.0.is_finite() && c.1.is_finite() && pose.heading.is_finite()) {
            return;
        }
        let len =
            (self.map.robot_radius / self.map.frame.cell_size * self.s as f64 * 1.6).max(12.0);
        let f = pose.forward();
        let (fx, fy) = (f.x, -f.y); // image y grows southwards
        let (rx, ry) = (-fy, fx);
        let tip = (c.0 + fx * len, c.1 + fy * len);
        let back = (c.0 - fx * len * 0.6, c.1 - fy * len * 0.6);
        let l = (back.0 + rx * len * 0.6, back.1 + ry * len * 0.6);
        let r = (back.0 - rx * len * 0.6, back.1 - ry * len * 0.6);
        if filled {
            self.fill_triangle([tip, l, r], rgb);
        }
        let edge = if filled { TEXT } else { rgb };
        let w = if filled { 1.5 } else { 2.5 };
        for (a, b) in [(tip, l), (l, r), (r, tip)] {
            self.thick_line(a, b, w, edge);
        }
    }

    fn fill_triangle(&mut self, v: [(f64, f64); 3], rgb: [u8; 3]) {
        let xs = v.map(|p| p.0);
        let ys = v.map(|p| p.1);
        let (x0, x1) = (
            xs.iter().copied().fold(f64::INFINITY, f64::min),
            xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        );
        let (y0, y1) = (
            ys.iter().copied().fold(f64::INFINITY, f64::min),
            ys.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        );
        let edge = |a: (f64, f64), b: (f64, f64), p: (f64, f64)| {
            (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0)
        };
        for y in y0.floor() as i64..=y1.ceil() as i64 {
            for x in x0.floor() as i64..=x1.ceil() as i64 {
                let p = (x as f64 + 0.5, y as f64 + 0.5);
                let (e0, e1, e2) = (
                    edge(v[0], v[1], p),
                    edge(v[1], v[2], p),
                    edge(v[2], v[0], p),
                );
                if (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) || (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0) {
                    self.put(x, y, rgb);
                }
            }
        }
    }

    /// Size in pixels of `text` at scale `k`.
    fn text_size(text: &str, k: u32) -> (i64, i64) {
        (text.chars().count() as i64 * 8 * k as i64, 8 * k as i64)
    }

    /// Draw `text` with its top-left corner at `at`; `bg` draws a box with a
    /// one-pixel frame behind it.
    fn text(&mut self, at: (f64, f64), text: &str, k: u32, rgb: [u8; 3], bg: Option<[u8; 3]>) {
        let (x0, y0) = (at.0.round() as i64, at.1.round() as i64);
        let (tw, th) = Self::text_size(text, k);
        if let Some(bg) = bg {
            self.rect(x0 - 2, y0 - 2, x0 + tw + 1, y0 + th + 2, [90, 90, 90]);
            self.rect(x0 - 1, y0 - 1, x0 + tw, y0 + th + 1, bg);
        }
        let k = k as i64;
        for (i, ch) in text.chars().enumerate() {
            let glyph = font8x8::legacy::BASIC_LEGACY
                .get(ch as usize)
                .copied()
                .unwrap_or(font8x8::legacy::BASIC_LEGACY[b'?' as usize]);
            for (gy, bits) in glyph.iter().enumerate() {
                for gx in 0..8 {
                    if bits & (1 << gx) != 0 {
                        let (px, py) = (x0 + (i as i64 * 8 + gx) * k, y0 + gy as i64 * k);
                        self.rect(px, py, px + k, py + k, rgb);
                    }
                }
            }
        }
    }

    fn text_centered(
        &mut self,
        c: (f64, f64),
        text: &str,
        k: u32,
        rgb: [u8; 3],
        bg: Option<[u8; 3]>,
    ) {
        if !(c.0.is_finite() && c.1.is_finite()) {
            return;
        }
        let (tw, th) = Self::text_size(text, k);
        self.text(
            (c.0 - tw as f64 / 2.0, c.1 - th as f64 / 2.0),
            text,
            k,
            rgb,
            bg,
        );
    }

    /// A region's name inside the region, at the first of a few candidate places
    /// whose box covers no wall or object.
    fn region_name(&mut self, reg: &crate::map::Region, k: u32) {
        let Some(bb) = reg.polygon.bbox() else { return };
        let (tw, th) = Self::text_size(&reg.name, k);
        let (tw, th) = (tw as f64, th as f64);
        let (x0, y0) = self.px(Point::new(bb.min.x, bb.max.y));
        let (x1, y1) = self.px(Point::new(bb.max.x, bb.min.y));
        let m = 0.3 / self.map.frame.cell_size * self.s as f64; // 30 cm inset
        let cx = (x0 + x1 - tw) / 2.0;
        let candidates = [
            (x0 + m, y0 + m),
            (cx, y0 + m),
            (x1 - m - tw, y0 + m),
            (x0 + m, y1 - m - th),
            (cx, y1 - m - th),
            (x1 - m - tw, y1 - m - th),
            (cx, (y0 + y1 - th) / 2.0),
        ];
        let at = candidates
            .iter()
            .copied()
            .find(|&(x, y)| self.box_is_clear(x - 3.0, y - 3.0, x + tw + 3.0, y + th + 3.0))
            .unwrap_or(candidates[0]);
        self.text(at, &reg.name, k, [40, 50, 90], Some([255, 255, 255]));
    }

    /// Whether a pixel box lies inside the image over free, instance-free cells.
    fn box_is_clear(&self, x0: f64, y0: f64, x1: f64, y1: f64) -> bool {
        let s = self.s as f64;
        if x0 < 0.0
            || y0 < 0.0
            || x1 > (self.map.frame.cols as f64 * s)
            || y1 > (self.map.frame.rows as f64 * s)
        {
            return false;
        }
        let (c0, c1) = ((x0 / s).floor() as usize, (x1 / s).ceil() as usize);
        let (r0, r1) = ((y0 / s).floor() as usize, (y1 / s).ceil() as usize);
        (r0..r1)
            .all(|r| (c0..c1).all(|c| self.map.obstacles.get(Cell::new(r, c)).is_none_or(|o| !*o)))
    }
}
