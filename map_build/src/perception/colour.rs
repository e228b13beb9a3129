//! The colour attribute: a colour word for a mask from the top-down RGB map.
//!
//! Each pixel is converted sRGB -> linear RGB -> XYZ (D65) -> CIELAB (the `palette`
//! crate does the conversion and the colour difference). The mask's colour is the
//! word of the per-channel median of its pixels' L*, a*, b* ([`MaskColour`]): the
//! median ignores specks of noise and the odd pixel of floor at the mask's edge,
//! equals the majority colour when more than half the pixels share one, and keeps
//! zero-mean sensor noise from giving dark pixels a hue (naming each pixel and
//! voting does not: with +-18 of noise per channel, only 35% of the pixels of a
//! black mask were named black one by one, the rest brown, purple, ...). It also
//! costs one palette look-up per mask instead of one per pixel.
//!
//! A colour is named by the nearest prototype of a [`ColourPalette`]. Achromatic
//! colours (chroma `C* = sqrt(a*^2 + b*^2)` below
//! [`ColourConfig::achromatic_chroma`]) take the achromatic prototype (black, grey,
//! silver, white) of the nearest lightness L*, since hue means nothing there; the
//! others take the chromatic prototype of least CIEDE2000 difference.
//!
//! The default palette, [`ColourPalette::basic`], has the eleven basic colour terms
//! plus silver (light grey): black, white, grey, silver, red, orange, yellow,
//! green, blue, purple, pink, brown. Each word has the RGB the renderer draws it in
//! ([`map_core::render::colour_rgb`]) as a prototype, so a map rendered from a scene reads back
//! with its scene's colours, plus common variants ([`BASIC_EXTRA_PROTOTYPES`]: pure,
//! dark and light ones); a pixel takes the word of its nearest prototype. "gray" is
//! reported as "grey" (the matcher treats them as one word).
//! [`ColourPalette::extended`] has every word the renderer knows.

use std::sync::OnceLock;

use palette::color_difference::Ciede2000;
use palette::white_point::D65;
use palette::{IntoColor, Lab, LinSrgb, Srgb};

use super::mask::Mask;
use map_core::grid::Grid;
use map_core::render::{colour_rgb, PALETTE};

/// The default palette's words (see the module docs).
pub const BASIC_COLOURS: &[&str] = &[
    "black", "white", "grey", "silver", "red", "orange", "yellow", "green", "blue", "purple",
    "pink", "brown",
];

/// Extra prototypes of the basic words besides the renderer's RGB (CSS/X11 colours
/// people call by the basic word), so that pure, dark and light variants are named
/// well: without them pure blue (0, 0, 255) is nearer the renderer's purple than its
/// blue in CIEDE2000, and dark grey falls to black.
pub const BASIC_EXTRA_PROTOTYPES: &[(&str, [u8; 3])] = &[
    ("black", [0, 0, 0]),
    ("white", [255, 255, 255]),
    ("grey", [128, 128, 128]),
    ("grey", [100, 100, 100]),
    ("silver", [192, 192, 192]),
    ("red", [255, 0, 0]),
    ("red", [178, 34, 34]),
    ("red", [128, 0, 0]),
    ("orange", [255, 165, 0]),
    ("orange", [230, 110, 20]),
    ("yellow", [255, 255, 0]),
    ("yellow", [255, 215, 0]),
    ("green", [0, 255, 0]),
    ("green", [0, 128, 0]),
    ("green", [0, 100, 0]),
    ("green", [107, 142, 35]),
    ("green", [46, 139, 87]),
    ("blue", [0, 0, 255]),
    ("blue", [0, 0, 128]),
    ("blue", [70, 130, 180]),
    ("blue", [30, 144, 255]),
    ("blue", [135, 206, 235]),
    ("purple", [128, 0, 128]),
    ("purple", [75, 0, 130]),
    ("purple", [150, 100, 220]),
    ("pink", [255, 192, 203]),
    ("pink", [255, 105, 180]),
    ("pink", [255, 0, 255]),
    ("brown", [139, 69, 19]),
    ("brown", [101, 67, 33]),
    ("brown", [160, 82, 45]),
    ("brown", [110, 60, 25]),
    ("brown", [210, 180, 140]),
];

/// CIELAB (D65) of an sRGB colour: `[L*, a*, b*]`.
pub fn srgb_to_lab(rgb: [u8; 3]) -> [f32; 3] {
    // The sRGB transfer function of each 8-bit value, computed once by `palette`
    // (a table look-up instead of three `powf` per pixel).
    static LINEAR: OnceLock<[f32; 256]> = OnceLock::new();
    let lin = LINEAR.get_or_init(|| {
        std::array::from_fn(|v| {
            Srgb::new(v as u8, 0, 0)
                .into_format::<f32>()
                .into_linear::<f32>()
                .red
        })
    });
    let [r, g, b] = rgb.map(|v| lin[usize::from(v)]);
    let lab: Lab = LinSrgb::new(r, g, b).into_color();
    [lab.l, lab.a, lab.b]
}

/// CIEDE2000 colour difference of two CIELAB colours.
pub fn ciede2000(a: [f32; 3], b: [f32; 3]) -> f32 {
    let lab = |v: [f32; 3]| Lab::<D65, f32>::new(v[0], v[1], v[2]);
    lab(a).difference(lab(b))
}

/// One prototype of a palette: a word and an sRGB colour it names.
#[derive(Debug, Clone, PartialEq)]
pub struct PaletteColour {
    /// The colour word.
    pub name: String,
    /// The prototype's sRGB colour.
    pub rgb: [u8; 3],
    /// CIELAB of `rgb`.
    pub lab: [f32; 3],
}

/// The colour words a classifier chooses from, each with one or more prototypes;
/// a pixel takes the word of its nearest prototype.
#[derive(Debug, Clone, PartialEq)]
pub struct ColourPalette {
    entries: Vec<PaletteColour>,
    names: Vec<String>,
}

impl ColourPalette {
    /// A palette of (word, sRGB) prototypes; a word may have several.
    pub fn new<S: Into<String>>(entries: impl IntoIterator<Item = (S, [u8; 3])>) -> Self {
        let mut p = ColourPalette {
            entries: Vec::new(),
            names: Vec::new(),
        };
        for (name, rgb) in entries {
            let name: String = name.into();
            if !p.names.contains(&name) {
                p.names.push(name.clone());
            }
            p.entries.push(PaletteColour {
                name,
                rgb,
                lab: srgb_to_lab(rgb),
            });
        }
        p
    }

    /// [`BASIC_COLOURS`]: the renderer's RGB of each word first, then
    /// [`BASIC_EXTRA_PROTOTYPES`].
    pub fn basic() -> Self {
        let own = BASIC_COLOURS
            .iter()
            .filter_map(|&w| colour_rgb(w).map(|rgb| (w, rgb)));
        ColourPalette::new(own.chain(BASIC_EXTRA_PROTOTYPES.iter().copied()))
    }

    /// Every word of the renderer's [`PALETTE`] at its RGB ("gray" left out: the same
    /// RGB as "grey"), plus pure black, white, red, green, blue and yellow.
    pub fn extended() -> Self {
        let own = PALETTE.iter().filter(|(w, _)| *w != "gray").copied();
        let pure = [
            ("black", [0, 0, 0]),
            ("white", [255, 255, 255]),
            ("red", [255, 0, 0]),
            ("green", [0, 128, 0]),
            ("blue", [0, 0, 255]),
            ("yellow", [255, 255, 0]),
        ];
        ColourPalette::new(own.chain(pure))
    }

    /// The prototypes.
    pub fn entries(&self) -> &[PaletteColour] {
        &self.entries
    }

    /// The distinct words, in order of first appearance.
    pub fn names(&self) -> &[String] {
        &self.names
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
    /// The colour words and prototypes to choose from. Default: [`ColourPalette::basic`].
    pub palette: ColourPalette,
    /// Chroma `C*` below which a pixel (and a palette entry) counts as achromatic.
    /// Default: 10 (greys, silver and black/white stay achromatic; the palest
    /// named colours, beige and cream, have `C*` of 17 or more).
    pub achromatic_chroma: f32,
    /// Largest difference between a mask's median colour and the nearest prototype
    /// ([`MaskColour::delta_e`]) that still names it; beyond it the mask gets no
    /// colour. Default: infinite (every mask is named).
    pub max_delta_e: f32,
}

impl Default for ColourConfig {
    fn default() -> Self {
        ColourConfig {
            palette: ColourPalette::basic(),
            achromatic_chroma: 10.0,
            max_delta_e: f32::INFINITY,
        }
    }
}

/// A mask's colour: the word of its pixels' median CIELAB.
#[derive(Debug, Clone, PartialEq)]
pub struct MaskColour {
    /// The colour word.
    pub colour: String,
    /// Pixels the median was taken over.
    pub pixels: u64,
    /// Per-channel median `[L*, a*, b*]`.
    pub median_lab: [f32; 3],
    /// Difference between the median and the word's nearest prototype: CIEDE2000,
    /// or |L* difference| for an achromatic median. Small = a typical example of the
    /// word.
    pub delta_e: f32,
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
    /// A classifier with the given settings.
    pub fn new(config: ColourConfig) -> Self {
        let (achromatic, chromatic) = (0..config.palette.entries.len())
            .partition(|&i| chroma(config.palette.entries[i].lab) < config.achromatic_chroma);
        ColourClassifier {
            config,
            achromatic,
            chromatic,
        }
    }

    /// The palette it names colours from.
    pub fn palette(&self) -> &ColourPalette {
        &self.config.palette
    }

    /// Index of the palette prototype nearest to a CIELAB colour, and its difference
    /// (`None` for an empty palette).
    pub fn nearest_lab(&self, lab: [f32; 3]) -> Option<(usize, f32)> {
        let entries = &self.config.palette.entries;
        // Achromatic colours compare lightness only, with the achromatic prototypes.
        let by_lightness =
            chroma(lab) < self.config.achromatic_chroma && !self.achromatic.is_empty();
        let pool: &[usize] = if by_lightness || self.chromatic.is_empty() {
            &self.achromatic
        } else {
            &self.chromatic
        };
        pool.iter()
            .map(|&i| {
                let e = entries[i].lab;
                let d = if by_lightness {
                    (e[0] - lab[0]).abs()
                } else {
                    ciede2000(lab, e)
                };
                (i, d)
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// Index of the palette prototype naming one pixel.
    pub fn nearest(&self, rgb: [u8; 3]) -> Option<usize> {
        self.nearest_lab(srgb_to_lab(rgb)).map(|(i, _)| i)
    }

    /// The word of one pixel.
    pub fn name(&self, rgb: [u8; 3]) -> Option<&str> {
        self.nearest(rgb)
            .map(|i| self.config.palette.entries[i].name.as_str())
    }

    /// The colour of a set of pixels: the word of their per-channel median CIELAB;
    /// `None` without pixels, or when the median is farther than `max_delta_e` from
    /// every prototype.
    pub fn classify_pixels(&self, pixels: impl IntoIterator<Item = [u8; 3]>) -> Option<MaskColour> {
        let (mut l, mut a, mut b) = (Vec::new(), Vec::new(), Vec::new());
        for p in pixels {
            let [x, y, z] = srgb_to_lab(p);
            l.push(x);
            a.push(y);
            b.push(z);
        }
        let median_lab = [median(&mut l)?, median(&mut a)?, median(&mut b)?];
        let (i, delta_e) = self.nearest_lab(median_lab)?;
        if delta_e > self.config.max_delta_e {
            return None;
        }
        Some(MaskColour {
            colour: self.config.palette.entries[i].name.clone(),
            pixels: l.len() as u64,
            median_lab,
            delta_e,
        })
    }

    /// The colour of a mask's pixels in a top-down RGB map of the same size
    /// (`None` when the sizes differ or the mask is empty).
    pub fn classify_mask(&self, rgb: &Grid<[u8; 3]>, mask: &Mask) -> Option<MaskColour> {
        if (rgb.rows(), rgb.cols()) != (mask.rows(), mask.cols()) {
            return None;
        }
        let data = rgb.as_slice();
        self.classify_pixels(mask.indices().filter_map(|i| data.get(i).copied()))
    }
}

impl Default for ColourClassifier {
    fn default() -> Self {
        ColourClassifier::new(ColourConfig::default())
    }
}

/// The median of the values (the upper one of the middle two for an even count);
/// `None` when empty. Reorders the slice.
fn median(v: &mut [f32]) -> Option<f32> {
    if v.is_empty() {
        return None;
    }
    let k = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(k, f32::total_cmp);
    Some(*m)
}
