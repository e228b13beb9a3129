//! The colour attribute: a colour word for a mask from the top-down RGB map.
//!
//! Each pixel is converted sRGB -> linear RGB -> XYZ (D65) -> CIELAB (the `palette`
//! crate does the conversion and the colour difference) and named by the nearest
//! entry of a [`ColourPalette`]; the mask's colour is the majority vote of its
//! pixels ([`ColourVote`] reports the winner's share), which ignores specks of
//! noise and the odd pixel of floor at the mask's edge.
//!
//! Achromatic pixels (chroma `C* = sqrt(a*^2 + b*^2)` below
//! [`ColourConfig::achromatic_chroma`]) take the palette's achromatic entry (black,
//! grey, silver, white) of the nearest lightness L*, since hue means nothing there;
//! the others take the chromatic entry of least CIEDE2000 difference.
//!
//! The default palette, [`ColourPalette::basic`], has the eleven basic colour terms
//! plus silver (light grey), each at the RGB the renderer draws it in
//! ([`crate::colour_rgb`]), so a map rendered from a scene reads back with its
//! scene's colours: black, white, grey, silver, red, orange, yellow, green, blue,
//! purple, pink, brown. "gray" is reported as "grey" (the matcher treats them as
//! one word). [`ColourPalette::extended`] has every word the renderer knows.

use std::collections::HashMap;

use palette::color_difference::Ciede2000;
use palette::white_point::D65;
use palette::{IntoColor, Lab, Srgb};

use super::mask::Mask;
use crate::grid::Grid;
use crate::render::{colour_rgb, PALETTE};

/// The default palette's words (see the module docs).
pub const BASIC_COLOURS: &[&str] = &[
    "black", "white", "grey", "silver", "red", "orange", "yellow", "green", "blue", "purple",
    "pink", "brown",
];

/// CIELAB (D65) of an sRGB colour: `[L*, a*, b*]`.
pub fn srgb_to_lab(rgb: [u8; 3]) -> [f32; 3] {
    let lab: Lab = Srgb::new(rgb[0], rgb[1], rgb[2])
        .into_format::<f32>()
        .into_linear()
        .into_color();
    [lab.l, lab.a, lab.b]
}

/// CIEDE2000 colour difference of two CIELAB colours.
pub fn ciede2000(a: [f32; 3], b: [f32; 3]) -> f32 {
    let lab = |v: [f32; 3]| Lab::<D65, f32>::new(v[0], v[1], v[2]);
    lab(a).difference(lab(b))
}

/// One named colour of a palette.
#[derive(Debug, Clone, PartialEq)]
pub struct PaletteColour {
    pub name: String,
    pub rgb: [u8; 3],
    /// CIELAB of `rgb`.
    pub lab: [f32; 3],
}

/// The colour words a classifier chooses from.
#[derive(Debug, Clone, PartialEq)]
pub struct ColourPalette {
    entries: Vec<PaletteColour>,
}

impl ColourPalette {
    /// A palette of (word, sRGB) pairs.
    pub fn new<S: Into<String>>(entries: impl IntoIterator<Item = (S, [u8; 3])>) -> Self {
        ColourPalette {
            entries: entries
                .into_iter()
                .map(|(name, rgb)| PaletteColour {
                    name: name.into(),
                    rgb,
                    lab: srgb_to_lab(rgb),
                })
                .collect(),
        }
    }

    /// [`BASIC_COLOURS`] at the renderer's RGB.
    pub fn basic() -> Self {
        ColourPalette::new(
            BASIC_COLOURS
                .iter()
                .filter_map(|&w| colour_rgb(w).map(|rgb| (w, rgb))),
        )
    }

    /// Every word of the renderer's [`PALETTE`] ("gray" left out: same RGB as "grey").
    pub fn extended() -> Self {
        ColourPalette::new(PALETTE.iter().filter(|(w, _)| *w != "gray").copied())
    }

    pub fn entries(&self) -> &[PaletteColour] {
        &self.entries
    }
}

impl Default for ColourPalette {
    fn default() -> Self {
        ColourPalette::basic()
    }
}

/// Settings of the colour classifier.
#[derive(Debug, Clone, PartialEq)]
pub struct ColourConfig {
    pub palette: ColourPalette,
    /// Chroma `C*` below which a pixel (and a palette entry) counts as achromatic.
    /// Default: 10 (greys, silver and black/white stay achromatic; the palest
    /// named colours, beige and cream, have `C*` of 17 or more).
    pub achromatic_chroma: f32,
    /// Smallest share of the votes the winning word needs; below it the mask gets no
    /// colour. Default: 0 (the plurality always wins).
    pub min_share: f64,
}

impl Default for ColourConfig {
    fn default() -> Self {
        ColourConfig {
            palette: ColourPalette::basic(),
            achromatic_chroma: 10.0,
            min_share: 0.0,
        }
    }
}

/// A mask's colour: the winning word and its share of the pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct ColourVote {
    pub colour: String,
    /// Index into the palette's entries.
    pub index: usize,
    pub votes: u64,
    pub pixels: u64,
    /// `votes / pixels`.
    pub share: f64,
}

/// Names pixels with palette words.
#[derive(Debug, Clone)]
pub struct ColourClassifier {
    config: ColourConfig,
    achromatic: Vec<usize>,
    chromatic: Vec<usize>,
}

fn chroma(lab: [f32; 3]) -> f32 {
    lab[1].hypot(lab[2])
}

impl ColourClassifier {
    pub fn new(config: ColourConfig) -> Self {
        let (achromatic, chromatic) = (0..config.palette.entries.len())
            .partition(|&i| chroma(config.palette.entries[i].lab) < config.achromatic_chroma);
        ColourClassifier {
            config,
            achromatic,
            chromatic,
        }
    }

    pub fn palette(&self) -> &ColourPalette {
        &self.config.palette
    }

    /// Index of the palette entry naming one pixel (`None` for an empty palette).
    pub fn nearest(&self, rgb: [u8; 3]) -> Option<usize> {
        let lab = srgb_to_lab(rgb);
        let entries = &self.config.palette.entries;
        // Achromatic pixels compare lightness only, with the achromatic entries.
        let by_lightness =
            chroma(lab) < self.config.achromatic_chroma && !self.achromatic.is_empty();
        let pool: &[usize] = if by_lightness || self.chromatic.is_empty() {
            &self.achromatic
        } else {
            &self.chromatic
        };
        let dist = |i: usize| {
            let e = entries[i].lab;
            if by_lightness {
                (e[0] - lab[0]).abs()
            } else {
                ciede2000(lab, e)
            }
        };
        pool.iter()
            .copied()
            .min_by(|&a, &b| dist(a).total_cmp(&dist(b)))
    }

    /// The word of one pixel.
    pub fn name(&self, rgb: [u8; 3]) -> Option<&str> {
        self.nearest(rgb)
            .map(|i| self.config.palette.entries[i].name.as_str())
    }

    /// Majority vote of the pixels' words (ties: the earlier palette entry); `None`
    /// without pixels, or when the winner's share is below `min_share`.
    pub fn vote(&self, pixels: impl IntoIterator<Item = [u8; 3]>) -> Option<ColourVote> {
        let n = self.config.palette.entries.len();
        let mut votes = vec![0u64; n];
        let mut cache: HashMap<[u8; 3], Option<usize>> = HashMap::new();
        let mut total = 0u64;
        for p in pixels {
            total += 1;
            let k = *cache.entry(p).or_insert_with(|| self.nearest(p));
            if let Some(v) = k.and_then(|k| votes.get_mut(k)) {
                *v += 1;
            }
        }
        let (index, &best) = votes
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(&a.0)))?;
        if total == 0 || best == 0 {
            return None;
        }
        let share = best as f64 / total as f64;
        if share < self.config.min_share {
            return None;
        }
        Some(ColourVote {
            colour: self.config.palette.entries[index].name.clone(),
            index,
            votes: best,
            pixels: total,
            share,
        })
    }

    /// The colour of a mask's pixels in a top-down RGB map of the same size
    /// (`None` when the sizes differ or the mask is empty).
    pub fn classify_mask(&self, rgb: &Grid<[u8; 3]>, mask: &Mask) -> Option<ColourVote> {
        if (rgb.rows(), rgb.cols()) != (mask.rows(), mask.cols()) {
            return None;
        }
        let data = rgb.as_slice();
        self.vote(mask.indices().filter_map(|i| data.get(i).copied()))
    }
}

impl Default for ColourClassifier {
    fn default() -> Self {
        ColourClassifier::new(ColourConfig::default())
    }
}
