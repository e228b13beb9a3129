//! Simulated perception with controlled errors: [`PerceptionInputs::with_noise`]
//! corrupts the inputs a perfect perception stack would give
//! ([`PerceptionInputs::from_scene`]) at set rates, reproducibly from a seed, so a
//! noise study can build maps from them and measure what each kind of error costs.
//!
//! The five kinds ([`PerceptionNoise`]), each a rate in [0, 1]:
//!
//! | kind | what a real stack gets wrong | what is done |
//! |---|---|---|
//! | `label_flip` | LSeg/CLIP pixels of an object read as a similar category | each object cell (label not in `background`) takes, with this probability, its category's *confusion partner* (one other object category per category, drawn per map; the background label when there is no other) |
//! | `fragment` | SAM splits one object into two masks | `rate * n` masks are cut in two across their longer side, at 30..70% of it; the far part becomes a new mask |
//! | `merge` | SAM covers two neighbours with one mask | `rate * n` masks absorb the nearest other mask of the same category whose centroid lies within `merge_radius_m` |
//! | `drop` | SAM misses an object | `rate * n` masks are removed |
//! | `colour_shift` | lighting and white balance change an object's colour | `rate * n` objects have every RGB pixel shifted: chromatic pixels turn by 60..180 degrees of CIELAB hue (either way), achromatic ones (chroma < 12) move 35..55 in lightness L* (darker when light, lighter when dark) |
//!
//! `n` is the number of input masks; a count `rate * n` that is not whole is rounded
//! up with probability its fraction (so 0.05 of 30 masks is 1 or 2, 1.5 on average),
//! down otherwise. Each kind draws from its own random stream
//! (fastrand's wyrand seeded with `seed` and the kind), and the masks a kind picks
//! are a prefix of one seeded permutation, so for a fixed seed a higher rate
//! corrupts a superset of what a lower rate does (common random numbers: curves over
//! the rate are not re-drawn at every point). Masks are picked in this order: drop,
//! then merge among the rest, then fragment among masks not merged; colour shifts
//! and label flips act on the RGB and label layers, under the original masks.
//!
//! Output masks: the surviving input masks in their order (merged ones holding both
//! objects' cells), then the fragments' far parts, in the order of their source
//! masks. The [`NoiseLog`] names every change by *input* mask index.
//!
//! ```
//! use map_core::{IvlMap, Scene};
//! use map_build::perception::{build_map, BuildConfig, PerceptionInputs, PerceptionNoise};
//! let scene = Scene::from_path(concat!(env!("CARGO_MANIFEST_DIR"), "/../examples/scenes/office-b.scene.json")).unwrap();
//! let clean = PerceptionInputs::from_scene(&scene);
//! let (noisy, log) = clean.with_noise(&PerceptionNoise::uniform(0.1, 7)).unwrap();
//! assert_eq!(log.dropped.len(), 3); // 0.1 * 30 masks
//! let built = build_map(&noisy, &BuildConfig::default()).unwrap();
//! assert!(built.map.instances.len() < clean.masks.len() + log.fragmented.len());
//! // Same seed, same corruption.
//! assert_eq!(clean.with_noise(&PerceptionNoise::uniform(0.1, 7)).unwrap().0, noisy);
//! ```

use palette::{IntoColor, Lab, Lch, Srgb};

use super::assemble::PerceptionInputs;
use super::labelling::{mode_label, LabelCounter, LabelMap};
use super::mask::Mask;
use map_core::geometry::Point;

/// Error rates and the seed of [`PerceptionInputs::with_noise`] (see the module
/// documentation for what each kind does).
#[derive(Debug, Clone, PartialEq)]
pub struct PerceptionNoise {
    /// Share of object cells whose label flips to the confusion partner.
    pub label_flip: f64,
    /// Share of masks split in two.
    pub fragment: f64,
    /// Share of masks merged with a same-category neighbour.
    pub merge: f64,
    /// Share of masks removed.
    pub drop: f64,
    /// Share of objects whose RGB pixels are colour-shifted.
    pub colour_shift: f64,
    /// Farthest centroid distance, metres, of a merge partner. Default 2.5.
    pub merge_radius_m: f64,
    /// Labels that are no object (as [`LabelConfig::background`](super::LabelConfig::background)):
    /// never flipped, never a flip target unless no object label is left. Default `[0]`.
    pub background: Vec<u16>,
    /// Seed of the random streams: the same seed gives the same corruption.
    pub seed: u64,
}

impl PerceptionNoise {
    /// No errors at all (the inputs come back unchanged).
    pub fn none(seed: u64) -> Self {
        Self::uniform(0.0, seed)
    }

    /// Every kind at the same rate.
    pub fn uniform(rate: f64, seed: u64) -> Self {
        PerceptionNoise {
            label_flip: rate,
            fragment: rate,
            merge: rate,
            drop: rate,
            colour_shift: rate,
            merge_radius_m: DEFAULT_MERGE_RADIUS_M,
            background: vec![0],
            seed,
        }
    }

    /// `(name, rate)` of the five kinds, in the module documentation's order.
    pub fn rates(&self) -> [(&'static str, f64); 5] {
        [
            ("label_flip", self.label_flip),
            ("fragment", self.fragment),
            ("merge", self.merge),
            ("drop", self.drop),
            ("colour_shift", self.colour_shift),
        ]
    }

    fn check(&self) -> Result<(), NoiseError> {
        for (field, value) in self.rates() {
            if !(0.0..=1.0).contains(&value) {
                return Err(NoiseError::Rate { field, value });
            }
        }
        if !(self.merge_radius_m.is_finite() && self.merge_radius_m >= 0.0) {
            return Err(NoiseError::Rate {
                field: "merge_radius_m",
                value: self.merge_radius_m,
            });
        }
        Ok(())
    }
}

/// Default [`PerceptionNoise::merge_radius_m`].
pub const DEFAULT_MERGE_RADIUS_M: f64 = 2.5;

/// Why noise could not be applied.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NoiseError {
    /// A rate outside [0, 1] (or a negative / non-finite merge radius).
    #[error("noise `{field}` must be in [0, 1] (merge_radius_m: >= 0), got {value}")]
    Rate {
        /// The field of [`PerceptionNoise`] that is out of range.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// The masks, label map and RGB map disagree in size.
    #[error("{what} is {rows}x{cols}, but the label map is {want_rows}x{want_cols}")]
    Shape {
        /// Which layer or mask, e.g. "RGB map", "mask 3".
        what: String,
        /// Its number of rows.
        rows: usize,
        /// Its number of columns.
        cols: usize,
        /// Number of rows of the label map.
        want_rows: usize,
        /// Number of columns of the label map.
        want_cols: usize,
    },
}

/// What [`PerceptionInputs::with_noise`] changed, by input mask index.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct NoiseLog {
    /// Label map cells whose label flipped.
    pub flipped_cells: u64,
    /// `(category label, its confusion partner)` for each object label.
    pub confusion: Vec<(u16, u16)>,
    /// Masks removed.
    pub dropped: Vec<usize>,
    /// `(kept mask, absorbed mask)`.
    pub merged: Vec<(usize, usize)>,
    /// Masks split in two (their far part is a new mask at the end).
    pub fragmented: Vec<usize>,
    /// Masks whose RGB pixels were shifted.
    pub colour_shifted: Vec<usize>,
}

/// Stream tags, so that each kind's draws do not depend on the other kinds' rates.
const STREAM_FLIP: u64 = 0x6c61_6265_6c00_0001;
const STREAM_DROP: u64 = 0x6472_6f70_0000_0002;
const STREAM_MERGE: u64 = 0x6d65_7267_6500_0003;
const STREAM_FRAGMENT: u64 = 0x6672_6167_0000_0004;
const STREAM_COLOUR: u64 = 0x636f_6c6f_7572_0005;

fn rng(seed: u64, stream: u64) -> fastrand::Rng {
    fastrand::Rng::with_seed(seed ^ stream.rotate_left(17))
}

/// `rate * n` rounded stochastically (down, or up with probability its fraction,
/// so its mean is `rate * n` exactly), at most `n`. One draw whatever the rate, so
/// the stream lines up across rates.
fn count(rate: f64, n: usize, r: &mut fastrand::Rng) -> usize {
    let u = r.f64();
    // `as` saturates; rate * n is finite and >= 0
    ((rate * n as f64 + u).floor() as usize).min(n)
}

impl PerceptionInputs {
    /// A corrupted copy of these inputs and the log of what changed (see the module
    /// documentation). The frame, obstacles, regions and robot are kept as they are;
    /// a colour label map, when present, is left alone (only `rgb` is shifted).
    pub fn with_noise(
        &self,
        noise: &PerceptionNoise,
    ) -> Result<(PerceptionInputs, NoiseLog), NoiseError> {
        noise.check()?;
        let labels = self.labels.labels();
        let (rows, cols) = (labels.rows(), labels.cols());
        let shape = |what: String, r: usize, c: usize| {
            if (r, c) == (rows, cols) {
                Ok(())
            } else {
                Err(NoiseError::Shape {
                    what,
                    rows: r,
                    cols: c,
                    want_rows: rows,
                    want_cols: cols,
                })
            }
        };
        for (i, m) in self.masks.iter().enumerate() {
            shape(format!("mask {i}"), m.rows(), m.cols())?;
        }
        if let Some(g) = &self.rgb {
            shape("RGB map".into(), g.rows(), g.cols())?;
        }

        let mut log = NoiseLog::default();
        let n = self.masks.len();
        let n_labels = self.labels.categories().len();
        let is_bg = |l: u16| noise.background.contains(&l);

        // Each mask's category (mode of the clean label map) and centroid.
        let mut counter = LabelCounter::new();
        let category: Vec<Option<u16>> = self
            .masks
            .iter()
            .map(|m| mode_label(&mut counter, labels, m, n_labels).map(|s| s.label))
            .collect();
        let centroid: Vec<Option<Point>> = self
            .masks
            .iter()
            .map(|m| m.centroid_rc().map(|(r, c)| self.frame.from_grid_f(r, c)))
            .collect();

        // Drop.
        let mut r = rng(noise.seed, STREAM_DROP);
        let k_drop = count(noise.drop, n, &mut r);
        let mut order: Vec<usize> = (0..n).collect();
        r.shuffle(&mut order);
        let mut gone = vec![false; n];
        for &i in order.iter().take(k_drop) {
            gone[i] = true;
            log.dropped.push(i);
        }
        log.dropped.sort_unstable();

        // Merge: the picked mask absorbs its nearest same-category neighbour.
        let mut r = rng(noise.seed, STREAM_MERGE);
        let k_merge = count(noise.merge, n, &mut r);
        let mut order: Vec<usize> = (0..n).collect();
        r.shuffle(&mut order);
        let mut merged_into: Vec<Vec<usize>> = vec![Vec::new(); n];
        let mut touched = vec![false; n];
        for &i in order.iter().take(k_merge) {
            if gone[i] || touched[i] {
                continue;
            }
            let (Some(ci), Some(pi)) = (category[i], centroid[i]) else {
                continue;
            };
            let partner = (0..n)
                .filter(|&j| j != i && !gone[j] && !touched[j] && category[j] == Some(ci))
                .filter_map(|j| centroid[j].map(|p| (j, p.dist(pi))))
                .filter(|&(_, d)| d <= noise.merge_radius_m)
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            if let Some((j, _)) = partner {
                gone[j] = true;
                touched[i] = true;
                touched[j] = true;
                merged_into[i].push(j);
                log.merged.push((i, j));
            }
        }

        // Fragment among the masks neither dropped nor merged.
        let mut r = rng(noise.seed, STREAM_FRAGMENT);
        let k_fragment = count(noise.fragment, n, &mut r);
        let mut order: Vec<usize> = (0..n).collect();
        r.shuffle(&mut order);
        let mut far_part: Vec<Option<Mask>> = vec![None; n];
        let mut near_part: Vec<Option<Mask>> = vec![None; n];
        for &i in order.iter().take(k_fragment) {
            let cut = r.f64() * 0.4 + 0.3;
            if gone[i] || touched[i] {
                continue;
            }
            if let Some((a, b)) = split(&self.masks[i], cut) {
                near_part[i] = Some(a);
                far_part[i] = Some(b);
                log.fragmented.push(i);
            }
        }
        log.fragmented.sort_unstable();

        let mut masks: Vec<Mask> = Vec::with_capacity(n + log.fragmented.len());
        for i in 0..n {
            if gone[i] {
                continue;
            }
            let m = match (&near_part[i], merged_into[i].as_slice()) {
                (Some(a), _) => a.clone(),
                (None, []) => self.masks[i].clone(),
                (None, others) => union(
                    std::iter::once(&self.masks[i]).chain(others.iter().map(|&j| &self.masks[j])),
                    rows,
                    cols,
                ),
            };
            masks.push(m);
        }
        masks.extend(far_part.into_iter().flatten());

        // Label flips: one confusion partner per object label.
        let mut r = rng(noise.seed, STREAM_FLIP);
        let objects: Vec<u16> = (0..n_labels)
            .filter_map(|l| u16::try_from(l).ok())
            .filter(|&l| !is_bg(l))
            .collect();
        let bg0 = noise.background.first().copied().unwrap_or(0);
        let mut partner = vec![0u16; n_labels];
        for &l in &objects {
            let others: Vec<u16> = objects.iter().copied().filter(|&o| o != l).collect();
            let p = if others.is_empty() {
                bg0
            } else {
                others[r.usize(..others.len())]
            };
            partner[usize::from(l)] = p;
            log.confusion.push((l, p));
        }
        let mut flipped = labels.clone();
        if noise.label_flip > 0.0 {
            for v in flipped.as_mut_slice() {
                // one draw per cell whatever its label, so streams line up across maps
                let u = r.f64();
                if !is_bg(*v) && u < noise.label_flip {
                    if let Some(&p) = partner.get(usize::from(*v)) {
                        *v = p;
                        log.flipped_cells += 1;
                    }
                }
            }
        }

        // Colour shifts on the RGB under the original masks.
        let mut rgb = self.rgb.clone();
        let mut r = rng(noise.seed, STREAM_COLOUR);
        let k_colour_shift = count(noise.colour_shift, n, &mut r);
        let mut order: Vec<usize> = (0..n).collect();
        r.shuffle(&mut order);
        for &i in order.iter().take(k_colour_shift) {
            let turn = (r.f64() * 120.0 + 60.0) * if r.bool() { 1.0 } else { -1.0 };
            let lift = r.f64() * 20.0 + 35.0;
            if let Some(g) = rgb.as_mut() {
                let px = g.as_mut_slice();
                for k in self.masks[i].indices() {
                    if let Some(p) = px.get_mut(k) {
                        *p = shift_colour(*p, turn, lift);
                    }
                }
                log.colour_shifted.push(i);
            }
        }
        log.colour_shifted.sort_unstable();

        let out = PerceptionInputs {
            labels: LabelMap::new_trusted(flipped, self.labels.categories().to_vec()),
            masks,
            rgb,
            ..self.clone()
        };
        Ok((out, log))
    }
}

/// Chroma (CIELAB C*) below which a colour counts as achromatic for a shift.
const ACHROMATIC_CHROMA: f32 = 12.0;

/// Turn a chromatic colour's CIELAB hue by `turn` degrees; move an achromatic one's
/// lightness by `lift` towards the other end (darker when L* > 50).
fn shift_colour(rgb: [u8; 3], turn: f64, lift: f64) -> [u8; 3] {
    let lab: Lab = Srgb::new(rgb[0], rgb[1], rgb[2])
        .into_format::<f32>()
        .into_color();
    let mut lch: Lch = lab.into_color();
    if lch.chroma < ACHROMATIC_CHROMA {
        let d = lift as f32;
        lch.l = if lch.l > 50.0 { lch.l - d } else { lch.l + d }.clamp(0.0, 100.0);
    } else {
        lch.hue += turn as f32;
    }
    let back: Srgb = lch.into_color();
    let c = back.into_format::<u8>();
    // into_format clamps out-of-gamut channels
    [c.red, c.green, c.blue]
}

/// Cut a mask across its longer bounding-box side at `cut` (0..1) of it: the cells
/// before the cut and those after; `None` when either part would be empty.
fn split(mask: &Mask, cut: f64) -> Option<(Mask, Mask)> {
    let [c0, r0, w, h] = mask.bbox()?;
    let (rows, cols) = (mask.rows(), mask.cols());
    let by_col = w >= h;
    let (start, len) = if by_col { (c0, w) } else { (r0, h) };
    let at = usize::try_from(start).ok()? + (f64::from(len) * cut).round() as usize;
    let (mut near, mut far) = (Vec::new(), Vec::new());
    for i in mask.indices() {
        let key = if by_col {
            i % cols.max(1)
        } else {
            i / cols.max(1)
        };
        if key < at {
            near.push(i);
        } else {
            far.push(i);
        }
    }
    if near.is_empty() || far.is_empty() {
        return None;
    }
    Some((
        Mask::from_sorted_indices(rows, cols, &near),
        Mask::from_sorted_indices(rows, cols, &far),
    ))
}

/// The union of masks of one size.
fn union<'a>(masks: impl Iterator<Item = &'a Mask>, rows: usize, cols: usize) -> Mask {
    let mut idx: Vec<usize> = masks.flat_map(Mask::indices).collect();
    idx.sort_unstable();
    idx.dedup();
    Mask::from_sorted_indices(rows, cols, &idx)
}

#[cfg(test)]
mod tests {
    use super::*;
    use map_core::grid::Cell;

    #[test]
    fn split_cuts_across_the_longer_side() {
        // 2 rows x 10 cols block at (1..3, 0..10) of a 5x12 grid
        let m = Mask::from_cells(
            5,
            12,
            (1..3).flat_map(|r| (0..10).map(move |c| Cell::new(r, c))),
        );
        let (a, b) = split(&m, 0.3).unwrap();
        assert_eq!((a.area(), b.area()), (6, 14));
        assert!(a.contains(Cell::new(2, 2)) && b.contains(Cell::new(1, 3)));
        // one cell cannot be split
        assert!(split(&Mask::from_cells(5, 12, [Cell::new(0, 0)]), 0.5).is_none());
    }

    #[test]
    fn colour_shift_changes_hue_or_lightness() {
        let red = [200, 30, 30];
        let s = shift_colour(red, 120.0, 40.0);
        assert!(s[1] > s[0] || s[2] > s[0], "{s:?}"); // no longer red-dominant
        let white = shift_colour([250, 250, 250], 120.0, 40.0);
        assert!(white.iter().all(|&v| v < 200), "{white:?}");
        let black = shift_colour([20, 20, 20], 120.0, 40.0);
        assert!(black.iter().all(|&v| v > 60), "{black:?}");
    }
}
