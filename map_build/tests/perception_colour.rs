//! The colour classifier: CIELAB conversion and CIEDE2000 against published values,
//! palette prototypes named by their own word, pure, shaded and tinted colours,
//! achromatic pixels by lightness, and the median colour of noisy masks.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use map_build::perception::{
    ciede2000, srgb_to_lab, ColourClassifier, ColourConfig, ColourPalette, Mask, BASIC_COLOURS,
};
use map_core::matcher::canonical;
use map_core::render::{colour_rgb, PALETTE};
use map_core::{Cell, Grid};

fn close(a: [f32; 3], b: [f32; 3], tol: f32) -> bool {
    a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= tol)
}

#[test]
fn srgb_to_lab_matches_reference_values() {
    // CIELAB (D65) of sRGB primaries, as colour-science references list them.
    let cases: [([u8; 3], [f32; 3]); 5] = [
        ([255, 255, 255], [100.0, 0.0, 0.0]),
        ([0, 0, 0], [0.0, 0.0, 0.0]),
        ([255, 0, 0], [53.24, 80.09, 67.20]),
        ([0, 255, 0], [87.73, -86.18, 83.18]),
        ([0, 0, 255], [32.30, 79.19, -107.86]),
    ];
    for (rgb, want) in cases {
        let got = srgb_to_lab(rgb);
        assert!(close(got, want, 0.05), "{rgb:?}: {got:?} vs {want:?}");
    }
    // mid grey: L* of sRGB 119 is about 50
    let g = srgb_to_lab([119, 119, 119]);
    assert!((g[0] - 50.0).abs() < 0.5 && g[1].abs() < 0.01 && g[2].abs() < 0.01);
}

#[test]
fn ciede2000_matches_sharmas_test_pairs() {
    // Sharma, Wu, Dalal (2005), Table 1: pairs 1, 7, 17 and 25.
    let pairs: [([f32; 3], [f32; 3], f32); 4] = [
        ([50.0, 2.6772, -79.7751], [50.0, 0.0, -82.7485], 2.0425),
        ([50.0, 0.0, 0.0], [50.0, -1.0, 2.0], 2.3669),
        ([50.0, 2.5, 0.0], [73.0, 25.0, -18.0], 27.1492),
        (
            [60.2574, -34.0099, 36.2677],
            [60.4626, -34.1751, 39.4387],
            1.2644,
        ),
    ];
    for (a, b, want) in pairs {
        let d = ciede2000(a, b);
        assert!((d - want).abs() < 2e-3, "{a:?} {b:?}: {d} vs {want}");
        assert!((ciede2000(b, a) - d).abs() < 1e-4);
    }
}

#[test]
fn every_prototype_is_named_by_its_own_word() {
    for palette in [ColourPalette::basic(), ColourPalette::extended()] {
        let c = ColourClassifier::new(ColourConfig {
            palette: palette.clone(),
            ..ColourConfig::default()
        });
        for e in palette.entries() {
            assert_eq!(c.name(e.rgb), Some(e.name.as_str()), "{e:?}");
        }
    }
    // The basic palette reads the renderer's colour of each of its words back, and
    // "gray" as "grey"; the extended palette reads back every renderer colour.
    let basic = ColourClassifier::default();
    for w in BASIC_COLOURS.iter().chain(&["gray"]) {
        let got = basic.name(colour_rgb(w).unwrap()).unwrap();
        assert_eq!(canonical(got), canonical(w));
    }
    let ext = ColourClassifier::new(ColourConfig {
        palette: ColourPalette::extended(),
        ..ColourConfig::default()
    });
    for (w, rgb) in PALETTE {
        assert_eq!(canonical(ext.name(*rgb).unwrap()), canonical(w), "{w}");
    }
    assert_eq!(ColourPalette::basic().names().len(), BASIC_COLOURS.len());
}

#[test]
fn pure_and_named_web_colours() {
    let c = ColourClassifier::default();
    let cases: &[([u8; 3], &str)] = &[
        ([255, 0, 0], "red"),
        ([139, 0, 0], "red"), // dark red
        ([0, 255, 0], "green"),
        ([34, 139, 34], "green"), // forest green
        ([128, 128, 0], "green"), // olive
        ([0, 0, 255], "blue"),
        ([0, 0, 139], "blue"),    // dark blue
        ([65, 105, 225], "blue"), // royal blue
        ([0, 255, 255], "blue"),  // cyan: no cyan in the basic palette
        ([255, 255, 0], "yellow"),
        ([255, 165, 0], "orange"),
        ([255, 140, 0], "orange"),
        ([128, 0, 128], "purple"),
        ([138, 43, 226], "purple"), // blue violet
        ([255, 192, 203], "pink"),
        ([255, 20, 147], "pink"), // deep pink
        ([139, 69, 19], "brown"),
        ([210, 105, 30], "orange"), // CSS "chocolate" is an orange-brown
        ([0, 0, 0], "black"),
        ([255, 255, 255], "white"),
        ([128, 128, 128], "grey"),
        ([192, 192, 192], "silver"),
    ];
    for &(rgb, want) in cases {
        assert_eq!(c.name(rgb), Some(want), "{rgb:?}");
    }
}

#[test]
fn shaded_and_tinted_colours_keep_their_word() {
    let c = ColourClassifier::default();
    let chromatic = [
        "red", "orange", "yellow", "green", "blue", "purple", "pink", "brown",
    ];
    for w in chromatic {
        let rgb = colour_rgb(w).unwrap();
        for f in [0.8f32, 0.9, 1.1] {
            let s = rgb.map(|v| (f32::from(v) * f).min(255.0) as u8);
            assert_eq!(c.name(s), Some(w), "{w} x {f}: {s:?}");
        }
        for t in [0.1f32, 0.2] {
            let s = rgb.map(|v| (f32::from(v) + (255.0 - f32::from(v)) * t) as u8);
            assert_eq!(c.name(s), Some(w), "{w} tinted {t}: {s:?}");
        }
    }
}

#[test]
fn achromatic_pixels_go_by_lightness() {
    let c = ColourClassifier::default();
    let order = ["black", "grey", "silver", "white"];
    let mut last = 0;
    for v in 0..=255u8 {
        let w = c.name([v, v, v]).unwrap();
        let k = order.iter().position(|o| *o == w).unwrap();
        assert!(k >= last, "{v}: {w} after {}", order[last]);
        last = k;
    }
    assert_eq!(last, 3);
    assert_eq!(c.name([20, 20, 20]), Some("black"));
    assert_eq!(c.name([90, 90, 90]), Some("grey"));
    // a faint tint (C* < 10) is still grey, not a hue
    assert_eq!(c.name([135, 128, 122]), Some("grey"));
    assert_eq!(c.name([180, 186, 196]), Some("silver"));
}

/// Deterministic noise in [-1, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }
}

#[test]
fn noisy_masks_get_the_right_colour() {
    let c = ColourClassifier::default();
    let mut rng = Lcg(7);
    for w in BASIC_COLOURS {
        let base = colour_rgb(w).unwrap();
        let (rows, cols) = (40, 50);
        let mut img = Grid::new(rows, cols, [214u8, 200, 176]); // floor
        for r in 5..35 {
            for col in 5..45 {
                let px = if rng.next() > 0.7 {
                    // 15% of the pixels: any colour at all
                    [rng.next(), rng.next(), rng.next()].map(|v| ((v + 1.0) * 127.0) as u8)
                } else {
                    // sensor noise: +-18 on each channel
                    base.map(|v| (f32::from(v) + 18.0 * rng.next()).clamp(0.0, 255.0) as u8)
                };
                img.set(Cell::new(r, col), px);
            }
        }
        // the mask overhangs the object by a cell of floor all round
        let mask = Mask::from_cells(
            rows,
            cols,
            (4..36).flat_map(|r| (4..46).map(move |col| Cell::new(r, col))),
        );
        let v = c.classify_mask(&img, &mask).unwrap();
        assert_eq!(v.colour, *w, "{v:?}");
        assert_eq!(v.pixels, mask.area());
        assert!(v.delta_e < 8.0, "{w}: {v:?}");
    }
}

#[test]
fn the_median_follows_the_majority_and_max_delta_e_rejects_odd_colours() {
    let red = colour_rgb("red").unwrap();
    let blue = colour_rgb("blue").unwrap();
    let px: Vec<[u8; 3]> = std::iter::repeat_n(red, 55)
        .chain(std::iter::repeat_n(blue, 45))
        .collect();
    let c = ColourClassifier::default();
    let v = c.classify_pixels(px.iter().copied()).unwrap();
    assert_eq!((v.colour.as_str(), v.pixels), ("red", 100));
    assert!(v.delta_e < 1e-3, "{v:?}");
    assert_eq!(v.median_lab, srgb_to_lab(red));
    assert_eq!(c.classify_pixels(std::iter::empty()), None);
    // teal is far from every basic prototype: named, but with a large difference
    let teal = c.classify_pixels([[0u8, 128, 128]; 4]).unwrap();
    assert!(teal.delta_e > 10.0, "{teal:?}");
    let strict = ColourClassifier::new(ColourConfig {
        max_delta_e: 10.0,
        ..ColourConfig::default()
    });
    assert_eq!(strict.classify_pixels([[0u8, 128, 128]; 4]), None);
    assert_eq!(strict.classify_pixels([red; 4]).unwrap().colour, "red");
    // a mask on a grid of another size, or an empty one, has no colour
    let img = Grid::new(3, 3, red);
    assert_eq!(c.classify_mask(&img, &Mask::empty(3, 3)), None);
    assert_eq!(
        c.classify_mask(&img, &Mask::from_grid(&Grid::new(2, 2, true))),
        None
    );
    assert_eq!(
        c.classify_mask(&img, &Mask::from_grid(&Grid::new(3, 3, true)))
            .unwrap()
            .colour,
        "red"
    );
}
